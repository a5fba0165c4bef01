"""The documentation: the Sphinx site builds with warnings as errors while
executing its examples (MyST-NB runs the pages' figure cells and the tutorial
notebook, each in a fresh kernel; the gallery runs the figure recipes), and
every other Python example of the README and of the pages runs as a reader
would paste it: each page in a fresh interpreter, top to bottom, with no hidden
set-up (``tests/pasted.py``), printed outputs checked.  Each block runs once:
the ``{code-cell}`` blocks in the site build, the others in the pasted run."""

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
    # SB_DOCS_EXECUTE=force: the site build executes every page's {code-cell} blocks (the
    # pasted runner leaves them to it), whatever the caller's environment says
    env = dict(os.environ, MPLBACKEND="Agg", SB_DOCS_EXECUTE="force")
    # the pages document this checkout: conf.py puts src/ first on the path
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    return env


def _sphinx(builder, out):
    cmd = [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", builder, str(DOCS), str(out),
           "-d", str(out / ".doctrees")]
    r = subprocess.run(cmd, capture_output=True, text=True, env=_env(), cwd=ROOT)
    assert r.returncode == 0, f"sphinx-build -b {builder} failed:\n{r.stdout[-4000:]}\n{r.stderr[-4000:]}"
    return r


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """The HTML site, built once for the tests of this module (warnings are errors)."""
    out = tmp_path_factory.mktemp("docs") / "html"
    _sphinx("html", out)
    return out


def _guide_order():
    conf = (DOCS / "conf.py").read_text()
    return re.findall(r'"([\w-]+)"', re.search(r"GUIDE_ORDER = \[(.*?)\]", conf, re.S).group(1))


def test_the_guide_order_names_every_guide_page():
    # a page missing from GUIDE_ORDER would slot in after the last one named ("Speed")
    pages = {p.stem for p in (DOCS / "guide").glob("*.md")} - {"index"}
    order = _guide_order()
    assert len(order) == len(set(order)) and set(order) == pages, set(order) ^ pages
    assert order.index("regions") == order.index("borders") + 1


