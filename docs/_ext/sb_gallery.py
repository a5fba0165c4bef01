"""The ``{sb-gallery}`` directive: the paper's figures, made while the docs build.

Each recipe of :data:`stairbounce.figures.FIGURES` runs at a reduced scale
(``sb_gallery_scale`` times its pixel counts, ``sb_gallery_max_iter``) into the
build's own scratch folder (beside its doctrees, never the source tree).  The
page opens with a grid of thumbnails, each a link to its figure's section, and
shows every image at the width of the page with the recipe's caption and
the code that makes it: the command, the Python call, and the recipe's own
source.  It shows no verdicts: at a reduced scale the comparisons with the
paper's numbers mean little, and the report of ``stairbounce figures`` (full
size) is where they live.  A failing recipe fails the build (a warning, and
the build runs with ``-W``).  Only the HTML-like builders make the figures.
"""

from __future__ import annotations

import inspect
import os
import textwrap
import time
from pathlib import Path

from docutils import nodes
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective

logger = logging.getLogger(__name__)

_IMAGE_BUILDERS = {"html", "dirhtml", "singlehtml"}


def _code(text, language):
    block = nodes.literal_block(text, text)
    block["language"] = language
    return block


def _recipe_source(recipe):
    """The recipe's source, dedented (the Fig. 5 and Fig. 6/7 recipes are closures)."""
    try:
        return textwrap.dedent(inspect.getsource(recipe)).rstrip()
    except (OSError, TypeError):  # pragma: no cover - a recipe without source
        return ""


class GalleryDirective(SphinxDirective):
    has_content = False
    option_spec = {}

    def run(self):
        app = self.env.app
        if app.builder.name not in _IMAGE_BUILDERS:
            return [nodes.paragraph(text="(the gallery is made by the HTML build)")]
        from stairbounce.figures import FIGURES, Settings, make_figures

        out = Path(app.doctreedir) / "sb_gallery"
        settings = Settings(out=out, fmt="png", dpi=100, scale=app.config.sb_gallery_scale,
                            max_iter=app.config.sb_gallery_max_iter, cache_dir=None)
        t0 = time.perf_counter()
        results = make_figures(settings)
        logger.info(f"[sb-gallery] {len(results)} figures in {time.perf_counter() - t0:.1f} s")
        section_nodes = [nodes.paragraph(text=(
            f"Made by stairbounce {app.config.release} while this page was built, with every "
            f"pixel count of the paper's grids times {settings.scale:g} and max_iter = "
            f"{settings.max_iter}; the command stairbounce figures makes them full size."))]
        # a grid of thumbnails, each a link to its figure's section below
        grid = nodes.container(classes=["sb-gallery-grid"])
        section_nodes.append(grid)
        for res in results:
            if res.error:
                logger.warning(f"[sb-gallery] recipe {res.name} failed: {res.error}",
                               location=(self.env.docname, self.lineno))
                continue
            section_id = nodes.make_id(f"gallery-{res.name}")
            sec = nodes.section(ids=[section_id])
            sec += nodes.title(text=f"{res.name}: {res.title}")
            for i, name in enumerate(res.files):
                # "/..." is relative to the source folder in Sphinx
                uri = "/" + os.path.relpath(out / name, self.env.srcdir).replace(os.sep, "/")
                self.env.note_dependency(str(out / name))
                sec += nodes.image(uri=uri, alt=f"{res.name}: {res.title}", width="100%")
                if i == 0:
                    thumb = nodes.paragraph(classes=["sb-gallery-thumb"])
                    link = nodes.reference("", "", internal=True, refid=section_id)
                    link += nodes.image(uri=uri, alt=f"{res.name} (thumbnail)")
                    link += nodes.inline(text=f"{res.name}: {res.title}")
                    thumb += link
                    grid += thumb
            if res.caption:
                sec += nodes.paragraph(text=res.caption)
            sec += nodes.paragraph(text="Full size, on the command line and in Python:")
            sec += _code(f"stairbounce figures --only {res.name}", "bash")
            sec += _code("from pathlib import Path\n"
                         "from stairbounce.figures import Settings, make_figures\n\n"
                         f'make_figures(Settings(out=Path("figures")), only=["{res.name}"])', "python")
            source = _recipe_source(FIGURES[res.name])
            if source:
                sec += nodes.raw("", f"<details><summary>The recipe: <code>stairbounce.figures</code>, "
                                     f"<code>{res.name}</code></summary>", format="html")
                sec += _code(source, "python")
                sec += nodes.raw("", "</details>", format="html")
            section_nodes.append(sec)
        return section_nodes


def setup(app):
    app.add_config_value("sb_gallery_scale", 0.25, "env")
    app.add_config_value("sb_gallery_max_iter", 300, "env")
    app.add_directive("sb-gallery", GalleryDirective)
    return {"version": "2", "parallel_read_safe": True, "parallel_write_safe": True}
