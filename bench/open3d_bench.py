#!/usr/bin/python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""The same stages as pointsurf_bench, done by Open3D (Debian's python3-open3d).

usage: /usr/bin/python3 open3d_bench.py STAGE CLOUD.ply    (or: open3d_bench.py baseline)
Prints one JSON line: stage, points, seconds (wall) and cpu_seconds (user + system, all threads)
of the stage (file reading excluded except for "read"), peak_rss_mb (whole process) and the
stage's quality figure. "baseline" imports numpy and open3d and reads nothing: the interpreter's
own peak memory, to subtract. "knn" queries in the file's order, "knn_spatial" in a Morton
order of the points (computed outside the timed part).
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


def cpu_seconds():
    u = resource.getrusage(resource.RUSAGE_SELF)
    return u.ru_utime + u.ru_stime


def morton_order(points):
    lo, hi = points.min(0), points.max(0)
    q = ((points - lo) / max(float((hi - lo).max()), 1e-300) * 1023).astype(np.uint64)
    code = np.zeros(len(points), dtype=np.uint64)
    for bit in range(10):
        for axis in range(3):
            code |= ((q[:, axis] >> np.uint64(bit)) & np.uint64(1)) << np.uint64(3 * bit + axis)
    return np.argsort(code, kind="stable")


def errors(truth, estimate):
    dots = np.sum(truth * estimate, axis=1)
    angle = np.degrees(np.arccos(np.clip(np.abs(dots), 0.0, 1.0)))
    return float(angle.mean()), float((dots > 0).mean())


def main():
    stage = sys.argv[1]
    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
    out = {"tool": "open3d", "stage": stage}
    if stage == "baseline":
        out["points"] = 0
        out["peak_rss_mb"] = peak_rss_mb()
        print(json.dumps(out))
        return
    path = sys.argv[2]
    t0, c0 = time.perf_counter(), cpu_seconds()
    pcd = o3d.io.read_point_cloud(path)
    read_seconds, read_cpu = time.perf_counter() - t0, cpu_seconds() - c0
    out["points"] = len(pcd.points)
    truth = np.asarray(pcd.normals).copy()
    timer = {}

    def start():
        timer["t"], timer["c"] = time.perf_counter(), cpu_seconds()

    def stop():
        out["seconds"] = time.perf_counter() - timer["t"]
        out["cpu_seconds"] = cpu_seconds() - timer["c"]

    if stage == "read":
        out["seconds"], out["cpu_seconds"] = read_seconds, read_cpu
    elif stage == "write":
        fd, tmp = tempfile.mkstemp(suffix=".ply")
        os.close(fd)
        start()
        o3d.io.write_point_cloud(tmp, pcd, write_ascii=False)
        stop()
        os.remove(tmp)
    elif stage in ("knn", "knn_spatial"):
        array = np.asarray(pcd.points)
        queries = array if stage == "knn" else np.ascontiguousarray(array[morton_order(array)])
        points = o3d.core.Tensor(array, dtype=o3d.core.Dtype.Float64)
        queries = o3d.core.Tensor(queries, dtype=o3d.core.Dtype.Float64)
        start()
        nns = o3d.core.nns.NearestNeighborSearch(points)
        nns.knn_index()
        indices, _ = nns.knn_search(queries, 30)
        stop()
        out["neighbors"] = int(indices.shape[0] * indices.shape[1])
    elif stage == "normals":
        pcd.normals = o3d.utility.Vector3dVector()
        start()
        pcd.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(30))
        stop()
        if len(truth) == len(pcd.points):
            out["mean_angle_deg"] = errors(truth, np.asarray(pcd.normals))[0]
    elif stage == "orient":
        pcd.normals = o3d.utility.Vector3dVector()
        pcd.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(30))
        normals = np.asarray(pcd.normals)
        flip = np.random.default_rng(5).integers(0, 2, len(normals)).astype(bool)
        normals[flip] *= -1
        pcd.normals = o3d.utility.Vector3dVector(normals)
        start()
        pcd.orient_normals_consistent_tangent_plane(10)
        stop()
        share = errors(truth, np.asarray(pcd.normals))[1]
        out["outward_share"] = share
        out["consistent_share"] = max(share, 1.0 - share)
    else:
        sys.exit(f"unknown stage {stage}")
    out["peak_rss_mb"] = peak_rss_mb()
    print(json.dumps(out))


if __name__ == "__main__":
    main()
