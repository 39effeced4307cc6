#!/usr/bin/python3
"""graded_gmsh.py: strongly graded tet meshes for issue #19, written as VTK XML (.vtu)
with a vertex scalar so tools/clvr-convert can read them.

usage: graded_gmsh.py point|layers OUT.vtu [--scale S] [--uniform H] [--threads T]

  point   box [-1,1]^3 meshed around an embedded centre point with a Distance +
          Threshold size field: edge 0.0005*S at the point (r < 0.005) growing
          linearly to 0.1*S at r = 1 (edge ratio 200, volume ratio ~10^6-10^7).
          Scalar "density": 1 / (1 + (r/0.05)^2) + 0.05, a point source that the
          fine cells resolve.
  layers  boundary-layer-like mesh: a triangulated unit square (edge 0.005*S at
          x = 0 growing to 0.035*S at x = 1) extruded 1 in z through 30 layers in
          geometric progression (ratio 1.5, first layer 2.6e-6 thick); each prism
          is cut into 3 tets by gmsh. Flat cells with aspect ratios up to 10^3-10^4
          at the wall. Scalar "density": a wall jet, exp(-z/0.02) (1 + 0.5 sin 6x).

S (default 1) scales every size; element count goes about as S^-3 (point) and
S^-2 (layers): S = 0.8 gives 0.66M tets (point), S = 1.2 0.86M (layers); --uniform 0.038 (point)
and 0.0174 (layers) give twins of about the same count.
--uniform H meshes the same box with the same scalar field at constant edge H: the
uniform mesh of the same optical depth that issue #19 compares against.
"""
import argparse
import sys

import gmsh
import numpy as np
import vtk
from vtk.util import numpy_support as ns


def mesh_point(scale):
    occ = gmsh.model.occ
    box = occ.addBox(-1, -1, -1, 2, 2, 2)
    p = occ.addPoint(0, 0, 0)
    occ.synchronize()
    gmsh.model.mesh.embed(0, [p], 3, box)
    f = gmsh.model.mesh.field
    d = f.add("Distance")
    f.setNumbers(d, "NodesList" if gmsh.__version__ < "4.9" else "PointsList", [p])
    t = f.add("Threshold")
    f.setNumber(t, "InField", d)
    f.setNumber(t, "SizeMin", 0.0005 * scale)
    f.setNumber(t, "SizeMax", 0.1 * scale)
    f.setNumber(t, "DistMin", 0.005)
    f.setNumber(t, "DistMax", 1.0)
    f.setAsBackgroundMesh(t)
    gmsh.model.mesh.generate(3)


def mesh_layers(scale):
    geo = gmsh.model.geo
    pts = [geo.addPoint(x, y, 0) for x, y in ((0, 0), (1, 0), (1, 1), (0, 1))]
    lines = [geo.addLine(pts[i], pts[(i + 1) % 4]) for i in range(4)]
    s = geo.addPlaneSurface([geo.addCurveLoop(lines)])
    n, ratio = 30, 1.5
    h = ratio ** np.arange(n)
    heights = list(np.cumsum(h) / h.sum())
    geo.extrude([(2, s)], 0, 0, 1, numElements=[1] * n, heights=heights, recombine=False)
    geo.synchronize()
    f = gmsh.model.mesh.field
    m = f.add("MathEval")
    f.setString(m, "F", "%g*(0.005 + 0.03*x)" % scale)
    f.setAsBackgroundMesh(m)
    gmsh.model.mesh.generate(3)


def mesh_uniform(kind, h):
    occ = gmsh.model.occ
    if kind == "point":
        occ.addBox(-1, -1, -1, 2, 2, 2)
    else:
        occ.addBox(0, 0, 0, 1, 1, 1)
    occ.synchronize()
    gmsh.option.setNumber("Mesh.MeshSizeMin", h)
    gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    gmsh.model.mesh.generate(3)


def to_vtu(kind, out):
    tags, coords, _ = gmsh.model.mesh.getNodes()
    xyz = coords.reshape(-1, 3)
    index = np.zeros(int(tags.max()) + 1, dtype=np.int64)
    index[tags.astype(np.int64)] = np.arange(len(tags))
    types, _, nodes = gmsh.model.mesh.getElements(3)
    tets = [np.asarray(nd, dtype=np.int64).reshape(-1, 4) for ty, nd in zip(types, nodes) if ty == 4]
    if not tets:
        sys.exit("graded_gmsh.py: gmsh made no tets")
    tets = index[np.concatenate(tets)]
    used = np.unique(tets)
    remap = np.full(len(xyz), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    xyz = xyz[used]
    tets = remap[tets]
    x, y, z = xyz[:, 0], xyz[:, 1], xyz[:, 2]
    if kind == "point":
        r = np.sqrt(x * x + y * y + z * z)
        dens = 1.0 / (1.0 + (r / 0.05) ** 2) + 0.05
    else:
        dens = np.exp(-z / 0.02) * (1.0 + 0.5 * np.sin(6.0 * x))
    ug = vtk.vtkUnstructuredGrid()
    p = vtk.vtkPoints()
    p.SetData(ns.numpy_to_vtk(xyz.astype(np.float64), deep=True))
    ug.SetPoints(p)
    cells = np.hstack([np.full((len(tets), 1), 4, dtype=np.int64), tets]).ravel()
    ca = vtk.vtkCellArray()
    ca.SetCells(len(tets), ns.numpy_to_vtkIdTypeArray(cells, deep=True))
    ug.SetCells(vtk.VTK_TETRA, ca)
    a = ns.numpy_to_vtk(dens.astype(np.float32), deep=True)
    a.SetName("density")
    ug.GetPointData().AddArray(a)
    ug.GetPointData().SetActiveScalars("density")
    w = vtk.vtkXMLUnstructuredGridWriter()
    w.SetFileName(out)
    w.SetDataModeToAppended()
    w.EncodeAppendedDataOff()
    w.SetInputData(ug)
    if not w.Write():
        sys.exit("graded_gmsh.py: could not write " + out)
    print("graded_gmsh.py: %s: %d tets, %d vertices" % (out, len(tets), len(xyz)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("kind", choices=["point", "layers"])
    ap.add_argument("out")
    ap.add_argument("--scale", type=float, default=1.0)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--uniform", type=float, metavar="H",
                    help="the same domain and scalar field meshed with constant edge H instead")
    a = ap.parse_args()
    gmsh.initialize(["gmsh", "-v", "2"])
    gmsh.option.setNumber("General.NumThreads", a.threads)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.option.setNumber("Mesh.Algorithm3D", 10 if a.threads > 1 else 1)
    gmsh.model.add(a.kind)
    if a.uniform:
        mesh_uniform(a.kind, a.uniform)
    else:
        (mesh_point if a.kind == "point" else mesh_layers)(a.scale)
    to_vtu(a.kind, a.out)
    gmsh.finalize()


if __name__ == "__main__":
    main()
