#!/usr/bin/env bash
# End-to-end checks of the clvr command line through the built binary: the
# built-in scene renders to every image format, --info and --stats-json report
# the documented fields, and bad command lines / files / devices exit with the
# documented codes and a one-line message, leaving no output file behind.
# Usage: test_cli_e2e.sh BUILD_DIR DATA_DIR
set -u
BUILD=$1
DATA=$2
CLVR=$BUILD/clvr
PY=/usr/bin/python3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
pass=0
fail=0
ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); echo "FAILED: $*" >&2; }

# expect CODE SUBSTRING -- command...: exit code and a stderr substring
expect() {
  local code=$1 text=$2
  shift 3
  "$@" >"$tmp/out" 2>"$tmp/err"
  local rc=$?
  if [ "$rc" -ne "$code" ]; then bad "$* exited $rc, expected $code: $(head -c 400 "$tmp/err")"; return; fi
  if [ -n "$text" ] && ! grep -qF -- "$text" "$tmp/err"; then bad "$*: stderr lacks '$text': $(head -c 400 "$tmp/err")"; return; fi
  ok
}

if ! "$CLVR" --list-devices >"$tmp/devices" 2>&1; then
  echo "SKIP: no OpenCL device: $(cat "$tmp/devices")"
  exit 77
fi
grep -q "device 0:0" "$tmp/devices" && grep -q "compute units" "$tmp/devices" && ok || bad "--list-devices output"

# The built-in scene renders to each format, with stats.
for ext in png exr pfm; do
  expect 0 "" -- "$CLVR" --device pocl --size 48x32 --spp 2 --quiet -o "$tmp/scene.$ext" --stats-json "$tmp/s.json"
  [ -s "$tmp/scene.$ext" ] && ok || bad "no $ext written"
done
head -c 8 "$tmp/scene.png" | od -An -c | grep -q "P   N   G" && ok || bad "png signature"
head -c 4 "$tmp/scene.exr" | od -An -tx1 | grep -q "76 2f 31 01" && ok || bad "exr magic"
head -c 2 "$tmp/scene.pfm" | grep -q "PF" && ok || bad "pfm header"
ls "$tmp" | grep -q "\.tmp\." && bad "temporary file left behind" || ok
$PY - "$tmp/s.json" <<'PYEOF' && ok || bad "stats json keys"
import json, sys, math
d = json.load(open(sys.argv[1]))
keys = ["elements", "bytes.vertices", "bytes.indices_before", "bytes.indices_after", "bytes.bvh",
        "time.preprocess_s", "render.rays_per_s", "render.samples_per_ray",
        "render.null_collisions_per_ray", "render.frame_s"]
for k in keys:
    v = d.get(k)
    if v is None:  # nested form
        v = d
        for part in k.split("."):
            v = v[part]
    assert isinstance(v, (int, float)) and math.isfinite(v), (k, v)
assert d["elements"] > 100000
assert d["bytes"]["indices_after"] < d["bytes"]["indices_before"]
assert d["render"]["rays_per_s"] > 0
PYEOF

# --info on every natively read test file.
for f in "$DATA"/vtk/*.vtk "$DATA"/umesh/*.umesh; do
  expect 0 "" -- "$CLVR" --info "$f"
  grep -q "^elements" "$tmp/out" && ok || bad "--info $f: no element count"
done
expect 0 "" -- "$CLVR" --info "$DATA/vtk/post.vtk"
grep -q "tets      8750" "$tmp/out" && ok || bad "post.vtk tet count: $(cat "$tmp/out")"

# Every method renders a real file.
for m in march track bins dda; do
  expect 0 "" -- "$CLVR" --device pocl "$DATA/vtk/post.vtk" --method $m --size 24x24 --spp 2 --quiet -o "$tmp/m.png"
done

# Usage errors: exit 2, the option named.
expect 2 "--size" -- "$CLVR" --size 0x5
expect 2 "--method" -- "$CLVR" --method nope
expect 2 "unknown option" -- "$CLVR" --frobnicate
expect 2 "--spp" -- "$CLVR" --spp
# Input errors: exit 3, the file named, no output written.
expect 3 "nope.bin" -- "$CLVR" "$tmp/nope.bin" -o "$tmp/never.png"
head -c 100 "$DATA/vtk/post.vtk" >"$tmp/cut.vtk"
expect 3 "cut.vtk" -- "$CLVR" "$tmp/cut.vtk" -o "$tmp/never.png"
[ -e "$tmp/never.png" ] && bad "output written for a bad input" || ok
# Device errors: exit 4 with what exists.
expect 4 "available" -- "$CLVR" --device no-such-device-xyz -o "$tmp/never.png"
expect 4 "pocl" -- env CLVR_FAIL=clGetPlatformIDs "$CLVR" -o "$tmp/never.png"
# Output errors: exit 5, an older file survives.
echo old >"$tmp/keep.png"
expect 2 ".jpg" -- "$CLVR" --device pocl --size 8x8 --spp 1 --quiet -o "$tmp/x.jpg"
expect 5 "no-such-dir" -- "$CLVR" --device pocl --size 8x8 --spp 1 --quiet -o "$tmp/no-such-dir/x.png"
[ "$(cat "$tmp/keep.png")" = old ] && ok || bad "older file damaged"

echo "test_cli_e2e: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
