#!/usr/bin/python3
"""test_convert: tools/clvr-convert turns every VTK-readable file in tests/data into a
.bin that an independent reader (below, written from docs/bin-format.md, sharing no code
with the converter) accepts, with the element counts tests/data/README.md states; broken
inputs fail with one line and leave no file behind.

Environment: CLVR_SHARED_DATA (tests/data), CLVR_BUILD_DIR (for build/clvr --info),
CLVR_CONVERT (the converter; default tools/clvr-convert beside this file),
CLVR_TEST_BRIEF=1 (the sanitizer build: only the cases that run clvr).
Exit: 0 all passed, 1 a check failed, 77 when /usr/bin/python3 has no VTK (skipped).
"""

import glob
import importlib.machinery
import importlib.util
import json
import math
import os
import shutil
import struct
import subprocess
import sys
import tempfile

from checklib import Checks

try:
    import numpy as np
    import vtk
    from vtk.util import numpy_support as ns
except ImportError as e:
    print(f"skipped: {sys.executable} cannot import {e.name} (run tools/setup-debian.sh)")
    sys.exit(77)

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.environ.get("CLVR_SHARED_DATA", os.path.join(HERE, "data"))
CONVERT = os.environ.get("CLVR_CONVERT", os.path.join(HERE, "..", "tools", "clvr-convert"))
BUILD = os.environ.get("CLVR_BUILD_DIR", "")
CLVR = os.path.join(BUILD, "clvr") if BUILD else ""

check = Checks()
NO_DEVICE = []  # the renders not checked for want of an OpenCL device


def no_device(r, what):
    """True when render r failed because this machine has no OpenCL device
    (`clvr --list-devices` fails too): noted, and main() then exits 77, so
    ctest reports the test skipped rather than passed. A render that failed
    for any other reason goes on to its check, and fails it."""
    if r.returncode == 0:
        return False
    d = subprocess.run([CLVR, "--list-devices"], capture_output=True, text=True, timeout=120)
    if d.returncode == 0:
        return False
    print(f"note: no OpenCL device for {what}: {d.stdout.strip()[:120]} {d.stderr.strip()[:120]}")
    NO_DEVICE.append(what)
    return True


# Independent .bin reader -------------------------------------------------------------

class BinMesh:
    pass


def read_bin(path):
    """Reads and validates a .bin per docs/bin-format.md (version 1 or 2). Returns
    (mesh, problems). For version 2, m.fields is a list of (name, association,
    components, min, max, values[count, components]) and m.scalars the first field per
    vertex (cell data averaged over the elements using each vertex)."""
    problems = []
    with open(path, "rb") as f:
        data = f.read()
    if len(data) < 256:
        return None, [f"{len(data)} bytes, shorter than the 256-byte header"]
    m = BinMesh()
    if data[0:8] != b"CLVRMESH":
        problems.append(f"magic {data[0:8]!r}")
    version, header_size = struct.unpack_from("<II", data, 8)
    m.version = version
    if version not in (1, 2):
        problems.append(f"version {version}")
    if header_size != 256:
        problems.append(f"header_size {header_size}")
    m.V, m.T, m.P, m.W, m.H = struct.unpack_from("<5Q", data, 16)
    m.lo = struct.unpack_from("<3f", data, 56)
    m.hi = struct.unpack_from("<3f", data, 68)
    m.smin, m.smax = struct.unpack_from("<2f", data, 80)
    m.name = data[88:152].rstrip(b"\0").decode("utf-8", "replace")
    if b"\0" in data[88:152].rstrip(b"\0"):
        problems.append("scalar_name has bytes after its NUL")
    flags = struct.unpack_from("<I", data, 152)[0]
    if flags != 0:
        problems.append(f"flags {flags}")
    nfields = struct.unpack_from("<I", data, 156)[0] if version == 2 else 0
    if any(data[160 if version == 2 else 156:256]):
        problems.append("reserved bytes not zero")
    E = m.T + m.P + m.W + m.H
    off = 256
    m.pos = np.frombuffer(data, "<f4", 3 * m.V, off).reshape(-1, 3) \
        if len(data) >= off + 12 * m.V else np.zeros((0, 3), np.float32)
    off += 12 * m.V
    if version == 1:
        want = 256 + 4 * (4 * m.V + 4 * m.T + 5 * m.P + 6 * m.W + 8 * m.H)
        if len(data) != want:
            problems.append(f"file size {len(data)}, header says {want}")
            return m, problems
        m.scalars = np.frombuffer(data, "<f4", m.V, off)
        off += 4 * m.V
    m.cells = []
    for n, k in ((m.T, 4), (m.P, 5), (m.W, 6), (m.H, 8)):
        if len(data) < off + 4 * n * k:
            return m, problems + ["file shorter than its index lists"]
        m.cells.append(np.frombuffer(data, "<u4", n * k, off).reshape(-1, k).astype(np.int64))
        off += 4 * n * k
    m.fields = []
    if version == 2:
        table = off
        off += 128 * nfields
        for i in range(nfields):
            raw, assoc, nc, lo, hi = struct.unpack_from("<64sIIff", data, table + 128 * i)
            if any(data[table + 128 * i + 80:table + 128 * (i + 1)]):
                problems.append(f"field {i}: reserved bytes not zero")
            if assoc not in (0, 1) or not 1 <= nc <= 16:
                problems.append(f"field {i}: association {assoc}, components {nc}")
                return m, problems
            count = m.V if assoc == 0 else E
            vals = np.frombuffer(data, "<f4", count * nc, off).reshape(count, nc) \
                if len(data) >= off + 4 * count * nc else None
            if vals is None:
                return m, problems + [f"field {i} cut short"]
            off += 4 * count * nc
            m.fields.append((raw.rstrip(b"\0").decode("utf-8", "replace"), assoc, nc, lo, hi, vals))
        if len(data) != off:
            problems.append(f"file size {len(data)}, header and table say {off}")
        if m.fields and m.fields[0][0] != m.name:
            problems.append(f"header scalar_name {m.name!r} is not the first field "
                            f"{m.fields[0][0]!r}")
        m.scalars = field_per_vertex(m, 0) if m.fields else np.zeros(m.V, np.float32)
    for lst in m.cells:
        if lst.size and lst.max() >= m.V:
            problems.append(f"index {lst.max()} >= V {m.V}")
    if not np.isfinite(m.pos).all() or not np.isfinite(m.scalars).all():
        problems.append("non-finite coordinate or scalar")
    if m.V:
        if tuple(m.pos.min(axis=0)) != m.lo or tuple(m.pos.max(axis=0)) != m.hi:
            problems.append(f"bounds {m.lo}..{m.hi} differ from the vertices' "
                            f"{tuple(m.pos.min(axis=0))}..{tuple(m.pos.max(axis=0))}")
        if version == 1 and (float(m.scalars.min()), float(m.scalars.max())) != (m.smin, m.smax):
            problems.append(f"scalar range {m.smin}..{m.smax} differs from the values' "
                            f"{m.scalars.min()}..{m.scalars.max()}")
    return m, problems


def field_per_vertex(m, i):
    """Field i of a version 2 mesh as one float32 per vertex: magnitude of vectors, cell
    data averaged over the elements that use each vertex (docs/bin-format.md)."""
    _, assoc, nc, _, _, vals = m.fields[i]
    v = vals[:, 0].astype(np.float64) if nc == 1 else np.sqrt((vals.astype(np.float64) ** 2).sum(1))
    if assoc == 0:
        return v.astype(np.float32)
    acc = np.zeros(m.V)
    cnt = np.zeros(m.V)
    e = 0
    for lst in m.cells:
        ev = v[e:e + lst.shape[0]]
        for k in range(lst.shape[1]):
            np.add.at(acc, lst[:, k], ev)
            np.add.at(cnt, lst[:, k], 1)
        e += lst.shape[0]
    return np.where(cnt > 0, acc / np.maximum(cnt, 1), 0).astype(np.float32)


