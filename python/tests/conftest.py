# SPDX-License-Identifier: GPL-3.0-or-later
"""Shapes known by construction, seeded: a sampled unit sphere and an icosphere mesh."""
import numpy as np
import pytest

import pointsurf


def sphere_points(n=2000, seed=1):
    """n points spread evenly on the unit sphere (Fibonacci lattice), with seeded jitter < 1e-3."""
    i = np.arange(n) + 0.5
    phi = np.arccos(1 - 2 * i / n)
    theta = np.pi * (1 + 5 ** 0.5) * i
    p = np.stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)], axis=1)
    return p + np.random.default_rng(seed).uniform(-1e-3, 1e-3, p.shape)


def octasphere(levels=3):
    """A closed unit sphere mesh: an octahedron split `levels` times, vertices pushed out."""
    v = [np.array(x, float) for x in [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]]
    f = [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)]
    for _ in range(levels):
        mid, out = {}, []

        def m(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                p = v[a] + v[b]
                v.append(p / np.linalg.norm(p))
                mid[key] = len(v) - 1
            return mid[key]
        for a, b, c in f:
            ab, bc, ca = m(a, b), m(b, c), m(c, a)
            out += [(a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca)]
        f = out
    return np.array(v), np.array(f, dtype=np.int32)


@pytest.fixture
def cloud():
    return pointsurf.PointCloud(sphere_points())


@pytest.fixture
def mesh():
    v, f = octasphere()
    return pointsurf.TriangleMesh(v, f)
