#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Summary of bench/register/features_bench.sh: appends the runs to the CSV and prints a
Markdown table of medians per pair and tool, with pointsurf / Open3D time ratios.

  features_summary.py RUNS.jsonl OUT.csv COMMIT DATE MACHINE
A run succeeds when its rotation error is under 5 degrees (close enough for ICP to finish).
"""
import csv
import json
import os
import statistics
import sys

FIELDS = ["commit", "date", "machine", "load", "dataset", "start", "run", "tool", "points_source", "points_target",
          "fpfh_s", "pfh_s", "pfh_ransac_s", "pfh_rotation_error_deg", "ransac_s", "total_s", "rotation_error_deg", "translation_error", "fitness",
          "inlier_rmse", "correspondences", "iterations", "converged"]


def median(rows, key):
    values = [r[key] for r in rows if r.get(key) is not None]
    return statistics.median(values) if values else None


def main(raw, out, commit, date, machine):
    runs = [json.loads(line) for line in open(raw) if line.strip()]
    new = not os.path.exists(out)
    with open(out, "a", newline="") as f:
        w = csv.DictWriter(f, fieldnames=FIELDS, extrasaction="ignore")
        if new:
            w.writeheader()
        for r in runs:
            w.writerow(dict(r, commit=commit, date=date, machine=machine))
    print(f"commit {commit}, {date}, {machine}; load (1 min) median "
          f"{statistics.median(r['load'] for r in runs):.2f}, max {max(r['load'] for r in runs):.2f}\n")
    print("| pair | points src/tgt | tool | FPFH s | PFH s | RANSAC s | total s | rotation error deg "
          "median / max | translation error median | fitness | within 5 deg |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for d in dict.fromkeys(r["dataset"] for r in runs):
        medians = {}
        for tool in ("pointsurf", "open3d"):
            rows = [r for r in runs if r["dataset"] == d and r["tool"] == tool]
            if not rows:
                continue
            m = {k: median(rows, k) for k in ("fpfh_s", "pfh_s", "pfh_ransac_s", "pfh_rotation_error_deg", "ransac_s", "total_s", "rotation_error_deg",
                                               "translation_error", "fitness", "points_source", "points_target")}
            medians[tool] = m
            ok = sum(r["rotation_error_deg"] < 5.0 for r in rows)
            fmt = lambda x, p=3: "-" if x is None else f"{x:.{p}f}"
            print(f"| {d} | {m['points_source']:.0f}/{m['points_target']:.0f} | {tool} | {fmt(m['fpfh_s'])} | "
                  f"{fmt(m['pfh_s'])} | {fmt(m['ransac_s'])} | {fmt(m['total_s'])} | "
                  f"{fmt(m['rotation_error_deg'], 2)} / {max(r['rotation_error_deg'] for r in rows):.2f} | "
                  f"{m['translation_error']:.2g} | {m['fitness']:.3f} | {ok}/{len(rows)} |")
        if len(medians) == 2:
            p, o = medians["pointsurf"], medians["open3d"]
            ratio = lambda k: p[k] / o[k]
            prow = [r for r in runs if r["dataset"] == d and r.get("pfh_rotation_error_deg") is not None]
            pfh = (f"PFH/FPFH time {p['pfh_s'] / p['fpfh_s']:.1f}x; PFH pose error median "
                   f"{median(prow, 'pfh_rotation_error_deg'):.2f} deg" if prow else "")
            print(f"| {d} | | pointsurf / Open3D | {ratio('fpfh_s'):.2f}x | | {ratio('ransac_s'):.2f}x | "
                  f"{ratio('total_s'):.2f}x | {pfh} | | | |")


if __name__ == "__main__":
    main(*sys.argv[1:6])
