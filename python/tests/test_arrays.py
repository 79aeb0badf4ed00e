# SPDX-License-Identifier: GPL-3.0-or-later
"""Arrays go out as views of the C++ memory (no copy) and come in with one copy."""
import gc

import numpy as np
import pytest

import pointsurf
from conftest import octasphere, sphere_points


def test_positions_copy_in_once_and_view_out():
    p = sphere_points(100)
    c = pointsurf.PointCloud(p)
    a, b = c.positions, c.positions
    assert a.ctypes.data == b.ctypes.data  # both views of the same C++ vector
    assert a.ctypes.data != p.ctypes.data  # one copy coming in
    assert a.shape == (100, 3) and a.dtype == np.float64
    np.testing.assert_array_equal(a, p)


def test_writes_through_a_view_reach_the_cloud():
    c = pointsurf.PointCloud(sphere_points(10))
    c.positions[3] = (7.0, 8.0, 9.0)
    np.testing.assert_array_equal(c.positions[3], (7.0, 8.0, 9.0))


def test_view_keeps_its_owner_alive():
    c = pointsurf.PointCloud(np.arange(30.0).reshape(10, 3))
    view = c.positions
    del c
    gc.collect()
    assert view.base is not None
    np.testing.assert_array_equal(view[9], (27.0, 28.0, 29.0))


def test_same_size_assignment_is_in_place():
    c = pointsurf.PointCloud(sphere_points(50))
    before = c.positions.ctypes.data
    c.positions = np.zeros((50, 3))
    assert c.positions.ctypes.data == before
    assert not c.positions.any()


def test_normals_colors_fields_round_trip():
    p = sphere_points(40)
    colors = np.random.default_rng(2).random((40, 3))
    c = pointsurf.PointCloud(p, normals=p, colors=colors, fields={"intensity": np.arange(40)})
    np.testing.assert_array_equal(c.normals, p)
    assert c.colors.dtype == np.float32
    np.testing.assert_allclose(c.colors, colors, rtol=1e-6)
    f = c.fields["intensity"]
    np.testing.assert_array_equal(f, np.arange(40))
    assert f.ctypes.data == c.fields["intensity"].ctypes.data
    assert c.remove_field("intensity") and "intensity" not in c.fields


def test_mesh_arrays():
    v, f = octasphere(1)
    m = pointsurf.TriangleMesh(v, f)
    assert m.triangles.dtype == np.int32 and m.triangles.shape == (32, 3)
    assert m.triangles.ctypes.data == m.triangles.ctypes.data
    np.testing.assert_array_equal(m.triangles, f)
    np.testing.assert_array_equal(m.vertices, v)
    m.set_face_field("area", np.ones(32))
    np.testing.assert_array_equal(m.face_fields["area"], np.ones(32))


def test_bad_shapes_are_usage_errors():
    with pytest.raises(pointsurf.UsageError, match="positions: expected an N x 3 array"):
        pointsurf.PointCloud(np.zeros((4, 2)))
    with pytest.raises(pointsurf.InputError):
        pointsurf.PointCloud(np.zeros((4, 3)), normals=np.zeros((3, 3)))
    with pytest.raises(pointsurf.InputError):
        pointsurf.TriangleMesh(np.zeros((3, 3)), np.array([[0, 1, 5]]))


def test_numpy_tuples():
    p = sphere_points(20)
    c = pointsurf.from_numpy(p)
    pos, normals, colors = pointsurf.to_numpy(c)
    assert pos.ctypes.data == c.positions.ctypes.data
    assert normals.shape == (0, 3) and colors.shape == (0, 3)
    v, f = octasphere(1)
    m = pointsurf.from_numpy(v, triangles=f)
    vv, ff = pointsurf.to_numpy(m)
    np.testing.assert_array_equal(ff, f)
