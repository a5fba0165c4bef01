"""The page's first picture, sent with its HTML.

A new page's interactive picture needs Bokeh and Panel's scripts evaluated,
a websocket, the session's document and the browser's views built before its
pixels can be painted: about 1.5 s on the idle 2-core machine for a 300 x 300
view whose computation takes 13 ms (``benchmarks/explorer_first_picture.py``
breaks it down).  So the page's HTML carries the view's picture itself, a PNG
in an ``<img>`` placed where the map's frame will be, ahead of the page's
scripts, so it is painted as soon as the HTML arrives; the interactive
picture replaces it (the
preview is removed by the map's own data source in the browser, the moment
the first pixels of the session arrive).

The preview is computed on the explorer's shared scheduler like any render
(one worker thread enters the numba kernels, sessions take turns), within a
budget: views of more than :data:`PREVIEW_MAX_PIXELS` pixels, pages asking
for a view with a bad query value (they show the message instead), and
previews not done within :data:`PREVIEW_BUDGET_S` of computation (a long
``max_iter``) send the page without one, cancelling the job.  The budget
counts from the preview's first slice: on a busy server (another session's
long render) the preview takes its place on the fair scheduler (its page is
a new, idle session, so it runs after the slice under way, or within the
scheduler's quantum) and the page waits for that turn up to
:data:`PREVIEW_TURN_S` (issue 37: the budget counted the wait, so a page
opened beside a heavy render went without its preview;
``benchmarks/explorer_preview_busy.py``).  A preview is the same scan as
the view's render, so its pixels are the picture's.
"""

from __future__ import annotations

import asyncio
import base64
import html
import io

import numpy as np

from .view import View, parse_query, render_slices, shade

__all__ = ["PREVIEW_BUDGET_S", "PREVIEW_TURN_S", "PREVIEW_MAX_PIXELS", "PREVIEW_ID", "preview_png", "preview_html",
           "page_preview", "with_preview"]

PREVIEW_MAX_PIXELS = 600 * 600
"""Largest view (pixels) whose picture is sent with the page's HTML."""

PREVIEW_BUDGET_S = 0.3
"""How long a page request waits for its preview's computation, from its
first slice, before it is sent without one."""

PREVIEW_TURN_S = 1.0
"""How long a page request waits for its preview's turn on the scheduler (the
slice under way and the quantum of a busy server's job, each bounded:
scheduler.QUANTUM, view.SLICE_WORK) before it is sent without one."""

PREVIEW_ID = "sb-preview"
"""The ``id`` of the preview's element; the map's data source removes it."""

# Where the map's frame sits on the page (CSS pixels from the page's top left),
# side by side with the controls, or below them in a window too narrow for
# both; measured in Chromium (tests/test_explorer_browser.py checks both, so a
# change of the page's layout, a widget more in the controls, says so there).
_FRAME_SIDE = (392, 64)
_FRAME_BELOW = (70, 667)
_SIDE_BY_SIDE_EXTRA = 180  # the colour bar and its labels right of the frame

# Run in the browser by the map's image source on its first data: the
# interactive picture is there, the preview goes once the canvas has painted
# it (two animation frames later), so no frame shows neither.
REMOVE_JS = (f"const p = document.getElementById({PREVIEW_ID!r}); "
             "if (p) requestAnimationFrame(() => requestAnimationFrame(() => p.remove()));")


def preview_png(view: View, rgba: np.ndarray) -> bytes:
    """The PNG of a view's shaded pixels (``rgba``: :func:`shade`'s uint32
    array, row 0 the lowest u), one image pixel per scan pixel, u upwards."""
    from PIL import Image

    pixels = np.ascontiguousarray(rgba[::-1]).view(np.uint8).reshape(view.height, view.width, 4)
    buf = io.BytesIO()
    Image.fromarray(pixels, "RGBA").save(buf, format="PNG", compress_level=1)
    return buf.getvalue()


