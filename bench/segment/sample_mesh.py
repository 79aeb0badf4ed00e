#!/usr/bin/python3
# Samples a mesh uniformly by area with its face normals (Open3D, seeded) into the segment
# bench's inputs, every point's "truth" -1 (a mesh has no primitive labels); prints N and the
# mean spacing (nearest-neighbour distance).
#   sample_mesh.py MESH N OUT.ply OUT.bin
import sys
import numpy as np
import open3d as o3d

from scene_io import write_scene

mesh_path, n, out_ply, out_bin = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
mesh = o3d.io.read_triangle_mesh(mesh_path)
mesh.compute_triangle_normals()
o3d.utility.random.seed(3)
pcd = mesh.sample_points_uniformly(n, use_triangle_normal=True)
points, normals = np.asarray(pcd.points), np.asarray(pcd.normals)
write_scene(np.c_[points, normals], np.full(len(points), -1, dtype=np.int32), out_ply, out_bin)
print(len(points), float(np.mean(pcd.compute_nearest_neighbor_distance())))
