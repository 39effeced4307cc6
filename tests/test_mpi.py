#!/usr/bin/python3
"""test_mpi: `mpirun -n N clvr` (issue 16, docs/mpi-compositing.md) renders the
single-process image in expectation, and fails cleanly.

Images (--sampler independent): the built-in scene (its medium spans the whole box, so the bisection
cuts through the visible structure for every N), 64x64, 16 spp, PFM (linear
rgb), with and without shadows. Single process and `mpirun -n 1/2/3` each
render twice with independent seeds. Per 4x4 block and channel b, with A the
single-process block means (runs A1, A2) and M the MPI ones:

    D_b = (M1 + M2)/2 - (A1 + A2)/2,   v_b = ((A1 - A2)^2 + (M1 - M2)^2) / 4

v_b is an unbiased estimate of Var(D_b) whatever the two variances are, so
R = sum D_b^2 / sum v_b is about 1 when the expectations agree (an F ratio
with about 770 and 1540 degrees of freedom where blocks are alike, far fewer
because a few bright blocks dominate) and grows with any bias. Measured
between four single-process renders (seeds 1-4, the three pairings): R =
0.84, 1.03, 1.15 with 4x4 blocks (0.72, 0.95, 1.40 with 8x8 blocks, hence the
smaller blocks). Pass: R < R_MAX = 2, and the summed block difference over
its standard error within Z_MAX = 5 (R squares each block's difference, so a
uniform bias of a few % passes it; the sum grows linearly with such a bias:
measured |z| 0.05-2.65 on unbroken runs). The same test on
compositings broken on purpose (test hook CLVR_MPI_TEST_BREAK: rank 0's
record only; rank order instead of depth order) must give R > R_MAX, so the
test can fail. With shadows, -n 2 and -n 3 also run with the light grid set
to 1 (test hook CLVR_MPI_TEST_LIGHT_GRID=one; any grid is unbiased), where all
the shadowing comes through the cross-rank pick of the correction ray: the
test of that pick and of the shadow-transmittance product. Failures: a rank that fails (test hook
CLVR_MPI_TEST_FAIL_RANK), an unwritable output on rank 0 and an option MPI
mode refuses must end the job with a non-zero status and exactly one message,
from rank 0, naming the rank, within a timeout, and leave no output.

`--method bins` and `--method track` (-n 2 with shadows, -n 3 without) match
one process with the same method, and the rank-order break is caught with
each. Ctrl-C (SIGINT to mpirun, which sends the ranks SIGTERM) must leave the
image accumulated so far, whole, with a message and a non-zero status. A generated mixed .bin (clvr-gen) renders the same way through the
distributed loader with the default automatic transfer function.

Environment: CLVR_BUILD_DIR (clvr, clvr-gen), CLVR_MPIEXEC (mpirun),
CLVR_TEST_BRIEF=1 (set by the sanitizer build, CMakeLists.txt): skips the
runs that repeat code paths already covered, which the plain build runs: -n 1,
one of -n 2 and -n 3 per shadow setting (2 with shadows, 3 without), the third
rank count where two are tested, two of the four method runs (bins -n 2 with
shadows, track -n 3 without are kept), the jitter control's statistics (every
MPI render above runs its host code, add_jitters) and the compositings broken
on purpose (they prove the statistic's power, not the code's memory safety).
Under ASan the brief test had grown to 380 s of a 31-minute CI run on a 2-core
VM (session 59).
"""

import math
import os
import shutil
import signal
import subprocess
import sys
import tempfile

from checklib import Checks, read_pfm

HERE = os.path.dirname(os.path.abspath(__file__))
BUILD = os.environ.get("CLVR_BUILD_DIR", os.path.join(HERE, "..", "build"))
CLVR = os.path.abspath(os.path.join(BUILD, "clvr"))
CLVR_GEN = os.path.abspath(os.path.join(BUILD, "clvr-gen"))
MPIEXEC = os.environ.get("CLVR_MPIEXEC") or shutil.which("mpirun") or "mpirun"
SIZE, SPP, BLOCK = 64, 16, 4
R_MAX = 2.0
# With G = 1 the shadow noise is far larger and heavier-tailed: measured
# 1.27 and 1.33 at 16 spp, 1.55 and 0.98 at 128 spp (no growth with spp, so no
# bias); the cross-rank pick weighted without the prefix transmittance gives
# 47 and 206.
R_MAX_G1 = 3.0
TIMEOUT = 300
BRIEF = os.environ.get("CLVR_TEST_BRIEF") == "1"

