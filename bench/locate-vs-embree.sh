#!/usr/bin/env bash
# bench/locate-vs-embree.sh: issue #4's comparison. Point location on a 1M-tet
# mesh (56^3 jittered cubes cut into 6 Kuhn tets each) with 1M random points
# in its bounds, every core (CLVR_BENCH_THREADS): clvr (OpenCL), Embree 3 and VTK's
# vtkStaticCellLocator on the same mesh and the same points.
#
# Usage: bench/locate-vs-embree.sh [--build DIR] [--no-install] [-- ARGS for bench_locate_embree]
#   --build       build directory (default: build-locate-vs); configured and built here
#   --no-install  do not apt-get the optional packages (libembree-dev, libvtk9-dev)
#   ARGS          e.g. --device pocl --leaf 8 --order sorted --queries 200000
#
# Installs the packages it needs when run as root (idempotent), builds, runs,
# and prints the uptime load before each measurement (the machine may be
# shared: compare medians, repeat when loaded). The last line is
# `point_queries_vs_embree: RATIO` (clvr queries/s over Embree's, same points).
set -euo pipefail

ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=$ROOT/build-locate-vs
INSTALL=1
ARGS=()
while [ $# -gt 0 ]; do
  case $1 in
    --build) BUILD=$2; shift 2 ;;
    --no-install) INSTALL=0; shift ;;
    --) shift; ARGS=("$@"); break ;;
    -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    *) echo "locate-vs-embree.sh: unknown argument '$1' (try --help)" >&2; exit 2 ;;
  esac
done

if [ $INSTALL -eq 1 ]; then
  need=()
  for p in libembree-dev libvtk9-dev; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || need+=("$p")
  done
  if [ ${#need[@]} -gt 0 ]; then
    if [ "$(id -u)" -eq 0 ]; then
      echo "locate-vs-embree.sh: installing ${need[*]}"
      DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "${need[@]}" >/dev/null ||
        { apt-get update >/dev/null && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "${need[@]}" >/dev/null; } ||
        echo "locate-vs-embree.sh: could not install ${need[*]}; going on without" >&2
    else
      echo "locate-vs-embree.sh: ${need[*]} missing and not root; going on without" >&2
    fi
  fi
fi

cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release >/dev/null
targets=(bench_locate_embree)
grep -q '^bench_vtk_locate' <(cmake --build "$BUILD" --target help | sed 's/^\.\.\. //') && targets+=(bench_vtk_locate)
cmake --build "$BUILD" -j2 --target "${targets[@]}" >/dev/null

RAW=$(mktemp /tmp/clvr-locate-XXXXXX.raw)
trap 'rm -f "$RAW"' EXIT
vtk_qps=
if [ -x "$BUILD/vtk_locate" ]; then
  "$BUILD/bench_locate_embree" "${ARGS[@]}" --dump "$RAW" >/dev/null
  echo "# load before VTK: $(uptime | sed 's/.*load average: //')"
  # The same thread count as clvr and Embree (bench_cpu_threads: every online
  # core, or CLVR_BENCH_THREADS); it was 2 whatever the machine.
  vtk_out=$("$BUILD/vtk_locate" "$RAW" --threads "${CLVR_BENCH_THREADS:-$(nproc)}")
  echo "$vtk_out"
  vtk_qps=$(awk '/^vtk_queries_per_s:/ { print $2 }' <<<"$vtk_out")
else
  echo "vtk: not installed (libvtk9-dev)"
fi
rm -f "$RAW"

echo "# load before clvr and Embree: $(uptime | sed 's/.*load average: //')"
out=$("$BUILD/bench_locate_embree" "${ARGS[@]}")
# Everything but the ratio line, then the VTK ratio, then the ratio line last.
grep -v '^point_queries_vs_embree:' <<<"$out"
clvr_qps=$(awk -F'|' '/^\| clvr/ { gsub(/ /, "", $3); print $3 }' <<<"$out")
if [ -n "$vtk_qps" ] && [ -n "$clvr_qps" ]; then
  awk -v a="$clvr_qps" -v b="$vtk_qps" 'BEGIN { printf "point_queries_vs_vtk: %.3f\n", a / b }'
fi
grep '^point_queries_vs_embree:' <<<"$out"
