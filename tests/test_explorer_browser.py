"""``stairbounce explore`` in a real browser: Debian's Chromium driven by Playwright.

The server is the console script, started on a free localhost port in a
subprocess.  Screenshots are saved under ``test-artifacts/`` (gitignored).
Skipped only when ``/usr/bin/chromium`` or the web extra is missing.
"""

from __future__ import annotations

import io
import os
import re
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace
from urllib.parse import parse_qs, urlparse

import numpy as np
import pytest

from stairbounce import plane, sliding_word

pytestmark = pytest.mark.browser

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = [
    "--no-sandbox", "--headless", "--disable-gpu", "--disable-background-networking",
    "--disable-component-update", "--disable-sync", "--no-first-run",
]
ARTIFACTS = Path(__file__).resolve().parent.parent / "test-artifacts"

if not os.path.exists(CHROMIUM):
    pytest.skip(f"no Chromium at {CHROMIUM} (apt-get install chromium)", allow_module_level=True)
sync_api = pytest.importorskip("playwright.sync_api", reason="playwright is in the test extra")
pytest.importorskip("panel", reason="panel is in the web extra")
from PIL import Image  # noqa: E402


def _start(args, log):
    """Start ``stairbounce explore ARGS`` writing to ``log``; return (process, URL printed)."""
    exe = shutil.which("stairbounce", path=os.path.dirname(sys.executable)) or shutil.which("stairbounce")
    cmd = [exe] if exe else [sys.executable, "-c", "from stairbounce.cli import main; main()"]
    with open(log, "w") as out:
        proc = subprocess.Popen(cmd + ["explore", "--no-browser", *args],
                                stdout=out, stderr=subprocess.STDOUT)
    deadline = time.monotonic() + 60
    while True:
        m = re.search(r"stairbounce explorer at (\S+) ", log.read_text())
        if m:
            return proc, m.group(1)
        if proc.poll() is not None or time.monotonic() > deadline:
            proc.kill()
            pytest.fail(f"stairbounce explore did not start: {log.read_text()}")
        time.sleep(0.2)


def _stop(proc):
    proc.terminate()
    try:
        proc.wait(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    """``stairbounce explore --port 0``; yields its URL (as printed), log file and pid."""
    log = tmp_path_factory.mktemp("explorer") / "server.log"
    proc, url = _start(["--port", "0"], log)
    assert url.startswith("http://127.0.0.1:") and not url.endswith(":0/")
    yield SimpleNamespace(url=url, log=log, pid=proc.pid)
    _stop(proc)


@pytest.fixture(scope="module")
def browser():
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        yield b
        b.close()


@pytest.fixture
def page(browser, server):
    ARTIFACTS.mkdir(exist_ok=True)
    page = browser.new_page(viewport={"width": 1600, "height": 1000})
    errors = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    start = server.log.stat().st_size
    yield page
    page.close()
    assert not errors, f"JavaScript errors on the page: {errors}"
    with open(server.log) as f:
        f.seek(start)
        log = f.read()
    assert "Traceback" not in log and "Error" not in log, f"the server logged: {log}"


def _wait_rendered(page, timeout=90_000):
    """Wait until the status line reports a finished render; return its text."""
    done = page.locator(".sb-status .sb-info").get_by_text("computed in")
    done.wait_for(timeout=timeout)
    return done.inner_text()


def _map_canvas(page):
    # the first Bokeh canvas of the page is the map
    return page.locator(".bk-Canvas").first


def _frame_box(page):
    """The map's plot frame (left, top, width, height) in its canvas, from Bokeh's views."""
    return page.evaluate(
        """() => {
            let found = null;
            function walk(v) {
              const t = v.model && v.model.title && v.model.title.text;
              if (t && t.startsWith('periodic sliding') && v.frame) {
                const b = v.frame.bbox;
                found = {left: b.x0, top: b.y0, width: b.x1 - b.x0, height: b.y1 - b.y0};
              }
              for (const c of (v.child_views ?? [])) walk(c);
            }
            for (const root of Bokeh.index) walk(root);
            return found;
        }"""
    )


def _model_data(page, name, body):
    """What the JavaScript ``body`` returns, run in the browser over ``d``: the
    data of the page's Bokeh model named ``name`` (None where there is none)."""
    return page.evaluate(
        """() => {
            for (const doc of Bokeh.documents) {
              const m = doc.get_model_by_name('%s');
              if (m == null) continue;
              const d = m.data instanceof Map ? Object.fromEntries(m.data) : m.data;
              %s
            }
            return null;
        }""" % (name, body)
    )


def _window(page):
    return (page.locator(".sb-e-window input").input_value(),
            page.locator(".sb-u-window input").input_value())


def _query(page):
    return {k: v[-1] for k, v in parse_qs(urlparse(page.url).query).items()}


def test_page_loads_and_draws_the_map(server, page):
    page.goto(server.url + "?e=0:1&u=0:1.5&size=320x320&max_iter=300")
    text = _wait_rendered(page)
    assert "320 x 320 pixels" in text and "max_iter 300" in text
    assert _window(page) == ("0:1", "0:1.5")
    png = _map_canvas(page).screenshot(path=str(ARTIFACTS / "explorer-map.png"))
    img = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))
    colours = np.unique(img.reshape(-1, 3), axis=0)
    # the Figure 4 window has black tongues, white no-sliding region and many word-length colours
    assert len(colours) > 12
    assert (img.sum(axis=2) == 0).mean() > 0.05
    page.screenshot(path=str(ARTIFACTS / "explorer-page.png"))


