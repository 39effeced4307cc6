#!/usr/bin/env bash
# bench/render-table5.sh: the paper's Table 5 on our data with bench_render:
# fps and Mrays/s at 1024x1024, 1 spp per frame, for march, track, bins and
# dda (32^3 and 128^3 macrocells) on the PLOT3D sets, two real meshes, the
# AMR-like generated meshes (1M and 10M elements) and a 50M-element mixed mesh.
# Results go through bench/run-all.sh into bench/results/render/.
#
# Usage: bench/render-table5.sh [--build DIR] [--data DIR] [--small] [-- ARGS for bench_render]
#   --build  build directory (default: build; bench_render, clvr-gen are built there)
#   --data   where converted and generated meshes are kept (default: /tmp/clvr-bench)
#   --small  skip the 10M and 50M meshes
# Big meshes: PoCL's device memory defaults to about 4 GiB, so POCL_MEMORY_LIMIT=20 (GiB).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=bench/table_common.sh
. "$ROOT/bench/table_common.sh"
table_args "$@"
table_build bench_render clvr-gen clvr
mkdir -p "$DATA"
CONVERT=$ROOT/tools/clvr-convert
for n in bluntfin comb post; do
  [ -f "$DATA/$n.bin" ] || "$CONVERT" "$ROOT/tests/data/plot3d/${n}xyz.bin" "$DATA/$n.bin" --quiet
done
[ -f "$DATA/fire.bin" ] || "$CONVERT" "$ROOT/tests/data/vtk/fire_ug.vtu" "$DATA/fire.bin" --quiet
[ -f "$DATA/amr-1M.bin" ] || "$BUILD/clvr-gen" amr "$DATA/amr-1M.bin" --elements 1M --quiet
MESHES=(--mesh "$DATA/bluntfin.bin" --mesh "$DATA/comb.bin" --mesh "$DATA/post.bin"
        --mesh "$ROOT/tests/data/vtk/notch_stress.vtk" --mesh "$DATA/fire.bin" --mesh "$DATA/amr-1M.bin")
if [ $SMALL = 0 ]; then
  MESHES+=(--mesh "$(table_generated amr 10M amr-10M)" --mesh "$(table_generated mixed 50M mixed-50M)")
fi
export POCL_MEMORY_LIMIT=${POCL_MEMORY_LIMIT:-20}
echo "render-table5.sh: load before: $(uptime)"
rc=0
"$ROOT/bench/run-all.sh" --build "$BUILD" --out "$ROOT/bench/results/render" --only render -- \
  "${MESHES[@]}" "${EXTRA[@]}" || rc=$?
echo "render-table5.sh: load after: $(uptime)"
exit $rc
