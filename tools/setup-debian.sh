#!/usr/bin/env bash
# setup-debian.sh: installs everything clvr needs to build, test and fuzz on Debian 12.
#
# Idempotent and quiet: when every package is already installed it does not touch apt
# at all (one dpkg-query, well under 2 s). Otherwise it runs apt-get update and install
# non-interactively, logs to $CLVR_SETUP_LOG (default /tmp/clvr-setup-debian.log) and
# prints the log's tail only when something fails. Needs root or sudo.
set -euo pipefail

PACKAGES=(
  # OpenCL: the PoCL CPU device (CI's device), the ICD loader, headers, clinfo.
  pocl-opencl-icd ocl-icd-opencl-dev opencl-headers clinfo
  # Image output and the viewer.
  libopenexr-dev libpng-dev libglfw3-dev
  # Build.
  cmake make gcc g++ pkg-config
  # tools/clvr-convert (runs with /usr/bin/python3) and test-mesh generation.
  python3-vtk9 python3-numpy tetgen
  # Benchmarks: Embree 3 (the paper's Table 3 and issue 4 comparisons), VTK C++ for its cell locator.
  libembree-dev libvtk9-dev
  # Headless viewer tests.
  xvfb xauth xdotool
  # libFuzzer and the sanitizer runtimes for the fuzz targets.
  clang libclang-rt-14-dev
)

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
