#!/usr/bin/python3
"""test_tf_auto: the default transfer function (--opacity auto --density auto,
issue 17) gives the median camera ray a useful optical depth on real data.

`clvr MESH --background none -o x.png` writes the volume's opacity along each
pixel's ray as alpha, so tau = -ln(1 - alpha) is the camera ray's optical depth
(the renderer's own estimate, not the host's probe). Over the pixels whose ray
meets the visible medium (tau > 1e-3 x the largest), the median must lie in
[0.2, 1.5]: translucent, neither a fog of nearly invisible wisps (the linear ramp
at density 1 gives the built-in scene 0.13 and notch_stress 0.03) nor an opaque
block. Meshes: the built-in scene, tests/data/vtk/post.vtk and notch_stress.vtk,
and the PLOT3D sets of tests/data/plot3d converted by tools/clvr-convert (left
out with a note when /usr/bin/python3 has no VTK). The ramp preset (--opacity
ramp --density 1) still renders the old image: byte-equal to an explicit
--tf file holding the ramp.

Environment: CLVR_BUILD_DIR (clvr), CLVR_SHARED_DATA (tests/data).
"""

import math
import os
import shutil
import subprocess
import sys
import tempfile

from checklib import Checks, read_png

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.environ.get("CLVR_SHARED_DATA", os.path.join(HERE, "data"))
BUILD = os.environ.get("CLVR_BUILD_DIR", os.path.join(HERE, "..", "build"))
CLVR = os.path.abspath(os.path.join(BUILD, "clvr"))
# The device the renders run on (tests/test_device.h: CLVR_TEST_DEVICE, default pocl).
DEVICE = os.environ.get("CLVR_TEST_DEVICE") or "pocl"
CONVERT = os.path.join(HERE, "..", "tools", "clvr-convert")
LOW, HIGH = 0.2, 1.5

check = Checks()


def run(args):
    return subprocess.run(args, capture_output=True, text=True, timeout=600)


def median_depth(png):
    w, h, ch, rows = read_png(png)
    taus = []
    for r in rows:
        for i in range(w):
            a = r[ch * i + 3]
            if a > 0:
                taus.append(-math.log(1.0 - min(a, 254.5) / 255.0))
    if not taus:
        return 0.0, 0
    top = max(taus)
    taus = sorted(t for t in taus if t > 1e-3 * top)
    return taus[len(taus) // 2], len(taus)


def render(tmp, mesh, extra, name):
    out = os.path.join(tmp, name + ".png")
    args = [CLVR] + ([mesh] if mesh else []) + ["--device", DEVICE, "--quiet", "--size", "64x64", "--spp", "16",
                                                "--background", "none", "-o", out] + extra
    r = run(args)
    if not check(r.returncode == 0, f"clvr renders {name}", (r.returncode, r.stderr.strip())):
        return None
    return out


def main():
    tmp = tempfile.mkdtemp(prefix="clvr-tf-auto-")
    meshes = [("built-in scene", None), ("post.vtk", os.path.join(DATA, "vtk", "post.vtk")),
              ("notch_stress.vtk", os.path.join(DATA, "vtk", "notch_stress.vtk"))]
    if run(["/usr/bin/python3", "-c", "import vtk"]).returncode == 0:
        for n in ["post", "bluntfin", "comb"]:
            out = os.path.join(tmp, n + ".bin")
            r = run(["/usr/bin/python3", CONVERT, os.path.join(DATA, "plot3d", n + "xyz.bin"), out, "--q",
                     os.path.join(DATA, "plot3d", n + "q.bin"), "--quiet"])
            if check(r.returncode == 0, f"clvr-convert converts plot3d/{n}", r.stderr.strip()):
                meshes.append((f"plot3d {n}", out))
    else:
        print("note: /usr/bin/python3 has no VTK: the PLOT3D sets were left out")
    try:
        for name, mesh in meshes:
            tag = name.replace(" ", "_")
            png = render(tmp, mesh, [], tag + "_auto")
            if not png:
                continue
            tau, n = median_depth(png)
            line = f"{name}: default (auto) median camera-ray optical depth {tau:.3f} over {n} pixels"
            if mesh is None or name.startswith("notch"):
                ramp = render(tmp, mesh, ["--opacity", "ramp", "--density", "1"], tag + "_ramp")
                if ramp:
                    line += f"; --opacity ramp --density 1: {median_depth(ramp)[0]:.3f}"
            print(line)
            check(LOW <= tau <= HIGH, f"{name}: the median camera ray's optical depth is useful", tau,
                  f"[{LOW}, {HIGH}]")
        # The ramp preset is the old default: equal to the ramp given as a file.
        tf = os.path.join(tmp, "ramp.txt")
        with open(tf, "w") as f:
            f.write("opacity 0 0\nopacity 1 1\n")
        a = render(tmp, meshes[1][1], ["--opacity", "ramp", "--density", "1"], "preset")
        b = render(tmp, meshes[1][1], ["--tf", tf, "--density", "1"], "file")
        if a and b:
            check(read_png(a) == read_png(b), "--opacity ramp --density 1 is the linear ramp at density 1")
        r = run([CLVR, "--opacity", "steep"])
        check(r.returncode == 2 and "--opacity" in r.stderr and "ramp" in r.stderr,
              "--opacity with a bad value: exit 2, one line naming the option and the choices", r.stderr.strip())
        r = run([CLVR, "--density", "lots"])
        check(r.returncode == 2 and "--density" in r.stderr and "auto" in r.stderr,
              "--density with a bad value: exit 2, one line naming the option and auto", r.stderr.strip())
    finally:
        if check.failed == 0:
            shutil.rmtree(tmp, ignore_errors=True)
        else:
            print(f"files kept in {tmp}")
    return 0


if __name__ == "__main__":
    rc = main()
    check.summary()
    sys.exit(rc if rc else (1 if check.failed else 0))
