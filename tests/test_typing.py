"""The package ships type hints (``py.typed``, PEP 561): mypy checks the
package with the configuration in pyproject.toml ([tool.mypy]), and the public
API's hints reach a user's code: a well-typed use passes, a misuse is caught."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"

def _mypy(*args, cwd=ROOT):
    # the package of this checkout, whatever is installed, with the project's
    # settings; the cache beside the repository keeps a rerun to seconds
    env = dict(os.environ, MYPYPATH=str(SRC))
    cmd = [sys.executable, "-m", "mypy", "--config-file", str(ROOT / "pyproject.toml"),
           "--cache-dir", str(ROOT / ".mypy_cache"), *args]
    return subprocess.run(cmd, capture_output=True, text=True, cwd=cwd, env=env)


def test_package_is_marked_as_typed():
    assert (SRC / "stairbounce" / "py.typed").is_file()


def test_mypy_passes_on_the_package():
    r = _mypy()
    assert r.returncode == 0, r.stdout[-4000:] + r.stderr[-2000:]
    assert "Success: no issues found" in r.stdout


def test_the_public_hints_reach_a_users_code(tmp_path):
    good = tmp_path / "good.py"
    good.write_text(textwrap.dedent("""
        import numpy as np
        import stairbounce as sb

        y, v, k = sb.poincare_map(1.0, 0.0, 0.5, 0.3)
        n: int = sb.impact_number(1, -0.3, 0.6, 0.2)
        lo, hi = sb.tongue(2, np.float32(0.1))
        bound: float = sb.no_sliding_bound(0.5)
        fit = sb.box_dimension(np.ones((64, 64), dtype=bool))
        d: float = fit.dimension
    """))
    r = _mypy(str(good), cwd=tmp_path)
    assert r.returncode == 0, r.stdout
    bad = tmp_path / "bad.py"
    bad.write_text(textwrap.dedent("""
        import stairbounce as sb

        a: str = sb.impact_number(1, -0.3, 0.6, 0.2)
        b = sb.tongue("2", 0.1)
        c = sb.box_dimension(None)
    """))
    r = _mypy(str(bad), cwd=tmp_path)
    assert r.returncode == 1, r.stdout
    # each misuse is named at its own line
    for line in (4, 5, 6):
        assert f"bad.py:{line}: error" in r.stdout, r.stdout
