#!/usr/bin/env bash
# setup-debian.sh: installs the Debian 12 packages clvr needs, by group.
#
# Usage: tools/setup-debian.sh [run|convert|test|all]   (default: all)
#        tools/setup-debian.sh --list GROUP             (print the group's packages)
#   run      build and run clvr: OpenCL (PoCL), OpenEXR, libpng, GLFW, CMake, a compiler,
#            pkg-config, Open MPI (the mpirun mode; what tools/demo.sh installs)
#   convert  run + tools/clvr-convert's VTK and NumPy
#   test     convert + what tools/test.sh needs: test meshes, benchmarks' Embree and VTK,
#            the headless viewer tests, fuzzing (clang), the man page (help2man), the
#            Python module's tests (meshio, venv)
#   all      everything (= test)
#
# Idempotent and quiet: when every package of the group is already installed it does
# not touch apt at all (one dpkg-query, well under 2 s). Otherwise it runs apt-get
# update and install non-interactively, logs to $CLVR_SETUP_LOG (default
# /tmp/clvr-setup-debian.log) and prints the log's tail only when something fails.
# Needs root or sudo. Exit status: 0 done, 1 installation failed or needs root, 2 bad
# command line.
set -euo pipefail

RUN_PACKAGES=(
  # OpenCL: the PoCL CPU device, the ICD loader and headers.
  pocl-opencl-icd ocl-icd-opencl-dev opencl-headers
  # Image output and the viewer.
  libopenexr-dev libpng-dev libglfw3-dev
  # Build.
  cmake make gcc g++ pkg-config
  # MPI mode (`mpirun -n N clvr ...`, docs/mpi-compositing.md); optional at build time.
  libopenmpi-dev openmpi-bin
)
CONVERT_PACKAGES=(
  # tools/clvr-convert (runs with /usr/bin/python3).
  python3-vtk9 python3-numpy
)
TEST_PACKAGES=(
  # Device listing in bug reports and CI logs; test-mesh generation.
  clinfo tetgen
  # Benchmarks: Embree 3 (the paper's Table 3 and issue 4 comparisons), VTK C++ for its cell locator.
  libembree-dev libvtk9-dev
  # Headless viewer tests.
  xvfb xauth xdotool
  # libFuzzer and the sanitizer runtimes for the fuzz targets.
  clang libclang-rt-14-dev
  # clvr.1 from clvr --help at build time (the install test checks it).
  help2man
  # The Python module's tests (issue 18): meshes from meshio, `pip install .` into a venv
  # (numpy and VTK come with the convert group).
  python3-meshio python3-venv
)

list_only=0
if [ "${1:-}" = "--list" ]; then
  list_only=1
  shift
fi
group=${1:-all}
case $group in
  run) PACKAGES=("${RUN_PACKAGES[@]}") ;;
  convert) PACKAGES=("${RUN_PACKAGES[@]}" "${CONVERT_PACKAGES[@]}") ;;
  test | all) PACKAGES=("${RUN_PACKAGES[@]}" "${CONVERT_PACKAGES[@]}" "${TEST_PACKAGES[@]}") ;;
  *)
    echo "setup-debian.sh: unknown group '$group'; use run, convert, test or all (--list GROUP prints one)" >&2
    exit 2
    ;;
esac
if [ $# -gt 1 ]; then
  echo "setup-debian.sh: one group at a time, got '$*'; use run, convert, test or all" >&2
  exit 2
fi
if [ $list_only -eq 1 ]; then
  printf '%s\n' "${PACKAGES[@]}"
  exit 0
fi

LOG=${CLVR_SETUP_LOG:-/tmp/clvr-setup-debian.log}

missing=()
for pkg in "${PACKAGES[@]}"; do
  [ "$(dpkg-query -W -f='${db:Status-Status}' "$pkg" 2>/dev/null)" = installed ] ||
    missing+=("$pkg")
done

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

if [ "$(id -u)" -eq 0 ]; then
  SUDO=()
elif command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
  SUDO=(sudo -n)
else
  echo "setup-debian.sh: missing packages: ${missing[*]}" >&2
  echo "setup-debian.sh: installing them needs root: run as root, or give this user" \
       "password-less sudo" >&2
  exit 1
fi

echo "setup-debian.sh: installing ${missing[*]} (log: $LOG)"
if ! { "${SUDO[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -qq &&
       "${SUDO[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq \
         --no-install-recommends "${missing[@]}"; } >"$LOG" 2>&1; then
  echo "setup-debian.sh: apt-get failed; last lines of $LOG:" >&2
  tail -n 25 "$LOG" >&2
  exit 1
fi
echo "setup-debian.sh: done"
