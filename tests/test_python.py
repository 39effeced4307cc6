#!/usr/bin/python3
"""test_python.py: the clvr Python module (python/clvr over libclvr), run by
ctest with PYTHONPATH=<build>/python (or, from tests/test_install.sh, the
installed copy). Proves:
  - Mesh.from_arrays, Mesh.from_meshio and Mesh.from_vtk of the same mesh
    (tests/data/vtk/fire_ug.vtu, hexahedra, field t) render the same image
    in distribution, and so do Mesh.load of a clvr-gen .bin with every cell
    type and from_arrays / from_meshio of its arrays (per 4x4 block and
    channel, K_SIGMA standard errors from independent batches); the
    comparison has power: another field of the same mesh is told apart;
  - bad inputs raise clvr.InputError (a ValueError) naming the array and
    the fix before any device work: wrong dtype, shape, an index out of
    range or negative, NaN in points or fields, unknown cell types and
    names; a bad device raises clvr.Error (ERR_NO_DEVICE); nothing the
    caller passed is modified (values, dtype, writeable flag);
  - render returns float32 (H, W, 4); save_image writes PNG and EXR through
    the program's writers and reports a bad path;
  - the clvr program and the module write the same pixels for the same
    mesh, defaults and seed (one pipeline, no drift);
  - borrowing: float32 points and fields and uint32 cells that are
    C-contiguous are lent, not copied (libclvr reads the caller's very
    address), other arrays and copy=True are not, and rendering leaves the
    caller's arrays as they were;
  - a file's fields: Mesh.load(path, scalar=...) and `fields` list every
    array of a legacy VTK file with two scalars and a vector, and of its
    clvr-convert .bin (version 2); another field
    named in Renderer(field=...) renders the same pixels as from_arrays of
    that field, and other pixels than the first field;
  - Scene (the separate, timed preprocessing with leaf and sampling sizes)
    and the render settings (get, set, refused with the member's name);
  - API 1.2: every setting's names (as clvr.h lists them) round-trip
    through setting_index, unknown ones raise; default_size; frame_box
    looks at the box's centre from the default direction (turned by the
    azimuth, nearer with zoom) and is the very camera a Renderer's
    automatic framing sets; tf_file_window of a file with and without a
    window; a time series' steps, times and bounds (the union of its
    meshes'), and the errors of a missing or bad series.
Exit 77 (skipped) without numpy/meshio/vtk or an OpenCL device."""
import os
import subprocess
import sys
import tempfile
import warnings

try:
    import numpy as np
    import meshio
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
except ImportError as e:
    print("test_python: %s: skipped (tools/setup-debian.sh test installs python3-numpy, python3-meshio, "
          "python3-vtk9)" % e, file=sys.stderr)
    sys.exit(77)

import clvr

DATA = os.environ.get("CLVR_SHARED_DATA", os.path.join(os.path.dirname(__file__), "data"))
BUILD = os.environ.get("CLVR_BUILD_DIR", "build")
# The device the renders run on (tests/test_device.h: CLVR_TEST_DEVICE, default pocl).
DEVICE = os.environ.get("CLVR_TEST_DEVICE") or "pocl"
# 6 SE, not 5: the variances come from 8 batches (Student-t tails) and 1024
# blocks are compared; the broken cases differ by tens to hundreds of SE.
W, H, BATCHES, FRAMES, K_SIGMA = 32, 32, 8, 4, 6.0
failures = 0


def check(cond, what):
    global failures
    if not cond:
        failures += 1
        print("FAILED: %s" % what, file=sys.stderr)


def raises(fn, exc, part, what):
    try:
        fn()
    except exc as e:
        check(part in str(e), "%s: message %r lacks %r" % (what, str(e), part))
        return e
    except Exception as e:  # noqa: BLE001 - a wrong exception type is a failure
        check(False, "%s: raised %s(%s), expected %s" % (what, type(e).__name__, e, exc.__name__))
        return None
    check(False, "%s: did not raise" % what)
    return None


def batches(r, base):
    """Mean image and variance of the mean over BATCHES independent batches."""
    imgs = np.stack([r.render(spp=FRAMES, seed=base + b) for b in range(BATCHES)]).astype(np.float64)
    return imgs.mean(0), imgs.var(0, ddof=1) / BATCHES


