"""How far to trust one box-counting number: D of the perimeter of the sliding
region against resolution, max_iter and fit range (issue 4).

For the paper's two windows (Fig. 6: [0, 0.333] x [0.4, 0.733], reported
D = 1.324; Fig. 7: [0.155, 0.2138] x [0.6, 0.658], reported D = 1.403) the
border of the status-0 region of a scan is measured with three fit ranges:

- ``auto``: the default of :func:`stairbounce.fractal.box_dimension` (largest
  linear region among sizes with >= 32 boxes, a heuristic);
- ``1-64 px``: every power of two up to 64 px, pixel scale included: the
  protocol that reproduces the paper's numbers at 500 px;
- ``4-32 px``: a fixed band of pixel sizes above the pixel scale, which probes
  finer and finer parameter scales as the resolution grows.

Sweeps: resolution at ``--max-iter-fixed`` (default 1000), max_iter at
``--resolution-fixed`` (default 1024), the paper's setting (500 px, max_iter
1000), and the word-length borders at that setting for comparison.  Prints a
table (D, 95% CI, r, fit range, seconds) and draws D against resolution and
max_iter and the local slopes ``d log N / d log(1/s)`` against the box side in
units of the window, to the PNG given on the command line.

Run: ``python benchmarks/dimension_convergence.py out.png`` (resolutions
256..4096, max_iter 500..4000: 66 s to 139 s on the shared 2-core machine,
depending on its load, half of it in the two 4096 px scans;
``--resolutions 256,512,1024,2048`` for a run of well under a minute).
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from stairbounce._io import atomic_path
from stairbounce.dimension import box_dimension, perimeter_dimension

WINDOWS = {
    "Fig6": dict(e=(0.0, 0.333), u=(0.4, 0.733), paper=1.324),
    "Fig7": dict(e=(0.155, 0.2138), u=(0.6, 0.658), paper=1.403),
}
FITS = {"auto": None, "1-64 px": (1, 64), "4-32 px": (4, 32)}


def measure(name, resolution, max_iter, which="sliding"):
    w = WINDOWS[name]
    t = time.perf_counter()
    base = perimeter_dimension(e=w["e"], u=w["u"], method="boxes", resolution=resolution, max_iter=max_iter,
                               which=which, fit_range=(1, 64) if resolution >= 128 else None)
    seconds = time.perf_counter() - t
    rows = {}
    for label, fr in FITS.items():
        try:
            rows[label] = base if fr == (1, 64) else box_dimension(base.border, fit_range=fr)
        except ValueError:
            rows[label] = None
    return rows, base, seconds


def fmt(est):
    if est is None:
        return f"{'-':>31s}"
    lo, hi = est.ci
    return f"{est.dimension:6.3f} [{lo:5.3f},{hi:5.3f}] r={est.r:6.4f}"


def local_slopes(est, resolution):
    s = est.sizes[est.usable].astype(float)
    c = np.asarray(est.counts, dtype=float)[est.usable]
    slope = np.diff(np.log(c)) / np.diff(np.log(1.0 / s))
    mid = np.sqrt(s[1:] * s[:-1]) / resolution  # box side in units of the window
    return mid, slope


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("plot", help="PNG (or .pdf/.svg) file for the figure")
    p.add_argument("--resolutions", default="256,512,1024,2048,4096")
    p.add_argument("--max-iters", default="500,1000,2000,4000")
    p.add_argument("--max-iter-fixed", type=int, default=1000)
    p.add_argument("--resolution-fixed", type=int, default=1024)
    args = p.parse_args()
    resolutions = [int(x) for x in args.resolutions.split(",")]
    max_iters = [int(x) for x in args.max_iters.split(",")]
    if not args.plot.lower().endswith((".png", ".pdf", ".svg")):
        sys.exit("plot must end in .png, .pdf or .svg")

    head = f"{'window':6s} {'px':>5s} {'max_iter':>8s} " + " ".join(f"{k:>31s}" for k in FITS)
    head += f" {'auto range':>10s} {'scan s':>7s}"
    print(head)
    print("-" * len(head))
    results = {}
    t0 = time.perf_counter()

    def row(name, res, mi, which="sliding"):
        key = (name, res, mi, which)
        if key not in results:
            results[key] = measure(name, res, mi, which)
        rows, base, sec = results[key]
        auto = rows["auto"]
        rng = f"{auto.fit_range[0]}-{auto.fit_range[1]}" if auto is not None else "-"
        tag = "" if which == "sliding" else "  (word-length borders)"
        print(f"{name:6s} {res:5d} {mi:8d} " + " ".join(fmt(rows[k]) for k in FITS)
              + f" {rng:>10s} {sec:7.1f}{tag}", flush=True)
        return rows, base

    for name in WINDOWS:
        print(f"# {name}: paper D = {WINDOWS[name]['paper']}; paper setting (500 px, max_iter 1000)")
        row(name, 500, 1000)
        row(name, 500, 1000, "words")
        print(f"# {name}: resolution sweep, max_iter {args.max_iter_fixed}")
        for r in resolutions:
            row(name, r, args.max_iter_fixed)
        print(f"# {name}: max_iter sweep, {args.resolution_fixed} px")
        for mi in max_iters:
            row(name, args.resolution_fixed, mi)
    print(f"total {time.perf_counter() - t0:.0f} s")

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(16, 5))
    colours = {"Fig6": "C0", "Fig7": "C3"}
    markers = {"auto": "o", "1-64 px": "s", "4-32 px": "^"}
    for name, w in WINDOWS.items():
        for ax, xs, keyf in (
            (axes[0], resolutions, lambda x: (name, x, args.max_iter_fixed, "sliding")),
            (axes[1], max_iters, lambda x: (name, args.resolution_fixed, x, "sliding")),
        ):
            for k, (label, mk) in enumerate(markers.items()):
                d, lo, hi, xx = [], [], [], []
                for x in xs:
                    est = results[keyf(x)][0][label]
                    if est is not None:
                        xx.append(x * (1 + 0.04 * (k - 1)))
                        d.append(est.dimension)
                        lo.append(est.dimension - est.ci[0])
                        hi.append(est.ci[1] - est.dimension)
                ax.errorbar(xx, d, yerr=[lo, hi], marker=mk, color=colours[name], capsize=3,
                            ls="-" if label == "auto" else ":", label=f"{name}, fit {label}")
            ax.axhline(w["paper"], color=colours[name], lw=0.8, ls="--")
        for r in resolutions:
            est = results[(name, r, args.max_iter_fixed, "sliding")][1]
            mid, slope = local_slopes(est, r)
            axes[2].plot(mid, slope, marker=".", color=colours[name],
                         alpha=0.35 + 0.65 * resolutions.index(r) / max(1, len(resolutions) - 1),
                         label=f"{name}, {r} px")
        axes[2].axhline(w["paper"], color=colours[name], lw=0.8, ls="--")
    axes[0].set_xscale("log", base=2)
    axes[0].set_xlabel(f"resolution (px per axis), max_iter = {args.max_iter_fixed}")
    axes[1].set_xscale("log", base=2)
    axes[1].set_xlabel(f"max_iter, {args.resolution_fixed} px")
    for ax in axes[:2]:
        ax.set_ylabel("D (95% CI)")
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize="x-small", ncol=2)
    axes[0].set_title("D against resolution (dashed: the paper's values)", fontsize="medium")
    axes[1].set_title("D against max_iter", fontsize="medium")
    axes[2].set_xscale("log")
    axes[2].set_xlabel("box side / window side")
    axes[2].set_ylabel("local slope d log N / d log(1/s)")
    axes[2].set_ylim(0.5, 2.0)
    axes[2].grid(True, alpha=0.3)
    axes[2].legend(fontsize="x-small", ncol=2)
    axes[2].set_title(f"local slopes, max_iter = {args.max_iter_fixed}", fontsize="medium")
    fig.suptitle("Box-counting dimension of the perimeter of the periodic sliding region")
    fig.tight_layout()
    with atomic_path(args.plot) as tmp:
        fig.savefig(tmp, dpi=110)
    print(f"wrote {args.plot}")


if __name__ == "__main__":
    main()
