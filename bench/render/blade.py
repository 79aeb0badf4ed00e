#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""A turbine-blade-like part with a known exact surface, and a simulated scan of it.

The blade: a NACA 4412 airfoil (closed trailing edge) lofted along z over a span of 1000 mm,
its chord tapering linearly from 300 mm at the root to 120 mm at the tip, twisted linearly by
35 degrees about the quarter-chord line, closed by flat caps at root and tip. Units: mm.

  blade.py OUT_DIR [--points N] [--sigma S] [--seed K] [--around A] [--along B]

writes OUT_DIR/blade_exact.ply (the exact surface as a fine closed triangle mesh: A points
around the profile, B stations along the span; the chord error of the default 720 x 600 mesh is
below 0.004 mm) and OUT_DIR/blade_scan.xyz (N points drawn area-uniformly on that surface with
isotropic Gaussian noise of standard deviation S mm, seeded). Prints the exact area and volume.
Needs numpy (Debian python3-numpy). The B-spline work can fit the same loft from blade_exact.ply.
"""
import argparse
import os

import numpy as np

SPAN, ROOT_CHORD, TIP_CHORD, TWIST_DEG = 1000.0, 300.0, 120.0, 35.0


def naca4412(x):
    """Upper and lower surface points of NACA 4412 at chord positions x in [0, 1] (closed trailing edge)."""
    m, p, t = 0.04, 0.4, 0.12
    yt = 5 * t * (0.2969 * np.sqrt(x) - 0.1260 * x - 0.3516 * x**2 + 0.2843 * x**3 - 0.1036 * x**4)
    yc = np.where(x < p, m / p**2 * (2 * p * x - x**2), m / (1 - p)**2 * ((1 - 2 * p) + 2 * p * x - x**2))
    dyc = np.where(x < p, 2 * m / p**2 * (p - x), 2 * m / (1 - p)**2 * (p - x))
    th = np.arctan(dyc)
    upper = np.stack([x - yt * np.sin(th), yc + yt * np.cos(th)], -1)
    lower = np.stack([x + yt * np.sin(th), yc - yt * np.cos(th)], -1)
    return upper, lower


def profile(around):
    """A closed profile loop, counter-clockwise, from the trailing edge over the upper side."""
    k = around // 2
    x = 0.5 * (1 - np.cos(np.linspace(0, np.pi, k + 1)))  # cosine spacing: dense at both edges
    upper, lower = naca4412(x)
    loop = np.concatenate([upper[::-1][:-1], lower[:-1]])  # TE -> LE over the top, LE -> TE below
    return loop  # shape (2k, 2); the trailing edge point is shared by both sides


def station(loop, z):
    s = z / SPAN
    chord = ROOT_CHORD + (TIP_CHORD - ROOT_CHORD) * s
    a = np.radians(TWIST_DEG * s)
    x = (loop[:, 0] - 0.25) * chord
    y = loop[:, 1] * chord
    return np.stack([x * np.cos(a) - y * np.sin(a), x * np.sin(a) + y * np.cos(a), np.full(len(loop), z)], -1)


def blade_mesh(around, along):
    loop = profile(around)
    n = len(loop)
    zs = np.linspace(0.0, SPAN, along)
    vertices = np.concatenate([station(loop, z) for z in zs])
    faces = []
    i = np.arange(n)
    j = (i + 1) % n
    for k in range(along - 1):
        a, b, c, d = k * n + i, k * n + j, (k + 1) * n + j, (k + 1) * n + i
        faces.append(np.stack([a, b, c], -1))
        faces.append(np.stack([a, c, d], -1))
    # Caps: a fan about each end's centroid, facing -z at the root and +z at the tip.
    root_c, tip_c = len(vertices), len(vertices) + 1
    vertices = np.concatenate([vertices, vertices[:n].mean(0, keepdims=True), vertices[-n:].mean(0, keepdims=True)])
    faces.append(np.stack([np.full(n, root_c), j, i], -1))
    top = (along - 1) * n
    faces.append(np.stack([np.full(n, tip_c), top + i, top + j], -1))
    faces = np.concatenate(faces).astype(np.int32)
    # The loop runs counter-clockwise seen from +z, so the side faces (a, b, c) point outward.
    return vertices, faces


def write_ply(path, vertices, faces):
    with open(path, "wb") as f:
        f.write((f"ply\nformat binary_little_endian 1.0\nelement vertex {len(vertices)}\nproperty double x\nproperty double y\n"
                 f"property double z\nelement face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n").encode())
        f.write(np.ascontiguousarray(vertices, dtype="<f8").tobytes())
        rec = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<i4", 3)])
        rec["n"] = 3
        rec["i"] = faces
        f.write(rec.tobytes())


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--points", type=int, default=60000)
    ap.add_argument("--sigma", type=float, default=0.2)
    ap.add_argument("--seed", type=int, default=16)
    ap.add_argument("--around", type=int, default=720)
    ap.add_argument("--along", type=int, default=600)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    v, f = blade_mesh(a.around, a.along)
    p0, p1, p2 = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    cross = np.cross(p1 - p0, p2 - p0)
    area = 0.5 * np.linalg.norm(cross, axis=1)
    volume = np.einsum("ij,ij->i", p0, cross).sum() / 6.0
    write_ply(os.path.join(a.out, "blade_exact.ply"), v, f)
    rng = np.random.default_rng(a.seed)
    t = rng.choice(len(f), size=a.points, p=area / area.sum())
    r1, r2 = rng.random(a.points), rng.random(a.points)
    s = np.sqrt(r1)
    pts = (1 - s)[:, None] * p0[t] + (s * (1 - r2))[:, None] * p1[t] + (s * r2)[:, None] * p2[t]
    pts += rng.normal(0.0, a.sigma, pts.shape)
    np.savetxt(os.path.join(a.out, "blade_scan.xyz"), pts, fmt="%.5f")
    print(f"blade: {len(f)} triangles, area {area.sum():.2f} mm^2, volume {volume:.1f} mm^3; scan {a.points} points, sigma {a.sigma} mm")


if __name__ == "__main__":
    main()
