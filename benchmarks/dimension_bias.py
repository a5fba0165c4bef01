"""The bias of the three dimension estimators on sets of known dimension that
resemble the border of the sliding region (issue 37).

The border of the model is a rough curve (D about 1.55) crossed by families of
thin tongues.  Two kinds of test set, each a two-class picture of the unit
square given by a classifier, as the model's ``sliding_classifier``:

- **Weierstrass graphs**: the region ``y > W(x)`` below the graph of
  ``W(x) = sum_n a^n cos(2 pi b^n x)`` (``0 < a < 1 < b``, ``a b > 1``), whose
  graph has box dimension ``2 + ln a / ln b`` (Kaplan, Mallet-Paret and Yorke,
  Ergodic Theory Dyn. Syst. 4 (1984) 261; Falconer, Fractal Geometry,
  Example 11.3).  The sum is cut at ``b^-n < 1e-12``, below every scale any
  estimator measures here, so the finite sum is the fractal at those scales.
- **a sliver family**: a disk and ``K`` thin tilted strips of length 0.5 and
  widths ``r^k`` (``r = 1/2``, widths 2^-6 .. 2^-33, so one sliver per octave
  of scale from 1.6e-2 down to 1.2e-10).  Its border is a finite union of
  smooth curves: box dimension exactly 1.  But at a scale ``s`` every strip
  wider than ``s`` has two sides and every thinner one counts once, so the
  number of curves an estimator sees grows by one per octave: what the model's
  tongues do to an estimate over a finite range of scales.

Each estimator runs with the settings the package uses for the windows of
Figs. 5d, 6 and 7 (``stairbounce dimension --method M``):

- ``before 0.4`` (the command's defaults before issue 37): uncertainty 10^5
  points, eps 1e-6..0.1 (11 values), automatic fit range; slicing 64 lines,
  1e-10..1e-2, every level fitted; boxes 512^2 px, automatic fit range;
- ``default`` (``stairbounce.dimension.perimeter.MODEL_DEFAULTS``, the
  defaults since issue 37): uncertainty 3 x 10^5 points at 9 eps 1e-8..1e-4;
  slicing 128 lines refined to 1e-8, fitted 1e-8..1e-4; boxes 2048^2 px, boxes
  of 4..64 px (2e-3..3e-2 of the window: a picture reaches no finer in the time);

over ``--seeds`` seeds (the random points or lines; the picture has no seed
but its window is shifted by a random fraction of a pixel), and prints, per
set, estimator and setting, the mean bias (estimate minus the exact dimension),
its spread (standard deviation over seeds), the mean interval half-width, and
how often the interval covers the exact answer; ``--json`` writes every
estimate.  The numbers are recorded in docs/guide/dimension.md ("Bias on sets of
known dimension") and used as the estimators' bias term
(``stairbounce.dimension.result.KNOWN_BIAS``).

Run: ``nice python benchmarks/dimension_bias.py --json bias.json`` (about
20 minutes on a 2-core machine at load 10-15 with 3 seeds).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time

import numpy as np
from numba import njit, prange

from stairbounce.dimension import DEFAULT_EPS, boundary, box_dimension, slicing_dimension, uncertainty_dimension
from stairbounce.dimension.perimeter import MODEL_DEFAULTS

UNIT = ((0.0, 1.0), (0.0, 1.0))


@njit(parallel=True, cache=True)
def _weierstrass(x, a, b, terms):
    out = np.empty(x.size)
    for i in prange(x.size):
        w, ak, bk = 0.0, 1.0, 1.0
        for _ in range(terms):
            w += ak * math.cos(2.0 * math.pi * bk * x[i])
            ak *= a
            bk *= b
        out[i] = w
    return out


class Weierstrass:
    """``classify(x, y) = y > W(x)`` on ``[0, 1] x [-A, A]`` scaled to the unit
    square, ``W`` the Weierstrass sum with ``a = b^(D - 2)`` cut at
    ``b^-n < cut``; ``exact`` its graph's box dimension ``D``."""

    def __init__(self, dimension, b=3.0, cut=1e-12):
        self.exact = float(dimension)
        self.a, self.b = b ** (dimension - 2.0), float(b)
        self.n = np.arange(int(math.log(1.0 / cut) / math.log(b)) + 1)
        self.amp = 1.0 / (1.0 - self.a) + 0.1
        self.name = f"Weierstrass D={dimension:g} (b={b:g})"

    def graph(self, x):
        """``W(x)`` in the unit square's units."""
        x = np.ascontiguousarray(x, dtype=float).ravel()
        return 0.5 + _weierstrass(x, self.a, self.b, self.n.size) / (2.0 * self.amp)

    def __call__(self, x, y):
        x = np.asarray(x, dtype=float)
        w = _weierstrass(np.ascontiguousarray(x).ravel(), self.a, self.b, self.n.size).reshape(x.shape)
        return (2.0 * np.asarray(y, dtype=float) - 1.0) * self.amp > w


