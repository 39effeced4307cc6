#!/usr/bin/env python3
"""make_seeds.py: writes the fuzz seed corpora under tests/fuzz/seeds/<target>/
(small valid files of every layout each reader accepts, so the fuzzer starts
from inside the formats). Run it again after changing a format; the files
are committed. Usage: tests/fuzz/make_seeds.py"""
import os
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "hostile"))
import meshgen as mg  # noqa: E402


def mixed():
    """One element of each type sharing vertices, scalars 0..1."""
    pos = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0.5, 0.5, 1),
           (0, 0, 2), (1, 0, 2), (0, 1, 2), (2, 0, 0), (2, 1, 0), (2, 0, 1), (2, 1, 1), (1, 0, 1), (1, 1, 1)]
    sc = [i / (len(pos) - 1) for i in range(len(pos))]
    return mg.mesh(pos, sc, {
        "tets": [(0, 1, 3, 5)],
        "pyramids": [(0, 1, 2, 3, 4)],
        "wedges": [(0, 1, 3, 5, 6, 7)],
        "hexes": [(1, 8, 9, 2, 12, 10, 11, 13)],
    }, "mixed")


def bin2_bytes(m, fields):
    """clvr .bin version 2 (docs/bin-format.md): positions, index lists, the field
    table and the fields. fields: [(name, association 0/1, components, flat values)]."""
    nv = len(m["positions"])
    counts = [len(m["cells"][t]) for t in mg.CELL_TYPES]
    h = bytearray(256)
    h[0:8] = b"CLVRMESH"
    struct.pack_into("<IIQ4Q", h, 8, 2, 256, nv, *counts)
    if nv:
        lo = [min(p[k] for p in m["positions"]) for k in range(3)]
        hi = [max(p[k] for p in m["positions"]) for k in range(3)]
        struct.pack_into("<3f3f", h, 56, *lo, *hi)
    if fields:
        h[88:88 + len(fields[0][0])] = fields[0][0].encode()
    struct.pack_into("<I", h, 156, len(fields))
    body = bytearray()
    for p in m["positions"]:
        body += struct.pack("<3f", *p)
    for t in mg.CELL_TYPES:
        for c in m["cells"][t]:
            body += struct.pack("<%dI" % len(c), *c)
    for name, assoc, nc, vals in fields:
        e = bytearray(128)
        e[0:len(name)] = name.encode()
        struct.pack_into("<IIff", e, 64, assoc, nc, min(vals), max(vals))
        body += e
    for _, _, _, vals in fields:
        body += struct.pack("<%df" % len(vals), *vals)
    return bytes(h) + bytes(body)


