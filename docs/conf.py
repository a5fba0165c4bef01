"""Sphinx configuration of the stairbounce documentation.

Build: ``sphinx-build -W --keep-going -b html docs docs/_build/html``.  The
build executes the examples: MyST-NB runs the code cells of the pages that are
notebooks (their figures appear on the page) and the tutorial notebook, each in
a fresh Jupyter kernel; the ``{sb-gallery}`` directive runs the paper's figure
recipes.  The ``{doctest}`` examples are checked by ``tests/test_docs.py``,
each page in a fresh interpreter as a reader would paste it (no set-up code
is added).  The package is imported from ``src/`` so that the pages document
this checkout, whatever is installed (the kernels get it through PYTHONPATH).
"""

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
SRC = HERE.parent / "src"
sys.path.insert(0, str(SRC))
sys.path.insert(0, str(HERE / "_ext"))
# the kernels that execute the pages import this checkout too
os.environ["PYTHONPATH"] = os.pathsep.join(p for p in (str(SRC), os.environ.get("PYTHONPATH", "")) if p)
# a kernel draws its figures with the notebook's inline backend only when no
# other backend is forced on it (the gallery's recipes choose Agg themselves)
os.environ.pop("MPLBACKEND", None)

import stairbounce  # noqa: E402

project = "stairbounce"
author = "stairbounce developers"
copyright = "2026, stairbounce developers"
release = stairbounce.__version__
version = release

extensions = [
    "myst_nb",  # MyST Markdown (it includes myst_parser) and executed notebooks
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.doctest",
    "sphinx.ext.mathjax",
    "sb_gallery",
]

root_doc = "index"
exclude_patterns = ["_build", "**.ipynb_checkpoints"]
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence"]
myst_heading_anchors = 3
# the explorer's Panel output in the tutorial needs a live kernel: its widget mime types
# have no static rendering (the page shows the rest of the notebook)
suppress_warnings = ["myst.header", "mystnb.unknown_mime_type"]

# MyST-NB: every notebook page (docs/tutorial.ipynb, and a Markdown page whose
# front matter says ``file_format: mystnb``) is executed by each build, in a
# fresh kernel, from the first cell to the last; an error fails the build
nb_execution_mode = os.environ.get("SB_DOCS_EXECUTE", "force")
nb_execution_timeout = 600
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_merge_streams = True

autodoc_member_order = "bysource"
autodoc_typehints = "none"  # the docstrings state the types in words
autodoc_default_options = {"members": False}
napoleon_numpy_docstring = True
napoleon_google_docstring = False
napoleon_use_rtype = False

doctest_default_flags = (
    __import__("doctest").ELLIPSIS
    | __import__("doctest").NORMALIZE_WHITESPACE
)

html_theme = "pydata_sphinx_theme"
html_title = f"stairbounce {release}"
html_static_path = ["_static"]
html_css_files = ["stairbounce.css"]
html_theme_options = {
    "navigation_with_keys": False,
    "header_links_before_dropdown": 6,
    "show_toc_level": 2,
    # no right-hand column: the article takes its width, so that code lines of
    # up to 100 characters fit beside the navigation on a 1280 px screen
    "secondary_sidebar_items": [],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
    "pygments_light_style": "default",
    "pygments_dark_style": "github-dark",
}
html_sidebars = {"index": [], "gallery": [], "api": []}

# gallery: the paper's figures made by stairbounce.figures at build time,
# small so that the whole build stays quick (see _ext/sb_gallery.py)
sb_gallery_scale = float(os.environ.get("SB_GALLERY_SCALE", "0.25"))
sb_gallery_max_iter = int(os.environ.get("SB_GALLERY_MAX_ITER", "300"))


# The user guide's toctree (guide/index.md) says "*", so that a new page slots in by
# existing; a glob sorts by name, so the pages that exist are listed first in
# reading order and the glob keeps only for pages not named here.
GUIDE_ORDER = ["model", "scans", "paper", "dimension", "dimension-study", "borders", "orbits",
               "motion", "explorer", "dask", "cli", "cluster", "explorer-server", "robustness",
               "numerics", "speed"]


def _order_guide(app, docname, source):
    if docname != "guide/index":
        return
    present = {p.stem for p in (HERE / "guide").glob("*.md")} - {"index"}
    lines = [name for name in GUIDE_ORDER if name in present]
    if present - set(GUIDE_ORDER):
        lines.append("*")
    source[0] = source[0].replace("\n*\n", "\n" + "\n".join(lines) + "\n", 1)


def setup(app):
    app.connect("source-read", _order_guide)
