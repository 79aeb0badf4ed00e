#!/usr/bin/python3
# A second primitive scene, made for checking the detector on data it was not tuned on: 18
# primitives of random type, size (a 5x range), orientation and place on a 3 x 3 x 2 grid
# (planar rectangles, spheres, cylinders, cones; no two touch), uniform density, sigma noise
# along the normals. Writes the binary PLY with "truth" and the raw dump like make_scene.py,
# and prints N and the mean spacing (nearest-neighbour distance, by Open3D).
#   make_mixed_scene.py N SIGMA SEED OUT.ply OUT.bin
import sys
import numpy as np
import open3d as o3d

from scene_io import write_scene

n_target, sigma, seed, out_ply, out_bin = int(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3]), sys.argv[4], sys.argv[5]
rng = np.random.default_rng(seed)


def unit(v):
    return v / np.linalg.norm(v)


def frame(a):
    x = unit(np.cross(np.array([1.0, 0, 0]) if abs(a[0]) < 0.9 else np.array([0, 1.0, 0]), a))
    return x, np.cross(a, x)


# Each primitive fits in a ball of radius 1.6 around its grid centre (cells 4 apart).
shapes = []
for i in range(18):
    centre = np.array([4.0 * (i % 3), 4.0 * ((i // 3) % 3), 4.0 * (i // 9)]) + rng.uniform(-0.3, 0.3, 3)
    axis = unit(rng.normal(size=3))
    kind = ["plane", "sphere", "cylinder", "cone"][rng.integers(4)]
    s = rng.uniform(0.3, 1.0)  # size factor: 0.3 to 1.0 (areas over about a 10x range)
    if kind == "plane":
        shapes.append((kind, centre, axis, 2.2 * s, 1.1 * s * rng.uniform(1.0, 2.0)))  # half sides
    elif kind == "sphere":
        shapes.append((kind, centre, axis, 1.4 * s, 0.0))
    elif kind == "cylinder":
        shapes.append((kind, centre, axis, 0.9 * s, 1.3 * s))  # radius, half length
    else:
        shapes.append((kind, centre, axis, np.radians(rng.uniform(20, 45)), 2.6 * s))  # half angle, slant length


def area(sh):
    kind, _, _, a, b = sh
    if kind == "plane":
        return 4 * a * b
    if kind == "sphere":
        return 4 * np.pi * a * a
    if kind == "cylinder":
        return 2 * np.pi * a * 2 * b
    return np.pi * b * b * np.sin(a) * (1 - 0.04)  # slant from 0.2 b to b


density = n_target / sum(area(s) for s in shapes)
P, N, T = [], [], []
for label, sh in enumerate(shapes):
    kind, c, ax, a, b = sh
    m = int(area(sh) * density)
    x, y = frame(ax)
    if kind == "plane":
        u, v = rng.uniform(-a, a, m), rng.uniform(-b, b, m)
        p, n = c + u[:, None] * x + v[:, None] * y, np.tile(ax, (m, 1))
    elif kind == "sphere":
        d = rng.normal(size=(m, 3))
        d /= np.linalg.norm(d, axis=1)[:, None]
        p, n = c + a * d, d
    elif kind == "cylinder":
        phi, h = rng.uniform(0, 2 * np.pi, m), rng.uniform(-b, b, m)
        d = np.cos(phi)[:, None] * x + np.sin(phi)[:, None] * y
        p, n = c + h[:, None] * ax + a * d, d
    else:
        t = np.sqrt(0.04 + rng.uniform(0, 1, m) * 0.96) * b  # slant distance from the apex, area-uniform
        phi = rng.uniform(0, 2 * np.pi, m)
        d = np.cos(phi)[:, None] * x + np.sin(phi)[:, None] * y
        apex = c - 0.5 * b * np.cos(a) * ax
        p = apex + (t * np.cos(a))[:, None] * ax + (t * np.sin(a))[:, None] * d
        n = np.cos(a) * d - np.sin(a) * ax
    P.append(p + rng.normal(0.0, sigma, (m, 1)) * n)
    N.append(n)
    T.append(np.full(m, label))
P, N, T = np.vstack(P), np.vstack(N), np.concatenate(T).astype(np.int32)
write_scene(np.c_[P, N], T, out_ply, out_bin)
pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(P))
print(len(P), float(np.mean(pcd.compute_nearest_neighbor_distance())))