class Slivers:
    """A disk and thin tilted strips of widths ``r^k``, ``k = k0 .. k0 + K - 1``
    (box dimension 1: a finite union of smooth curves)."""

    exact = 1.0

    def __init__(self, r=0.5, k0=6, count=28, tilt=0.05):
        self.widths = r ** np.arange(k0, k0 + count, dtype=float)
        self.centres = np.linspace(0.03, 0.97, count)
        self.tilt = tilt
        self.name = f"slivers r={r:g}, widths {self.widths[-1]:.1e}..{self.widths[0]:.1e}"

    def __call__(self, x, y):
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        inside = (x - 0.2) ** 2 + (y - 0.5) ** 2 < 0.15 ** 2
        along = (x > 0.45) & (x < 0.95)
        dy = y - self.tilt * (x - 0.45)
        for c, w in zip(self.centres, self.widths):
            inside |= along & (np.abs(dy - c) < 0.5 * w)
        return inside


def sets():
    return [Weierstrass(1.3), Weierstrass(1.5), Weierstrass(1.6), Slivers()]


SETTINGS = {
    "before 0.4": {
        "uncertainty": dict(n_points=100_000, eps=DEFAULT_EPS),
        "slicing": dict(n_lines=64, scale_min=1e-10, scale_max=1e-2),
        "boxes": dict(resolution=512, fit_range=None),
    },
    "default": {  # MODEL_DEFAULTS, the defaults for a window of the model
        "uncertainty": dict(n_points=MODEL_DEFAULTS["uncertainty"]["n_points"],
                            eps=np.asarray(MODEL_DEFAULTS["uncertainty"]["eps"])),
        "slicing": dict(n_lines=MODEL_DEFAULTS["slicing"]["n_lines"], scale_min=MODEL_DEFAULTS["slicing"]["scales"][0],
                        scale_max=MODEL_DEFAULTS["slicing"]["scales"][1],
                        fit_range=MODEL_DEFAULTS["slicing"]["fit_range"]),
        "boxes": dict(resolution=MODEL_DEFAULTS["boxes"]["resolution"], fit_range=MODEL_DEFAULTS["boxes"]["fit_range"]),
    },
}


def picture(classify, n, shift):
    """The classes at the centres of an ``n x n`` grid of the unit square
    shifted by ``shift`` pixels (rows along y)."""
    c = (np.arange(n) + 0.5) / n
    if hasattr(classify, "graph"):  # y > W(x): W once per column
        return (c[:, None] + shift[1] / n) > classify.graph(c + shift[0] / n)[None, :]
    out = np.empty((n, n), dtype=bool)
    for i in range(n):
        out[i] = classify(c + shift[0] / n, np.full(n, c[i] + shift[1] / n))
    return out


