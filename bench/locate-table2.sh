#!/usr/bin/env bash
# bench/locate-table2.sh: the paper's Table 2 on our data with bench_locate:
# point queries/s and BVH bytes per element for leaf clusters of N = 1, 4, 8,
# 16, 32, on real meshes (the PLOT3D sets cut into tets, the largest real data
# we ship) and generated ones from 1M to 50M elements (Kuhn tets, the mixed
# generator at 10M and 50M). 1M uniform random points in each mesh's bounds.
# Writes bench/results/locate-table2/<date>-<device>.md (one table per mesh).
#
# Usage: bench/locate-table2.sh [--build DIR] [--data DIR] [--small] [-- ARGS for bench_locate]
#   --build  build directory (default: build; bench_locate and clvr-gen are built there)
#   --data   where converted and generated meshes are kept (default: /tmp/clvr-bench)
#   --small  skip the 10M and 50M meshes
# Big meshes: PoCL's device memory defaults to about 4 GiB, so POCL_MEMORY_LIMIT=20 (GiB).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=bench/table_common.sh
. "$ROOT/bench/table_common.sh"
table_args "$@"
table_build bench_locate clvr-gen clvr
mkdir -p "$DATA"
CONVERT=$ROOT/tools/clvr-convert
MESHES=()
for n in bluntfin comb post; do
  [ -f "$DATA/$n-tets.bin" ] || "$CONVERT" "$ROOT/tests/data/plot3d/${n}xyz.bin" "$DATA/$n-tets.bin" --tets --quiet
  MESHES+=("$DATA/$n-tets.bin")
done
MESHES+=(cubes) # bench_locate's own 1M Kuhn tets
if [ $SMALL = 0 ]; then
  MESHES+=("$(table_generated mixed 10M mixed-10M)" "$(table_generated mixed 50M mixed-50M)")
fi
export POCL_MEMORY_LIMIT=${POCL_MEMORY_LIMIT:-20}
DEV=$("$BUILD/clvr" --list-devices 2>/dev/null | sed -n 's/^ *device 0:0 *//p' | head -n 1)
SLUG=$(printf '%s' "${DEV:-device}" | tr -c 'A-Za-z0-9' '-' | tr 'A-Z' 'a-z' | sed 's/--*/-/g; s/^-//; s/-$//')
OUT=$ROOT/bench/results/locate-table2
mkdir -p "$OUT"
MD=$OUT/$(date -u +%F)-$SLUG.md
TMP=$MD.tmp
{
  echo "# bench/locate-table2.sh, $(date -u +%FT%TZ), commit $(git -C "$ROOT" rev-parse --short HEAD)$(git -C "$ROOT" diff --quiet || echo -dirty), $(nproc) cores"
  echo
} >"$TMP"
rc=0
for m in "${MESHES[@]}"; do
  args=()
  [ "$m" = cubes ] || args=(--mesh "$m")
  echo "locate-table2.sh: ${m##*/} (load $(cut -d' ' -f1-3 /proc/loadavg))" >&2
  if ! "$BUILD/bench_locate" "${args[@]}" "${EXTRA[@]}" >>"$TMP" 2>"$TMP.err"; then
    rc=1
    { echo "bench_locate ${args[*]} failed:"; echo '```'; tail -n 5 "$TMP.err"; echo '```'; } >>"$TMP"
  fi
  echo >>"$TMP"
done
rm -f "$TMP.err"
mv "$TMP" "$MD"
echo "locate-table2.sh: wrote $MD" >&2
exit $rc
