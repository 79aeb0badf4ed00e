#!/usr/bin/python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""The same stages as pointsurf_bench, done by Open3D (Debian's python3-open3d).

usage: /usr/bin/python3 open3d_bench.py STAGE CLOUD.ply
Prints one JSON line: stage, points, seconds (file reading excluded except for "read"),
peak_rss_mb (whole process) and the stage's quality figure.
"""
import json
import os
import resource
import sys
import tempfile
import time

import numpy as np
import open3d as o3d


def peak_rss_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def errors(truth, estimate):
    dots = np.sum(truth * estimate, axis=1)
    angle = np.degrees(np.arccos(np.clip(np.abs(dots), 0.0, 1.0)))
    return float(angle.mean()), float((dots > 0).mean())


def main():
    stage, path = sys.argv[1], sys.argv[2]
    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
    out = {"tool": "open3d", "stage": stage}
    t0 = time.perf_counter()
    pcd = o3d.io.read_point_cloud(path)
    read_seconds = time.perf_counter() - t0
    out["points"] = len(pcd.points)
    truth = np.asarray(pcd.normals).copy()
    if stage == "read":
        out["seconds"] = read_seconds
    elif stage == "write":
        fd, tmp = tempfile.mkstemp(suffix=".ply")
        os.close(fd)
        t0 = time.perf_counter()
        o3d.io.write_point_cloud(tmp, pcd, write_ascii=False)
        out["seconds"] = time.perf_counter() - t0
        os.remove(tmp)
    elif stage == "knn":
        points = o3d.core.Tensor(np.asarray(pcd.points), dtype=o3d.core.Dtype.Float64)
        t0 = time.perf_counter()
        nns = o3d.core.nns.NearestNeighborSearch(points)
        nns.knn_index()
        indices, _ = nns.knn_search(points, 30)
        out["seconds"] = time.perf_counter() - t0
        out["neighbors"] = int(indices.shape[0] * indices.shape[1])
    elif stage == "normals":
        pcd.normals = o3d.utility.Vector3dVector()
        t0 = time.perf_counter()
        pcd.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(30))
        out["seconds"] = time.perf_counter() - t0
        out["mean_angle_deg"] = errors(truth, np.asarray(pcd.normals))[0]
    elif stage == "orient":
        pcd.normals = o3d.utility.Vector3dVector()
        pcd.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(30))
        normals = np.asarray(pcd.normals)
        flip = np.random.default_rng(5).integers(0, 2, len(normals)).astype(bool)
        normals[flip] *= -1
        pcd.normals = o3d.utility.Vector3dVector(normals)
        t0 = time.perf_counter()
        pcd.orient_normals_consistent_tangent_plane(10)
        out["seconds"] = time.perf_counter() - t0
        share = errors(truth, np.asarray(pcd.normals))[1]
        out["outward_share"] = share
        out["consistent_share"] = max(share, 1.0 - share)
    else:
        sys.exit(f"unknown stage {stage}")
    out["peak_rss_mb"] = peak_rss_mb()
    print(json.dumps(out))


if __name__ == "__main__":
    main()
