#!/usr/bin/env bash
# Proves `cmake --install` (issue 17): into a temporary prefix it puts clvr,
# clvr-gen and clvr-convert in bin/, clvr.1 (made from clvr --help, so it names
# every option the help names) in share/man/man1, README and docs in
# share/doc/clvr; the installed clvr runs from there (--help, --version, and a
# tiny render where an OpenCL device exists), away from the source tree.
# The fallback page maker (tools/man_from_help.cmake, for machines without
# help2man) is checked the same way.
# Usage: test_install.sh BUILD_DIR SOURCE_DIR
set -u
BUILD=$1
SRC=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
pass=0
fail=0
ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); echo "FAILED: $*" >&2; }

if ! cmake --install "$BUILD" --prefix "$tmp/p" >"$tmp/install.log" 2>&1; then
  bad "cmake --install failed: $(tail -5 "$tmp/install.log")"
  echo "test_install: $pass passed, $fail failed"
  exit 1
fi
P=$tmp/p
for f in bin/clvr bin/clvr-gen bin/clvr-convert; do
  [ -x "$P/$f" ] && ok || bad "$f missing or not executable"
done
for f in share/man/man1/clvr.1 share/doc/clvr/README.md share/doc/clvr/bin-format.md \
  share/doc/clvr/transfer-function.md share/doc/clvr/troubleshooting.md share/doc/clvr/viewer.md; do
  [ -s "$P/$f" ] && ok || bad "$f missing or empty"
done
man1=$P/share/man/man1/clvr.1
cd "$tmp" || exit 1
"$P/bin/clvr" --help >"$tmp/help" 2>&1 && ok || bad "installed clvr --help failed"
# A man page: the .TH header, and every option of --help (roff writes - as \-).
check_man() {
  grep -q '^\.TH CLVR "\?1' "$1" && ok || bad "$1 has no .TH CLVR 1 header"
  sed 's/\\-/-/g; s/\\f[BIRP]//g; s/\\e/\\/g' "$1" >"$tmp/man.txt"
  local missing
  missing=$(grep -o -- '--[a-z][a-z-]*' "$tmp/help" | sort -u | while read -r opt; do
    grep -qF -- "$opt" "$tmp/man.txt" || echo "$opt"
  done)
  [ -z "$missing" ] && ok || bad "options of --help missing from $1: $missing"
}
check_man "$man1"
cmake -DCLVR="$P/bin/clvr" -DOUT="$tmp/fallback.1" -DVERSION=0 -P "$SRC/tools/man_from_help.cmake" &&
  check_man "$tmp/fallback.1" || bad "tools/man_from_help.cmake failed"
"$P/bin/clvr" --version | grep -q "^clvr [0-9]" && ok || bad "installed clvr --version"
"$P/bin/clvr-convert" --help >/dev/null 2>&1 && ok || bad "installed clvr-convert --help"
if "$P/bin/clvr" --list-devices >/dev/null 2>&1; then
  "$P/bin/clvr" --device pocl --size 8x8 --spp 1 --quiet -o "$tmp/i.png" && [ -s "$tmp/i.png" ] && ok ||
    bad "installed clvr does not render"
else
  echo "note: no OpenCL device; the installed clvr's render is not tried"
fi

echo "test_install: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
