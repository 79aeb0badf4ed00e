#!/usr/bin/python3
# SPDX-License-Identifier: GPL-3.0-or-later
# Open3D peer for bench/reconstruct/run_poisson_bench.sh (Open3D 0.16, /usr/bin/python3).
#   poisson_open3d.py CLOUD.ply DEPTH OUT.ply
# Runs TriangleMesh.create_from_point_cloud_poisson (PoissonRecon inside; scale 1.1, no linear
# fit, all threads) at DEPTH on the cloud and its normals, untrimmed; prints one JSON line:
# seconds (the call alone, reading excluded), peak_rss_mb (whole process: the interpreter and
# Open3D's import included), peak_rss_net_mb (the peak minus the resident size just before the
# call), triangles. Writes the mesh for mesh_metrics_runner.
import json
import resource
import sys
import time

import open3d as o3d


def current_rss_mb():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * resource.getpagesize() / 2**20


def main():
    cloud_path, depth, out_path = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    cloud = o3d.io.read_point_cloud(cloud_path)
    if not cloud.has_normals():
        sys.exit(f"{cloud_path}: no normals")
    before = current_rss_mb()
    start = time.perf_counter()
    mesh, _densities = o3d.geometry.TriangleMesh.create_from_point_cloud_poisson(cloud, depth=depth)
    seconds = time.perf_counter() - start
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    o3d.io.write_triangle_mesh(out_path, mesh)
    print(json.dumps({"tool": "open3d", "points": len(cloud.points), "depth": depth, "seconds": seconds,
                      "peak_rss_mb": peak, "peak_rss_net_mb": max(0.0, peak - before), "triangles": len(mesh.triangles)}))


if __name__ == "__main__":
    main()
