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
# The device the renders run on (tests/test_device.h: CLVR_TEST_DEVICE, default pocl).
DEV=${CLVR_TEST_DEVICE:-pocl}
# The exposure, background, camera, legend, clip and colour-map options are
# checked on a small real file (notch_stress.vtk: 2,192 hexes and wedges, 0.9 s a
# run under ASan against 2 s for the built-in scene's 275k cells, which the
# format, stats and display checks keep).
S=(--device "$DEV" "$DATA/vtk/notch_stress.vtk")
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
  expect 0 "" -- "$CLVR" --device "$DEV" --size 48x32 --spp 2 --quiet -o "$tmp/scene.$ext" --stats-json "$tmp/s.json"
  [ -s "$tmp/scene.$ext" ] && ok || bad "no $ext written"
done
# A run with memory to spare keeps its element boxes and says nothing about them.
"$CLVR" --device "$DEV" --size 16x16 --spp 1 -o "$tmp/boxes.png" 2>"$tmp/boxes.err" && ok || bad "render for the element-box notice"
grep -q "element boxes" "$tmp/boxes.err" && bad "element-box notice on a run that fits with them: $(grep "element boxes" "$tmp/boxes.err")" || ok
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
# The image pass (the control variates' fit, on by default) ran once for the
# image written; the built-in scene has shadows, so the light grid was built.
assert d["render"]["image_s"] > 0 and d["render"]["light_s"] > 0, d["render"]
PYEOF

# --estimator auto with shadows (the default) walks a small tet mesh (its face
# adjacency is built), urm does not (clvr_estimator_auto); on a mesh without
# tets (notch_stress: hexes and wedges) auto's pilot picks the walk through
# them or urm (it needs the adjacency either way, 24 bytes a hex, 18 a
# wedge), and says which: --stats-json's render.estimator and
# render.pilot_walk_cells (-1 on a tet mesh, where no pilot runs).
for est in auto urm; do
  expect 0 "" -- "$CLVR" --device "$DEV" --size 16x16 --spp 1 --quiet --estimator $est -o "$tmp/post-$est.png" \
    --stats-json "$tmp/post-$est.json" "$DATA/vtk/post.vtk"
done
expect 0 "" -- "$CLVR" --device "$DEV" --size 16x16 --spp 1 --quiet -o "$tmp/notch-auto.png" \
  --stats-json "$tmp/notch-auto.json" "$DATA/vtk/notch_stress.vtk"
$PY - "$tmp/post-auto.json" "$tmp/post-urm.json" "$tmp/notch-auto.json" <<'PYEOF' && ok || bad "auto with shadows walks post.vtk's 8,750 tets; on notch_stress's hexes its pilot picks and says so"
import json, sys
pa, pu, na = (json.load(open(p)) for p in sys.argv[1:])
a, u = (d["bytes"].get("adjacency", 0) for d in (pa, pu))
assert a == 16 * 8750 + 8 and u == 0, (a, u)
used = [d["render"]["estimator"] for d in (pa, pu, na)]
assert used[:2] == ["walk", "urm"] and used[2] in ("walk", "urm"), used
r = na["render"]
assert r["pilot_walk_cells"] == (1 if used[2] == "walk" else 0) and r["pilot_pixels"] > 0 and r["pilot_s"] > 0, r
assert pa["render"]["pilot_walk_cells"] == -1 and pa["render"]["pilot_s"] == 0, pa["render"]
assert na["bytes"].get("adjacency", 0) > 0, na["bytes"]
PYEOF

# --one-curve: notch_stress's hexes and wedges go on one curve by default
# (auto: the wedges' 8 slots cost at most 1.5x), its wedges stored as hexes,
# and --stats-json counts them; off keeps a curve per type (more instances,
# none collapsed); a wrong value is a usage error naming the choices.
for oc in auto on off; do
  expect 0 "" -- "$CLVR" --device "$DEV" --size 16x16 --spp 1 --quiet --one-curve $oc -o "$tmp/notch-$oc.png" \
    --stats-json "$tmp/notch-$oc.json" "$DATA/vtk/notch_stress.vtk"
done
$PY - "$tmp/notch-auto.json" "$tmp/notch-on.json" "$tmp/notch-off.json" <<'PYEOF' && ok || bad "--one-curve: collapsed wedges and instances in --stats-json"
import json, sys
a, on, off = (json.load(open(p))["clusters"] for p in sys.argv[1:])
cells = json.load(open(sys.argv[1]))["cells"]
assert cells["wedges"] > 0 and cells["hexes"] > 0, cells
for c in (a, on):
    assert c["collapsed"] == {"tets": 0, "pyramids": 0, "wedges": cells["wedges"]}, c