def test_wheel_zoom_changes_window_and_url(server, page):
    page.goto(server.url + "?e=0:1&u=0:1.5&size=320x320&max_iter=200")
    _wait_rendered(page)
    before_window, before_query = _window(page), _query(page)
    box = _map_canvas(page).bounding_box()
    page.mouse.move(box["x"] + box["width"] * 0.4, box["y"] + box["height"] * 0.5)
    page.mouse.wheel(0, -400)  # zoom in
    page.wait_for_function(
        "([e]) => !document.location.search.includes('e=' + e + '&')", arg=[before_query["e"]],
        timeout=30_000)
    _wait_rendered(page)
    after_window, after_query = _window(page), _query(page)
    assert after_window != before_window
    assert after_query["e"] != before_query["e"] and after_query["u"] != before_query["u"]
    e_lo, e_hi = map(float, after_query["e"].split(":"))
    u_lo, u_hi = map(float, after_query["u"].split(":"))
    assert 0 <= e_lo < e_hi <= 1 and e_hi - e_lo < 1
    assert 0 <= u_lo < u_hi <= 1.5 and u_hi - u_lo < 1.5
    # the window in the URL is the window shown as numbers
    assert after_window == (after_query["e"], after_query["u"])
    # reloading the shared URL shows the same window
    page.goto(page.url)
    _wait_rendered(page)
    assert _window(page) == after_window
    page.screenshot(path=str(ARTIFACTS / "explorer-zoomed.png"))