def tet_volumes(pos, tets):
    p = pos.astype(np.float64)
    a, b, c, d = (p[tets[:, i]] for i in range(4))
    return np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) / 6.0


def hex_volumes(pos, hexes):
    """Hex volumes as the sum of 6 tets around the 0-6 diagonal (exact for planar faces
    and independent of the converter's split)."""
    v = np.zeros(hexes.shape[0])
    for t in ((0, 1, 2, 6), (0, 2, 3, 6), (0, 3, 7, 6), (0, 7, 4, 6), (0, 4, 5, 6),
              (0, 5, 1, 6)):
        v += tet_volumes(pos, hexes[:, t])
    return v


# Running the converter -----------------------------------------------------------------

def convert(args, tmp):
    r = subprocess.run([CONVERT] + args, capture_output=True, text=True, timeout=300)
    leftovers = [f for f in os.listdir(tmp) if f.endswith(".tmp")]
    check(not leftovers, f"no temporary files left after clvr-convert {args}", leftovers, [])
    return r


def clvr_info_check(out, biggest, label):
    """clvr --info OUT.bin exits 0 and reports the largest element count."""
    r = subprocess.run([CLVR, "--info", out], capture_output=True, text=True, timeout=120)
    ok = check(r.returncode == 0, f"{label}: clvr --info exit status (stderr: "
               f"{r.stderr.strip()[:200]})", r.returncode, 0)
    if ok:
        tokens = r.stdout.replace(",", " ").split()
        check(str(biggest) in tokens, f"{label}: clvr --info prints the count {biggest}",
              r.stdout[:300], str(biggest))


def clvr_has_info():
    if not CLVR or not os.access(CLVR, os.X_OK):
        return False, f"not checked: no clvr binary in {BUILD or '(CLVR_BUILD_DIR unset)'}"
    r = subprocess.run([CLVR, "--help"], capture_output=True, text=True, timeout=60)
    if "--info" not in r.stdout + r.stderr:
        return False, f"not checked: {CLVR} --help lists no --info yet"
    return True, f"checked with {CLVR}"


# (input relative to DATA, extra args, (T, P, W, H), scalar name or None to skip)
CASES = [
    ("plot3d/bluntfinxyz.bin", [], (0, 0, 0, 37479), "Density"),
    ("plot3d/combxyz.bin", [], (0, 0, 0, 43008), "Density"),
    # post's iblank is 1 or -1, never 0: the -1 points are the fringe of the periodic
    # seam (j = 0, 74, 75 of 76; j = 75 repeats j = 0), not holes. VTK hides only
    # iblank 0, so nothing is blanked; dropping the -1 cells would cut a 14.4 degree
    # wedge out of the ring.
    ("plot3d/postxyz.bin", [], (0, 0, 0, 102675), "VelocityMagnitude"),
    ("vtk/kiefer_tet10.vtu", [], (56786, 0, 0, 0), "Equivalent (von-Mises) Stress (psi)"),
    ("vtk/fire_ug.vtu", [], (0, 0, 0, 10462), "t"),
    ("vtk/notch_stress.vtk", [], (0, 0, 4, 2188), "Nodal Stress-0"),
    ("vtk/post.vtk", [], (8750, 0, 0, 0), "Pressure"),
    # uGridEx: 12 cells, of which 2 tets and 2 hexes are 3D (the rest vertices, lines,
    # triangles, quads, a polygon... dropped).
    ("vtk/uGridEx.vtk", [], (2, 0, 0, 2), "scalars"),
    ("vtk/pyramid_ug.vtu", [], (0, 1, 0, 0), "temperature"),
    ("vtk/pyramid_ug.vtu", ["--scalar", "velocity"], (0, 1, 0, 0), "velocity"),
    ("vtk/notch_stress.vtk", ["--scalar", "Nodal Stress"], (0, 0, 4, 2188), "Nodal Stress"),
    ("plot3d/combxyz.bin", ["--scalar", "StagnationEnergy"], (0, 0, 0, 43008),
     "StagnationEnergy"),
]


def vtk_read(path):
    r = vtk.vtkXMLUnstructuredGridReader() if path.endswith(".vtu") else vtk.vtkDataSetReader()
    r.SetFileName(path)
    r.Update()
    return r.GetOutput()


def test_files(tmp, info_ok):
    covered = {rel for rel, _, _, _ in CASES}
    for path in sorted(glob.glob(os.path.join(DATA, "*", "*"))):
        rel = os.path.relpath(path, DATA)
        if rel.endswith(".umesh") or rel.endswith(".md") or rel.endswith("q.bin"):
            continue  # umesh: not VTK's; q files: read with their xyz grid
        check(rel in covered, f"{rel}: has a case in test_convert.py", rel, "a case")
    for rel, extra, want, scalar in CASES:
        src = os.path.join(DATA, rel)
        label = rel + ("" if not extra else " " + " ".join(extra))
        out = os.path.join(tmp, os.path.basename(rel) + "-" + str(len(extra)) + ".bin")
        r = convert([src, out] + extra, tmp)
        if not check(r.returncode == 0, f"{label}: exit status (stderr: {r.stderr.strip()})",
                     r.returncode, 0):
            continue
        check(r.stdout.count("\n") == 1 and str(want[3] or want[0] or want[1] or want[2])
              in r.stdout, f"{label}: one summary line with the counts", r.stdout, None)
        m, problems = read_bin(out)
        if not check(m is not None and not problems, f"{label}: valid .bin", problems, []):
            continue
        check((m.T, m.P, m.W, m.H) == want, f"{label}: element counts (T, P, W, H)",
              (m.T, m.P, m.W, m.H), want)
        check(m.name == scalar, f"{label}: scalar name", m.name, scalar)
        used = np.zeros(m.V, bool)
        for lst in m.cells:
            used[lst.reshape(-1)] = True
        check(used.all(), f"{label}: every vertex used", int((~used).sum()), 0)
        if m.T:
            v = tet_volumes(m.pos, m.cells[0])
            check((v > 0).all(), f"{label}: tets have VTK's (positive) orientation",
                  int((v <= 0).sum()), 0)
        if info_ok:
            clvr_info_check(out, max(want), label)


def test_cell_stats(tmp):
    """tools/cell-stats.py (bench/graded.sh's first section) on what the converter
    writes (a version 2 .bin, whose fields follow the elements): its counts and
    volume extremes match this test's own reading. It read version 2 files as
    version 1 (a scalar array after the positions) and failed on every mesh."""
    src = os.path.join(DATA, "vtk", "kiefer_tet10.vtu")
    out = os.path.join(tmp, "cellstats.bin")
    r = convert([src, out, "--quiet"], tmp)
    if not check(r.returncode == 0, "cell-stats: the input converts", r.stderr[-500:], "exit 0"):
        return
    m, _ = read_bin(out)
    js = os.path.join(tmp, "cellstats.json")
    tool = os.path.join(HERE, "..", "tools", "cell-stats.py")
    r = subprocess.run([sys.executable, tool, out, "--json", js], capture_output=True, text=True, timeout=300)
    if not check(r.returncode == 0 and os.path.exists(js), "cell-stats.py reads a version 2 .bin", r.stderr[-500:],
                 "exit 0"):
        return
    with open(js) as f:
        row = json.load(f)[0]
    vol = tet_volumes(m.pos, m.cells[0])
    check(row["elements"] == m.T and row["tets"] == m.T, "cell-stats.py: element counts", row["elements"], m.T)
    check(math.isclose(row["vol_min"], float(vol.min()), rel_tol=1e-6) and
          math.isclose(row["vol_max"], float(vol.max()), rel_tol=1e-6), "cell-stats.py: volume extremes",
          (row["vol_min"], row["vol_max"]), (float(vol.min()), float(vol.max())))


