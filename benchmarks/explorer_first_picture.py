"""Where a new explorer page's time goes, up to its first picture (issue 25).

    python benchmarks/explorer_first_picture.py [--repeat 5] [--size 300]

Starts ``stairbounce explore`` on a free port, then opens the page
``?size=SIZExSIZE`` ``--repeat`` times in Chromium (Playwright, every
non-loopback request cut off) and reports, from the moment the page is
requested (the browser's own clocks: Navigation and Resource Timing, and the
page's WebSocket wrapped before any script runs):

- html:      the page's HTML received (responseEnd of the navigation);
- scripts:   the last script (Bokeh, Panel) received;
- ws open:   the websocket to the server opened;
- document:  the session's document received (Bokeh's PULL-DOC-REPLY);
- picture:   the picture's pixels received (the first binary websocket
             buffer over 50 kB);
- drawn:     the status line says "computed in" (the picture is on the page);

and the bytes received on the websocket up to the picture.  The server-side
computation of the same view is timed in this process for comparison
(``compute_view`` + ``shade``, best of the repeats).  The machine's load
(``os.getloadavg``) is printed before and after: these are wall times.
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
import time

from _timing import int_options  # same folder: run as a script

_WRAP_WS = """
(() => {
  const Native = window.WebSocket;
  window.__sb_ws = {open: null, doc: null, picture: null, bytes: 0, bytes_at_picture: null};
  window.WebSocket = function(url, protocols) {
    const ws = protocols === undefined ? new Native(url) : new Native(url, protocols);
    ws.addEventListener('open', () => { window.__sb_ws.open ??= performance.now(); });
    ws.addEventListener('message', (ev) => {
      const s = window.__sb_ws;
      const text = typeof ev.data === 'string' ? ev.data : '';
      const size = typeof ev.data === 'string' ? ev.data.length : (ev.data.byteLength ?? ev.data.size ?? 0);
      s.bytes += size;
      if (s.doc === null && text.includes('PULL-DOC-REPLY')) s.doc = performance.now();
      // the picture is the first large binary buffer (RGBA pixels), with the
      // document itself when it was computed before the document was sent
      if (s.picture === null && typeof ev.data !== 'string' && size > 50000) {
        s.picture = performance.now(); s.bytes_at_picture = s.bytes;
      }
    });
    return ws;
  };
  // the picture sent with the page's HTML: the first frame it is decoded and on the page
  window.__sb_preview = {shown: null, removed: null};
  const poll = () => {
    const img = document.querySelector('#sb-preview img');
    const p = window.__sb_preview;
    if (p.shown === null && img && img.complete && img.naturalWidth > 0) p.shown = performance.now();
    if (p.shown !== null && !img) { p.removed = performance.now(); return; }
    requestAnimationFrame(poll);
  };
  requestAnimationFrame(poll);
  window.WebSocket.prototype = Native.prototype;
  Object.assign(window.WebSocket, Native);
})();
"""

_LOOPBACK = re.compile(r"^(https?|wss?)://(127\.0\.0\.1|localhost|\[::1\])[:/]")


def _start_server():
    proc = subprocess.Popen([sys.executable, "-c", "from stairbounce.cli import main; main()",
                             "explore", "--no-browser", "--port", "0"],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    url = None
    for line in proc.stdout:
        m = re.search(r"stairbounce explorer at (\S+) ", line)
        url = url or (m.group(1) if m else None)
        if "kernels ready" in line:
            return proc, url
    raise RuntimeError("the explorer did not start")


def one_page(browser, url, size):
    page = browser.new_page(viewport={"width": 1400, "height": 1000})
    page.route("**/*", lambda r: r.continue_() if _LOOPBACK.match(r.request.url) else r.abort())
    page.add_init_script(_WRAP_WS)
    page.goto(f"{url}?e=0:1&u=0:1.5&size={size}x{size}&max_iter=1000", wait_until="commit")
    page.locator(".sb-status .sb-info").get_by_text("computed in").wait_for(timeout=120_000)
    t = page.evaluate("""() => {
        const nav = performance.getEntriesByType('navigation')[0];
        const js = performance.getEntriesByType('resource').filter(r => r.name.includes('.js'));
        return {start: nav.startTime, html: nav.responseEnd,
                scripts: Math.max(0, ...js.map(r => r.responseEnd)),
                ws: window.__sb_ws, preview: window.__sb_preview, drawn: performance.now()};
    }""")
    page.close()
    ws = t["ws"]
    return {"html": t["html"], "scripts": t["scripts"], "ws open": ws["open"], "document": ws["doc"],
            "picture": ws["picture"], "drawn": t["drawn"], "kB": (ws["bytes_at_picture"] or 0) / 1e3,
            "preview": t["preview"]["shown"], "preview gone": t["preview"]["removed"]}


def main():
    args = int_options(argparse.ArgumentParser(description=__doc__.split("\n")[0]), repeat=5, size=300).parse_args()
    from playwright.sync_api import sync_playwright

    from stairbounce.explorer.view import View, compute_view, shade

    print(f"load before: {os.getloadavg()[0]:.2f}")
    view = View(0.0, 1.0, 0.0, 1.5, args.size, args.size, 1000)
    compute_view(View(0.0, 1.0, 0.0, 1.5, 16, 16, 10))
    comp = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        shade(compute_view(view), view.color)
        comp.append(time.perf_counter() - t0)
    proc, url = _start_server()
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path="/usr/bin/chromium",
                                        args=["--no-sandbox", "--headless", "--disable-gpu"])
            one_page(browser, url, args.size)  # the first page after a start warms caches
            runs = [one_page(browser, url, args.size) for _ in range(args.repeat)]
            browser.close()
    finally:
        proc.terminate()
        proc.wait(timeout=20)
    print(f"{args.size} x {args.size} pixels, Fig. 4 window, max_iter 1000; median of {args.repeat} pages "
          f"(ms from the request; min..max)")
    for key in ("html", "preview", "scripts", "ws open", "document", "picture", "drawn", "preview gone"):
        vals = [r[key] for r in runs if r[key] is not None]
        if vals:
            print(f"  {key:<9} {statistics.median(vals):7.0f}   ({min(vals):.0f}..{max(vals):.0f})")
    print(f"  websocket bytes up to the picture: {statistics.median(r['kB'] for r in runs):.0f} kB")
    print(f"  the view's computation in this process (compute_view + shade): best {min(comp) * 1e3:.0f} ms")
    print(f"load after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
