#!/usr/bin/env bash
# bench/converge-all.sh: issue 14's figure, time to 2% relative RMSE for every
# estimator, with and without shadows, on the meshes the issue names:
#   - the 1M-tet bench mesh and a real solver mesh cut into tets (PLOT3D post from
#     tests/data, VelocityMagnitude), each against VTK's ray-cast mapper in the same
#     run (bench/render-vs-vtk.sh);
#   - the built-in scene, a real mixed-element mesh (tests/data/vtk/notch_stress.vtk,
#     hexes and wedges) and the AMR-like mesh of `clvr-gen amr` at density 1 (thin)
#     and 8 (dense): clvr alone (`bench_render --converge`), as VTK's mappers draw
#     tets only.
# Usage: bench/converge-all.sh [--build DIR] [--data DIR] [--size WxH] [--ref-spp R]
#                              [--max-spp M] [--estimators LIST] [--only NAME,...]
#   defaults: build, /tmp/clvr-bench, 256x256 (the size issue 14 checks unseen meshes
#   at), 128, 256, delta,urm, every mesh (names: tets-1M post default notch amr-d1 amr-d8)
# Output: bench/results/render-converge/<date>-<mesh>.md and .json, and the
# render-vs-vtk files for the VTK rows.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=$ROOT/build
DATA=/tmp/clvr-bench
SIZE=256x256
REF=128
MAXSPP=256
EST=delta,urm
ONLY=tets-1M,post,default,notch,amr-d1,amr-d8
while [ $# -gt 0 ]; do
  case $1 in
    --build) BUILD=$(cd "$2" && pwd); shift 2 ;;
    --data) DATA=$2; shift 2 ;;
    --size) SIZE=$2; shift 2 ;;
    --ref-spp) REF=$2; shift 2 ;;
    --max-spp) MAXSPP=$2; shift 2 ;;
    --estimators) EST=$2; shift 2 ;;
    --only) ONLY=$2; shift 2 ;;
    -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    *) echo "converge-all.sh: unknown argument '$1' (try --help)" >&2; exit 2 ;;
  esac
done
cmake --build "$BUILD" -j2 --target bench_render clvr-gen >/dev/null
mkdir -p "$DATA" "$ROOT/bench/results/render-converge"
want() { case ",$ONLY," in *",$1,"*) return 0 ;; *) return 1 ;; esac; }
day=$(date -u +%Y-%m-%d)

if want tets-1M; then
  "$ROOT/bench/render-vs-vtk.sh" --build "$BUILD" --data "$DATA" --size "$SIZE" --ref-spp "$REF" \
    --max-spp "$MAXSPP" --estimators "$EST" --mappers raycast --tag "$SIZE"
fi
if want post; then
  post=$DATA/post-tets.bin
  [ -f "$post" ] || "$ROOT/tools/clvr-convert" "$ROOT/tests/data/plot3d/postxyz.bin" "$post" --tets \
    --scalar VelocityMagnitude --quiet
  "$ROOT/bench/render-vs-vtk.sh" --build "$BUILD" --data "$DATA" --mesh "$post" --size "$SIZE" --ref-spp "$REF" \
    --max-spp "$MAXSPP" --estimators "$EST" --mappers raycast --tag "$SIZE"
fi
converge() { # name mesh density
  local out=$ROOT/bench/results/render-converge/$day-$1-$SIZE
  echo "converge-all.sh: $1 ($2, density $3); $(uptime)" >&2
  "$BUILD/bench_render" --converge --mesh "$2" --density "$3" --size "$SIZE" --ref-spp "$REF" --max-spp "$MAXSPP" \
    --estimators "$EST" --json "$out.json.tmp" >"$out.md.tmp"
  mv "$out.json.tmp" "$out.json"
  mv "$out.md.tmp" "$out.md"
  cat "$out.md"
}
want default && converge default default 1
want notch && converge notch "$ROOT/tests/data/vtk/notch_stress.vtk" 1
if want amr-d1 || want amr-d8; then
  amr=$DATA/amr-1M.bin
  [ -f "$amr" ] || "$BUILD/clvr-gen" amr "$amr" --elements 1M --quiet
  want amr-d1 && converge amr-1M-density1 "$amr" 1
  want amr-d8 && converge amr-1M-density8 "$amr" 8
fi
exit 0
