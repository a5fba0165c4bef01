"""Offline maths: the site serves MathJax itself, so formulas typeset with no network.

The MathJax files come from the ``django-static-mathjax`` wheel (the ``[docs]``
extra), which packages the MathJax team's own release (MathJax 3.2.2, the
``es5`` components of the ``mathjax-full`` npm package, Apache-2.0) as plain
files; nothing of Django is used.  After an HTML build this extension copies
the component that the pages load (``tex-chtml.js``, named by ``mathjax_path``
in conf.py) and what it loads on demand (TeX extensions, the CHTML fonts, the
menu and its accessibility parts) into ``_static/mathjax/`` of the built site.
The pages then refer to ``_static/mathjax/tex-chtml.js`` by a relative path,
which works over ``file://`` and over HTTP alike.  A missing package fails the
build with a message that says what to install.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from sphinx.errors import ExtensionError
from sphinx.util import logging

logger = logging.getLogger(__name__)

# what tex-chtml.js loads on demand, relative to it
_PARTS = ("input/tex/extensions", "output/chtml/fonts/woff-v2", "ui", "a11y", "sre", "adaptors")


def mathjax_source() -> Path:
    """The folder of MathJax's components in the installed wheel."""
    try:
        import mathjax  # the django-static-mathjax wheel's package (data only)
    except ImportError as exc:  # pragma: no cover - the [docs] extra installs it
        raise ExtensionError("the documentation serves MathJax itself: pip install "
                             "django-static-mathjax (in the [docs] extra)") from exc
    root = Path(mathjax.__file__).resolve().parent / "static" / "mathjax" / "es5"
    if not (root / "tex-chtml.js").is_file():  # pragma: no cover
        raise ExtensionError(f"no MathJax component tex-chtml.js under {root}")
    return root


def _check_path(app, config):
    if config.mathjax_path.startswith(("http:", "https:", "//")):
        raise ExtensionError(f"mathjax_path is a URL ({config.mathjax_path}): the site must "
                             "typeset its maths offline; name a file under _static/")
    mathjax_source()


def _copy(app, exc):
    if exc is not None or app.builder.format != "html":
        return
    src = mathjax_source()
    dest = Path(app.outdir) / "_static" / Path(app.config.mathjax_path).parent
    dest.mkdir(parents=True, exist_ok=True)
    shutil.copy2(src / Path(app.config.mathjax_path).name, dest)
    for part in _PARTS:
        shutil.copytree(src / part, dest / part, dirs_exist_ok=True)
    logger.info(f"[sb-mathjax] MathJax copied into {dest}")


def setup(app):
    app.connect("config-inited", _check_path)
    app.connect("build-finished", _copy)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
