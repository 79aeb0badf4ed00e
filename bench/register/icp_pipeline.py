# SPDX-License-Identifier: GPL-3.0-or-later
"""The whole registration pipeline (voxel grid, normals, FPFH, RANSAC, ICP) of pointsurf
(icp_pipeline_runner) against Open3D's same recipe (icp_pipeline_open3d.py), same voxel size v,
radii, RANSAC cap and confidence; interleaved rounds, per-step medians. pointsurf's ICP runs with
its normal-angle check (45 degrees) and without (180); Open3D with its default threads and with
one (OMP_NUM_THREADS=1: on a loaded machine its OpenMP threads wait on each other).

Pairs (v = 2 mean spacings of the source):
  hippo   hippo2 turned by 90 degrees about its centroid onto hippo1; truth = the reference pose
          of icp_pairs.hippo_pair composed with the turn
  kitten  the kitten pair of icp_pairs (70 % overlap, noise 0.1 spacing) moved by 75 degrees
Scores: rotation and translation error of the RANSAC and final poses against the truth; fitness
and inlier RMSE (Open3D evaluate_registration) within 0.4 v, ICP's max distance.

  icp_pipeline.py BUILD_DIR REPEATS WORK HIPPO1 HIPPO2 KITTEN CSV COMMIT DATE MACHINE
"""
import json
import os
import statistics
import subprocess
import sys

import numpy as np

from icp_pairs import apply, hippo_pair, kitten_pair, motion, open_csv, score, spacing, write_pair

HERE = os.path.dirname(os.path.abspath(__file__))
build, repeats, work, hippo1, hippo2, kitten_path, csv_path, commit, date, machine = sys.argv[1:]
runner = os.path.join(build, "bench", "icp_pipeline_runner")
INNER, SEED = 3, 1
STEPS = ("voxel", "normals", "fpfh", "ransac", "icp", "total")


def hippo_turned():
    source, target, reference, _, _ = hippo_pair(hippo1, hippo2)
    c = np.asarray(source.points).mean(axis=0)
    turn = motion([0.4, 1.0, -0.3], 90.0, [0.0, 0.0, 0.0], about=c)
    return apply(turn, source), target, reference @ np.linalg.inv(turn)


def kitten_turned():
    truth = motion([1.0, 0.2, -0.5], 75.0, [0.1, -0.05, 0.2])
    source, target, truth, _, _ = kitten_pair(kitten_path, False, truth=truth)
    return source, target, truth


os.makedirs(work, exist_ok=True)
pairs = {"hippo": hippo_turned(), "kitten": kitten_turned()}
configs = [("pointsurf", 45), ("pointsurf", 180), ("open3d", 180), ("open3d-1t", 180)]
out, w = open_csv(csv_path)
files = {}
for name, (source, target, truth) in pairs.items():
    d = write_pair(work, name, source, target)
    files[name] = (d, 2.0 * spacing(source))

results = []
for r in range(1, int(repeats) + 1):
    print(f"round {r}/{repeats} (load {os.getloadavg()[0]:.2f})", file=sys.stderr)
    for name, (source, target, truth) in pairs.items():
        d, v = files[name]
        args = [os.path.join(d, "source.ply"), os.path.join(d, "target.ply"), str(v), str(SEED)]
        for tool, normal_deg in configs:
            load = os.getloadavg()[0]
            if tool == "pointsurf":
                cmd, env = [runner, *args, str(normal_deg), str(INNER)], None
            else:
                cmd = [sys.executable, os.path.join(HERE, "icp_pipeline_open3d.py"), *args, str(INNER)]
                env = dict(os.environ, **({"OMP_NUM_THREADS": "1"} if tool == "open3d-1t" else {}))
            j = json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True, env=env).stdout.strip().splitlines()[-1])
            final, coarse = np.array(j["matrix"]).reshape(4, 4), np.array(j["ransac_matrix"]).reshape(4, 4)
            fit, rmse, rot, trans = score(source, target, 0.4 * v, final, truth)
            _, _, rot_ransac, trans_ransac = score(source, target, 0.4 * v, coarse, truth)
            for step in STEPS:
                scored = {"ransac": (j["ransac_iterations"], "", "", rot_ransac, trans_ransac),
                          "total": (j["icp_iterations"], f"{fit:.6f}", f"{rmse:.6g}", rot, trans)}.get(step, ("", "", "", "", ""))
                w.writerow([commit, date, machine, f"{load:.2f}", "pipeline", name, tool, "plane", normal_deg, r, step, f"{j[step]:.6f}", "",
                            *scored[:3], *(f"{x:.6g}" if x != "" else "" for x in scored[3:]), f"{0.4 * v:.6g}", j["down_source"],
                            j["down_target"]])
            out.flush()
            results.append(dict(pair=name, tool=tool, normal=normal_deg, fit=fit, rot=rot, trans=trans, rot_ransac=rot_ransac,
                                **{s: j[s] for s in STEPS}))

print("| pair | tool | ICP normal check | voxel ms | normals ms | FPFH ms | RANSAC ms | ICP ms | total ms | RANSAC rot. error (deg) | "
      "final rot. error (deg) | final transl. error | fitness |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for name in pairs:
    for tool, normal_deg in configs:
        rs = [x for x in results if x["pair"] == name and x["tool"] == tool and x["normal"] == normal_deg]
        check = f"{normal_deg} deg" if normal_deg < 180 else "off"
        times = " | ".join(f"{1000 * statistics.median(x[s] for x in rs):.1f}" for s in STEPS)
        errors = f"{statistics.median(x['rot_ransac'] for x in rs):.3f} | {statistics.median(x['rot'] for x in rs):.4f} | " \
                 f"{statistics.median(x['trans'] for x in rs):.3g} | {statistics.median(x['fit'] for x in rs):.4f}"
        print(f"| {name} | {tool} | {check} | {times} | {errors} |")
