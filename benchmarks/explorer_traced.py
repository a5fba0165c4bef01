"""The explorer's traced borders (issue 22 item 4): the time of a view's trace as
the explorer runs it (``explorer.view.trace_slices``, one word per scheduler
slice, then ``traced_overlay``: the graph, the words on both sides of each arc
and which border points the arcs replace), at 32, 48 and 64 seed pixels per
side, in three views: a Theorem 3.1 tongue (0.6:0.8 x 0.05:0.2), the Fig. 5e
window and the whole Fig. 4 window.

    python benchmarks/explorer_traced.py [--sides 32,48,64] [--views tongue1,fig5e,fig4]

Baseline in the same process: ``stairbounce.window_regions`` of the same window
and seeds in one call (the ratio shows what slicing and the overlay's data cost).
"""

from __future__ import annotations

import argparse
import os
import time

import stairbounce as sb
from stairbounce.explorer import view as V

VIEWS = {
    "tongue1": V.View(0.6, 0.8, 0.05, 0.2, 600, 600, max_iter=1000),
    "fig5e": V.View(0.04, 0.065, 0.92, 0.945, 600, 600, max_iter=1000),
    "fig4": V.View(0.0, 1.0, 0.0, 1.5, 600, 600, max_iter=1000),
}


def _sliced(view, side):
    work = V.trace_slices(view, side)
    slices, longest = 0, 0.0
    while True:
        t = time.perf_counter()
        try:
            next(work)
        except StopIteration as stop:
            return stop.value, slices, longest
        slices += 1
        longest = max(longest, time.perf_counter() - t)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sides", default="32,48,64")
    ap.add_argument("--views", default="tongue1,fig5e,fig4")
    args = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.2f}, {os.cpu_count()} cores")
    sb.window_regions((0.6, 0.8), (0.05, 0.2), resolution=8, max_iter=100)  # compile / load the kernels
    for name in args.views.split(","):
        view = VIEWS[name]
        pts = V.view_border_points(view)
        for side in (int(s) for s in args.sides.split(",")):
            t = time.perf_counter()
            base = sb.window_regions(*V.trace_window(view), resolution=side, max_iter=view.max_iter)
            t_base = time.perf_counter() - t
            t = time.perf_counter()
            regions, slices, longest = _sliced(view, side)
            t_trace = time.perf_counter() - t
            t = time.perf_counter()
            ov = V.traced_overlay(view, regions, pts)
            t_overlay = time.perf_counter() - t
            assert [r.word for r in regions] == [r.word for r in base]
            total = t_trace + t_overlay
            print(f"{name} seeds {side}x{side}: {ov['words']} words, {len(ov['incomplete'])} incomplete, "
                  f"{sum(ov['counts'].values())} arcs; trace {t_trace:.2f} s in {slices} slices "
                  f"(longest {longest:.2f} s) + overlay {t_overlay:.2f} s = {total:.2f} s, "
                  f"{ov['words'] / total:.0f} words/s; {sum(ov['covered'])} of {len(ov['covered'])} border "
                  f"points replaced; baseline window_regions {t_base:.2f} s, ratio {total / t_base:.2f}",
                  flush=True)


if __name__ == "__main__":
    main()
