#!/usr/bin/python3
"""test_viewer: `clvr --view` under Xvfb (Mesa software OpenGL), driven by a
CLVR_VIEW_SCRIPT session (see host/app/viewer.h), proves that the window shows the
volume; that a colour-map switch changes the mean colour, a zoom the coverage and
a middle-button pan moves the picture by the dragged pixels; that R and
C / shift+C restore the first image bit for bit; that resize re-allocates the
image; that the title reports spp, rates, method and device; that X, P and K
write files; and that K's command line, rendered offline at the same spp,
reproduces the viewer's accumulated image. The estimator: --estimator and
--urm-steps start the viewer, E / shift+E cycle it (and A the pixel filter, V adaptive sampling), the title and the K line
carry it. The window and the P key's PNG use the exposure and tone curve of
`clvr -o x.png` (the PNG equals the offline one byte for byte). Also: without a display --view fails
with one line naming the fix, a bad script command fails with its line number,
and --help lists the controls.

Environment: CLVR_BUILD_DIR (clvr), CLVR_SHARED_DATA (tests/data).
Exit: 0 all passed, 1 a check failed, 77 when Xvfb is not installed.
"""

import os
import re
import select
import shlex
import shutil
import struct
import subprocess
import sys
import tempfile

from checklib import Checks, read_png, read_pfm as read_pfm_stored

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.environ.get("CLVR_SHARED_DATA", os.path.join(HERE, "data"))
BUILD = os.environ.get("CLVR_BUILD_DIR", os.path.join(HERE, "..", "build"))
CLVR = os.path.abspath(os.path.join(BUILD, "clvr"))
MESH = os.path.join(DATA, "vtk", "post.vtk")
BACKGROUND_LINEAR = (0.05, 0.05, 0.07)  # clvr's default, linear


def aces(x):
    """host/io/image.c's default tone curve (clvr_image_tonemap, CLVR_TONEMAP_ACES)."""
    x *= 1.5
    return min(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 1.0)


# What the window shows of the background: the default tone curve of PNG output
# (screenshots decode the window's sRGB back to display-linear values).
BACKGROUND = tuple(aces(c) for c in BACKGROUND_LINEAR)

check = Checks()


def run(args, env=None, cwd=None, timeout=180):
    e = dict(os.environ)
    if env:
        e.update(env)
    return subprocess.run(args, env=e, cwd=cwd, capture_output=True, text=True, timeout=timeout)


def read_pfm(path):
    """Returns (w, h, rows top to bottom of [(r, g, b), ...])."""
    w, h, floats = read_pfm_stored(path)
    assert len(floats) == w * h * 3, f"{path}: not a colour PFM"
    rows = []
    for y in range(h):  # PFM stores rows bottom to top
        base = (h - 1 - y) * w * 3
        rows.append([tuple(floats[base + 3 * x: base + 3 * x + 3]) for x in range(w)])
    return w, h, rows


def strip_rows(h):
    """Rows at the bottom covered by the transfer-function strip and its markers."""
    return int(min(max(h / 14.0, 6.0), 24.0)) + 6


def volume_stats(img):
    """Coverage (fraction of non-background pixels above the strip), their mean
    colour and the x of their centroid."""
    w, h, rows = img
    n = covered = 0
    mean = [0.0, 0.0, 0.0]
    cx = 0.0
    for y in range(h - strip_rows(h)):
        for x, p in enumerate(rows[y]):
            n += 1
            if max(abs(p[k] - BACKGROUND[k]) for k in range(3)) > 0.02:
                covered += 1
                cx += x
                for k in range(3):
                    mean[k] += p[k]
    if covered:
        mean = [m / covered for m in mean]
        cx /= covered
    return covered / max(n, 1), mean, cx


def max_diff(a, b):
    if a[0] != b[0] or a[1] != b[1]:
        return float("inf")
    return max(abs(p[k] - q[k]) for ra, rb in zip(a[2], b[2]) for p, q in zip(ra, rb) for k in range(3))


def mean_abs_diff(a, b):
    tot = cnt = 0
    for ra, rb in zip(a[2], b[2]):
        for p, q in zip(ra, rb):
            tot += sum(abs(p[k] - q[k]) for k in range(3))
            cnt += 3
    return tot / max(cnt, 1)