def differing_blocks(a, b, what):
    (ma, va), (mb, vb) = a, b
    d = (ma - mb).reshape(H // 4, 4, W // 4, 4, 4).sum((1, 3))
    v = (va + vb).reshape(H // 4, 4, W // 4, 4, 4).sum((1, 3))
    se = np.sqrt(v)
    bad = np.abs(d) > K_SIGMA * se + 1e-4
    z = np.where(se > 0, np.abs(d) / np.maximum(se, 1e-30), 0)
    print("  %s: %d of %d blocks differ by more than %g SE (worst %.1f SE)"
          % (what, bad.sum(), bad.size, K_SIGMA, z.max()), file=sys.stderr)
    return int(bad.sum())


def render_stats(mesh, ctx, field, base):
    r = clvr.Renderer(mesh, device=ctx, width=W, height=H, field=field)
    img = r.render(spp=1)
    check(img.dtype == np.float32 and img.shape == (H, W, 4), "render returns float32 (H, W, 4), got %s %s"
          % (img.dtype, img.shape))
    out = batches(r, base)
    r.close()
    return out


def same_pixels(x, y, ctx, field, what):
    """x and y hold the same arrays: with one seed their images are the same
    pixels (a statistical comparison would let a 10% bias through here)."""
    imgs = []
    for mesh in (x, y):
        r = clvr.Renderer(mesh, device=ctx, width=W, height=H, field=field)
        imgs.append(r.render(spp=4, seed=11))
        r.close()
    d = float(np.abs(imgs[0] - imgs[1]).max())
    print("  %s, same seed: largest difference %g" % (what, d), file=sys.stderr)
    return d == 0.0


def read_vtk(path):
    rd = vtkXMLUnstructuredGridReader()
    rd.SetFileName(path)
    rd.Update()
    return rd.GetOutput()


def read_bin(path):
    """A .bin by hand (docs/bin-format.md), not through clvr."""
    raw = open(path, "rb").read()
    nv, nt, npy, nw, nh = (int(x) for x in np.frombuffer(raw, "<u8", 5, 16))
    off = 256
    xyz = np.frombuffer(raw, "<f4", 3 * nv, off).reshape(-1, 3)
    off += 12 * int(nv)
    s = np.frombuffer(raw, "<f4", nv, off)
    off += 4 * int(nv)
    cells = {}
    for name, n, k in (("tetra", nt, 4), ("pyramid", npy, 5), ("wedge", nw, 6), ("hexahedron", nh, 8)):
        cells[name] = np.frombuffer(raw, "<u4", int(n) * k, off).reshape(-1, k)
        off += 4 * k * int(n)
    return xyz, cells, s


def test_same_image(ctx):
    fire = os.path.join(DATA, "vtk", "fire_ug.vtu")
    m = meshio.read(fire)
    pts, hexes, t = m.points.copy(), m.cells_dict["hexahedron"].copy(), m.point_data["t"].copy()
    a = clvr.Mesh.from_arrays(m.points, {"hexahedron": m.cells_dict["hexahedron"]}, {"t": m.point_data["t"]})
    b = clvr.Mesh.from_meshio(m)
    c = clvr.Mesh.from_vtk(read_vtk(fire))
    check(np.array_equal(m.points, pts) and np.array_equal(m.cells_dict["hexahedron"], hexes)
          and np.array_equal(m.point_data["t"], t), "from_arrays/from_meshio modified the caller's arrays")
    check(a.num_points == 12323 and a.num_cells["hexahedron"] == 10462, "fire counts: %r" % a)
    check({"t", "u", "v", "w", "mfrac"} <= set(b.field_names) and "uvw" not in b.field_names,
          "from_meshio keeps the scalar fields only: %s" % b.field_names)
    check(set(b.field_names) == set(c.field_names), "from_vtk fields %s vs from_meshio %s"
          % (c.field_names, b.field_names))
    lo, hi = a.bounds
    check(np.allclose(lo, m.points.min(0), atol=1e-5) and np.allclose(hi, m.points.max(0), atol=1e-5), "bounds")
    sa = render_stats(a, ctx, "t", 100)
    sb = render_stats(b, ctx, "t", 200)
    sc = render_stats(c, ctx, "t", 300)
    su = render_stats(b, ctx, "mfrac", 400)
    print("test_python: fire_ug.vtu:", file=sys.stderr)
    check(differing_blocks(sa, sb, "from_arrays vs from_meshio") == 0, "from_arrays and from_meshio differ")
    check(same_pixels(a, b, ctx, "t", "from_arrays vs from_meshio"), "from_arrays and from_meshio: other pixels")
    check(differing_blocks(sa, sc, "from_arrays vs from_vtk") == 0, "from_arrays and from_vtk differ")
    check(differing_blocks(sa, su, "field t vs field mfrac (must differ)") > 5, "the comparison has no power")
    check(sa[0][..., 3].max() > 0.1, "the fire image is empty")

    # Every cell type: a clvr-gen .bin through libclvr's reader and its arrays.
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "mixed.bin")
        subprocess.run([os.path.join(BUILD, "clvr-gen"), "mixed", path, "--elements", "3000", "--seed", "5",
                        "--quiet"], check=True)
        xyz, cells, s = read_bin(path)
        check(all(len(v) for v in cells.values()), "clvr-gen mixed has every type")
        loaded = clvr.Mesh.load(path)
        arrays = clvr.Mesh.from_arrays(xyz, cells, {"scalar": s})
        mio = clvr.Mesh.from_meshio(meshio.Mesh(xyz, [(k, v) for k, v in cells.items()], point_data={"s": s}))
    sl = render_stats(loaded, ctx, None, 500)
    sa = render_stats(arrays, ctx, None, 600)
    sm = render_stats(mio, ctx, None, 700)
    print("test_python: clvr-gen mixed:", file=sys.stderr)
    check(differing_blocks(sl, sa, "load(.bin) vs from_arrays") == 0, ".bin and from_arrays differ")
    check(differing_blocks(sl, sm, "load(.bin) vs from_meshio") == 0, ".bin and from_meshio differ")
    check(same_pixels(loaded, arrays, ctx, None, "load(.bin) vs from_arrays"), ".bin and from_arrays: other pixels")
    check(same_pixels(loaded, mio, ctx, None, "load(.bin) vs from_meshio"), ".bin and from_meshio: other pixels")


def test_program_matches_module(ctx):
    """The clvr program and the module share one pipeline: with the same
    defaults, seed and device they write the same pixels (a drift of any
    default, camera, transfer function or setting shows here)."""
    vtk = os.path.join(DATA, "vtk", "notch_stress.vtk")
    with tempfile.TemporaryDirectory() as tmp:
        pfm = os.path.join(tmp, "cli.pfm")
        subprocess.run([os.path.join(BUILD, "clvr"), vtk, "--device", DEVICE, "--size", "40x32", "--spp", "4",
                        "--seed", "7", "--quiet", "-o", pfm], check=True)
        raw = open(pfm, "rb").read()
    magic, size, scale, data = raw.split(b"\n", 3)
    w, h = (int(x) for x in size.split())
    cli = np.frombuffer(data, "<f4").reshape(h, w, 3)[::-1]  # PFM rows run bottom to top
    r = clvr.Renderer(clvr.Mesh.load(vtk), device=ctx, width=40, height=32)
    img = r.render(spp=4, seed=7)
    d = np.abs(img[..., :3] - cli).max()
    print("test_python: clvr program vs module, same seed: largest difference %g" % d, file=sys.stderr)
    check(d <= 1e-6 and cli.mean() > 0.01, "the program and the module render differently (%g)" % d)


def test_bad_inputs(ctx):
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float64)
    tet = np.array([[0, 1, 2, 3]], np.int64)
    f = np.array([0.0, 1.0, 2.0, 3.0])
    keep = [x.copy() for x in (pts, tet, f)]
    mk = clvr.Mesh.from_arrays
    E = clvr.InputError
    raises(lambda: mk(pts.astype(str), {"tetra": tet}, {"f": f}), E, "dtype", "string points")
    raises(lambda: mk(pts.astype(complex), {"tetra": tet}, {"f": f}), E, "dtype", "complex points")
    raises(lambda: mk(pts[:, :2], {"tetra": tet}, {"f": f}), E, "(N, 3)", "points of shape (4, 2)")
    raises(lambda: mk(pts, {"tetra": tet.astype(float)}, {"f": f}), E, "integers", "float indices")
    raises(lambda: mk(pts, {"tetra": tet[:, :3]}, {"f": f}), E, "(M, 4)", "3 indices per tetra")
    raises(lambda: mk(pts, {"tetra": tet + 1}, {"f": f}), E, "is 4 but there are 4 points", "index out of range")
    raises(lambda: mk(pts, {"tetra": tet - 1}, {"f": f}), E, "[0, 0] is -1", "negative index")
    raises(lambda: mk(pts, {"tet": tet}, {"f": f}), E, "hexahedron", "unknown cell type")
    raises(lambda: mk(pts, {"tetra": tet[:0]}, {"f": f}), E, "no cells", "no cells")
    raises(lambda: mk(pts, {"tetra": tet}, {}), E, "point_data", "no field")
    raises(lambda: mk(pts, {"tetra": tet}, {"f": f[:3]}), E, "(4,)", "short field")
    bad = pts.copy()
    bad[2, 1] = np.nan
    raises(lambda: mk(bad, {"tetra": tet}, {"f": f}), E, "points[2, 1]", "NaN point")
    raises(lambda: mk(pts * 1e39, {"tetra": tet}, {"f": f}), E, "float32", "points overflowing float32")
    badf = f.copy()
    badf[3] = np.inf
    e = raises(lambda: mk(pts, {"tetra": tet}, {"f": badf}), E, "point_data['f'][3]", "infinite field")
    check(e is None or e.result == "ERR_BAD_VALUE", "NaN's result name")
    check(isinstance(e, ValueError), "InputError is a ValueError")
    pairs = mk(pts, [("tetra", tet), ("tetra", tet)], {"f": f})  # meshio's list of (type, array)
    check(pairs.num_cells["tetra"] == 2 and pairs.field_names == ["f"], "cells as (type, array) pairs: %r" % pairs)
    raises(lambda: mk(pts, [tet], {"f": f}), E, "pairs", "cells list without types")
    ro = pts.copy()
    ro.flags.writeable = False
    good = mk(ro, {"tetra": tet}, {"f": f})
    check(not ro.flags.writeable, "writeable flag changed")
    check(all(np.array_equal(a, b) and a.dtype == b.dtype for a, b in zip(keep, (pts, tet, f))),
          "inputs were modified")
    raises(lambda: clvr.Renderer(good, device=ctx, width=8, height=8, field="nope"), E, "'f'", "unknown field")
    raises(lambda: clvr.Renderer(good, device=ctx, width=0, height=8), E, "width", "width 0")
    raises(lambda: clvr.Renderer("mesh.vtu", device=ctx), E, "clvr.Mesh", "not a Mesh")
    e = raises(lambda: clvr.Context("no-such-device-xyz"), clvr.Error, "no-such-device-xyz", "bad device")
    check(e is None or e.result == "ERR_NO_DEVICE", "bad device's result name: %s" % getattr(e, "result", None))
    raises(lambda: clvr.Mesh.load(os.path.join(DATA, "nope.bin")), clvr.Error, "nope.bin", "missing file")
    r = clvr.Renderer(good, device=ctx, width=8, height=8)
    raises(lambda: r.render(spp=1, camera={"eye": (1, 1, 1)}), E, "target", "eye without target")
    raises(lambda: r.render(spp=1, camera={"azimut": 3}), E, "azimut", "camera typo")
    raises(lambda: r.render(spp=1, camera={"eye": (1, 1, 1), "target": (1, 1, 1)}), E, "", "eye == target")
    raises(lambda: r.render(spp=1, tf="rainbow"), E, "viridis", "unknown colour map")
    raises(lambda: r.render(spp=1, method="magic"), E, "dda", "unknown method")
    raises(lambda: r.render(spp=0), E, "spp", "spp 0")
    raises(lambda: r.stat("speed"), E, "frames", "unknown stat")
    img = r.render(spp=2, camera={"eye": (2, 2, 3), "target": (0.3, 0.3, 0.3)}, tf={"colormap": "viridis",
                   "range": (0, 3), "density": 2.0}, light={"direction": (1, 1, 1), "shadows": False},
                   background=(0, 0, 0), method="track", estimator="delta")
    check(r.stat("frames") == 2 and img.shape == (8, 8, 4), "settings then frames")
    img2 = r.render(spp=2, accumulate=True)
    check(r.stat("frames") == 4 and np.isfinite(img2).all(), "accumulate adds frames")
    r.render(spp=1, tf={"table": np.array([[0, 0, 0, 0], [1, 1, 1, 1]]), "range": (0, 3)})
    check(r.stats["frames"] == 1, "stats dict")
    with tempfile.TemporaryDirectory() as tmp:
        for ext in ("png", "exr"):
            p = os.path.join(tmp, "x." + ext)
            clvr.save_image(p, img)
            check(os.path.getsize(p) > 0, "save_image " + ext)
        raises(lambda: clvr.save_image(os.path.join(tmp, "no", "x.png"), img), clvr.Error, "x.png", "bad dir")
        raises(lambda: clvr.save_image(os.path.join(tmp, "x.jpg"), img), E, "x.jpg", "bad extension")
        raises(lambda: clvr.save_image(os.path.join(tmp, "x.png"), img[..., :3]), E, "(height, width, 4)", "RGB")
    r.close()


