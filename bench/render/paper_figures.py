#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""The paper's figures (issue 16, item 4) from pointsurf pipelines on the blade of blade.py.

  paper_figures.py [--cli build/pointsurf] [--out bench/out/paper] [--docs docs/paper]

(a) every reconstruction method on the blade scan: deviation of its mesh's vertices from the
    exact surface, and of the scan from its mesh (max and mean positive and negative), with a
    deviation colour map each;
(b) surface-area change of random, curvature and regional simplification at equal reduction
    (ratio 0.25), each reconstructed by the default triangulation, against the full scan's mesh;
(c) reconstruction time against point count for each method (one pipeline; its HTML report's
    time chart is the plot).
Writes the pipelines, run reports, meshes and pictures under --out, the pictures and reports the
docs show under --docs, and the tables (Markdown) on stdout.
"""
import argparse
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
METHODS = ["triangulate", "ball-pivot", "cocone", "crust"]
TOL = 0.5  # mm: the tolerance band of the maps (2.5 sigma of the scan noise)


def run(cli, pipeline, out, name, extra=()):
    path = os.path.join(out, name + ".json")
    with open(path, "w") as f:
        json.dump(pipeline, f, indent=1)
    report = os.path.join(out, name + "_run.json")
    r = subprocess.run([cli, "run", path, "--report", report, "--quiet", *extra], capture_output=True, text=True)
    if r.returncode != 0:
        print(f"{name}: exit {r.returncode}: {r.stderr.strip()}", file=sys.stderr)
        return None
    with open(report) as f:
        return json.load(f)


def stage(report, kind, tag=None):
    for s in report["stages"]:
        if s["type"] == kind and (tag is None or s["tag"] == tag):
            return s
    return None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", default="build/pointsurf")
    ap.add_argument("--out", default="bench/out/paper")
    ap.add_argument("--docs", default="docs/paper")
    a = ap.parse_args()
    cli, out, docs = os.path.abspath(a.cli), os.path.abspath(a.out), os.path.abspath(a.docs)
    os.makedirs(out, exist_ok=True)
    os.makedirs(docs, exist_ok=True)
    subprocess.run([sys.executable, os.path.join(HERE, "blade.py"), out], check=True)
    scan, exact = os.path.join(out, "blade_scan.xyz"), os.path.join(out, "blade_exact.ply")
    pic = {"view": "front", "size": "600x900", "field": "deviation", "tolerance": TOL, "unit": "mm", "range": [-2.0, 2.0]}

    # (a) every method.
    rows = []
    for m in METHODS:
        mesh = os.path.join(out, f"mesh_{m}.ply")
        rep = run(cli, [scan, {"type": "normals", "tag": "oriented", "orient": "mst"}, {"type": "reconstruct", "method": m}, mesh,
                        {"type": "evaluate", "tolerance": TOL}, os.path.join(out, f"scan_from_{m}.ply"),
                        dict(pic, type="render", filename=os.path.join(docs, f"scan_from_{m}.png"), title=f"scan from the {m} mesh (mm)")],
                  out, f"a_{m}")
        if rep is None:
            rows.append((m, None, None, None))
            continue
        rec = stage(rep, "reconstruct")
        # The exact surface (its 432,002 vertices) measured against the mesh: where the mesh lies
        # outside the exact surface the exact points are inside it (negative), so signs swap.
        back = run(cli, [mesh, {"type": "read", "tag": "exact", "filename": exact},
                         {"type": "evaluate", "inputs": ["read1"], "reference": "exact", "tolerance": TOL},
                         os.path.join(out, f"exact_from_{m}.ply"),
                         dict(pic, type="render", filename=os.path.join(docs, f"exact_from_{m}.png"),
                              title=f"exact blade from the {m} mesh (mm)")],
                   out, f"a_{m}_exact")
        rows.append((m, rec, stage(rep, "evaluate")["metrics"], back and stage(back, "evaluate")["metrics"]))
    print("### (a) deviations, mm (scan: 60,000 points, noise sigma 0.2 mm)\n")
    print("| method | triangles | reconstruct s | mesh from exact surface: max + / max - | mean + / mean - | scan from mesh: max + / max - | mean + / mean - | Hausdorff scan-mesh |")
    print("|---|---|---|---|---|---|---|---|")
    for m, rec, dev, ex in rows:
        if rec is None:
            print(f"| {m} | failed | | | | | | |")
            continue
        d, e = dev["deviation"], ex["deviation"] if ex else None
        ee = (f"{-e['max_negative']:.3f} / {-e['max_positive']:.3f} | {-e['mean_negative']:.3f} / {-e['mean_positive']:.3f}" if e else "n/a | n/a")
        print(f"| {m} | {rec['counts'].get('triangles', rec['counts'].get('faces', '?'))} | {rec['seconds']:.2f} | {ee} | "
              f"{d['max_positive']:.3f} / {d['max_negative']:.3f} | {d['mean_positive']:.3f} / {d['mean_negative']:.3f} | "
              f"{dev['distance']['hausdorff']:.3f} |")

    # (b) area change at equal reduction.
    print("\n### (b) surface area after simplification to 25% of the points, triangulated, mm^2\n")
    full = run(cli, [scan, {"type": "normals", "tag": "oriented", "orient": "mst"}, {"type": "reconstruct"}, {"type": "quality"}], out, "b_full")
    base = stage(full, "quality")["metrics"]["quality"]["area"] if full else float("nan")
    print(f"| input | points | area | change vs the full scan's mesh | change vs the exact area |")
    print("|---|---|---|---|---|")
    exact_area = 439109.85
    print(f"| full scan | 60000 | {base:.1f} | 0 | {100 * (base - exact_area) / exact_area:+.2f}% |")
    for m in ["random", "curvature", "regional"]:
        rep = run(cli, [scan, {"type": "normals", "tag": "oriented", "orient": "mst"}, {"type": "curvature"},
                        {"type": "simplify", "method": m, "ratio": 0.25}, {"type": "reconstruct"}, {"type": "quality"}], out, f"b_{m}")
        if rep is None:
            print(f"| {m} | failed | | | |")
            continue
        area = stage(rep, "quality")["metrics"]["quality"]["area"]
        kept = stage(rep, "simplify")["counts"].get("output", stage(rep, "simplify")["counts"].get("kept", "?"))
        print(f"| {m} 25% | {kept} | {area:.1f} | {100 * (area - base) / base:+.2f}% | {100 * (area - exact_area) / exact_area:+.2f}% |")

    # (c) time against point count: one pipeline, its report's time chart.
    steps = [scan, {"type": "normals", "tag": "oriented", "orient": "mst"}]
    for n in [7500, 15000, 30000, 60000]:
        tag = f"n{n}"
        steps.append({"type": "simplify", "tag": tag, "inputs": ["oriented"], "method": "random", "count": n} if n < 60000
                     else {"type": "transform", "tag": tag, "inputs": ["oriented"]})
        for m in METHODS:
            steps.append({"type": "reconstruct", "tag": f"{m}_{n}", "inputs": [tag], "method": m})
            steps.append({"type": "quality", "tag": f"q_{m}_{n}"})
    rep = run(cli, steps, out, "c_times", ["--html", os.path.join(out, "times_report.html")])
    print("\n### (c) reconstruction time (s) against point count\n")
    print("| points | " + " | ".join(METHODS) + " |")
    print("|---|" + "---|" * len(METHODS))
    if rep:
        for n in [7500, 15000, 30000, 60000]:
            cells = []
            for m in METHODS:
                s = stage(rep, "reconstruct", f"{m}_{n}")
                cells.append(f"{s['seconds']:.2f}" if s else "n/a")
            print(f"| {n} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