def test_values_match_vtk(tmp):
    """Coordinates and scalars equal what VTK itself reads, vertex by vertex."""
    for rel, name in (("vtk/pyramid_ug.vtu", "temperature"), ("vtk/fire_ug.vtu", "t")):
        src = os.path.join(DATA, rel)
        out = os.path.join(tmp, "values.bin")
        r = convert([src, out, "--quiet"], tmp)
        check(r.returncode == 0 and r.stdout == "", f"{rel} --quiet: exit 0, no output",
              (r.returncode, r.stdout), (0, ""))
        m, problems = read_bin(out)
        if not check(not problems, f"{rel}: valid .bin", problems, []):
            continue
        d = vtk_read(src)
        pts = ns.vtk_to_numpy(d.GetPoints().GetData()).astype(np.float32)
        sc = ns.vtk_to_numpy(d.GetPointData().GetArray(name)).astype(np.float32)
        check(m.V == pts.shape[0] and np.array_equal(m.pos, pts),
              f"{rel}: positions equal VTK's", m.V, pts.shape[0])
        check(m.V == sc.shape[0] and np.array_equal(m.scalars, sc),
              f"{rel}: scalars equal VTK's", m.scalars[:4].tolist(), sc[:4].tolist())


def test_reorientation_and_tets(tmp):
    """fire_ug.vtu stores its hexes inside out; the converter mirrors them. --tets keeps
    the volume exactly (sum of tets = sum of hexes) with 5 or 6 tets per hex."""
    src = os.path.join(DATA, "vtk/fire_ug.vtu")
    d = vtk_read(src)
    conn = ns.vtk_to_numpy(d.GetCells().GetConnectivityArray()).reshape(-1, 8)
    raw = hex_volumes(ns.vtk_to_numpy(d.GetPoints().GetData()), conn)
    check((raw < 0).all(), "fire_ug.vtu hexes are inside out in the file (premise)",
          int((raw < 0).sum()), conn.shape[0])
    hexes = os.path.join(tmp, "fire-hex.bin")
    tets = os.path.join(tmp, "fire-tet.bin")
    r1 = convert([src, hexes, "--quiet"], tmp)
    r2 = convert([src, tets, "--tets", "--quiet"], tmp)
    if not check(r1.returncode == 0 and r2.returncode == 0, "fire_ug: converts with --tets",
                 (r1.stderr, r2.stderr), ("", "")):
        return
    mh, p1 = read_bin(hexes)
    mt, p2 = read_bin(tets)
    if not check(not p1 and not p2, "fire_ug --tets: valid .bin", p1 + p2, []):
        return
    vh = hex_volumes(mh.pos, mh.cells[3])
    check((vh > 0).all(), "fire_ug: hexes reoriented to positive volume",
          int((vh <= 0).sum()), 0)
    check(np.isclose(vh.sum(), -raw.sum(), rtol=1e-6), "fire_ug: reorienting keeps volume",
          vh.sum(), -raw.sum())
    check((mt.P, mt.W, mt.H) == (0, 0, 0) and 5 * mh.H <= mt.T <= 6 * mh.H,
          "fire_ug --tets: only tets, 5 or 6 per hex", (mt.T, mt.P, mt.W, mt.H), 6 * mh.H)
    vt = tet_volumes(mt.pos, mt.cells[0])
    check((vt > 0).all(), "fire_ug --tets: every tet positive", int((vt <= 0).sum()), 0)
    check(math.isclose(vt.sum(), vh.sum(), rel_tol=1e-6), "fire_ug --tets: volume kept",
          vt.sum(), vh.sum())
    r = convert([os.path.join(DATA, "vtk/uGridEx.vtk"), tets, "--tets", "--quiet"], tmp)
    m, p = read_bin(tets)
    check(r.returncode == 0 and not p and (m.T, m.P, m.W, m.H) == (14, 0, 0, 0),
          "uGridEx --tets: 2 tets + 2 hexes x 6", (m.T, m.P, m.W, m.H), (14, 0, 0, 0))


def write_plot3d(path, dims, xyz, iblank=None, order="<", byte_count=False, grids=1,
                 double=False):
    """A binary PLOT3D grid file holding `grids` copies of one grid."""
    real = "d" if double else "f"
    n = dims[0] * dims[1] * dims[2]

    def record(payload):
        if byte_count:
            return struct.pack(f"{order}i", len(payload)) + payload + \
                struct.pack(f"{order}i", len(payload))
        return payload
    out = b""
    if grids > 1:
        out += record(struct.pack(f"{order}i", grids))
    out += record(struct.pack(f"{order}{3 * grids}i", *(list(dims) * grids)))
    for _ in range(grids):
        body = struct.pack(f"{order}{3 * n}{real}", *xyz)
        if iblank is not None:
            body += struct.pack(f"{order}{n}i", *iblank)
        out += record(body)
    with open(path, "wb") as f:
        f.write(out)


def test_plot3d_layouts_and_blanking(tmp):
    """Layouts detected from the sizes; iblank 0 hides every cell around the point."""
    dims = (3, 3, 3)
    xs, ys, zs = [], [], []
    for k in range(3):
        for j in range(3):
            for i in range(3):
                xs.append(float(i))
                ys.append(float(j) * 2.0)
                zs.append(float(k) * 3.0)
    xyz = xs + ys + zs
    blank_corner = [1] * 27
    blank_corner[0] = 0          # in 1 of the 8 cells
    blank_centre = [1] * 27
    blank_centre[13] = 0         # in all 8 cells
    fringe = [-1] * 27           # fringe points are not holes: all 8 cells stay
    cases = [
        ("le-plain", dict(), 8),
        ("be-iblank-corner", dict(order=">", iblank=blank_corner), 7),
        ("le-iblank-fringe", dict(iblank=fringe), 8),
        ("be-records-double", dict(order=">", byte_count=True, double=True), 8),
        ("le-multi-records", dict(byte_count=True, grids=2, iblank=blank_corner), 14),
        ("le-centre", dict(iblank=blank_centre), None),
    ]
    for name, kw, hexes in cases:
        src = os.path.join(tmp, f"{name}xyz.bin")
        out = os.path.join(tmp, f"{name}.bin")
        write_plot3d(src, dims, xyz, **kw)
        r = convert([src, out, "--quiet"], tmp)
        if hexes is None:
            check(r.returncode == 1 and not os.path.exists(out) and "no 3D cells" in r.stderr,
                  f"plot3d {name}: every cell blanked is an error", r.stderr.strip(),
                  "no 3D cells")
            continue
        if not check(r.returncode == 0, f"plot3d {name}: exit status ({r.stderr.strip()})",
                     r.returncode, 0):
            continue
        m, problems = read_bin(out)
        check(not problems and m.H == hexes, f"plot3d {name}: hexes", (problems, m.H), hexes)
        if not problems:
            vol = hex_volumes(m.pos, m.cells[3]).sum()
            check(math.isclose(vol, hexes * 6.0), f"plot3d {name}: volume", vol, hexes * 6.0)


def test_plot3d_q_option(tmp):
    """--q names the solution when the names do not pair; without one, scalars are 0."""
    grid = os.path.join(tmp, "grid.x")
    flow = os.path.join(tmp, "flow.sol")
    shutil.copy(os.path.join(DATA, "plot3d/bluntfinxyz.bin"), grid)
    shutil.copy(os.path.join(DATA, "plot3d/bluntfinq.bin"), flow)
    out = os.path.join(tmp, "q.bin")
    for extra, name, smax_positive in ((["--q", flow], "Density", True), ([], "", False)):
        r = convert([grid, out, "--quiet"] + extra, tmp)
        m, problems = read_bin(out) if r.returncode == 0 else (None, [r.stderr])
        check(not problems and (m.H, m.name, m.smax > 0) == (37479, name, smax_positive),
              f"plot3d grid.x {extra}: hexes, scalar", (problems, m and (m.H, m.name, m.smax)),
              (37479, name))


