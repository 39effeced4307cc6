#!/usr/bin/python3
"""graded_summary.py: bench/graded.sh's summary against issue #19's goals.

usage: [CLVR_BENCH_CPU=LINE] graded_summary.py RAWDIR OUT.json GRADED=UNIFORM ...

Reads the JSON files graded.sh left in RAWDIR (stats.json, locate-MESH-ORDER.json, rep-MESH-ORDER-R.json,
table2-MESH.json, render-EST.json, converge-MESH.json), merges them into OUT.json (the
converge runs without their per-spp points and transfer-function tables; "cpu": the
machine, bench/host-cpu.sh's line, from CLVR_BENCH_CPU) and prints
Markdown: point location vs Embree (goal >= 1.5x, tree + indices <= 1/3 of Embree's),
best leaf size per mesh, and graded over uniform rendering ratios (goal <= 2x).
"""
import glob
import json
import os
import statistics
import sys


def load(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def base(path):
    return os.path.splitext(os.path.basename(path))[0]


def main():
    raw, out, pairs = sys.argv[1], sys.argv[2], [p.split("=", 1) for p in sys.argv[3:]]
    merged = {"cpu": os.environ.get("CLVR_BENCH_CPU", ""), "stats": load(os.path.join(raw, "stats.json")),
              "locate": {}, "table2": {}, "render": None, "converge": {}, "pairs": pairs}
    for p in sorted(glob.glob(os.path.join(raw, "locate-*.json"))):
        merged["locate"][base(p)[len("locate-"):]] = load(p)
    for p in sorted(glob.glob(os.path.join(raw, "table2-*.json"))):
        merged["table2"][base(p)[len("table2-"):]] = load(p)
    merged["repeats"] = {}
    for p in sorted(glob.glob(os.path.join(raw, "rep-*.json"))):
        merged["repeats"][base(p)[len("rep-"):]] = load(p)
    merged["render"] = {}
    for p in sorted(glob.glob(os.path.join(raw, "render*.json"))):
        d = load(p)
        if d:
            # render-EST[-MESH].json (one run per pair since session 57); a plain
            # render.json (older runs) is urm, the renderer's default then
            est = base(p)[len("render-"):].split("-", 1)[0] or "urm"
            merged["render"].setdefault(est, {"rows": []})["rows"] += d.get("rows", [])
    for p in sorted(glob.glob(os.path.join(raw, "converge-*.json"))):
        d = load(p)
        if d:
            d.pop("tf", None)
            for r in d.get("rows", []):
                r.pop("points", None)
        merged["converge"][base(p)[len("converge-"):]] = d
    with open(out, "w") as f:
        json.dump(merged, f, indent=1)
        f.write("\n")

    o = ["## Summary against issue #19's goals", ""]
    if merged["stats"]:
        o += ["Cell volumes: " + "; ".join("%s %d elements, max/min %.2g, q99/q01 %.2g" % (
            s["mesh"], s["elements"], s["vol_ratio"], s["vol_q99_over_q01"]) for s in merged["stats"]) + ".", ""]
    if merged["locate"]:
        o += ["Point location, clvr vs Embree 3's faster query (goal: >= 1.5x; tree + indices <= 1/3 of Embree's):", "",
              "| mesh | points | clvr q/s | Embree q/s | ratio | goal 1.5x | clvr / Embree bytes | goal 1/3 | load |",
              "|---|---|---:|---:|---:|---|---:|---|---:|"]
        for key, d in merged["locate"].items():
            if not d:
                continue
            rows = {r["method"]: r for r in d["rows"]}
            c = rows.get("clvr")
            e = [r for m, r in rows.items() if m.startswith("embree")]
            if not c or not e:
                continue
            b = max(e, key=lambda r: r["queries_per_s"])
            ratio = c["queries_per_s"] / b["queries_per_s"]
            mem = (c["tree_bytes"] + c["index_bytes"]) / (b["tree_bytes"] + b["index_bytes"])
            mesh, order = key.rsplit("-", 1)
            o.append("| %s | %s | %.3g | %.3g | %.2f | %s | %.2f | %s | %.1f |" % (
                mesh, order, c["queries_per_s"], b["queries_per_s"], ratio, "met" if ratio >= 1.5 else "missed",
                mem, "met" if mem <= 1 / 3 else "missed", c["load"]))
        o.append("")
    if merged["repeats"]:
        runs = {}
        for key, d in merged["repeats"].items():
            mesh_order = key.rsplit("-", 1)[0]
            rows = {r["method"]: r for r in (d or {}).get("rows", [])}
            e = [r for m, r in rows.items() if m.startswith("embree")]
            if "clvr" in rows and e:
                b = max(e, key=lambda r: r["queries_per_s"])
                runs.setdefault(mesh_order, []).append((rows["clvr"]["queries_per_s"] / b["queries_per_s"],
                                                        rows["clvr"]["load"]))
        o += ["Point location, repeats (bench_locate_embree alone): clvr over Embree's faster query, the goal "
              "judged on the median:", "",
              "| mesh | points | per run | median | goal 1.5x | loads |", "|---|---|---|---:|---|---|"]
        for mesh_order, v in runs.items():
            mesh, order = mesh_order.rsplit("-", 1)
            med = statistics.median(x for x, _ in v)
            o.append("| %s | %s | %s | %.2f | %s | %s |" % (
                mesh, order, ", ".join("%.2f" % x for x, _ in v), med, "met" if med >= 1.5 else "missed",
                ", ".join("%.1f" % l for _, l in v)))
        o.append("")
    if merged["table2"]:
        o += ["Table 2 shape, best leaf size N per mesh (random points):", "",
              "| mesh | best N | q/s at best | q/s N=1 | 4 | 8 | 16 | 32 | load |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
        for mesh, d in merged["table2"].items():
            if not d:
                continue
            rows = {r["N"]: r for r in d["rows"]}
            best = max(d["rows"], key=lambda r: r["queries_per_s"])
            o.append("| %s | %d | %.3g | %s | %.1f |" % (
                mesh, best["N"], best["queries_per_s"],
                " | ".join("%.3g" % rows[n]["queries_per_s"] if n in rows else "" for n in (1, 4, 8, 16, 32)),
                best["load"]))
        o.append("")
    if merged["render"]:
        o += ["Rendering, graded over uniform (goal: samples/ray and null collisions/ray <= 2x):", "",
              "| graded / uniform | estimator, method | samples/ray | null/ray | samples ratio | null ratio | Mrays/s graded / uniform | goal | load |",
              "|---|---|---:|---:|---:|---:|---:|---|---:|"]
    for est, r in merged["render"].items():
        by = {}
        for row in r["rows"]:
            by[(os.path.splitext(row["mesh"])[0], row["label"])] = row
        for g, u in pairs:
            for (m, label), gr in by.items():
                if m != g or (u, label) not in by:
                    continue
                ur = by[(u, label)]
                sr = gr["samples_per_ray"] / ur["samples_per_ray"] if ur["samples_per_ray"] else float("inf")
                nr = (gr["null_collisions_per_ray"] / ur["null_collisions_per_ray"]
                      if ur["null_collisions_per_ray"] else float("inf"))
                o.append("| %s / %s | %s, %s | %.3g / %.3g | %.3g / %.3g | %.2f | %.2f | %.3g / %.3g | %s | %.1f |" % (
                    g, u, est, label, gr["samples_per_ray"], ur["samples_per_ray"], gr["null_collisions_per_ray"],
                    ur["null_collisions_per_ray"], sr, nr, gr["mrays_per_s"], ur["mrays_per_s"],
                    "met" if sr <= 2 and nr <= 2 else "missed", gr["load_before"]))
    if merged["render"]:
        o.append("")
    if merged["converge"]:
        o += ["Time to 2 % relative RMSE (256x256, dda, 32-spp reference; '>X (fit Y)': not reached within "
              "48 spp, Y = the 1/n fit's estimate):", "",
              "| graded / uniform | estimator | shadows | s graded | s uniform | graded / uniform | samples/ray graded / uniform | load |",
              "|---|---|---|---:|---:|---:|---:|---:|"]
        for g, u in pairs:
            dg, du = merged["converge"].get(g), merged["converge"].get(u)
            if not dg or not du:
                continue
            ru = {(x["estimator"], x["shadows"]): x for x in du["rows"]}
            for x in dg["rows"]:
                y = ru.get((x["estimator"], x["shadows"]))
                if not y:
                    continue

                def t(z):
                    if z.get("reached"):
                        return z["at"]["device_s"], "%.2f" % z["at"]["device_s"]
                    f = z.get("fit_s")  # null: nothing to fit
                    return f, "> (fit %s)" % ("-" if f is None else "%.1f" % f)
                (tg, sg), (tu, su) = t(x), t(y)
                o.append("| %s / %s | %s | %s | %s | %s | %s | %.3g / %.3g | %.1f |" % (
                    g, u, x["estimator"], "on" if x["shadows"] else "off", sg, su,
                    "%.2f" % (tg / tu) if tg and tu else "n/a",
                    x["samples_per_ray"], y["samples_per_ray"], x["load_before"]))
        o.append("")
    print("\n".join(o))


if __name__ == "__main__":
    main()