def preview_html(view: View, png: bytes) -> str:
    """The preview's HTML: the picture where the map's frame will be (beside
    the controls, or below them when the window is too narrow for both)."""
    x, y = _FRAME_SIDE
    bx, by = _FRAME_BELOW
    narrow = x + view.width + _SIDE_BY_SIDE_EXTRA
    data = base64.b64encode(png).decode("ascii")
    what = html.escape(f"e {view.e_lo:g} to {view.e_hi:g}, u {view.u_lo:g} to {view.u_hi:g}")
    return (
        f"<style>#{PREVIEW_ID}{{position:absolute;left:{x}px;top:{y}px;z-index:10;pointer-events:none;"
        f"font:italic 13px sans-serif;color:#555}}"
        f"#{PREVIEW_ID} img{{display:block;width:{view.width}px;height:{view.height}px;"
        f"image-rendering:pixelated}}"
        f"@media (max-width:{narrow}px){{#{PREVIEW_ID}{{left:{bx}px;top:{by}px}}}}</style>"
        f'<div id="{PREVIEW_ID}"><img alt="the view ({what})" width="{view.width}" '
        f'height="{view.height}" src="data:image/png;base64,{data}">'
        f"<div>{what}: loading the interactive page ...</div></div>"
    )


def with_preview(page: str, snippet: str) -> str:
    """``page`` with ``snippet`` before its first script (Bokeh's and Panel's,
    which block the parser while they load and run: ahead of them the
    picture is painted at once), else first in its ``<body>``; unchanged
    with neither.  The page's ``<meta charset>`` and title come before its
    scripts and stay in the head."""
    if not snippet:
        return page
    body = page.find("<body")
    script = page.find("<script")
    if script >= 0 and (body < 0 or script < body):
        return page[:script] + snippet + page[script:]
    end = page.find(">", body) if body >= 0 else -1
    if end < 0:
        return page
    return page[: end + 1] + snippet + page[end + 1 :]


def _work(view: View):
    """The preview as scheduler slices (the render's own slices)."""
    ds = yield from render_slices(view)
    return preview_png(view, shade(ds, view.color))


def _announced(work, started):
    """``work``'s slices, calling ``started()`` as its first slice begins."""
    started()
    return (yield from work)


async def page_preview(query_arguments, scheduler, ready=None, budget=PREVIEW_BUDGET_S,
                       turn=PREVIEW_TURN_S) -> str:
    """page_preview(query_arguments, scheduler, ready=None, budget=PREVIEW_BUDGET_S, turn=PREVIEW_TURN_S) -> str

    The preview's HTML for a page request's query (Tornado's
    ``query_arguments``), or ``""``: when the query has a bad value, the view
    is larger than :data:`PREVIEW_MAX_PIXELS`, the kernels are not loaded yet
    (``ready``, an Event, not set), the scheduler did not start it within
    ``turn`` seconds or did not finish it within ``budget`` seconds of its
    start (the job is then cancelled).
    """
    view, messages = parse_query(query_arguments)
    if messages or view.pixels > PREVIEW_MAX_PIXELS or (ready is not None and not ready.is_set()):
        return ""
    loop = asyncio.get_running_loop()
    answer: asyncio.Future = loop.create_future()

    def done(result, error, _job):
        def give():
            if not answer.done():
                answer.set_result(None if error is not None else result)
        loop.call_soon_threadsafe(give)

    started = asyncio.Event()
    owner = object()  # a page without a session yet: an owner of its own, idle so far
    scheduler.submit(owner, "preview", _announced(_work(view), lambda: loop.call_soon_threadsafe(started.set)),
                     on_done=done)
    try:
        await asyncio.wait_for(started.wait(), turn)  # its turn: after the slice under way
        png = await asyncio.wait_for(asyncio.shield(answer), budget)
    except asyncio.TimeoutError:
        scheduler.cancel(owner)
        return ""
    return preview_html(view, png) if png else ""