def test_borrowing(ctx):
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], np.float32)
    tets = np.array([[0, 1, 2, 3], [1, 2, 3, 4]], np.uint32)
    f = np.array([0.0, 1.0, 2.0, 3.0, 4.0], np.float32)
    keep = [x.copy() for x in (pts, tets, f)]
    m = clvr.Mesh.from_arrays(pts, {"tetra": tets}, {"f": f})
    for name, a in (("points", pts), ("tetra", tets), ("f", f)):
        check(m.borrowed(name) and m.array_address(name) == a.ctypes.data, "%s lent, not copied" % name)
    r = clvr.Renderer(m, device=ctx, width=8, height=8)
    r.render(spp=2)
    check(all(np.array_equal(a, b) and a.dtype == b.dtype for a, b in zip(keep, (pts, tets, f))),
          "borrowed arrays modified by rendering")
    m.close()  # the renderer keeps the mesh's arrays (and libclvr's dataset) alive
    check(np.isfinite(r.render(spp=1)).all(), "render after Mesh.close")
    r.close()
    conv = clvr.Mesh.from_arrays(pts.astype(np.float64), {"tetra": tets.astype(np.int64)}, {"f": f[::1]})
    check(conv.array_address("points") != pts.ctypes.data, "a float64 array is converted, not lent")
    check(conv.borrowed("f") and conv.array_address("f") == f.ctypes.data, "a float32 field is lent")
    strided = np.ascontiguousarray(np.repeat(f, 2))[::2]
    sm = clvr.Mesh.from_arrays(pts, {"tetra": tets}, {"f": strided})
    check(sm.array_address("f") != strided.ctypes.data, "a strided field is copied")
    cp = clvr.Mesh.from_arrays(pts, {"tetra": tets}, {"f": f}, copy=True)
    check(not cp.borrowed("points") and not cp.borrowed("tetra") and not cp.borrowed("f"), "copy=True copies")
    check(cp.array_address("points") != pts.ctypes.data, "copy=True: another address")


