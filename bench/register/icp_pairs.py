# SPDX-License-Identifier: GPL-3.0-or-later
"""The pairs of the registration benches (icp_bench.py, icp_pipeline.py) and how a pose is
scored. Each pair builder returns (source, target, truth, start, max_distance) as Open3D clouds
with normals and 4x4 matrices mapping the source onto the target."""
import csv
import os

import numpy as np
import open3d as o3d

# The columns of bench/results/register.csv: icp_bench.py writes task icp (one step, icp),
# icp_pipeline.py task pipeline (a row per step: voxel, normals, fpfh, ransac, icp, total; errors
# on the ransac and total rows).
HEADER = ["commit", "date", "machine", "load", "task", "pair", "tool", "metric", "max_normal_deg", "run", "step", "seconds", "cpu_seconds",
          "iterations", "fitness", "inlier_rmse", "rotation_error_deg", "translation_error", "max_distance", "points_source", "points_target"]


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


def kitten_pair(kitten_path, resampled, truth=None, start_deg=4.0):
    """Two 77 % crops of data/kitten.xyz along a direction (70 % of the source over the target),
    noise 0.1 spacing on the source, moved by the inverse of `truth`; the start is `truth` spoiled
    by start_deg degrees and 2 spacings about the source's centroid."""
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
    truth = motion([0.2, 1.0, 0.3], 20.0, [0.05, -0.08, 0.1]) if truth is None else truth
    source = apply(np.linalg.inv(truth), source)
    c = np.asarray(source.points).mean(axis=0)
    start = truth @ motion([1.0, -0.5, 0.7], start_deg, 2 * h * np.array([0.6, 0.0, 0.8]), about=c)
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
    """A hollow box (wall 0.1) scanned all round as target, its three outer faces towards (1, 1, 1)
    as source, the start 0.07 inwards on each face."""
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


def armadillo_pair(mesh_path):
    """Two independent area-uniform samplings of CGAL's armadillo.off (200k points each, triangle
    normals, Open3D seed 3) cropped to 77 % along a direction (70 % overlap), a known motion, the
    start 4 degrees and 2 spacings off: the size of a real station pair."""
    mesh = o3d.io.read_triangle_mesh(mesh_path)
    mesh.compute_triangle_normals()
    o3d.utility.random.seed(3)
    target, source = (mesh.sample_points_uniformly(200000, use_triangle_normal=True) for _ in range(2))
    d = np.array([1.0, 0.3, -0.2]) / np.linalg.norm([1.0, 0.3, -0.2])

    def crop(c, lo, hi):
        rank = np.argsort(np.asarray(c.points) @ d, kind="stable")
        return c.select_by_index(rank[int(lo * len(rank)):int(hi * len(rank))].tolist())

    target, source = crop(target, 0.0, 0.77), crop(source, 0.23, 1.0)
    h = spacing(source)
    truth = motion([0.2, 1.0, 0.3], 20.0, [5.0, -8.0, 10.0])
    source = apply(np.linalg.inv(truth), source)
    c = np.asarray(source.points).mean(axis=0)
    start = truth @ motion([1.0, -0.5, 0.7], 4.0, 2 * h * np.array([0.6, 0.0, 0.8]), about=c)
    return source, target, truth, start, 3 * h


def hippo_pair(hippo1, hippo2):
    """hippo2 onto hippo1; the start from Open3D's FPFH + RANSAC (seeded, voxel 3 spacings), the
    reference pose Open3D point-to-plane from it to a standstill (500 iterations, thresholds
    1e-12) within 3 spacings."""
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


def score(source, target, dist, m, truth):
    e = o3d.pipelines.registration.evaluate_registration(source, target, dist, m)
    c = np.asarray(source.points).mean(axis=0)
    rot = angle_deg(m[:3, :3].T @ truth[:3, :3])
    trans = float(np.linalg.norm((m[:3, :3] @ c + m[:3, 3]) - (truth[:3, :3] @ c + truth[:3, 3])))
    return e.fitness, e.inlier_rmse, rot, trans


def open_csv(path):
    """The CSV opened for appending (its header written when new) and its writer."""
    new = not os.path.exists(path)
    out = open(path, "a", newline="")
    writer = csv.writer(out)
    if new:
        writer.writerow(HEADER)
    return out, writer


def write_pair(work, name, source, target):
    """WORK/NAME/source.ply and target.ply (with normals); returns the folder."""
    d = os.path.join(work, name)
    os.makedirs(d, exist_ok=True)
    o3d.io.write_point_cloud(os.path.join(d, "source.ply"), source)
    o3d.io.write_point_cloud(os.path.join(d, "target.ply"), target)
    return d