check = Checks()


def mpi_env(extra=None):
    env = dict(os.environ)
    # CI runs as root; Open MPI refuses that without both variables.
    env["OMPI_ALLOW_RUN_AS_ROOT"] = "1"
    env["OMPI_ALLOW_RUN_AS_ROOT_CONFIRM"] = "1"
    # Shared memory between ranks on one machine; no network probing.
    env.setdefault("OMPI_MCA_btl", "self,vader")
    for k in ("CLVR_MPI_TEST_BREAK", "CLVR_MPI_TEST_FAIL_RANK", "CLVR_MPI_TEST_LIGHT_GRID"):
        env.pop(k, None)
    env.update(extra or {})
    return env


def clvr_args(out, seed, shadows, extra=()):
    # Independent frames and seeds: the four renders of a comparison are
    # independent, which v_b's expectation relies on.
    return [CLVR, "--size", f"{SIZE}x{SIZE}", "--spp", str(SPP), "--seed", str(seed), "--sampler", "independent",
            "--shadows",
            "on" if shadows else "off", "--quiet", "-o", out, *extra]


def run_single(out, seed, shadows):
    p = subprocess.run(clvr_args(out, seed, shadows), capture_output=True, text=True, timeout=TIMEOUT,
                       env=mpi_env())
    return p


def run_mpi(n, args, extra_env=None, timeout=TIMEOUT):
    cmd = [MPIEXEC, "--oversubscribe", "-n", str(n), *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=mpi_env(extra_env))


