"""The documentation: the Sphinx site builds with warnings as errors, every
example in it runs (``sphinx.ext.doctest``), and the tutorial notebook
executes from top to bottom in a fresh kernel."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

import stairbounce as sb

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
NOTEBOOK = DOCS / "tutorial.ipynb"

pytest.importorskip("sphinx")
pytest.importorskip("myst_parser")


def _env():
    env = dict(os.environ, MPLBACKEND="Agg")
    # the pages document this checkout: conf.py puts src/ first on the path
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    return env


def _sphinx(builder, out):
    cmd = [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", builder, str(DOCS), str(out),
           "-d", str(out / ".doctrees")]
    r = subprocess.run(cmd, capture_output=True, text=True, env=_env(), cwd=ROOT)
    assert r.returncode == 0, f"sphinx-build -b {builder} failed:\n{r.stdout[-4000:]}\n{r.stderr[-4000:]}"
    return r


@pytest.mark.slow
def test_html_site_builds_without_warnings(tmp_path):
    out = tmp_path / "html"
    _sphinx("html", out)
    api = (out / "api.html").read_text()
    # every public name has its own documented entry, generated from its docstring
    for name in sb.__all__:
        assert f'id="stairbounce.{name}"' in api, name
    for name in sb.plot.__all__:
        assert f'id="stairbounce.plot.{name}"' in api, name
    # the gallery: each recipe of stairbounce.figures ran during the build and its image is on the page
    gallery = (out / "gallery.html").read_text()
    from stairbounce.figures import FIGURES

    images = set(re.findall(r'<img[^>]+src="_images/([^"]+)"', gallery))
    assert {f"{name}.png" for name in FIGURES} <= images
    for name in images:
        assert (out / "_images" / name).stat().st_size > 1000
    # the guide pages slot in through the glob toctree, the notebook is offered for download
    index = (out / "index.html").read_text()
    for page in ("guide/model", "guide/scans", "guide/orbits", "guide/explorer", "guide/dask"):
        assert f'href="{page}.html"' in index, page
    assert list((out / "_downloads").rglob("tutorial.ipynb"))


@pytest.mark.slow
def test_every_example_in_the_docs_runs(tmp_path):
    out = tmp_path / "doctest"
    _sphinx("doctest", out)
    summary = (out / "output.txt").read_text()
    total = summary[summary.index("Doctest summary"):]
    tests = int(re.search(r"(\d+) tests", total).group(1))
    assert tests >= 40, summary[-1000:]  # the examples were found, not skipped
    assert re.search(r"\b0 failures in tests\b", total), summary[-2000:]


def test_notebook_is_committed_without_outputs():
    nbformat = pytest.importorskip("nbformat")
    nb = nbformat.read(NOTEBOOK, as_version=4)
    for cell in nb.cells:
        if cell.cell_type == "code":
            assert cell.outputs == [] and cell.execution_count is None, cell.source[:60]


@pytest.mark.slow
def test_tutorial_notebook_executes(monkeypatch):
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    pytest.importorskip("ipykernel")
    # the kernel's own inline backend, so that figures become outputs
    monkeypatch.delenv("MPLBACKEND", raising=False)
    monkeypatch.setenv("PYTHONPATH", _env()["PYTHONPATH"])
    nb = nbformat.read(NOTEBOOK, as_version=4)
    # a failing cell (including its assert statements) raises CellExecutionError
    nbclient.NotebookClient(nb, timeout=300, kernel_name="python3", resources={"metadata": {"path": str(ROOT)}}).execute()
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs]
    pngs = [o for o in outputs if "image/png" in o.get("data", {})]
    # one bounce's trajectory, Fig. 4, the zoom, the dimension and the orbit diagram
    assert len(pngs) >= 5
    text = "".join(o.get("text", "") for o in outputs if o.output_type == "stream")
    assert "of the pixels have a periodic sliding solution" in text and "D = " in text
    # the explorer displayed inline (Panel's HTML bundle)
    assert any("application/vnd.holoviews_exec.v0+json" in o.get("data", {}) for o in outputs)
