#!/usr/bin/env python3
"""Surface-area change of simplification (the paper's measure, 0.43 % for its regional method).

For each input cloud (with oriented normals) and each ratio: CGAL's hierarchy simplification
(Pauly et al. 2002) is run first, its cluster size bisected so that its output is the point count
nearest to ratio x N; every pointsurf method is then asked for exactly that count (grid within
about 3 %), so that all methods are compared at equal reduction. Every cloud, the full one
included, is meshed by the same region-growing reconstruction; the area change is
|A_simplified - A_full| / A_full (areas by Open3D), printed next to the holes of each mesh.

  area_bench.py CLI CGAL_BIN WORK CSV RATIOS NAME=CLOUD [NAME=CLOUD ...]

Called by run_area_bench.sh. Appends raw rows to CSV (commit, date, machine) and prints a
markdown table per input."""
import json
import os
import subprocess
import sys

import numpy as np
import open3d as o3d

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "reconstruct"))
import tables  # noqa: E402  (results_csv: header once, date, machine)

METHODS = ("regional", "cgal-hierarchy", "curvature", "curvature-distance", "grid", "random")
# The measure's own noise: regional again at 1 % fewer and 1 % more points (a different mesh
# through almost the same points), not a method.
SENSITIVITY = (("regional-1%", 0.99), ("regional+1%", 1.01))
# Regional without its rim step (--no-keep-boundary), at the same count.
VARIANTS = {"regional-no-boundary": ["--no-keep-boundary"]}
CGAL_VARIATION = 0.01  # CGAL's own example value: clusters split further where the surface bends


def run(*args):
    subprocess.run([str(a) for a in args], check=True, stdout=subprocess.DEVNULL)


def reconstruct(cli, cloud, mesh, report):
    run(cli, "reconstruct", cloud, mesh, "-q", "--report", report)
    r = json.load(open(report))
    holes = next((s["counts"]["holes"] for s in r["stages"] if "holes" in s.get("counts", {})), -1)
    return o3d.io.read_triangle_mesh(mesh).get_surface_area(), holes


def cgal_at(cgal, xyz, out, wanted):
    """CGAL's hierarchy output nearest `wanted` points: bisect the cluster size (the output
    shrinks as the size grows)."""
    def count(size):
        line = subprocess.run([cgal, xyz, str(size), str(CGAL_VARIATION), out], check=True, capture_output=True,
                              text=True).stdout
        return json.loads(line)["output_points"]
    lo, hi = 2, 4096
    best = None
    while lo <= hi:
        mid = (lo + hi) // 2
        c = count(mid)
        if best is None or abs(c - wanted) < abs(best[1] - wanted):
            best = (mid, c)
        if c > wanted:
            lo = mid + 1
        elif c < wanted:
            hi = mid - 1
        else:
            break
    return best[0], count(best[0])


def with_normals(full, xyz_out, ply_out):
    """CGAL keeps input points: give each its input normal (nearest input point)."""
    pts = np.loadtxt(xyz_out, ndmin=2)
    tree = o3d.geometry.KDTreeFlann(full)
    normals = np.asarray(full.normals)
    nn = [tree.search_knn_vector_3d(p, 1)[1][0] for p in pts]
    pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pts))
    pc.normals = o3d.utility.Vector3dVector(normals[nn])
    o3d.io.write_point_cloud(ply_out, pc)


def main():
    cli, cgal, work, csv_path, ratios = sys.argv[1:6]
    inputs = [a.split("=", 1) for a in sys.argv[6:]]
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    out, date, machine = tables.results_csv(
        csv_path, ["commit", "date", "machine", "input", "points", "ratio", "method", "output_points", "area", "area_change_pct",
                   "holes", "full_area", "full_holes", "cgal_size"])
    os.makedirs(work, exist_ok=True)
    for name, cloud in inputs:
        d = os.path.join(work, name)
        os.makedirs(d, exist_ok=True)
        full_cloud = o3d.io.read_point_cloud(cloud)
        n = len(full_cloud.points)
        xyz = os.path.join(d, "full.xyz")
        np.savetxt(xyz, np.asarray(full_cloud.points), fmt="%.17g")
        full_area, full_holes = reconstruct(cli, cloud, f"{d}/full_mesh.ply", f"{d}/full.json")
        print(f"\n### {name}: {n} points, full mesh area {full_area:.6g}, {full_holes} holes\n")
        print("| ratio | method | points | area change | holes |")
        print("|---|---|---|---|---|")
        for ratio in ratios.split():
            size, m = cgal_at(cgal, xyz, f"{d}/cgal_{ratio}.xyz", round(float(ratio) * n))
            for method in METHODS + tuple(VARIANTS) + tuple(label for label, _ in SENSITIVITY):
                print(f"[area] {name} {method} {ratio}", file=sys.stderr)
                simplified = f"{d}/{method}_{ratio}.ply"
                if method == "cgal-hierarchy":
                    with_normals(full_cloud, f"{d}/cgal_{ratio}.xyz", simplified)
                elif method in VARIANTS:
                    run(cli, "simplify", cloud, simplified, "--method", "regional", "--count", m, "-q", *VARIANTS[method])
                elif method in dict(SENSITIVITY):
                    run(cli, "simplify", cloud, simplified, "--method", "regional", "--count", round(m * dict(SENSITIVITY)[method]), "-q")
                else:
                    run(cli, "simplify", cloud, simplified, "--method", method, "--count", m, "-q")
                points = len(o3d.io.read_point_cloud(simplified).points)
                area, holes = reconstruct(cli, simplified, f"{d}/{method}_{ratio}_mesh.ply", f"{d}/{method}_{ratio}.json")
                change = 100 * abs(area - full_area) / full_area
                print(f"| {ratio} | {method} | {points} | {change:.2f} % | {holes} |", flush=True)
                out.writerow([commit, date, machine, name, n, ratio, method, points, f"{area:.6g}", f"{change:.3f}", holes,
                              f"{full_area:.6g}", full_holes, size if method == "cgal-hierarchy" else ""])


if __name__ == "__main__":
    main()