def _write_hex_vtk(path, title, pts, hexes, scalars, vectors=None):
    """Legacy VTK hexahedra with point fields: scalars {name: values}, vectors {name: rows}."""
    with open(path, "w") as fh:
        fh.write("# vtk DataFile Version 3.0\n%s\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS %d float\n"
                 % (title, len(pts)))
        fh.writelines("%.9g %.9g %.9g\n" % tuple(p) for p in pts)
        fh.write("CELLS %d %d\n" % (len(hexes), 9 * len(hexes)))
        fh.writelines("8 " + " ".join(map(str, h)) + "\n" for h in hexes)
        fh.write("CELL_TYPES %d\n" % len(hexes) + "12\n" * len(hexes))
        fh.write("POINT_DATA %d\n" % len(pts))
        for name, values in scalars.items():
            fh.write("SCALARS %s float\nLOOKUP_TABLE default\n" % name)
            fh.writelines("%.9g\n" % v for v in values)
        for name, rows in (vectors or {}).items():
            fh.write("VECTORS %s float\n" % name)
            fh.writelines("%.9g %.9g %.9g\n" % tuple(r) for r in rows)


def _write_fields_vtk(path, n=6):
    g = np.linspace(0.0, 1.0, n + 1)
    z, y, x = np.meshgrid(g, g, g, indexing="ij")
    pts = np.stack([x.ravel(), y.ravel(), z.ravel()], 1).astype(np.float32)
    idx = np.arange((n + 1) ** 3).reshape(n + 1, n + 1, n + 1)  # [k, j, i]
    c = idx[:-1, :-1, :-1].ravel()
    di, dj, dk = 1, n + 1, (n + 1) ** 2
    hexes = np.stack([c, c + di, c + di + dj, c + dj, c + dk, c + di + dk, c + di + dj + dk, c + dj + dk],
                     1).astype(np.uint32)
    a = pts[:, 0].copy()
    b = (4.0 * (pts[:, 1] - 0.5) ** 2).astype(np.float32)
    _write_hex_vtk(path, "fields", pts, hexes, {"a": a, "b": b}, {"v": [(p[2], 0.5, -p[0]) for p in pts]})
    return pts, hexes, a, b