def legacy_ugrid(path, points, cells):
    """An ASCII legacy .vtk unstructured grid; cells are (vtk type, [point ids])."""
    with open(path, "w") as f:
        f.write("# vtk DataFile Version 3.0\ntest\nASCII\nDATASET UNSTRUCTURED_GRID\n")
        f.write(f"POINTS {len(points)} double\n")
        for p in points:
            f.write(" ".join(repr(float(c)) for c in p) + "\n")
        f.write(f"CELLS {len(cells)} {sum(len(ids) + 1 for _, ids in cells)}\n")
        for _, ids in cells:
            f.write(f"{len(ids)} " + " ".join(map(str, ids)) + "\n")
        f.write(f"CELL_TYPES {len(cells)}\n" + "".join(f"{t}\n" for t, _ in cells))
        f.write(f"POINT_DATA {len(points)}\nSCALARS s float 1\nLOOKUP_TABLE default\n")
        f.write("".join(f"{i}\n" for i in range(len(points))))


def test_quadratic_and_voxel_cells(tmp):
    """Quadratic cells keep their corners, in VTK's linear order; voxels become hexes."""
    hexc = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1),
            (0, 1, 1)]
    wedgec = [(0, 0, 0), (0, 1, 0), (1, 0, 0), (0, 0, 1), (0, 1, 1), (1, 0, 1)]
    pyrc = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0.5, 0.5, 1)]
    # (VTK type, corners, number of further nodes, x shift, clvr slot)
    kinds = [(25, hexc, 12, 0, 3), (29, hexc, 19, 2, 3), (26, wedgec, 9, 4, 2),
             (27, pyrc, 8, 6, 1), (24, [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)], 6, 8, 0)]
    points, cells, want = [], [], {0: [], 1: [], 2: [], 3: []}
    for vtk_type, corners, extra, dx, slot in kinds:
        base = len(points)
        shifted = [(x + dx, y, z) for x, y, z in corners]
        points += shifted
        # Further nodes off the corners, so that taking one of them shows in the check.
        points += [(dx + 0.3 + 0.01 * i, 0.4, 0.45) for i in range(extra)]
        cells.append((vtk_type, list(range(base, base + len(corners) + extra))))
        want[slot].append(shifted)
    cells.append((5, [0, 1, 2]))  # a triangle: dropped
    src = os.path.join(tmp, "quadratic.vtk")
    legacy_ugrid(src, points, cells)
    out = os.path.join(tmp, "quadratic.bin")
    r = convert([src, out], tmp)
    if not check(r.returncode == 0, f"quadratic cells: exit status ({r.stderr.strip()})",
                 r.returncode, 0):
        return
    check("1 2D/1D/0D cells dropped" in r.stdout, "quadratic cells: the triangle is counted "
          "as dropped", r.stdout.strip(), "1 2D/1D/0D cells dropped")
    m, problems = read_bin(out)
    if not check(not problems, "quadratic cells: valid .bin", problems, []):
        return
    check((m.T, m.P, m.W, m.H) == (1, 1, 1, 2), "quadratic cells: counts",
          (m.T, m.P, m.W, m.H), (1, 1, 1, 2))
    for slot in range(4):
        got = [[tuple(float(c) for c in m.pos[i]) for i in cell] for cell in m.cells[slot]]
        check(got == [[tuple(float(c) for c in p) for p in cell] for cell in want[slot]],
              f"quadratic cells: corners of type slot {slot} in VTK order", got, want[slot])

    # Image data: voxels, whose corners VTK lists x-fastest.
    src = os.path.join(tmp, "image.vtk")
    with open(src, "w") as f:
        f.write("# vtk DataFile Version 3.0\nimage\nASCII\nDATASET STRUCTURED_POINTS\n"
                "DIMENSIONS 3 3 3\nSPACING 1 2 3\nORIGIN 0 0 0\nPOINT_DATA 27\n"
                "SCALARS s float 1\nLOOKUP_TABLE default\n" +
                " ".join(str(i) for i in range(27)) + "\n")
    r = convert([src, out, "--quiet"], tmp)
    m, problems = read_bin(out)
    if check(r.returncode == 0 and not problems and m.H == 8, "image data: 8 hexes",
             (r.stderr, problems), []):
        v = hex_volumes(m.pos, m.cells[3])
        check(np.allclose(v, 6.0), "image data: every voxel a proper 1x2x3 hex", v.tolist(),
              [6.0] * 8)


def test_ghosts_in_unstructured_grid(tmp):
    """A hidden point removes every cell using it; duplicate and hidden cells go too."""
    d = vtk_read(os.path.join(DATA, "vtk/fire_ug.vtu"))
    conn = ns.vtk_to_numpy(d.GetCells().GetConnectivityArray()).reshape(-1, 8)
    pg = np.zeros(d.GetNumberOfPoints(), np.uint8)
    pg[[5, 100]] |= 2                       # HIDDENPOINT
    cg = np.zeros(d.GetNumberOfCells(), np.uint8)
    cg[[7, 8, 9]] = 1                       # DUPLICATECELL
    cg[[20]] = 32                           # HIDDENCELL
    gone = np.isin(conn, [5, 100]).any(axis=1)
    gone[[7, 8, 9, 20]] = True
    for name, arr, attrs in (("p", pg, d.GetPointData()), ("c", cg, d.GetCellData())):
        a = ns.numpy_to_vtk(arr, deep=1, array_type=vtk.VTK_UNSIGNED_CHAR)
        a.SetName("vtkGhostType")
        attrs.AddArray(a)
    src = os.path.join(tmp, "ghosts.vtu")
    w = vtk.vtkXMLUnstructuredGridWriter()
    w.SetFileName(src)
    w.SetInputData(d)
    w.Write()
    out = os.path.join(tmp, "ghosts.bin")
    r = convert([src, out], tmp)
    m, problems = read_bin(out) if r.returncode == 0 else (None, [r.stderr])
    want = int((~gone).sum())
    check(not problems and m.H == want, "ghost types: hidden and duplicate cells removed",
          (problems, m and m.H), want)
    check(f"{int(gone.sum())} blanked cells removed" in r.stdout,
          "ghost types: removed cells counted", r.stdout.strip(), int(gone.sum()))


