#!/usr/bin/python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""register-many on scans with known poses: the first pass alone (chain, first) against the
global refinement, error against the truth and time.

Each object is cut into N views around its vertical axis (the points facing each viewpoint, a
seeded 80 % of them, Gaussian noise of SIGMA mean spacings), each moved into a frame of its own
by a seeded rigid motion; neighbouring views overlap by about half and the last overlaps the
first. The error of a pose is the RMS distance between where it and the truth put the scan's
points, in mean spacings, averaged over the scans.

  bench/register/multi_bench.py BUILD/pointsurf OUT.csv
Objects: data/kitten.xyz, CGAL's bull.off and ChineseDragon-10kv.off vertices (the refinement's
prune distance and link weighting were chosen on these three) and, unseen, camel.off and
bear.off (extracted from libcgal-demo's data.tar.gz).
"""
import json
import os
import platform
import subprocess
import sys
import tarfile
import tempfile
import time
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
CGAL_TAR = Path("/usr/share/doc/libcgal-demo/data.tar.gz")
VIEWS, SIGMA, SEEDS = 4, 0.3, (1, 2, 3)


def read_off(path):
    lines = [l for l in Path(path).read_text().split("\n") if l.strip() and not l.startswith("#")]
    nv, nf = map(int, lines[1].split()[:2])
    v = np.array([list(map(float, l.split()[:3])) for l in lines[2:2 + nv]])
    f = np.array([list(map(int, l.split()[1:4])) for l in lines[2 + nv:2 + nv + nf]])
    n = np.zeros_like(v)
    fn = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])  # area-weighted, outward for CCW faces
    for k in range(3):
        np.add.at(n, f[:, k], fn)
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)
    return v, n


def cgal_mesh(name, scratch):
    out = Path(scratch) / name
    if not out.exists():
        with tarfile.open(CGAL_TAR) as tar:
            member = next(m for m in tar.getmembers() if m.name.endswith("meshes/" + name))
            out.write_bytes(tar.extractfile(member).read())
    return read_off(out)


def mean_spacing(p):
    import open3d as o3d
    return float(np.mean(o3d.geometry.PointCloud(o3d.utility.Vector3dVector(p)).compute_nearest_neighbor_distance()))


def rotation(axis, angle):
    axis = axis / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def make_views(p, normals, seed, spacing, up):
    rng = np.random.default_rng(seed)
    centre = p.mean(axis=0)
    size = np.linalg.norm(p.max(axis=0) - p.min(axis=0))
    a_axis, b_axis = [np.eye(3)[i] for i in range(3) if i != up]
    scans, truth = [], []
    for v in range(VIEWS):
        a = 2 * np.pi * v / VIEWS
        view = centre + 3 * size * (np.cos(a) * a_axis + np.sin(a) * b_axis)
        keep = (np.einsum("ij,ij->i", normals, view - p) > 0) & (rng.uniform(size=len(p)) <= 0.8)
        q = p[keep] + SIGMA * spacing * rng.standard_normal((keep.sum(), 3))
        qn = normals[keep]
        r, t = np.eye(3), np.zeros(3)
        if v > 0:
            r = rotation(rng.standard_normal(3), 0.6 * rng.uniform() + 0.2)
            t = 0.3 * size * rng.standard_normal(3)
        # The scan in its own frame: x_own = R^T (x - t); pose maps own -> first frame.
        scans.append(((q - t) @ r, qn @ r))
        truth.append((r, t))
    return scans, truth


def pose_error(poses, truth, scans, spacing):
    errs = []
    for (r, t), (q, _), m in zip(truth, scans, poses):
        m = np.array(m).reshape(4, 4)
        a = q @ m[:3, :3].T + m[:3, 3]
        b = q @ r.T + t
        errs.append(np.sqrt(((a - b) ** 2).sum(axis=1).mean()))
    return float(np.mean(errs)) / spacing


def main():
    cli, out_csv = sys.argv[1], Path(sys.argv[2])
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    date = datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    machine = f"{platform.node()} {os.cpu_count()} cores"
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = os.environ.get("KEEP", tmp)
        k = np.loadtxt(ROOT / "data" / "kitten.xyz")
        objects = [("kitten", "tuned", k[:, :3], k[:, 3:6], 1)]
        for name, role in (("bull.off", "tuned"), ("ChineseDragon-10kv.off", "tuned"), ("camel.off", "unseen"), ("bear.off", "unseen")):
            v, nn = cgal_mesh(name, tmp)
            objects.append((name.split(".")[0], role, v, nn, 1))
        for name, role, p, n, up in objects:
            spacing = mean_spacing(p)
            for seed in SEEDS:
                scans, truth = make_views(p, n, seed, spacing, up)
                files = []
                for i, (q, qn) in enumerate(scans):
                    f = Path(tmp) / f"{name}_{seed}_{i}.xyz"
                    np.savetxt(f, np.hstack([q, qn]), fmt="%.17g")
                    files.append(str(f))
                for mode, refine in (("chain", False), ("first", False), ("chain", True), ("first", True)):
                    report = Path(tmp) / "r.json"
                    cmd = [cli, "register-many", *files, "--out", str(Path(tmp) / "m.ply"), "--mode", mode,
                           "--refine" if refine else "--no-refine", "--report", str(report), "--quiet"]
                    load = os.getloadavg()[0]
                    start = time.perf_counter()
                    r = subprocess.run(cmd, capture_output=True, text=True)
                    wall = time.perf_counter() - start
                    if r.returncode != 0:
                        rows.append([commit, date, machine, name, role, seed, mode, refine, "", "", "", f"{wall:.3f}", f"{load:.2f}",
                                     f"exit {r.returncode}: {r.stderr.strip().splitlines()[-1] if r.stderr.strip() else ''}"])
                        continue
                    st = [s for s in json.loads(report.read_text())["stages"] if s["type"] == "register-many"][0]
                    poses = [st["metrics"][f"pose_{i}"] for i in range(VIEWS)]
                    err = pose_error(poses, truth, scans, spacing)
                    rows.append([commit, date, machine, name, role, seed, mode, refine, f"{err:.4f}", st["counts"]["links"],
                                 st["counts"]["pruned_links"], f"{st['seconds']:.3f}", f"{load:.2f}", ""])
                    print(",".join(map(str, rows[-1])), flush=True)
    header = "commit,date,machine,object,role,seed,mode,refine,error_spacings,links,pruned_links,seconds,load,note"
    out_csv.parent.mkdir(parents=True, exist_ok=True)
    out_csv.write_text(header + "\n" + "\n".join(",".join(map(str, r)) for r in rows) + "\n")


if __name__ == "__main__":
    main()