def test_tap_shows_the_word_of_the_point(server, page):
    max_iter = 500
    page.goto(server.url + f"?e=0:0.4&u=0.3:1.1&size=300x300&max_iter={max_iter}&color=word_length")
    _wait_rendered(page)
    # pick a pixel whose word has more than one letter, and click its centre
    es = plane.pixel_centres(0.0, 0.4, 300)
    us = plane.pixel_centres(0.3, 1.1, 300)
    ds = plane.scan(e=(0.0, 0.4, 300), u=(0.3, 1.1, 300), max_iter=max_iter)
    candidates = np.argwhere(ds["word_length"].values >= 3)
    assert len(candidates) > 0
    i, j = candidates[len(candidates) // 2]
    box = _map_canvas(page).bounding_box()
    frame = _frame_box(page)
    x = box["x"] + frame["left"] + (j + 0.5) / 300 * frame["width"]
    y = box["y"] + frame["top"] + (1 - (i + 0.5) / 300) * frame["height"]
    page.mouse.click(x, y)
    word_el = page.locator(".sb-word")
    word_el.wait_for(timeout=60_000)
    e = float(page.locator(".sb-e").inner_text())
    u = float(page.locator(".sb-u").inner_text())
    assert (e, u) == (es[j], us[i])  # the tapped pixel's centre, where its colour was computed
    assert ds["word_length"].values[i, j] == len(sliding_word(e, u, max_iter=max_iter))
    w = sliding_word(e, u, max_iter=max_iter)
    assert w is not None
    assert word_el.inner_text() == w.format()
    assert _query(page)["point"] == f"{e!r},{u!r}"
    page.screenshot(path=str(ARTIFACTS / "explorer-tap.png"))


def test_bad_url_gives_a_message_not_a_crash(server, page):
    page.goto(server.url + "?e=1:0&size=5000x5000&max_iter=abc&color=nope")
    _wait_rendered(page)
    msg = page.locator(".sb-url-text").inner_text()
    assert "e=" in msg and "size=" in msg and "pixel budget" in msg and "max_iter=" in msg
    assert "color=" in msg
    assert _window(page) == ("0:1", "0:1.5")  # the default window is shown instead
    page.screenshot(path=str(ARTIFACTS / "explorer-bad-url.png"))


def test_widgets_rerender_and_update_the_url(server, page):
    page.goto(server.url + "?e=0:1&u=0:1.5&size=240x240&max_iter=200")
    _wait_rendered(page)
    box = page.locator(".sb-e-window input")
    box.fill("0:0.3")
    box.press("Enter")
    page.locator(".sb-status .sb-info").get_by_text("e 0 to 0.3,").wait_for(timeout=60_000)
    assert _query(page)["e"] == "0:0.3"
    frame = _frame_box(page)
    assert frame["width"] == 240 and frame["height"] == 240
    page.locator(".sb-max-iter input").fill("350")
    page.locator(".sb-max-iter input").press("Enter")
    page.locator(".sb-status .sb-info").get_by_text("max_iter 350,").wait_for(timeout=60_000)
    page.locator(".sb-color select").select_option(label="period (steps)")
    page.wait_for_function("() => document.location.search.includes('color=period')", timeout=30_000)
    page.locator(".sb-overlays input").first.uncheck()
    page.wait_for_function("() => document.location.search.includes('overlays=no_sliding')",
                           timeout=30_000)
    q = _query(page)
    assert (q["e"], q["max_iter"], q["color"], q["overlays"]) == ("0:0.3", "350", "period", "no_sliding")
    # the page refuses a view over the pixel budget with a message, and keeps the last image
    page.locator(".sb-status .sb-info").wait_for()
    for sel, value in ((".sb-width input", "1000"), (".sb-height input", "1001")):
        page.locator(sel).fill(value)
        page.locator(sel).press("Enter")
    page.locator(".sb-status .sb-error").get_by_text("pixel budget").wait_for(timeout=30_000)
    assert "size=1000x240" in page.url or "size=240x240" in page.url
    page.screenshot(path=str(ARTIFACTS / "explorer-widgets.png"))


def test_download_buttons_give_the_view(server, page, tmp_path):
    page.goto(server.url + "?e=0.1:0.3&u=0.5:0.9&size=200x150&max_iter=300")
    _wait_rendered(page)
    with page.expect_download(timeout=60_000) as info:
        page.get_by_text("Download .nc").click()
    path = tmp_path / info.value.suggested_filename
    info.value.save_as(path)
    assert path.name == "stairbounce_e0.1-0.3_u0.5-0.9.nc"
    ds = plane.load(path)
    ref = plane.scan(e=(0.1, 0.3, 200), u=(0.5, 0.9, 150), max_iter=300)
    np.testing.assert_array_equal(ds["word_length"].values, ref["word_length"].values)
    with page.expect_download(timeout=60_000) as info:
        page.get_by_text("Download PNG").click()
    png = tmp_path / info.value.suggested_filename
    info.value.save_as(png)
    img = Image.open(png)
    assert png.suffix == ".png" and img.width > 200 and img.height > 150
    shutil.copy(png, ARTIFACTS / "explorer-download.png")


# --------------------------------------------------------------------------- #
# Issue 14: many users, history, hosts, layout                                #
# --------------------------------------------------------------------------- #


def _status(page):
    # the pane's text lives in its shadow root: the spans, not the host element
    text = " | ".join(page.locator(".sb-status span").all_inner_texts())
    assert text  # never vacuous
    return text


def _type_windows(page, e, u):
    """Type both windows, Enter once (in the u box)."""
    page.locator(".sb-e-window input").fill(e)
    page.locator(".sb-u-window input").fill(u)
    page.locator(".sb-u-window input").press("Enter")


def _wait_view(page, window, shown, stale=None, timeout=60.0):
    """Wait until the window boxes read ``window`` and, at the same moment, the
    status reports a finished render whose text starts with ``shown`` (and not
    with ``stale``, the view before).

    Both at once: a render that started at once leaves the last view's
    "computed in" line on the page until it finishes, so the status alone (or
    the boxes alone, before the server has taken a Back) can read an older view.
    """
    deadline = time.monotonic() + timeout
    while True:
        info = page.locator(".sb-status .sb-info").all_inner_texts()
        now = _window(page), any(t.startswith(shown) and "computed in" in t
                                 and not (stale and t.startswith(stale)) for t in info)
        if now == (window, True):
            return
        if time.monotonic() > deadline:
            raise AssertionError(f"waited for {window} and {shown!r}; the page shows {now[0]} and {info}")
        time.sleep(0.1)


def test_back_and_forward_restore_the_view(server, page):
    """Defect 1: Back undoes a zoom (picture, window boxes, status, address bar agree)."""
    page.goto(server.url + "?e=0:1&u=0:1.5&size=200x200&max_iter=200")
    _wait_rendered(page)
    start = page.evaluate("() => history.length")
    _type_windows(page, "0:0.5", "0.5:1.5")
    _wait_view(page, ("0:0.5", "0.5:1.5"), "e 0 to 0.5, u 0.5 to 1.5:")
    box = _map_canvas(page).bounding_box()  # a wheel zoom: another entry
    page.mouse.move(box["x"] + box["width"] * 0.4, box["y"] + box["height"] * 0.5)
    page.mouse.wheel(0, -300)
    page.wait_for_function("() => !document.location.search.includes('e=0:0.5&')", timeout=30_000)
    zoomed = _window(page)  # the boxes are set with the address bar, before the render
    assert zoomed != ("0:0.5", "0.5:1.5")
    _wait_view(page, zoomed, "e ", stale="e 0 to 0.5, u 0.5 to 1.5:")
    assert page.evaluate("() => history.length") == start + 2
    page.go_back()
    _wait_view(page, ("0:0.5", "0.5:1.5"), "e 0 to 0.5, u 0.5 to 1.5:")
    assert _query(page)["e"] == "0:0.5"
    page.go_back()
    _wait_view(page, ("0:1", "0:1.5"), "e 0 to 1, u 0 to 1.5:")
    page.go_forward()
    _wait_view(page, ("0:0.5", "0.5:1.5"), "e 0 to 0.5, u 0.5 to 1.5:")
    page.go_forward()
    page.wait_for_function("([e]) => document.location.search.includes('e=' + e + '&')",
                           arg=[zoomed[0]], timeout=30_000)
    # the address bar changes at once; the boxes and the picture follow when
    # the server has taken the Forward
    _wait_view(page, zoomed, "e ", stale="e 0 to 0.5, u 0.5 to 1.5:")
    # navigating history made no new entries
    assert page.evaluate("() => history.length") == start + 2


def test_one_enter_applies_both_windows(server, page):
    """Defect 12: one Enter, one render with both windows, one history entry."""
    page.goto(server.url + "?e=0:1&u=0:1.5&size=200x200&max_iter=200")
    _wait_rendered(page)
    start = page.evaluate("() => history.length")
    page.locator(".sb-e-window input").fill("0.1:0.3")
    page.locator(".sb-u-window input").click()  # moving to the u box applies nothing yet
    page.locator(".sb-u-window input").fill("0.5:0.9")
    page.locator(".sb-u-window input").press("Enter")
    page.locator(".sb-status .sb-info").get_by_text("e 0.1 to 0.3, u 0.5 to 0.9:").wait_for(timeout=60_000)
    assert page.evaluate("() => history.length") == start + 1
    q = _query(page)
    assert (q["e"], q["u"]) == ("0.1:0.3", "0.5:0.9")


@pytest.mark.slow
def test_several_tabs_and_page_requests_each_tab_its_own_view(server, browser):
    """Many users at once: three tabs opened with different queries while
    plain page requests come in (each answered from the one kept session)
    show their own windows; two rounds of a wheel zoom in every tab, with
    more requests coming in, get every tab its own new picture each time."""
    import threading
    import urllib.request

    # pictures of 600 x 600 (1.4 MB each on the websocket), the size at which
    # Panel's own sending lost the last change while a picture was being written
    queries = ["?e=0:0.5&u=0.5:1.5&size=600x600&max_iter=200",
               "?e=0.04:0.065&u=0.92:0.945&size=600x560&max_iter=300",
               "?e=0.5:1&u=0:0.5&size=560x600&max_iter=150"]
    windows = [("0:0.5", "0.5:1.5"), ("0.04:0.065", "0.92:0.945"), ("0.5:1", "0:0.5")]
    answers = []

    def requests(n):
        for _ in range(n):
            with urllib.request.urlopen(server.url + "?e=0.1:0.2", timeout=60) as r:
                answers.append(b"<title>stairbounce explorer</title>" in r.read())

    pages = [browser.new_page(viewport={"width": 1280, "height": 900}) for _ in queries]
    try:
        t = threading.Thread(target=requests, args=(10,))
        t.start()
        for pg, q in zip(pages, queries):
            pg.goto(server.url + q)
        for pg, q, w in zip(pages, queries, windows):
            text = _wait_rendered(pg)
            assert _window(pg) == w and q.split("size=")[1].split("&")[0].replace("x", " x ") in text
        t.join()
        for _ in range(2):  # two rounds of a zoom in every tab while page requests come in
            t = threading.Thread(target=requests, args=(10,))
            t.start()
            _zoom_each(pages, [_window(pg) for pg in pages])
            t.join()
        assert answers == [True] * 30
    finally:
        for pg in pages:
            pg.close()


def _zoom_each(pages, windows):
    """A wheel zoom in every page at once; each must show its own new picture."""
    before = [_status(pg) for pg in pages]
    for pg in pages:
        box = _map_canvas(pg).bounding_box()
        pg.mouse.move(box["x"] + box["width"] * 0.5, box["y"] + box["height"] * 0.5)
        pg.mouse.wheel(0, -300)
    for pg, w, old in zip(pages, windows, before):
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            status = _status(pg)
            if "computed in" in status and status != old and _window(pg) != w:
                break
            time.sleep(0.1)
        else:
            raise AssertionError(f"no new picture after the zoom within 60 s: {_status(pg)}")
        e_lo, e_hi = map(float, _window(pg)[0].split(":"))
        lo, hi = map(float, w[0].split(":"))
        assert lo <= e_lo < e_hi <= hi and e_hi - e_lo < hi - lo  # zoomed into its own window


def test_cheap_render_does_not_wait_for_another_sessions_heavy_one(server, browser):
    """Defect 2: session B's small view and tap finish while session A's
    heavy render (1000 x 1000, max_iter 5000, two thirds of the pixels do
    not slide and lie below Cor. 2.1's bound, so the scan cannot prune
    them) is still running; closing A's page stops its render."""
    import psutil

    a = browser.new_page(viewport={"width": 1600, "height": 1000})
    b = browser.new_page(viewport={"width": 1600, "height": 1000})
    try:
        a.goto(server.url + "?e=0.3:0.4&u=0.3:0.45&size=1000x1000&max_iter=5000")
        a.locator(".sb-status .sb-busy").get_by_text("%").wait_for(timeout=60_000)  # A is computing
        b.goto(server.url + "?e=0:0.4&u=0.3:1.1&size=200x200&max_iter=300")
        _wait_rendered(b)
        assert "computed in" not in _status(a)  # A still computes
        frame, box = _frame_box(b), _map_canvas(b).bounding_box()
        b.mouse.click(box["x"] + frame["left"] + 0.1 * frame["width"],
                      box["y"] + frame["top"] + 0.5 * frame["height"])
        b.locator(".sb-point").get_by_text("period").wait_for(timeout=60_000)
        assert "computed in" not in _status(a)
        b.screenshot(path=str(ARTIFACTS / "explorer-beside-a-heavy-render.png"))
    finally:
        a.close()
    # A's page is gone: its render stops (the server goes idle within a slice)
    proc = psutil.Process(server.pid)
    time.sleep(1.5)
    before = sum(proc.cpu_times()[:2])
    time.sleep(3.0)
    used = sum(proc.cpu_times()[:2]) - before
    b.close()
    assert used < 1.0, f"the server used {used:.1f} s of CPU in 3 s after the heavy page closed"


@pytest.mark.parametrize("size", [(1280, 720), (1600, 1000)])
def test_status_and_tap_result_above_the_fold(server, browser, size):
    """Defect 11: on laptop screens the status line and the tapped point's
    word are visible without scrolling."""
    w, h = size
    page = browser.new_page(viewport={"width": w, "height": h})
    try:
        page.goto(server.url + "?e=0:1&u=0:1.5&size=600x600&max_iter=300")
        _wait_rendered(page)
        status = page.locator(".sb-status").bounding_box()
        assert status["y"] >= 0 and status["y"] + status["height"] <= h
        # tap inside the n = 3 tongue (Thm 3.1: 1 < u <= sqrt(3/2)(1-e)/(1+e)), in the visible part
        frame, box = _frame_box(page), _map_canvas(page).bounding_box()
        x = box["x"] + frame["left"] + 0.02 * frame["width"]
        y = box["y"] + frame["top"] + (1 - 1.1 / 1.5) * frame["height"]
        assert y < h
        page.mouse.click(x, y)
        word = page.locator(".sb-word")
        word.wait_for(timeout=60_000)
        assert word.inner_text() == "(3, 0^\u221e)"
        for el in (page.locator(".sb-point"), word):
            bb = el.bounding_box()
            assert bb["y"] >= 0 and bb["y"] + bb["height"] <= h
        page.screenshot(path=str(ARTIFACTS / f"explorer-{w}x{h}.png"))
    finally:
        page.close()


def test_a_very_long_url_value_gets_the_apps_message(server, page):
    """Defect 10: 20 000 digits (Panel's own parser fails above 4300)."""
    page.goto(server.url + "?e=" + "1" * 20000 + "&size=200x200&max_iter=100")
    _wait_rendered(page)
    msg = page.locator(".sb-url-text").inner_text()
    assert "ignored e=" in msg and "20000 characters" in msg
    assert _window(page)[0] == "0:1"


def _ipv6_loopback():
    try:
        with socket.socket(socket.AF_INET6) as s:
            s.bind(("::1", 0))
        return True
    except OSError:
        return False


@pytest.mark.slow
@pytest.mark.parametrize("host", ["0.0.0.0", "::1"])
def test_other_hosts_serve_a_working_page(browser, tmp_path, host):
    """Defect 4: with --host 0.0.0.0 or ::1 the page renders (the websocket is
    accepted); the URL printed opens it (IPv6 in brackets)."""
    if host == "::1" and not _ipv6_loopback():
        pytest.skip("no IPv6 loopback on this machine")
    proc, url = _start(["--host", host, "--port", "0"], tmp_path / "server.log")
    try:
        port = int(url.rsplit(":", 1)[1].strip("/"))
        urls = [url, f"http://127.0.0.1:{port}/"] if host == "0.0.0.0" else [url]
        if host == "::1":
            assert url == f"http://[::1]:{port}/"
        for u in urls:
            page = browser.new_page()
            try:
                page.goto(u + "?size=100x100&max_iter=50")
                text = _wait_rendered(page, timeout=60_000)
                assert "100 x 100 pixels" in text
            finally:
                page.close()
    finally:
        _stop(proc)


# --------------------------------------------------------------------------- #
# issue 25: offline, one history entry per wheel gesture, the page's width    #
# --------------------------------------------------------------------------- #

_LOOPBACK = re.compile(r"^(https?|wss?)://(127\.0\.0\.1|localhost|\[::1\])[:/]")


def test_the_page_loads_nothing_from_outside_the_server(server, browser):
    """With every non-loopback request cut off (an offline or firewalled
    machine), the page asks for nothing outside the server, its stylesheets
    come from the server, and it draws, taps and zooms as usual."""
    page = browser.new_page(viewport={"width": 1400, "height": 1000})
    outside, css = [], []
    page.route("**/*", lambda route: route.continue_() if _LOOPBACK.match(route.request.url)
               or route.request.url.startswith(("data:", "blob:")) else (outside.append(route.request.url),
                                                                         route.abort()))
    page.on("response", lambda r: css.append((r.url, r.status)) if ".css" in r.url else None)
    errors = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    try:
        page.goto(server.url + "?e=0:0.4&u=0.3:1.1&size=200x200&max_iter=200")
        _wait_rendered(page)
        box = _map_canvas(page).bounding_box()
        page.mouse.click(box["x"] + box["width"] * 0.3, box["y"] + box["height"] * 0.5)
        page.locator(".sb-point").get_by_text("word").first.wait_for(timeout=60_000)
        page.mouse.move(box["x"] + box["width"] * 0.4, box["y"] + box["height"] * 0.5)
        page.mouse.wheel(0, -300)
        page.wait_for_function("() => !document.location.search.includes('e=0:0.4&')", timeout=30_000)
        _wait_rendered(page)
    finally:
        page.close()
    assert outside == [] and not errors
    # Panel's stylesheets (theme, widgets, loading spinner) were served, by this server
    assert len(css) >= 5 and all(_LOOPBACK.match(u) and status == 200 for u, status in css), css
    assert any("/static/extensions/panel/" in u for u, _ in css)


def test_a_quick_notched_wheel_zoom_is_one_step_back(server, page):
    """Six wheel notches 100 ms apart are one zoom: Back returns to the view
    before it, not to a view part way through."""
    page.goto(server.url + "?e=0:1&u=0:1.5&size=200x200&max_iter=200")
    _wait_rendered(page)
    start = page.evaluate("() => history.length")
    box = _map_canvas(page).bounding_box()
    page.mouse.move(box["x"] + box["width"] * 0.4, box["y"] + box["height"] * 0.5)
    for _ in range(6):
        page.mouse.wheel(0, -100)
        page.wait_for_timeout(100)
    page.wait_for_function("() => !document.location.search.includes('e=0:1&')", timeout=30_000)
    _wait_rendered(page)
    page.wait_for_timeout(1500)  # any late RangesUpdate of the gesture has arrived
    _wait_rendered(page)
    assert page.evaluate("() => history.length") == start + 1
    page.go_back()
    page.locator(".sb-status .sb-info").get_by_text("e 0 to 1, u 0 to 1.5:").wait_for(timeout=60_000)
    assert _window(page) == ("0:1", "0:1.5")


def test_tap_panels_use_the_page_width_and_the_title_is_clean(server, page):
    page.goto(server.url + "?e=0:0.4&u=0.3:1.1&size=200x200&max_iter=200")
    _wait_rendered(page)
    box = _map_canvas(page).bounding_box()
    page.mouse.click(box["x"] + box["width"] * 0.3, box["y"] + box["height"] * 0.5)
    page.locator(".sb-point").get_by_text("word").first.wait_for(timeout=60_000)
    page.locator(".sb-tap-panels .bk-Canvas").nth(2).wait_for(timeout=60_000)  # built by the tap
    page.wait_for_timeout(500)  # laid out
    width = page.viewport_size["width"]
    panels = page.locator(".sb-tap-panels").bounding_box()
    assert panels["width"] > 0.9 * width
    canvases = [c.bounding_box() for c in page.locator(".sb-tap-panels .bk-Canvas").all()]
    # the trajectory across the page; the orbit diagram and section side by side below it
    assert len(canvases) == 3 and canvases[0]["width"] > 0.85 * width
    assert canvases[1]["width"] + canvases[2]["width"] > 0.8 * width
    assert "\u00b6" not in page.locator(".sb-title").inner_text()
    assert page.locator(".sb-title h2").inner_text() == "stairbounce explorer"


_FRAME_ON_PAGE = """() => {
    let found = null;
    function walk(v) {
      const t = v.model && v.model.title && v.model.title.text;
      if (t && t.startsWith('periodic sliding') && v.frame && v.canvas_view) {
        const r = v.canvas_view.el.getBoundingClientRect(), b = v.frame.bbox;
        found = {left: r.left + b.x0 + window.scrollX, top: r.top + b.y0 + window.scrollY};
      }
      for (const c of (v.child_views ?? [])) walk(c);
    }
    for (const root of Bokeh.index) walk(root);
    return found;
}"""


@pytest.mark.parametrize("width", [1600, 800])
def test_the_first_picture_comes_with_the_page_where_the_map_will_be(server, browser, width):
    """The page's HTML carries the view's picture (explorer/preview.py): with
    Bokeh's scripts cut off it is still on the page, with the view's own
    pixels, over the place of the map's frame (side by side with the controls
    at 1600 px, below them at 800); on a working page it is gone once the
    session's picture is drawn."""
    from stairbounce.explorer.view import compute_view, parse_query, shade

    query = "?e=0:1&u=0:1.5&size=300x300&max_iter=1000"
    live = browser.new_page(viewport={"width": width, "height": 1000})
    try:
        live.goto(server.url + query)
        _wait_rendered(live)  # also: the server's kernels are loaded, so it sends previews
        live.wait_for_function("() => !document.getElementById('sb-preview')", timeout=10_000)
        frame = live.evaluate(_FRAME_ON_PAGE)
    finally:
        live.close()
    still = browser.new_page(viewport={"width": width, "height": 1000})
    still.route("**/*.js*", lambda route: route.abort())  # no Bokeh, no Panel: the HTML alone
    try:
        img = still.locator("#sb-preview img")
        # the page comes without its picture when the preview misses its budget of 0.3 s of
        # computation (preview.PREVIEW_BUDGET_S), as it may on a machine loaded several
        # times over: up to three page loads, the picture asked of one of them
        for attempt in range(3):
            still.goto(server.url + query)
            if img.count():
                break
        img.wait_for(timeout=10_000)
        still.wait_for_function("() => document.querySelector('#sb-preview img').naturalWidth > 0")
        box = img.bounding_box()
        src = img.get_attribute("src")
        still.screenshot(path=str(ARTIFACTS / f"explorer-preview-{width}.png"))
    finally:
        still.close()
    assert box["width"] == 300 and box["height"] == 300
    assert abs(box["x"] - frame["left"]) <= 3 and abs(box["y"] - frame["top"]) <= 3, (box, frame)
    import base64

    pixels = np.asarray(Image.open(io.BytesIO(base64.b64decode(src.partition(",")[2]))).convert("RGBA"))
    view, _ = parse_query({k: v[-1] for k, v in parse_qs(query[1:]).items()})
    assert np.array_equal(pixels.view(np.uint32)[..., 0], shade(compute_view(view), view.color)[::-1])


def test_a_page_with_a_bad_value_comes_without_a_preview(server):
    import urllib.request

    with urllib.request.urlopen(server.url + "?size=300x300&max_iter=oops", timeout=30) as answer:
        page = answer.read().decode()
    assert "<body" in page and 'id="sb-preview"' not in page
    with urllib.request.urlopen(server.url + "?size=300x300&max_iter=100", timeout=30) as answer:
        page = answer.read().decode()
    assert 'id="sb-preview"' in page


def test_traced_borders_mode_draws_the_arcs(server, page):
    """Issue 22 item 4: the "traced" overlay, turned on in a view of Theorem 3.1's
    first tongue (one word, (1, 0^inf)), draws its chatter arc and the window's
    sides as traced arcs (the page's Bokeh model of the arcs, read in the
    browser), says so in the status, and puts the mode in the URL."""
    page.goto(server.url + "?e=0.6:0.8&u=0.05:0.2&size=200x150&max_iter=300&overlays=none")
    _wait_rendered(page)
    boxes = page.locator(".sb-overlays input")
    assert boxes.count() == 5
    boxes.nth(3).check()
    line = page.locator(".sb-status .sb-trace").get_by_text("traced borders: 1 word")
    line.wait_for(timeout=60_000)
    assert "chatter 1" in line.inner_text() and "replaced by arcs" in line.inner_text()
    assert _query(page)["overlays"] == "traced"
    arcs = _model_data(page, "sb-traced-arcs", """
        return {kind: Array.from(d.kind), points: Array.from(d.xs, (x) => x.length), low: Array.from(d.word_low)};""")
    assert arcs is not None and sorted(set(arcs["kind"])) == ["chatter", "window"]
    i = arcs["kind"].index("chatter")
    assert arcs["points"][i] > 5 and arcs["low"][i] == "(1, 0^inf)"
    page.screenshot(path=str(ARTIFACTS / "explorer-traced.png"))


def test_proven_overlay_draws_the_certified_atlas_and_its_key(server, page):
    """Issue 36 item 8, issue 46 item 2: the "proven" overlay, turned on in the
    Fig. 7 window, draws the certified atlas as one picture (the page's Bokeh
    model, read in the browser: an RGBA image at the view's pixels whose hover
    labels name proven words and hatched undecided reasons, and the map's
    canvas shows the hatch colours), shows its key saying that undecided areas
    are numerical, and puts the mode in the URL.  A tap on a box shows its
    certificate and changes no pixel of the overlay away from the tap's marker
    (no selection fade)."""
    page.goto(server.url + "?e=0.155:0.2138&u=0.6:0.658&size=128x128&max_iter=300&overlays=none")
    _wait_rendered(page)
    before = np.asarray(Image.open(io.BytesIO(_map_canvas(page).screenshot())).convert("RGB"))
    page.locator(".sb-overlays input").nth(4).check()
    line = page.locator(".sb-status .sb-proven").get_by_text("certified in")
    line.wait_for(timeout=60_000)
    assert re.search(r"proven overlay: (\d+) boxes to depth 6", line.inner_text())
    assert _query(page)["overlays"] == "proven"
    drawn = _model_data(page, "sb-proven-image", """
        if (!d.image.length) return {n: 0};
        const codes = new Set(d.code[0]);
        return {n: d.image[0].length, codes: codes.size, shape: d.image[0].shape ?? null};""")
    assert drawn is not None and drawn["n"] == 128 * 128 and drawn["codes"] > 3
    key = page.locator(".sb-proven-key").get_by_text("Undecided areas are numerical")
    key.wait_for(timeout=10_000)
    page.wait_for_timeout(500)
    shot = _map_canvas(page).screenshot(path=str(ARTIFACTS / "explorer-proven.png"))
    on = np.asarray(Image.open(io.BytesIO(shot)).convert("RGB"))
    # the graze hatch (violet) is on the map now and was not before
    violet = np.array([0x80, 0x00, 0xFF])
    assert (np.abs(on.astype(int) - violet).sum(axis=2) < 40).sum() > 20
    assert (np.abs(before.astype(int) - violet).sum(axis=2) < 40).sum() == 0
    # a tap: the certificate line, and the overlay's pixels unchanged away from the marker
    box, frame = _map_canvas(page).bounding_box(), _frame_box(page)
    x = box["x"] + frame["left"] + 0.43 * frame["width"]
    y = box["y"] + frame["top"] + 0.66 * frame["height"]
    page.mouse.click(x, y)
    page.locator(".sb-cert").get_by_text("certified atlas").wait_for(timeout=60_000)
    page.mouse.move(box["x"] + 2, box["y"] + 2)  # no hover tooltip over the map
    page.wait_for_timeout(500)
    after = np.asarray(Image.open(io.BytesIO(_map_canvas(page).screenshot(
        path=str(ARTIFACTS / "explorer-proven-tapped.png")))).convert("RGB"))
    assert after.shape == on.shape
    # inside the plot frame (the canvas's own border takes the keyboard focus's outline)
    f0, f1 = int(frame["top"]) + 1, int(frame["top"] + frame["height"]) - 1
    g0, g1 = int(frame["left"]) + 1, int(frame["left"] + frame["width"]) - 1
    changed = np.argwhere(np.abs(after[f0:f1, g0:g1].astype(int) - on[f0:f1, g0:g1].astype(int)).sum(axis=2) > 30)
    changed += [f0, g0]
    far = np.hypot(changed[:, 1] - (x - box["x"]), changed[:, 0] - (y - box["y"])) > 12
    assert not far.any(), (f"{far.sum()} pixels changed away from the tap's marker, rows "
                           f"{changed[far, 0].min()}-{changed[far, 0].max()}, columns {changed[far, 1].min()}-"
                           f"{changed[far, 1].max()} of {after.shape}; tap at {x - box['x']:.0f}, {y - box['y']:.0f}")
