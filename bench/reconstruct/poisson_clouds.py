#!/usr/bin/python3
# SPDX-License-Identifier: GPL-3.0-or-later
# Inputs of bench/reconstruct/run_poisson_bench.sh (numpy and Open3D 0.16, /usr/bin/python3).
#   poisson_clouds.py CLEAN.ply NOISY.ply CLEAN.pcd NOISY.pcd
# From the clean area-uniform sample with true normals (pointsurf_bench sample) writes the noisy
# cloud, Gaussian noise of 0.25 % of the bounding-box diagonal on every position (normals kept)
# plus 1 % outliers uniform in the box grown by 5 % with random unit normals (seed 1), and both
# clouds as binary PCD with normals for PCL's pcl_poisson_reconstruction. Every tool gets the
# same positions and the same oriented normals.
import sys

import numpy as np
import open3d as o3d


def main():
    clean_ply, noisy_ply, clean_pcd, noisy_pcd = sys.argv[1:5]
    cloud = o3d.io.read_point_cloud(clean_ply)
    if not cloud.has_normals():
        sys.exit(f"{clean_ply}: no normals")
    p, n = np.asarray(cloud.points), np.asarray(cloud.normals)
    rng = np.random.default_rng(1)
    lo, hi = p.min(axis=0), p.max(axis=0)
    diagonal = float(np.linalg.norm(hi - lo))
    noisy = p + rng.normal(scale=0.0025 * diagonal, size=p.shape)
    count = len(p) // 100
    grow = 0.05 * (hi - lo)
    outliers = rng.uniform(lo - grow, hi + grow, size=(count, 3))
    directions = rng.normal(size=(count, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    out = o3d.geometry.PointCloud()
    out.points = o3d.utility.Vector3dVector(np.vstack([noisy, outliers]))
    out.normals = o3d.utility.Vector3dVector(np.vstack([n, directions]))
    o3d.io.write_point_cloud(noisy_ply, out)
    o3d.io.write_point_cloud(clean_pcd, cloud)
    o3d.io.write_point_cloud(noisy_pcd, out)


if __name__ == "__main__":
    main()
