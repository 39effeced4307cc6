#!/usr/bin/python3
"""graded_twin.py: a uniform twin of a real graded mesh for issue #19, written as VTK
XML (.vtu) for tools/clvr-convert.

usage: graded_twin.py IN OUT.vtu --elements N [--cells tets|hexes] [--scalar NAME]

IN is the graded mesh as its solver wrote it (a .vtk or .vtu unstructured grid, e.g.
foamToVTK's output). The twin is a lattice of cubes over IN's bounding box, each cube a
hexahedron or 6 Kuhn tets, keeping only the cubes whose 8 corners lie inside IN's cells,
so it covers IN's domain less a layer of at most one cube along its boundary. Its vertex
scalar is IN's field probed at the corners (vtkProbeFilter; a cell field is first
averaged to the vertices, as clvr-convert does), so the same transfer function gives
the same optical depth up to the twin's interpolation. The cube edge is chosen for about
N cells: a first probe on a coarse lattice measures the fraction of the box IN covers,
a second lattice is sized from it and a third corrects the count when the second missed
it by more than 3%.

Issue #19 compares samples and null collisions per ray on each graded mesh with a
uniform mesh of the same element count at the same optical depth; for an OpenFOAM case
no generator knows the field, so it is sampled from the solver's own mesh.
"""
import argparse
import sys

import numpy as np
import vtk
from vtk.util import numpy_support as ns


def fail(msg):
    print("graded_twin.py: " + msg, file=sys.stderr)
    sys.exit(1)


def read(path):
    if path.endswith(".vtu"):
        r = vtk.vtkXMLUnstructuredGridReader()
    elif path.endswith(".vtk"):
        r = vtk.vtkUnstructuredGridReader()
        r.ReadAllScalarsOn()
    else:
        fail("%s: expected a .vtk or .vtu unstructured grid" % path)
    r.SetFileName(path)
    r.Update()
    ug = r.GetOutput()
    if ug is None or ug.GetNumberOfCells() == 0:
        fail("%s: no cells read (not an unstructured grid?)" % path)
    return ug


def with_point_scalar(ug, name, path):
    if ug.GetPointData().GetArray(name) is not None:
        return ug
    if ug.GetCellData().GetArray(name) is None:
        fail("%s: no point or cell array named '%s' (--scalar)" % (path, name))
    c2p = vtk.vtkCellDataToPointData()
    c2p.SetInputData(ug)
    c2p.Update()
    return c2p.GetOutput()


def probe(src, lo, h, dims, name):
    """IN's scalar and validity at the lattice points lo + h (i, j, k), x fastest."""
    img = vtk.vtkImageData()
    img.SetOrigin(*lo)
    img.SetSpacing(h, h, h)
    img.SetDimensions(*dims)
    p = vtk.vtkProbeFilter()
    p.SetInputData(img)
    p.SetSourceData(src)
    p.Update()
    out = p.GetOutput()
    valid = ns.vtk_to_numpy(out.GetPointData().GetArray(p.GetValidPointMaskArrayName())).astype(bool)
    vals = ns.vtk_to_numpy(out.GetPointData().GetArray(name)).astype(np.float32)
    return valid.reshape(dims[2], dims[1], dims[0]), vals.reshape(dims[2], dims[1], dims[0])


def lattice(lo, hi, h):
    dims = [max(2, int(np.ceil((hi[k] - lo[k]) / h)) + 1) for k in range(3)]
    return dims


def kept_cubes(valid):
    """Cubes (k, j, i of their lowest corner) whose 8 corners are all valid."""
    v = valid
    m = (v[:-1, :-1, :-1] & v[:-1, :-1, 1:] & v[:-1, 1:, :-1] & v[:-1, 1:, 1:] &
         v[1:, :-1, :-1] & v[1:, :-1, 1:] & v[1:, 1:, :-1] & v[1:, 1:, 1:])
    return m


# A cube's corners as (dx, dy, dz) in VTK's hexahedron order.
CORNERS = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]


