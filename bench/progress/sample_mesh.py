#!/usr/bin/env python3
"""Samples N points (with face normals) uniformly by area on a triangle mesh (OFF), as .xyz
"x y z nx ny nz": the 1M-point input of progress_trace.sh. Pure Python, fixed seed."""
import bisect
import random
import sys


def read_off(path):
    words = open(path).read().split()
    assert words[0] == "OFF", "expected an OFF file"
    nv, nf = int(words[1]), int(words[2])
    at = 4
    v = [tuple(float(w) for w in words[at + 3 * i: at + 3 * i + 3]) for i in range(nv)]
    at += 3 * nv
    faces = []
    for _ in range(nf):
        k = int(words[at])
        idx = [int(w) for w in words[at + 1: at + 1 + k]]
        at += 1 + k
        faces += [(idx[0], idx[j], idx[j + 1]) for j in range(1, k - 1)]
    return v, faces


def main():
    path, n, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    v, faces = read_off(path)
    cum, normals, total = [], [], 0.0
    for a, b, c in faces:
        p, q, r = v[a], v[b], v[c]
        u = [q[i] - p[i] for i in range(3)]
        w = [r[i] - p[i] for i in range(3)]
        x = (u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0])
        norm = (x[0] ** 2 + x[1] ** 2 + x[2] ** 2) ** 0.5
        total += norm
        cum.append(total)
        normals.append(tuple(c / norm for c in x) if norm > 0 else (0.0, 0.0, 1.0))
    rng = random.Random(1)
    with open(out, "w") as f:
        for _ in range(n):
            t = bisect.bisect_left(cum, rng.random() * total)
            a, b, c = faces[t]
            s, r = rng.random(), rng.random()
            if s + r > 1.0:
                s, r = 1.0 - s, 1.0 - r
            p = [v[a][i] + s * (v[b][i] - v[a][i]) + r * (v[c][i] - v[a][i]) for i in range(3)]
            nn = normals[t]
            f.write(f"{p[0]:.6f} {p[1]:.6f} {p[2]:.6f} {nn[0]:.5f} {nn[1]:.5f} {nn[2]:.5f}\n")


if __name__ == "__main__":
    main()
