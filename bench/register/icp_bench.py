# SPDX-License-Identifier: GPL-3.0-or-later
"""ICP against Open3D registration_icp and PCL pcl_icp on the same pairs, same start, same max
correspondence distance and iteration cap; pointsurf with and without the normal-angle check.
Interleaved rounds; every result is scored the same way (Open3D evaluate_registration at the
pair's max distance; rotation and translation error against the known motion, the translation
error measured at the source's centroid).

Pairs:
  hippo     CGAL demo hippo2 onto hippo1 (real scans, no known motion): start from Open3D's
            FPFH + RANSAC (seeded), errors against a reference = Open3D point-to-plane run to a
            standstill (500 iterations, thresholds 1e-12) from that start
  kitten    data/kitten.xyz: target the first 77 % along a direction, source the last 77 % (70 %
            of it overlaps), noise 0.1 spacing, known motion; start 4 degrees and 2 spacings off
  kitten-resampled  the same, but the target keeps the even-ranked points and the source the
            odd-ranked ones: no point in both, as with two real scans
  armadillo two samplings of CGAL's armadillo.off, 154k points each, 70 % overlap, known motion,
            start 4 degrees and 2 spacings off
  wall      a hollow box (wall 0.1) scanned all round as target, three outer faces as source,
            start 0.07 inwards on each face: the case the normal-angle check is for

  icp_bench.py BUILD_DIR REPEATS WORK HIPPO1 HIPPO2 KITTEN ARMADILLO CSV COMMIT DATE MACHINE
Appends raw rows to CSV and prints a Markdown table of medians.
"""
import json
import os
import resource
import statistics
import subprocess
import sys
import time

import numpy as np
import open3d as o3d

from icp_pairs import apply, armadillo_pair, hippo_pair, kitten_pair, open_csv, score, wall_pair, write_pair

HERE = os.path.dirname(os.path.abspath(__file__))
build, repeats, work, hippo1, hippo2, kitten_path, armadillo, csv_path, commit, date, machine = sys.argv[1:]
repeats = int(repeats)
runner = os.path.join(build, "bench", "icp_runner")
os.makedirs(work, exist_ok=True)
ITERATIONS, RELATIVE, INNER = 50, 1e-6, 3


def write_pcd(path, c):
    o3d.io.write_point_cloud(path, o3d.geometry.PointCloud(c.points), write_ascii=True)


def run_pcl(pair_dir, dist):
    """pcl_icp target source_started: its process time less that of a run that finds no pair
    (reading, writing and starting the process), and the transform it prints."""
    def children_cpu():
        u = resource.getrusage(resource.RUSAGE_CHILDREN)
        return u.ru_utime + u.ru_stime

    def once(d):
        cwd = os.path.join(pair_dir, "pcl_out")
        os.makedirs(cwd, exist_ok=True)
        t0, c0 = time.perf_counter(), children_cpu()
        out = subprocess.run(["pcl_icp", os.path.join(pair_dir, "target.pcd"), os.path.join(pair_dir, "started.pcd"), "-d", str(d),
                              "-i", str(ITERATIONS)], cwd=cwd, capture_output=True, text=True, check=True).stdout
        return time.perf_counter() - t0, children_cpu() - c0, out
    full, full_cpu, out = once(dist)
    idle, idle_cpu, _ = once(1e-12)
    def numbers(line):
        try:
            return [float(x) for x in line.split()]
        except ValueError:
            return []
    rows = [r for r in map(numbers, out.splitlines()) if len(r) == 4]
    return max(full - idle, 0.0), max(full_cpu - idle_cpu, 0.0), np.array(rows[-4:])


pairs = {"hippo": hippo_pair(hippo1, hippo2), "kitten": kitten_pair(kitten_path, False), "kitten-resampled": kitten_pair(kitten_path, True),
         "armadillo": armadillo_pair(armadillo), "wall": wall_pair()}
configs = [("pointsurf", "point", 45), ("pointsurf", "point", 180), ("pointsurf", "plane", 45), ("pointsurf", "plane", 180),
           ("open3d", "point", 180), ("open3d", "plane", 180), ("open3d-1t", "point", 180), ("open3d-1t", "plane", 180),
           ("pcl", "point", 180)]
