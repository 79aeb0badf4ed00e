#!/usr/bin/python3
# Open3D peer for bench/segment: segment_plane repeated until fewer than MIN_POINTS are left
# (or a plane below MIN_POINTS), and cluster_dbscan. Prints one JSON line; writes int32 labels.
#   open3d_segment.py planes IN.ply EPSILON MIN_POINTS ITERATIONS MAX_PLANES OUT.labels
#   open3d_segment.py dbscan IN.ply RADIUS OUT.labels
import json, sys, time
import numpy as np
import open3d as o3d

mode, path = sys.argv[1], sys.argv[2]
if hasattr(o3d.utility, "random"):
    o3d.utility.random.seed(1)
pcd = o3d.io.read_point_cloud(path)
n = len(pcd.points)
if mode == "planes":
    eps, min_points, iterations, max_planes, out = float(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5]), int(sys.argv[6]), sys.argv[7]
    labels = np.full(n, -1, dtype=np.int32)
    remaining = np.arange(n)
    t0 = time.perf_counter()
    rest = pcd
    planes = 0
    while len(remaining) >= min_points and planes < max_planes:
        model, inliers = rest.segment_plane(distance_threshold=eps, ransac_n=3, num_iterations=iterations)
        if len(inliers) < min_points:
            break
        labels[remaining[inliers]] = planes
        planes += 1
        rest = rest.select_by_index(inliers, invert=True)
        remaining = np.delete(remaining, inliers)
    seconds = time.perf_counter() - t0
    print(json.dumps({"tool": "open3d", "seconds": round(seconds, 4), "primitives": planes, "unassigned": int((labels < 0).sum())}))
else:
    radius, out = float(sys.argv[3]), sys.argv[4]
    t0 = time.perf_counter()
    labels = np.asarray(pcd.cluster_dbscan(eps=radius, min_points=1), dtype=np.int32)
    seconds = time.perf_counter() - t0
    print(json.dumps({"tool": "open3d", "seconds": round(seconds, 4), "segments": int(labels.max() + 1), "unassigned": int((labels < 0).sum())}))
labels.tofile(out)
