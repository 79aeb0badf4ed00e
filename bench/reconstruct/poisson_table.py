#!/usr/bin/python3
# SPDX-License-Identifier: GPL-3.0-or-later
# Table and raw CSV rows of bench/reconstruct/run_poisson_bench.sh.
#   poisson_table.py RESULTS.jsonl CSV COMMIT
# Medians per (mesh, points, cloud, depth, tool); ratios are pointsurf / the better peer (the
# faster for time, the smaller for memory, the lower for Chamfer): below 1, pointsurf is better.
import sys

from tables import find, fmt, load, median, metrics, results_csv


def main():
    rows = load(sys.argv[1])
    csv_path, commit = sys.argv[2], sys.argv[3]
    out, date, machine = results_csv(csv_path, [
        "commit", "date", "machine", "mesh", "points", "cloud", "depth", "tool", "runs", "load1_median", "seconds_median",
        "seconds_min", "seconds_max", "time_ratio_to_faster_peer", "peak_rss_mb_median", "peak_rss_net_mb_median",
        "memory_ratio_to_smaller_peer", "triangles", "boundary_edges", "non_manifold_edges", "non_manifold_vertices",
        "components", "chamfer", "chamfer_ratio_to_better_peer", "hausdorff", "failed"])
    keys = sorted({(r["mesh"], r["points"], r["kind"], r["depth"]) for r in rows if "mesh" in r},
                  key=lambda k: (k[0], k[1], ["clean", "noisy"].index(k[2]), k[3]))
    tools = [t for t in ["pointsurf", "open3d", "pcl"] if any(r.get("tool") == t for r in rows)]
    print("| mesh | points | cloud | depth | tool | seconds | time ratio | peak MB | net MB | memory ratio | Chamfer | Chamfer ratio | "
          "Hausdorff | non-manifold edges | boundary edges | triangles | load |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for mesh, n, kind, depth in keys:
        match = dict(mesh=mesh, points=n, kind=kind, depth=depth)
        sec = {t: median(rows, "seconds", tool=t, **match) for t in tools}
        mem = {t: median(rows, "peak_rss_mb", tool=t, **match) for t in tools}
        net = {t: median(rows, "peak_rss_net_mb", tool=t, **match) for t in tools}
        met = {t: metrics(rows, tool=t, **match) for t in tools}
        cham = {t: find(met[t], "chamfer") for t in tools}

        def best_peer(values, pick=min):
            peers = [v for t, v in values.items() if t != "pointsurf" and v is not None]
            return pick(peers) if peers else None

        def ratio_to(values):
            mine, peer = values.get("pointsurf"), best_peer(values)
            return mine / peer if mine is not None and peer else None

        for t in tools:
            runs = [r for r in rows if r.get("tool") == t and "run" in r and all(r.get(k) == v for k, v in match.items())]
            secs = [r["seconds"] for r in runs if "seconds" in r]
            failed = next((r["failed"] for r in runs if "failed" in r), None)
            load1 = median(rows, "load1", tool=t, **match)
            m = met[t]
            mine = t == "pointsurf"
            tr, mr, cr = (ratio_to(sec), ratio_to(mem), ratio_to(cham)) if mine else (None, None, None)
            print(f"| {mesh} | {n} | {kind} | {depth} | {t} | {fmt(sec[t], 2) if secs else (failed or '-')} | {fmt(tr)} | "
                  f"{fmt(mem[t], 0)} | {fmt(net[t], 0)} | {fmt(mr)} | {fmt(cham[t], 6)} | {fmt(cr)} | "
                  f"{fmt(find(m, 'hausdorff'), 5)} | {fmt(find(m, 'non_manifold_edges'))} | {fmt(find(m, 'boundary_edges'))} | "
                  f"{fmt(find(m, 'triangles'))} | {fmt(load1, 1)} |")
            out.writerow([commit, date, machine, mesh, n, kind, depth, t, len(secs), load1, sec[t], min(secs) if secs else None,
                          max(secs) if secs else None, tr, mem[t], net[t], mr, find(m, "triangles"), find(m, "boundary_edges"),
                          find(m, "non_manifold_edges"), find(m, "non_manifold_vertices"), find(m, "components"), cham[t], cr,
                          find(m, "hausdorff"), failed])


if __name__ == "__main__":
    main()
