# SPDX-License-Identifier: GPL-3.0-or-later
"""The committed type stub is the one the registry generates now."""
import subprocess
import sys
from pathlib import Path

TOOL = Path(__file__).resolve().parents[1] / "tools" / "make_stubs.py"


def test_committed_stub_is_current():
    r = subprocess.run([sys.executable, str(TOOL), "--check"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


def test_stub_is_valid_python():
    stub = TOOL.parents[1] / "pointsurf" / "__init__.pyi"
    compile(stub.read_text(), str(stub), "exec")  # e.g. no parameter named twice


def _typed_dicts():
    """The stub's TypedDicts written as calls: name -> {key: type text}."""
    import ast
    stub = TOOL.parents[1] / "pointsurf" / "__init__.pyi"
    out = {}
    for node in ast.parse(stub.read_text()).body:
        if isinstance(node, ast.Assign) and isinstance(node.value, ast.Call) and getattr(node.value.func, "id", "") == "TypedDict":
            fields = node.value.args[1]
            out[node.targets[0].id] = {ast.literal_eval(k): ast.unparse(v) for k, v in zip(fields.keys, fields.values)}
    return out


def test_stage_results_are_typed_from_the_declarations():
    import numpy as np
    import pointsurf
    dicts = _typed_dicts()
    # The stub types exactly what the registry declares.
    normals = next(s for s in pointsurf.STAGES if s["name"] == "normals")
    assert set(dicts["NormalsCounts"]) == {r["key"] for r in normals["results"] if r["block"] == "counts"}
    assert dicts["NormalsMetrics"]["mean_spacing"] == "float"
    assert dicts["EvaluateMetricsDeviation"]["rms"] == "float"
    # A run's record holds only typed keys, of their types.
    rng = np.random.default_rng(1)
    p = rng.normal(size=(400, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    out = pointsurf.normals(pointsurf.PointCloud(positions=p), k=16)
    python_type = {"int": int, "float": float, "bool": bool, "str": str}
    for block, name in (("counts", "NormalsCounts"), ("metrics", "NormalsMetrics")):
        assert out.report[block], block
        for key, value in out.report[block].items():
            assert key in dicts[name], f"{block} {key} is not typed"
            assert isinstance(value, python_type[dicts[name][key]]), (key, value)
