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
  wall      a hollow box (wall 0.1) scanned all round as target, three outer faces as source,
            start 0.07 inwards on each face: the case the normal-angle check is for

  icp_bench.py BUILD_DIR REPEATS WORK HIPPO1 HIPPO2 KITTEN CSV COMMIT DATE MACHINE
Appends raw rows to CSV and prints a Markdown table of medians.
"""
import csv
import json
import os
import statistics
import subprocess
import sys
import time

import numpy as np
import open3d as o3d

HERE = os.path.dirname(os.path.abspath(__file__))
build, repeats, work, hippo1, hippo2, kitten_path, csv_path, commit, date, machine = sys.argv[1:]
repeats = int(repeats)
runner = os.path.join(build, "bench", "icp_runner")
os.makedirs(work, exist_ok=True)
ITERATIONS, RELATIVE, INNER = 50, 1e-6, 5
rng = np.random.default_rng(2026)


def cloud(points, normals):
    c = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    c.normals = o3d.utility.Vector3dVector(normals)
    return c


def rotation(axis, deg):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    return o3d.geometry.get_rotation_matrix_from_axis_angle(axis * np.radians(deg))


def motion(axis, deg, t, about=np.zeros(3)):
    m = np.eye(4)
    m[:3, :3] = rotation(axis, deg)
    m[:3, 3] = about - m[:3, :3] @ about + np.asarray(t)
    return m


def apply(m, c):
    c = o3d.geometry.PointCloud(c)
    c.transform(m)
    return c


def spacing(c):
    return float(np.mean(c.compute_nearest_neighbor_distance()))


def angle_deg(r):
    return float(np.degrees(np.arccos(np.clip((np.trace(r) - 1) / 2, -1, 1))))


def kitten_pair(resampled):
    a = np.loadtxt(kitten_path)
    p, n = a[:, :3], a[:, 3:]
    d = np.array([1.0, 0.3, -0.2])
    rank = np.argsort(p @ d, kind="stable")
    count = len(p)
    t_idx = [rank[r] for r in range(int(0.77 * count)) if not resampled or r % 2 == 0]
    s_idx = [rank[r] for r in range(int(0.23 * count), count) if not resampled or r % 2 == 1]
    target, source = cloud(p[t_idx], n[t_idx]), cloud(p[s_idx], n[s_idx])
    h = spacing(source)
    noisy = np.asarray(source.points) + np.random.default_rng(7).normal(0, 0.1 * h, (len(s_idx), 3))
    source.points = o3d.utility.Vector3dVector(noisy)
    truth = motion([0.2, 1.0, 0.3], 20.0, [0.05, -0.08, 0.1])
    source = apply(np.linalg.inv(truth), source)
    c = np.asarray(source.points).mean(axis=0)
    start = truth @ motion([1.0, -0.5, 0.7], 4.0, 2 * h * np.array([0.6, 0.0, 0.8]), about=c)
    return source, target, truth, start, 3 * h


def cube_points(count, half, seed):
    g = np.random.default_rng(seed)
    face = g.integers(0, 6, count)
    axis, sign = face // 2, np.where(face % 2 == 0, 1.0, -1.0)
    p = g.uniform(-half, half, (count, 3))
    n = np.zeros((count, 3))
    p[np.arange(count), axis] = sign * half
    n[np.arange(count), axis] = sign
    return p, n


def wall_pair():
    wall = 0.1
    po, no = cube_points(24000, 1.0, 1)
    pi, ni = cube_points(21000, 1.0 - wall, 2)
    target = cloud(np.vstack([po, pi]), np.vstack([no, -ni]))
    ps, ns = cube_points(24000, 1.0, 3)
    seen = ns @ np.ones(3) > 0
    source = cloud(ps[seen] + np.random.default_rng(4).normal(0, 0.002, (seen.sum(), 3)), ns[seen])
    truth = motion([0.3, -1.0, 0.5], 10.0, [0.1, 0.15, -0.05])
    source = apply(np.linalg.inv(truth), source)
    start = motion([1, 0, 0], 0.0, [-0.7 * wall] * 3) @ truth
    return source, target, truth, start, 0.15


def hippo_pair():
    source, target = o3d.io.read_point_cloud(hippo2), o3d.io.read_point_cloud(hippo1)
    h = spacing(source)
    v = 3 * h
    o3d.utility.random.seed(1)

    def prep(c):
        d = c.voxel_down_sample(v)
        f = o3d.pipelines.registration.compute_fpfh_feature(d, o3d.geometry.KDTreeSearchParamHybrid(radius=5 * v, max_nn=100))
        return d, f

    (sd, sf), (td, tf) = prep(source), prep(target)
    reg = o3d.pipelines.registration
    g = reg.registration_ransac_based_on_feature_matching(
        sd, td, sf, tf, True, 1.5 * v, reg.TransformationEstimationPointToPoint(False), 3,
        [reg.CorrespondenceCheckerBasedOnEdgeLength(0.9), reg.CorrespondenceCheckerBasedOnDistance(1.5 * v)],
        reg.RANSACConvergenceCriteria(100000, 0.999))
    start = g.transformation
    ref = reg.registration_icp(source, target, 3 * h, start, reg.TransformationEstimationPointToPlane(),
                               reg.ICPConvergenceCriteria(1e-12, 1e-12, 500)).transformation
    return source, target, ref, start, 3 * h


def write_pcd(path, c):
    o3d.io.write_point_cloud(path, o3d.geometry.PointCloud(c.points), write_ascii=True)


def run_pcl(pair_dir, dist):
    """pcl_icp target source_started: its process time less that of a run that finds no pair
    (reading, writing and starting the process), and the transform it prints."""
    def once(d):
        cwd = os.path.join(pair_dir, "pcl_out")
        os.makedirs(cwd, exist_ok=True)
        t0 = time.perf_counter()
        out = subprocess.run(["pcl_icp", os.path.join(pair_dir, "target.pcd"), os.path.join(pair_dir, "started.pcd"), "-d", str(d),
                              "-i", str(ITERATIONS)], cwd=cwd, capture_output=True, text=True, check=True).stdout
        return time.perf_counter() - t0, out
    full, out = once(dist)
    idle, _ = once(1e-12)
    def numbers(line):
        try:
            return [float(x) for x in line.split()]
        except ValueError:
            return []
    rows = [r for r in map(numbers, out.splitlines()) if len(r) == 4]
    return max(full - idle, 0.0), np.array(rows[-4:])


def score(source, target, dist, m, truth):
    e = o3d.pipelines.registration.evaluate_registration(source, target, dist, m)
    c = np.asarray(source.points).mean(axis=0)
    rot = angle_deg(m[:3, :3].T @ truth[:3, :3])
    trans = float(np.linalg.norm((m[:3, :3] @ c + m[:3, 3]) - (truth[:3, :3] @ c + truth[:3, 3])))
    return e.fitness, e.inlier_rmse, rot, trans


pairs = {"hippo": hippo_pair(), "kitten": kitten_pair(False), "kitten-resampled": kitten_pair(True), "wall": wall_pair()}
configs = [("pointsurf", "point", 45), ("pointsurf", "point", 180), ("pointsurf", "plane", 45), ("pointsurf", "plane", 180),
           ("open3d", "point", 180), ("open3d", "plane", 180), ("open3d-1t", "point", 180), ("open3d-1t", "plane", 180),
           ("pcl", "point", 180)]
new = not os.path.exists(csv_path)
out = open(csv_path, "a", newline="")
w = csv.writer(out)
if new:
    w.writerow(["commit", "date", "machine", "load", "pair", "tool", "metric", "max_normal_deg", "run", "seconds", "iterations",
                "fitness", "inlier_rmse", "rotation_error_deg", "translation_error", "max_distance", "points_source", "points_target"])
files = {}
for name, (source, target, truth, start, dist) in pairs.items():
    d = os.path.join(work, name)
    os.makedirs(d, exist_ok=True)
    o3d.io.write_point_cloud(os.path.join(d, "source.ply"), source)
    o3d.io.write_point_cloud(os.path.join(d, "target.ply"), target)
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
                seconds, iterations, m = j["seconds"], j["iterations"], np.array(j["matrix"]).reshape(4, 4)
            elif tool.startswith("open3d"):
                env = dict(os.environ, **({"OMP_NUM_THREADS": "1"} if tool == "open3d-1t" else {}))
                text = subprocess.run([sys.executable, os.path.join(HERE, "icp_open3d.py"), *args, metric, str(dist), str(ITERATIONS),
                                       str(RELATIVE), str(INNER)], capture_output=True, text=True, check=True, env=env).stdout
                j = json.loads(text.strip().splitlines()[-1])
                seconds, iterations, m = j["seconds"], text.count("ICP Iteration #"), np.array(j["matrix"]).reshape(4, 4)
            else:
                seconds, m = run_pcl(d, dist)
                m = m @ start
                iterations = -1
            fit, rmse, rot, trans = score(source, target, dist, m, truth)
            row = [commit, date, machine, f"{load:.2f}", name, tool, metric, normal_deg, r, f"{seconds:.6f}", iterations, f"{fit:.6f}",
                   f"{rmse:.6g}", f"{rot:.6g}", f"{trans:.6g}", f"{dist:.6g}", len(source.points), len(target.points)]
            w.writerow(row)
            out.flush()
            results.append(dict(zip(["pair", "tool", "metric", "normal", "seconds", "iterations", "fitness", "rmse", "rot", "trans"],
                                    [name, tool, metric, normal_deg, seconds, iterations, fit, rmse, rot, trans])))

print("| pair | tool | metric | normal check | median ms | iterations | fitness | inlier RMSE | rotation error (deg) | translation error |")
print("|---|---|---|---|---|---|---|---|---|---|")
for name in pairs:
    for tool, metric, normal_deg in configs:
        rs = [x for x in results if x["pair"] == name and x["tool"] == tool and x["metric"] == metric and x["normal"] == normal_deg]
        last = rs[-1]
        check = f"{normal_deg} deg" if tool == "pointsurf" and normal_deg < 180 else "off"
        its = "?" if last["iterations"] < 0 else last["iterations"]
        print(f"| {name} | {tool} | {metric} | {check} | {1000 * statistics.median(x['seconds'] for x in rs):.1f} | {its} | "
              f"{last['fitness']:.4f} | {last['rmse']:.4g} | {last['rot']:.4f} | {last['trans']:.3g} |")
