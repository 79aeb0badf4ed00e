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
