"""meshgen.py: writers for small (and deliberately broken) meshes in the three
formats clvr reads, for tests/test_hostile.py and the fuzz seeds
(tests/fuzz/make_seeds.py). Standard library only, so it runs under any
python3. Layouts: docs/bin-format.md, host/io/mesh_umesh.c, host/mesh_vtk.c.

A mesh is a dict: positions (list of (x, y, z)), scalars (list), cells
(dict: 'tets'/'pyramids'/'wedges'/'hexes' -> list of index tuples),
scalar_name. Values are written as given (NaN, inf, negative or huge
indices included): the point is to produce what a broken writer would.
"""
import math
import struct

CELL_TYPES = ("tets", "pyramids", "wedges", "hexes")
CELL_VERTS = {"tets": 4, "pyramids": 5, "wedges": 6, "hexes": 8}
VTK_CELL_TYPE = {"tets": 10, "pyramids": 14, "wedges": 13, "hexes": 12}


def mesh(positions, scalars, cells, scalar_name="s"):
    full = {t: list(cells.get(t, [])) for t in CELL_TYPES}
    return {"positions": list(positions), "scalars": list(scalars), "cells": full, "scalar_name": scalar_name}


# ---------------------------------------------------------------- shapes

def unit_tet(scalars=(0.0, 1.0, 0.5, 0.25)):
    """One positively oriented tet (VTK order: the fourth vertex is on the
    side the first three's right-hand normal points to)."""
    pos = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
    return mesh(pos, scalars, {"tets": [(0, 1, 2, 3)]})


def hex_grid(n=3, scalar=None):
    """n x n x n unit hexes on [0, 1]^3 (VTK hex order), scalar = x + y + z by
    default, or scalar(x, y, z)."""
    f = scalar or (lambda x, y, z: x + y + z)
    pos, sc = [], []
    for k in range(n + 1):
        for j in range(n + 1):
            for i in range(n + 1):
                x, y, z = i / n, j / n, k / n
                pos.append((x, y, z))
                sc.append(f(x, y, z))

    def v(i, j, k):
        return (k * (n + 1) + j) * (n + 1) + i

    hexes = []
    for k in range(n):
        for j in range(n):
            for i in range(n):
                hexes.append((v(i, j, k), v(i + 1, j, k), v(i + 1, j + 1, k), v(i, j + 1, k),
                              v(i, j, k + 1), v(i + 1, j, k + 1), v(i + 1, j + 1, k + 1), v(i, j + 1, k + 1)))
    return mesh(pos, sc, {"hexes": hexes})


def tet_grid(n=3, scalar=None):
    """The hex grid split into 6 tets per hex (Kuhn triangulation), all
    positively oriented."""
    h = hex_grid(n, scalar)
    tets = []
    for c in h["cells"]["hexes"]:
        # Kuhn: the 6 paths from corner 0 to corner 6 of the VTK hex.
        for a, b in ((1, 2), (2, 3), (3, 7), (7, 4), (4, 5), (5, 1)):
            t = (c[0], c[a], c[b], c[6])
            if signed_volume([h["positions"][i] for i in t]) < 0:
                t = (t[1], t[0], t[2], t[3])
            tets.append(t)
    return mesh(h["positions"], h["scalars"], {"tets": tets}, h["scalar_name"])


def signed_volume(p):
    ax, ay, az = (p[1][k] - p[0][k] for k in range(3))
    bx, by, bz = (p[2][k] - p[0][k] for k in range(3))
    cx, cy, cz = (p[3][k] - p[0][k] for k in range(3))
    return (ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)) / 6.0


# ---------------------------------------------------------------- .bin

def bin_bytes(m, num_vertices=None, num_cells=None, version=1, header_size=256, flags=0, cut=None, extra=b""):
    """clvr .bin; the header counts may be overridden (num_vertices,
    num_cells: dict type -> count) to lie about the arrays that follow."""
    nv = len(m["positions"]) if num_vertices is None else num_vertices
    counts = [len(m["cells"][t]) for t in CELL_TYPES]
    if num_cells:
        counts = [num_cells.get(t, c) for t, c in zip(CELL_TYPES, counts)]
    pos = m["positions"]
    finite = [p for p in pos if all(math.isfinite(c) for c in p)] or [(0, 0, 0)]
    lo = [min(p[k] for p in finite) for k in range(3)]
    hi = [max(p[k] for p in finite) for k in range(3)]
    sc = [s for s in m["scalars"] if math.isfinite(s)] or [0.0]
    h = bytearray(256)
    h[0:8] = b"CLVRMESH"
    struct.pack_into("<II", h, 8, version, header_size)
    struct.pack_into("<Q", h, 16, nv)
    struct.pack_into("<4Q", h, 24, *counts)
    struct.pack_into("<3f3f2f", h, 56, *lo, *hi, min(sc), max(sc))
    name = m["scalar_name"].encode()[:63]
    h[88:88 + len(name)] = name
    struct.pack_into("<I", h, 152, flags)
    body = bytearray()
    for p in pos:
        body += struct.pack("<3f", *p)
    body += struct.pack("<%df" % len(m["scalars"]), *m["scalars"])
    for t in CELL_TYPES:
        for c in m["cells"][t]:
            body += struct.pack("<%dI" % len(c), *[i & 0xFFFFFFFF for i in c])
    data = bytes(h) + bytes(body) + extra
    return data if cut is None else data[:cut]


