"""The three estimators of the border's dimension side by side (issue 24).

For the paper's Fig. 6 and Fig. 7 windows and the Fig. 5d window
(``[0, 0.1] x [0.9, 1]``), over the same scales (fractions of the window):

- **common scales** 1e-3..3.2e-2 at ``max_iter`` 1000: box counting of a
  ``--resolution``^2 scan (default 4096 px: boxes of 4..128 px), the
  uncertainty exponent (``--points`` random points, 7 eps from 1e-3 to
  3.2e-2) and slicing (``--lines`` random lines, levels 3.2e-2 down to 5e-4);
- **fine scales** 1e-8..1e-4, where no picture reaches: the uncertainty
  exponent (``--fine-points``, 9 eps) and slicing, at ``max_iter`` 1000 and
  4000 (and ``--max-iter-top``, default 16000, for slicing): the local
  dimension scale by scale shows where a finite ``max_iter`` truncates the
  border.

Every D is printed with its interval covering the drift of the local slope
(statistical and systematic terms apart) and its scales.  Writes a Markdown
table to stdout and every number to ``--json``.

Run: ``python benchmarks/dimension_table.py --json table.json`` (about 15
minutes on a busy 2-core machine with the defaults).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np

from stairbounce.dimension import (
    perimeter_dimension,
    sliding_classifier,
    slicing_dimension,
    uncertainty_dimension,
)
from _timing import int_options

WINDOWS = {
    "fig6": ((0.0, 0.333), (0.4, 0.733)),
    "fig7": ((0.155, 0.2138), (0.6, 0.658)),
    "fig5d": ((0.0, 0.1), (0.9, 1.0)),
}
COMMON = (1e-3, 3.2e-2)
FINE = (1e-8, 1e-4)


def record(name, res, seconds, pixels=None):
    """One estimate as JSON; box sides in pixels become fractions of the window."""
    lo, hi = res.interval
    per = 1.0 if pixels is None else 1.0 / pixels
    mid, dl, half = res.local_band()
    return {"estimator": name, "D": res.dimension, "interval": [lo, hi], "ci95": list(res.ci),
            "statistical": res.statistical, "systematic": res.systematic, "halves": list(res.halves),
            "scales": [s * per for s in res.scales], "max_iter": res.max_iter,
            "local": [list(map(float, mid * per)), list(map(float, dl)), list(map(float, half))],
            "seconds": seconds, "warning": res.warning()}


def timed(call):
    t = time.perf_counter()
    res = call()
    return res, time.perf_counter() - t


def common(window, args):
    (e, u) = window
    out = []
    res, dt = timed(lambda: perimeter_dimension(e=e, u=u, method="boxes", resolution=args.resolution, max_iter=1000,
                                                fit_range=(4, args.resolution // 32)))
    out.append(record(f"boxes {args.resolution} px, 4..{args.resolution // 32} px", res, dt,
                      pixels=args.resolution))
    res, dt = timed(lambda: uncertainty_dimension(sliding_classifier(1000), window,
                                                  eps=np.logspace(-3, np.log10(COMMON[1]), 7),
                                                  n_points=args.points, seed=0))
    out.append(record(f"uncertainty, {args.points} points", res, dt))
    res, dt = timed(lambda: slicing_dimension(sliding_classifier(1000), window, n_lines=args.lines,
                                              scale_min=COMMON[0], scale_max=COMMON[1], seed=0))
    out.append(record(f"slicing, {args.lines} lines", res, dt))
    return out


def fine(window, args):
    out = []
    for mi in (1000, 4000):
        res, dt = timed(lambda: uncertainty_dimension(sliding_classifier(mi), window,
                                                      eps=np.logspace(-8, -4, 9),
                                                      n_points=args.fine_points, seed=0))
        out.append(record(f"uncertainty, {args.fine_points} points", res, dt))
    for mi in (1000, 4000, args.max_iter_top):
        res, dt = timed(lambda: slicing_dimension(sliding_classifier(mi), window, n_lines=args.lines,
                                                  scale_min=FINE[0] / 2, scale_max=1e-2,
                                                  fit_range=FINE, seed=0))
        out.append(record(f"slicing, {args.lines} lines", res, dt))
    return out


def cell(r):
    lo, hi = r["interval"]
    return (f"{r['D']:.3f} [{lo:.3f}, {hi:.3f}] (+-{r['statistical']:.3f} stat, "
            f"+-{r['systematic']:.3f} drift)")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    int_options(p, resolution=4096, points=200_000, fine_points=400_000, lines=128, max_iter_top=16000)
    p.add_argument("--windows", default="fig6,fig7,fig5d")
    p.add_argument("--skip-fine", action="store_true")
    p.add_argument("--json", default=None)
    args = p.parse_args(argv)
    results = {}
    if args.json and os.path.exists(args.json):
        results = json.load(open(args.json))
    for name in args.windows.split(","):
        window = WINDOWS[name]
        entry = results.setdefault(name, {})
        if "common" not in entry:
            entry["common"] = common(window, args)
            print(name, "common", [cell(r) for r in entry["common"]], file=sys.stderr, flush=True)
        if not args.skip_fine and "fine" not in entry:
            entry["fine"] = fine(window, args)
            print(name, "fine", [cell(r) for r in entry["fine"]], file=sys.stderr, flush=True)
        if args.json:
            tmp = args.json + ".tmp"
            with open(tmp, "w") as f:
                json.dump(results, f, indent=1)
            os.replace(tmp, args.json)
    print("| window | scales (of the window) | max_iter | estimator | D [interval] (stat, drift) | time |")
    print("|---|---|---|---|---|---|")
    for name, entry in results.items():
        for part in ("common", "fine"):
            for r in entry.get(part, []):
                lo, hi = r["scales"]
                print(f"| {name} | {lo:.2g}..{hi:.2g} | {r['max_iter']} | {r['estimator']} | {cell(r)} | "
                      f"{r['seconds']:.0f} s |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
