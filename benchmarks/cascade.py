"""A cascade located exactly (issue 39), against sampling the line on a grid.

    python benchmarks/cascade.py [--repeat 3] [--grid 1000000]

Case: the family (1^k, 0^inf) on the line e = 0.01, u in [0.6, 0.75]
(50 members, k = 1..50; member 51 has no float on the line).

- ``sb.cascade``: every member's interval with both edges to adjacent floats,
  labelled, the neighbours' words, the law and the accumulation enclosure;
  members per second.
- Baseline: the same line sampled on a grid of ``--grid`` points with
  ``sb.scan_points`` (the scan's fast kernel, max_iter 1000), its throughput,
  the members such a grid sees (a member is seen when a grid point has its
  word), and the time a grid fine enough to put one point in the narrowest
  member would take at that throughput (its edges then known only to the
  grid spacing).

Second case (``--window``, the issue's target "the families of the Fig. 5e
window in under 30 s"): ``sb.cascades`` on the Fig. 5e window e in [0.04, 0.065],
u in [0.92, 0.945] (words of a 128 x 128 scan, each family located exactly on
3 lines, k_max 60, families of families), against the same process's
``sb.scan`` of that window at the same 128 x 128 pixels (the bare cost of
seeing its words).

Every timing is the best of ``--repeat`` runs after a warm-up call.
"""

from __future__ import annotations

import argparse
import os

import numpy as np

import stairbounce as sb
from _timing import wall_times

E, U = 0.01, (0.6, 0.75)
PATTERN = "(1^k, 0^inf)"


def best(f, repeat):
    times, out = wall_times(f, repeat, warm=True)
    return min(times), out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--grid", type=int, default=1_000_000)
    ap.add_argument("--window", action="store_true", help="only the Fig. 5e window's families")
    args = ap.parse_args()
    print(f"load: {os.getloadavg()}")
    if args.window:
        window(args.repeat)
        return

    t_c, c = best(lambda: sb.cascade(PATTERN, e=E, u=U, k_max=60), args.repeat)
    m = c.members
    print(f"cascade {PATTERN} at e = {E}: {len(m)} members in {t_c:.3f} s "
          f"({len(m) / t_c:.0f} members/s); stop: {c.stop[:60]}...")
    narrow = float(m.width.min())
    print(f"  narrowest member: {narrow:.3g} wide (k = {int(m.k[m.width.idxmin()])})")

    us = np.linspace(U[0], U[1], args.grid)
    es = np.full_like(us, E)
    t_g, ds = best(lambda: sb.scan_points(es, us, max_iter=1000), args.repeat)
    rate = args.grid / t_g
    # a grid point shows member k when it slides with word length k and period k
    # (the only word of length k and period k is 1^k)
    seen = np.unique(ds.period.values[(ds.status.values == 0) & (ds.word_length.values == ds.period.values)])
    print(f"grid of {args.grid} points: {t_g:.3f} s ({rate / 1e6:.2f} M points/s), spacing "
          f"{(U[1] - U[0]) / (args.grid - 1):.2g}; members seen: {len(seen)} of {len(m)}")
    need = (U[1] - U[0]) / narrow
    print(f"a grid with one point in the narrowest member: {need:.3g} points, about "
          f"{need / rate:.3g} s at that rate = x{need / rate / t_c:.3g} the cascade's time "
          f"(and its edges only to the spacing, not to rounding)")
    print(f"ratio, cascade vs this grid of {args.grid}: x{t_g / t_c:.2f} (time of the grid / time of the cascade)")


def window(repeat):
    e, u, n = (0.04, 0.065), (0.92, 0.945), 128
    t_f, df = best(lambda: sb.cascades(e=e, u=u, resolution=n, lines=3, k_max=60), repeat)
    lv = df.level.value_counts().to_dict()
    print(f"families of the Fig. 5e window: {lv.get(1, 0)} at level 1, {lv.get(2, 0)} at level 2, "
          f"{int(df[df.level == 1].members.sum())} members located exactly, in {t_f:.2f} s")
    t_s, _ = best(lambda: sb.scan(e=(*e, n), u=(*u, n), max_iter=1000), repeat)
    print(f"baseline sb.scan of the window at {n} x {n}: {t_s:.3f} s; ratio families / scan: x{t_f / t_s:.1f}")
    print(f"load after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
