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

import inspect
import os
import re
import sys
from pathlib import Path

import sphinx.ext.autosummary
from sphinx.errors import PycodeError
from sphinx.pycode import ModuleAnalyzer

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
    "sphinx.ext.autosummary",  # the summary table at the top of each API page
    "sphinx.ext.napoleon",
    "sphinx.ext.doctest",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",  # [source] links: the highlighted module beside each entry
    "sb_gallery",
    "sb_mathjax",  # MathJax served by the site itself: the maths typesets offline
    "sb_offline_panel",  # the tutorial's inline explorer: Bokeh and Panel served by the site
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
# The signature shown is the function's own, with the type hints the package ships
# (py.typed); a docstring's first line, which restates the signature for help() in a
# terminal, is not shown twice: _docstring_signature keeps only what it adds (the
# names of the returned values).  The docstrings state the other types in words.
autodoc_docstring_signature = False
autodoc_typehints = "signature"
autodoc_typehints_format = "short"
python_maximum_signature_line_length = 88  # longer signatures: one parameter a line
autodoc_default_options = {"members": False}
# the tables only: every entry is written out on its topic's page (docs/api/)
autosummary_generate = False
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
    # the right-hand column: "On this page" (the page's sections, and on the API
    # pages each function) and the link to the page's source
    "secondary_sidebar_items": ["page-toc", "sourcelink"],
    "footer_start": ["copyright"],
    "footer_end": ["sphinx-version"],
    "pygments_light_style": "default",
    "pygments_dark_style": "github-dark",
}
# no left column on the pages that have no sub-pages to list (it would be an empty
# "Section Navigation"); the user guide's and the API's pages list their siblings
html_sidebars = {"index": [], "getting-started": [], "tutorial": [], "gallery": []}

# maths: MathJax 3 from the django-static-mathjax wheel (the MathJax team's own
# build, the [docs] extra), copied into the site by _ext/sb_mathjax.py: no CDN
mathjax_path = "mathjax/tex-chtml.js"
mathjax3_config = {"chtml": {"displayAlign": "center"}}

# gallery: the paper's figures made by stairbounce.figures at build time,
# small so that the whole build stays quick (see _ext/sb_gallery.py)
sb_gallery_scale = float(os.environ.get("SB_GALLERY_SCALE", "0.25"))
sb_gallery_max_iter = int(os.environ.get("SB_GALLERY_MAX_ITER", "300"))


# The user guide's toctree (guide/index.md) says "*", so that a new page appears by
# existing; a glob sorts by name, so the pages named here are listed first in reading
# order and the glob keeps only a page not named here, last.  tests/test_docs.py
# fails while a page is missing here, so that none stays last ("Regions" once did).
GUIDE_ORDER = ["model", "staircase", "scans", "paper", "dimension", "dimension-study", "borders",
               "regions", "proven", "cascades", "orbits", "motion", "explorer", "dask", "cli", "cluster", "explorer-server",
               "robustness", "numerics", "speed"]


def _order_guide(app, docname, source):
    if docname != "guide/index":
        return
    present = {p.stem for p in (HERE / "guide").glob("*.md")} - {"index"}
    lines = [name for name in GUIDE_ORDER if name in present]
    if present - set(GUIDE_ORDER):
        lines.append("*")
    source[0] = source[0].replace("\n*\n", "\n" + "\n".join(lines) + "\n", 1)


_SIGNATURE_LINE = re.compile(r"^(?P<name>\w+)\(.*?\)(?:\s*->\s*(?P<returns>.+))?$")


def _docstring_signature(app, what, name, obj, options, lines):
    """Drop a docstring's first line when it restates the signature (shown above it);
    what it says of the returned values stays, as "Returns ..." (only where the
    docstring has no Returns section)."""
    if not callable(obj) or not lines:  # (sb.scan, a callable module, counts as data)
        return
    m = _SIGNATURE_LINE.match(lines[0].strip())
    if not m or m.group("name") != name.rsplit(".", 1)[-1]:
        return
    rest = lines[1:]
    while rest and not rest[0].strip():
        rest = rest[1:]
    returns = m.group("returns")
    if returns and not any(line.strip() in ("Returns", "Yields") for line in rest):
        rest = [*rest, "", f"Returns ``{returns.strip()}``."]
    lines[:] = rest


def _data_docstring(app, what, name, obj, options, lines):
    """A constant re-exported by the package (``sb.SLIDING``, ``sb.__version__``) has
    its docstring where it is defined (a string right below it, or ``#:``), not the
    docstring of its type (int's, str's), which autodoc would show."""
    if callable(obj) or lines != (inspect.getdoc(type(obj)) or "").splitlines():
        return
    short = name.rsplit(".", 1)[-1]
    for modname in sorted(m for m in sys.modules if m.startswith("stairbounce.")):
        if getattr(sys.modules[modname], short, _MISSING) is not obj:
            continue
        try:
            docs = ModuleAnalyzer.for_module(modname).find_attr_docs()
        except PycodeError:
            continue
        if ("", short) in docs:
            lines[:] = [line for line in docs[("", short)] if line.strip()]
            return
    lines[:] = []


_MISSING = object()

# autosummary's table gives each name its docstring's first sentence, ended at a period
# followed by a space: "(Prop. 2.3)" and "eq. (2.2)" are abbreviations, not ends
sphinx.ext.autosummary.WELL_KNOWN_ABBREVIATIONS += ("Prop.", "Props.", "eq.", "Eq.", "Fig.",
                                                   "Figs.", "Sec.", "Thm.", "Cor.", "cf.")


def setup(app):
    app.connect("source-read", _order_guide)
    app.connect("autodoc-process-docstring", _docstring_signature)
    app.connect("autodoc-process-docstring", _data_docstring)
