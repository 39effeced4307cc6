#!/usr/bin/env bash
# bench/graded.sh: issue #19's measurements on strongly graded meshes, each beside
# a uniform mesh of the same domain and scalar field (same optical depth) and about
# the same element count (tools/make-graded-meshes.sh builds them all):
#   1. cell-size statistics (tools/cell-stats.py)
#   2. point location vs Embree 3 (and VTK): bench/locate-vs-embree.sh --mesh, random
#      sorted (Morton order) and rays (24 stratified samples per random chord, a work item
#      carrying one ray's hint through them, as the renderer does) points
#   2b. REPEATS more runs of bench_locate_embree alone (no VTK) per graded mesh and
#      order: the summary's goal column uses their median (single runs on a shared
#      machine disagree by up to 2.6x)
#   3. the paper's Table 2 shape (bench_locate, leaf N = 1..32, random points)
#   4. rendering: build/bench_render samples/ray, null collisions/ray, Mrays/s
#      (track and dda; auto, urm and delta estimators), then bench_render --converge
#      time to 2 % relative RMSE (delta and urm, shadows off and on); each twin with
#      its graded mesh's transfer function, camera and automatic density (--like)
# Writes bench/results/graded/<date>-<device>.md (every tool's own table plus a
# summary against #19's goals) and .json (all raw JSON merged).
#
# Usage: bench/graded.sh [--dir DIR] [--build DIR] [--queries Q] [--size WxH] [--skip LIST]
#   --dir      meshes (default /tmp/clvr-graded; built there when missing)
#   --build    build directory (default build)
#   --queries  point queries per locate run (default 1000000: at 300k a run of clvr at 1e7
#              queries/s lasts 30 ms, and session 61 saw clvr's rate move 8.4-10.5e6 between
#              such runs against 0.98-1.12e7 at 1M)
#   --size     bench_render frame size (default 256x256; --converge is 256x256, --ref-spp 32, --max-spp 48)
#   --repeats  bench_locate_embree repeats per graded mesh and order (default 3)
#   --skip     comma list of stats,locate,repeats,table2,render,converge
#   --tag TAG  results go to <date>-<device>-TAG.{md,json} (a partial rerun beside a full one)
# The machine may be shared: every tool records the 1-minute load average beside each
# figure; compare ratios measured in one run.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
DIR=/tmp/clvr-graded
BUILD=$ROOT/build
QUERIES=1000000
SIZE=256x256
SKIP=
TAG=
REPEATS=3
while [ $# -gt 0 ]; do
  case $1 in
    --dir) DIR=$2; shift 2 ;;
    --build) BUILD=$(cd "$2" && pwd); shift 2 ;;
    --queries) QUERIES=$2; shift 2 ;;
    --size) SIZE=$2; shift 2 ;;
    --skip) SKIP=$2; shift 2 ;;
    --tag) TAG=-$2; shift 2 ;;
    --repeats) REPEATS=$2; shift 2 ;;
    -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    *) echo "graded.sh: unknown argument '$1' (try --help)" >&2; exit 2 ;;
  esac
done
skip() { [[ ",$SKIP," == *",$1,"* ]]; }
say() { echo "graded.sh: $* (load $(cut -d' ' -f1-3 /proc/loadavg))" >&2; }

cmake -S "$ROOT" -B "$BUILD" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$BUILD" -j2 --target bench_locate bench_locate_embree bench_render clvr-gen >/dev/null
"$ROOT/tools/make-graded-meshes.sh" --dir "$DIR"

# graded mesh -> its uniform twin (same box, same scalar, about the same count)
declare -A TWIN=([gmsh-point]=gmsh-point-uniform [gmsh-layers]=gmsh-layers-uniform)
GRADED=(gmsh-point gmsh-layers)
# The OpenFOAM igloo, cut into tets and as its own mixed cells (the hardest case for
# point location), each beside a lattice of as many tets or hexes over its domain with
# its field T probed at their corners (tools/graded_twin.py; until session 57 the tets'
# twin was clvr-gen cellvar, another field and so another optical depth).
for m in of-igloo-tets of-igloo; do
  kind=hexes
  [ $m = of-igloo-tets ] && kind=tets
  if [ -f "$DIR/$m.bin" ] && [ -f "$DIR/of-igloo-twin-$kind.bin" ]; then
    GRADED+=("$m")
    TWIN[$m]=of-igloo-twin-$kind
  fi
done
# Real meshes without a twin: the PLOT3D grids cut into tets (and the igloo when its
# twins could not be built).
REAL=(post-tets)
for m in bluntfin-tets comb-tets of-igloo-tets of-igloo; do
  [ -f "$DIR/$m.bin" ] && [ -z "${TWIN[$m]:-}" ] && REAL+=("$m")
done
LOCATE=()
for g in "${GRADED[@]}"; do LOCATE+=("$g" "${TWIN[$g]}"); done
LOCATE+=("${REAL[@]}")

