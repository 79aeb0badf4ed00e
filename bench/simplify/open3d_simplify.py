#!/usr/bin/python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Open3D's voxel_down_sample on the same cloud and cell as `simplify_runner grid`.

usage: /usr/bin/python3 open3d_simplify.py CLOUD.ply CELL [OUT.ply]
Prints one JSON line: points, output_points, seconds (the down-sampling alone), peak_rss_mb.
"""
import json
import resource
import sys
import time

import open3d as o3d


def main():
    path, cell = sys.argv[1], float(sys.argv[2])
    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
    pcd = o3d.io.read_point_cloud(path)
    pcd.normals = o3d.utility.Vector3dVector()  # positions only, as simplify_runner grid
    t0 = time.perf_counter()
    down = pcd.voxel_down_sample(cell)
    seconds = time.perf_counter() - t0
    out = {"tool": "open3d", "stage": "grid", "points": len(pcd.points), "output_points": len(down.points),
           "seconds": seconds, "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0}
    if len(sys.argv) > 3:
        o3d.io.write_point_cloud(sys.argv[3], down)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
