#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Open3D side of bench/register/features_bench.sh, and the pair preparation both tools read.

  features_open3d.py prep-hippo HIPPO1.ply HIPPO2.ply VOXEL STARTS OUTDIR
  features_open3d.py prep-mesh MESH.off POINTS VOXEL STARTS OUTDIR
  features_open3d.py run SOURCE.ply TARGET.ply TRUTH.json VOXEL SEED

prep-*: the pairs, voxel-downsampled by Open3D (normals averaged), normals re-estimated
(radius 2 voxels, at most 30 neighbours, kept on the side of the averaged ones), written as
PLY with normals, one source per start rotation: OUTDIR/target.ply, OUTDIR/source_K.ply and
OUTDIR/truth_K.json ({"matrix": 4x4 row-major mapping the source onto the target}).
  hippo: target = hippo1, source = hippo2 turned by a seeded random rotation about its centre.
    There is no published pose: the reference is the best (by fitness at one mean spacing)
    of 20 Open3D RANSAC runs each refined by point-to-plane ICP on the full clouds.
  mesh: POINTS area-uniform samples of the mesh (triangle normals; a .xyz file with normals
    is used as it is, POINTS ignored), split at random between
    two scans (different samplings), each cropped by a plane to 85 % of the shape (about 70 %
    in common), Gaussian noise of 0.2 sample spacings, the source moved by a seeded motion.
