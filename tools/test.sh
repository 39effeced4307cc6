#!/usr/bin/env bash
# tools/test.sh: the one command that proves clvr works on this machine (README, CI).
#
# Runs stages in order and stops at the first failure, exiting with its status (the
# test stage exits with ctest's). Usage: tools/test.sh [STAGE...]; no argument runs
# DEFAULT_STAGES. Adding a stage: write a stage_NAME function and list NAME below.
# Environment: CLVR_BUILD (build directory, default build), CLVR_JOBS (default 2),
# CTEST_PARALLEL_LEVEL (ctest's own; default CLVR_JOBS: tests run two at a time,
# which took the sanitizer stage's first pass from 565 to 374 s on a 2-core VM,
# since most of a test under ASan is single-threaded host code; every test keeps
# its files apart: mkdtemp, or names with its pid).
set -euo pipefail

cd "$(dirname "$0")/.."
BUILD=${CLVR_BUILD:-build}
JOBS=${CLVR_JOBS:-2}
export CTEST_PARALLEL_LEVEL=${CTEST_PARALLEL_LEVEL:-$JOBS}
DEFAULT_STAGES=(setup configure build test sanitize fuzz)

# Packages: the `test` group of tools/setup-debian.sh (running, converting, tests,
# benchmarks, fuzzing); it returns at once when all are installed, and uses sudo
# itself when it must install as a user that is not root.
stage_setup() {
  tools/setup-debian.sh test
}

stage_configure() {
  mkdir -p "$BUILD"
  cmake -S . -B "$BUILD" -DCLVR_WERROR=ON >"$BUILD/configure.log" 2>&1 ||
    { cat "$BUILD/configure.log" >&2; return 1; }
}

stage_build() {
  cmake --build "$BUILD" -j"$JOBS"
}

stage_test() {
  ctest --test-dir "$BUILD" --output-on-failure && TEST_STAGE_RAN=1
}

# The whole suite again under AddressSanitizer + UndefinedBehaviorSanitizer
# (gcc, build-asan), without the `slow` label. PoCL's own leaks and its LLVM JIT
# need a few runtime options: see tools/sanitizer.supp and tools/sanitizer.env.
# It relies on the test stage before it: PoCL's LLVM leaks (no clvr frame) in
# every process that compiles a kernel, and the test stage leaves every kernel
# the suite builds in PoCL's cache (~/.cache/pocl), so that here none compiles.
# Run alone on a machine whose cache lacks them, 11 tests failed on those
# leaks (session 60); `tools/test.sh test sanitize` is the way to run it.
ASAN_BUILD=${CLVR_ASAN_BUILD:-build-asan}
TEST_STAGE_RAN=0
stage_sanitize() {
  [ "$TEST_STAGE_RAN" = 1 ] ||
    echo "sanitize: the test stage did not run first; kernels not in PoCL's cache compile here, and" \
      "PoCL's LLVM leaks then fail tests with reports that name only libpocl/libLLVM frames" \
      "(tools/sanitizer.supp). Run 'tools/test.sh test sanitize' to rule that out." >&2
  mkdir -p "$ASAN_BUILD"
  cmake -S . -B "$ASAN_BUILD" -DCLVR_SANITIZE=ON -DCLVR_WERROR=ON -DCLVR_BIG_TESTS=OFF \
    >"$ASAN_BUILD/configure.log" 2>&1 || { cat "$ASAN_BUILD/configure.log" >&2; return 1; }
  cmake --build "$ASAN_BUILD" -j"$JOBS" || return 1
  (
    # shellcheck source=tools/sanitizer.env
    . tools/sanitizer.env
    # Chained with &&: stages run where `set -e` is off (`stage_X || rc=$?`), so a
    # failure of the first pass must not be hidden by the second's status.
    ctest --test-dir "$ASAN_BUILD" -LE "slow|$CLVR_SANITIZE_NO_LEAK_LABELS" --output-on-failure &&
      ASAN_OPTIONS="$ASAN_OPTIONS:detect_leaks=0" \
        ctest --test-dir "$ASAN_BUILD" -L "$CLVR_SANITIZE_NO_LEAK_LABELS" -LE slow --output-on-failure
  )
}

