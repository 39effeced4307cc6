#!/usr/bin/env bash
# Proves `pip install .` (issue 18): into a fresh venv (with Debian's numpy,
# meshio and VTK from --system-site-packages), offline (--no-index), with
# the in-tree build backend bundling this build's libclvr (CLVR_LIBRARY);
# the installed module loads its own copy of the library and passes
# tests/test_python.py --quick from outside the source tree.
# Usage: test_pip.sh BUILD_DIR SOURCE_DIR. Exit 77 without python3-venv.
set -u
BUILD=$1
SRC=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
/usr/bin/python3 -m venv --system-site-packages "$tmp/venv" >"$tmp/venv.log" 2>&1 ||
  { echo "test_pip: python3 -m venv failed (python3-venv): skipped"; exit 77; }
cd "$SRC" || exit 1
if ! CLVR_LIBRARY="$BUILD/libclvr.so.1" "$tmp/venv/bin/pip" install --no-index . >"$tmp/pip.log" 2>&1; then
  tail -20 "$tmp/pip.log"
  echo "test_pip: pip install . failed"
  exit 1
fi
cd "$tmp" || exit 1
lib=$(env -u CLVR_LIBRARY -u PYTHONPATH "$tmp/venv/bin/python" -c 'import clvr, os; print(os.path.realpath(clvr._lib._name))')
case $lib in
  "$tmp"/venv/lib/python3*/site-packages/clvr/libclvr.so.1) ;;
  *) echo "test_pip: the installed module loads '$lib', not its bundled libclvr.so.1"; exit 1 ;;
esac
env -u PYTHONPATH CLVR_SHARED_DATA="$SRC/tests/data" CLVR_BUILD_DIR="$BUILD" \
  "$tmp/venv/bin/python" "$SRC/tests/test_python.py" --quick
