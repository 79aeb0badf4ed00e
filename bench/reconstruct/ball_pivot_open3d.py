#!/usr/bin/python3
# SPDX-License-Identifier: GPL-3.0-or-later
# Open3D peer for bench/reconstruct/run_ball_pivot_bench.sh (Open3D 0.16, /usr/bin/python3).
#   ball_pivot_open3d.py CLOUD.ply R1,R2,.. OUT.ply
# Runs TriangleMesh.create_from_point_cloud_ball_pivoting with the same radii as pointsurf on
# the same cloud and normals; prints one JSON line: seconds (the call alone, reading excluded),
# peak_rss_mb (whole process), triangles. Writes the mesh for mesh_metrics_runner.
import json
import resource
import sys
import time

import open3d as o3d


def main():
    cloud_path, radii_text, out_path = sys.argv[1:4]
    radii = [float(r) for r in radii_text.split(",")]
    cloud = o3d.io.read_point_cloud(cloud_path)
    if not cloud.has_normals():
        sys.exit(f"{cloud_path}: no normals")
    start = time.perf_counter()
    mesh = o3d.geometry.TriangleMesh.create_from_point_cloud_ball_pivoting(cloud, o3d.utility.DoubleVector(radii))
    seconds = time.perf_counter() - start
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    o3d.io.write_triangle_mesh(out_path, mesh)
    print(json.dumps({"tool": "open3d", "points": len(cloud.points), "seconds": seconds, "peak_rss_mb": rss,
                      "triangles": len(mesh.triangles)}))


if __name__ == "__main__":
    main()