def test_fields(ctx):
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "fields.vtk")
        pts, hexes, a, b = _write_fields_vtk(path)
        m = clvr.Mesh.load(path, field_ranges=True)
        names = [(f["name"], f["components"], f["loaded"]) for f in m.fields]
        check(names == [("a", 1, True), ("b", 1, False), ("v", 3, False)], "fields of the file: %r" % names)
        check(m.fields[1]["range"] is not None and abs(m.fields[1]["range"][1] - 1.0) < 1e-6, "b's range decoded")
        check(abs(m.field_range("b")[1] - 1.0) < 1e-6, "field_range of a field not read yet")
        mb = clvr.Mesh.load(path, scalar="b")
        check(mb.fields[1]["loaded"] and not mb.fields[0]["loaded"], "scalar='b' loads b first")
        arrays = clvr.Mesh.from_arrays(pts, {"hexahedron": hexes}, {"a": a, "b": b})
        tf = {"colormap": "viridis", "range": (0.0, 1.0), "density": 1.0, "ramp": True}
        imgs = {}
        for key, mesh, field in (("file b", m, "b"), ("arrays b", arrays, "b"), ("file a", m, "a"),
                                 ("load b", mb, None)):
            with clvr.Renderer(mesh, device=ctx, width=24, height=20, field=field) as r:
                imgs[key] = r.render(spp=4, tf=tf, seed=7)
        check(np.array_equal(imgs["file b"], imgs["arrays b"]), "field b from the file == from arrays")
        check(np.array_equal(imgs["load b"], imgs["arrays b"]), "Mesh.load(scalar='b') renders b")
        check(np.abs(imgs["file b"] - imgs["file a"]).mean() > 1e-3, "field a renders other pixels")
        check(m.fields[1]["loaded"], "b in memory after rendering it")
        raises(lambda: clvr.Renderer(m, device=ctx, width=8, height=8, field="nope"), clvr.InputError, "nope",
               "unknown field of a file")
        # The same file as a clvr .bin version 2 (clvr-convert keeps every array).
        conv = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools", "clvr-convert")
        binpath = os.path.join(tmp, "fields.bin")
        cp = subprocess.run([sys.executable, conv, "--quiet", path, binpath], capture_output=True, text=True)
        check(cp.returncode == 0, "clvr-convert: %s" % cp.stderr[-300:])
        if cp.returncode == 0:
            mbin = clvr.Mesh.load(binpath)
            check([f["name"] for f in mbin.fields] == ["a", "b", "v"], ".bin v2 fields: %r" % mbin.fields)
            with clvr.Renderer(mbin, device=ctx, width=24, height=20, field="b") as r:
                check(np.array_equal(r.render(spp=4, tf=tf, seed=7), imgs["arrays b"]), ".bin field b == arrays b")