assert off["collapsed"] == {"tets": 0, "pyramids": 0, "wedges": 0}, off
assert off["instances"] > on["instances"], (off["instances"], on["instances"])
PYEOF
expect 2 "--one-curve expects on, off or auto" -- "$CLVR" --one-curve sometimes

# --info on every natively read test file.
for f in "$DATA"/vtk/*.vtk "$DATA"/umesh/*.umesh; do
  expect 0 "" -- "$CLVR" --info "$f"
  grep -q "^elements" "$tmp/out" && ok || bad "--info $f: no element count"
done
expect 0 "" -- "$CLVR" --info "$DATA/vtk/post.vtk"
grep -q "tets      8750" "$tmp/out" && ok || bad "post.vtk tet count: $(cat "$tmp/out")"

# Every method renders a real file.
for m in march track bins dda; do
  expect 0 "" -- "$CLVR" --device "$DEV" "$DATA/vtk/post.vtk" --method $m --size 24x24 --spp 2 --quiet -o "$tmp/m.png"
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
# Output errors: exit 5. (An older file at the path surviving a write that fails
# part-way, with no temporary file left: tests/test_hostile.py, output_write_fails.)
expect 2 ".jpg" -- "$CLVR" --device "$DEV" --size 8x8 --spp 1 --quiet -o "$tmp/x.jpg"
expect 5 "no-such-dir" -- "$CLVR" "${S[@]}" --size 8x8 --spp 1 --quiet -o "$tmp/no-such-dir/x.png"

# --help lists every option the parser accepts (issue 17), and the README's
# option table and docs name every long option of --help.
"$CLVR" --help >"$tmp/help.txt"
src=$(dirname "$0")/..
for opt in $(grep -o 'strcmp(a, "[^"]*")' "$src/host/app/cli.c" | sed 's/strcmp(a, "//; s/")//' | sort -u); do
  grep -qE -- "(^|[ ,])$opt([ ,=]|$)" "$tmp/help.txt" && ok || bad "--help does not list $opt"
done
for opt in $(grep -oE -- '--[a-z][a-z-]+' "$tmp/help.txt" | sort -u); do
  cat "$src/README.md" "$src"/docs/*.md | grep -qF -- "$opt" && ok || bad "README and docs do not mention $opt"
done

# Display (issue 17): the default PNG of the converged built-in scene uses
# the code range (99.9th percentile of the brightest channel >= 218, measured 227; the plain
# clamp stops near 200 of 255) without clipping (< 0.1% of pixels at 255);
# EXR stays linear whatever --exposure and --tonemap say. Measured on the image of
# the old default transfer function, which --opacity ramp --density 1 keeps (the
# automatic one is denser: 237 with aces, 235 with the plain clamp). 64 spp give
# the figures of 256 (227 and 199-200 with seeds 1-4) in a third of the time.
R=(--device "$DEV" --size 96x96 --spp 64 --quiet --opacity ramp --density 1)
expect 0 "" -- "$CLVR" "${R[@]}" -o "$tmp/tm.png"
expect 0 "" -- "$CLVR" "${R[@]}" --tonemap none -o "$tmp/plain.png"
$PY - "$tmp/tm.png" "$tmp/plain.png" "$(dirname "$0")" <<'PYEOF' && ok || bad "default tone mapping: dim or clipped"
import sys
sys.path.insert(0, sys.argv[3])
from checklib import read_png
def stats(path):
    w, h, ch, rows = read_png(path)
    m = sorted(max(r[i * ch:i * ch + 3]) for r in rows for i in range(w))
    return m[int(0.999 * (len(m) - 1))], sum(v == 255 for v in m) / len(m)
tm, plain = stats(sys.argv[1]), stats(sys.argv[2])
print("p99.9 code, clipped fraction: aces", tm, "none", plain)
assert 218 <= tm[0] <= 254 and tm[1] < 0.001, tm
assert plain[0] + 10 < tm[0], (plain, tm)
PYEOF
expect 0 "" -- "$CLVR" "${S[@]}" --size 32x32 --spp 2 --quiet -o "$tmp/lin.exr"
expect 0 "" -- "$CLVR" "${S[@]}" --size 32x32 --spp 2 --quiet -o "$tmp/lin2.exr" --exposure 2 --tonemap filmic
cmp -s "$tmp/lin.exr" "$tmp/lin2.exr" && ok || bad "--exposure/--tonemap changed an EXR"
expect 0 "" -- "$CLVR" "${S[@]}" --size 32x32 --spp 2 --quiet -o "$tmp/ev.png" --exposure 2
expect 0 "" -- "$CLVR" "${S[@]}" --size 32x32 --spp 2 --quiet -o "$tmp/ev0.png"
cmp -s "$tmp/ev.png" "$tmp/ev0.png" && bad "--exposure 2 left the PNG unchanged" || ok
# --background none: RGBA PNG, the corner (background) transparent, the centre not.
expect 0 "" -- "$CLVR" "${S[@]}" --size 48x48 --spp 16 --quiet --background none -o "$tmp/clear.png"
$PY - "$tmp/clear.png" "$(dirname "$0")" <<'PYEOF' && ok || bad "--background none: no transparent corner / opaque centre"
import sys
sys.path.insert(0, sys.argv[2])
from checklib import read_png
w, h, ch, rows = read_png(sys.argv[1])
assert ch == 4, ch
assert rows[0][3] == 0 and rows[h - 1][4 * (w - 1) + 3] == 0, "corners"
assert max(rows[h // 2][4 * i + 3] for i in range(w)) > 64, "centre row"
PYEOF
expect 2 "--background" -- "$CLVR" --background clear
expect 2 "--tonemap" -- "$CLVR" --tonemap reinhard

# Camera (issue 17): --orbit N writes N numbered, different images; --up and
# the framing options render; they conflict with --camera.
expect 0 "" -- "$CLVR" "${S[@]}" --size 24x24 --spp 2 --quiet --orbit 3 --up z -o "$tmp/turn.png"
[ -s "$tmp/turn.0000.png" ] && [ -s "$tmp/turn.0001.png" ] && [ -s "$tmp/turn.0002.png" ] && [ ! -e "$tmp/turn.png" ] &&
  [ ! -e "$tmp/turn.0003.png" ] && ok || bad "--orbit 3: $(ls "$tmp" | grep turn | tr '\n' ' ')"
cmp -s "$tmp/turn.0000.png" "$tmp/turn.0001.png" && bad "--orbit frames are identical" || ok
expect 0 "" -- "$CLVR" "${S[@]}" --size 24x24 --spp 2 --quiet --up z --azimuth 30 --elevation 10 --zoom 1.5 -o "$tmp/v.png"
expect 0 "" -- "$CLVR" "${S[@]}" --size 24x24 --spp 2 --quiet -o "$tmp/v0.png"
cmp -s "$tmp/v.png" "$tmp/v0.png" && bad "--up z --azimuth 30 gave the default view" || ok
expect 2 "--camera" -- "$CLVR" --camera 1,2,3,0,0,0,0,1,0 --up z
expect 2 "--up" -- "$CLVR" --up q

# --legend (issue 17): the bottom-left corner changes, with white text there,
# the rest of the image (same seed) does not; not for EXR.
expect 0 "" -- "$CLVR" "${S[@]}" --size 96x96 --spp 2 --quiet -o "$tmp/noleg.png"
expect 0 "" -- "$CLVR" "${S[@]}" --size 96x96 --spp 2 --quiet --legend -o "$tmp/leg.png"
$PY - "$tmp/noleg.png" "$tmp/leg.png" "$(dirname "$0")" <<'PYEOF' && ok || bad "--legend: not drawn where expected"
import sys
sys.path.insert(0, sys.argv[3])
from checklib import read_png
w, h, ch, a = read_png(sys.argv[1])
_, _, _, b = read_png(sys.argv[2])
assert a[:h // 2] == b[:h // 2], "the top half changed"
corner = [b[y][x * ch:x * ch + 3] for y in range(h - 30, h) for x in range(0, 60)]
assert sum(p == b"\xff\xff\xff" for p in corner) > 20, "no white text in the corner"
assert a[h - 10] != b[h - 10], "the bottom rows did not change"
PYEOF
expect 2 "--legend" -- "$CLVR" --legend -o "$tmp/leg.exr"

# Clipping and the outline (issue 17): a plane that keeps everything changes
# nothing (same seed), one that keeps nothing leaves the background, and
# --outline draws over the image; --tf FILE:NAME picks a preset and an
# unknown one names those the file has.
expect 0 "" -- "$CLVR" "${S[@]}" --size 32x32 --spp 2 --quiet -o "$tmp/ref32.png"
expect 0 "" -- "$CLVR" "${S[@]}" --size 32x32 --spp 2 --quiet --clip 1,0,0,1e30 -o "$tmp/clipall.png"
cmp -s "$tmp/clipall.png" "$tmp/ref32.png" && ok || bad "--clip keeping everything changed the image"
expect 0 "" -- "$CLVR" "${S[@]}" --size 32x32 --spp 2 --quiet --clip 1,0,0,-1e30 -o "$tmp/clipnone.png"
expect 0 "" -- "$CLVR" "${S[@]}" --size 32x32 --spp 2 --quiet --clip-box 0,0,0,1e-6,1e-6,1e-6 --outline -o "$tmp/clipbox.png"
expect 0 "" -- "$CLVR" "${S[@]}" --size 32x32 --spp 2 --quiet --outline -o "$tmp/outline.png"
$PY - "$tmp/clipnone.png" "$tmp/ref32.png" "$tmp/outline.png" "$tmp/clipbox.png" "$(dirname "$0")" <<'PYEOF' && ok || bad "--clip / --clip-box / --outline images"
import sys
sys.path.insert(0, sys.argv[5])
from checklib import read_png
w, h, ch, none = read_png(sys.argv[1])
_, _, _, full = read_png(sys.argv[2])
_, _, _, outl = read_png(sys.argv[3])
_, _, _, cbox = read_png(sys.argv[4])
px = lambda img: [img[y][x * ch:x * ch + 3] for y in range(h) for x in range(w)]
assert len(set(px(none))) == 1, "a clip that keeps nothing left more than the background"
assert px(none) != px(full)
assert sum(a != b for a, b in zip(px(outl), px(full))) > 20, "--outline drew nothing"
# A clip box of 1e-6 keeps no medium: the background wherever the outline does not
# pass (where outline.png equals the plain image), and the outline drawn.
bg = px(none)[0]
kept = [c for c, o, f in zip(px(cbox), px(outl), px(full)) if o == f and c != bg]
assert not kept, "--clip-box 1e-6 left %d pixels of medium" % len(kept)
assert sum(c != bg for c in px(cbox)) > 20, "--clip-box with --outline drew no outline"
PYEOF
expect 2 "--clip" -- "$CLVR" --clip 0,0,0,1
expect 2 "--clip-box" -- "$CLVR" --clip-box 1,0,0,0,1,1
printf '[{"Name":"Blue","RGBPoints":[0,0,0,1, 1,0,0,1]},{"Name":"Red","RGBPoints":[0,1,0,0, 1,1,0,0]}]' >"$tmp/presets.json"
expect 0 "" -- "$CLVR" "${S[@]}" --size 16x16 --spp 1 --quiet --tf "$tmp/presets.json:Red" -o "$tmp/red.png"
expect 3 'no colour map named "Green"; the file has "Blue", "Red"' -- "$CLVR" "${S[@]}" --size 16x16 --spp 1 --quiet --tf "$tmp/presets.json:Green" -o "$tmp/green.png"

# First run (issue 17), PoCL with an empty kernel cache: the compilation is
# announced and timed apart from clustering; no line of the compiler's own
# ("1 warning generated.") reaches the user; the second run is silent about it.
mkdir -p "$tmp/kernel-cache"
# Under ASan (tools/test.sh sanitize) leak checking is off for this run only:
# PoCL 3.1 / LLVM 15 leak on a cold compile (an unchanged test_sfc shows the
# same 16-byte direct leak in libpocl with an empty POCL_CACHE_DIR). A cold
# cache for PoCL (POCL_CACHE_DIR) and NVIDIA (CUDA_CACHE_PATH) alike.
expect 0 "compiling kernels (cached for next time)" -- env POCL_CACHE_DIR="$tmp/kernel-cache" CUDA_CACHE_PATH="$tmp/kernel-cache" \
  ASAN_OPTIONS="${ASAN_OPTIONS:-}:detect_leaks=0" "$CLVR" "${S[@]}" --size 16x16 --spp 1 -o "$tmp/first.png" --stats-json "$tmp/first.json"
grep -v "^clvr: " "$tmp/err" | grep -q . && bad "lines not from clvr on a cold cache: $(grep -v '^clvr: ' "$tmp/err" | head -3)" || ok
grep -q "generated" "$tmp/err" && bad "compiler output shown: $(grep generated "$tmp/err")" || ok
$PY - "$tmp/first.json" <<'PYEOF' && ok || bad "time.kernel_build_s missing or zero"
import json, sys
d = json.load(open(sys.argv[1]))
assert d["time.kernel_build_s"] > 0.3 and d["time"]["kernel_build_s"] == d["time.kernel_build_s"], d["time"]
assert d["time.preprocess_s"] < d["time.kernel_build_s"], d["time"]
PYEOF
# A warm load that takes over CLVR_BUILD_NOTICE_S (0.4 s) still says so: on a loaded
# machine (two ASan tests and mpirun's ranks on 2 cores) it can. One more run tells
# load from a cache that is not used, which says it every time.
for try in 1 2; do
  expect 0 "" -- env POCL_CACHE_DIR="$tmp/kernel-cache" CUDA_CACHE_PATH="$tmp/kernel-cache" "$CLVR" "${S[@]}" --size 16x16 --spp 1 -o "$tmp/first.png"
  grep -q "compiling kernels" "$tmp/err" || break
done
grep -q "compiling kernels" "$tmp/err" && bad "a warm cache still says compiling kernels (twice)" || ok

echo "test_cli_e2e: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
