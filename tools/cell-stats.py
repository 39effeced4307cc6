#!/usr/bin/python3
"""cell-stats.py: element-size statistics of clvr .bin meshes (docs/bin-format.md).

usage: cell-stats.py MESH.bin [MESH.bin ...] [--json FILE] [--name NAME ...]

For each mesh: element count per type; element volume min, max, max/min, and the
quantiles 1, 10, 50, 90, 99 %; the ratio of the 99 % to the 1 % quantile (the
grading without a few slivers); the longest over the shortest element bounding-box
edge per element (anisotropy), median and 99 %. Volumes: tets exactly; pyramids,
wedges and hexes as the sum of the tets of a fixed split (exact for planar faces).
Prints one Markdown table (a row per mesh); --json writes a list of objects.
"""
import argparse
import json
import os
import sys

import numpy as np

COUNTS = (("tets", 4), ("pyramids", 5), ("wedges", 6), ("hexes", 8))
# Tet splits in VTK vertex order (see docs/bin-format.md).
SPLITS = {
    "tets": [(0, 1, 2, 3)],
    "pyramids": [(0, 1, 2, 4), (0, 2, 3, 4)],
    "wedges": [(0, 1, 2, 3), (1, 2, 3, 4), (2, 3, 4, 5)],
    "hexes": [(0, 1, 3, 4), (1, 2, 3, 6), (1, 4, 5, 6), (3, 4, 6, 7), (1, 3, 4, 6)],
}
QUANTILES = (0.01, 0.10, 0.50, 0.90, 0.99)


def read_bin(path):
    with open(path, "rb") as f:
        head = f.read(256)
        if len(head) != 256 or head[:8] != b"CLVRMESH":
            sys.exit("cell-stats.py: %s: not a clvr .bin mesh" % path)
        version = int(np.frombuffer(head, dtype="<u4", count=1, offset=8)[0])
        if version not in (1, 2):
            sys.exit("cell-stats.py: %s: .bin version %d, this reads 1 and 2" % (path, version))
        v, t, p, w, h = np.frombuffer(head, dtype="<u8", count=5, offset=16)
        pos = np.fromfile(f, dtype="<f4", count=3 * int(v)).reshape(-1, 3)
        if version == 1:  # version 2 keeps its fields after the elements
            np.fromfile(f, dtype="<f4", count=int(v))  # scalars
        elems = {}
        for (name, k), n in zip(COUNTS, (t, p, w, h)):
            elems[name] = np.fromfile(f, dtype="<u4", count=k * int(n)).reshape(-1, k)
    return pos, elems


def volumes(pos, idx, split):
    vol = np.zeros(len(idx), dtype=np.float64)
    for a, b, c, d in split:
        pa = pos[idx[:, a]].astype(np.float64)
        e1 = pos[idx[:, b]] - pa
        e2 = pos[idx[:, c]] - pa
        e3 = pos[idx[:, d]] - pa
        vol += np.abs(np.einsum("ij,ij->i", e1, np.cross(e2, e3))) / 6.0
    return vol


def stats(path, name):
    pos, elems = read_bin(path)
    vols, aniso = [], []
    for kind, idx in elems.items():
        if len(idx) == 0:
            continue
        for lo in range(0, len(idx), 1 << 20):  # chunks keep memory small
            chunk = idx[lo:lo + (1 << 20)]
            vols.append(volumes(pos, chunk, SPLITS[kind]))
            p = pos[chunk]
            ext = p.max(axis=1) - p.min(axis=1)
            aniso.append(ext.max(axis=1) / np.maximum(ext.min(axis=1), 1e-30))
    vol = np.concatenate(vols)
    an = np.concatenate(aniso)
    q = np.quantile(vol, QUANTILES)
    pos_vol = vol[vol > 0]
    lo, hi = float(pos_vol.min()) if len(pos_vol) else 0.0, float(vol.max())
    return {
        "mesh": name,
        "file": os.path.basename(path),
        "vertices": int(len(pos)),
        "elements": int(len(vol)),
        **{kind: int(len(idx)) for kind, idx in elems.items()},
        "zero_volume": int((vol <= 0).sum()),
        "vol_min": lo,
        "vol_max": hi,
        "vol_ratio": hi / lo if lo > 0 else float("inf"),
        **{"vol_q%02d" % round(100 * qq): float(x) for qq, x in zip(QUANTILES, q)},
        "vol_q99_over_q01": float(q[-1] / q[0]) if q[0] > 0 else float("inf"),
        "bbox_aspect_median": float(np.median(an)),
        "bbox_aspect_q99": float(np.quantile(an, 0.99)),
    }


def markdown(rows):
    out = ["| mesh | elements | tets / pyr / wedges / hexes | vol min | q01 | q50 | q99 | vol max "
           "| max/min | q99/q01 | bbox aspect median / q99 |",
           "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        out.append("| %s | %d | %d / %d / %d / %d | %.3g | %.3g | %.3g | %.3g | %.3g | %.2g | %.2g | %.1f / %.1f |" % (
            r["mesh"], r["elements"], r["tets"], r["pyramids"], r["wedges"], r["hexes"], r["vol_min"],
            r["vol_q01"], r["vol_q50"], r["vol_q99"], r["vol_max"], r["vol_ratio"], r["vol_q99_over_q01"],
            r["bbox_aspect_median"], r["bbox_aspect_q99"]))
    return "\n".join(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("--json")
    ap.add_argument("--name", action="append", default=[], help="row names, in order (default: file stem)")
    a = ap.parse_args()
    rows = []
    for i, m in enumerate(a.meshes):
        name = a.name[i] if i < len(a.name) else os.path.splitext(os.path.basename(m))[0]
        rows.append(stats(m, name))
    print(markdown(rows))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(rows, f, indent=1)
            f.write("\n")


if __name__ == "__main__":
    main()
