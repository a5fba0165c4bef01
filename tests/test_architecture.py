"""docs/design.md's one-way data flow: the core imports no plotting, CLI or web code."""

import subprocess
import sys

import pytest

CORE = ["_validate", "model", "symbolic", "trajectory", "units", "plane", "orbits", "fractal", "atlas",
        "atlas_boxes", "nonsliding", "borders", "regions", "_io", "_interrupt"]
FORBIDDEN = ["matplotlib", "typer", "rich", "bokeh", "panel", "dask", "distributed"]


@pytest.mark.parametrize("module", CORE)
def test_core_module_imports_no_plotting_cli_or_web(module):
    code = (
        f"import sys, stairbounce.{module}; "
        f"print([m for m in {FORBIDDEN!r} if m in sys.modules])"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert r.stdout.strip() == "[]", f"stairbounce.{module} imports {r.stdout.strip()}"
