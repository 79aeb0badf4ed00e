#!/usr/bin/python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Orientation on real scans that carry their own normals: share of points whose MST-oriented
normal (pointsurf normals, k = 30, orient-k 10 / Open3D estimate_normals(KNN 30) +
orient_normals_consistent_tangent_plane(10)) agrees in sign with the scan's normals.

usage: /usr/bin/python3 bench/orientation_sweep.py PATH/TO/pointsurf SCAN.ply ...
(bench/orientation_sweep.sh prepares CGAL's example scans and calls this.)
"""
import subprocess
import sys

import numpy as np, open3d as o3d
o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
files = sys.argv[2:]
OUT = "/tmp/pointsurf_orientation_sweep.ply"
cli = sys.argv[1]
print("| scan | points | pointsurf agreement | Open3D agreement |")
print("|---|---|---|---|")
for f in files:
    a = o3d.io.read_point_cloud(f)
    N0 = np.asarray(a.normals).copy()
    subprocess.run([cli, "normals", f, OUT, "--orient", "mst", "-q"], check=True)
    ours = np.asarray(o3d.io.read_point_cloud(OUT).normals)
    b = o3d.io.read_point_cloud(f)
    b.normals = o3d.utility.Vector3dVector()
    b.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(30))
    b.orient_normals_consistent_tangent_plane(10)
    theirs = np.asarray(b.normals)
    agree = lambda n: (np.sum(N0 * n, 1) > 0).mean()
    print(f"| {f.split('/')[-1]} | {len(N0)} | {agree(ours):.3f} | {agree(theirs):.3f} |")
