#!/usr/bin/env python3
"""clvr_turntable.py: reads a .vtu (or any mesh meshio reads) with meshio,
renders a turntable of N frames (default 8) with the clvr Python module and
writes NAME.0000.png ... NAME.0007.png.

    PYTHONPATH=build/python python3 tools/clvr_turntable.py \\
        tests/data/vtk/fire_ug.vtu --field t -o /tmp/fire --frames 8 --spp 32

Needs python3-meshio and python3-numpy (tools/setup-debian.sh convert)."""
import argparse
import sys

import meshio

import clvr


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("mesh", help="a mesh file meshio reads (.vtu, .vtk, .msh, ...)")
    ap.add_argument("-o", "--output", default="turntable", help="output prefix (default turntable)")
    ap.add_argument("--field", help="scalar point field to render (default: the first)")
    ap.add_argument("--frames", type=int, default=8, help="images around the turntable (default 8)")
    ap.add_argument("--spp", type=int, default=32, help="samples per pixel per image (default 32)")
    ap.add_argument("--size", default="512x512", help="WIDTHxHEIGHT (default 512x512)")
    ap.add_argument("--device", default="pocl", help="OpenCL device (default pocl)")
    ap.add_argument("--colormap", default="cool-warm")
    a = ap.parse_args()
    w, h = (int(x) for x in a.size.lower().split("x"))
    try:
        mesh = clvr.Mesh.from_meshio(meshio.read(a.mesh), fields=[a.field] if a.field else None)
        print("%s: %r" % (a.mesh, mesh), file=sys.stderr)
        with clvr.Renderer(mesh, device=a.device, width=w, height=h, field=a.field) as r:
            r.set_tf(a.colormap)
            for i in range(a.frames):
                img = r.render(spp=a.spp, camera={"azimuth": 360.0 * i / a.frames})
                path = "%s.%04d.png" % (a.output, i)
                clvr.save_image(path, img)
                print("wrote %s" % path, file=sys.stderr)
    except clvr.Error as e:
        print("clvr_turntable: %s" % e, file=sys.stderr)
        return 2 if isinstance(e, clvr.InputError) else 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
