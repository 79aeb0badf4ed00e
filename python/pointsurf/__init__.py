# SPDX-License-Identifier: GPL-3.0-or-later
"""pointsurf: raw 3D scans to verified surfaces, from Python.

Every stage of the pipeline registry is a function here, generated at import time from the
registry (names with dashes become underscores; keyword parameters named as on the command
line): ``pointsurf.normals(cloud, k=30, orient="mst")`` returns a new PointCloud with a
``.report`` dict, and leaves ``cloud`` unchanged. ``pointsurf.run(pipeline)`` runs a whole
pipeline (a list of dicts and file names, or a JSON file). See docs/python.md.
"""
import builtins as _builtins
import inspect as _inspect
import json as _json
import os as _os

from . import _pointsurf as _core
from ._pointsurf import (CancelledError, ComputeError, Error, InputError, PointCloud, TriangleMesh,
                         UsageError, __version__)
from ._interop import from_numpy, from_open3d, to_numpy, to_open3d

#: The registry as plain data: one dict per stage (name, summary, description, shape, measures,
#: consumes, produces, methods, default_method, params: [{name, type, default, unit, range, doc, ...}]).
STAGES = _core.stages()

__all__ = ["PointCloud", "TriangleMesh", "Error", "UsageError", "InputError", "ComputeError",
           "CancelledError", "STAGES", "run", "from_numpy", "to_numpy", "from_open3d", "to_open3d"]


def _text(value):
    """A Python value in the command line's (--set) form, checked by the library as there."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (str, _os.PathLike)):
        return _os.fspath(value)
    if hasattr(value, "tolist"):  # numpy scalars and arrays
        value = value.tolist()
    if isinstance(value, (list, tuple)):
        return ",".join(_text(v) for v in value)
    if isinstance(value, float):
        return repr(value)
    return str(value)


def _is_data(value):
    return isinstance(value, (PointCloud, TriangleMesh))


def _parameters(spec):
    """The stage's parameters as the signature shows them: "method" first, then the registry's."""
    params = []
    if spec["methods"]:
        params.append({"name": "method", "default": spec["default_method"], "type": "choice",
                       "doc": "one of " + ", ".join(spec["methods"]), "unit": "", "range": "",
                       "choices": spec["methods"], "methods": []})
    seen = {p["name"] for p in params}
    for p in spec["params"]:
        if p["name"] not in seen:  # a name shared by several methods is shown once
            seen.add(p["name"])
            params.append(p)
    return params


def _doc(spec):
    lines = [spec["summary"], "", spec["description"], ""]
    slots = spec["consumes"]
    if slots:
        lines.append("Data: " + ", ".join(f"{name} ({kind})" for name, kind in slots))
    lines.append("Returns: " + (f"a new {'TriangleMesh' if spec['produces'] == 'mesh' else 'PointCloud or TriangleMesh'}"
                                " with a .report dict" if spec["produces"] else "the report dict"))
    lines += ["", "Parameters (keyword only; unset ones take the registry's defaults):"]
    for p in _parameters(spec):
        extra = ", ".join(x for x in (p.get("unit", ""), p.get("range", "")) if x)
        only = f" [{', '.join(p['methods'])}]" if p.get("methods") else ""
        lines.append(f"  {p['name']} = {p['default']!r}{' (' + extra + ')' if extra else ''}{only}: {p['doc']}")
    lines.append("  progress: callable(fraction) -> bool | None; False cancels (CancelledError)")
    return "\n".join(lines)


def _usage_error(stage, message):
    """A UsageError raised here, with the attributes the library's errors carry."""
    e = UsageError(f"{stage}: {message}")
    e.kind, e.stage, e.stage_index, e.key, e.file, e.offset, e.message = "usage", stage, None, None, None, None, message
    return e


def _make_stage(spec):
    name = spec["name"]
    slots = [slot for slot, _ in spec["consumes"]]
    many = spec["shape"] == "merge"  # any number of clouds, given as a list or one by one
    # read's file in, write's and render's file out (register's T.json stays a keyword)
    takes_file = spec["shape"] in ("read", "write", "picture")

    def stage(*args, progress=None, **params):
        data, rest = [], list(args)
        if many:
            data = list(rest.pop(0)) if rest and isinstance(rest[0], (list, tuple)) else [a for a in rest if _is_data(a)]
            rest = [a for a in rest if not _is_data(a)]
        else:
            while rest and _is_data(rest[0]) and len(data) < len(slots):
                data.append(rest.pop(0))
            for slot in slots[len(data):]:
                if _is_data(params.get(slot)):
                    data.append(params.pop(slot))
        if rest and takes_file and "filename" not in params:
            params["filename"] = rest.pop(0)
        if rest:
            raise _usage_error(name, f"unexpected positional argument {rest[0]!r}")
        if not many and len(data) != len(slots):
            raise _usage_error(name, f"expected {len(slots)} data argument(s) ({', '.join(slots)}), got {len(data)}")
        given = [(key, _text(value)) for key, value in params.items() if value is not None]
        product, report = _core.run_stage(name, data, given, progress)
        report = _json.loads(report)["stages"][0]
        for key in ("index", "tag", "inputs"):  # the placeholders of the one-step pipeline
            report.pop(key, None)
        if product is None:
            return report
        product.report = report
        return product

    stage.__name__ = stage.__qualname__ = name.replace("-", "_")
    stage.__doc__ = _doc(spec)
    P = _inspect.Parameter
    sig = [P(slot, P.POSITIONAL_ONLY) for slot in slots]
    if takes_file:
        sig.append(P("filename", P.POSITIONAL_OR_KEYWORD))
    # A parameter named as a data slot (evaluate's "reference", a pipeline tag) is the data here.
    sig += [P(p["name"], P.KEYWORD_ONLY, default=p["default"]) for p in _parameters(spec)
            if p["name"] != "filename" and p["name"] not in slots]
    sig.append(P("progress", P.KEYWORD_ONLY, default=None))
    stage.__signature__ = _inspect.Signature(sig)
    return stage


for _spec in STAGES:
    _fn = _make_stage(_spec)
    globals()[_fn.__name__] = _fn
    if not hasattr(_builtins, _fn.__name__):  # "import *" must not shadow range()
        __all__.append(_fn.__name__)
del _spec, _fn


def run(pipeline, overrides=(), progress=None):
    """Runs a pipeline: a list of stages (dicts with "type" and parameter keys, file names for
    readers and writers) or the path of a JSON pipeline file. ``overrides`` are "STAGE.KEY=VALUE"
    strings (the CLI's --set). Returns the run's report dict (the schema of docs/cli.md)."""
    if isinstance(pipeline, (str, _os.PathLike)):
        path = _os.fspath(pipeline)
        try:
            with open(path, encoding="utf-8") as f:
                text = f.read()
        except OSError as e:
            raise InputError(f"{path}: cannot read the pipeline: {e.strerror}") from None
        origin = path
    else:
        text, origin = _json.dumps(list(pipeline)), "pipeline"
    return _json.loads(_core.run_json(text, origin, list(overrides), progress))
