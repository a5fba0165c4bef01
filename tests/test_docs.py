"""The documentation: the Sphinx site builds with warnings as errors while
executing its examples (MyST-NB runs the pages' figure cells and the tutorial
notebook, each in a fresh kernel; the gallery runs the figure recipes), and
every Python example of the README and of the pages runs as a reader would
paste it: each page in a fresh interpreter, top to bottom, with no hidden
set-up (``tests/pasted.py``), printed outputs checked."""

from __future__ import annotations

import json
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
PAGES = [ROOT / "README.md", *sorted(DOCS.glob("*.md")), *sorted((DOCS / "guide").glob("*.md"))]

sys.path.insert(0, str(Path(__file__).resolve().parent))
import pasted  # noqa: E402

pytest.importorskip("sphinx")
pytest.importorskip("myst_nb")


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
    # the gallery shows the code that makes each figure, and no verdicts (they
    # live in the report of `stairbounce figures`, made at full size)
    shown = re.sub(r"<[^>]+>", "", gallery)  # the code as a reader sees it (highlighting removed)
    for name in FIGURES:
        assert f"stairbounce figures --only {name}" in shown, name
    # (outside the code shown: a recipe's own source computes its report rows)
    text = re.sub(r"<[^>]+>", " ", re.sub(r"<pre>.*?</pre>", " ", gallery, flags=re.S))
    for verdict in ("agrees", "differs", "not comparable"):
        assert not re.search(rf"\b{verdict}\b", text), verdict
    # the guide pages slot in through the user guide's glob toctree, in reading order
    index = (out / "index.html").read_text()
    for page in ("guide/index", "guide/model", "guide/scans", "guide/orbits", "guide/explorer", "guide/dask",
                 "guide/paper", "guide/robustness", "guide/numerics", "tutorial", "gallery", "api", "citing",
                 "changelog"):
        assert f'href="{page}.html"' in index, page
    guide = (out / "guide" / "index.html").read_text()
    order = [guide.index(f'href="{name}.html"') for name in ("model", "scans", "paper", "dimension", "orbits")]
    assert order == sorted(order)
    # pages whose examples draw show the figures, made while the site was built
    for page, least in (("getting-started", 1), ("guide/model", 1), ("guide/scans", 2), ("guide/orbits", 1),
                        ("guide/dimension", 2), ("guide/motion", 3), ("guide/dask", 1), ("guide/explorer", 2)):
        html = (out / f"{page}.html").read_text()
        images = re.findall(r'<img[^>]+src="(?:\.\./)?_images/([^"]+)"', html)
        assert len(images) >= least, page
        for name in images:
            assert (out / "_images" / name).stat().st_size > 1000, (page, name)
    # formulas are typeset (MathJax), not ASCII code
    model = (out / "guide" / "model.html").read_text()
    assert model.count('class="math') >= 5 and "sqrt((n-1)/2)" not in model
    # the maintained theme
    assert "pydata-sphinx-theme" in index or "pydata_sphinx_theme" in index
    # the tutorial is a page of the site, executed while it was built: its
    # figures, its printed results and the explorer inline
    tutorial = (out / "tutorial.html").read_text()
    assert len(re.findall(r'<img[^>]+src="_images/', tutorial)) >= 5
    assert "of the pixels have a periodic sliding solution" in tutorial and "D = " in tutorial
    assert "data-root-id" in tutorial  # Panel's rendered page
    assert list((out / "_downloads").rglob("tutorial.ipynb"))


def _examples_of(page):
    return [b for b in pasted.blocks(page.read_text())]


@pytest.mark.slow
@pytest.mark.parametrize("page", [p for p in PAGES if _examples_of(p)], ids=lambda p: str(p.relative_to(ROOT)))
def test_every_example_runs_as_pasted(page, tmp_path):
    # a fresh interpreter per page, in an empty folder (examples that write files
    # write there), with nothing defined beforehand
    r = subprocess.run([sys.executable, str(ROOT / "tests" / "pasted.py"), str(page)], capture_output=True,
                       text=True, env=_env(), cwd=tmp_path)
    assert r.returncode == 0, r.stderr[-4000:]
    summary = json.loads(r.stdout.strip().splitlines()[-1])
    assert not summary["failures"], "\n".join(summary["failures"])[-6000:]
    assert summary["blocks"] + len(summary["not_run"]) >= 1, summary
    # a block is left out only with its reason stated
    for entry in summary["not_run"]:
        assert entry.split(": ", 1)[1].strip(), entry


def test_the_pages_hold_the_examples_and_no_hidden_setup():
    conf = (DOCS / "conf.py").read_text()
    assert "doctest_global_setup" not in conf
    counted = 0
    for page in PAGES:
        for kind, source, line, reason in pasted.blocks(page.read_text()):
            if kind in pasted.DOCTEST_KINDS:
                counted += source.count(">>> ")
    # the 121 checked examples of the pages before they ran as pasted, and more
    assert counted >= 121, counted


def test_the_runner_checks_outputs_and_refuses_hidden_names(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("```python\nx = 2\n```\n\n```{doctest}\n>>> x + 1\n4\n```\n\n"
                    "```{doctest}\n>>> sb.scan\n...\n```\n")
    summary = pasted.run(page)
    assert summary["blocks"] == 3 and len(summary["failures"]) == 2
    assert "Expected:\n    4\nGot:\n    3" in summary["failures"][0]
    assert "NameError: name 'sb' is not defined" in summary["failures"][1]


def test_notebook_is_committed_without_outputs():
    nbformat = pytest.importorskip("nbformat")
    nb = nbformat.read(NOTEBOOK, as_version=4)
    for cell in nb.cells:
        if cell.cell_type == "code":
            assert cell.outputs == [] and cell.execution_count is None, cell.source[:60]
