#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Per-call cost of the Python bindings on a 1M-point cloud, against the CLI / library and
against Open3D's Python API, interleaved in one run (medians of REPEATS).

    PYTHONPATH=build/python /usr/bin/python3 bench/python/bench_python.py [POINTS] [REPEATS]

Calls: normals (k = 30, orient none: PCA only, as Open3D's estimate_normals) and reconstruct
(ball pivoting; Open3D's create_from_point_cloud_ball_pivoting with the radii pointsurf chose).
Per call: pointsurf Python wall time, the library's own stage time (its report's "seconds"),
so overhead = wall - stage (input copy, worker thread, output wrap); the CLI's wall time
(includes reading and writing the file) and its stage time; Open3D's wall time. Rows go to
bench/results/python_bench.csv with commit, date, machine and load average.
BENCH_OPEN3D=0 leaves Open3D out of the process (it slows pointsurf's reconstruct in the same
process: see docs/benchmarks.md)."""
import csv
import datetime
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import pointsurf

ROOT = Path(__file__).resolve().parents[2]
CLI = Path(os.environ.get("BUILD_DIR", ROOT / "build")) / "pointsurf"
OUT = ROOT / "bench" / "results" / "python_bench.csv"


def wavy_surface(n, seed=1):
    """A smooth open height field z = 0.1 sin(3x) cos(2y) over [0, 1]^2, n points, seeded."""
    rng = np.random.default_rng(seed)
    xy = rng.random((n, 2))
    z = 0.1 * np.sin(3 * xy[:, 0]) * np.cos(2 * xy[:, 1])
    return np.column_stack([xy, z])


def timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


def cli(stage, src, args, tmp):
    report = Path(tmp) / "cli_report.json"
    dst = Path(tmp) / "cli_out.ply"
    wall, _ = timed(lambda: subprocess.run([str(CLI), stage, str(src), str(dst), *args, "--report", str(report), "--quiet"],
                                           check=True))
    rep = json.loads(report.read_text())
    stage_s = next(s["seconds"] for s in rep["stages"] if s["type"] == stage)
    return wall, stage_s


def main():
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 1_000_000
    repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 3
    with_open3d = os.environ.get("BENCH_OPEN3D", "1") != "0"
    if with_open3d:
        import open3d as o3d
        o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
    p = wavy_surface(n)
    cloud = pointsurf.PointCloud(p)
    rows = []
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    machine = f"{platform.node()} {os.cpu_count()} cores"
    with tempfile.TemporaryDirectory() as tmp:
        src = Path(tmp) / "in.ply"
        pointsurf.write(cloud, src)
        with_normals = pointsurf.normals(cloud, orient="direction")
        src_n = Path(tmp) / "in_normals.ply"
        pointsurf.write(with_normals, src_n)
        for rep in range(repeats):
            load = os.getloadavg()[0]
            # normals
            wall, out = timed(lambda: pointsurf.normals(cloud, k=30, orient="none"))
            rows.append(("normals", "pointsurf-python", rep, wall, out.report["seconds"], load))
            wall, stage_s = cli("normals", src, ["--k", "30", "--orient", "none"], tmp)
            rows.append(("normals", "pointsurf-cli", rep, wall, stage_s, load))
            if with_open3d:
                pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(p))
                wall, _ = timed(lambda: pc.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(30)))
                rows.append(("normals", "open3d", rep, wall, wall, load))
            # reconstruct (ball pivoting) from the same cloud with normals
            wall, mesh = timed(lambda: pointsurf.reconstruct(with_normals, method="ball-pivot"))
            rows.append(("reconstruct", "pointsurf-python", rep, wall, mesh.report["seconds"], load))
            radii = [float(r) for r in mesh.report["parameters"]["radii"]]
            wall, stage_s = cli("reconstruct", src_n, ["--method", "ball-pivot"], tmp)
            rows.append(("reconstruct", "pointsurf-cli", rep, wall, stage_s, load))
            if with_open3d:
                pcn = pointsurf.to_open3d(with_normals)
                wall, _ = timed(lambda: o3d.geometry.TriangleMesh.create_from_point_cloud_ball_pivoting(
                    pcn, o3d.utility.DoubleVector(radii)))
                rows.append(("reconstruct", "open3d", rep, wall, wall, load))
            print(f"run {rep + 1}/{repeats} done (load {load:.1f}); ball-pivot radii {radii}", file=sys.stderr)
    date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%MZ")
    new = not OUT.exists()
    with OUT.open("a", newline="") as f:
        w = csv.writer(f)
        if new:
            w.writerow(["commit", "date", "machine", "points", "stage", "tool", "run", "wall_s", "stage_s", "load1"])
        for r in rows:
            w.writerow([commit, date, machine, n, r[0], r[1], r[2], f"{r[3]:.4f}", f"{r[4]:.4f}", f"{r[5]:.2f}"])
    med = {}
    for stage in ("normals", "reconstruct"):
        for tool in ("pointsurf-python", "pointsurf-cli", "open3d"):
            sel = [r for r in rows if r[0] == stage and r[1] == tool]
            med[stage, tool] = (statistics.median(r[3] for r in sel), statistics.median(r[4] for r in sel)) if sel \
                else (float("nan"), float("nan"))
    print("| call | Python wall s | its stage s | Python overhead s | CLI wall s (with I/O) | CLI stage s | Open3D s | Python / Open3D |")
    print("|---|---|---|---|---|---|---|---|")
    for stage in ("normals", "reconstruct"):
        pw, ps = med[stage, "pointsurf-python"]
        cw, cs = med[stage, "pointsurf-cli"]
        ow, _ = med[stage, "open3d"]
        print(f"| {stage} | {pw:.3f} | {ps:.3f} | {pw - ps:.3f} | {cw:.3f} | {cs:.3f} | {ow:.3f} | {pw / ow:.2f} |")


if __name__ == "__main__":
    main()
