#!/usr/bin/python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Open3D's nearest cheap proxy for feature points: surface variation above a threshold.

Open3D (and PCL) have no sharp-edge screening; a curvature (surface variation) threshold is
what users of those libraries apply. This is pointsurf's candidate step alone, done by Open3D:
covariances of the 30 nearest neighbours (estimate_covariances), their eigenvalues (numpy),
s = l0 / (l0 + l1 + l2) > max(floor, 4 * median(s)) -- the same threshold pointsurf derives, with
floor half the variation of a point on a 28-degree crease (detect_feature_points' min_turn_deg).

usage: /usr/bin/python3 open3d_features.py CLOUD.ply DISTANCES.txt
DISTANCES.txt: per point, the distance to the nearest sharp edge in mean spacings (written by
features_runner). Prints one JSON line, scored with the runner's bands (truth 1.0, tolerance 1.5).
"""
import json
import resource
import sys
import time

import numpy as np
import open3d as o3d


def main():
    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
    pcd = o3d.io.read_point_cloud(sys.argv[1])
    dist = np.loadtxt(sys.argv[2])
    t0 = time.perf_counter()
    pcd.estimate_covariances(o3d.geometry.KDTreeSearchParamKNN(30))
    cov = np.asarray(pcd.covariances)
    eig = np.linalg.eigvalsh(cov)
    total = eig.sum(axis=1)
    s = np.where(total > 0, eig[:, 0] / np.where(total > 0, total, 1.0), 0.0)
    half = np.radians(28.0) / 2.0
    l0 = (0.25 - 16.0 / (9.0 * np.pi ** 2)) * np.sin(half) ** 2
    floor = 0.5 * l0 / (l0 + 0.25 * np.cos(half) ** 2 + 0.25)
    threshold = min(max(floor, 4.0 * float(np.median(s))), 0.3)
    labels = s > threshold
    seconds = time.perf_counter() - t0
    labelled = int(labels.sum())
    truth = dist <= 1.0
    out = {
        "tool": "open3d", "variant": "variation_only", "points": len(pcd.points), "seconds": seconds,
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
        "precision": float((labels & (dist <= 1.5)).sum()) / labelled if labelled else 0.0,
        "recall": float((labels & truth).sum()) / float(truth.sum()) if truth.any() else 0.0,
        "labelled": labelled, "threshold": threshold,
    }
    print(json.dumps(out))


if __name__ == "__main__":
    main()