def start_xvfb():
    """Starts a private Xvfb on a free display (-displayfd); returns (process, ":N").
    xvfb-run is not used: its cleanup sometimes fails with exit status 5.
    -noreset: by default the server resets when its last client leaves, and a
    session that connects during the reset fails ("Failed to open display");
    under ASan beside test_mpi (ctest -j2) two sessions did."""
    rfd, wfd = os.pipe()
    proc = subprocess.Popen(["Xvfb", "-displayfd", str(wfd), "-screen", "0", "640x480x24", "-nolisten", "tcp",
                             "-noreset"],
                            pass_fds=(wfd,), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    os.close(wfd)
    data = b""
    while not data.endswith(b"\n"):
        ready, _, _ = select.select([rfd], [], [], 30.0)
        chunk = os.read(rfd, 64) if ready else b""
        if not chunk:
            break
        data += chunk
    os.close(rfd)
    if not data.strip().isdigit():
        proc.kill()
        proc.wait()
        return None, None
    return proc, ":" + data.strip().decode()


def png_size(path):
    with open(path, "rb") as f:
        head = f.read(24)
    if head[:8] != b"\x89PNG\r\n\x1a\n":
        return None
    return struct.unpack(">II", head[16:24])


SESSION = """\
# initial view
frames 3
shot s0.pfm
title
# colour map: next, then back
key C
frames 3
shot s1.pfm
key C shift
# pan by 20 pixels to the right
drag middle 20 0
frames 3
shot s_pan.pfm
# reset the camera: the first image again, bit for bit
key R
frames 3
shot s_reset.pfm
# zoom in
scroll 3
frames 3
shot s2.pfm
# the same view 3 frames on: the noise a change that failed to restart leaves
frames 3
shot s2b.pfm
# orbit
drag left 60 0
frames 3
shot s3.pfm
frames 3
shot s3b.pfm
# transfer-function window and density
key ]
key }
key +
frames 3
shot s4.pfm
key W
key -
# methods and shadows
key M
frames 2
title
key S
key M
frames 1
title
# light
drag left 40 20 light
key LEFT ctrl
frames 2
# window size
resize 160 120
frames 3
shot s5.pfm
title
key X
key P
key K
key H
save acc.pfm
quit
"""


# Real X input (xdotool) must act exactly like the scripted input it stands for.
XDOTOOL_SESSION = """\
frames 1
run xdotool getwindowfocus mousemove --window %1 64 64
run xdotool key c
frames 3
shot x_c.pfm
key C shift
key C
frames 3
shot x_cref.pfm
key C shift
run xdotool getwindowfocus mousemove --window %1 64 64 mousedown 1 mousemove --window %1 84 64 mouseup 1
frames 3
shot x_drag.pfm
key R
drag left 20 0
frames 3
shot x_dragref.pfm
key R
run xdotool click 4
frames 3
shot x_wheel.pfm
key R
scroll 1
frames 3
shot x_wheelref.pfm
run xdotool key q
title
quit
"""


ESTIMATOR_SESSION = """\
frames 2
save d.pfm
title
key E
frames 1
title
key E shift
key E
key A
key V
frames 3
save acc.pfm
key P
key K
shot e.pfm
title
quit
"""


def run_session(xvfb, tmp, name, session, args):
    """Runs the viewer with args and the CLVR_VIEW_SCRIPT session text in a new directory tmp/name: (dir, result)."""
    d = os.path.join(tmp, name)
    os.makedirs(d)
    script = os.path.join(d, name + ".txt")
    with open(script, "w") as f:
        f.write(session)
    return d, run(xvfb + [CLVR] + args, env={"CLVR_VIEW_SCRIPT": script}, cwd=d)


def estimator_session(xvfb, tmp):
    """--estimator, --urm-steps, E / shift+E, and the display curve of PNG output."""
    args = ["--view", "--quiet", "--size", "64x48", "--estimator", "delta", "--urm-steps", "5", "--exposure", "0.5",
            "--tonemap", "filmic", MESH]
    d, r = run_session(xvfb, tmp, "estimator", ESTIMATOR_SESSION, args)
    if not check(r.returncode == 0, "the estimator session exits 0", (r.returncode, r.stderr.strip())):
        return
    out = r.stdout
    titles = re.findall(r"^title: (.*)$", out, re.M)
    if check(len(titles) == 3, "three title lines printed", len(titles), 3):
        check(" dda delta " in titles[0], "--estimator delta starts the viewer with delta (title)", titles[0])
        check(" dda urm " in titles[1], "E switches to urm (title)", titles[1])
        check(" dda urm " in titles[2], "shift+E then E come back to urm (title)", titles[2])
        check(" spp + adaptive |" in titles[0], "adaptive sampling on by default (title)", titles[0])
        check(" spp + adaptive |" not in titles[2], "V turns adaptive sampling off (title)", titles[2])
    view_txt = os.path.join(d, "clvr-view.txt")
    if not check(os.path.exists(view_txt), "K wrote clvr-view.txt"):
        return
    with open(view_txt) as f:
        line = f.read().strip()
    for opt in ["--estimator urm", "--urm-steps 5", "--exposure 0.5", "--tonemap filmic", "--pixel-filter point",
                "--adaptive off"]:
        check(opt in line, f"the K line has {opt}", line)
    base = shlex.split(line)[1:]

    def offline(extra, out_name):
        path = os.path.join(d, out_name)
        r = run([CLVR] + base + extra + ["--quiet", "-o", path], cwd=d)
        return path if check(r.returncode == 0, f"the K line runs offline ({out_name})", (r.returncode, r.stderr)) \
            else None

    # The first frames were delta with 5 urm steps and the box filter: the K line with
    # --estimator delta --pixel-filter box at 2 spp renders them exactly; the accumulated urm image at its spp likewise
    # (urm with 16 steps would differ, so --urm-steps reached the renderer).
    m = re.search(r"saved acc\.pfm \((\d+)x(\d+), (\d+) spp\)", out)
    if not check(m is not None, "save acc.pfm reports its spp", out):
        return
    spp = m.group(3)
    p = offline(["--spp", "2", "--estimator", "delta", "--pixel-filter", "box", "--adaptive", "0.1"], "off_d.pfm")
    if p:
        dd = max_diff(read_pfm(os.path.join(d, "d.pfm")), read_pfm(p))
        check(dd <= 1e-6, "the viewer's first frames are --estimator delta's, offline", dd, 0.0)
    p = offline(["--spp", spp], "off_acc.pfm")
    if p:
        a = read_pfm(os.path.join(d, "acc.pfm"))
        dd = max_diff(a, read_pfm(p))
        check(dd <= 1e-6, f"after E the viewer renders urm with --urm-steps 5 (offline equal at {spp} spp)", dd, 0.0)
        p16 = offline(["--spp", spp, "--urm-steps", "16"], "off_16.pfm")
        if p16:
            check(max_diff(a, read_pfm(p16)) > 1e-4, "--urm-steps 16 gives another image (the check can fail)",
                  max_diff(a, read_pfm(p16)))
        pb = offline(["--spp", spp, "--pixel-filter", "box"], "off_box.pfm")
        if pb:
            check(max_diff(a, read_pfm(pb)) > 1e-4, "after A the viewer renders the point filter (box differs)",
                  max_diff(a, read_pfm(pb)))
    # The P key's PNG is the offline PNG of the same view, byte for byte in its
    # pixels (same exposure, tone curve, sRGB), and the window shows it within one
    # code (the window's sRGB encoding is a table).
    png = os.path.join(d, "clvr-view-001.png")
    p = offline(["--spp", spp], "off.png")
    if check(os.path.exists(png), "P saved clvr-view-001.png") and p:
        a, b = read_png(png), read_png(p)
        check(a == b, "the P key's PNG equals `clvr -o x.png` of the K line (exposure, filmic curve)",
              (a[:3], b[:3]))
        w, h, ch, rows = a
        shot = read_pfm(os.path.join(d, "e.pfm"))
        worst = 0
        for y in range(h - strip_rows(h)):
            for x in range(w):
                for k in range(3):
                    code = round(255.0 * srgb_encode(shot[2][y][x][k]))
                    worst = max(worst, abs(code - rows[y][ch * x + k]))
        check(worst <= 1, "the window shows the PNG's codes (within 1)", worst, "<= 1")


DENOISE_SESSION = """\
frames 2
save raw.pfm
key D
frames 2
save dn.pfm
key K
quit
"""


def denoise_session(xvfb, tmp):
    """D shows the denoised preview: the window's image is `clvr --denoise` of its K line, and differs from the raw one."""
    d, r = run_session(xvfb, tmp, "denoise", DENOISE_SESSION, ["--view", "--quiet", "--size", "64x48", MESH])
    if not check(r.returncode == 0, "the denoise session exits 0", (r.returncode, r.stderr.strip())):
        return
    view_txt = os.path.join(d, "clvr-view.txt")
    if not check(os.path.exists(view_txt), "K wrote clvr-view.txt (denoise session)"):
        return
    with open(view_txt) as f:
        line = f.read().strip()
    check("--denoise" in line, "after D the K line has --denoise", line)
    base = shlex.split(line)[1:]
    off = os.path.join(d, "off_dn.pfm")
    r = run([CLVR] + base + ["--spp", "2", "--quiet", "-o", off], cwd=d)
    if check(r.returncode == 0, "the K line with --denoise runs offline", (r.returncode, r.stderr)):
        dn = read_pfm(os.path.join(d, "dn.pfm"))
        check(max_diff(dn, read_pfm(off)) <= 1e-6, "the window's denoised image is `clvr --denoise` of its K line",
              max_diff(dn, read_pfm(off)))
        raw = read_pfm(os.path.join(d, "raw.pfm"))
        check(max_diff(dn, raw) > 1e-4, "the denoised image differs from the raw one (the check can fail)",
              max_diff(dn, raw))


def srgb_encode(c):
    return 12.92 * c if c <= 0.0031308 else 1.055 * c ** (1.0 / 2.4) - 0.055


def main():
    if not shutil.which("Xvfb"):
        print("skipped: Xvfb is not installed (apt-get install xvfb; see tools/setup-debian.sh)")
        return 77
    if not os.path.exists(CLVR):
        print(f"FAIL {CLVR} does not exist (build the clvr target)")
        return 1

    # --help lists every control.
    r = run([CLVR, "--help"])
    for control in ["Viewer controls", "left drag", "middle drag", "wheel", "R ", "C / shift+C", "[ / ]", "{ / }",
                    "+ / -", "S ", "M / shift+M", "E / shift+E", "A ", "L+left drag", "X / P", "K ", "H ", "Escape"]:
        check(control in r.stdout, f"--help mentions the viewer control '{control}'")

    tmp = tempfile.mkdtemp(prefix="clvr-viewer-")
    xvfb_proc = None
    try:
        # No display: one line on stderr with the fix, non-zero exit, and quickly
        # (before preprocessing).
        e = dict(os.environ)
        e.pop("DISPLAY", None)
        e.pop("WAYLAND_DISPLAY", None)
        r = subprocess.run([CLVR, "--view", MESH], env=e, capture_output=True, text=True, timeout=60)
        check(r.returncode == 4, "--view without a display exits 4", r.returncode, 4)
        lines = r.stderr.strip().splitlines()
        check(len(lines) == 1 and "display" in r.stderr.lower() and "-o" in r.stderr,
              "--view without a display says so in one line and suggests -o", r.stderr)

        xvfb_proc, display = start_xvfb()
        if not check(xvfb_proc is not None, "Xvfb starts and reports its display"):
            return 1
        xvfb = ["env", "DISPLAY=" + display]

        # A bad script command is an error naming the file and line.
        bad = os.path.join(tmp, "bad.txt")
        with open(bad, "w") as f:
            f.write("frames 1\nwiggle 3\n")
        r = run(xvfb + [CLVR, "--view", "--quiet", "--size", "64x64", MESH], env={"CLVR_VIEW_SCRIPT": bad}, cwd=tmp)
        check(r.returncode == 2 and "bad.txt:2" in r.stderr and "wiggle" in r.stderr,
              "an unknown script command fails with file:line", (r.returncode, r.stderr.strip()))

        # The scripted session.
        script = os.path.join(tmp, "session.txt")
        with open(script, "w") as f:
            f.write(SESSION)
        r = run(xvfb + [CLVR, "--view", "--quiet", "--size", "128x128", MESH], env={"CLVR_VIEW_SCRIPT": script},
                cwd=tmp)
        if not check(r.returncode == 0, "the scripted viewer session exits 0", r.returncode, 0):
            print(r.stdout)
            print(r.stderr)
            return 1
        out = r.stdout
        shots = {}
        for name in ["s0", "s1", "s_pan", "s_reset", "s2", "s2b", "s3", "s3b", "s4", "s5"]:
            path = os.path.join(tmp, name + ".pfm")
            if check(os.path.exists(path), f"screenshot {name}.pfm written"):
                shots[name] = read_pfm(path)
        if len(shots) < 10:
            return 1
        st = {k: volume_stats(v) for k, v in shots.items()}
        for k, (cov, mean, cx) in st.items():
            print(f"{k}: {shots[k][0]}x{shots[k][1]}, coverage {cov:.3f}, mean colour "
                  f"({mean[0]:.3f}, {mean[1]:.3f}, {mean[2]:.3f}), centroid x {cx:.1f}")

        check(shots["s0"][0:2] == (128, 128), "the window is --size", shots["s0"][0:2], (128, 128))
        corner = shots["s0"][2][0][0]
        check(max(abs(corner[k] - BACKGROUND[k]) for k in range(3)) < 0.004,
              "the window shows the background through the default (aces) tone curve", corner, BACKGROUND)
        check(st["s0"][0] > 0.10, "the first image shows the volume (> 10% non-background pixels)", st["s0"][0])
        dcol = sum(abs(a - b) for a, b in zip(st["s0"][1], st["s1"][1]))
        check(dcol > 0.03, "C (next colour map) changes the mean colour of the volume", dcol, "> 0.03")
        shift = st["s_pan"][2] - st["s0"][2]
        check(12.0 < shift < 28.0, "a 20-pixel middle drag pans the picture about 20 pixels right", shift, 20)
        d = max_diff(shots["s0"], shots["s_reset"])
        check(d == 0.0, "R and C, shift+C restore the first image exactly (same frames, same seed)", d, 0.0)
        check(st["s2"][0] > 1.3 * st["s0"][0], "three wheel notches in raise the coverage by > 30%",
              (st["s0"][0], st["s2"][0]))
        # A change must move the image by more than 3x what 3 more frames of
        # the same view do: an ignored key or drag (no restart) leaves a
        # longer accumulation of the same image, which differs by noise only.
        noise2 = mean_abs_diff(shots["s2"], shots["s2b"])
        noise3 = mean_abs_diff(shots["s3"], shots["s3b"])
        print(f"mean |diff|: orbit {mean_abs_diff(shots['s2'], shots['s3']):.4f} (3 more frames: {noise2:.4f}), "
              f"] }} + {mean_abs_diff(shots['s3'], shots['s4']):.4f} (3 more frames: {noise3:.4f})")
        check(mean_abs_diff(shots["s2"], shots["s3"]) > max(0.005, 3.0 * noise2),
              "a left drag (orbit) changes the image by more than noise",
              (mean_abs_diff(shots["s2"], shots["s3"]), noise2))
        check(mean_abs_diff(shots["s3"], shots["s4"]) > max(0.005, 3.0 * noise3),
              "] } + (window, density) change the image by more than noise",
              (mean_abs_diff(shots["s3"], shots["s4"]), noise3))
        check(shots["s5"][0:2] == (160, 120), "resize 160x120 gives a 160x120 window image", shots["s5"][0:2],
              (160, 120))
        check(st["s5"][0] > 0.05, "after the resize the volume is still shown", st["s5"][0])

        titles = re.findall(r"^title: (.*)$", out, re.M)
        if check(len(titles) == 4, "four title lines printed", len(titles), 4):
            for t in titles:
                check(all(w in t for w in ["spp", "fps", "Mrays/s", "density"]) and "clvr" in t,
                      "the title shows spp, fps, Mrays/s, the transfer function", t)
            check(" dda " in titles[0] and "3 spp" in titles[0], "title 1: dda, 3 spp", titles[0])
            check(" march " in titles[1] and "shadows n/a" in titles[1], "title 2: M switches to march", titles[1])
            check(" track " in titles[2] and "shadows off" in titles[2], "title 3: M then track, S shadows off",
                  titles[2])
            m = re.search(r"([0-9.]+) Mrays/s", titles[3])
            check(m is not None and float(m.group(1)) > 0.0, "Mrays/s is positive while rendering", titles[3])

        exr = os.path.join(tmp, "clvr-view-001.exr")
        png = os.path.join(tmp, "clvr-view-001.png")
        if check(os.path.exists(exr), "X saved clvr-view-001.exr", out):
            with open(exr, "rb") as f:
                check(f.read(4) == b"\x76\x2f\x31\x01", "clvr-view-001.exr is an OpenEXR file")
        if check(os.path.exists(png), "P saved clvr-view-001.png"):
            check(png_size(png) == (160, 120), "the PNG has the window size", png_size(png), (160, 120))
        check("saved clvr-view-001.exr" in out and "saved clvr-view-001.png" in out, "X and P print the file names")
        check("Viewer controls" in out and "rotate the light" in out, "H prints the controls")

        view_txt = os.path.join(tmp, "clvr-view.txt")
        if not check(os.path.exists(view_txt), "K wrote clvr-view.txt"):
            return 1
        with open(view_txt) as f:
            line = f.read().strip()
        check(line in out, "K prints the same line it writes", line)
        for opt in ["--camera", "--range", "--colormap", "--density", "--method", "--light", "--size 160x120",
                    "--shadows off", "--method track"]:
            check(opt in line, f"the K line has {opt}", line)

        # The K line renders the viewer's image offline.
        m = re.search(r"saved acc\.pfm \((\d+)x(\d+), (\d+) spp\)", out)
        if check(m is not None, "save acc.pfm reports its spp", out):
            spp = m.group(3)
            args = shlex.split(line)
            check(args[0] == "clvr", "the K line starts with clvr", args[0])
            off = os.path.join(tmp, "offline.pfm")
            r = run([CLVR] + args[1:] + ["--spp", spp, "--quiet", "-o", off], cwd=tmp)
            if check(r.returncode == 0, "the K line runs offline", (r.returncode, r.stderr)):
                a, b = read_pfm(os.path.join(tmp, "acc.pfm")), read_pfm(off)
                d = max_diff(a, b)
                check(d <= 1e-6, f"offline render of the K line at {spp} spp equals the viewer's image", d, 0.0)

        estimator_session(xvfb, tmp)
        denoise_session(xvfb, tmp)

        # --up z: the viewer orbits about z, and its K line carries that up vector.
        up_dir = os.path.join(tmp, "up")
        os.makedirs(up_dir)
        script = os.path.join(up_dir, "up.txt")
        with open(script, "w") as f:
            f.write("frames 1\ndrag left 30 10\nframes 1\nkey K\nquit\n")
        r = run(xvfb + [CLVR, "--view", "--quiet", "--size", "64x48", "--up", "z", MESH],
                env={"CLVR_VIEW_SCRIPT": script}, cwd=up_dir)
        m = re.search(r"--camera (\S+)", r.stdout)
        up = [float(x) for x in m.group(1).split(",")[6:]] if m else None
        check(r.returncode == 0 and up == [0.0, 0.0, 1.0], "--view --up z: the K line's up vector is 0,0,1",
              (r.returncode, up, r.stderr[-200:]), [0.0, 0.0, 1.0])

        # Real input through the GLFW callbacks, when xdotool is installed.
        if shutil.which("xdotool"):
            script = os.path.join(tmp, "xdotool.txt")
            with open(script, "w") as f:
                f.write(XDOTOOL_SESSION)
            r = run(xvfb + [CLVR, "--view", "--quiet", "--size", "128x128", MESH], env={"CLVR_VIEW_SCRIPT": script},
                    cwd=tmp)
            if check(r.returncode == 0, "the xdotool session exits 0", (r.returncode, r.stderr.strip())):
                for real, ref, what in [("x_c", "x_cref", "the C key"), ("x_drag", "x_dragref", "a 20-pixel left drag"),
                                        ("x_wheel", "x_wheelref", "a wheel notch")]:
                    a, b = read_pfm(os.path.join(tmp, real + ".pfm")), read_pfm(os.path.join(tmp, ref + ".pfm"))
                    check(max_diff(a, b) == 0.0, f"{what} from X (xdotool) acts exactly like the scripted one",
                          max_diff(a, b), 0.0)
                check(mean_abs_diff(read_pfm(os.path.join(tmp, "x_drag.pfm")),
                                    read_pfm(os.path.join(tmp, "x_wheel.pfm"))) > 0.005,
                      "the xdotool drag and wheel images differ from each other")
                check("title:" not in r.stdout, "the Q key from X quits the viewer", r.stdout)
        else:
            print("note: xdotool is not installed: the real X input checks were left out")
    finally:
        if xvfb_proc:
            xvfb_proc.terminate()
            xvfb_proc.wait()
        if check.failed == 0:
            shutil.rmtree(tmp, ignore_errors=True)
        else:
            print(f"files kept in {tmp}")
    return 0


if __name__ == "__main__":
    rc = main()
    check.summary()
    sys.exit(rc if rc else (1 if check.failed else 0))
