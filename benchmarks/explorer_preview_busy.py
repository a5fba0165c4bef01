"""A second page's first picture beside a heavy render (issue 37).

    python benchmarks/explorer_preview_busy.py [--repeat 4] [--size 300]

Starts ``stairbounce explore`` on a free port and opens, in Chromium
(Playwright, every non-loopback request cut off), pages of a SIZE x SIZE view
(Fig. 4 window, max_iter 1000) in two conditions, alternately:

- idle:  nothing else runs on the server (the same-process baseline);
- busy:  another page has just asked for a heavy render (1000 x 1000,
         max_iter 5000, the Fig. 4 window) and is computing it.

For each page it reports, from the request (the browser's own clocks), when
the preview sent with the HTML is on the page (``preview``; none when the
server sent the page without it), when the interactive picture is drawn (the
status line says "computed in") and the first picture of either kind
(``first picture``), with the ratio busy / idle.  The machine's load is
printed before and after: these are wall times on a shared machine.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

from _timing import int_options
from explorer_first_picture import _LOOPBACK, _start_server  # same folder: run as a script

_POLL_PREVIEW = """
(() => {
  window.__sb_preview = {shown: null};
  const poll = () => {
    const img = document.querySelector('#sb-preview img');
    if (img && img.complete && img.naturalWidth > 0) { window.__sb_preview.shown = performance.now(); return; }
    requestAnimationFrame(poll);
  };
  requestAnimationFrame(poll);
})();
"""

HEAVY = "?e=0:1&u=0:1.5&size=1000x1000&max_iter=5000"


def _new_page(browser):
    page = browser.new_page(viewport={"width": 1400, "height": 1000})
    page.route("**/*", lambda r: r.continue_() if _LOOPBACK.match(r.request.url) else r.abort())
    return page


def one_page(browser, url, size):
    page = _new_page(browser)
    page.add_init_script(_POLL_PREVIEW)
    page.goto(f"{url}?e=0:1&u=0:1.5&size={size}x{size}&max_iter=1000", wait_until="commit")
    page.locator(".sb-status .sb-info").get_by_text("computed in").wait_for(timeout=120_000)
    t = page.evaluate("() => ({start: performance.getEntriesByType('navigation')[0].startTime, "
                      "preview: window.__sb_preview.shown, drawn: performance.now()})")
    page.close()
    first = t["drawn"] if t["preview"] is None else min(t["preview"], t["drawn"])
    return {"preview": t["preview"], "drawn": t["drawn"], "first picture": first}


def busy_page(browser, url, size):
    """One page beside a heavy render that another page started."""
    heavy = _new_page(browser)
    heavy.goto(url + HEAVY, wait_until="commit")
    # computing: its first slices are under way (the status says "computing ... %")
    heavy.locator(".sb-status .sb-busy").get_by_text("%").wait_for(timeout=120_000)
    try:
        out = one_page(browser, url, size)
        out["heavy still busy"] = heavy.locator(".sb-status .sb-info").get_by_text("computed in").count() == 0
        return out
    finally:
        heavy.close()


def main():
    args = int_options(argparse.ArgumentParser(description=__doc__.split("\n")[0]), repeat=4, size=300).parse_args()
    from playwright.sync_api import sync_playwright

    print(f"load before: {os.getloadavg()[0]:.2f}")
    proc, url = _start_server()
    runs = {"idle": [], "busy": []}
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path="/usr/bin/chromium",
                                        args=["--no-sandbox", "--headless", "--disable-gpu"])
            one_page(browser, url, args.size)  # the first page after a start warms caches
            for _ in range(args.repeat):
                runs["idle"].append(one_page(browser, url, args.size))
                runs["busy"].append(busy_page(browser, url, args.size))
                time.sleep(0.5)
            browser.close()
    finally:
        proc.terminate()
        proc.wait(timeout=20)
    print(f"{args.size} x {args.size} pixels, Fig. 4 window, max_iter 1000; busy: beside a render of "
          f"{HEAVY}; medians of {args.repeat} pages, ms from the request (min..max)")
    med = {}
    for cond, rs in runs.items():
        previews = sum(r["preview"] is not None for r in rs)
        print(f"  {cond}: previews sent {previews} of {len(rs)}"
              + (f", heavy render still running at the end {sum(r['heavy still busy'] for r in rs)} of {len(rs)}"
                 if cond == "busy" else ""))
        for key in ("preview", "first picture", "drawn"):
            vals = [r[key] for r in rs if r[key] is not None]
            if vals:
                med[cond, key] = statistics.median(vals)
                print(f"    {key:<14} {med[cond, key]:7.0f}   ({min(vals):.0f}..{max(vals):.0f})")
    for key in ("first picture", "drawn"):
        if ("idle", key) in med and ("busy", key) in med:
            print(f"  {key}: busy / idle = {med['busy', key] / med['idle', key]:.2f}")
    print(f"load after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
