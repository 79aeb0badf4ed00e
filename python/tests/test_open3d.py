# SPDX-License-Identifier: GPL-3.0-or-later
"""Open3D geometries to and from pointsurf's (skipped where open3d cannot be imported)."""
import numpy as np
import pytest

import pointsurf
from conftest import octasphere, sphere_points

o3d = pytest.importorskip("open3d")


def test_point_cloud_both_ways():
    p = sphere_points(300)
    c = pointsurf.normals(pointsurf.PointCloud(p, colors=np.full((300, 3), 0.5)))
    oc = pointsurf.to_open3d(c)
    assert isinstance(oc, o3d.geometry.PointCloud)
    np.testing.assert_array_equal(np.asarray(oc.points), c.positions)
    np.testing.assert_array_equal(np.asarray(oc.normals), c.normals)
    back = pointsurf.from_open3d(oc)
    np.testing.assert_array_equal(back.positions, p)
    np.testing.assert_array_equal(back.normals, c.normals)
    np.testing.assert_allclose(back.colors, 0.5)


def test_mesh_both_ways():
    v, f = octasphere(2)
    om = pointsurf.to_open3d(pointsurf.TriangleMesh(v, f))
    assert isinstance(om, o3d.geometry.TriangleMesh)
    np.testing.assert_array_equal(np.asarray(om.triangles), f)
    back = pointsurf.from_open3d(om)
    np.testing.assert_array_equal(back.triangles, f)
    np.testing.assert_array_equal(back.vertices, v)


def test_open3d_cloud_through_a_stage():
    oc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(sphere_points(1000)))
    out = pointsurf.normals(pointsurf.from_open3d(oc), k=12)
    assert len(out.normals) == 1000
