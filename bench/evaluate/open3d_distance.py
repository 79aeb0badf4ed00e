# SPDX-License-Identifier: GPL-3.0-or-later
"""open3d_distance.py MESH.ply POINTS.ply MODE OUT.npy

MODE raycast (RaycastingScene.compute_distance), raycast-signed (compute_signed_distance) or
cloud (PointCloud.compute_point_cloud_distance from the points to the mesh's vertices). Times the
scene (hierarchy) build plus the queries, file reading excluded; prints one JSON object with peak
RSS raw and the baseline after importing numpy and open3d (interpreter + libraries)."""
import json
import resource
import sys
import time

import numpy as np
import open3d as o3d


def rss_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def main():
    mesh_path, points_path, mode, out = sys.argv[1:5]
    baseline = rss_mb()
    mesh = o3d.io.read_triangle_mesh(mesh_path)
    points = np.asarray(o3d.io.read_point_cloud(points_path).points)
    before = rss_mb()
    start = time.perf_counter()
    if mode in ("raycast", "raycast-signed"):
        scene = o3d.t.geometry.RaycastingScene()
        scene.add_triangles(o3d.t.geometry.TriangleMesh.from_legacy(mesh))
        query = o3d.core.Tensor(points.astype(np.float32))
        if mode == "raycast":
            d = scene.compute_distance(query).numpy()
        else:
            d = scene.compute_signed_distance(query).numpy()
    elif mode == "cloud":
        cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
        vertices = o3d.geometry.PointCloud(mesh.vertices)
        d = np.asarray(cloud.compute_point_cloud_distance(vertices))
    else:
        raise SystemExit(f"unknown mode {mode}")
    seconds = time.perf_counter() - start
    np.save(out, d.astype(np.float64))
    print(json.dumps({"mode": mode, "seconds": round(seconds, 4), "peak_rss_mb": round(rss_mb(), 1),
                      "baseline_rss_mb": round(baseline, 1), "rss_before_mb": round(before, 1),
                      "points": int(len(points)), "triangles": int(len(mesh.triangles))}))


if __name__ == "__main__":
    main()