# libFuzzer (clang, build-fuzz) on every reader and the transfer-function
# parser, CLVR_FUZZ_SECONDS each (default 35; 45 until CI neared its 30-minute
# bound) with ASan + UBSan, seeded with tests/fuzz/seeds, tests/fuzz/regressions
# and tests/data. The corpus grows in build-fuzz/corpus between runs. A crash
# stops the stage with the input's path: fix the parser, then copy the input to
# tests/fuzz/regressions/<target>/.
FUZZ_BUILD=${CLVR_FUZZ_BUILD:-build-fuzz}
FUZZ_SECONDS=${CLVR_FUZZ_SECONDS:-35}
stage_fuzz() {
  command -v clang >/dev/null || { echo "fuzz: clang not found (tools/setup-debian.sh installs it)" >&2; return 1; }
  mkdir -p "$FUZZ_BUILD"
  CC=clang cmake -S . -B "$FUZZ_BUILD" -DCLVR_FUZZ=ON -DCLVR_WERROR=ON -DCLVR_BIG_TESTS=OFF -DCLVR_VIEWER=OFF \
    >"$FUZZ_BUILD/configure.log" 2>&1 || { cat "$FUZZ_BUILD/configure.log" >&2; return 1; }
  cmake --build "$FUZZ_BUILD" -j"$JOBS" --target fuzz_bin fuzz_umesh fuzz_vtk fuzz_tf || return 1
  local t
  for t in bin umesh vtk tf; do
    local corpus="$FUZZ_BUILD/corpus/$t" artifacts="$FUZZ_BUILD/artifacts/$t" log="$FUZZ_BUILD/fuzz_$t.log"
    local seeds=(tests/fuzz/seeds/"$t" tests/fuzz/regressions/"$t") opts=()
    case $t in
      umesh) seeds+=(tests/data/umesh) ;;
      vtk) seeds+=(tests/data/vtk); opts+=(-dict=tests/fuzz/vtk.dict) ;;
      tf) opts+=(-dict=tests/fuzz/tf.dict) ;;
    esac
    mkdir -p "$corpus" "$artifacts"
    # -seed=1: the same mutation sequence on every run, so CI is repeatable.
    # -max_len keeps the big tests/data files as (truncated) seeds without
    # slowing every run; leaks are errors (libFuzzer's default with ASan).
    if ! UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 "$FUZZ_BUILD/fuzz_$t" \
        -seed=1 -max_total_time="$FUZZ_SECONDS" -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
        -artifact_prefix="$artifacts/" -print_final_stats=1 "${opts[@]}" "$corpus" "${seeds[@]}" >"$log" 2>&1; then
      tail -n 40 "$log" >&2
      echo "fuzz_$t: crash; input(s): $(ls "$artifacts"/* 2>/dev/null | tr '\n' ' ')" >&2
      echo "fuzz_$t: fix it, then: cp INPUT tests/fuzz/regressions/$t/<what-it-was> (replayed by ctest)" >&2
      return 1
    fi
    echo "fuzz_$t: $(sed -n 's/^stat::number_of_executed_units: *//p' "$log") runs in ${FUZZ_SECONDS} s," \
      "$(grep -o 'cov: [0-9]*' "$log" | tail -n 1), corpus $(find "$corpus" -type f | wc -l) files, no crash"
  done
}

stages=("$@")
[ ${#stages[@]} -gt 0 ] || stages=("${DEFAULT_STAGES[@]}")
for s in "${stages[@]}"; do
  if ! declare -F "stage_$s" >/dev/null; then
    echo "tools/test.sh: unknown stage '$s' (stages: $(declare -F | sed -n 's/^declare -f stage_//p' | tr '\n' ' '))" >&2
    exit 2
  fi
done
for s in "${stages[@]}"; do
  echo "== $s"
  start=$SECONDS
  rc=0
  "stage_$s" || rc=$?
  if [ $rc -ne 0 ]; then
    echo "== $s failed (exit $rc) after $((SECONDS - start)) s" >&2
    exit $rc
  fi
  echo "== $s ok ($((SECONDS - start)) s)"
done
