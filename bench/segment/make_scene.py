#!/usr/bin/python3
# The primitive scene of tests/support/primitive_scene.cpp (ground, wall, sphere, tilted
# cylinder, cone), N points about, sigma noise along the normals, as binary PLY with normals and
# the int field "truth"; also a raw float64 dump (N x 6) for the CGAL peer.
#   make_scene.py N SIGMA OUT.ply OUT.bin
import sys
import numpy as np

from scene_io import write_scene

n_target, sigma, out_ply, out_bin = int(sys.argv[1]), float(sys.argv[2]), sys.argv[3], sys.argv[4]
rng = np.random.default_rng(1)
t30 = np.tan(np.radians(30.0))
areas = [100.0, 40.0, 4 * np.pi * 1.44, 2 * np.pi * 0.8 * 2.4, np.pi * t30 * (9.0 - 0.36) / np.cos(np.radians(30.0))]
density = n_target / sum(areas)
P, N, T = [], [], []

def frame(a):
    x = np.cross(np.array([1.0, 0, 0]) if abs(a[0]) < 0.9 else np.array([0, 1.0, 0]), a)
    x /= np.linalg.norm(x)
    return x, np.cross(a, x)

def add(p, n, label):
    P.append(p + rng.normal(0.0, sigma, (len(p), 1)) * n); N.append(n); T.append(np.full(len(p), label))

m = int(areas[0] * density); add(np.c_[rng.uniform(-5, 5, m), rng.uniform(-5, 5, m), np.zeros(m)], np.tile([0, 0, 1.0], (m, 1)), 0)
m = int(areas[1] * density); add(np.c_[rng.uniform(-5, 5, m), np.full(m, 5.0), rng.uniform(0.3, 4.3, m)], np.tile([0, 1.0, 0], (m, 1)), 1)
m = int(areas[2] * density); d = rng.normal(size=(m, 3)); d /= np.linalg.norm(d, axis=1)[:, None]; add(np.array([2.2, -2.0, 2.0]) + 1.2 * d, d, 2)
a = np.array([0.3, 0.2, 1.0]); a /= np.linalg.norm(a); x, y = frame(a)
m = int(areas[3] * density); phi = rng.uniform(0, 2 * np.pi, m); h = rng.uniform(-1.2, 1.2, m)
d = np.cos(phi)[:, None] * x + np.sin(phi)[:, None] * y; add(np.array([-2.2, -2.0, 2.2]) + h[:, None] * a + 0.8 * d, d, 3)
a = np.array([0, 0, -1.0]); x, y = frame(a)
m = int(areas[4] * density); h = np.sqrt(0.36 + rng.uniform(0, 1, m) * (9.0 - 0.36)); phi = rng.uniform(0, 2 * np.pi, m)
d = np.cos(phi)[:, None] * x + np.sin(phi)[:, None] * y
nrm = np.cos(np.radians(30)) * d - np.sin(np.radians(30)) * a
add(np.array([1.5, 2.0, 3.6]) + h[:, None] * a + (h * t30)[:, None] * d, nrm, 4)
P, N, T = np.vstack(P), np.vstack(N), np.concatenate(T).astype(np.int32)
write_scene(np.c_[P, N], T, out_ply, out_bin)
print(len(P))
