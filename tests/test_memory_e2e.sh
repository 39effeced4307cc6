#!/usr/bin/env bash
# End-to-end memory checks of partitioned preprocessing (issue #15) through
# the built binaries: a generated mixed mesh renders in K partitions with
# bytes.peak_rss, bytes.resident and partitions in --stats-json, the same
# picture as in one partition, and with --element-boxes off (no boxes, same
# picture); under an address-space limit (ulimit -v) too
# small for it, clvr refuses from the .bin header with its own message and
# exit code 1 instead of aborting inside the OpenCL driver.
# Usage: test_memory_e2e.sh BUILD_DIR
set -u
BUILD=$1
CLVR=$BUILD/clvr
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
pass=0
fail=0
ok() { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); echo "FAILED: $*" >&2; }

if ! "$CLVR" --list-devices >/dev/null 2>&1; then echo "no OpenCL device: skipped"; exit 77; fi
"$BUILD/clvr-gen" mixed "$tmp/m.bin" --elements 200k --quiet || { echo "clvr-gen failed"; exit 1; }

for k in 1 3; do
  if "$CLVR" "$tmp/m.bin" -o "$tmp/k$k.pfm" --size 48x48 --spp 4 --partitions $k --stats-json "$tmp/k$k.json" -q \
      2>"$tmp/err$k"; then ok; else bad "--partitions $k failed: $(cat "$tmp/err$k")"; fi
done
/usr/bin/python3 - "$tmp" <<'PY' && ok || bad "stats or images"
import json, struct, sys
d = sys.argv[1]
a, b = json.load(open(d + "/k1.json")), json.load(open(d + "/k3.json"))
assert a["partitions"] == 1 and b["partitions"] == 3, (a["partitions"], b["partitions"])
for s in (a, b):
    assert s["bytes"]["peak_rss"] >= s["bytes"]["resident"] > 0, s["bytes"]
    assert s["bytes.peak_rss"] == s["bytes"]["peak_rss"]
    assert s["time"]["partition_s"] >= 0 and "merge_s" in s["time"]
assert b["time"]["partition_s"] > 0
def pfm(p):
    f = open(p, "rb").read()
    parts = f.split(b"\n", 3)
    w, h = map(int, parts[1].split())
    return struct.unpack("<%df" % (w * h * 3), parts[3][: w * h * 12])
x, y = pfm(d + "/k1.pfm"), pfm(d + "/k3.pfm")
# same seed, same elements found at the same points: the same picture
# (float rounding may differ in the traversal order of equal hits)
diff = max(abs(p - q) for p, q in zip(x, y))
assert diff < 1e-3, diff
assert max(x) > 0.01
PY

# --element-boxes off: no boxes in the stats, the same elements found, so
# the same picture; a wrong value is a usage error.
if "$CLVR" "$tmp/m.bin" -o "$tmp/nobox.pfm" --size 48x48 --spp 4 --partitions 1 --element-boxes off \
    --stats-json "$tmp/nobox.json" -q 2>"$tmp/errnb"; then ok; else bad "--element-boxes off failed: $(cat "$tmp/errnb")"; fi
/usr/bin/python3 - "$tmp" <<'PY' && ok || bad "--element-boxes off: stats or image"
import json, struct, sys
d = sys.argv[1]
a, b = json.load(open(d + "/k1.json")), json.load(open(d + "/nobox.json"))
assert a["bytes"]["element_boxes"] > 0 and b["bytes"]["element_boxes"] == 0, (a["bytes"], b["bytes"])
def pfm(p):
    f = open(p, "rb").read()
    parts = f.split(b"\n", 3)
    w, h = map(int, parts[1].split())
    return struct.unpack("<%df" % (w * h * 3), parts[3][: w * h * 12])
x, y = pfm(d + "/k1.pfm"), pfm(d + "/nobox.pfm")
diff = max(abs(p - q) for p, q in zip(x, y))
assert diff < 1e-3 and max(x) > 0.01, diff
PY
"$CLVR" "$tmp/m.bin" -o "$tmp/x.png" --element-boxes maybe >/dev/null 2>"$tmp/erru"
rc=$?
if [ "$rc" -eq 2 ] && grep -q "element-boxes expects on, off or auto" "$tmp/erru"; then ok
else bad "--element-boxes maybe: exit $rc: $(cat "$tmp/erru")"; fi

