# SPDX-License-Identifier: GPL-3.0-or-later
"""Open3D's global-registration recipe, step by step, with icp_pipeline_runner's parameters
(voxel v: voxel_down_sample(v); estimate_normals(hybrid 2 v, 30); compute_fpfh_feature(hybrid
5 v, 100); registration_ransac_based_on_feature_matching(mutual filter, 1.5 v, point-to-point,
3 points, edge-length 0.9 and distance checkers, RANSACConvergenceCriteria(100000, 0.999));
registration_icp point-to-plane on the full clouds within 0.4 v, 30 iterations). One JSON line:
per-step median wall seconds of REPEATS runs, the RANSAC and final matrices.
  icp_pipeline_open3d.py SOURCE TARGET VOXEL SEED REPEATS"""
import json
import statistics
import sys
import time

import numpy as np
import open3d as o3d

reg = o3d.pipelines.registration
src, tgt, voxel, seed, repeats = sys.argv[1:]
v = float(voxel)
source, target = o3d.io.read_point_cloud(src), o3d.io.read_point_cloud(tgt)
steps = {k: [] for k in ("voxel", "normals", "fpfh", "ransac", "icp", "total")}
o3d.utility.random.seed(int(seed))
for _ in range(int(repeats)):
    t0 = start = time.perf_counter()
    sd, td = source.voxel_down_sample(v), target.voxel_down_sample(v)
    steps["voxel"].append(time.perf_counter() - t0)
    t0 = time.perf_counter()
    for c in (sd, td):
        c.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=2 * v, max_nn=30))
    steps["normals"].append(time.perf_counter() - t0)
    t0 = time.perf_counter()
    fs, ft = (reg.compute_fpfh_feature(c, o3d.geometry.KDTreeSearchParamHybrid(radius=5 * v, max_nn=100)) for c in (sd, td))
    steps["fpfh"].append(time.perf_counter() - t0)
    t0 = time.perf_counter()
    g = reg.registration_ransac_based_on_feature_matching(
        sd, td, fs, ft, True, 1.5 * v, reg.TransformationEstimationPointToPoint(False), 3,
        [reg.CorrespondenceCheckerBasedOnEdgeLength(0.9), reg.CorrespondenceCheckerBasedOnDistance(1.5 * v)],
        reg.RANSACConvergenceCriteria(100000, 0.999))
    steps["ransac"].append(time.perf_counter() - t0)
    t0 = time.perf_counter()
    f = reg.registration_icp(source, target, 0.4 * v, g.transformation, reg.TransformationEstimationPointToPlane(),
                             reg.ICPConvergenceCriteria(1e-6, 1e-6, 30))
    steps["icp"].append(time.perf_counter() - t0)
    steps["total"].append(time.perf_counter() - start)
out = {k: statistics.median(x) for k, x in steps.items()}
out.update(tool="open3d", down_source=len(sd.points), down_target=len(td.points), ransac_iterations=-1, icp_iterations=-1,
           ransac_matrix=np.asarray(g.transformation).ravel().tolist(), matrix=np.asarray(f.transformation).ravel().tolist())
print(json.dumps(out))
