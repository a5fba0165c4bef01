"""Re-render time of ``stairbounce explore`` (issue 7).

    python benchmarks/explorer.py [--repeat 5] [--browser]

Server side, JIT warm, best of ``--repeat``:

- the paper's Figure 4 window (e 0..1, u 0..1.5), 600 x 600 pixels, max_iter
  1000: ``compute_view`` (the scan in cancellable bands of rows) plus
  ``shade`` (class colours), the work behind one re-render; target < 1 s;
- windows where nothing slides (every pixel runs all max_iter steps, the
  worst case at that size): high u (flights), the middle of the plane, and e
  near 1 just above Corollary 2.1's bound (many impacts per step);
- the same views as one ``plane.scan`` call, to show what the bands cost;
- the event loop's latency while a render runs on the app's worker thread
  (the largest gap between 5 ms ticks of the main thread): the numba kernels
  release the GIL, so the page's server keeps answering.

With ``--browser`` it also times the full round trip in Chromium: type a new u
window on the page, wait for the new image's status line (includes the
websocket transfer of the 600 x 600 RGBA image and the canvas redraw).
"""

from __future__ import annotations

import argparse
import os
import socket
import subprocess
import sys
import threading
import time

import numpy as np

from stairbounce import plane
from stairbounce.explorer.view import View, compute_view, shade
from _timing import wall_times

CASES = [
    ("Fig. 4 window", View(0.0, 1.0, 0.0, 1.5, 600, 600, 1000)),
    ("nothing slides: high u (e 0.5..1, u 5..6)", View(0.5, 1.0, 5.0, 6.0, 600, 600, 1000)),
    ("nothing slides: middle (e 0.3..1, u 1..1.5)", View(0.3, 1.0, 1.0, 1.5, 600, 600, 1000)),
    ("nothing slides: e near 1 (e 0.9..0.99, u 0.1..0.2)", View(0.9, 0.99, 0.1, 0.2, 600, 600, 1000)),
]


def best(fn, repeat):
    times, out = wall_times(fn, repeat)
    return min(times), out


def render(view):
    """The server's work for one re-render: the scan, then the colours."""
    ds = compute_view(view)
    shade(ds, view.color)
    return ds


def loop_latency(view):
    """Largest gap between 5 ms sleeps of this thread while ``view`` renders on another."""
    th = threading.Thread(target=render, args=(view,))
    gaps = []
    th.start()
    last = time.perf_counter()
    while th.is_alive():
        time.sleep(0.005)
        now = time.perf_counter()
        gaps.append(now - last)
        last = now
    th.join()
    return max(gaps)


def server_side(repeat):
    compute_view(View(0.0, 1.0, 0.0, 1.5, 32, 32, 10))  # load the compiled kernels
    print(f"{'case':<52} {'render':>8} {'one scan':>9} {'slides':>7} {'M steps/s':>10} {'loop gap':>9}")
    for name, view in CASES:
        t_render, ds = best(lambda v=view: render(v), repeat)
        t_scan, _ = best(lambda v=view: plane.scan(e=(v.e_lo, v.e_hi, v.width), u=(v.u_lo, v.u_hi, v.height),
                                                  max_iter=v.max_iter), repeat)
        sliding = ds["status"].values == 0
        # steps actually taken: a period for sliding pixels, max_iter for the rest
        steps = float(ds["period"].values[sliding].sum()) + float((~sliding).sum()) * view.max_iter
        gap = loop_latency(view)
        print(f"{name:<52} {t_render:>7.3f}s {t_scan:>8.3f}s {sliding.mean():>7.1%} "
              f"{steps / t_scan / 1e6:>10.0f} {1000 * gap:>7.1f}ms")


def browser_round_trip(repeat):
    from playwright.sync_api import sync_playwright

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    srv = subprocess.Popen([sys.executable, "-c", "from stairbounce.cli import main; main()", "explore",
                            "--port", str(port), "--no-browser"],
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        for _ in range(300):
            try:
                socket.create_connection(("127.0.0.1", port), 0.2).close()
                break
            except OSError:
                time.sleep(0.2)
        args = ["--no-sandbox", "--headless", "--disable-gpu", "--disable-background-networking",
                "--disable-component-update", "--disable-sync", "--no-first-run"]
        with sync_playwright() as p:
            b = p.chromium.launch(executable_path="/usr/bin/chromium", args=args)
            page = b.new_page(viewport={"width": 1600, "height": 1000})
            page.goto(f"http://127.0.0.1:{port}/?e=0:1&u=0:1.5&size=600x600&max_iter=1000")
            page.locator(".sb-info").get_by_text("computed in").wait_for(timeout=120_000)
            times = []
            for k in range(repeat):
                hi = "1.5" if k % 2 else "1.4999"
                box = page.locator(".sb-u-window input")
                t0 = time.perf_counter()
                box.fill(f"0:{hi}")
                box.press("Enter")
                page.locator(".sb-info").get_by_text(f"u 0 to {hi}:").wait_for(timeout=120_000)
                times.append(time.perf_counter() - t0)
            b.close()
        print(f"browser round trip, Fig. 4 window 600 x 600, max_iter 1000: best {min(times):.3f} s, "
              f"median {np.median(times):.3f} s over {repeat}")
    finally:
        srv.terminate()
        srv.wait()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--browser", action="store_true", help="also time the round trip in Chromium")
    a = ap.parse_args()
    print(f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}")
    server_side(a.repeat)
    if a.browser:
        browser_round_trip(a.repeat)


if __name__ == "__main__":
    main()