def write(target, name, data):
    d = os.path.join(HERE, "seeds", target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def main():
    tet, grid, mix = mg.unit_tet(), mg.hex_grid(2), mixed()
    tgrid = mg.tet_grid(1)
    # .bin
    write("bin", "tet.bin", mg.bin_bytes(tet))
    write("bin", "hex_grid.bin", mg.bin_bytes(grid))
    write("bin", "mixed.bin", mg.bin_bytes(mix))
    write("bin", "tet_grid.bin", mg.bin_bytes(tgrid))
    write("bin", "empty.bin", mg.bin_bytes(mg.mesh([], [], {}, "")))
    # .bin version 2: point, cell and vector fields, a shared name, no fields
    ne = sum(len(mix["cells"][t]) for t in mg.CELL_TYPES)
    nv = len(mix["positions"])
    write("bin", "mixed_fields_v2.bin", bin2_bytes(mix, [
        ("s", 0, 1, list(mix["scalars"])),
        ("s", 1, 1, [float(10 * i) for i in range(ne)]),
        ("vel", 0, 3, [float(i % 5) for i in range(3 * nv)]),
        ("stress", 1, 6, [float(i % 7) - 3 for i in range(6 * ne)])]))
    write("bin", "tet_cell_v2.bin", bin2_bytes(tet, [("c", 1, 1, [2.5])]))
    write("bin", "grid_nofields_v2.bin", bin2_bytes(grid, []))
    # .umesh, every version the reader takes
    write("umesh", "mixed_566.umesh", mg.umesh_bytes(mix, 0x566))
    write("umesh", "mixed_567.umesh", mg.umesh_bytes(mix, 0x567))
    write("umesh", "tet_568.umesh", mg.umesh_bytes(tet, 0x568))
    write("umesh", "grid_567.umesh", mg.umesh_bytes(grid, 0x567))
    # legacy VTK: ASCII and binary, classic and 5.1 cells, point and cell data
    tri = ((5, (0, 1, 2)),)
    write("vtk", "mixed_ascii.vtk", mg.vtk_bytes(mix, extra_cells=tri))
    write("vtk", "mixed_binary.vtk", mg.vtk_bytes(mix, binary=True, extra_cells=tri))
    write("vtk", "mixed_51_binary.vtk", mg.vtk_bytes(mix, binary=True, version="5.1", new_layout=True))
    write("vtk", "mixed_51_ascii.vtk", mg.vtk_bytes(mix, version="5.1", new_layout=True))
    write("vtk", "tet_celldata.vtk", mg.vtk_bytes(tet, cell_data=True))
    write("vtk", "grid_celldata_binary.vtk", mg.vtk_bytes(grid, binary=True, cell_data=True))
    # FIELD arrays, VECTORS, METADATA and a quadratic tet (type 24)
    field = (b"# vtk DataFile Version 4.2\nfield test\nASCII\nDATASET UNSTRUCTURED_GRID\n"
             b"FIELD FieldData 1\nTIME 1 1 double\n0.5\n"
             b"POINTS 10 double\n0 0 0 1 0 0 0 1 0 0 0 1 .5 0 0 .5 .5 0 0 .5 0 0 0 .5 .5 0 .5 0 .5 .5\n"
             b"METADATA\nINFORMATION 0\n\n"
             b"CELLS 1 11\n10 0 1 2 3 4 5 6 7 8 9\nCELL_TYPES 1\n24\n"
             b"POINT_DATA 10\nVECTORS vel float\n" + b"1 0 0\n" * 10 +
             b"FIELD attrs 2\nrho 1 10 float\n0 1 2 3 4 5 6 7 8 9\nuvw 3 10 double\n" + b"0 1 2 " * 10 + b"\n"
             b"CELL_DATA 1\nSCALARS id int\nLOOKUP_TABLE default\n7\n")
    write("vtk", "quadratic_field.vtk", field)
    # a polyhedron (type 42: a hexagonal prism's face stream) beside a tet, classic and 5.1 cells
    poly = ("\n".join(['# vtk DataFile Version 4.2', 'polyhedra', 'ASCII', 'DATASET UNSTRUCTURED_GRID', 'POINTS 13 float', '1.0 0.0 0', '0.5 0.866025 0', '-0.5 0.866025 0', '-1.0 0.0 0', '-0.5 -0.866025 0', '0.5 -0.866025 0', '1.0 0.0 1', '0.5 0.866025 1', '-0.5 0.866025 1', '-1.0 0.0 1', '-0.5 -0.866025 1', '0.5 -0.866025 1', '0 0 2', 'CELLS 2 51', '45 8 6 5 4 3 2 1 0 6 6 7 8 9 10 11 4 0 1 7 6 4 1 2 8 7 4 2 3 9 8 4 3 4 10 9 4 4 5 11 10 4 5 0 6 11', '4 6 7 8 12', 'CELL_TYPES 2', '42 10', 'POINT_DATA 13', 'SCALARS s float', 'LOOKUP_TABLE default', '0 1 2 3 4 5 6 7 8 9 10 11 12', 'CELL_DATA 2', 'SCALARS c float', 'LOOKUP_TABLE default', '10 20']) + "\n").encode()
    write("vtk", "polyhedron_ascii.vtk", poly)
    stream = "8 6 5 4 3 2 1 0 6 6 7 8 9 10 11 4 0 1 7 6 4 1 2 8 7 4 2 3 9 8 4 3 4 10 9 4 4 5 11 10 4 5 0 6 11"
    poly51 = poly.replace(b"4.2", b"5.1").replace(
        b"CELLS 2 51\n45 " + stream.encode() + b"\n4 6 7 8 12\n",
        b"CELLS 3 49\nOFFSETS vtktypeint64\n0 45 49\nCONNECTIVITY vtktypeint64\n" + stream.encode() +
        b" 6 7 8 12\n")
    assert poly51 != poly
    write("vtk", "polyhedron_51_ascii.vtk", poly51)
    # transfer functions: the text format and ParaView JSON
    write("tf", "ramp.tf", b"# soft ramp\ncolormap viridis\nopacity 0 0\nopacity 0.3 0 0.5 0.2\nopacity 1 0.8\n"
                           b"range -1.5 2.5\ndensity 2\ntable 512\n")
    write("tf", "colors.tf", b"colorspace Lab\ncolor 0 0.23 0.30 0.75\ncolor 0.5 0.86 0.86 0.86\n"
                             b"color 1 0.71 0.02 0.15\nopacity 0 0\nopacity 1 1\n")
    write("tf", "step_hsv.tf", b"\xef\xbb\xbfcolorspace Step\r\ncolor 0 0 0 0\r\ncolor 1 1 1 1\r\n"
                               b"colorspace HSV\r\n")
    write("tf", "paraview.json", b'[\n  {\n    "ColorSpace" : "Diverging",\n    "Name" : "Cool to Warm",\n'
                                 b'    "RGBPoints" : [ -1, 0.2314, 0.2980, 0.7529,  0, 0.865, 0.865, 0.865,  '
                                 b'1, 0.7059, 0.0157, 0.1490 ],\n    "Points" : [ -1, 0, 0.5, 0,  1, 1, 0.5, 0 ]\n  }\n]\n')
    write("tf", "object.json", b'{"Name": "x\\u00e9\\ud83d\\ude00", "ColorSpace": "HSV", "NanColor": [1, 0, 0],'
                               b' "RGBPoints": [0, 0, 0, 0, 1e0, 1, 0.5, 0.25], "Creator": null,'
                               b' "Annotations": [true, false, {"a": -0.0e-1}]}')
    print("seeds written under", os.path.join(HERE, "seeds"))


if __name__ == "__main__":
    main()