def kuhn_tets():
    """The 6 tets of a cube along its 0-6 diagonal (corner indices as in CORNERS), each
    with positive volume: the same pattern in every cube, so the tets are conforming."""
    idx = {c: i for i, c in enumerate(CORNERS)}
    tets = []
    for a, b, _ in ((0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)):
        p0 = (0, 0, 0)
        p1 = tuple(1 if k == a else 0 for k in range(3))
        p2 = tuple(1 if k in (a, b) else 0 for k in range(3))
        t = [idx[p0], idx[p1], idx[p2], idx[(1, 1, 1)]]
        q = np.array([CORNERS[i] for i in t], float)
        if np.linalg.det(q[1:] - q[0]) < 0:
            t[1], t[2] = t[2], t[1]
        tets.append(t)
    return tets


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("input")
    ap.add_argument("output")
    ap.add_argument("--elements", type=int, required=True, help="about this many cells")
    ap.add_argument("--cells", choices=("tets", "hexes"), default="tets")
    ap.add_argument("--scalar", default="T", help="the field to probe (default T)")
    a = ap.parse_args()
    if a.elements < 6:
        fail("--elements %d: at least 6" % a.elements)
    if not a.output.endswith(".vtu"):
        fail("%s: the output is a .vtu file" % a.output)
    src = with_point_scalar(read(a.input), a.scalar, a.input)
    b = src.GetBounds()
    lo, hi = np.array(b[0::2]), np.array(b[1::2])
    vol = float(np.prod(hi - lo))
    if not vol > 0:
        fail("%s: the bounding box is flat (%s .. %s)" % (a.input, lo, hi))
    per_cube = 6 if a.cells == "tets" else 1
    # Cube edge for N cells if the mesh filled a fraction f of its box.
    edge = lambda f: (f * vol * per_cube / a.elements) ** (1.0 / 3.0)
    h = edge(1.0) * 2.0  # coarse: 1/8 of the cubes, to measure the fraction
    for attempt in range(3):
        dims = lattice(lo, hi, h)
        valid, vals = probe(src, lo, h, dims, a.scalar)
        keep = kept_cubes(valid)
        n = int(keep.sum()) * per_cube
        if n == 0:
            fail("no cube of edge %g lies inside %s: is it a volume mesh?" % (h, a.input))
        if attempt == 2 or (attempt > 0 and abs(n - a.elements) <= 0.03 * a.elements):
            break
        f = keep.sum() * h ** 3 / vol
        h = edge(f)
    print("graded_twin.py: %d %s (asked %d), cube edge %.5g, %.3f of the box, lattice %s" %
          (n, a.cells, a.elements, h, keep.sum() * h ** 3 / vol, "x".join(map(str, dims))), file=sys.stderr)

    # Keep only the corners of kept cubes, renumbered.
    nz, ny, nx = valid.shape
    used = np.zeros_like(valid)
    kz, ky, kx = np.nonzero(keep)
    for dx, dy, dz in CORNERS:
        used[kz + dz, ky + dy, kx + dx] = True
    ids = np.full(valid.shape, -1, np.int64)
    ids[used] = np.arange(int(used.sum()))
    zz, yy, xx = np.nonzero(used)
    pts = np.stack([lo[0] + xx * h, lo[1] + yy * h, lo[2] + zz * h], axis=1).astype(np.float32)
    corner = np.stack([ids[kz + dz, ky + dy, kx + dx] for dx, dy, dz in CORNERS], axis=1)
    if a.cells == "hexes":
        conn, vtk_type, nv = corner, vtk.VTK_HEXAHEDRON, 8
    else:
        conn = np.concatenate([corner[:, t] for t in kuhn_tets()], axis=0)
        vtk_type, nv = vtk.VTK_TETRA, 4

    ug = vtk.vtkUnstructuredGrid()
    vp = vtk.vtkPoints()
    vp.SetData(ns.numpy_to_vtk(pts, deep=True))
    ug.SetPoints(vp)
    cells = vtk.vtkCellArray()
    offsets = np.arange(0, conn.shape[0] * nv + 1, nv, dtype=np.int64)
    cells.SetData(ns.numpy_to_vtkIdTypeArray(offsets, deep=True),
                  ns.numpy_to_vtkIdTypeArray(conn.reshape(-1).astype(np.int64), deep=True))
    ug.SetCells(vtk_type, cells)
    s = ns.numpy_to_vtk(vals[used].astype(np.float32), deep=True)
    s.SetName(a.scalar)
    ug.GetPointData().AddArray(s)
    w = vtk.vtkXMLUnstructuredGridWriter()
    w.SetFileName(a.output)
    w.SetInputData(ug)
    w.SetDataModeToAppended()
    w.EncodeAppendedDataOff()
    if not w.Write():
        fail("%s: VTK could not write it" % a.output)


if __name__ == "__main__":
    main()
