"""Borders as curves (stairbounce.structure, issue 22): time per traced point and
per arc, all regions of the Fig. 5e window, counts of regions, arcs and corners
by kind in the Fig. 5e and Fig. 7 windows, N(p) from regions, areas against
pixel counts, the bands' self-similarity, and the words found from corners
(``window_regions(from_corners=True)``) against the seeded run alone.

    python benchmarks/regions.py [--resolution 128] [--pixels 2048] [--quick]

Prints throughput and, as the baseline in the same process, the seed scan
(pixels per second) that the regions are found from.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

import stairbounce as sb
from stairbounce import structure
from stairbounce.structure import regions
from stairbounce.figures import BLOWUPS, DIMENSION_WINDOWS


def _window_report(name, e, u, res):
    t = time.perf_counter()
    regs = sb.window_regions(e, u, resolution=res)
    dt = time.perf_counter() - t
    graph = sb.border_graph(regs)
    c = graph.counts()
    points = sum(a.e.size for _, _, a in graph.edges)
    worst = max((r.area_error for r in regs), default=0.0)
    total = sum(r.area for r in regs)
    print(f"{name}: e {e} u {u}, seeds {res}x{res}: {dt:.1f} s; {c['words']} words, "
          f"{c['components']} components, {len(graph.nodes)} corners, {len(graph.edges)} arcs "
          f"({points} points, {dt / max(points, 1) * 1e6:.1f} us per point)")
    two_sided = sum(1 for _, _, a in graph.edges if a.outside)
    print(f"  arcs by kind {c['arcs']}; {two_sided} arcs with a traced word on both sides, "
          f"{getattr(graph, 'junctions', 0)} cuts at one-sided junctions")
    print(f"  corners by kinds {c['corners']}")
    print(f"  traced area {total:.9g} of the window's {(e[1] - e[0]) * (u[1] - u[0]):.6g}; "
          f"largest area error estimate {worst:.2e}; {sum(not r.complete for r in regs)} words incomplete")
    nby = graph.words_by_period()
    print("  N(p) from regions:", ", ".join(f"{p}:{n}" for p, n in list(nby.items())[:25]),
          "..." if len(nby) > 25 else "")
    return regs, dt


def _corner_report(name, e, u, res, plain, dt_plain):
    """Words found with corner seeding against the seeded run alone (``plain``)."""
    t = time.perf_counter()
    regs = sb.window_regions(e, u, resolution=res, from_corners=True)
    dt = time.perf_counter() - t
    before = {r.word.letters for r in plain}
    new = [r for r in regs if r.word.letters not in before]
    pixel = (e[1] - e[0]) * (u[1] - u[0]) / res**2
    sizes = np.array([r.area / pixel for r in new])
    print(f"  from corners: {dt:.1f} s ({dt / dt_plain:.1f} x the seeded run); {len(regs)} words "
          f"({len(new)} new: {np.sum(sizes >= 0.25)} of >= 1/4 seed pixel, {np.sum(sizes >= 1 / 16)} of "
          f">= 1/16; {sum(not r.complete for r in new)} incomplete); traced area "
          f"{sum(r.area for r in regs):.9g} (seeded alone {sum(r.area for r in plain):.9g})")


def _coverage(e, u, res=32, fine=512):
    """Seeded at ``res`` with and without corners: how many of the words a ``fine``
    scan sees (by their pixel count there) each run finds."""
    es, us = regions._grid(e, u, fine)
    h1, h2, _ = regions._label_grid(es, us, 1000, 1.0, 0.0)
    keys, counts = np.unique(np.stack([h1.ravel(), h2.ravel()], 1), axis=0, return_counts=True)
    px = {(int(a), int(b)): int(c) for (a, b), c in zip(keys, counts) if a != 0}
    per = (fine // res) ** 2  # fine pixels per seed pixel
    for fc in (False, True):
        t = time.perf_counter()
        regs = sb.window_regions(e, u, resolution=res, from_corners=fc)
        dt = time.perf_counter() - t
        found = set()
        for r in regs:
            ks = regions.itinerary_of_word(r.word)
            found.add(tuple(int(h) for h in structure.itinerary._hash_itinerary(ks, ks.size)))
        row = []
        for frac in (1.0, 0.25, 1 / 16, 1 / 64):
            big = {k for k, c in px.items() if c >= frac * per}
            row.append(f">= {frac:g} seed pixel: {len(big & found)} of {len(big)}")
        print(f"  seeds {res}x{res}{' + corners' if fc else ''}: {dt:.1f} s, {len(regs)} words; words of a "
              f"{fine}x{fine} scan found, by size: " + ", ".join(row))


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--resolution", type=int, default=128)
    ap.add_argument("--pixels", type=int, default=2048)
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args(argv)
    print("load:", os.getloadavg())
    e5, u5 = BLOWUPS["fig5e"]
    # compile everything once
    sb.word_region((2, 2), e5, u5, resolution=16)

    # baseline in the same process: the seed scan's pixels per second
    es, us = regions._grid(e5, u5, 256)
    t = time.perf_counter()
    regions._label_grid(es, us, 1000, 1.0, 0.0)
    scan_rate = 256 * 256 / (time.perf_counter() - t)
    print(f"seed scan (itinerary hashes, max_iter 1000): {scan_rate:.3g} pixels/s")

    # per point and per arc, from i21's border points
    bp = sb.border_points((*e5, 32), (*u5, 32), max_iter=1000)
    rng = np.random.default_rng(0)
    picks = rng.choice(bp.sizes["point"], 10 if a.quick else 40, replace=False)
    t = time.perf_counter()
    pts = 0
    for i in picks:
        arc = sb.trace_border(float(bp.e[i]), float(bp.u[i]), window=(e5, u5))
        pts += arc.e.size
    dt = time.perf_counter() - t
    print(f"trace_border from {len(picks)} border points of Fig. 5e: {dt / len(picks) * 1e3:.1f} ms per arc, "
          f"{dt / pts * 1e6:.1f} us per point ({pts} points; "
          f"{scan_rate * dt / pts:.0f} seed-scan pixels per traced point)")

    regs5, dt5 = _window_report("Fig. 5e", e5, u5, a.resolution)
    _corner_report("Fig. 5e", e5, u5, a.resolution, regs5, dt5)
    if not a.quick:
        _coverage(e5, u5)
    if not a.quick:
        (e7, u7), _ = DIMENSION_WINDOWS["fig7"]
        regs7, dt7 = _window_report("Fig. 7", e7, u7, a.resolution)
        _corner_report("Fig. 7", e7, u7, a.resolution, regs7, dt7)

        # areas against pixel counts
        n = a.pixels
        es, us = regions._grid(e5, u5, n)
        t = time.perf_counter()
        h1, h2, _ = regions._label_grid(es, us, 1000, 1.0, 0.0)
        print(f"pixel counts at {n}x{n}: {time.perf_counter() - t:.1f} s")
        cell = ((e5[1] - e5[0]) / n) * ((u5[1] - u5[0]) / n)
        for r in regs5[:6]:
            ks = regions.itinerary_of_word(r.word)
            h = structure.itinerary._hash_itinerary(ks, ks.size)
            mask = (h1 == h[0]) & (h2 == h[1])
            px = mask.sum() * cell
            # the pixel-boundary error: half the pixels between those surely inside
            # (all four neighbours in the region) and those touching it
            m = np.pad(mask, 1, mode="edge")
            nbs = (m[:-2, 1:-1], m[2:, 1:-1], m[1:-1, :-2], m[1:-1, 2:])
            gap = ((mask & ~np.logical_and.reduce(nbs)) | (~mask & np.logical_or.reduce(nbs))).sum() * cell
            print(f"  {r.word.format(ascii=True):>32s}: traced {r.area:.12e} (+- {r.area_error:.1e}), "
                  f"pixels {px:.12e}, relative difference {(px - r.area) / r.area:+.2e} "
                  f"(pixel-boundary error {0.5 * gap / r.area:.1e})")

        t = time.perf_counter()
        s = sb.band_similarity(resolution=a.resolution)
        print(f"band similarity ({time.perf_counter() - t:.1f} s):")
        for m in (2, 3):
            row = s[m]
            print(f"  words (n,)*{m}, n = {row['n']}: tips e = {[f'{x:.6f}' for x in row['tip_e']]}, "
                  f"areas = {[f'{x:.4e}' for x in row['area']]}")
            print(f"    tip ratios {[f'{x:.4f}' for x in row['tip_ratio']]}, "
                  f"area ratios {[f'{x:.4f}' for x in row['area_ratio']]}")
        print(f"  tongue tip ratios e_(n+1)/e_n: {[f'{x:.4f}' for x in s['tongue_tip_ratio']]}")


if __name__ == "__main__":
    main()
