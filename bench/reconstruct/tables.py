# SPDX-License-Identifier: GPL-3.0-or-later
"""Shared by the reconstruction benches' result tables (run_*_bench.sh): the JSON lines the
runners wrote, their medians, the metrics block of a mesh, number formatting and the raw CSV
under bench/results/ (appended, header once, with date and machine)."""
import csv
import datetime
import json
import os
import statistics


def load(path):
    return [json.loads(line) for line in open(path) if line.strip()]


def _matches(row, match):
    return all(row.get(k) == v for k, v in match.items())


def median(rows, key, sub=None, **match):
    """Median of row[key] (or row[key][sub]) over the rows whose fields equal `match`; None if none."""
    v = [(r[key][sub] if sub else r[key]) for r in rows if _matches(r, match) and key in r]
    return statistics.median(v) if v else None


def metrics(rows, **match):
    """The metrics block (mesh_metrics_runner) of the first matching row, or {}."""
    for r in rows:
        if _matches(r, match) and "metrics" in r:
            return r["metrics"]
    return {}


def find(d, *names):
    """The first of `names` in d or in one of its sub-dicts; None if absent."""
    for name in names:
        if name in d:
            return d[name]
        for v in d.values():
            if isinstance(v, dict) and name in v:
                return v[name]
    return None


def fmt(v, d=3):
    return "-" if v is None else (f"{v:.{d}f}" if isinstance(v, float) else str(v))


def ratio(a, b):
    return "-" if a is None or b is None or b == 0 else f"{a/b:.3f}"


def results_csv(path, header):
    """A csv writer appending to `path` (header written when the file is new), the UTC date and
    the machine, for the rows of one run."""
    new_file = not os.path.exists(path)
    out = csv.writer(open(path, "a", newline=""))
    if new_file:
        out.writerow(header)
    date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    machine = f"{os.uname().nodename} {os.cpu_count()} cores"
    return out, date, machine
