#!/usr/bin/env bash
# make-graded-meshes.sh: builds issue #19's strongly graded meshes (and uniform
# meshes of the same domain, scalar field and about the same element count) from
# Debian packages, as clvr .bin files in DIR. Nothing here is committed: the meshes
# are 10-40 MB each and rebuilt in a few minutes.
#
# Usage: tools/make-graded-meshes.sh [--dir DIR] [--no-install] [--no-openfoam] [--force]
#   --dir          output directory (default /tmp/clvr-graded)
#   --no-install   never apt-get; fail (gmsh) or skip (OpenFOAM) when a package is missing
#   --no-openfoam  skip the OpenFOAM case
#   --force        rebuild meshes that are already there
#
# Meshes (all tets unless said; tools/cell-stats.py prints their size statistics):
#   gmsh-point.bin            box [-1,1]^3, Distance + Threshold size field around an
#                             embedded centre point: edge 4e-4 .. 0.08, ~0.66M tets,
#                             element volume max/min ~10^7 (tools/graded_gmsh.py point)
#   gmsh-point-uniform.bin    the same box and scalar at constant edge 0.038 (~0.66M)
#   gmsh-layers.bin           boundary-layer-like: a graded triangulation of the unit
#                             square extruded through 30 geometric layers (first 2.6e-6
#                             thick, ratio 1.5), prisms cut into tets, ~0.86M tets,
#                             bounding-box aspect up to ~10^4 (graded_gmsh.py layers)
#   gmsh-layers-uniform.bin   the unit cube, same scalar, constant edge 0.0174
#   of-igloo.bin / of-igloo-tets.bin
#                             OpenFOAM's iglooWithFridges tutorial (snappyHexMesh with
#                             one more refinement level than the tutorial, a 2x finer
#                             background mesh, 3 surface layers), 5 iterations of
#                             buoyantBoussinesqSimpleFoam, foamToVTK -poly-decomp, then
#                             tools/clvr-convert with scalar T: mixed cells, and split
#                             into tets (--tets) for the Embree/VTK comparisons
#   of-igloo-twin-tets.bin / of-igloo-twin-hexes.bin
#                             their uniform twins (tools/graded_twin.py): a lattice of
#                             cubes over the igloo's box, kept where the solver's mesh
#                             is, as Kuhn tets (as many as of-igloo-tets) or hexes (as
#                             many as of-igloo's cells), T probed from foamToVTK's output
#   bluntfin-tets.bin, comb-tets.bin, post-tets.bin
#                             the PLOT3D grids in tests/data (curvilinear, graded to
#                             their walls), cut into tets
# Packages: gmsh python3-gmsh python3-vtk9 python3-numpy (required), openfoam
# openfoam-examples (optional); installed here with apt-get when run as root
# (tools/setup-debian.sh has no bench group, so they are not listed there).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
DIR=/tmp/clvr-graded
INSTALL=1
OPENFOAM=1
FORCE=0
while [ $# -gt 0 ]; do
  case $1 in
    --dir) DIR=$2; shift 2 ;;
    --no-install) INSTALL=0; shift ;;
    --no-openfoam) OPENFOAM=0; shift ;;
    --force) FORCE=1; shift ;;
    -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    *) echo "make-graded-meshes.sh: unknown argument '$1' (try --help)" >&2; exit 2 ;;
  esac
done
say() { echo "make-graded-meshes.sh: $*" >&2; }
die() { say "error: $*"; exit 1; }

