# SPDX-License-Identifier: GPL-3.0-or-later
"""Open3D's registration_icp with the arguments of icp_runner (one JSON line, median wall and CPU time of
REPEATS calls, after the debug lines of one more call; each call builds its own target kd-tree, as icp_runner times it).
  icp_open3d.py SOURCE TARGET START.txt point|plane MAX_DISTANCE MAX_ITERATIONS RELATIVE REPEATS
RELATIVE is given to ICPConvergenceCriteria as relative_fitness and relative_rmse (Open3D
compares absolute changes with them)."""
import json
import statistics
import sys
import time

import numpy as np
import open3d as o3d

src, tgt, start_path, metric, dist, iters, rel, repeats = sys.argv[1:]
source, target = o3d.io.read_point_cloud(src), o3d.io.read_point_cloud(tgt)
start = np.loadtxt(start_path).reshape(4, 4)
est = (o3d.pipelines.registration.TransformationEstimationPointToPoint() if metric == "point"
       else o3d.pipelines.registration.TransformationEstimationPointToPlane())
criteria = o3d.pipelines.registration.ICPConvergenceCriteria(float(rel), float(rel), int(iters))
seconds, cpu = [], []
for _ in range(int(repeats)):
    t0, c0 = time.perf_counter(), time.process_time()
    r = o3d.pipelines.registration.registration_icp(source, target, float(dist), start, est, criteria)
    seconds.append(time.perf_counter() - t0)
    cpu.append(time.process_time() - c0)
# Open3D 0.16 returns no iteration count: one more call with debug logging prints a line per
# iteration ("ICP Iteration #k"), which the driver counts.
sys.stdout.flush()
o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Debug)
o3d.pipelines.registration.registration_icp(source, target, float(dist), start, est, criteria)
o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Warning)
print(json.dumps({"tool": "open3d", "seconds": statistics.median(seconds), "cpu_seconds": statistics.median(cpu), "fitness": r.fitness, "inlier_rmse": r.inlier_rmse,
                  "iterations": -1, "converged": None, "matrix": np.asarray(r.transformation).ravel().tolist()}))