def block_means(path):
    w, h, d = read_pfm(path)
    nb = w // BLOCK
    out = []
    for by in range(h // BLOCK):
        for bx in range(nb):
            for c in range(3):
                s = 0.0
                for y in range(by * BLOCK, (by + 1) * BLOCK):
                    row = y * w
                    for x in range(bx * BLOCK, (bx + 1) * BLOCK):
                        s += d[3 * (row + x) + c]
                out.append(s / (BLOCK * BLOCK))
    return out


def ratio(a1, a2, m1, m2):
    """R = sum D_b^2 / sum v_b over the blocks (the module docstring), and z,
    the summed block difference over its standard error: R squares each
    block's difference, so a small bias spread evenly over the image grows R
    only as the sum of squares, while it grows z linearly (a uniform shift of
    a few % that R lets pass is many standard errors in z)."""
    num = den = dsum = 0.0
    for x1, x2, y1, y2 in zip(a1, a2, m1, m2):
        d = (y1 + y2) / 2 - (x1 + x2) / 2
        num += d * d
        dsum += d
        den += ((x1 - x2) ** 2 + (y1 - y2) ** 2) / 4
    if den > 0:
        return num / den, dsum / math.sqrt(den)
    return (0.0, 0.0) if num == 0 else (float("inf"), float("inf"))


Z_MAX = 5.0


def render_pair(tmp, tag, runner):
    """Two renders with seeds 11 and 12 (single: 1 and 2); None on failure."""
    means = []
    for k, seed in enumerate((1, 2) if tag.startswith("single") else (11, 12)):
        out = os.path.join(tmp, f"{tag}-{k}.pfm")
        p = runner(out, seed)
        if not check(p.returncode == 0 and os.path.exists(out), f"{tag} seed {seed} renders",
                     f"exit {p.returncode}: {p.stderr[-2000:]}", "exit 0"):
            return None
        means.append(block_means(out))
    return means


def rmse(path, ref):
    _, _, d = read_pfm(path)
    return math.sqrt(sum((a - b) ** 2 for a, b in zip(d, ref)) / len(ref))


def jitter_control(tmp):
    """Rank 0's image subtracts the box filter's jitter control variate, from
    offsets it draws again on the host (add_jitters in host/mpi/mpi_main.c)
    that must be the device's. Drawn from the wrong frames (test hook
    CLVR_MPI_TEST_BREAK=jitter) the image stays unbiased, so the R test above
    cannot see it, but the control only adds noise. Default sampler, 2 spp,
    no shadows, RMSE against one process's 512 spp over three seeds each:
    measured 0.0043 (-n 2), 0.0128 (-n 2, wrong frames), 0.0054 (one process
    at 2 spp; -n 2 is lower, as each rank spends urm's points on its own
    region). Pass: below 0.6 of the broken runs' and 1.5 of one process's."""
    ref_path = os.path.join(tmp, "jit-ref.pfm")
    base = [CLVR, "--size", f"{SIZE}x{SIZE}", "--shadows", "off", "--quiet"]
    p = subprocess.run(base + ["--spp", "512", "--seed", "99", "-o", ref_path], capture_output=True, text=True,
                       timeout=TIMEOUT, env=mpi_env())
    if not check(p.returncode == 0, "jitter control: reference renders", p.stderr[-2000:], "exit 0"):
        return
    _, _, ref = read_pfm(ref_path)
    err = {"mpi": [], "broken": [], "single": []}
    for seed in (11, 12, 13):
        args = base + ["--spp", "2", "--seed", str(seed)]
        for kind in err:
            out = os.path.join(tmp, f"jit-{kind}-{seed}.pfm")
            if kind == "single":
                # Every pixel 2 samples, as under mpirun (no adaptive sampling there).
                p = subprocess.run(args + ["--adaptive", "off", "-o", out], capture_output=True, text=True,
                                   timeout=TIMEOUT, env=mpi_env())
            else:
                p = run_mpi(2, args + ["-o", out], {"CLVR_MPI_TEST_BREAK": "jitter"} if kind == "broken" else None)
            if not check(p.returncode == 0 and os.path.exists(out), f"jitter control: {kind} seed {seed} renders",
                         p.stderr[-2000:], "exit 0"):
                return
            err[kind].append(rmse(out, ref))
    e = {k: sum(v) / len(v) for k, v in err.items()}
    print(f"jitter control, 2 spp: RMSE -n 2 {e['mpi']:.5f}, wrong frames {e['broken']:.5f}, "
          f"one process {e['single']:.5f}")
    check(e["mpi"] < 0.6 * e["broken"], "rank 0's jitter control variate lowers the error (against wrong frames')",
          e["mpi"], f"< {0.6 * e['broken']:.5f}")
    check(e["mpi"] < 1.5 * e["single"], "-n 2's error is near one process's at the same spp", e["mpi"],
          f"< {1.5 * e['single']:.5f}")


def main():
    if not os.path.exists(CLVR):
        print(f"no {CLVR}: build first")
        return 1
    tmp = tempfile.mkdtemp(prefix="clvr-test-mpi-")
    try:
        for shadows in (True, False):
            sh = "shadows" if shadows else "no shadows"
            ref = render_pair(tmp, f"single-{int(shadows)}", lambda out, seed: run_single(out, seed, shadows))
            if ref is None:
                continue
            for n in ((2,) if shadows else (3,)) if BRIEF else (1, 2, 3):
                got = render_pair(tmp, f"mpi{n}-{int(shadows)}",
                                  lambda out, seed: run_mpi(n, clvr_args(out, seed, shadows)))
                if got is None:
                    continue
                r, z = ratio(ref[0], ref[1], got[0], got[1])
                print(f"-n {n}, {sh}: R = {r:.3f}, summed difference {z:.2f} SE")
                check(r < R_MAX, f"mpirun -n {n} ({sh}) matches one process: R = sum D^2 / sum Var(D)", r,
                      f"< {R_MAX}")
                check(abs(z) < Z_MAX, f"mpirun -n {n} ({sh}): no bias over the whole image", z, f"|z| < {Z_MAX}")
            if not shadows:
                continue
            # Every shadow through the correction rays (test hook: light grid
            # G = 1, still unbiased): the cross-rank shadow-point pick and the
            # product of the ranks' shadow transmittances at full strength.
            for n in (2,) if BRIEF else (2, 3):
                got = render_pair(tmp, f"mpi{n}-g1",
                                  lambda out, seed: run_mpi(n, clvr_args(out, seed, True),
                                                            {"CLVR_MPI_TEST_LIGHT_GRID": "one"}))
                if got is None:
                    continue
                r, z = ratio(ref[0], ref[1], got[0], got[1])
                print(f"-n {n}, shadows, light grid G = 1: R = {r:.3f}, summed difference {z:.2f} SE")
                check(r < R_MAX_G1, f"mpirun -n {n} with G = 1 matches one process", r, f"< {R_MAX_G1}")
                check(abs(z) < Z_MAX, f"mpirun -n {n} with G = 1: no bias over the whole image", z,
                      f"|z| < {Z_MAX}")
            # The test must be able to fail: compositings broken on purpose.
            for hook, n in () if BRIEF else (("rank0", 2), ("order", 2), ("order", 3)):
                got = render_pair(tmp, f"broken-{hook}-{n}",
                                  lambda out, seed: run_mpi(n, clvr_args(out, seed, shadows),
                                                            {"CLVR_MPI_TEST_BREAK": hook}))
                if got is None:
                    continue
                r, _ = ratio(ref[0], ref[1], got[0], got[1])
                print(f"broken compositing ({hook}, -n {n}): R = {r:.3f}")
                check(r > R_MAX, f"a compositing broken on purpose ({hook}, -n {n}) is caught", r, f"> {R_MAX}")

        if not BRIEF:
            jitter_control(tmp)

        # The other majorant sources: per-ray bins and the one global
        # majorant (track) restrict to a rank's region the same way as the
        # macrocell grid, so they must match one process with the same
        # method too; a broken compositing must be caught with them as well.
        methods = (("bins", 2, True), ("track", 3, False)) if BRIEF else \
            (("bins", 2, True), ("bins", 3, False), ("track", 2, True), ("track", 3, False))
        for method, n, shadows in methods:
            sh = "shadows" if shadows else "no shadows"
            margs = ("--method", method)
            ref = render_pair(tmp, f"single-{method}-{int(shadows)}", lambda out, seed: subprocess.run(
                clvr_args(out, seed, shadows, margs), capture_output=True, text=True, timeout=TIMEOUT, env=mpi_env()))
            got = render_pair(tmp, f"mpi{n}-{method}-{int(shadows)}",
                              lambda out, seed: run_mpi(n, clvr_args(out, seed, shadows, margs))) if ref else None
            if ref and got:
                r, z = ratio(ref[0], ref[1], got[0], got[1])
                print(f"-n {n}, --method {method}, {sh}: R = {r:.3f}, summed difference {z:.2f} SE")
                check(r < R_MAX, f"mpirun -n {n} --method {method} ({sh}) matches one process", r, f"< {R_MAX}")
                check(abs(z) < Z_MAX, f"mpirun -n {n} --method {method} ({sh}): no bias over the whole image", z,
                      f"|z| < {Z_MAX}")
            if ref and n == 2 and not BRIEF:
                bad = render_pair(tmp, f"broken-{method}", lambda out, seed: run_mpi(
                    n, clvr_args(out, seed, shadows, margs), {"CLVR_MPI_TEST_BREAK": "order"}))
                if bad:
                    r, _ = ratio(ref[0], ref[1], bad[0], bad[1])
                    print(f"broken compositing (order, -n {n}, --method {method}): R = {r:.3f}")
                    check(r > R_MAX, f"a broken compositing is caught with --method {method}", r, f"> {R_MAX}")

        # A .bin file goes through the distributed loader (each rank reads its
        # part; docs/mpi-loading.md) and the automatic transfer function is
        # summed over the ranks' owned elements: the default --opacity auto
        # and --density auto must give the single process's image (taking
        # them from rank 0's share alone moved the mean by 3% on post-tets).
        mesh = os.path.join(tmp, "mixed.bin")
        g = subprocess.run([CLVR_GEN, "mixed", mesh, "--elements", "30k", "--quiet"], capture_output=True, text=True,
                           timeout=TIMEOUT)
        if check(g.returncode == 0, "clvr-gen mixed 30k", g.stderr[-1000:]):
            mesh_args = (mesh,)
            ref = render_pair(tmp, "single-bin", lambda out, seed: subprocess.run(
                clvr_args(out, seed, True, mesh_args), capture_output=True, text=True, timeout=TIMEOUT, env=mpi_env()))
            for n in ((2,) if BRIEF else (2, 3)) if ref else ():
                got = render_pair(tmp, f"mpi{n}-bin", lambda out, seed: run_mpi(n, clvr_args(out, seed, True, mesh_args)))
                if got is None:
                    continue
                r, z = ratio(ref[0], ref[1], got[0], got[1])
                print(f"-n {n}, .bin (distributed loading, automatic transfer function): R = {r:.3f}, "
                      f"summed difference {z:.2f} SE")
                check(r < R_MAX, f"mpirun -n {n} on a .bin matches one process", r, f"< {R_MAX}")
                check(abs(z) < Z_MAX, f"mpirun -n {n} on a .bin: no bias over the whole image", z, f"|z| < {Z_MAX}")

        # A .bin whose field is cell data (kiefer_tet10: von Mises stress per
        # element, averaged onto the vertices) cannot be split by the
        # distributed loader; every rank reads it whole and keeps its share,
        # with a note, and the image is still the single process's.
        cell_bin = os.path.join(tmp, "kiefer.bin")
        conv = os.path.join(HERE, "..", "tools", "clvr-convert")
        c = subprocess.run([conv, os.path.join(HERE, "data", "vtk", "kiefer_tet10.vtu"), cell_bin], capture_output=True,
                           text=True, timeout=TIMEOUT)
        if check(c.returncode == 0, "clvr-convert kiefer_tet10.vtu", c.stderr[-1000:]):
            cell_args = (cell_bin,)
            ref = render_pair(tmp, "single-cell", lambda out, seed: subprocess.run(
                clvr_args(out, seed, True, cell_args), capture_output=True, text=True, timeout=TIMEOUT, env=mpi_env()))
            got = render_pair(tmp, "mpi2-cell", lambda out, seed: run_mpi(2, clvr_args(out, seed, True, cell_args)))
            if ref and got:
                r, z = ratio(ref[0], ref[1], got[0], got[1])
                print(f"-n 2, .bin with a cell field (read whole by every rank): R = {r:.3f}, summed difference {z:.2f} SE")
                check(r < R_MAX, "mpirun -n 2 on a .bin with a cell field matches one process", r, f"< {R_MAX}")
                check(abs(z) < Z_MAX, "mpirun -n 2 on a .bin with a cell field: no bias over the whole image", z,
                      f"|z| < {Z_MAX}")

        # Ctrl-C: mpirun sends the ranks SIGTERM; they stop after a frame all
        # of them finished and rank 0 writes what was accumulated (the
        # single-process program's behaviour). Without the ranks' handler
        # SIGTERM kills them and no image is left.
        out = os.path.join(tmp, "interrupted.pfm")
        # Not --quiet: the progress lines say when frames are running.
        cmd = [MPIEXEC, "--oversubscribe", "-n", "2", *[a for a in clvr_args(out, 1, True) if a != "--quiet"]]
        cmd[cmd.index("--spp") + 1] = "1000000"
        proc = subprocess.Popen(cmd, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True, env=mpi_env())
        err_lines = []
        try:
            # Progress lines come about once a second once frames run.
            for line in proc.stderr:
                err_lines.append(line)
                if line.startswith("clvr: frame "):
                    break
            proc.send_signal(signal.SIGINT)
            _, rest = proc.communicate(timeout=60)
            err_lines.append(rest)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.communicate()
        text = "".join(err_lines)
        check(proc.returncode not in (0, None), "Ctrl-C under mpirun ends the job with a non-zero status",
              proc.returncode, "!= 0")
        check("interrupted after" in text, "Ctrl-C under mpirun: rank 0 says how many frames the image holds",
              text[-1500:], "'interrupted after N of M frames'")
        if check(os.path.exists(out), "Ctrl-C under mpirun leaves the image accumulated so far"):
            w, h, d = read_pfm(out)
            check((w, h) == (SIZE, SIZE) and all(math.isfinite(x) for x in d) and max(d) > 0,
                  "the interrupted image is whole, finite and not black", (w, h, max(d)), (SIZE, SIZE))
        check(not [f for f in os.listdir(tmp) if f.startswith("interrupted.pfm.tmp")],
              "no temporary file left by the interrupted write")

        # Failures end the job: non-zero status, one message naming the rank, no output.
        out = os.path.join(tmp, "fail.pfm")
        p = run_mpi(3, clvr_args(out, 1, True), {"CLVR_MPI_TEST_FAIL_RANK": "1"}, timeout=120)
        lines = [l for l in p.stderr.splitlines() if l.startswith("clvr:") and "rank 1" in l]
        check(p.returncode != 0, "a failing rank gives a non-zero status", p.returncode, "!= 0")
        check(len(lines) == 1 and "CLVR_MPI_TEST_FAIL_RANK" in lines[0], "one message naming rank 1",
              p.stderr[-1500:], "one 'clvr: rank 1: ...' line")
        check(not os.path.exists(out), "no image after a failed rank")
        bad = os.path.join(tmp, "no-such-dir", "x.pfm")
        p = run_mpi(2, clvr_args(bad, 1, True), timeout=120)
        msgs = [l for l in p.stderr.splitlines() if l.startswith("clvr:")]
        check(p.returncode != 0 and len(msgs) == 1 and "no-such-dir" in msgs[0] and "rank 0" in msgs[0],
              "an unwritable output on rank 0: one message naming rank 0 and the path",
              f"exit {p.returncode}: {p.stderr[-1500:]}", "non-zero, one message")
        # A .bin that is not there fails in the distributed loader's own
        # agreement: one message, naming the file and the rank once.
        gone = os.path.join(tmp, "no-such-mesh.bin")
        p = run_mpi(2, clvr_args(out, 1, True, (gone,)), timeout=120)
        msgs = [l for l in p.stderr.splitlines() if l.startswith("clvr:")]
        check(p.returncode != 0 and len(msgs) == 1 and gone in msgs[0] and msgs[0].count("rank ") == 1,
              "a missing .bin: one message naming the file and the rank once", f"exit {p.returncode}: "
              f"{p.stderr[-1500:]}", "non-zero, one message, 'rank ' once")
        p = run_mpi(2, clvr_args(out, 1, True, ("--estimator", "delta")), timeout=120)
        msgs = [l for l in p.stderr.splitlines() if l.startswith("clvr:")]
        check(p.returncode == 2 and len(msgs) == 1 and "--estimator delta" in msgs[0] and "urm" in msgs[0],
              "--estimator delta is refused once, with the fix", f"exit {p.returncode}: {p.stderr[-1500:]}",
              "exit 2, one message")
        p = run_mpi(2, clvr_args(out, 1, True, ("--adaptive", "0.2")), timeout=120)
        msgs = [l for l in p.stderr.splitlines() if l.startswith("clvr:")]
        check(p.returncode == 2 and len(msgs) == 1 and "--adaptive 0.2" in msgs[0] and "--adaptive off" in msgs[0],
              "--adaptive 0.2 is refused once, with the fix", f"exit {p.returncode}: {p.stderr[-1500:]}",
              "exit 2, one message")
        # Stats: rank 0 writes the per-rank table and JSON.
        js = os.path.join(tmp, "stats.json")
        p = run_mpi(2, clvr_args(out, 1, True, ("--stats-json", js)), timeout=TIMEOUT)
        ok = p.returncode == 0 and os.path.exists(js)
        if check(ok, "--stats-json under mpirun", p.stderr[-1500:]):
            import json
            with open(js) as f:
                j = json.load(f)
            ranks = j.get("per_rank", [])
            check(j.get("ranks") == 2 and len(ranks) == 2, "two ranks in the stats", j.get("ranks"), 2)
            owned = sum(r["owned_elements"] for r in ranks)
            check(owned == j.get("elements"), "owned elements sum to the mesh's", owned, j.get("elements"))
            check(all(r["bytes_peak_rss"] > 0 and 0 <= r["comm_share"] <= 1 for r in ranks),
                  "per-rank memory and communication share", ranks)
    except subprocess.TimeoutExpired as e:
        check(False, f"no hang: {e.cmd[:6]} ran past {e.timeout} s")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    check.summary()
    return 1 if check.failed else 0


if __name__ == "__main__":
    sys.exit(main())
