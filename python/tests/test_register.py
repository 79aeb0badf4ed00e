# SPDX-License-Identifier: GPL-3.0-or-later
"""Registration through the generated stages: a known motion recovered, T.json written, several
scans merged with a field "scan"."""
import json
from pathlib import Path

import numpy as np

import pointsurf

KITTEN = Path(__file__).resolve().parents[2] / "data" / "kitten.xyz"


def _rotation_z(deg):
    a = np.radians(deg)
    return np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])


def test_register_recovers_a_known_motion(tmp_path):
    kitten = pointsurf.read(KITTEN)
    m = np.eye(4)
    m[:3, :3] = _rotation_z(25)
    m[:3, 3] = [0.1, -0.05, 0.02]
    moved = pointsurf.transform(kitten, matrix=m.flatten().tolist())
    out = pointsurf.register(moved, kitten, out=tmp_path / "T.json")
    # The moved source lies back on the kitten, and T.json holds the inverse motion.
    np.testing.assert_allclose(out.positions, kitten.positions, atol=1e-6)
    t = json.loads((tmp_path / "T.json").read_text())
    np.testing.assert_allclose(np.array(t["matrix"]), np.linalg.inv(m), atol=1e-6)
    assert t["converged"] and t["fitness"] > 0.99
    assert len(out.report["metrics"]["transform"]) == 16


def test_register_many_merges_with_a_scan_field():
    kitten = pointsurf.read(KITTEN)
    y = kitten.positions[:, 1]
    a = pointsurf.range(kitten, field="y", min=-0.5, max=0.2)
    b = pointsurf.range(kitten, field="y", min=-0.2, max=0.5)
    m = np.eye(4)
    m[:3, :3] = _rotation_z(-30)
    b = pointsurf.transform(b, matrix=m.flatten().tolist())
    merged = pointsurf.register_many([a, b])
    assert len(merged) == len(a) + len(b) == (y <= 0.2).sum() + (y >= -0.2).sum()
    scan = merged.fields["scan"]
    assert scan[0] == 0 and scan[-1] == 1 and (scan == 1).sum() == len(b)
    assert len(merged.report["metrics"]["pose_1"]) == 16
