# SPDX-License-Identifier: GPL-3.0-or-later
# Open3D side of bench/clean/run_clean_bench.sh (Open3D 0.16 under /usr/bin/python3):
#   open3d_clean.py sor IN K STD_RATIO KEPT_OUT
#   open3d_clean.py radius IN MIN_NEIGHBOURS RADIUS KEPT_OUT
# Times the filter (its kd-tree build included, file reading excluded), writes the kept indices.
import json
import resource
import sys
import time

import numpy as np
import open3d as o3d

stage, path, a, b, kept_out = sys.argv[1:6]
cloud = o3d.io.read_point_cloud(path)
start = time.perf_counter()
if stage == "sor":
    _, kept = cloud.remove_statistical_outlier(nb_neighbors=int(a), std_ratio=float(b))
else:
    _, kept = cloud.remove_radius_outlier(nb_points=int(a), radius=float(b))
seconds = time.perf_counter() - start
np.savetxt(kept_out, np.asarray(kept, dtype=np.int64), fmt="%d")
print(json.dumps({"tool": "open3d", "stage": stage, "points": len(cloud.points), "seconds": seconds, "kept": len(kept),
                  "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0}))
