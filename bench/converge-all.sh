#!/usr/bin/env bash
# bench/converge-all.sh: issue 14's figure, time to 2% relative RMSE for every
# estimator, with and without shadows, on the meshes the issue names:
#   - the 1M-tet bench mesh and a real solver mesh cut into tets (PLOT3D post from
#     tests/data, VelocityMagnitude), each against VTK's ray-cast mapper in the same
#     run (bench/render-vs-vtk.sh);
#   - the built-in scene, a real mixed-element mesh (tests/data/vtk/notch_stress.vtk,
#     hexes and wedges) and the AMR-like mesh of `clvr-gen amr` at density 1 (thin)
#     and 8 (dense), each against VTK twice: clvr on the cells as they are while VTK
#     draws them cut into tets (its mappers take tets only; vtkDataSetTriangleFilter,
#     as ParaView does), and both on the same cut tets (bench/tetrahedralize.py; the
#     stricter reading, issue 14's check on unseen meshes).
# Usage: bench/converge-all.sh [--build DIR] [--data DIR] [--size WxH] [--ref-spp R]
#                              [--max-spp M] [--estimators LIST] [--only NAME,...]
#   defaults: build, /tmp/clvr-bench, 256x256 (the size issue 14 checks unseen meshes
#   at), 128, 256, delta,urm, every mesh (names: tets-1M post default notch amr-d1 amr-d8)
# Output: the render-vs-vtk files (bench/results/render-vs-vtk/), one per mesh and,
# for the mixed and hex meshes, one more for their cut into tets (<mesh>-cut).
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
mkdir -p "$DATA"
want() { case ",$ONLY," in *",$1,"*) return 0 ;; *) return 1 ;; esac; }

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
vs_vtk() { # mesh.bin density tag: native cells, then the same cut into tets
  echo "converge-all.sh: $1 (density $2); $(uptime)" >&2
  "$ROOT/bench/render-vs-vtk.sh" --build "$BUILD" --data "$DATA" --mesh "$1" --density "$2" --size "$SIZE" \
    --ref-spp "$REF" --max-spp "$MAXSPP" --estimators "$EST" --mappers raycast --tag "$3"
  local cut=${1%.bin}-cut.bin
  [ -f "$cut" ] || /usr/bin/python3 "$ROOT/bench/tetrahedralize.py" "$1" "$cut"
  "$ROOT/bench/render-vs-vtk.sh" --build "$BUILD" --data "$DATA" --mesh "$cut" --density "$2" --size "$SIZE" \
    --ref-spp "$REF" --max-spp "$MAXSPP" --estimators "$EST" --mappers raycast --tag "$3"
}
if want default; then
  def=$DATA/default.bin # the built-in scene: clvr-gen mixed at 56^3 cubes
  [ -f "$def" ] || "$BUILD/clvr-gen" mixed "$def" --elements 275k --quiet
  vs_vtk "$def" 1 "$SIZE"
fi
if want notch; then
  notch=$DATA/notch.bin
  [ -f "$notch" ] || "$ROOT/tools/clvr-convert" "$ROOT/tests/data/vtk/notch_stress.vtk" "$notch" --quiet
  vs_vtk "$notch" 1 "$SIZE"
fi
if want amr-d1 || want amr-d8; then
  amr=$DATA/amr-1M.bin
  [ -f "$amr" ] || "$BUILD/clvr-gen" amr "$amr" --elements 1M --quiet
  want amr-d1 && vs_vtk "$amr" 1 "$SIZE-density1"
  want amr-d8 && vs_vtk "$amr" 8 "$SIZE-density8"
fi
exit 0