DEV=$("$BUILD/clvr" --list-devices 2>/dev/null | sed -n 's/^ *device 0:0 *//p' | head -n 1) || true
SLUG=$(printf '%s' "${DEV:-device}" | tr -c 'A-Za-z0-9' '-' | tr 'A-Z' 'a-z' | sed 's/--*/-/g; s/^-//; s/-$//')
OUT=$ROOT/bench/results/graded
mkdir -p "$OUT"
BASE=$OUT/$(date -u +%F)-$SLUG$TAG
RAW=$(mktemp -d /tmp/clvr-graded-results-XXXXXX)
MD=$RAW/body.md
CPU=$("$ROOT/bench/host-cpu.sh")
: >"$MD"
{
  echo "# bench/graded.sh, $(date -u +%FT%TZ), commit $(git -C "$ROOT" rev-parse --short HEAD)$(git -C "$ROOT" diff --quiet || echo -dirty), $(nproc) cores, load at start $(cut -d' ' -f1-3 /proc/loadavg)"
  echo
  echo "CPU: $CPU."
  echo
  echo "Meshes from tools/make-graded-meshes.sh in $DIR. Load = 1-minute load average (shared machine)."
  echo
} >"$RAW/head.md"

if ! skip stats; then
  say "cell statistics"
  args=()
  for m in "${LOCATE[@]}"; do args+=("$DIR/$m.bin"); done
  { echo "## Cell sizes (tools/cell-stats.py; volumes in mesh units^3)"; echo
    nice /usr/bin/python3 "$ROOT/tools/cell-stats.py" "${args[@]}" --json "$RAW/stats.json"; echo; } >>"$MD"
fi

export POCL_MEMORY_LIMIT=${POCL_MEMORY_LIMIT:-20}
if ! skip locate; then
  echo "## Point location vs Embree 3 (bench/locate-vs-embree.sh --mesh, $QUERIES queries, leaf 16, 2 threads)" >>"$MD"
  echo >>"$MD"
  for m in "${LOCATE[@]}"; do
    for order in random sorted rays; do
      say "locate-vs-embree $m $order"
      { echo "### $m, $order points"; echo; echo '```'
        nice "$ROOT/bench/locate-vs-embree.sh" --no-install --build "$BUILD" -- --mesh "$DIR/$m.bin" --order "$order" \
          --queries "$QUERIES" --json "$RAW/locate-$m-$order.json" 2>&1 || echo "FAILED"
        echo '```'; echo; } >>"$MD"
    done
  done
fi

if ! skip repeats; then
  for ((r = 1; r <= REPEATS; r++)); do
    for m in "${GRADED[@]}" "${REAL[@]}"; do
      for order in random sorted rays; do
        say "repeat $r: bench_locate_embree $m $order"
        nice "$BUILD/bench_locate_embree" --mesh "$DIR/$m.bin" --order "$order" --queries "$QUERIES" \
          --json "$RAW/rep-$m-$order-$r.json" >/dev/null 2>&1 || echo "repeat $r $m $order FAILED" >>"$MD"
      done
    done
  done
fi

if ! skip table2; then
  echo "## Table 2 shape (bench_locate, $QUERIES random queries, N = 1..32)" >>"$MD"
  echo >>"$MD"
  for m in "${LOCATE[@]}"; do
    say "table2 $m"
    { nice "$BUILD/bench_locate" --mesh "$DIR/$m.bin" --queries "$QUERIES" --json "$RAW/table2-$m.json" 2>&1 ||
        echo "bench_locate $m FAILED"; echo; } >>"$MD"
  done
fi

# Rendering compares each graded mesh with its twin under one transfer function: the
# graded mesh's scalar range, box and camera, at clvr's automatic density for it
# (bench_render --like GRADED --density auto: the median visible camera ray at optical
# depth 0.75). Before session 57 each mesh had its own range and density 1, at which the
# igloo was nearly transparent (0.02 samples per ray).
if ! skip render; then
  # auto (the renderer's default: the walk through cells, or urm where the pilot
  # finds it faster), urm (a fixed number of steps per ray, so samples/ray hardly depend
  # on the mesh) and delta tracking (samples and null collisions follow the majorants).
  for est in auto urm delta; do
    echo "## Rendering (bench_render $SIZE, --estimator $est, track and dda, --like the graded mesh, --density auto)" >>"$MD"
    echo >>"$MD"
    for g in "${GRADED[@]}"; do
      say "bench_render --estimator $est $g"
      { nice "$BUILD/bench_render" --mesh "$DIR/$g.bin" --mesh "$DIR/${TWIN[$g]}.bin" --like "$DIR/$g.bin" \
          --density auto --estimator "$est" --size "$SIZE" --frames 3 --warmup 1 --methods track,dda \
          --json "$RAW/render-$est-$g.json" 2>&1 | grep -v '^bench_render: hull' || echo "bench_render FAILED"; echo; } >>"$MD"
    done
  done
fi

if ! skip converge; then
  echo "## Time to 2 % relative RMSE (bench_render --converge, 256x256, dda, reference 32 spp, --like the graded mesh, --density auto)" >>"$MD"
  echo >>"$MD"
  for g in "${GRADED[@]}"; do
    for m in "$g" "${TWIN[$g]}"; do
      say "converge $m"
      { nice "$BUILD/bench_render" --converge --mesh "$DIR/$m.bin" --like "$DIR/$g.bin" --density auto --size 256x256 \
          --method dda --ref-spp 32 --max-spp 48 --json "$RAW/converge-$m.json" 2>&1 || echo "converge $m FAILED"; echo; } >>"$MD"
    done
  done
fi

say "summary"
pairs=()
for g in "${GRADED[@]}"; do pairs+=("$g=${TWIN[$g]}"); done
CLVR_BENCH_CPU=$CPU /usr/bin/python3 "$ROOT/bench/graded_summary.py" "$RAW" "$BASE.json" "${pairs[@]}" >"$RAW/summary.md"
cat "$RAW/head.md" "$RAW/summary.md" "$MD" >"$BASE.md"
rm -rf "$RAW"
say "wrote $BASE.md and $BASE.json"
