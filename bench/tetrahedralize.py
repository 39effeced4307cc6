#!/usr/bin/python3
"""tetrahedralize.py: cut every cell of a clvr .bin mesh into tets the way ParaView
does before it volume-renders an unstructured grid (vtkDataSetTriangleFilter), and
write the result as a clvr .bin through tools/clvr-convert. bench/converge-all.sh
uses it so that clvr and VTK can also be timed on the very same tets (issue 14's
check on meshes "cut into tets so that VTK can draw them").

Usage: tetrahedralize.py IN.bin OUT.bin   (Debian's /usr/bin/python3, python3-vtk9)
"""
import os
import subprocess
import sys
import tempfile

import vtk

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import vtk_render  # noqa: E402  (read_bin, build_grid)


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__.strip())
    src, out = sys.argv[1], sys.argv[2]
    pos, sc, lists = vtk_render.read_bin(src)
    grid, cut_s = vtk_render.build_grid(pos, sc, lists)
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    with tempfile.TemporaryDirectory() as tmp:
        vtu = os.path.join(tmp, "cut.vtu")
        w = vtk.vtkXMLUnstructuredGridWriter()
        w.SetFileName(vtu)
        w.SetInputData(grid)
        w.SetDataModeToBinary()
        if not w.Write():
            sys.exit(f"tetrahedralize.py: cannot write {vtu}")
        subprocess.run([os.path.join(root, "tools", "clvr-convert"), vtu, out, "--scalar", "scalar", "--quiet"],
                       check=True)
    print(f"tetrahedralize.py: {src}: {sum(i.shape[0] for _, i in lists)} cells -> {grid.GetNumberOfCells()} tets "
          f"({cut_s:.2f} s) in {out}")


if __name__ == "__main__":
    main()
