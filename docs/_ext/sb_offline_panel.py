"""Offline widgets: the tutorial's Panel output loads Bokeh and Panel from the site itself.

The tutorial notebook ends with the explorer inline (``sb.explorer.inline()``).
Executed while the site is built, its output is Panel's notebook bundle: a
script that fetches BokehJS and Panel's JavaScript and CSS from the public CDNs
(``cdn.bokeh.org/bokeh/release/...`` and ``cdn.holoviz.org/panel/<version>/dist/...``)
and then draws the explorer's first view (a static picture on the site: the
callbacks need a running kernel).  With no network that page would show nothing.

After an HTML build this extension finds every such URL in the built pages,
copies the file it names from the installed ``bokeh`` and ``panel`` packages
(the same versions that wrote the output: ``bokeh/server/static/js/bokeh-NAME.min.js``
for ``bokeh-NAME-<version>.min.js``, ``panel/dist/PATH`` for ``.../dist/PATH``)
into ``_static/offline/`` and rewrites the URL as a path relative to the page.
Only the files that pages name are copied (about 3 MB, not the packages' 130 MB).
A URL whose file the installed packages do not hold fails the build, naming it.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

from sphinx.errors import ExtensionError
from sphinx.util import logging

logger = logging.getLogger(__name__)

CDN = re.compile(r"https://cdn\.(?:bokeh\.org/bokeh/release|holoviz\.org/panel/[0-9][0-9a-z.\-]*/dist)"
                 r"/[^\"'\s\\)<>]+")
_BOKEH_FILE = re.compile(r"^(bokeh(?:-[a-z]+)?)-[0-9][0-9a-z.\-]*?(\.min\.js|\.js)$")


def local_file(url: str) -> tuple[Path, str]:
    """The installed file a CDN URL names, and its path under ``_static/offline/``."""
    import bokeh
    import panel

    if "cdn.bokeh.org" in url:
        name = url.rsplit("/", 1)[1]
        m = _BOKEH_FILE.match(name)
        if not m:
            raise ExtensionError(f"[sb-offline] a BokehJS URL of an unknown form: {url}")
        local = m.group(1) + m.group(2)
        return Path(bokeh.__file__).parent / "server" / "static" / "js" / local, f"bokeh/{local}"
    path = url.split("/dist/", 1)[1]
    return Path(panel.__file__).parent / "dist" / path, f"panel/{path}"


def rewrite(html: str, page_dir_depth: int, copy) -> str:
    """``html`` with every CDN URL replaced by a relative path; ``copy(src, rel)`` is called per file."""
    prefix = "../" * page_dir_depth + "_static/offline/"

    def sub(m):
        src, rel = local_file(m.group(0))
        if not src.is_file():
            raise ExtensionError(f"[sb-offline] {m.group(0)} names {src}, which the installed "
                                 "bokeh/panel do not hold: the page would need the network")
        copy(src, rel)
        return prefix + rel

    return CDN.sub(sub, html)


def _offline(app, exc):
    if exc is not None or app.builder.format != "html":
        return
    out = Path(app.outdir)
    dest = out / "_static" / "offline"
    copied: set[str] = set()

    def copy(src: Path, rel: str) -> None:
        if rel not in copied:
            (dest / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dest / rel)
            copied.add(rel)

    pages = 0
    for page in out.rglob("*.html"):
        html = page.read_text(encoding="utf-8")
        if not CDN.search(html):
            continue
        depth = len(page.relative_to(out).parts) - 1
        page.write_text(rewrite(html, depth, copy), encoding="utf-8")
        pages += 1
    if pages:
        logger.info(f"[sb-offline] {len(copied)} Bokeh/Panel files served by the site for {pages} page(s)")


def setup(app):
    app.connect("build-finished", _offline)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