@pytest.mark.slow
def test_html_site_builds_without_warnings(site):
    out = site
    api_pages = sorted((out / "api").glob("*.html"))
    api = {page.stem: page.read_text() for page in api_pages}
    # every public name has its own documented entry, generated from its docstring,
    # on one of the API's topic pages, each page opening with a summary table
    everything = "\n".join(api.values())
    for name in sb.__all__:
        assert f'id="stairbounce.{name}"' in everything, name
    for name in sb.plot.__all__:
        assert f'id="stairbounce.plot.{name}"' in api["plot"], name
    for stem, html in api.items():
        if stem in ("index", "genindex"):
            continue
        assert 'class="autosummary' in html, stem
        entries = set(re.findall(r'<dt class="sig sig-object py" id="([\w.]+)"', html))
        assert entries, stem
        # each entry links to its highlighted source ([source], sphinx.ext.viewcode)
        assert html.count('class="viewcode-link"') >= len([e for e in entries if e.count(".") == 1]) - 1, stem
        # "On this page" lists the page's entries
        assert 'class="page-toc' in html and "On this page" in html, stem
    assert list((out / "_modules" / "stairbounce").rglob("*.html"))
    # the signature shows the type hints the package ships (py.typed)
    model = api["model"]
    sig = model[model.index('id="stairbounce.poincare_map"'):]
    sig = re.sub(r"<[^>]+>", "", sig[:sig.index("</dt>")])
    assert "y: Real" in sig and "tuple[float, float, int]" in sig, sig
    # the docstring's own signature line is not repeated under it; what it said of the
    # returned values stays
    body = re.sub(r"<[^>]+>", "", model[model.index('id="stairbounce.poincare_map"'):])[:3000]
    assert "poincare_map(y, v, e, u)" not in body
    body = re.sub(r"<[^>]+>", "", model[model.index('id="stairbounce.tongue"'):])[:3000]
    assert "tongue(n, e)" not in body and "Returns (u_low, u_high)." in body
    # a constant shows its own description, not its type's docstring
    assert "int([x])" not in model and "str(object=" not in api["index"]
    # the summary tables end a summary at the end of its sentence, not at "Prop."
    table = re.sub(r"<[^>]+>", "", model[model.index('class="autosummary'):model.index("</table>")])
    assert "edge to edge (Prop. 2.3)." in table, table
    # the gallery: each recipe of stairbounce.figures ran during the build and its image is on the page
    gallery = (out / "gallery.html").read_text()
    from stairbounce.figures import FIGURES

    images = set(re.findall(r'<img[^>]+src="_images/([^"]+)"', gallery))
    assert {f"{name}.png" for name in FIGURES} <= images
    for name in images:
        assert (out / "_images" / name).stat().st_size > 1000
    # its navigation: a grid of thumbnails linking to each figure's section, and
    # "On this page" listing them
    grid = gallery[gallery.index('class="sb-gallery-grid'):]
    toc = gallery[gallery.index('class="page-toc'):]
    for name in FIGURES:
        anchor = "gallery-" + name.replace("_", "-")  # (docutils' make_id)
        assert f'href="#{anchor}"' in grid and f'id="{anchor}"' in gallery, name
        assert f'href="#{anchor}"' in toc, name
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
                 "guide/paper", "guide/robustness", "guide/numerics", "tutorial", "gallery", "api/index",
                 "citing", "changelog"):
        assert f'href="{page}.html"' in index, page
    guide = (out / "guide" / "index.html").read_text()
    order = [guide.index(f'href="{name}.html"') for name in _guide_order()]
    assert order == sorted(order)
    # the top bar: short labels, so that it holds on one line
    navbar = index[index.index('class="bd-navbar-elements'):]
    labels = re.findall(r'<a class="nav-link nav-internal" href="[^"]+">\s*([^<]+?)\s*</a>', navbar)
    assert labels[:6] == ["Getting started", "Tutorial", "Gallery", "User guide", "API", "Reference"], labels
    # no empty "Section Navigation" column on pages without sub-pages; an
    # "On this page" column wherever a page has sections
    for page in ("getting-started", "tutorial", "gallery"):
        html = (out / f"{page}.html").read_text()
        assert "Section Navigation" not in html, page
        assert 'class="page-toc' in html, page
    assert "Section Navigation" in (out / "guide" / "model.html").read_text()
    # pages whose examples draw show the figures, made while the site was built
    for page, least in (("getting-started", 1), ("guide/model", 1), ("guide/scans", 2), ("guide/orbits", 1),
                        ("guide/dimension", 2), ("guide/motion", 3), ("guide/dask", 1), ("guide/explorer", 2)):
        html = (out / f"{page}.html").read_text()
        images = re.findall(r'<img[^>]+src="(?:\.\./)?_images/([^"]+)"', html)
        assert len(images) >= least, page
        for name in images:
            assert (out / "_images" / name).stat().st_size > 1000, (page, name)
    # formulas are typeset (MathJax), not ASCII code, by the site's own copy of
    # MathJax: no page loads a script from the network
    model = (out / "guide" / "model.html").read_text()
    assert model.count('class="math') >= 5 and "sqrt((n-1)/2)" not in model
    for page in out.rglob("*.html"):
        html = page.read_text()
        scripts = re.findall(r'<script[^>]*\ssrc="([^"]+)"', html)
        assert not [src for src in scripts if re.match(r"(https?:)?//", src)], page
        if 'class="math' in html:
            mathjax = [src for src in scripts if src.split("?")[0].endswith("mathjax/tex-chtml.js")]
            assert mathjax, page
            assert (page.parent / mathjax[0].split("?")[0]).resolve().is_file(), page
    assert list((out / "_static" / "mathjax" / "output" / "chtml" / "fonts" / "woff-v2").glob("*.woff"))
    # the maintained theme
    assert "pydata-sphinx-theme" in index or "pydata_sphinx_theme" in index
    # the tutorial is a page of the site, executed while it was built: its
    # figures, its printed results and the explorer inline
    tutorial = (out / "tutorial.html").read_text()
    assert len(re.findall(r'<img[^>]+src="_images/', tutorial)) >= 5
    assert "of the pixels have a periodic sliding solution" in tutorial and "D = " in tutorial
    assert "data-root-id" in tutorial  # Panel's rendered page
    # ... whose BokehJS and Panel files the site serves (docs/_ext/sb_offline_panel.py):
    # the notebook's output named the public CDNs
    assert "cdn.bokeh.org" not in tutorial and "cdn.holoviz.org" not in tutorial
    served = re.findall(r'_static/offline/([^"\'\s\\]+)', tutorial)
    assert "bokeh/bokeh.min.js" in served and "panel/panel.min.js" in served
    for rel in served:
        assert (out / "_static" / "offline" / rel).stat().st_size > 0, rel
    assert list((out / "_downloads").rglob("tutorial.ipynb"))


CHROMIUM = Path("/usr/bin/chromium")


