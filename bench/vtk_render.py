#!/usr/bin/python3
"""vtk_render.py: frame times of VTK's CPU unstructured-grid volume mappers on a
clvr .bin tet mesh, for bench/render-vs-vtk.sh. Run with Debian's /usr/bin/python3
(python3-vtk9) under `xvfb-run -a` (the window is off-screen but VTK's X11 build
still wants a display).

Usage: vtk_render.py MESH.bin --setup CONVERGE.json --json OUT.json [--size WxH]
                     [--mappers raycast,pt,zsweep] [--frames N] [--image-dir DIR]

MESH.bin: docs/bin-format.md. The three mappers take tets only; a mesh with pyramids,
wedges or hexahedra is cut into tets by vtkDataSetTriangleFilter first, as ParaView
does before it volume-renders an unstructured grid (the cut is timed apart, as clvr's
preprocessing is). CONVERGE.json: what `bench_render --converge`
wrote for the same mesh: its camera (eye, target, up, fovy) and its baked transfer
function (linear rgb and extinction per world unit over the scalar range), so both
renderers see the same view and the same medium. Extinction sigma becomes VTK's
per-unit-distance opacity: alpha = 1 - exp(-sigma * u) with ScalarOpacityUnitDistance u.
Colours are sRGB-encoded for VTK, which blends display values.

Timing per mapper: the first Render() (it builds the mapper's structures) is reported
apart; then N frames, each after a 1-degree camera azimuth so that no mapper can reuse
its previous image or sort, timed with wall clock around Render() (these mappers run on
the CPU; vtkUnstructuredGridVolumeRayCastMapper uses every core through vtkMultiThreader;
projected tetrahedra sort on the CPU and rasterise through Mesa's llvmpipe). The median
is the frame time.
"""
import argparse
import json
import os
import struct
import sys
import time

import numpy as np
import vtk
from vtk.util import numpy_support


def read_bin(path):
    """Positions, the scalar clvr renders by default and the cells of a .bin
    (docs/bin-format.md): a list of (VTK cell type, index array) for tets,
    pyramids, wedges and hexahedra. Version 2 (tools/clvr-convert): the point
    field named in the header (its first field), else the first 1-component
    point field."""
    with open(path, "rb") as f:
        head = f.read(256)
        if head[:8] != b"CLVRMESH":
            sys.exit(f"vtk_render.py: {path}: not a clvr .bin mesh")
        version = struct.unpack_from("<I", head, 8)[0]
        nv, nt, npy, nw, nh = struct.unpack_from("<5Q", head, 16)
        pos = np.fromfile(f, dtype="<f4", count=3 * nv).reshape(nv, 3)
        def cells():
            return [(kind, np.fromfile(f, dtype="<u4", count=k * n).reshape(n, k))
                    for kind, k, n in ((vtk.VTK_TETRA, 4, nt), (vtk.VTK_PYRAMID, 5, npy), (vtk.VTK_WEDGE, 6, nw),
                                       (vtk.VTK_HEXAHEDRON, 8, nh))]
        if version == 1:
            sc = np.fromfile(f, dtype="<f4", count=nv)
            return pos, sc, cells()
        if version != 2:
            sys.exit(f"vtk_render.py: {path}: .bin version {version} (1 and 2 are read)")
        lists = cells()
        nf = struct.unpack_from("<I", head, 156)[0]
        want = head[88:152].split(b"\0", 1)[0].decode("utf-8", "replace")
        table = [f.read(128) for _ in range(nf)]
        ne = nt + npy + nw + nh
        sc = None
        first = None
        for e in table:
            name = e[:64].split(b"\0", 1)[0].decode("utf-8", "replace")
            assoc, comps = struct.unpack_from("<2I", e, 64)
            count = nv if assoc == 0 else ne
            data = np.fromfile(f, dtype="<f4", count=count * comps)
            if assoc == 0 and comps == 1:
                if name == want and sc is None:
                    sc = data
                if first is None:
                    first = data
        if sc is None:
            sc = first
        if sc is None:
            sys.exit(f"vtk_render.py: {path}: no 1-component point field to draw (convert with --scalar NAME)")
    return pos, sc, lists