# ensure PKG... : installs what is missing when allowed; returns 1 when still missing.
ensure() {
  local need=() p
  for p in "$@"; do
    [ "$(dpkg-query -W -f='${db:Status-Status}' "$p" 2>/dev/null)" = installed ] || need+=("$p")
  done
  [ ${#need[@]} -eq 0 ] && return 0
  if [ $INSTALL -eq 1 ] && [ "$(id -u)" -eq 0 ]; then
    say "installing ${need[*]} (log /tmp/clvr-graded-apt.log)"
    DEBIAN_FRONTEND=noninteractive timeout 900 apt-get install -y --no-install-recommends "${need[@]}" \
      >/tmp/clvr-graded-apt.log 2>&1 ||
      { apt-get update >>/tmp/clvr-graded-apt.log 2>&1 &&
        DEBIAN_FRONTEND=noninteractive timeout 900 apt-get install -y --no-install-recommends "${need[@]}" \
          >>/tmp/clvr-graded-apt.log 2>&1; } || { say "could not install ${need[*]}"; return 1; }
    return 0
  fi
  say "missing packages: ${need[*]} (run this script as root, or apt-get install them)"
  return 1
}

ensure gmsh python3-gmsh python3-vtk9 python3-numpy || die "gmsh meshes need the packages above"
mkdir -p "$DIR"
CONVERT=$ROOT/tools/clvr-convert
GMSH=$ROOT/tools/graded_gmsh.py

have() { [ $FORCE -eq 0 ] && [ -s "$1" ]; }

gmsh_mesh() { # NAME KIND ARGS...
  local name=$1 kind=$2; shift 2
  if have "$DIR/$name.bin"; then say "$name.bin: already there"; return; fi
  say "$name: gmsh ($kind $*)"
  nice /usr/bin/python3 "$GMSH" "$kind" "$DIR/$name.vtu" "$@" >&2
  nice "$CONVERT" --quiet --scalar density "$DIR/$name.vtu" "$DIR/$name.bin"
  rm -f "$DIR/$name.vtu"
  say "$name.bin: done"
}
gmsh_mesh gmsh-point point --scale 0.8
gmsh_mesh gmsh-point-uniform point --uniform 0.038
gmsh_mesh gmsh-layers layers --scale 1.2
gmsh_mesh gmsh-layers-uniform layers --uniform 0.0174

for n in bluntfin comb post; do
  if have "$DIR/$n-tets.bin"; then continue; fi
  say "$n-tets.bin: tools/clvr-convert --tets tests/data/plot3d/${n}xyz.bin"
  nice "$CONVERT" --quiet --tets "$ROOT/tests/data/plot3d/${n}xyz.bin" "$DIR/$n-tets.bin"
done

if [ $OPENFOAM -eq 1 ]; then
  if ! ensure openfoam openfoam-examples; then
    say "OpenFOAM not installed: skipping of-igloo (pass --no-openfoam to silence)"
  elif have "$DIR/of-igloo-tets.bin" && have "$DIR/of-igloo.bin"; then
    say "of-igloo.bin, of-igloo-tets.bin: already there"
  else
    SRC=/usr/share/doc/openfoam-examples/examples/heatTransfer/buoyantBoussinesqSimpleFoam/iglooWithFridges
    [ -d "$SRC" ] || die "$SRC missing (openfoam-examples)"
    CASE=$DIR/of-igloo
    rm -rf "$CASE"
    cp -r "$SRC" "$CASE"
    find "$CASE" -name '*.gz' -exec gunzip {} +
    # Finer than the tutorial: 2x background mesh, one more refinement level
    # everywhere (checked below: the patterns must match).
    sed -i 's/(20 20 10) simpleGrading/(40 40 20) simpleGrading/' "$CASE/system/blockMeshDict"
    sed -i 's/levels ((0.01 3));/levels ((0.01 4));/; s/level (3 3);/level (4 4);/; s/level (2 2);/level (3 3);/' \
      "$CASE/system/snappyHexMeshDict"
    grep -q '(40 40 20) simpleGrading' "$CASE/system/blockMeshDict" || die "blockMeshDict: pattern not found"
    grep -q 'levels ((0.01 4))' "$CASE/system/snappyHexMeshDict" || die "snappyHexMeshDict: pattern not found"
    # 5 SIMPLE iterations: enough for T to leave its uniform initial value around the
    # fridges; the finer mesh diverges (floating point exception) near iteration 9.
    sed -i 's/^endTime .*/endTime         5;/; s/^writeInterval .*/writeInterval   5;/' "$CASE/system/controlDict"
    say "of-igloo: blockMesh, snappyHexMesh, 5 iterations of buoyantBoussinesqSimpleFoam, foamToVTK (logs in $CASE)"
    (
      set +eu
      # shellcheck disable=SC1091
      . /usr/share/openfoam/etc/bashrc >/dev/null 2>&1
      # (set -e does not act inside a subshell on the left of ||: each step checks.)
      cd "$CASE" || exit 1
      blockMesh >log.blockMesh 2>&1 || exit 1
      nice snappyHexMesh -overwrite >log.snappyHexMesh 2>&1 || exit 1
      nice buoyantBoussinesqSimpleFoam >log.solve 2>&1 || exit 1
      [ -d 5 ] || exit 1
      foamToVTK -latestTime -poly-decomp -legacy -noFaceZones -noPointValues >log.foamToVTK 2>&1 ||
        foamToVTK -latestTime -poly-decomp >log.foamToVTK 2>&1 || exit 1
    ) || die "OpenFOAM step failed; see the logs (log.*) in $CASE"
    VTK=$(find "$CASE/VTK" -maxdepth 1 -type f \( -name '*.vtk' -o -name '*.vtu' \) | sort | tail -n 1)
    [ -n "$VTK" ] || die "foamToVTK wrote nothing in $CASE/VTK"
    say "of-igloo: tools/clvr-convert $VTK (cell scalar T averaged to vertices by clvr-convert)"
    nice "$CONVERT" --quiet --scalar T "$VTK" "$DIR/of-igloo.bin"
    nice "$CONVERT" --quiet --tets --scalar T "$VTK" "$DIR/of-igloo-tets.bin"
  fi
  # Uniform twins of the igloo (tools/graded_twin.py): cubes over its box, kept where
  # the solver's mesh is, T probed at their corners; as many tets as of-igloo-tets and
  # as many hexes as of-igloo's cells.
  VTK=$(find "$DIR/of-igloo/VTK" -maxdepth 1 -type f \( -name '*.vtk' -o -name '*.vtu' \) 2>/dev/null | sort | tail -n 1)
  for kind in tets hexes; do
    src=$DIR/of-igloo.bin
    [ $kind = tets ] && src=$DIR/of-igloo-tets.bin
    if have "$DIR/of-igloo-twin-$kind.bin" || [ ! -s "$src" ]; then continue; fi
    [ -n "$VTK" ] || die "of-igloo-twin-$kind: foamToVTK's output is missing from $DIR/of-igloo/VTK (--force rebuilds the case)"
    # header: counts of tets, pyramids, wedges and hexes at bytes 24-55 (docs/bin-format.md)
    n=$(/usr/bin/python3 -c "import struct,sys; h=open(sys.argv[1],'rb').read(56); print(sum(struct.unpack('<4Q',h[24:56])))" "$src")
    say "of-igloo-twin-$kind: tools/graded_twin.py, about $n cells"
    nice /usr/bin/python3 "$ROOT/tools/graded_twin.py" "$VTK" "$DIR/of-igloo-twin-$kind.vtu" --elements "$n" \
      --cells $kind --scalar T >&2
    nice "$CONVERT" --quiet --scalar T "$DIR/of-igloo-twin-$kind.vtu" "$DIR/of-igloo-twin-$kind.bin"
    rm -f "$DIR/of-igloo-twin-$kind.vtu"
  done
fi
say "meshes in $DIR:"
ls -l "$DIR"/*.bin >&2
