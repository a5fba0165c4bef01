"""The picture sent with the explorer page's HTML (``explorer/preview.py``).

Its pixels are the view's own (the scan the session renders, shaded the same
way), it is sent only within its budget, and a page without it still works.
The browser side (its place on the page, its removal) is in
``tests/test_explorer_browser.py``.
"""

from __future__ import annotations

import asyncio
import base64
import io
import re
import threading
import time

import numpy as np
import pytest

pytest.importorskip("panel", reason="panel is in the web extra")
from PIL import Image  # noqa: E402

from stairbounce.explorer import preview as pv  # noqa: E402
from stairbounce.explorer.scheduler import Scheduler  # noqa: E402
from stairbounce.explorer.view import View, compute_view, parse_query, shade  # noqa: E402


@pytest.fixture(autouse=True, scope="module")
def _kernels_loaded():
    """The server loads its kernels before it sends previews (``ready``): so here."""
    shade(compute_view(View(width=16, height=16, max_iter=10)), "word_length")


def _query(**kw):
    return {k: [v.encode()] for k, v in kw.items()}


def _png_of(snippet):
    m = re.search(r'src="data:image/png;base64,([^"]+)"', snippet)
    assert m, snippet[:200]
    return np.asarray(Image.open(io.BytesIO(base64.b64decode(m.group(1)))).convert("RGBA"))


def _ask(query, sched=None, ready=None, budget=30.0):
    """The preview for ``query``; a long budget where the answer must not
    depend on the machine's load (the server's is PREVIEW_BUDGET_S)."""
    sched = Scheduler(name="preview-test") if sched is None else sched
    return asyncio.run(pv.page_preview(query, sched, ready=ready, budget=budget))


def test_the_preview_is_the_view_s_picture_u_upwards():
    q = _query(e="0.05:0.3", u="0.5:1.2", size="90x70", max_iter="500", color="period")
    snippet = _ask(q)
    img = _png_of(snippet)
    view, msgs = parse_query(q)
    assert not msgs and img.shape == (70, 90, 4)
    want = shade(compute_view(view), view.color)[::-1]  # the top row of the image is the highest u
    assert np.array_equal(img.view(np.uint32)[..., 0], want)
    assert f'width="{view.width}" height="{view.height}"' in snippet
    assert 'id="sb-preview"' in snippet and "pointer-events:none" in snippet
    assert "e 0.05 to 0.3, u 0.5 to 1.2: loading the interactive page" in snippet


@pytest.mark.parametrize("query, why", [
    (dict(size="abc"), "a bad value: the page shows the message, not a picture"),
    (dict(size="700x700"), "over PREVIEW_MAX_PIXELS"),
    (dict(nonsense="1"), "an unknown parameter is reported"),
])
def test_no_preview_for_bad_or_large_views(query, why):
    assert _ask(_query(**query)) == "", why


def test_no_preview_before_the_kernels_are_loaded():
    assert _ask(_query(size="50x50"), ready=threading.Event()) == ""
    ready = threading.Event()
    ready.set()
    assert "sb-preview" in _ask(_query(size="50x50"), ready=ready)


def test_a_preview_over_its_budget_is_cancelled_and_the_page_goes_without(monkeypatch):
    sched = Scheduler(name="preview-budget")
    slices = []

    def slow(view):  # a render of 200 slices of 10 ms, far over the budget
        for i in range(200):
            slices.append(i)
            time.sleep(0.01)
            yield None
        return b"never"

    monkeypatch.setattr(pv, "_work", slow)
    assert _ask(_query(size="50x50"), sched, budget=0.2) == ""
    assert slices, "the preview was asked for"
    deadline = time.monotonic() + 5
    while sched.busy() and time.monotonic() < deadline:  # the job is dropped at its next slice
        time.sleep(0.02)
    assert not sched.busy()
    assert len(slices) < 200, "the preview was waited for, or ran on after the page went without it"


def test_with_preview_puts_the_snippet_before_the_scripts_or_first_in_the_body():
    page = ('<html><head><meta charset="utf-8"><title>t</title><script src="x.js"></script></head>'
            '<body class="a">\n<div id="root"></div></body></html>')
    out = pv.with_preview(page, "<img id='p'>")
    assert out.index("<img id='p'>") + len("<img id='p'>") == out.index("<script")
    assert out.index("<title>") < out.index("<img id='p'>")
    assert out.replace("<img id='p'>", "") == page
    no_script = '<html><head><title>t</title></head><body class="a"><div></div></body></html>'
    out = pv.with_preview(no_script, "<img id='p'>")
    assert out.index("<img id='p'>") == out.index('<body class="a">') + len('<body class="a">')
    assert pv.with_preview(page, "") == page
    assert pv.with_preview("<html>no body</html>", "<img>") == "<html>no body</html>"


def test_the_narrow_layout_rule_follows_the_view_width():
    view = View(width=300, height=200)
    snippet = pv.preview_html(view, b"png")
    side = pv._FRAME_SIDE[0] + 300 + pv._SIDE_BY_SIDE_EXTRA
    assert f"@media (max-width:{side}px)" in snippet


def test_beside_a_long_render_the_preview_takes_its_turn_and_is_not_skipped():
    """Issue 37: a page opened while another session's long render keeps the
    worker busy went without its preview (its budget counted the wait for the
    slice under way).  The preview is placed on the fair scheduler ahead of
    the render's remaining slices (its page is a new, idle session) and the
    page waits for that turn; its budget counts its own computation.  The
    worker here is run by the test: the wait before the preview's turn is
    made longer than its budget, deterministically."""
    sched = Scheduler(thread=False, name="preview-busy")
    other = object()

    def long_render():  # another session's render, many slices
        for _ in range(100):
            time.sleep(0.06)
            yield None

    sched.submit(other, "render", long_render())
    for _ in range(10):  # under way: 0.6 s of that session's compute, over the scheduler's quantum
        sched.run_next()

    async def page():
        task = asyncio.create_task(pv.page_preview(_query(size="50x50"), sched, budget=1.0, turn=60.0))
        await asyncio.sleep(1.5)  # the slice under way outlasts the preview's budget: not a reason to skip it
        assert not task.done() and sched.busy()
        assert sched._pick().kind == "preview"  # its place: next, before the render's remaining slices
        while not task.done():
            await asyncio.to_thread(sched.run_next)
            await asyncio.sleep(0.01)
        return task.result()

    snippet = asyncio.run(page())
    assert 'id="sb-preview"' in snippet
    assert [j.kind for j in sched._jobs] == ["render"]  # the long render goes on afterwards


def test_a_preview_that_gets_no_turn_is_cancelled_and_the_page_goes_without():
    sched = Scheduler(thread=False, name="preview-no-turn")  # nothing runs: the worker never frees
    snippet = asyncio.run(pv.page_preview(_query(size="50x50"), sched, budget=30.0, turn=0.2))
    assert snippet == "" and not sched.busy()  # the job was dropped with the page's wait
