#!/usr/bin/env bash
# tools/test.sh: the one command that proves clvr works on this machine (README, CI).
#
# Runs stages in order and stops at the first failure, exiting with its status (the
# test stage exits with ctest's). Usage: tools/test.sh [STAGE...]; no argument runs
# DEFAULT_STAGES. Adding a stage: write a stage_NAME function and list NAME below.
# Environment: CLVR_BUILD (build directory, default build), CLVR_JOBS (default 2),
# CTEST_PARALLEL_LEVEL (ctest's own).
set -euo pipefail

cd "$(dirname "$0")/.."
BUILD=${CLVR_BUILD:-build}
JOBS=${CLVR_JOBS:-2}
DEFAULT_STAGES=(setup configure build test)

# Packages: tools/setup-debian.sh returns at once when all are installed, and uses
# sudo itself when it must install as a user that is not root.
stage_setup() {
  tools/setup-debian.sh
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
  ctest --test-dir "$BUILD" --output-on-failure
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
