#!/usr/bin/python3
# SPDX-License-Identifier: GPL-3.0-or-later
# PCL peer for bench/reconstruct/run_triangulate_bench.sh: pcl_gp3_surface (pcl-tools, PCL's
# GreedyProjectionTriangulation) on the same cloud and normals.
#   gp3_pcl.py CLOUD.ply RADIUS MU OUT.ply
# The cloud and its normals go to the tool as a binary PCD of floats (x y z normal_x normal_y
# normal_z curvature: the PointNormal fields it reads; a PCD of doubles would not match them).
# Prints one JSON line:
# seconds (the triangulation alone, as the tool reports it: "[done, X ms"; the whole process when
# it does not), process_seconds (the whole process, reading and writing included), peak_rss_mb
# (the tool's process), triangles. Writes the mesh as PLY (from the tool's VTK) for
# mesh_metrics_runner.
import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time


def vtk_to_ply(vtk_path, ply_path):
    """Legacy ASCII VTK POLYDATA (POINTS, POLYGONS) to ASCII PLY; returns the triangle count."""
    tokens = open(vtk_path).read().split()
    i = tokens.index("POINTS")
    n = int(tokens[i + 1])
    coords = tokens[i + 3:i + 3 + 3 * n]
    j = tokens.index("POLYGONS")
    count = int(tokens[j + 1])
    faces, k = [], j + 3
    for _ in range(count):
        m = int(tokens[k])
        faces.append(tokens[k + 1:k + 1 + m])
        k += 1 + m
    with open(ply_path, "w") as out:
        out.write(f"ply\nformat ascii 1.0\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\n"
                  f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
        for v in range(n):
            out.write(" ".join(coords[3 * v:3 * v + 3]) + "\n")
        for f in faces:
            out.write(f"{len(f)} " + " ".join(f) + "\n")
    return len(faces)


def write_pcd(ply_path, pcd_path):
    import numpy as np
    import open3d as o3d
    cloud = o3d.io.read_point_cloud(ply_path)
    if not cloud.has_normals():
        sys.exit(f"{ply_path}: no normals")
    n = len(cloud.points)
    data = np.zeros((n, 7), dtype=np.float32)
    data[:, 0:3] = np.asarray(cloud.points)
    data[:, 3:6] = np.asarray(cloud.normals)
    with open(pcd_path, "wb") as out:
        out.write((f"# .PCD v0.7\nVERSION 0.7\nFIELDS x y z normal_x normal_y normal_z curvature\nSIZE 4 4 4 4 4 4 4\n"
                   f"TYPE F F F F F F F\nCOUNT 1 1 1 1 1 1 1\nWIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\n"
                   f"DATA binary\n").encode())
        out.write(data.tobytes())


def main():
    ply, radius, mu, out_ply = sys.argv[1:5]
    with tempfile.TemporaryDirectory() as tmp:
        vtk = os.path.join(tmp, "gp3.vtk")
        cloud = os.path.join(tmp, "cloud.pcd")
        write_pcd(ply, cloud)
        start = time.perf_counter()
        proc = subprocess.run(["pcl_gp3_surface", cloud, vtk, "-radius", radius, "-mu", mu], capture_output=True, text=True)
        process_seconds = time.perf_counter() - start
        if proc.returncode != 0:
            sys.exit(f"pcl_gp3_surface failed: {proc.stderr}{proc.stdout}")
        text = re.sub(r"\x1b\[[0-9;]*m", "", proc.stdout + proc.stderr)
        # The tool reports loading, triangulation and saving each as "[done, X ms ...]"; the
        # triangulation is the first that counts polygons (saving is the second).
        done = re.findall(r"\[done, ([0-9.]+) ms : ([0-9]+) polygons\]", text)
        seconds = float(done[0][0]) / 1000.0 if done else process_seconds
        triangles = vtk_to_ply(vtk, out_ply)
    rss = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0
    print(json.dumps({"tool": "pcl_gp3", "seconds": seconds, "process_seconds": process_seconds, "peak_rss_mb": rss,
                      "triangles": triangles}))


if __name__ == "__main__":
    main()
