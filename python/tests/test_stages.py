# SPDX-License-Identifier: GPL-3.0-or-later
"""Every registered stage is a function (generated from the registry), callable with its
defaults; inputs stay unchanged; errors keep the library's kind and message."""
import inspect
import json

import numpy as np
import pytest

import pointsurf
from conftest import octasphere, sphere_points

NAMES = [s["name"] for s in pointsurf.STAGES]


def test_registry_is_not_empty_and_each_stage_is_a_function():
    assert {"read", "write", "normals", "reconstruct", "evaluate"} <= set(NAMES)
    for spec in pointsurf.STAGES:
        fn = getattr(pointsurf, spec["name"].replace("-", "_"))
        params = inspect.signature(fn).parameters
        for p in spec["params"]:
            assert p["name"] in params
            if p["name"] in [slot for slot, _ in spec["consumes"]]:
                continue  # the data itself (evaluate's reference)
            if p["name"] != "filename":
                defaults = [q["default"] for q in spec["params"] if q["name"] == p["name"]]
                assert params[p["name"]].default in defaults  # per method, the first shown
        assert spec["summary"] in fn.__doc__


def _inputs(spec, tmp_path, cloud, mesh):
    """Data and file arguments for a stage, chosen from its declared slots."""
    args = []
    for slot, kind in spec["consumes"]:
        if spec["shape"] == "merge":
            args.append([cloud, cloud.copy()])
        elif kind == "mesh" or slot == "mesh":
            args.append(mesh)
        else:
            args.append(cloud)
    if spec["name"] == "read":
        path = tmp_path / "in.ply"
        pointsurf.write(cloud, path)
        args.append(path)
    elif spec["shape"] in ("write", "picture"):  # register's T.json (out) is optional
        args.append(tmp_path / ("out.png" if spec["shape"] == "picture" else "out.ply"))
    return args


@pytest.mark.parametrize("name", NAMES)
def test_every_stage_runs_with_its_defaults(name, tmp_path, cloud, mesh):
    spec = next(s for s in pointsurf.STAGES if s["name"] == name)
    if spec["consumes"] and spec["consumes"][0][1] != "mesh":
        cloud = pointsurf.normals(cloud)  # stages that need normals get them
    before_cloud, before_mesh = cloud.positions.copy(), mesh.vertices.copy()
    out = getattr(pointsurf, name.replace("-", "_"))(*_inputs(spec, tmp_path, cloud, mesh))
    report = out if isinstance(out, dict) else out.report
    assert report["type"] == name
    assert "parameters" in report and "counts" in report
    if spec["produces"]:
        assert isinstance(out, (pointsurf.PointCloud, pointsurf.TriangleMesh))
    np.testing.assert_array_equal(cloud.positions, before_cloud)  # input unchanged
    np.testing.assert_array_equal(mesh.vertices, before_mesh)


def test_normals_keywords_and_report(cloud):
    out = pointsurf.normals(cloud, k=12, orient="mst")
    assert out is not cloud and len(cloud.normals) == 0
    assert out.normals.shape == (len(cloud), 3)
    # Outward on the unit sphere centred at the origin: normal . position > 0.
    assert (np.einsum("ij,ij->i", out.normals, out.positions) > 0).mean() > 0.99 or \
           (np.einsum("ij,ij->i", out.normals, out.positions) < 0).mean() > 0.99
    params = dict(out.report["parameters"]) if isinstance(out.report["parameters"], list) else out.report["parameters"]
    assert params["k"] == 12 and params["orient"] == "mst"


def test_reconstruct_then_evaluate(cloud):
    mesh = pointsurf.reconstruct(pointsurf.normals(cloud))
    assert isinstance(mesh, pointsurf.TriangleMesh) and len(mesh.triangles) > 1000
    ev = pointsurf.evaluate(mesh, cloud)
    assert ev.report["type"] == "evaluate" and ev.report["metrics"]


def test_usage_error_has_the_cli_message(cloud):
    with pytest.raises(pointsurf.UsageError, match=r'normals: k: "abc" is not an integer'):
        pointsurf.normals(cloud, k="abc")
    with pytest.raises(pointsurf.UsageError, match=r'did you mean "k"\?'):
        pointsurf.normals(cloud, kk=3)
    with pytest.raises(pointsurf.UsageError, match=r'orient: "mts" is not one of .*did you mean "mst"\?'):
        pointsurf.normals(cloud, orient="mts")
    assert issubclass(pointsurf.UsageError, pointsurf.Error)