def estimate(classify, method, kw, seed):
    """One estimate of ``method`` with settings ``kw``; ``(result, pixels)``."""
    if method == "uncertainty":
        return uncertainty_dimension(classify, UNIT, seed=seed, **kw), None
    if method == "slicing":
        return slicing_dimension(classify, UNIT, seed=seed, **kw), None
    n = kw["resolution"]
    shift = np.random.default_rng(seed).uniform(0.0, 1.0, 2) * (seed > 0)
    region = picture(classify, n, shift)
    return box_dimension(boundary(region), fit_range=kw["fit_range"]), n


def run(seeds=4, only=None, out=sys.stderr):
    rows = []
    for s in sets():
        if only and only not in s.name:
            continue
        for setting, methods in SETTINGS.items():
            for method, kw in methods.items():
                for seed in range(seeds):
                    t0 = time.perf_counter()
                    try:
                        res, px = estimate(s, method, kw, seed)
                    except ValueError as exc:  # too few uncertain points or levels to fit
                        print(f"{s.name:40s} {setting:8s} {method:12s} seed {seed}: no fit ({exc})",
                              file=out, flush=True)
                        continue
                    per = 1.0 if px is None else 1.0 / px
                    rows.append(dict(set=s.name, exact=s.exact, setting=setting, method=method, seed=seed,
                                     D=res.dimension, interval=list(res.interval), ci95=list(res.ci),
                                     systematic=res.systematic, scales=[v * per for v in res.scales],
                                     seconds=time.perf_counter() - t0))
                    print(f"{s.name:40s} {setting:8s} {method:12s} seed {seed}: D = {res.dimension:.4f} "
                          f"[{res.interval[0]:.4f}, {res.interval[1]:.4f}] ({rows[-1]['seconds']:.1f} s)",
                          file=out, flush=True)
    return rows


def summarise(rows):
    """Per (set, setting, method): mean bias, its spread over seeds, the mean
    interval half-width, and how many intervals cover the exact answer."""
    keys = []
    for r in rows:
        k = (r["set"], r["setting"], r["method"])
        if k not in keys:
            keys.append(k)
    out = []
    for k in keys:
        g = [r for r in rows if (r["set"], r["setting"], r["method"]) == k]
        bias = np.array([r["D"] - r["exact"] for r in g])
        half = np.mean([0.5 * (r["interval"][1] - r["interval"][0]) for r in g])
        cover = sum(r["interval"][0] <= r["exact"] <= r["interval"][1] for r in g)
        out.append(dict(set=k[0], setting=k[1], method=k[2], exact=g[0]["exact"], bias=float(bias.mean()),
                        spread=float(bias.std(ddof=1)) if bias.size > 1 else float("nan"),
                        half_width=float(half), covered=f"{cover}/{len(g)}", scales=g[0]["scales"]))
    return out


def table(summary):
    lines = ["| set | setting | estimator | scales (of the window) | bias (mean) | spread (sd) | "
             "interval half-width | covers |", "|---|---|---|---|---|---|---|---|"]
    for s in summary:
        lo, hi = s["scales"]
        lines.append(f"| {s['set']} | {s['setting']} | {s['method']} | {lo:.2g}..{hi:.2g} | {s['bias']:+.3f} | "
                     f"{s['spread']:.3f} | {s['half_width']:.3f} | {s['covered']} |")
    return "\n".join(lines)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seeds", type=int, default=3)
    p.add_argument("--only", default=None, help="only the sets whose name contains this")
    p.add_argument("--json", default=None)
    a = p.parse_args(argv)
    t0 = time.perf_counter()
    load0 = os.getloadavg()[0]
    rows = run(a.seeds, a.only)
    summary = summarise(rows)
    print(table(summary))
    print(f"\n{time.perf_counter() - t0:.0f} s, load {load0:.2f} -> {os.getloadavg()[0]:.2f}, {os.cpu_count()} cpus")
    if a.json:
        from pathlib import Path

        Path(a.json).write_text(json.dumps(dict(rows=rows, summary=summary), indent=1))


if __name__ == "__main__":
    main()
