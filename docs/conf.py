"""Sphinx configuration of the stairbounce documentation.

Build: ``sphinx-build -W --keep-going -b html docs docs/_build/html``;
examples: ``sphinx-build -W -b doctest docs docs/_build/doctest``.
The package is imported from ``src/`` so that the pages document this
checkout, whatever is installed.
"""

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "src"))
sys.path.insert(0, str(HERE / "_ext"))
os.environ.setdefault("MPLBACKEND", "Agg")

import stairbounce  # noqa: E402

project = "stairbounce"
author = "stairbounce developers"
copyright = "stairbounce developers"
release = stairbounce.__version__
version = release

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.doctest",
    "sphinx.ext.mathjax",
    "sb_gallery",
]

source_suffix = {".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "**.ipynb_checkpoints", "tutorial.ipynb"]
myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3
suppress_warnings = ["myst.header"]

autodoc_member_order = "bysource"
autodoc_typehints = "none"  # the signatures carry no annotations worth showing
autodoc_default_options = {"members": False}
napoleon_numpy_docstring = True
napoleon_google_docstring = False
napoleon_use_rtype = False

# every doctest group starts from the flat API, on a non-interactive backend
doctest_global_setup = """
import numpy as np
import stairbounce as sb
"""
doctest_default_flags = (
    __import__("doctest").ELLIPSIS
    | __import__("doctest").NORMALIZE_WHITESPACE
)

html_theme = "alabaster"
html_title = f"stairbounce {release}"
html_static_path = []
html_theme_options = {"description": "a ball bouncing down a staircase", "fixed_sidebar": True}

# gallery: the paper's figures made by stairbounce.figures at build time,
# small so that the whole build stays quick (see _ext/sb_gallery.py)
sb_gallery_scale = float(os.environ.get("SB_GALLERY_SCALE", "0.12"))
sb_gallery_max_iter = int(os.environ.get("SB_GALLERY_MAX_ITER", "300"))


# The user guide's toctree says "guide/*", so that a new page slots in by
# existing; a glob sorts by name, so the pages that exist are listed first in
# reading order and the glob keeps only for pages not named here.
GUIDE_ORDER = ["model", "scans", "dimension", "orbits", "motion", "explorer", "dask"]


def _order_guide(app, docname, source):
    if docname != "index":
        return
    present = {p.stem for p in (HERE / "guide").glob("*.md")}
    lines = [f"guide/{name}" for name in GUIDE_ORDER if name in present]
    if present - set(GUIDE_ORDER):
        lines.append("guide/*")
    source[0] = source[0].replace("\nguide/*\n", "\n" + "\n".join(lines) + "\n", 1)


def setup(app):
    app.connect("source-read", _order_guide)