# A device allocation limit too small (lowered for the test): the device
# check runs from the .bin header too, before the mesh is read (no
# "loading" line), with the numbers and exit code 4 (device memory).
CLVR_MAX_ALLOC_BYTES=1000000 "$CLVR" "$tmp/m.bin" -o "$tmp/small.png" --spp 1 >"$tmp/out" 2>"$tmp/err"
rc=$?
if [ "$rc" -eq 4 ] && grep -q "CL_DEVICE_MAX_MEM_ALLOC_SIZE, lowered" "$tmp/err" && grep -q -- "--partitions" "$tmp/err" \
   && ! grep -q "clvr: loading" "$tmp/err" && [ ! -e "$tmp/small.png" ]; then ok
else bad "CLVR_MAX_ALLOC_BYTES=1000000: exit $rc: $(head -c 600 "$tmp/err")"; fi

# The walk estimator's face adjacency (16 bytes per tet, one buffer): a
# mesh split into pieces below the allocation limit renders with urm and
# says so, with no adjacency in the stats; without the limit it is built
# and counted, silently.
"$BUILD/clvr-gen" cellvar "$tmp/t.bin" --elements 600k --quiet || bad "clvr-gen cellvar failed"
for lim in 9000000 0; do
  if [ "$lim" -gt 0 ]; then export CLVR_MAX_ALLOC_BYTES=$lim; else unset CLVR_MAX_ALLOC_BYTES; fi
  "$CLVR" "$tmp/t.bin" -o "$tmp/w$lim.pfm" --size 32x32 --spp 1 --partitions 2 --shadows off --estimator walk \
    --stats-json "$tmp/w$lim.json" >"$tmp/out" 2>"$tmp/err" || bad "walk with limit $lim: $(head -c 600 "$tmp/err")"
  n=$(grep -c "could not hold the walk estimator's face adjacency" "$tmp/err")
  want=0
  [ "$lim" -gt 0 ] && want=1
  if [ "$n" -eq "$want" ]; then ok; else bad "walk with limit $lim: $n adjacency notices: $(head -c 600 "$tmp/err")"; fi
done
unset CLVR_MAX_ALLOC_BYTES
/usr/bin/python3 - "$tmp" <<'PY' && ok || bad "adjacency bytes in --stats-json"
import json, sys
d = sys.argv[1]
a, b = json.load(open(d + "/w9000000.json")), json.load(open(d + "/w0.json"))
assert a["bytes"]["adjacency"] == 0, a["bytes"]
# 4 bytes per face slot, 4 slots per tet, and 4 per instance cluster + 1
assert 16 * b["elements"] < b["bytes"]["adjacency"] < 16 * b["elements"] + 4096, (b["bytes"], b["elements"])
PY

# An address space too small: clvr's own refusal, from the header. (Not
# under AddressSanitizer, whose shadow memory alone needs terabytes of
# address space: such a binary cannot start under ulimit -v at all.)
if grep -q "^CLVR_SANITIZE:BOOL=ON" "$BUILD/CMakeCache.txt" 2>/dev/null; then
  echo "sanitizer build: the ulimit -v check is skipped"
else
  ( ulimit -v 400000; "$CLVR" "$tmp/m.bin" -o "$tmp/no.png" --spp 1 ) >"$tmp/out" 2>"$tmp/err"
  rc=$?
  if [ "$rc" -eq 1 ] && grep -q "address-space limit" "$tmp/err" && grep -q "ulimit -v" "$tmp/err" \
     && grep -Eq "[0-9]+ elements, [0-9]+ vertices need about" "$tmp/err" && [ ! -e "$tmp/no.png" ]; then ok
  else bad "ulimit -v 400000: exit $rc: $(head -c 600 "$tmp/err")"; fi
fi

echo "test_memory_e2e: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
