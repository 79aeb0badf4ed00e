# SPDX-License-Identifier: GPL-3.0-or-later
"""open3d_whole_process.py MESH.ply POINTS.ply OUT.ply

What a user of Open3D 0.16 writes to colour a scan by its distance to a mesh, timed as a whole
process by the caller: read the mesh and the points, build a RaycastingScene (Embree),
compute_distance (unsigned, float32), write the points with a `deviation` attribute as binary
PLY. The peer of `pointsurf evaluate MESH --reference POINTS --sign unsigned --out OUT.ply`."""
import sys

import numpy as np
import open3d as o3d


def main():
    mesh_path, points_path, out = sys.argv[1:4]
    mesh = o3d.t.io.read_triangle_mesh(mesh_path)
    cloud = o3d.t.io.read_point_cloud(points_path)
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(mesh)
    d = scene.compute_distance(cloud.point["positions"].to(o3d.core.Dtype.Float32))
    cloud.point["deviation"] = d.reshape((-1, 1))
    if not o3d.t.io.write_point_cloud(out, cloud):
        raise SystemExit(f"could not write {out}")
    print(f"{len(d)} points, max {float(d.max().item()):.6g}")


if __name__ == "__main__":
    main()
