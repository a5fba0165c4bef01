"""Benchmark: the motion scan (<k>, Lyapunov exponents) of the paper's grid.

    python benchmarks/motion.py [--n-e 500] [--n-u 350] [--steps 1000] [--transient 1000] [--repeat 3]

Rows, all JIT-warm and run in this process: ``motion_scan`` (kernel
``_motion_fast``: 32 pixels in lockstep in a branch-free loop, interleaved
chunks over the threads), the same on one numba thread, the plain kernel
``_motion_plain`` (one pixel at a time, prange over rows) and, for scale, the
sliding scan ``plane.scan`` of the same grid (it stops where the orbit slides,
max_iter = transient + steps).  Wall and process CPU time are printed: CPU
time is the steadier measure on a shared machine.  The fast and plain kernels'
answers are checked to be identical.
"""

from __future__ import annotations

import argparse
import os
import time

import numba
import numpy as np

from stairbounce.nonsliding import motion_scan
from stairbounce.plane import scan
from _timing import int_options


def best(f, repeat):
    walls, cpus = [], []
    for _ in range(repeat):
        w, c = time.perf_counter(), time.process_time()
        r = f()
        walls.append(time.perf_counter() - w)
        cpus.append(time.process_time() - c)
    return min(walls), min(cpus), r


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    int_options(p, n_e=500, n_u=350, steps=1000, transient=1000, repeat=3)
    a = p.parse_args(argv)
    grid = dict(e=(0.0, 1.0, a.n_e), u=(0.0, 1.5, a.n_u), steps=a.steps, transient=a.transient)
    motion_scan((0.0, 1.0, 8), (0.0, 1.5, 8), 10, 10)  # compile
    motion_scan((0.0, 1.0, 8), (0.0, 1.5, 8), 10, 10, kernel="plain")
    print(f"load average {os.getloadavg()}, numba threads {numba.get_num_threads()}")
    w, c, fast = best(lambda: motion_scan(**grid), a.repeat)
    ns = np.where(fast.slide_step.values == 0, a.steps + a.transient, fast.slide_step.values)
    its = float(ns.sum())
    print(f"grid {a.n_e} x {a.n_u}, {a.transient} transient + {a.steps} kept steps: "
          f"{its / 1e6:.1f} M map steps (non-sliding pixels: {(fast.slide_step == 0).mean().item():.1%})")
    print(f"motion_scan (fast)   {w:7.3f} s wall  {c:7.3f} s CPU  {its / w / 1e6:6.0f} M steps/s")
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    w1, c1, _ = best(lambda: motion_scan(**grid), a.repeat)
    numba.set_num_threads(threads)
    print(f"fast, 1 thread       {w1:7.3f} s wall  {c1:7.3f} s CPU  (x{w1 / w:.2f} for the threads)")
    wp, cp, plain = best(lambda: motion_scan(**grid, kernel="plain"), a.repeat)
    same = all(np.array_equal(fast[v].values, plain[v].values, equal_nan=True) for v in fast.data_vars)
    print(f"plain kernel         {wp:7.3f} s wall  {cp:7.3f} s CPU  "
          f"(fast is x{wp / w:.2f} wall, x{cp / c:.2f} CPU; identical: {same})")
    scan((0.0, 1.0, 8), (0.0, 1.5, 8), 10)
    ws, cs, _ = best(lambda: scan(grid["e"], grid["u"], max_iter=a.steps + a.transient), a.repeat)
    print(f"sliding scan         {ws:7.3f} s wall  {cs:7.3f} s CPU  (motion costs x{w / ws:.2f})")
    print(f"load average {os.getloadavg()}")


if __name__ == "__main__":
    main()
