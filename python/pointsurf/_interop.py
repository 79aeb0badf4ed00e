# SPDX-License-Identifier: GPL-3.0-or-later
"""Conversions to and from plain numpy tuples and Open3D geometries (via numpy)."""
import numpy as _np

from ._pointsurf import PointCloud, TriangleMesh


def to_numpy(data):
    """(positions, normals, colors) of a PointCloud, (vertices, triangles) of a TriangleMesh:
    views of the C++ memory (no copy)."""
    if isinstance(data, TriangleMesh):
        return data.vertices, data.triangles
    return data.positions, data.normals, data.colors


def from_numpy(positions, normals=None, colors=None, triangles=None):
    """A PointCloud from N x 3 positions (optional normals, colours in [0, 1]), or a
    TriangleMesh when ``triangles`` (F x 3 indices) is given. Copies once."""
    if triangles is not None:
        return TriangleMesh(positions, triangles, normals, colors)
    return PointCloud(positions, normals, colors)


def to_open3d(data):
    """An open3d.geometry.PointCloud or TriangleMesh with the same arrays (copied by Open3D)."""
    import open3d as o3d
    v3 = o3d.utility.Vector3dVector
    if isinstance(data, TriangleMesh):
        out = o3d.geometry.TriangleMesh(v3(data.vertices), o3d.utility.Vector3iVector(data.triangles))
        if len(data.vertex_normals):
            out.vertex_normals = v3(data.vertex_normals)
        if len(data.vertex_colors):
            out.vertex_colors = v3(data.vertex_colors.astype(_np.float64))
        return out
    out = o3d.geometry.PointCloud(v3(data.positions))
    if len(data.normals):
        out.normals = v3(data.normals)
    if len(data.colors):
        out.colors = v3(data.colors.astype(_np.float64))
    return out


def from_open3d(geometry):
    """A PointCloud or TriangleMesh from an Open3D geometry (one copy)."""
    if hasattr(geometry, "triangles"):
        mesh = TriangleMesh(_np.asarray(geometry.vertices), _np.asarray(geometry.triangles))
        if geometry.has_vertex_normals():
            mesh.vertex_normals = _np.asarray(geometry.vertex_normals)
        if geometry.has_vertex_colors():
            mesh.vertex_colors = _np.asarray(geometry.vertex_colors)
        return mesh
    cloud = PointCloud(_np.asarray(geometry.points))
    if geometry.has_normals():
        cloud.normals = _np.asarray(geometry.normals)
    if geometry.has_colors():
        cloud.colors = _np.asarray(geometry.colors)
    return cloud
