"""Throughput of the orbit-diagram kernel (issue 5): the paper's Figs. 8 and 9.

3000 parameter values x 2200 iterates (2000 discarded, 200 kept), JIT warm;
target < 0.1 s on 2 cores.  Every figure is measured in this process against
baselines run here too, so the ratios hold on a busy machine even when the
absolute times do not:

- parallel: ``orbit_diagram`` (``_orbit_kernel``, prange over the values);
- serial: the same kernel on one numba thread;
- warm start: ``orbit_diagram(..., warm_start=True)``, sequential by design;
- Python: a loop over the public ``poincare_map`` on a subsample of the
  values, scaled to the full sweep.

Run: ``python benchmarks/orbits.py [--repeat 7] [--n 3000]``.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numba
import numpy as np

from stairbounce import poincare_map
from stairbounce.orbits import orbit_diagram
from _timing import wall_times

CASES = {
    "Fig. 8 (e = 0.001, u in [0.3, 2.0])": (0.001, (0.3, 2.0)),
    "Fig. 9 (e = 0.1, u in [0.3, 1.0])": (0.1, (0.3, 1.0)),
}


def timed(fn, repeat):
    """Best and median wall time of ``repeat`` calls."""
    times, _ = wall_times(fn, repeat)
    return min(times), statistics.median(times)


def python_loop(e, us, transient, keep):
    for u in us:
        y, v = 0.1, 0.0
        for _ in range(transient + keep):
            y, v, _k = poincare_map(y, v, e, u)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=3000, help="parameter values")
    parser.add_argument("--transient", type=int, default=2000)
    parser.add_argument("--keep", type=int, default=200)
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--python-values", type=int, default=20,
                        help="values run through the Python baseline (scaled to --n)")
    args = parser.parse_args()
    steps = args.n * (args.transient + args.keep)
    threads = numba.get_num_threads()
    orbit_diagram(0.1, np.linspace(0.3, 1.0, 16), transient=10, keep=10)  # compile / load cache
    orbit_diagram(0.1, np.linspace(0.3, 1.0, 16), transient=10, keep=10, warm_start=True)
    print(f"{args.n} values x {args.transient + args.keep} iterates = {steps / 1e6:.1f} M map steps; "
          f"numba {numba.__version__}, {threads} threads ({numba.threading_layer()} layer)")

    for label, (e, (lo, hi)) in CASES.items():
        us = np.linspace(lo, hi, args.n)

        def par():
            orbit_diagram(e, us, transient=args.transient, keep=args.keep)

        def warm():
            orbit_diagram(e, us, transient=args.transient, keep=args.keep, warm_start=True)

        best_par, med_par = timed(par, args.repeat)
        numba.set_num_threads(1)
        try:
            best_ser, med_ser = timed(par, max(3, args.repeat // 2))
        finally:
            numba.set_num_threads(threads)
        best_warm, med_warm = timed(warm, max(3, args.repeat // 2))
        sub = us[:: max(1, args.n // args.python_values)]
        t = time.perf_counter()
        python_loop(e, sub, args.transient, args.keep)
        py = (time.perf_counter() - t) * args.n / sub.size

        print(f"\n{label}")
        print(f"  {'kernel':<34} {'best s':>9} {'median s':>9} {'M steps/s':>10} {'x Python':>9}")
        rows = [
            (f"parallel ({threads} threads)", best_par, med_par),
            ("serial (1 thread)", best_ser, med_ser),
            ("warm start (sequential)", best_warm, med_warm),
            (f"Python loop ({sub.size} values, scaled)", py, py),
        ]
        for name, best, med in rows:
            print(f"  {name:<34} {best:>9.4f} {med:>9.4f} {steps / best / 1e6:>10.1f} {py / best:>9.0f}")
        print(f"  parallel speed-up over serial: x{best_ser / best_par:.2f}; "
              f"target < 0.1 s: {'met' if best_par < 0.1 else 'NOT met'} ({best_par * 1e3:.1f} ms)")


if __name__ == "__main__":
    main()