@pytest.mark.slow
@pytest.mark.browser
def test_the_site_typesets_its_maths_and_navigates_offline(site):
    playwright = pytest.importorskip("playwright.sync_api")
    if not CHROMIUM.exists():
        pytest.skip("no /usr/bin/chromium (apt-get install chromium)")
    with playwright.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=str(CHROMIUM), args=["--no-sandbox"])
        context = browser.new_context(viewport={"width": 1280, "height": 800}, offline=True)
        asked = []
        context.route("**/*", lambda route: route.continue_() if route.request.url.startswith("file:")
                      else (asked.append(route.request.url), route.abort()))
        page = context.new_page()
        try:
            for name in ("guide/model", "getting-started", "api/model"):
                page.goto((site / f"{name}.html").as_uri())
                page.wait_for_load_state("load")
                spans = page.locator("article .math").count()
                if spans:
                    # MathJax replaces each formula by its rendering (no raw TeX left)
                    page.wait_for_function(
                        "n => document.querySelectorAll('article mjx-container').length >= n", arg=spans,
                        timeout=20_000)
                    assert "\\(" not in page.locator("article").inner_text(), name
                # one line of top bar, and an "On this page" column beside the article
                assert page.locator("header.bd-header").bounding_box()["height"] < 100, name
                assert page.locator(".bd-sidebar-secondary .toc-entry a").count() >= 3, name
            # the tutorial's inline explorer draws its first view with no network
            page.goto((site / "tutorial.html").as_uri())
            page.wait_for_function("() => window.Bokeh !== undefined && Bokeh.documents.length > 0",
                                   timeout=30_000)
            page.wait_for_function("() => Bokeh.documents.some(d => d.roots().length > 0)", timeout=30_000)
            # the column's links move the page to the section
            page.goto((site / "gallery.html").as_uri())
            page.locator(".sb-gallery-grid a").nth(3).click()
            page.wait_for_function("() => window.scrollY > 500")
            assert page.evaluate("location.hash").startswith("#gallery-")
        finally:
            browser.close()
    assert asked == [], asked[:5]


def _examples_of(page):
    return [b for b in pasted.blocks(page.read_text())]


@pytest.mark.slow
@pytest.mark.parametrize("page", [p for p in PAGES if _examples_of(p)], ids=lambda p: str(p.relative_to(ROOT)))
def test_every_example_runs_as_pasted(page, tmp_path):
    # a fresh interpreter per page, in an empty folder (examples that write files
    # write there), with nothing defined beforehand; the {code-cell} blocks are left to
    # the site build (test_html_site_builds_without_warnings executes each page's cells
    # in a fresh kernel, top to bottom), so that each block runs once in the suite
    r = subprocess.run([sys.executable, str(ROOT / "tests" / "pasted.py"), str(page), "--without-cells"],
                       capture_output=True, text=True, env=_env(), cwd=tmp_path)
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


def test_the_runner_leaves_the_cells_to_the_site_build_only_when_asked(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("```{code-cell} ipython3\nraise SystemExit(3)\n```\n\n```python\nx = 2\n```\n\n"
                    "```{doctest}\n>>> x + 1\n3\n```\n")
    left = pasted.run(page, cells=False)
    assert (left["blocks"], left["cells_left"], left["failures"]) == (2, 1, [])
    every = pasted.run(page)  # a reader pasting the page runs the cell too
    assert every["blocks"] == 3 and every["cells_left"] == 0 and "SystemExit: 3" in every["failures"][0]


def test_notebook_is_committed_without_outputs():
    nbformat = pytest.importorskip("nbformat")
    nb = nbformat.read(NOTEBOOK, as_version=4)
    for cell in nb.cells:
        if cell.cell_type == "code":
            assert cell.outputs == [] and cell.execution_count is None, cell.source[:60]


def test_the_numerics_page_states_the_range_of_e_the_code_accepts():
    text = (DOCS / "guide" / "numerics.md").read_text()
    assert "`e = 0` or `2^-53 <= e < 1`" in text and "`0 <= e < 1`" not in text
    for e in (0.0, 2.0**-53, 0.5, 1 - 2.0**-53):
        sb.poincare_map(1.0, 0.0, e, 0.9)
    for e in (2.0**-54, 5e-324):
        with pytest.raises(ValueError, match="2\\^-53"):
            sb.poincare_map(1.0, 0.0, e, 0.9)
    with pytest.raises(ValueError, match="e"):
        sb.poincare_map(1.0, 0.0, 1.0, 0.9)
