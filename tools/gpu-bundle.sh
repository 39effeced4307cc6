#!/usr/bin/env bash
# tools/gpu-bundle.sh: clvr's tests and benchmarks on a machine that has a GPU
# vendor's OpenCL driver but nothing else clvr needs (no OpenCL loader, PoCL,
# OpenEXR, compiler or network): a rented GPU node, a bare container.
#
# Usage, here (Debian 12 with tools/setup-debian.sh test done):
#   tools/gpu-bundle.sh [OUT.tar.xz]      (default: gpu-bundle.tar.xz)
# builds build-bundle/ (no viewer, MPI or VTK; the tests and benchmarks) and
# packs it with the shared libraries it loads that glibc does not provide
# (Debian's libOpenCL.so.1 loader, OpenEXR, Imath, libpng, Embree, TBB), about
# 12 MB. There, from a copy of the same source tree:
#   tar xJf gpu-bundle.tar.xz && bash build-bundle/run-on-device.sh OUTDIR [TESTS-REGEX]
# runs ctest on the first GPU (CLVR_TEST_DEVICE=gpu; CTEST_LIMIT seconds, 300),
# then, without a regex, bench/run-all.sh (BENCH_LIMIT, 300, per part), and
# writes OUTDIR/ctest.log, OUTDIR/run-all.log and the benchmark reports under
# OUTDIR/bench and OUTDIR/bench-render. A cold NVIDIA cache costs about 140 s
# of kernel compilation in the first test that builds each program. CTest files hold this tree's absolute path: the runner
# links it to the copy when the paths differ (it must be able to create it).
# The ICD: the system's /etc/OpenCL/vendors if it has one, else an ICD file
# naming libnvidia-opencl.so.1 where the driver put it (found by ldconfig or
# under /usr/local/nvidia).
# bench/gpu-session.sh runs the same in a fixed time budget, with a cold-compile
# build log and convergence runs (session 42).
# Results: bench/results/gpu/2026-11-28-nvidia-h200.md, 2026-11-29-nvidia-h200-s42.md.
set -euo pipefail

cd "$(dirname "$0")/.."
OUTF=${1:-gpu-bundle.tar.xz}
B=build-bundle
cmake -S . -B "$B" -DCMAKE_BUILD_TYPE=Release -DCLVR_VIEWER=OFF -DCMAKE_DISABLE_FIND_PACKAGE_MPI=ON \
  -DCMAKE_DISABLE_FIND_PACKAGE_VTK=ON >"$B.configure.log" 2>&1 || { cat "$B.configure.log" >&2; exit 1; }
cmake --build "$B" -j"${CLVR_JOBS:-2}"

# Libraries the programs load, less glibc's and the C++ runtime's (a newer
# distribution has newer ones, which old binaries can use).
mkdir -p "$B/lib"
for f in "$B"/clvr "$B"/bench_* "$B"/test_* "$B"/lib*.so*; do
  [ -f "$f" ] && [ -x "$f" ] || continue
  ldd "$f" 2>/dev/null | awk '/=> \// { print $3 }'
done | sort -u | while read -r lib; do
  case $(basename "$lib") in
    libc.so*|libm.so*|libpthread.so*|libdl.so*|librt.so*|libgcc_s.so*|libstdc++.so*|ld-linux*|libclvr*) ;;
    *) cp -L "$lib" "$B/lib/" ;;
  esac
done

# env.sh: the environment on the device, sourced by run-on-device.sh and
# bench/gpu-session.sh. ROOT is the tree the bundle lies in there.
cat >"$B/env.sh" <<EOF
# Written by tools/gpu-bundle.sh; source it (it sets ROOT and the environment).
SRC=$PWD                       # the tree the bundle was built in (CTest's paths)
EOF
cat >>"$B/env.sh" <<'EOF'
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
if [ "$ROOT" != "$SRC" ]; then
  if [ -e "$SRC" ] && [ ! -L "$SRC" ]; then echo "gpu bundle: $SRC exists and is not this tree: run from there" >&2; return 1; fi
  mkdir -p "$(dirname "$SRC")" && ln -sfn "$ROOT" "$SRC" || return 1
fi
export LD_LIBRARY_PATH=$ROOT/build-bundle/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
# A system ICD directory may list PoCL alone (the H200 machine of session 42 did):
# then NVIDIA's library joins a copy of it.
if ! grep -qs nvidia /etc/OpenCL/vendors/*.icd && [ -z "${OCL_ICD_VENDORS:-}" ]; then
  lib=$(ldconfig -p | awk '/libnvidia-opencl.so.1/ { print $NF; exit }')
  [ -n "$lib" ] || lib=$(ls /usr/local/nvidia/lib64/libnvidia-opencl.so.1 2>/dev/null || true)
  mkdir -p "$ROOT/build-bundle/icd" && cp /etc/OpenCL/vendors/*.icd "$ROOT/build-bundle/icd/" 2>/dev/null
  echo "${lib:-libnvidia-opencl.so.1}" >"$ROOT/build-bundle/icd/nvidia.icd"
  export OCL_ICD_VENDORS=$ROOT/build-bundle/icd
fi
EOF

cat >"$B/run-on-device.sh" <<'EOF'
#!/usr/bin/env bash
# Written by tools/gpu-bundle.sh: the tests and benchmarks on the first GPU.
set -u
. "$(dirname "$0")/env.sh" || exit 1
OUT=${1:?usage: run-on-device.sh OUTDIR [TESTS-REGEX]}
REGEX=${2:-}
mkdir -p "$OUT"
"$ROOT/build-bundle/clvr" --list-devices || exit 1
( cd "$ROOT/build-bundle" &&
  CLVR_TEST_DEVICE=${CLVR_TEST_DEVICE:-gpu} timeout "${CTEST_LIMIT:-300}" ctest -j"${CTEST_JOBS:-8}" --timeout 240 \
    ${REGEX:+-R "$REGEX"} --output-on-failure >"$OUT/ctest.log" 2>&1 )
echo "ctest exit $?"; grep -E "tests passed|\*\*\*" "$OUT/ctest.log"
[ -n "$REGEX" ] && exit 0
# bench_render alone, at 4 s per configuration instead of its 30 (10 of them).
mkdir -p "$OUT/bench" "$OUT/bench-render"
timeout "${BENCH_LIMIT:-300}" "$ROOT/bench/run-all.sh" --build "$ROOT/build-bundle" --out "$OUT/bench" --timeout 150 \
  --only locate --only locate_embree --only preprocess >"$OUT/run-all.log" 2>&1
echo "run-all exit $?"
timeout "${BENCH_LIMIT:-300}" "$ROOT/bench/run-all.sh" --build "$ROOT/build-bundle" --out "$OUT/bench-render" --timeout 150 \
  --only render -- --budget 4 >>"$OUT/run-all.log" 2>&1
echo "run-all (render) exit $?"; grep -E "^run-all.sh|failed" "$OUT/run-all.log"
EOF
chmod +x "$B/run-on-device.sh"
tar cf - --exclude='*.o' --exclude='*.o.d' --exclude="$B/CMakeFiles/*.dir" --exclude="$B/CMakeFiles/CMakeScratch" "$B" | xz -T"${CLVR_JOBS:-2}" -6 >"$OUTF.tmp"
mv "$OUTF.tmp" "$OUTF"
echo "gpu-bundle.sh: wrote $OUTF ($(du -h "$OUTF" | cut -f1)); there: tar xJf $(basename "$OUTF") && bash $B/run-on-device.sh OUTDIR"