def test_scene_settings(ctx):
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], np.float32)
    tets = np.array([[0, 1, 2, 3], [1, 2, 3, 4]], np.uint32)
    m = clvr.Mesh.from_arrays(pts, {"tetra": tets}, {"f": np.arange(5, dtype=np.float32)})
    sc = clvr.Scene(m, device=ctx, leaf_size=1, sampling_size=1)
    st = sc.stats
    check(st["leaf_size"] == 1 and st["leaves"] == 2 and st["elements"] == 2, "scene stats %r" % st)
    check(st["preprocess_s"] > 0 and list(st["stages"])[-2:] == ["bvh", "hull"], "preprocessing timed per stage")
    r1 = clvr.Renderer(sc, width=8, height=8, method="track", estimator="delta", seed=5)
    r2 = clvr.Renderer(sc, width=8, height=8)
    r2.set_settings(method="track", estimator="delta", seed=5)
    check(r1.settings == r2.settings, "settings at creation == set_settings")
    check(np.array_equal(r1.render(spp=2), r2.render(spp=2)), "two renderers on one scene, same pixels")
    raises(lambda: r1.set_settings(bins=99), clvr.InputError, "bins", "bins 99")
    raises(lambda: r1.set_settings(metod="dda"), clvr.InputError, "metod", "settings typo")
    check(r1.settings["bins"] != 99 and r1.settings["method"] == "track", "refused settings change nothing")
    r1.set_settings(clip_lo=(0, 0, 0), clip_hi=(0.5, 0.5, 0.5))
    check(r1.settings["clip_box"] and r1.settings["clip_hi"] == (0.5, 0.5, 0.5), "clip box set")
    raises(lambda: clvr.Scene(m, device=ctx, leaf_size=0), clvr.InputError, "leaf_size", "leaf_size 0")
    # one_curve (API 1.10): a hex and a tet on one curve, the tet stored as a
    # collapsed hex (auto: 16 index slots instead of 12, under 1.5x), or a
    # curve each.
    hp = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1], [0, 0, 2]],
                  np.float32)
    mixed = clvr.Mesh.from_arrays(hp, {"hexahedron": np.arange(8, dtype=np.uint32).reshape(1, 8),
                                       "tetra": np.array([[4, 5, 7, 8]], np.uint32)},
                                  {"f": np.arange(9, dtype=np.float32)})
    by = {oc: clvr.Scene(mixed, device=ctx, one_curve=oc).stats for oc in ("auto", "on", "off")}
    check(by["auto"]["collapsed_cells"] == (1, 0, 0, 0) and by["on"]["collapsed_cells"] == (1, 0, 0, 0)
          and by["off"]["collapsed_cells"] == (0, 0, 0, 0), "one_curve: collapsed cells %r" % by)
    check(by["on"]["instances"] == 1 and by["off"]["instances"] == 2, "one_curve: instances %r" % by)
    raises(lambda: clvr.Scene(mixed, device=ctx, one_curve="sometimes"), clvr.InputError, "sometimes",
           "one_curve sometimes")
    # Whole-number settings go through one check: no bools, nothing a
    # ctypes field would wrap silently (seed is 64-bit, the others 32).
    raises(lambda: clvr.Scene(m, device=ctx, leaf_size=True), clvr.InputError, "leaf_size", "leaf_size True")
    raises(lambda: clvr.Scene(m, device=ctx, partitions=2 ** 32), clvr.InputError, "partitions", "partitions 2^32")
    raises(lambda: r1.set_settings(macrocells=2 ** 32 + 32), clvr.InputError, "macrocells",
           "macrocells 2^32 + 32 (would wrap to 32)")
    raises(lambda: r1.set_settings(urm_steps=True), clvr.InputError, "urm_steps", "urm_steps True")
    raises(lambda: r1.set_settings(seed=2 ** 64), clvr.InputError, "seed", "seed 2^64")
    r1.set_settings(seed=2 ** 40 + 7)
    check(r1.settings["seed"] == 2 ** 40 + 7, "a 64-bit seed is kept whole: %r" % r1.settings["seed"])
    # The pixel filter (API 1.3, its own call under the settings dict).
    check(r1.settings["pixel_filter"] == "box", "box filter by default")
    raises(lambda: r1.set_settings(pixel_filter="gauss", bins=8), clvr.InputError, "gauss", "pixel_filter gauss")
    check(r1.settings["pixel_filter"] == "box" and r1.settings["bins"] != 8, "a refused filter changes nothing")
    r3 = clvr.Renderer(sc, width=8, height=8, method="track", estimator="delta", seed=5, pixel_filter="point")
    r1.set_settings(pixel_filter="point")
    check(r3.settings["pixel_filter"] == "point" and r1.settings["pixel_filter"] == "point", "point filter set")
    # Adaptive sampling (API 1.7): 0.1 by default, 0 off, a negative threshold refused.
    check(abs(r1.settings["adaptive"] - 0.1) < 1e-6, "adaptive sampling at 0.1 by default")
    r1.set_settings(adaptive=0)
    check(r1.settings["adaptive"] == 0.0, "adaptive sampling off")
    raises(lambda: r1.set_settings(adaptive=-1), clvr.InputError, "threshold", "adaptive -1")
    r1.set_settings(adaptive=0.1)
    # The denoiser (API 1.4): off by default, the denoised image refused without its guides, then a smoother image
    # of the same frames.
    check(r1.settings["denoise"] is False, "no denoiser guides by default")
    r1.render(spp=1)
    raises(lambda: r1.image(denoised=True), clvr.InputError, "clvr_tracer_set_denoise", "denoised image without guides")
    r1.set_settings(denoise=True)
    check(r1.settings["denoise"] is True, "denoise set")
    r4 = clvr.Renderer(sc, width=32, height=32, seed=5, denoise=True)  # dda, urm
    check(r4.settings["denoise"] is True, "denoise set at construction")
    r4.render(spp=2)
    dn, raw = r4.image(denoised=True), r4.image()
    check(dn.shape == raw.shape and float(np.abs(dn - raw).max()) > 1e-5,
          "the denoised image differs from the raw one (%g)" % float(np.abs(dn - raw).max()))
    r1.set_settings(denoise=False)
    check(not np.array_equal(r2.render(spp=2), r3.render(spp=2)), "the point filter renders another image")
    raises(lambda: clvr.Renderer(sc, width=True, height=8), clvr.InputError, "width", "width True")
    raises(lambda: clvr.Renderer(sc, width=8, height=65537), clvr.InputError, "[1, 65536]", "height 65537")


# clvr.h's comment on clvr_setting_name: each setting's names in index order.
SETTING_NAMES = {"method": ["march", "track", "bins", "dda"], "estimator": ["delta", "urm", "walk", "auto"],
                 "sampler": ["independent", "ld"], "tonemap": ["none", "aces", "filmic"],
                 "element_boxes": ["auto", "on", "off"], "one_curve": ["auto", "on", "off"]}


def _write_box_vtk(path, lo, hi, fields):
    """One hexahedron filling the box [lo, hi], point fields {name: f(x, y, z)} (legacy VTK)."""
    pts = [(hi[0] if (i ^ (i >> 1)) & 1 else lo[0], hi[1] if i & 2 else lo[1], hi[2] if i & 4 else lo[2])
           for i in range(8)]  # VTK hexahedron order: the bottom face (z lo) round, then the top
    _write_hex_vtk(path, "box", pts, [range(8)], {name: [f(*p) for p in pts] for name, f in fields.items()})
    return pts