out, w = open_csv(csv_path)
files = {}
for name, (source, target, truth, start, dist) in pairs.items():
    d = write_pair(work, name, source, target)
    np.savetxt(os.path.join(d, "start.txt"), start.reshape(1, 16))
    write_pcd(os.path.join(d, "target.pcd"), target)
    write_pcd(os.path.join(d, "started.pcd"), apply(start, source))
    files[name] = d
    s0 = score(source, target, dist, start, truth)
    print(f"{name}: {len(source.points)} -> {len(target.points)} points, max distance {dist:.4g}, start off by {s0[2]:.2f} deg / "
          f"{s0[3]:.4g}", file=sys.stderr)

results = []
for r in range(1, repeats + 1):
    load = os.getloadavg()[0]
    print(f"round {r}/{repeats} (load {load:.2f})", file=sys.stderr)
    for name, (source, target, truth, start, dist) in pairs.items():
        d = files[name]
        args = [os.path.join(d, "source.ply"), os.path.join(d, "target.ply"), os.path.join(d, "start.txt")]
        for tool, metric, normal_deg in configs:
            load = os.getloadavg()[0]
            if tool == "pointsurf":
                j = json.loads(subprocess.run([runner, *args, metric, str(dist), str(ITERATIONS), str(normal_deg), str(RELATIVE), str(INNER)],
                                              capture_output=True, text=True, check=True).stdout)
                seconds, cpu, iterations, m = j["seconds"], j["cpu_seconds"], j["iterations"], np.array(j["matrix"]).reshape(4, 4)
            elif tool.startswith("open3d"):
                env = dict(os.environ, **({"OMP_NUM_THREADS": "1"} if tool == "open3d-1t" else {}))
                text = subprocess.run([sys.executable, os.path.join(HERE, "icp_open3d.py"), *args, metric, str(dist), str(ITERATIONS),
                                       str(RELATIVE), str(INNER)], capture_output=True, text=True, check=True, env=env).stdout
                j = json.loads(text.strip().splitlines()[-1])
                seconds, cpu, iterations = j["seconds"], j["cpu_seconds"], text.count("ICP Iteration #")
                m = np.array(j["matrix"]).reshape(4, 4)
            else:
                seconds, cpu, m = run_pcl(d, dist)
                m = m @ start
                iterations = -1
            fit, rmse, rot, trans = score(source, target, dist, m, truth)
            row = [commit, date, machine, f"{load:.2f}", "icp", name, tool, metric, normal_deg, r, "icp", f"{seconds:.6f}", f"{cpu:.6f}",
                   iterations, f"{fit:.6f}",
                   f"{rmse:.6g}", f"{rot:.6g}", f"{trans:.6g}", f"{dist:.6g}", len(source.points), len(target.points)]
            w.writerow(row)
            out.flush()
            results.append(dict(zip(["pair", "tool", "metric", "normal", "seconds", "cpu", "iterations", "fitness", "rmse", "rot", "trans"],
                                    [name, tool, metric, normal_deg, seconds, cpu, iterations, fit, rmse, rot, trans])))

print("| pair | tool | metric | normal check | median ms | median CPU ms | iterations | fitness | inlier RMSE | rotation error (deg) | translation error |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
for name in pairs:
    for tool, metric, normal_deg in configs:
        rs = [x for x in results if x["pair"] == name and x["tool"] == tool and x["metric"] == metric and x["normal"] == normal_deg]
        last = rs[-1]
        check = f"{normal_deg} deg" if tool == "pointsurf" and normal_deg < 180 else "off"
        its = "?" if last["iterations"] < 0 else last["iterations"]
        print(f"| {name} | {tool} | {metric} | {check} | {1000 * statistics.median(x['seconds'] for x in rs):.1f} | "
              f"{1000 * statistics.median(x['cpu'] for x in rs):.1f} | {its} | "
              f"{last['fitness']:.4f} | {last['rmse']:.4g} | {last['rot']:.4f} | {last['trans']:.3g} |")
