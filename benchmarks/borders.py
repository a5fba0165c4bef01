"""Border points located to rounding (issue 21), against the scan in the same process.

    python benchmarks/borders.py [--repeat 3] [--big 1024] [--quick]

Cases (max_iter 1000):

1. The paper's grid (500 x 350 over e in (0, 1), u in (0, 1.5)):
   ``sb.border_points`` (its own pruned scan, the pairs, the bisections, the
   words) against an unpruned ``sb.scan`` of the same grid (every pixel
   iterated) and the pruned one; points per second; the cost of one trial
   point of the bisection and of one map step inside it against a map step of
   the unpruned scan (useful iterations: the period, or max_iter).  Also the
   kernel with plain midpoint bisection (``secant=False``) for the trial count.
2. The Fig. 5e window at big x big: ``border_points`` and ``word_table`` (given
   the points) times.
3. ``outcome="sliding"`` on the paper grid and the Fig. 6 and 7 windows
   (400 x 400): its bisection in rounds on the scan's kernel against the
   per-pair kernel (``lanes=False``), the rows checked equal.
4. The kinds' shares on the border of the sliding region in the Fig. 6 and 7
   windows (400 x 400), for the note: by crossings (``outcome="sliding"``)
   and among the word-border points that have a non-sliding side.

Every timing is the best of ``--repeat`` runs after a warm-up call.
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numba
import numpy as np

import stairbounce as sb
from stairbounce import structure
from stairbounce.structure import borders
from _timing import wall_times

FIG5E = ((0.04, 0.065), (0.92, 0.945))
WINDOWS = {"fig6": ((0.0, 0.333), (0.4, 0.733)), "fig7": ((0.155, 0.2138), (0.6, 0.658))}


def best(fn, repeat):
    times, out = wall_times(fn, repeat, warm=True)
    return min(times), out


def useful_iterations(ds):
    mi = int(ds.attrs["max_iter"])
    return int(np.where(ds.status.values == 0, ds.period.values, mi).sum())


def kernel_counts(ds, secant):
    es, us, period, max_iter = borders._grid_input(ds)
    a, b, axis = borders._pairs(period, us.size, es.size)
    t = time.perf_counter()
    found, out = borders._run_pairs(es, us, period, a, b, axis, max_iter, None, secant)
    dt = time.perf_counter() - t
    return dt, a.size, out[found]


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--big", type=int, default=1024)
    p.add_argument("--quick", action="store_true", help="smaller windows (a smoke test)")
    args = p.parse_args(argv)
    scale = 0.25 if args.quick else 1.0
    n_e, n_u = int(500 * scale), int(350 * scale)
    big = int(args.big * scale)
    print(f"load: {os.getloadavg()[0]:.2f} (1 min), {numba.get_num_threads()} numba threads, "
          f"python {sys.version.split()[0]}")

    grid = dict(e=(0.0, 1.0, n_e), u=(0.0, 1.5, n_u), max_iter=1000)
    t_plain, ds_full = best(lambda: sb.scan(**grid, prune=False), args.repeat)
    t_scan, ds = best(lambda: sb.scan(**grid), args.repeat)
    t_bp, pts = best(lambda: sb.border_points(**grid), args.repeat)
    n = pts.sizes["point"]
    steps_scan = useful_iterations(ds_full)
    print(f"\n1. paper grid {n_e} x {n_u}, max_iter 1000: {n} border points")
    print(f"   unpruned scan      {t_plain:8.3f} s   ({steps_scan / t_plain / 1e6:.1f} M map steps/s)")
    print(f"   pruned scan        {t_scan:8.3f} s")
    print(f"   border_points      {t_bp:8.3f} s   {n / t_bp:,.0f} points/s   "
          f"ratio to the unpruned scan {t_bp / t_plain:.2f}")
    for secant in (True, False):
        dt, pairs, out = kernel_counts(ds, secant)
        dt, pairs, out = kernel_counts(ds, secant)
        trials, steps = out[:, 9].sum(), out[:, 10].sum()
        per_step_scan = t_plain / steps_scan
        print(f"   kernel ({'secant' if secant else 'bisect'}): {dt:.3f} s on {pairs} pairs; "
              f"{trials / max(n, 1):.1f} trial points per border point, {steps / max(trials, 1):.1f} map "
              f"steps per trial; one trial = {dt / max(trials, 1) / per_step_scan:.1f} scan steps, "
              f"one map step in it = {dt / max(steps, 1) / per_step_scan:.2f} scan steps")

    w = dict(e=(*FIG5E[0], big), u=(*FIG5E[1], big), max_iter=1000)
    t_s, ds5 = best(lambda: sb.scan(**w), 1)
    t_b, p5 = best(lambda: sb.border_points(ds5), 1)
    t_w, tab = best(lambda: sb.word_table(ds5, points=p5), 1)
    print(f"\n2. Fig. 5e window {big} x {big}: scan {t_s:.2f} s, border_points (given the scan) "
          f"{t_b:.2f} s for {p5.sizes['point']} points ({p5.sizes['point'] / t_b:,.0f} points/s), "
          f"word_table (given both) {t_w:.2f} s: {tab.sizes['word']} words, "
          f"{tab.sizes['p']} periods")

    t_sl, q = best(lambda: sb.border_points(ds, outcome="sliding"), 1)
    print(f"\n3. border_points(outcome='sliding'), paper grid {n_e} x {n_u}: {t_sl:.3f} s for "
          f"{q.sizes['point']} crossings (given the scan); its bisection, rounds on the scan's kernel "
          f"against the per-pair kernel (model._step per trial), the same rows checked:")
    m = int(400 * scale)
    cases = {"paper grid": ds, **{name: sb.scan(e=(*e, m), u=(*u, m), max_iter=1000)
                                  for name, (e, u) in WINDOWS.items()}}
    for name, dsc in cases.items():
        es, us, period, max_iter = borders._grid_input(dsc)
        a, b, axis = borders._pairs(period, us.size, es.size, sliding=True)
        t_pair, (f1, o1) = best(lambda: borders._run_pairs(es, us, period, a, b, axis, max_iter, None,
                                                            sliding=True, lanes=False), args.repeat)
        t_round, (f2, o2) = best(lambda: borders._sliding_rounds(es, us, period, a, b, axis, max_iter,
                                                                  None), args.repeat)
        same = np.array_equal(f1, f2) and np.array_equal(o1, o2)
        steps = o2[:, 10].sum()
        print(f"   {name}: {a.size} crossings, {steps / 1e6:.1f} M trial steps: per pair {t_pair:.3f} s, "
              f"rounds {t_round:.3f} s ({steps / t_round / 1e6:.0f} M steps/s), x{t_pair / t_round:.2f}; "
              f"same rows: {same}; border_points takes "
              f"{'the rounds' if a.size >= borders._ROUND_LANES_MIN else 'the per-pair kernel'}")
        if not same:
            raise SystemExit("the rounds' rows differ from the per-pair kernel's")
    print(f"\n4. kinds on the border of the sliding region ({m} x {m}), by crossings "
          "(outcome='sliding'), and among the word-border points with a side that does not slide:")
    for name, (e, u) in WINDOWS.items():
        dsw = sb.scan(e=(*e, m), u=(*u, m), max_iter=1000)
        for outcome in ("sliding", "word"):
            q = sb.border_points(dsw, outcome=outcome)
            s = q.sliding_border.values
            kinds = q.kind.values[s]
            shares = ", ".join(f"{k} {100 * np.mean(kinds == k):.1f} %" for k in structure.itinerary.KINDS)
            print(f"   {name} {e} x {u}, outcome {outcome}: {int(s.sum())} points: {shares}")


if __name__ == "__main__":
    main()
