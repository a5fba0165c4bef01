"""The ``{sb-gallery}`` directive: the paper's figures, made while the docs build.

Each recipe of :data:`stairbounce.figures.FIGURES` runs at a small scale
(``sb_gallery_scale`` times its pixel counts, ``sb_gallery_max_iter``) into the build's own scratch folder (beside its
doctrees, never the source tree), and the page shows every image with the
recipe's title and its comparison with the paper.  A failing recipe fails the
build (a warning, and the build runs with ``-W``).  Only the HTML-like
builders make the figures; the doctest builder skips them.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

from docutils import nodes
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective

logger = logging.getLogger(__name__)

_IMAGE_BUILDERS = {"html", "dirhtml", "singlehtml"}


class GalleryDirective(SphinxDirective):
    has_content = False
    option_spec = {}

    def run(self):
        app = self.env.app
        if app.builder.name not in _IMAGE_BUILDERS:
            return [nodes.paragraph(text="(the gallery is made by the HTML build)")]
        from stairbounce.figures import CRITERION, Settings, make_figures

        out = Path(app.doctreedir) / "sb_gallery"
        settings = Settings(out=out, fmt="png", dpi=70, scale=app.config.sb_gallery_scale,
                            max_iter=app.config.sb_gallery_max_iter, cache_dir=None)
        t0 = time.perf_counter()
        results = make_figures(settings)
        logger.info(f"[sb-gallery] {len(results)} figures in {time.perf_counter() - t0:.1f} s")
        section_nodes = []
        note = nodes.paragraph(text=(
            f"Made by stairbounce {app.config.release} while this page was built: "
            f"every pixel count of the paper's grids times {settings.scale:g}, "
            f"max_iter = {settings.max_iter}. The command stairbounce figures makes them full size. "
            f"Verdicts as in the report: {CRITERION}").replace("**", ""))
        section_nodes.append(note)
        for res in results:
            if res.error:
                logger.warning(f"[sb-gallery] recipe {res.name} failed: {res.error}",
                               location=(self.env.docname, self.lineno))
                continue
            sec = nodes.section(ids=[nodes.make_id(f"gallery-{res.name}")])
            sec += nodes.title(text=f"{res.name}: {res.title}")
            for name in res.files:
                # "/..." is relative to the source folder in Sphinx
                uri = "/" + os.path.relpath(out / name, self.env.srcdir).replace(os.sep, "/")
                self.env.note_dependency(str(out / name))
                sec += nodes.image(uri=uri, alt=f"{res.name} ({name})", width="90%")
            rows = [r for r in res.rows]
            if rows:
                sec += _table(rows)
            section_nodes.append(sec)
        return section_nodes


def _table(rows):
    table = nodes.table()
    group = nodes.tgroup(cols=4)
    table += group
    for width in (30, 25, 25, 10):
        group += nodes.colspec(colwidth=width)
    head = nodes.thead()
    group += head
    head += _row(["quantity", "paper", "here", "verdict"])
    body = nodes.tbody()
    group += body
    for r in rows:
        # the report's own verdict and words (stairbounce.figures.CRITERION):
        # agrees / differs / not comparable, with why
        body += _row([r.quantity, r.paper, r.measured, r.verdict_text()])
    return table


def _row(cells):
    row = nodes.row()
    for text in cells:
        entry = nodes.entry()
        entry += nodes.paragraph(text=str(text))
        row += entry
    return row


def setup(app):
    app.add_config_value("sb_gallery_scale", 0.12, "env")
    app.add_config_value("sb_gallery_max_iter", 300, "env")
    app.add_directive("sb-gallery", GalleryDirective)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