def build_grid(pos, sc, lists):
    """The unstructured grid of the cells; cut into tets (vtkDataSetTriangleFilter,
    ParaView's Tetrahedralize) when it has other cells. Returns the grid of tets
    and the seconds the cut took."""
    pts = vtk.vtkPoints()
    pts.SetData(numpy_support.numpy_to_vtk(np.ascontiguousarray(pos), deep=1))
    types, conns = [], []
    for kind, idx in lists:
        n, k = idx.shape
        if n == 0:
            continue
        types.append(np.full(n, kind, dtype=np.uint8))
        conns.append(np.hstack([np.full((n, 1), k, dtype=np.int64), idx.astype(np.int64)]).ravel())
    n = sum(len(t) for t in types)
    conn = np.concatenate(conns) if conns else np.zeros(0, dtype=np.int64)
    cells = vtk.vtkCellArray()
    cells.SetCells(n, numpy_support.numpy_to_vtkIdTypeArray(conn, deep=1))
    ug = vtk.vtkUnstructuredGrid()
    ug.SetPoints(pts)
    ctypes = numpy_support.numpy_to_vtk(np.concatenate(types) if types else np.zeros(0, dtype=np.uint8), deep=1,
                                        array_type=vtk.VTK_UNSIGNED_CHAR)
    ug.SetCells(ctypes, cells)
    arr = numpy_support.numpy_to_vtk(np.ascontiguousarray(sc), deep=1)
    arr.SetName("scalar")
    ug.GetPointData().SetScalars(arr)
    if all(kind == vtk.VTK_TETRA or idx.shape[0] == 0 for kind, idx in lists):
        return ug, 0.0
    t = time.time()
    cut = vtk.vtkDataSetTriangleFilter()
    cut.TetrahedraOnlyOn()
    cut.SetInputData(ug)
    cut.Update()
    return cut.GetOutput(), time.time() - t


def srgb(c):
    c = max(0.0, min(1.0, c))
    return 12.92 * c if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055


