#!/usr/bin/env bash
# Sets up a fresh Debian 12 machine with what running clvr needs (the `run`
# group of tools/setup-debian.sh: no test, benchmark or fuzzing packages),
# builds clvr and renders the built-in default scene to clvr.png (pass other
# clvr options after the script name, e.g. `tools/demo.sh -o scene.exr --spp 256`).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$here/tools/setup-debian.sh" run
cmake -S "$here" -B "$here/build" -DCMAKE_BUILD_TYPE=Release > "$here/build-configure.log" 2>&1 \
  || { cat "$here/build-configure.log"; exit 1; }
cmake --build "$here/build" -j"$(nproc)" --target clvr > "$here/build.log" 2>&1 \
  || { tail -50 "$here/build.log"; exit 1; }
"$here/build/clvr" "$@"