def test_exodus(tmp):
    """Exodus II via vtkExodusIIWriter: point and cell results both reachable."""
    d = vtk_read(os.path.join(DATA, "vtk/fire_ug.vtu"))
    n = d.GetNumberOfCells()
    blocks = np.ones(n, np.int32)
    blocks[n // 3:] = 2  # two element blocks; both must be read
    for name, arr in (("ElementBlockIds", blocks),
                      ("cellval", np.arange(n, dtype=np.float64))):
        a = ns.numpy_to_vtk(arr, deep=1)
        a.SetName(name)
        d.GetCellData().AddArray(a)
    src = os.path.join(tmp, "fire.exo")
    w = vtk.vtkExodusIIWriter()
    w.SetFileName(src)
    w.SetInputData(d)
    w.WriteAllTimeStepsOff()
    w.Write()
    for extra, name in (([], "t"), (["--scalar", "cellval"], "cellval")):
        out = os.path.join(tmp, "exo.bin")
        r = convert([src, out, "--quiet"] + extra, tmp)
        m, problems = read_bin(out) if r.returncode == 0 else (None, [r.stderr])
        check(not problems and (m.H, m.name) == (10462, name), f"exodus {extra}: hexes, name",
              (problems, m and (m.H, m.name)), (10462, name))
        if name == "cellval" and not problems:
            check(0.0 <= m.smin and m.smax <= n - 1 and m.smax > m.smin,
                  "exodus: cell data averaged into the cells' range", (m.smin, m.smax),
                  (0, n - 1))


def test_errors(tmp):
    """Broken inputs: exit 1, one line on stderr naming the file, no output file."""
    trunc = os.path.join(tmp, "truncated.vtu")
    with open(os.path.join(DATA, "vtk/fire_ug.vtu"), "rb") as f:
        data = f.read()
    with open(trunc, "wb") as f:
        f.write(data[:len(data) // 2])
    garbage = os.path.join(tmp, "garbage.vtk")
    with open(garbage, "wb") as f:
        f.write(b"# vtk DataFile Version 3.0\nnonsense\nBINARY\nDATASET BOGUS\n")
    badsize = os.path.join(tmp, "oddxyz.bin")
    with open(badsize, "wb") as f:
        f.write(struct.pack("<3i", 2, 2, 2) + b"\0" * 37)
    existing_bin = os.path.join(tmp, "already.bin")
    shutil.copy(os.path.join(tmp, "fire-hex.bin"), existing_bin) \
        if os.path.exists(os.path.join(tmp, "fire-hex.bin")) else None
    cases = [
        ("missing file", os.path.join(tmp, "no-such.vtu"), [], "no such file"),
        ("truncated .vtu", trunc, [], "VTK cannot read"),
        ("unknown scalar", os.path.join(DATA, "vtk/post.vtk"), ["--scalar", "NoSuchArray"],
         "NoSuchArray"),
        ("broken legacy .vtk", garbage, [], ""),
        ("PLOT3D size fits no layout", badsize, [], "PLOT3D"),
        ("only 2D/1D cells", None, [], "no 3D cells"),
    ]
    if os.path.exists(existing_bin):
        cases.append(("a clvr .bin as input", existing_bin, [], "already a clvr .bin"))
    for label, src, extra, needle in cases:
        if src is None:
            src = os.path.join(tmp, "flat.vtk")
            with open(src, "w") as f:
                f.write("# vtk DataFile Version 3.0\nflat\nASCII\nDATASET UNSTRUCTURED_GRID\n"
                        "POINTS 3 float\n0 0 0 1 0 0 0 1 0\nCELLS 1 4\n3 0 1 2\n"
                        "CELL_TYPES 1\n5\n")
        out = os.path.join(tmp, "error-out.bin")
        r = convert([src, out] + extra, tmp)
        lines = r.stderr.splitlines()
        check(r.returncode == 1, f"error {label}: exit 1", r.returncode, 1)
        check(len(lines) == 1 and src in lines[0] and needle in lines[0],
              f"error {label}: one stderr line naming the file and '{needle}'",
              r.stderr, f"clvr-convert: {src}: ...{needle}...")
        check(r.stdout == "", f"error {label}: nothing on stdout", r.stdout, "")
        check(not os.path.exists(out), f"error {label}: no output file", True, False)
    # A failed conversion leaves an existing output untouched.
    out = os.path.join(tmp, "keep.bin")
    with open(out, "wb") as f:
        f.write(b"old")
    r = convert([trunc, out], tmp)
    with open(out, "rb") as f:
        check(r.returncode == 1 and f.read() == b"old", "error: existing output untouched",
              r.returncode, 1)


def test_list(tmp):
    r = convert([os.path.join(DATA, "vtk/fire_ug.vtu"), "--list"], tmp)
    names = [ln.split("'")[1] for ln in r.stdout.splitlines() if "'" in ln]
    check(r.returncode == 0 and names == ["t", "uvw", "u", "v", "w", "mfrac"],
          "fire_ug --list: every point array in file order", names,
          ["t", "uvw", "u", "v", "w", "mfrac"])
    r = convert([os.path.join(DATA, "plot3d/postxyz.bin"), "--list"], tmp)
    check(r.returncode == 0 and "'Density'" in r.stdout and "'VelocityMagnitude'" in r.stdout,
          "postxyz --list: q file found by name", r.stdout[:200], "Density, VelocityMagnitude")


def test_output_name_and_avs(tmp):
    """An output not named .bin is refused before reading (exit 2, one line, nothing
    written); AVS UCD .inp reads through vtkAVSucdReader with its node data; and
    clvr names this converter for every extension the converter reads."""
    src = os.path.join(DATA, "vtk/post.vtk")
    for bad in ("out.png", "out.vtu", "out", "out.bin.tmp"):
        out = os.path.join(tmp, bad)
        r = convert([src, out], tmp)
        lines = r.stderr.splitlines()
        check(r.returncode == 2 and len(lines) == 1 and out in lines[0] and ".bin" in lines[0]
              and not os.path.exists(out), f"output name {bad}: exit 2, one line naming it, no file",
              (r.returncode, r.stderr), (2, f"clvr-convert: {out}: ... *.bin ..."))
    for label, args in (("no output", [src]), ("unknown option", [src, "x.bin", "--frobnicate"])):
        r = convert(args, tmp)
        check(r.returncode == 2 and len(r.stderr.splitlines()) == 1 and "clvr-convert" in r.stderr,
              f"{label}: exit 2, one line", (r.returncode, r.stderr), (2, "clvr-convert: ..."))
    r = convert([src, os.path.join(tmp, "upper.BIN"), "--quiet"], tmp)
    check(r.returncode == 0, "output name upper.BIN accepted", r.stderr, "")

    # AVS UCD: a hexahedron (bottom face, then top) and a pyramid (apex first,
    # AVS's order) sharing the hex's top face; one node data component.
    inp = os.path.join(tmp, "two.inp")
    with open(inp, "w") as f:
        f.write("# AVS UCD written by test_convert.py\n9 2 1 0 0\n")
        pts = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1),
               (0.5, 0.5, 2)]
        for i, p in enumerate(pts):
            f.write(f"{i + 1} {p[0]} {p[1]} {p[2]}\n")
        f.write("1 1 hex 1 2 3 4 5 6 7 8\n2 1 pyr 9 5 6 7 8\n1 1\ntemp, K\n")
        for i in range(9):
            f.write(f"{i + 1} {i * 0.5}\n")
    out = os.path.join(tmp, "two.bin")
    r = convert([inp, out], tmp)
    m, problems = read_bin(out) if r.returncode == 0 else (None, [r.stderr])
    check(m is not None and not problems and (m.T, m.P, m.W, m.H) == (0, 1, 0, 1)
          and m.name == "temp" and abs(float(m.scalars.max()) - 4.0) < 1e-6
          and "reoriented" not in r.stdout,
          "AVS UCD .inp: 1 hex + 1 pyramid, scalar 'temp' 0..4, none inside out",
          (r.stdout.strip(), problems), "(0, 1, 0, 1) temp")

    # Every extension the converter reads gets clvr's pointer to the converter.
    if not os.access(CLVR, os.X_OK):
        check(False, f"clvr binary at {CLVR} for the format messages")
        return
    spec = importlib.util.spec_from_loader("clvr_convert",
                                           importlib.machinery.SourceFileLoader("clvr_convert", CONVERT))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    missing = []
    for ext in sorted(mod.CONVERTER_EXT - {".vtk"}):  # legacy .vtk clvr reads itself
        path = os.path.join(tmp, "data" + ext)
        with open(path, "wb") as f:
            f.write(b"not a mesh\n")
        r = subprocess.run([CLVR, "--info", path], capture_output=True, text=True, timeout=60)
        lines = r.stderr.splitlines()
        if not (r.returncode == 3 and len(lines) == 1 and "tools/clvr-convert" in lines[0] and path in lines[0]):
            missing.append((ext, r.returncode, r.stderr.strip()[:160]))
    check(not missing, f"clvr names tools/clvr-convert for all {len(mod.CONVERTER_EXT) - 1} converter "
          "extensions", missing, [])


def clvr_info(path, *extra):
    r = subprocess.run([CLVR, "--info", path, *extra], capture_output=True, text=True, timeout=120)
    return r


def info_scalar_range(stdout):
    """(name, lo, hi) from clvr --info's "scalar NAME, range [lo, hi]" line."""
    for line in stdout.splitlines():
        if line.startswith("scalar "):
            body = line[len("scalar"):].strip()
            name, rest = body.rsplit(", range [", 1)
            lo, hi = rest.split("]")[0].split(", ")
            return name, float(lo), float(hi)
    return None, None, None


def test_fields(tmp):
    """Every point and cell array survives conversion with VTK's values (version 2
    field table), clvr --info lists each one, and --scalar reaches any of them: a vector
    by magnitude or one component, and point:/cell: where both share a name."""
    src = os.path.join(DATA, "vtk/fire_ug.vtu")
    out = os.path.join(tmp, "fire_fields.bin")
    r = convert([src, out, "--quiet"], tmp)
    m, problems = read_bin(out) if r.returncode == 0 else (None, [r.stderr])
    check(m is not None and not problems and m.version == 2, "fire_ug.vtu: a valid version 2 .bin",
          problems, [])
    if m is None:
        return
    rd = vtk.vtkXMLUnstructuredGridReader()
    rd.SetFileName(src)
    rd.Update()
    pd = rd.GetOutput().GetPointData()
    names = [pd.GetArrayName(i) for i in range(pd.GetNumberOfArrays())]
    got = [(f[0], f[1], f[2]) for f in m.fields]
    want = [(n, 0, pd.GetArray(n).GetNumberOfComponents()) for n in names]
    check(got == want, "fire_ug.vtu: every point array kept, in file order", got, want)
    worst = 0.0
    for f in m.fields:
        ref = ns.vtk_to_numpy(pd.GetArray(f[0])).reshape(m.V, -1)  # no vertex is unused here
        worst = max(worst, float(np.abs(f[5] - ref).max()))
    check(worst < 1e-5, "fire_ug.vtu: every field's values equal VTK's", worst, "< 1e-5")
    if not os.access(CLVR, os.X_OK):
        return
    r = clvr_info(out)
    listed = [ln.split()[1] for ln in r.stdout.splitlines() if ln.startswith("  point ")
              or ln.startswith("  cell ")]
    check(r.returncode == 0 and listed == names, "clvr --info lists every field", listed, names)
    uvw = ns.vtk_to_numpy(pd.GetArray("uvw")).astype(np.float32)
    for spec, ref in (("uvw", np.sqrt((uvw.astype(np.float64) ** 2).sum(1))), ("uvw:y", uvw[:, 1]),
                      ("point:mfrac", ns.vtk_to_numpy(pd.GetArray("mfrac")))):
        r = clvr_info(out, "--scalar", spec)
        name, lo, hi = info_scalar_range(r.stdout)
        check(r.returncode == 0 and name == spec.replace("point:", "") and abs(lo - ref.min()) < 1e-4 * max(1, abs(ref.min()))
              and abs(hi - ref.max()) < 1e-4 * max(1, abs(ref.max())),
              f"clvr --scalar {spec}: the field's range", (r.returncode, name, lo, hi, r.stderr.strip()),
              (spec, float(ref.min()), float(ref.max())))
    r = clvr_info(out, "--scalar", "nope")
    check(r.returncode != 0 and "uvw" in r.stderr and "nope" in r.stderr and out in r.stderr,
          "clvr --scalar nope: names the file, the spec and the fields there are", r.stderr.strip(), "...")

    # A point and a cell array with one name (post.vtk's Pressure, and its cell
    # average as cell data), converted from a .vtu VTK writes at test time.
    rd = vtk.vtkUnstructuredGridReader()
    rd.SetFileName(os.path.join(DATA, "vtk/post.vtk"))
    rd.Update()
    ug = rd.GetOutput()
    p2c = vtk.vtkPointDataToCellData()
    p2c.SetInputData(ug)
    p2c.Update()
    cellp = ns.vtk_to_numpy(p2c.GetOutput().GetCellData().GetArray("Pressure")) * 10.0
    both = vtk.vtkUnstructuredGrid()
    both.DeepCopy(ug)
    arr = ns.numpy_to_vtk(cellp, deep=1)
    arr.SetName("Pressure")
    both.GetCellData().AddArray(arr)
    vtu = os.path.join(tmp, "both.vtu")
    w = vtk.vtkXMLUnstructuredGridWriter()
    w.SetFileName(vtu)
    w.SetInputData(both)
    w.Write()
    out = os.path.join(tmp, "both.bin")
    r = convert([vtu, out, "--quiet"], tmp)
    m, problems = read_bin(out) if r.returncode == 0 else (None, [r.stderr])
    got = [(f[0], f[1]) for f in m.fields] if m else None
    check(m is not None and not problems and got == [("Pressure", 0), ("Pressure", 1)],
          "point and cell 'Pressure' both kept", (got, problems), [("Pressure", 0), ("Pressure", 1)])
    if m is None:
        return
    check(np.allclose(m.fields[1][5][:, 0], cellp.astype(np.float32)), "cell 'Pressure' in element order")
    r1, r2 = clvr_info(out, "--scalar", "point:Pressure"), clvr_info(out, "--scalar", "cell:Pressure")
    (n1, lo1, hi1), (n2, lo2, hi2) = info_scalar_range(r1.stdout), info_scalar_range(r2.stdout)
    avg = field_per_vertex(m, 1)
    check(r1.returncode == 0 and r2.returncode == 0 and hi2 > 5 * hi1
          and abs(hi2 - float(avg.max())) < 1e-3 * float(avg.max()) and "cell data averaged" in r2.stdout,
          "point:Pressure and cell:Pressure both reachable, cell data averaged to the vertices",
          (lo1, hi1, lo2, hi2, r1.stderr.strip(), r2.stderr.strip()), f"cell max {avg.max()}")


def test_warnings_once(tmp):
    """Flawed real meshes (post.vtk appended to itself: 8750 duplicate tets; fire_ug.vtu,
    whose hexes are all inside out, saved as legacy .vtk by VTK): clvr-convert says so
    once, on one line; clvr warns on a render and --quiet silences it."""
    rd = vtk.vtkUnstructuredGridReader()
    rd.SetFileName(os.path.join(DATA, "vtk/post.vtk"))
    rd.Update()
    a = vtk.vtkAppendFilter()
    a.AddInputData(rd.GetOutput())
    a.AddInputData(rd.GetOutput())
    a.SetMergePoints(1)
    a.Update()
    dup = os.path.join(tmp, "post_twice.vtk")
    w = vtk.vtkUnstructuredGridWriter()
    w.SetFileName(dup)
    w.SetInputData(a.GetOutput())
    w.SetFileTypeToBinary()
    w.Write()
    out = os.path.join(tmp, "post_twice.bin")
    r = convert([dup, out], tmp)
    warn = [ln for ln in r.stderr.splitlines() if "warning" in ln]
    check(r.returncode == 0 and len(warn) == 1 and "8750 duplicate elements" in warn[0] and dup in warn[0],
          "clvr-convert: duplicates said once, on one line", r.stderr.strip(), "... 8750 duplicate elements ...")
    r = convert([dup, os.path.join(tmp, "q.bin"), "--quiet"], tmp)
    check(r.returncode == 0 and r.stderr == "" and r.stdout == "", "clvr-convert --quiet prints nothing",
          (r.stdout, r.stderr), ("", ""))
    if not os.access(CLVR, os.X_OK):
        return
    png = os.path.join(tmp, "w.png")
    base = ["--size", "16x16", "--spp", "1", "-o", png]
    for mesh, what in ((out, "8750 duplicate elements"), (None, "10462 inverted elements")):
        if mesh is None:
            x = vtk.vtkXMLUnstructuredGridReader()
            x.SetFileName(os.path.join(DATA, "vtk/fire_ug.vtu"))
            x.Update()
            mesh = os.path.join(tmp, "fire_legacy.vtk")
            w = vtk.vtkUnstructuredGridWriter()
            w.SetFileName(mesh)
            w.SetInputData(x.GetOutput())
            w.SetFileTypeToBinary()
            w.Write()
        r = subprocess.run([CLVR, mesh] + base, capture_output=True, text=True, timeout=300)
        if no_device(r, "the render warnings"):
            return
        warn = [ln for ln in r.stderr.splitlines() if "warning" in ln and what in ln]
        check(r.returncode == 0 and len(warn) == 1, f"clvr {os.path.basename(mesh)}: '{what}' warned once",
              r.stderr.strip()[:300], what)
        r = subprocess.run([CLVR, mesh, "--quiet"] + base, capture_output=True, text=True, timeout=300)
        check(r.returncode == 0 and r.stderr == "", f"clvr --quiet {os.path.basename(mesh)}: no warning",
              r.stderr.strip()[:300], "")


HEX_FACES = ((0, 4, 7, 3), (1, 2, 6, 5), (0, 1, 5, 4), (3, 7, 6, 2), (0, 3, 2, 1), (4, 5, 6, 7))


def png_pixels(path):
    r = vtk.vtkPNGReader()
    r.SetFileName(path)
    r.Update()
    return ns.vtk_to_numpy(r.GetOutput().GetPointData().GetScalars()).astype(np.float64)


def test_polyhedra(tmp):
    """fire_ug.vtu's 10,462 hexes written by VTK as polyhedron cells (type 42) in legacy
    .vtk, as OpenFOAM's foamToVTK -legacy writes its polyhedra (4.2 classic cells and
    5.1 offsets): clvr reads them directly, decomposes each (3 pyramids per hex), says
    how many, leaves no hole, and renders what the hexes render."""
    x = vtk.vtkXMLUnstructuredGridReader()
    x.SetFileName(os.path.join(DATA, "vtk/fire_ug.vtu"))
    x.Update()
    src = x.GetOutput()
    poly = vtk.vtkUnstructuredGrid()
    poly.SetPoints(src.GetPoints())
    poly.GetPointData().ShallowCopy(src.GetPointData())
    ids = vtk.vtkIdList()
    for c in range(src.GetNumberOfCells()):
        cell = src.GetCell(c)
        p = [cell.GetPointId(i) for i in range(8)]
        ids.Reset()
        ids.InsertNextId(6)
        for f in HEX_FACES:
            ids.InsertNextId(4)
            for k in f:
                ids.InsertNextId(p[k])
        poly.InsertNextCell(vtk.VTK_POLYHEDRON, ids)
    hexes = os.path.join(tmp, "fire_hex.vtk")
    w = vtk.vtkUnstructuredGridWriter()
    w.SetFileName(hexes)
    w.SetInputData(src)
    w.SetFileTypeToBinary()
    w.Write()
    if not os.access(CLVR, os.X_OK):
        return
    ref = None
    for version in (42, 51):
        path = os.path.join(tmp, f"fire_poly{version}.vtk")
        w = vtk.vtkUnstructuredGridWriter()
        w.SetFileName(path)
        w.SetInputData(poly)
        w.SetFileTypeToBinary()
        if version == 42:
            w.SetFileVersion(42)
        w.Write()
        r = clvr_info(path)
        tokens = r.stdout.split()
        check(r.returncode == 0 and "decomposed" in tokens and tokens[tokens.index("decomposed") + 1] == "10462"
              and tokens[tokens.index("pyramids") + 1] == "31386" and "left out" not in r.stdout,
              f"polyhedra {version}: clvr --info: 10462 decomposed into 31386 pyramids, none left out",
              (r.returncode, r.stdout[:400], r.stderr.strip()), "decomposed 10462")
        png = os.path.join(tmp, f"poly{version}.png")
        args = ["--size", "48x48", "--spp", "2", "-o", png]
        r = subprocess.run([CLVR, path] + args, capture_output=True, text=True, timeout=300)
        if no_device(r, "the polyhedra render"):
            return
        check(r.returncode == 0 and "10462 polyhedra decomposed" in r.stderr and "left out" not in r.stderr
              and "inverted" not in r.stderr and "degenerate" not in r.stderr,
              f"polyhedra {version}: rendered, decomposition said, no hole, no inverted element",
              r.stderr.strip()[-400:], "... 10462 polyhedra decomposed ...")
        if ref is None:
            hpng = os.path.join(tmp, "hex.png")
            r = subprocess.run([CLVR, hexes, "--quiet"] + args[:-1] + [hpng], capture_output=True, text=True,
                               timeout=300)
            check(r.returncode == 0, "the hexes' reference image renders", r.stderr.strip()[-300:], "")
            ref = png_pixels(hpng) if r.returncode == 0 else None
        if ref is not None and os.path.exists(png):
            diff = float(np.abs(png_pixels(png) - ref).mean())
            check(diff < 2.0, f"polyhedra {version}: the image matches the hexes' (mean |diff| of 255)",
                  diff, "< 2")


def exodus_time_steps(tmp):
    """Exodus II with 3 time steps (fire_ug.vtu with t + 100 * time, written by
    vtkExodusIIWriter from a temporal source): one .bin per step, one warning line."""
    from vtk.util.vtkAlgorithm import VTKPythonAlgorithmBase
    base = vtk_read(os.path.join(DATA, "vtk/fire_ug.vtu"))
    t0 = ns.vtk_to_numpy(base.GetPointData().GetArray("t")).astype(np.float64)
    times = [0.0, 1.0, 2.0]
    sddp = vtk.vtkStreamingDemandDrivenPipeline

    class Source(VTKPythonAlgorithmBase):
        def __init__(self):
            VTKPythonAlgorithmBase.__init__(self, nInputPorts=0, nOutputPorts=1,
                                            outputType="vtkUnstructuredGrid")

        def RequestInformation(self, request, in_info, out_info):
            info = out_info.GetInformationObject(0)
            for t in times:
                info.Append(sddp.TIME_STEPS(), t)
            info.Append(sddp.TIME_RANGE(), times[0])
            info.Append(sddp.TIME_RANGE(), times[-1])
            return 1

        def RequestData(self, request, in_info, out_info):
            info = out_info.GetInformationObject(0)
            t = info.Get(sddp.UPDATE_TIME_STEP()) if info.Has(sddp.UPDATE_TIME_STEP()) else 0.0
            out = vtk.vtkUnstructuredGrid.GetData(out_info)
            out.DeepCopy(base)
            a = ns.numpy_to_vtk(t0 + 100.0 * t, deep=1)
            a.SetName("t")
            out.GetPointData().RemoveArray("t")
            out.GetPointData().AddArray(a)
            return 1

    src = os.path.join(tmp, "fire_t.exo")
    alg = Source()  # kept alive while the writer pulls from it
    w = vtk.vtkExodusIIWriter()
    w.SetFileName(src)
    w.SetInputConnection(alg.GetOutputPort())
    w.WriteAllTimeStepsOn()
    w.Write()
    out = os.path.join(tmp, "exo_t.bin")
    r = convert([src, out, "--scalar", "t"], tmp)
    steps = [os.path.join(tmp, f"exo_t.{i:04d}.bin") for i in range(3)]
    ok = r.returncode == 0 and all(os.path.isfile(p) for p in steps) and os.path.isfile(out + ".series")
    warn = [ln for ln in r.stderr.splitlines() if "warning" in ln]
    check(ok and len(warn) == 1 and "10462 inverted" in warn[0] and "2 more steps" in warn[0],
          "Exodus with 3 time steps: 3 .bin and a .series, the inverted hexes said once",
          (r.returncode, r.stderr.strip()), "one warning line")
    if ok:
        maxes = [float(read_bin(p)[0].scalars.max()) for p in steps]
        check(np.allclose(maxes, [t0.max() + 100 * t for t in times], rtol=1e-6),
              "Exodus time steps: each step holds its own t", maxes, "t + 100 * time")


def test_series(tmp):
    """A time series of real data (post.vtk's Pressure times 1, 2, 3 at times 0, 0.5, 1,
    written by VTK as .vtu files with a ParaView .pvd and a .vtu.series) converts to one
    .bin per step plus OUT.bin.series; clvr renders it to numbered frames with one range
    over all steps (--range auto-all) and one camera; a missing step leaves nothing."""
    import json
    rd = vtk.vtkUnstructuredGridReader()
    rd.SetFileName(os.path.join(DATA, "vtk/post.vtk"))
    rd.Update()
    base = rd.GetOutput()
    pres = ns.vtk_to_numpy(base.GetPointData().GetArray("Pressure")).astype(np.float64)
    sdir = os.path.join(tmp, "series")
    os.makedirs(sdir)
    names = []
    for i in range(3):
        g = vtk.vtkUnstructuredGrid()
        g.DeepCopy(base)
        a = ns.numpy_to_vtk(pres * (i + 1), deep=1)
        a.SetName("Pressure")
        g.GetPointData().RemoveArray("Pressure")
        g.GetPointData().AddArray(a)
        names.append(f"post_{i}.vtu")
        w = vtk.vtkXMLUnstructuredGridWriter()
        w.SetFileName(os.path.join(sdir, names[-1]))
        w.SetInputData(g)
        w.Write()
    pvd = os.path.join(sdir, "post.pvd")
    with open(pvd, "w") as f:
        f.write('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1"><Collection>\n')
        for i, n in enumerate(names):
            f.write(f'<DataSet timestep="{i * 0.5}" part="0" file="{n}"/>\n')
        f.write("</Collection></VTKFile>\n")
    jser = os.path.join(sdir, "post.vtu.series")
    with open(jser, "w") as f:
        json.dump({"file-series-version": "1.0",
                   "files": [{"name": n, "time": i * 0.5} for i, n in enumerate(names)]}, f)
    outs = {}
    for src, stem in ((pvd, "pvd"), (jser, "json")):
        out = os.path.join(tmp, f"{stem}.bin")
        r = convert([src, out, "--quiet"], tmp)
        series = out + ".series"
        steps = [os.path.join(tmp, f"{stem}.{i:04d}.bin") for i in range(3)]
        ok = r.returncode == 0 and os.path.isfile(series) and all(os.path.isfile(p) for p in steps)
        check(ok, f"{os.path.basename(src)}: 3 steps and a .series written", (r.returncode, r.stderr.strip()), "0")
        if not ok:
            return
        with open(series) as f:
            doc = json.load(f)
        check([e["name"] for e in doc["files"]] == [os.path.basename(p) for p in steps]
              and [e["time"] for e in doc["files"]] == [0.0, 0.5, 1.0],
              f"{os.path.basename(series)}: names and times", doc, "0000..0002 at 0, 0.5, 1")
        maxes = [float(read_bin(p)[0].scalars.max()) for p in steps]
        check(np.allclose(maxes, [pres.max() * k for k in (1, 2, 3)], rtol=1e-6),
              f"{os.path.basename(src)}: each step holds its own values", maxes, "x1, x2, x3")
        outs[stem] = series
    # A step that cannot be read: exit 1, one line, nothing written.
    bad = os.path.join(sdir, "bad.pvd")
    with open(bad, "w") as f:
        f.write('<VTKFile type="Collection"><Collection><DataSet timestep="0" file="post_0.vtu"/>'
                '<DataSet timestep="1" file="missing.vtu"/></Collection></VTKFile>\n')
    r = convert([bad, os.path.join(tmp, "bad.bin")], tmp)
    left = [f for f in os.listdir(tmp) if f.startswith("bad.")]
    check(r.returncode == 1 and "missing.vtu" in r.stderr and not left,
          "a series with a missing step: exit 1, names it, writes nothing", (r.returncode, r.stderr, left),
          (1, "missing.vtu", []))
    exodus_time_steps(tmp)
    if not os.access(CLVR, os.X_OK):
        return
    frame = os.path.join(tmp, "frame.png")
    r = subprocess.run([CLVR, outs["pvd"], "-o", frame, "--size", "32x32", "--spp", "2"],
                       capture_output=True, text=True, timeout=300)
    if no_device(r, "the series render"):
        return
    frames = [os.path.join(tmp, f"frame.{i:04d}.png") for i in range(3)]
    want = f"one range [{np.float32(pres.min()):g}, {np.float32(pres.max() * 3):g}]"
    check(r.returncode == 0 and all(os.path.isfile(p) for p in frames) and want in r.stderr,
          "clvr renders the series to frame.0000..0002.png with one range over all steps",
          (r.returncode, r.stderr.strip()[-600:]), want)
    if all(os.path.isfile(p) for p in frames):
        a, c = png_pixels(frames[0]), png_pixels(frames[2])
        check(float(np.abs(a - c).mean()) > 1.0, "the fixed range shows the field growing: frames differ",
              float(np.abs(a - c).mean()), "> 1")
    r = subprocess.run([CLVR, outs["json"], "--orbit", "3"], capture_output=True, text=True, timeout=60)
    check(r.returncode == 2 and "--orbit" in r.stderr, "a series with --orbit: usage error", r.stderr.strip(), 2)


def test_cell_data_flat(tmp):
    """kiefer_tet10.vtu's von Mises stress is cell data: by default clvr renders it
    averaged onto the vertices (a narrower range); --cell-data flat renders each
    element's own value, so the range is exactly VTK's cell range and the image differs."""
    src = os.path.join(DATA, "vtk/kiefer_tet10.vtu")
    out = os.path.join(tmp, "kiefer_flat.bin")
    r = convert([src, out, "--quiet"], tmp)
    if not check(r.returncode == 0, "kiefer_tet10.vtu converts", r.stderr.strip(), "") or \
            not os.access(CLVR, os.X_OK):
        return
    cells = vtk_read(src).GetCellData()
    lo, hi = cells.GetArray(0).GetRange(0)
    ra, rf = clvr_info(out), clvr_info(out, "--cell-data", "flat")
    _, alo, ahi = info_scalar_range(ra.stdout)
    _, flo, fhi = info_scalar_range(rf.stdout)
    check(rf.returncode == 0 and abs(flo - lo) <= 1e-5 * abs(lo) + 1e-7 and abs(fhi - hi) <= 1e-5 * abs(hi)
          and "flat" in rf.stdout, "--cell-data flat: the range is the cells' own", (flo, fhi), (lo, hi))
    check(ra.returncode == 0 and ahi < hi * 0.99 and "averaged" in ra.stdout,
          "default: cell data averaged to the vertices (narrower range), and --info says so", (alo, ahi),
          f"max < {hi}")
    pngs = []
    for extra in ([], ["--cell-data", "flat"]):
        png = os.path.join(tmp, f"kiefer{len(extra)}.png")
        r = subprocess.run([CLVR, out, "--quiet", "--size", "48x48", "--spp", "2", "-o", png] + extra,
                           capture_output=True, text=True, timeout=300)
        if no_device(r, "the flat render"):
            return
        check(r.returncode == 0, f"clvr {' '.join(extra) or 'default'} renders kiefer", r.stderr.strip(), "")
        pngs.append(png)
    if all(os.path.isfile(p) for p in pngs):
        diff = float(np.abs(png_pixels(pngs[0]) - png_pixels(pngs[1])).mean())
        check(diff > 0.2, "flat and averaged cell data render differently", diff, "> 0.2")


def main():
    if not os.path.isfile(CONVERT):
        print(f"FAIL no converter at {CONVERT}")
        print("0 passed, 1 failed")
        return 1
    info_ok, info_note = clvr_has_info()
    tmp = tempfile.mkdtemp(prefix="clvr-test-convert-")
    try:
        # CLVR_TEST_BRIEF=1 (the sanitizer build, CMakeLists.txt): only the
        # cases that run clvr on what the converter wrote. The converter is
        # Python, the same under ASan; the plain build runs every case.
        brief = os.environ.get("CLVR_TEST_BRIEF") == "1"
        test_files(tmp, info_ok)
        if not brief:
            test_cell_stats(tmp)
            test_values_match_vtk(tmp)
            test_reorientation_and_tets(tmp)
            test_plot3d_layouts_and_blanking(tmp)
            test_plot3d_q_option(tmp)
            test_quadratic_and_voxel_cells(tmp)
            test_ghosts_in_unstructured_grid(tmp)
            test_exodus(tmp)
            test_errors(tmp)
            test_list(tmp)
        test_output_name_and_avs(tmp)
        test_fields(tmp)
        test_warnings_once(tmp)
        test_polyhedra(tmp)
        test_series(tmp)
        test_cell_data_flat(tmp)
        skipped = sorted(os.path.relpath(p, DATA) for p in glob.glob(os.path.join(DATA, "*", "*"))
                         if p.endswith(".umesh"))
        print(f"not VTK-readable, skipped: {', '.join(skipped)}")
        print(f"clvr --info: {info_note}")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    check.summary()
    if check.failed:
        return 1
    if NO_DEVICE:
        print(f"skipped (no OpenCL device): {', '.join(NO_DEVICE)}")
        return 77
    return 0


if __name__ == "__main__":
    sys.exit(main())