def test_api12(ctx):
    E = clvr.InputError
    # Names of settings: the header's tables, both ways.
    for setting, expected in SETTING_NAMES.items():
        names = clvr.setting_names(setting)
        check(names == expected, "setting_names(%r) = %r, clvr.h lists %r" % (setting, names, expected))
        for i, name in enumerate(expected):
            check(clvr.setting_name(setting, i) == name, "setting_name(%r, %d) = %r, expected %r"
                  % (setting, i, clvr.setting_name(setting, i), name))
            got = clvr.setting_index(setting, name)
            check(got == i, "setting_index(%r, %r) = %r, expected %d" % (setting, name, got, i))
        check(clvr.setting_name(setting, len(expected)) is None, "setting_name(%r) past the end is None" % setting)
    e = raises(lambda: clvr.setting_index("method", "magic"), E, "march, track, bins, dda", "unknown method name")
    check(e is None or e.result == "ERR_USAGE", "unknown name's result: %s" % getattr(e, "result", None))
    raises(lambda: clvr.setting_index("colour", "aces"), E, "'colour'", "setting_index of an unknown setting")
    raises(lambda: clvr.setting_names("colour"), E, "'colour'", "setting_names of an unknown setting")
    check(clvr.setting_name("colour", 0) is None, "setting_name of an unknown setting is None")
    raises(lambda: clvr.setting_name("method", -1), E, "index", "negative setting index")
    r = clvr.Renderer(clvr.Mesh.load(os.path.join(DATA, "vtk", "uGridEx.vtk")), device=ctx, width=8, height=8)
    st = r.settings
    check(st["method"] in SETTING_NAMES["method"] and st["estimator"] in SETTING_NAMES["estimator"]
          and st["sampler"] in SETTING_NAMES["sampler"], "the renderer's settings are named in the tables: %r" % st)
    r.close()
    check(clvr.default_size() == (512, 512), "default_size() = %r" % (clvr.default_size(),))

    # Framing a box without a tracer.
    lo, hi = (0.0, -1.0, 2.0), (4.0, 1.0, 3.0)
    centre = 0.5 * (np.array(lo) + np.array(hi))
    eye, target = clvr.frame_box(lo, hi)
    eye, target = np.array(eye), np.array(target)
    check(np.allclose(target, centre, atol=1e-6), "frame_box target %s is not the box centre %s" % (target, centre))
    d = eye - target
    dist = np.linalg.norm(d)
    default_dir = np.array([1.0, 0.8, 1.6]) / np.linalg.norm([1.0, 0.8, 1.6])  # camera.h: CLVR_CAMERA_VIEW_X/Y/Z
    check(dist > np.linalg.norm(np.subtract(hi, lo)) / 2 and np.allclose(d / dist, default_dir, atol=1e-5),
          "frame_box eye %s: expected outside the box along %s" % (eye, default_dir))
    # Azimuth turns the view about +y: +90 degrees takes (x, z) to (z, -x).
    e90, t90 = (np.array(v) for v in clvr.frame_box(lo, hi, azimuth=90))
    d90 = (e90 - t90) / np.linalg.norm(e90 - t90)
    turned = np.array([default_dir[2], default_dir[1], -default_dir[0]])
    check(np.allclose(t90, centre, atol=1e-6) and np.allclose(d90, turned, atol=1e-5),
          "frame_box azimuth 90: direction %s, expected %s" % (d90, turned))
    # Elevation raises the eye; zoom 2 dollies halfway to the centre; up given as +y is up None.
    eup = np.array(clvr.frame_box(lo, hi, elevation=30)[0]) - centre
    check((eup / np.linalg.norm(eup))[1] > default_dir[1] + 0.2, "frame_box elevation 30 raises the eye: %s" % eup)
    ez = np.array(clvr.frame_box(lo, hi, zoom=2)[0]) - centre
    check(abs(np.linalg.norm(ez) * 2 / dist - 1) < 1e-5 and np.allclose(ez / np.linalg.norm(ez), default_dir,
                                                                         atol=1e-5),
          "frame_box zoom 2: distance %g, expected %g" % (np.linalg.norm(ez), dist / 2))
    check(clvr.frame_box(lo, hi, up=(0, 1, 0)) == clvr.frame_box(lo, hi), "frame_box up +y == up None")
    check(clvr.frame_box(lo, hi, width=512, height=512) == clvr.frame_box(lo, hi), "frame_box's default size")
    wide = np.linalg.norm(np.array(clvr.frame_box(lo, hi, fovy=60)[0]) - centre)
    check(wide < dist, "a wider fovy frames from nearer: %g vs %g" % (wide, dist))
    e = raises(lambda: clvr.frame_box(hi, lo), E, "lo <= hi", "frame_box of an inverted box")
    check(e is None or e.result == "ERR_BAD_VALUE", "inverted box's result: %s" % getattr(e, "result", None))
    raises(lambda: clvr.frame_box(lo, hi, zoom=0), E, "zoom", "frame_box zoom 0")
    raises(lambda: clvr.frame_box(lo, hi, width=0), E, "width", "frame_box width 0")
    # The same camera as a Renderer's automatic framing of a mesh with these bounds.
    with tempfile.TemporaryDirectory() as tmp:
        box = os.path.join(tmp, "box.vtk")
        _write_box_vtk(box, lo, hi, {"s": lambda x, y, z: x})
        m = clvr.Mesh.load(box)
    check(m.bounds == (lo, hi), "box mesh bounds %r" % (m.bounds,))
    with clvr.Renderer(m, device=ctx, width=40, height=24) as r:
        cam = r.camera
        fb = clvr.frame_box(*m.bounds, width=40, height=24)
        check((cam["eye"], cam["target"]) == fb, "the renderer's first camera %r != frame_box %r" % (cam, fb))
        view = {"azimuth": 30.0, "elevation": -20.0, "zoom": 1.5, "fovy": 40.0, "up": (0, 0, 1)}
        r.set_camera(view)
        cam = r.camera
        fb = clvr.frame_box(*m.bounds, width=40, height=24, **view)
        check((cam["eye"], cam["target"]) == fb, "set_camera(%r) gives %r, frame_box %r" % (view, cam, fb))
        check(fb != clvr.frame_box(*m.bounds, width=24, height=40, **view), "frame_box depends on the image shape")

    with tempfile.TemporaryDirectory() as tmp:
        # Transfer function files: with and without their own window.
        ranged, plain, pv = (os.path.join(tmp, n) for n in ("ranged.tf", "plain.tf", "map.json"))
        with open(ranged, "w") as fh:
            fh.write("colormap viridis\nopacity 0 0\nopacity 1 0.8\nrange -1.5 2.5   # the window\n")
        with open(plain, "w") as fh:
            fh.write("colormap viridis\nopacity 0 0\nopacity 1 0.8\n")
        with open(pv, "w") as fh:
            fh.write('[{"ColorSpace": "RGB", "Name": "m", "RGBPoints": [-3, 0, 0, 1, 7, 1, 0, 0]}]\n')
        check(clvr.tf_file_window(ranged) == (-1.5, 2.5), "tf_file_window(range line) = %r"
              % (clvr.tf_file_window(ranged),))
        check(clvr.tf_file_window(plain) is None, "tf_file_window(no range) = %r" % (clvr.tf_file_window(plain),))
        check(clvr.tf_file_window(pv) == (-3.0, 7.0), "tf_file_window(ParaView map) = %r"
              % (clvr.tf_file_window(pv),))
        raises(lambda: clvr.tf_file_window(os.path.join(tmp, "nope.tf")), clvr.Error, "nope.tf", "missing TF file")

        # A time series of two meshes (one in a subfolder), fields s and t.
        os.mkdir(os.path.join(tmp, "sub"))
        lo0, hi0, lo1, hi1 = (0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (0.5, -1.0, 0.25), (2.0, 0.5, 3.0)
        _write_box_vtk(os.path.join(tmp, "a.vtk"), lo0, hi0, {"s": lambda x, y, z: x, "t": lambda x, y, z: -z})
        _write_box_vtk(os.path.join(tmp, "sub", "b.vtk"), lo1, hi1,
                       {"s": lambda x, y, z: 10 + y, "t": lambda x, y, z: 5 * z})
        path = os.path.join(tmp, "run.series")
        with open(path, "w") as fh:
            fh.write('{"file-series-version": "1.0", "files": [{"name": "a.vtk", "time": 0.5}, '
                     '{"name": "sub/b.vtk", "time": 2.25}]}\n')
        check(clvr.is_series(path) and clvr.is_series("X.SERIES") and not clvr.is_series(os.path.join(tmp, "a.vtk"))
              and not clvr.is_series("series"), "is_series")
        steps = [(os.path.join(tmp, "a.vtk"), 0.5), (os.path.join(tmp, "sub", "b.vtk"), 2.25)]
        with clvr.Series(path) as se:
            check(len(se) == 2, "len(series) = %d" % len(se))
            check([se.step(0), se.step(1)] == steps, "series steps %r, expected %r" % ([se.step(0), se.step(1)], steps))
            check(list(se) == steps and se[-1] == steps[1], "iterating / indexing the series: %r" % list(se))
            raises(lambda: se.step(2), E, "step 2", "series step past the end")
            raises(lambda: se[2], IndexError, "step 2", "series[2]")
            meshes = [clvr.Mesh.load(p) for p, _ in steps]
            blo, bhi, vmin, vmax = se.bounds()
            want_lo = tuple(min(m.bounds[0][k] for m in meshes) for k in range(3))
            want_hi = tuple(max(m.bounds[1][k] for m in meshes) for k in range(3))
            check(all(np.all(np.array(m.bounds[0]) >= blo) and np.all(np.array(m.bounds[1]) <= bhi) for m in meshes)
                  and (blo, bhi) == (want_lo, want_hi), "series bounds %r, %r; the meshes' union is %r, %r"
                  % (blo, bhi, want_lo, want_hi))
            want_s = (min(m.field_range("s")[0] for m in meshes), max(m.field_range("s")[1] for m in meshes))
            check((vmin, vmax) == want_s == (0.0, 10.5), "series range of s (the first field) %r, expected %r"
                  % ((vmin, vmax), want_s))
            tr = se.bounds("t")[2:]
            check(tr == (-1.0, 15.0), "series range of t %r, expected (-1, 15)" % (tr,))
            raises(lambda: se.bounds("nope"), clvr.Error, "nope", "series bounds of an unknown field")
            check("2 steps" in repr(se), repr(se))
        check(len(se) == 0, "a closed series has no steps")
        raises(lambda: clvr.Series(os.path.join(tmp, "missing.series")), clvr.Error, "missing.series",
               "missing series file")
        bad = os.path.join(tmp, "bad.series")
        with open(bad, "w") as fh:
            fh.write('{"steps": []}\n')
        raises(lambda: clvr.Series(bad), clvr.Error, "not a series file", "a JSON file that is not a series")
        gone = os.path.join(tmp, "gone.series")
        with open(gone, "w") as fh:
            fh.write('{"files": [{"name": "a.vtk"}, {"name": "gone.vtk"}]}\n')
        with clvr.Series(gone) as se:
            check([t for _, t in se] == [0.0, 1.0], "a step without a time gets its index: %r" % list(se))
            raises(lambda: se.bounds(), clvr.Error, "step 1 of", "series with a missing step")


def main():
    try:
        ctx = clvr.Context(DEVICE)
    except clvr.Error as e:
        print("test_python: no OpenCL device (%s): skipped" % e, file=sys.stderr)
        return 77
    print("test_python: clvr %s, API %d, %r, module %s" % (clvr.version(), clvr.api_version(), ctx,
                                                          clvr.__file__), file=sys.stderr)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        test_bad_inputs(ctx)
        test_borrowing(ctx)
        test_fields(ctx)
        test_scene_settings(ctx)
        test_api12(ctx)
    if "--quick" not in sys.argv:
        test_program_matches_module(ctx)
        test_same_image(ctx)
    print("test_python: %s" % ("all passed" if not failures else "%d failure(s)" % failures), file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