def test_input_error_names_the_file(tmp_path):
    bad = tmp_path / "bad.ply"
    bad.write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n")
    with pytest.raises(pointsurf.InputError, match="bad.ply"):
        pointsurf.read(bad)
    with pytest.raises(pointsurf.InputError, match="missing.ply"):
        pointsurf.read(tmp_path / "missing.ply")


def test_errors_carry_their_kind_and_place(cloud, tmp_path):
    with pytest.raises(pointsurf.UsageError) as info:
        pointsurf.normals(cloud, k=2)
    e = info.value
    assert (e.kind, e.stage, e.key, e.file) == ("usage", "normals", "k", None)
    assert e.stage_index is None  # a stage call is not a pipeline: no position to show
    assert e.message == "k: 2 is out of range [3, inf)"
    with pytest.raises(pointsurf.InputError) as info:
        pointsurf.read(tmp_path / "missing.ply")
    assert info.value.kind == "input" and info.value.file.endswith("missing.ply")
    src = tmp_path / "in.ply"
    pointsurf.write(cloud, src)
    with pytest.raises(pointsurf.UsageError) as info:
        pointsurf.run([str(src), {"type": "clean"}, {"type": "normals", "kk": 16}, str(tmp_path / "x.ply")])
    e = info.value
    assert (e.stage_index, e.stage, e.key) == (3, "normals", "kk")
    assert "stage 3 (normals)" in str(e) and "stage 3" not in e.message
    with pytest.raises(pointsurf.UsageError) as info:  # raised by the Python side: the same attributes
        pointsurf.normals(cloud, cloud)
    assert (info.value.kind, info.value.stage, info.value.key) == ("usage", "normals", None)


CLOUD_FORMATS = ["ply", "xyz", "pcd", "las", "laz", "e57"]
MESH_FORMATS = ["ply", "off", "obj", "stl"]


def test_every_registered_format_is_tested():
    read = next(s for s in pointsurf.STAGES if s["name"] == "read")
    choices = set(next(p for p in read["params"] if p["name"] == "format")["choices"]) - {""}
    assert choices <= set(CLOUD_FORMATS + MESH_FORMATS), choices


def test_every_format_round_trips(tmp_path, cloud):
    for ext in CLOUD_FORMATS:
        path = tmp_path / f"c.{ext}"
        pointsurf.write(cloud, path)
        back = pointsurf.read(path)
        assert len(back) == len(cloud)
        np.testing.assert_allclose(back.positions, cloud.positions, atol=1e-4)
    v, f = octasphere(2)
    m = pointsurf.TriangleMesh(v, f)
    for ext in MESH_FORMATS:
        path = tmp_path / f"m.{ext}"
        pointsurf.write(m, path)
        back = pointsurf.read(path)
        assert isinstance(back, pointsurf.TriangleMesh) and len(back.triangles) == len(f)


def test_run_a_pipeline_list_and_file(tmp_path, cloud):
    src = tmp_path / "in.ply"
    pointsurf.write(cloud, src)
    steps = [str(src), {"type": "normals", "k": 16}, {"type": "reconstruct"}, str(tmp_path / "mesh.ply")]
    report = pointsurf.run(steps)
    assert report["status"] == "ok" and [s["type"] for s in report["stages"]] == ["read", "normals", "reconstruct", "write"]
    assert isinstance(pointsurf.read(tmp_path / "mesh.ply"), pointsurf.TriangleMesh)
    path = tmp_path / "p.json"
    steps[-1] = str(tmp_path / "mesh2.ply")
    path.write_text(json.dumps(steps))
    assert pointsurf.run(path, overrides=["normals.k=20"])["stages"][1]["parameters"]["k"] == 20
    with pytest.raises(pointsurf.UsageError, match=r'unknown key "kk"'):
        pointsurf.run([str(src), {"type": "normals", "kk": 16}, str(tmp_path / "x.ply")])


def test_declared_report_metrics_are_in_the_registry():
    evaluate = next(s for s in pointsurf.STAGES if s["name"] == "evaluate")
    rms = next(r for r in evaluate["results"] if r["key"] == "deviation/rms")
    assert (rms["type"], rms["unit"], rms["better"]) == ("number", "cloud units", "lower")
    quality = next(s for s in pointsurf.STAGES if s["name"] == "quality")
    assert {"quality/watertight", "quality/genus", "quality/angles_deg/p50"} <= {r["key"] for r in quality["results"]}
