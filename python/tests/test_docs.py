# SPDX-License-Identifier: GPL-3.0-or-later
"""The examples of docs/python.md run as written (from the repository root)."""
import os
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_docs_examples_run(monkeypatch):
    text = (ROOT / "docs" / "python.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert len(blocks) >= 2
    monkeypatch.chdir(ROOT)
    scope = {}  # later blocks use what earlier ones imported
    for block in blocks:
        exec(compile(block, "docs/python.md", "exec"), scope)
    assert os.path.exists("/tmp/b9_mesh.ply")
