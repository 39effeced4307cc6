#!/bin/sh
# bench/mpi-load.sh [ELEMENTS] [RANKS...]: MPI mode's distributed loading
# (docs/mpi-loading.md) against one process's clvr_mesh_load, on a
# `clvr-gen mixed` mesh of ELEMENTS (default 10M) generated under /tmp and
# deleted afterwards. Prints one line per rank: bytes of the file regions it
# reads (its slices) and bytes read (the element slice is read twice),
# load wall and CPU seconds, peak RSS (and the RSS right after MPI_Init,
# the fixed overhead), the MiB of the mesh's (share's) arrays once loaded,
# the share's owned and ghost elements (ghost% of owned). RANKS
# defaults to "1 2". Wall time on a loaded machine says little: read the
# CPU seconds and the load average printed with the table.
# Environment: CLVR_BUILD_DIR (default build), MPIEXEC (default mpirun),
# CLVR_BENCH_OUT (a file to copy the table to).
set -eu
here=$(cd "$(dirname "$0")/.." && pwd)
build=${CLVR_BUILD_DIR:-$here/build}
mpiexec=${MPIEXEC:-mpirun}
n=${1:-10M}
shift || true
ranks=${*:-1 2}
for f in "$build/clvr-gen" "$build/mpi_load_probe"; do
    [ -x "$f" ] || { echo "mpi-load.sh: $f is missing: build with an MPI (libopenmpi-dev) first" >&2; exit 2; }
done
tmp=$(mktemp -d /tmp/mpil-bench-XXXXXX)
trap 'rm -rf "$tmp"' EXIT INT TERM
# Open MPI refuses root without these (CI containers run as root).
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
"$build/clvr-gen" mixed "$tmp/mesh.bin" --elements "$n" --quiet
size=$(stat -c %s "$tmp/mesh.bin")
run() { "$mpiexec" -n "$1" --oversubscribe --bind-to none "$build/mpi_load_probe" "$tmp/mesh.bin" $2; }
{
    echo "# clvr MPI loading: clvr-gen mixed --elements $n ($size bytes), $(date -u +%Y-%m-%dT%H:%MZ), load $(cut -d' ' -f1-3 /proc/loadavg)"
    printf '%-7s %4s %14s %14s %8s %8s %9s %9s %9s %12s %12s %7s\n' mode rank slice_bytes bytes_read wall_s cpu_s peakRSS_M startRSS_M arrays_M owned ghosts ghost%
    run 1 --single
    for k in $ranks; do run "$k" ""; done
    echo "# load after: $(cut -d' ' -f1-3 /proc/loadavg)"
} | tee "${CLVR_BENCH_OUT:-/dev/null}"