run: Open3D's recipe on a prepared pair (compute_fpfh_feature with radius 5 voxels and at most
100 neighbours; registration_ransac_based_on_feature_matching with mutual filter, max
correspondence distance 1.5 voxels, edge-length checker 0.9 and distance checker, 3 points,
RANSACConvergenceCriteria(100000, 0.999)); prints one JSON line with the times and the errors.
"""
import json
import sys
import time

import numpy as np
import open3d as o3d

reg = o3d.pipelines.registration


def random_rotation(rng):
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def motion(r, t):
    m = np.eye(4)
    m[:3, :3] = r
    m[:3, 3] = t
    return m


def downsample(cloud, voxel):
    down = cloud.voxel_down_sample(voxel)
    down.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=2 * voxel, max_nn=30))
    return down


def fpfh(cloud, voxel):
    return reg.compute_fpfh_feature(cloud, o3d.geometry.KDTreeSearchParamHybrid(radius=5 * voxel, max_nn=100))


def ransac(source, target, fs, ft, voxel):
    distance = 1.5 * voxel
    return reg.registration_ransac_based_on_feature_matching(
        source, target, fs, ft, True, distance, reg.TransformationEstimationPointToPoint(False), 3,
        [reg.CorrespondenceCheckerBasedOnEdgeLength(0.9), reg.CorrespondenceCheckerBasedOnDistance(distance)],
        reg.RANSACConvergenceCriteria(100000, 0.999))


def write_pair(outdir, target, sources, truths):
    o3d.io.write_point_cloud(f"{outdir}/target.ply", target)
    for k, (s, m) in enumerate(zip(sources, truths)):
        o3d.io.write_point_cloud(f"{outdir}/source_{k}.ply", s)
        with open(f"{outdir}/truth_{k}.json", "w") as f:
            json.dump({"matrix": m.tolist()}, f)


def prep_hippo(hippo1, hippo2, voxel, starts, outdir):
    target_full = o3d.io.read_point_cloud(hippo1)
    source_full = o3d.io.read_point_cloud(hippo2)
    target = downsample(target_full, voxel)
    source = downsample(source_full, voxel)
    # Reference pose: the best of 20 RANSAC + ICP runs on this pair.
    spacing = float(np.mean(target_full.compute_nearest_neighbor_distance()))
    ft, fs = fpfh(target, voxel), fpfh(source, voxel)
    best = None
    for seed in range(20):
        o3d.utility.random.seed(seed)
        r = ransac(source, target, fs, ft, voxel)
        icp = reg.registration_icp(source_full, target_full, voxel, r.transformation,
                                   reg.TransformationEstimationPointToPlane(),
                                   reg.ICPConvergenceCriteria(max_iteration=100))
        icp = reg.registration_icp(source_full, target_full, 2 * spacing, icp.transformation,
                                   reg.TransformationEstimationPointToPlane(),
                                   reg.ICPConvergenceCriteria(max_iteration=100))
        e = reg.evaluate_registration(source_full, target_full, spacing, icp.transformation)
        if best is None or e.fitness > best[0]:
            best = (e.fitness, e.inlier_rmse, icp.transformation.copy())
    print(f"hippo reference: fitness {best[0]:.4f} at {spacing:.5f} (one spacing), rmse {best[1]:.5f}", file=sys.stderr)
    rng = np.random.default_rng(2026)
    center = source_full.get_center()
    sources, truths = [], []
    for _ in range(starts):
        turn = motion(random_rotation(rng), center) @ motion(np.eye(3), -center)  # about the centre
        s = o3d.geometry.PointCloud(source_full)
        s.transform(turn)
        sources.append(downsample(s, voxel))
        truths.append(best[2] @ np.linalg.inv(turn))
    write_pair(outdir, target, sources, truths)


def prep_mesh(mesh_path, points, voxel, starts, outdir):
    if mesh_path.endswith(".xyz"):  # points with normals (x y z nx ny nz): used as they are
        sample = o3d.io.read_point_cloud(mesh_path, format="xyzn")
    else:
        mesh = o3d.io.read_triangle_mesh(mesh_path)
        mesh.compute_triangle_normals()
        o3d.utility.random.seed(1)
        sample = mesh.sample_points_uniformly(points, use_triangle_normal=True)
    xyz, nrm = np.asarray(sample.points), np.asarray(sample.normals)
    spacing = float(np.mean(sample.compute_nearest_neighbor_distance()))
    size = np.linalg.norm(xyz.max(0) - xyz.min(0))
    rng = np.random.default_rng(7)
    direction = rng.normal(size=3)
    direction /= np.linalg.norm(direction)
    along = xyz @ direction
    low, high = np.quantile(along, [0.15, 0.85])
    half = rng.random(len(xyz)) < 0.5
    src_mask, tgt_mask = half & (along <= high), ~half & (along >= low)

    def cloud(mask, seed):
        c = o3d.geometry.PointCloud()
        noise = np.random.default_rng(seed).normal(scale=0.2 * spacing, size=(mask.sum(), 3))
        c.points = o3d.utility.Vector3dVector(xyz[mask] + noise)
        c.normals = o3d.utility.Vector3dVector(nrm[mask])
        return c

    target = downsample(cloud(tgt_mask, 11), voxel)
    source_full = cloud(src_mask, 12)
    sources, truths = [], []
    for _ in range(starts):
        truth = motion(random_rotation(rng), rng.uniform(-0.5 * size, 0.5 * size, 3))
        s = o3d.geometry.PointCloud(source_full)
        s.transform(np.linalg.inv(truth))
        sources.append(downsample(s, voxel))
        truths.append(truth)
    write_pair(outdir, target, sources, truths)


def errors(estimate, truth, at):
    r = estimate[:3, :3].T @ truth[:3, :3]
    s = 0.5 * np.linalg.norm([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
    angle = np.degrees(np.arctan2(s, 0.5 * (np.trace(r) - 1.0)))
    moved = lambda m: m[:3, :3] @ at + m[:3, 3]
    return float(angle), float(np.linalg.norm(moved(estimate) - moved(truth)))


def run(source_path, target_path, truth_path, voxel, seed):
    source = o3d.io.read_point_cloud(source_path)
    target = o3d.io.read_point_cloud(target_path)
    with open(truth_path) as f:
        truth = np.array(json.load(f)["matrix"])
    o3d.utility.random.seed(seed)
    t0 = time.perf_counter()
    fs, ft = fpfh(source, voxel), fpfh(target, voxel)
    fpfh_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    r = ransac(source, target, fs, ft, voxel)
    ransac_s = time.perf_counter() - t0
    at = 0.5 * (source.get_min_bound() + source.get_max_bound())
    rot, trans = errors(np.asarray(r.transformation), truth, at)
    print(json.dumps({"tool": "open3d", "points_source": len(source.points), "points_target": len(target.points),
                      "fpfh_s": fpfh_s, "pfh_s": None, "ransac_s": ransac_s, "total_s": fpfh_s + ransac_s,
                      "rotation_error_deg": rot, "translation_error": trans, "fitness": r.fitness,
                      "inlier_rmse": r.inlier_rmse, "correspondences": len(r.correspondence_set),
                      "iterations": None, "converged": None}))


if __name__ == "__main__":
    mode = sys.argv[1]
    if mode == "prep-hippo":
        prep_hippo(sys.argv[2], sys.argv[3], float(sys.argv[4]), int(sys.argv[5]), sys.argv[6])
    elif mode == "prep-mesh":
        prep_mesh(sys.argv[2], int(sys.argv[3]), float(sys.argv[4]), int(sys.argv[5]), sys.argv[6])
    elif mode == "run":
        run(sys.argv[2], sys.argv[3], sys.argv[4], float(sys.argv[5]), int(sys.argv[6]))
    else:
        sys.exit(__doc__)
