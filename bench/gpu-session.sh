#!/usr/bin/env bash
# bench/gpu-session.sh: one lent GPU machine's checks, in a fixed time budget.
#
# Usage, on the GPU machine, from a copy of the tree with tools/gpu-bundle.sh's
# bundle unpacked beside it (build-bundle/):
#   bench/gpu-session.sh OUTDIR [SECONDS] [MESH-DIR]
# SECONDS (default 540) bounds the whole script; each phase gets what is left and is
# skipped when too little is. MESH-DIR holds .bin meshes for the convergence runs
# (comb-tets.bin, fire-tets.bin, notch.bin; missing ones are skipped).
#
# Phases, each appending to OUTDIR/res.tgz (a device tool brings back only a few files):
#  1. `clvr --list-devices`.
#  2. In the background, with a cache of its own: one render of the built-in scene with
#     CLVR_BUILD_LOG=1 and NVIDIA's -cl-nv-verbose: each program's cold compile time and
#     its registers and spills per kernel.
#  3. One render that fills the driver's kernel cache, then ctest on the GPU
#     (CLVR_TEST_DEVICE=gpu, or as set); test_cli_e2e still checks a cold cache.
#  4. bench_render --converge, urm and walk, with and without shadows: time to 2%
#     relative RMSE, the light grid's time, frame times.
#  5. bench/run-all.sh: point location (ours and Embree's on every core), preprocessing,
#     rendering at 2 s per configuration.
set -u
ROOT=$(cd "$(dirname "$0")/.." && pwd)
OUT=${1:?usage: gpu-session.sh OUTDIR [SECONDS] [MESH-DIR]}
BUDGET=${2:-540}
MESHES=${3:-$ROOT/.gpu-data}
B=$ROOT/build-bundle
DEV=${CLVR_TEST_DEVICE:-gpu}   # pocl: a dry run of the script on a CPU
T0=$(date +%s)
left() { echo $((BUDGET - ($(date +%s) - T0))); }
R=/tmp/gpu-session-results
rm -rf "$R" && mkdir -p "$R" "$OUT"
pack() { tar czf "$OUT/res.tgz.tmp" -C "$R" . && mv "$OUT/res.tgz.tmp" "$OUT/res.tgz"; }
stamp() { echo "[$(($(date +%s) - T0)) s] $*" | tee -a "$R/timeline.txt"; }

# The bundle's environment (tools/gpu-bundle.sh's env.sh): CTest's absolute
# paths, the bundled libraries, NVIDIA's ICD where the system lists none.
. "$B/env.sh" || exit 1

stamp "phase 1: devices"
"$B/clvr" --list-devices >"$R/devices.txt" 2>&1 || { cat "$R/devices.txt"; pack; exit 1; }
cat "$R/devices.txt"; nvidia-smi >"$R/nvidia-smi.txt" 2>&1; pack

stamp "phase 2: cold compile with -cl-nv-verbose (background)"
( CUDA_CACHE_PATH=/tmp/nv-verbose-cache CLVR_BUILD_LOG=1 CLVR_BUILD_OPTIONS=-cl-nv-verbose \
    timeout 400 "$B/clvr" --device "$DEV" --size 64x64 --spp 1 --stats -o /tmp/nv-verbose.exr \
    >"$R/nv-verbose.log" 2>&1; echo "exit $?" >>"$R/nv-verbose.log" ) &
VERBOSE=$!

# Session 42 let every test compile render.cl cold in its own process: about 220 s
# each, and test_render and test_cli_e2e ran out of time. One render first fills
# the driver's cache for all of them (the same programs with the same options).
stamp "phase 3: warm the kernel cache, then ctest"
timeout 400 "$B/clvr" --device "$DEV" --size 64x64 --spp 1 --denoise -o /tmp/warm.exr >"$R/warm.log" 2>&1
stamp "warm-up exit $?"
( cd "$B" && CLVR_TEST_DEVICE=$DEV timeout "$(( $(left) > 210 ? $(left) - 150 : 60 ))" ctest -j12 --timeout 260 --output-on-failure \
    >"$R/ctest.log" 2>&1; echo "ctest exit $?" >>"$R/ctest.log" )
grep -E "tests passed|\*\*\*|ctest exit" "$R/ctest.log"; pack

stamp "phase 4: convergence"
conv() {  # NAME ARGS...
  local name=$1; shift
  [ "$(left)" -gt 40 ] || { stamp "skip $name"; return; }
  timeout "$(( $(left) - 30 ))" "$B/bench_render" --device "$DEV" --converge --repeats 3 --json "$R/conv-$name.json" "$@" \
    >"$R/conv-$name.log" 2>&1
  stamp "$name exit $?"; pack
}
conv default-512-noshadow --size 512x512 --ref-spp 64 --max-spp 8 --estimators urm,walk --no-shadows
conv default-512-shadow --size 512x512 --ref-spp 64 --max-spp 8 --estimators urm,walk --only-shadows
for m in comb-tets fire-tets notch; do
  [ -f "$MESHES/$m.bin" ] || continue
  conv "$m-256" --mesh "$MESHES/$m.bin" --size 256x256 --ref-spp 64 --max-spp 8 --estimators urm,walk
done

stamp "phase 5: run-all"
if [ "$(left)" -gt 60 ]; then
  timeout "$(( $(left) - 45 ))" "$ROOT/bench/run-all.sh" --build "$B" --out "$R/bench" --timeout 90 \
    --only locate --only locate_embree --only preprocess >"$R/run-all.log" 2>&1
  stamp "run-all exit $?"; pack
fi
if [ "$(left)" -gt 40 ]; then
  timeout "$(( $(left) - 15 ))" "$ROOT/bench/run-all.sh" --build "$B" --out "$R/bench-render" --timeout 90 \
    --only render -- --budget 2 >>"$R/run-all.log" 2>&1
  stamp "run-all render exit $?"
fi
kill "$VERBOSE" 2>/dev/null
grep -E "built in|ptxas|registers|spill|exit" "$R/nv-verbose.log" | head -40
stamp "done"; pack