# ---------------------------------------------------------------- .umesh

def umesh_bytes(m, version=0x566):
    """umesh 566 (unnamed scalars) or 567 (named per-vertex attributes)."""
    out = bytearray(struct.pack("<Q", 0x234235000 + version))
    out += struct.pack("<Q", len(m["positions"]))
    for p in m["positions"]:
        out += struct.pack("<3f", *p)
    if version == 0x566:
        out += struct.pack("<Q", len(m["scalars"]))
        out += struct.pack("<%df" % len(m["scalars"]), *m["scalars"])
    else:
        name = m["scalar_name"].encode()
        out += struct.pack("<Q", 1)
        out += struct.pack("<i", len(name)) + name
        out += struct.pack("<Q", len(m["scalars"]))
        out += struct.pack("<%df" % len(m["scalars"]), *m["scalars"])
        out += struct.pack("<Q", 0)  # per-element attributes
    out += struct.pack("<Q", 0) + struct.pack("<Q", 0)  # triangles, quads
    for t in CELL_TYPES:
        cells = m["cells"][t]
        out += struct.pack("<Q", len(cells))
        for c in cells:
            out += struct.pack("<%di" % len(c), *[(i + 2**31) % 2**32 - 2**31 for i in c])
    if version >= 0x568:
        out += struct.pack("<Q", 0) + struct.pack("<Q", 0)  # grids, gridScalars
    return bytes(out)


# ---------------------------------------------------------------- legacy VTK

def _fmt(v):
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    return str(v)


def vtk_bytes(m, binary=False, version="3.0", new_layout=False, cell_data=False, extra_cells=()):
    """Legacy VTK unstructured grid. new_layout: VTK 5.1 OFFSETS /
    CONNECTIVITY; cell_data: the scalar as CELL_DATA (one value per cell:
    the mean of its vertices'). extra_cells: (vtk type, ids) appended, e.g.
    triangles that the reader skips."""
    cells = []
    for t in CELL_TYPES:
        for c in m["cells"][t]:
            cells.append((VTK_CELL_TYPE[t], list(c)))
    cells += [(vt, list(ids)) for vt, ids in extra_cells]
    out = bytearray(("# vtk DataFile Version %s\nclvr hostile test\n%s\nDATASET UNSTRUCTURED_GRID\n"
                     % (version, "BINARY" if binary else "ASCII")).encode())

    def arr(fmt_char, values, per_line=9):
        if binary:
            return struct.pack(">%d%s" % (len(values), fmt_char), *values) + b"\n"
        lines = []
        for i in range(0, len(values), per_line):
            lines.append(" ".join(_fmt(v) for v in values[i:i + per_line]))
        return ("\n".join(lines) + "\n").encode()

    flat = [c for p in m["positions"] for c in p]
    out += b"POINTS %d float\n" % len(m["positions"])
    out += arr("f", [float(v) for v in flat])
    if new_layout:
        offs, conn = [0], []
        for _, ids in cells:
            conn += ids
            offs.append(len(conn))
        out += b"CELLS %d %d\nOFFSETS vtktypeint64\n" % (len(offs), len(conn))
        out += arr("q", offs)
        out += b"CONNECTIVITY vtktypeint64\n"
        out += arr("q", conn)
    else:
        stream = []
        for _, ids in cells:
            stream += [len(ids)] + ids
        out += b"CELLS %d %d\n" % (len(cells), len(stream))
        out += arr("i", stream)
    out += b"CELL_TYPES %d\n" % len(cells)
    out += arr("i", [vt for vt, _ in cells])
    name = m["scalar_name"] or "s"
    if cell_data:
        vals = []
        for _, ids in cells:
            vs = [m["scalars"][i] for i in ids if 0 <= i < len(m["scalars"])]
            vals.append(sum(vs) / len(vs) if vs else 0.0)
        out += b"CELL_DATA %d\nSCALARS %s float 1\nLOOKUP_TABLE default\n" % (len(cells), name.encode())
        out += arr("f", vals)
    else:
        out += b"POINT_DATA %d\nSCALARS %s float 1\nLOOKUP_TABLE default\n" % (len(m["scalars"]), name.encode())
        out += arr("f", [float(v) for v in m["scalars"]])
    return bytes(out)