def volume_property(tf, unit):
    lo, hi = tf["range"]
    table = tf["table"]
    n = len(table)
    ctf = vtk.vtkColorTransferFunction()
    otf = vtk.vtkPiecewiseFunction()
    step = max(1, n // 64)
    for i in list(range(0, n, step)) + [n - 1]:
        r, g, b, sigma = table[i]
        x = lo + (hi - lo) * i / (n - 1)
        ctf.AddRGBPoint(x, srgb(r), srgb(g), srgb(b))
        otf.AddPoint(x, 1.0 - np.exp(-sigma * unit))
    prop = vtk.vtkVolumeProperty()
    prop.SetColor(ctf)
    prop.SetScalarOpacity(otf)
    prop.SetScalarOpacityUnitDistance(unit)
    prop.SetInterpolationTypeToLinear()
    prop.ShadeOff()
    return prop


def make_mapper(name):
    if name == "raycast":
        return vtk.vtkUnstructuredGridVolumeRayCastMapper()
    if name == "pt":
        return vtk.vtkProjectedTetrahedraMapper()
    if name == "zsweep":
        return vtk.vtkUnstructuredGridVolumeZSweepMapper()
    sys.exit(f"vtk_render.py: unknown mapper {name}")


FULL = {"raycast": "vtkUnstructuredGridVolumeRayCastMapper", "pt": "vtkProjectedTetrahedraMapper",
        "zsweep": "vtkUnstructuredGridVolumeZSweepMapper"}


def load1():
    try:
        return float(open("/proc/loadavg").read().split()[0])
    except OSError:
        return -1.0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mesh")
    ap.add_argument("--setup", required=True)
    ap.add_argument("--json", required=True)
    ap.add_argument("--size", default="512x512")
    ap.add_argument("--mappers", default="raycast,pt,zsweep")
    ap.add_argument("--frames", type=int, default=3)
    ap.add_argument("--image-dir")
    a = ap.parse_args()
    w, h = (int(v) for v in a.size.split("x"))
    setup = json.load(open(a.setup))
    t0 = time.time()
    pos, sc, lists = read_bin(a.mesh)
    ug, cut_s = build_grid(pos, sc, lists)
    build_s = time.time() - t0 - cut_s
    ncells = sum(idx.shape[0] for _, idx in lists)
    ntets = ug.GetNumberOfCells()
    cut_note = (f"{ncells} cells cut into {ntets} tets by vtkDataSetTriangleFilter in {cut_s:.2f} s"
                if cut_s > 0.0 else f"{ntets} tets")
    lo, hi = pos.min(axis=0), pos.max(axis=0)
    diag = float(np.linalg.norm(hi - lo))
    prop = volume_property(setup["tf"], diag / 256.0)
    cam_j = setup["camera"]
    bg = (0.05, 0.05, 0.07)
    print(f"# vtk_render: {os.path.basename(a.mesh)}, {cut_note}, "
          f"{w}x{h}, VTK {vtk.vtkVersion.GetVTKVersion()}, .bin read and grid built in {build_s:.2f} s", flush=True)
    print("| mapper | first frame (s) | median frame (s) | frames | load |\n|---|---:|---:|---:|---:|", flush=True)
    rows = []
    for name in a.mappers.split(","):
        mapper = make_mapper(name)
        mapper.SetInputData(ug)
        vol = vtk.vtkVolume()
        vol.SetMapper(mapper)
        vol.SetProperty(prop)
        ren = vtk.vtkRenderer()
        ren.SetBackground(*bg)
        ren.AddVolume(vol)
        win = vtk.vtkRenderWindow()
        win.SetOffScreenRendering(1)
        win.SetSize(w, h)
        win.AddRenderer(ren)
        cam = ren.GetActiveCamera()
        cam.SetPosition(*cam_j["eye"])
        cam.SetFocalPoint(*cam_j["target"])
        cam.SetViewUp(*cam_j["up"])
        cam.SetViewAngle(cam_j["fovy"])
        ren.ResetCameraClippingRange()
        load_before = load1()
        t = time.time()
        win.Render()
        first = time.time() - t
        times = []
        for _ in range(a.frames):
            cam.Azimuth(1.0)
            ren.ResetCameraClippingRange()
            t = time.time()
            win.Render()
            times.append(time.time() - t)
        med = float(np.median(times))
        row = {"mapper": FULL[name], "short": name, "first_frame_s": first, "frame_s": med, "frames_s": times,
               "load_before": load_before, "load_after": load1()}
        if a.image_dir:
            os.makedirs(a.image_dir, exist_ok=True)
            w2i = vtk.vtkWindowToImageFilter()
            w2i.SetInput(win)
            w2i.Update()
            png = vtk.vtkPNGWriter()
            png.SetFileName(os.path.join(a.image_dir, f"vtk-{name}.png"))
            png.SetInputConnection(w2i.GetOutputPort())
            png.Write()
        print(f"| {FULL[name]} | {first:.2f} | {med:.2f} | {len(times)} | {row['load_after']:.2f} |", flush=True)
        rows.append(row)
        win.Finalize()
        del win, ren, vol, mapper
    json.dump({"bench": "vtk_render", "mesh": a.mesh, "tets": int(ntets), "cells": int(ncells),
               "tetrahedralize_s": cut_s, "width": w, "height": h, "vtk": vtk.vtkVersion.GetVTKVersion(),
               "grid_build_s": build_s, "rows": rows}, open(a.json, "w"), indent=1)


if __name__ == "__main__":
    main()
