"""Speed of the two dimension estimators of issue 12, with baselines run in the same process.

1. ``uncertainty_dimension`` of the Fig. 7 window's sliding border:
   ``--points`` random points (default 10^6), the 11 default eps, max_iter
   1000, random directions: 1 + 2 x 11 = 23 classifications per point.
   Baseline: ``plane.scan_points`` of the same 10^6 points once; the ratio
   ``time / (23 x baseline)`` is the estimator's overhead over classifying
   (1.0 = none; perturbed points cost what their neighbours cost).
2. ``atlas_boxes.store_box_counts`` of a finished tiled store of the Fig. 7
   window (default: 8192^2 px, tile 1024, built under ``--store-dir`` first
   if missing, not timed; ``--store PATH`` for another, e.g. 32768^2).
   Baseline: ``fractal.boundary`` + ``fractal.box_counts`` of a 4096^2 block
   of the same store held in memory; the ratio compares pixels per second.

Run: ``python benchmarks/dimension_speed.py`` (about a minute on an idle
2-core machine, plus the one-off 8192^2 store).  Prints the load average
beside each number: the machine is shared.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from stairbounce.atlas import scan_to_zarr
from stairbounce.atlas_boxes import store_box_counts, store_info
from stairbounce.figures import DIMENSION_WINDOWS
from stairbounce.dimension import (
    DEFAULT_EPS,
    boundary,
    box_counts,
    random_points,
    sliding_classifier,
    uncertainty_dimension,
)
from stairbounce.plane import scan_points


def load():
    return f"load {os.getloadavg()[0]:.2f} on {os.cpu_count()} cpus"


def bench_uncertainty(n_points, max_iter):
    (e, u), _ = DIMENSION_WINDOWS["fig7"]
    classify = sliding_classifier(max_iter)
    x, y, _ = random_points((e, u), 2000, seed=1)
    scan_points(x, y, max_iter=max_iter)  # compile / load numba's cache outside the timings
    x, y, _ = random_points((e, u), n_points, seed=0)
    t = time.perf_counter()
    scan_points(x, y, max_iter=max_iter)
    base = time.perf_counter() - t
    print(f"baseline: scan_points of {n_points} points, max_iter {max_iter}: {base:.2f} s "
          f"({n_points / base / 1e6:.2f} M points/s; {load()})")
    t = time.perf_counter()
    est = uncertainty_dimension(classify, (e, u), n_points=n_points, seed=0)
    sec = time.perf_counter() - t
    per = 1 + 2 * DEFAULT_EPS.size
    print(f"uncertainty_dimension, Fig. 7 window, {n_points} points x {DEFAULT_EPS.size} eps, "
          f"max_iter {max_iter}: {sec:.2f} s ({per * n_points / sec / 1e6:.2f} M classifications/s); "
          f"ratio to {per} x baseline: {sec / (per * base):.2f}; D = {est.dimension:.4f} ({load()})")


def bench_boxes(store, store_dir, resolution, tile):
    if store is None:
        (e, u), _ = DIMENSION_WINDOWS["fig7"]
        store = Path(store_dir) / f"fig7_{resolution}_1000_t{tile}.zarr"
        Path(store_dir).mkdir(parents=True, exist_ok=True)
        t = time.perf_counter()
        scan_to_zarr(store, e=(e[0], e[1], resolution), u=(u[0], u[1], resolution), max_iter=1000, tile=tile)
        print(f"store {store} ready ({time.perf_counter() - t:.1f} s, not timed below)")
    info = store_info(store)
    n_e, n_u = info["n_e"], info["n_u"]
    # baseline: the same steps on one block held in memory
    import zarr

    side = min(4096, n_e, n_u)
    block = zarr.open_group(str(store), mode="r")["status"][:side, :side]
    box_counts(boundary(block == 0))  # compile (the parallel kernels of large images) outside the timing
    t = time.perf_counter()
    box_counts(boundary(block == 0))
    base = time.perf_counter() - t
    base_rate = side * side / base
    print(f"baseline: boundary + box_counts of a {side}^2 block in memory: {base:.3f} s "
          f"({base_rate / 1e6:.0f} M px/s; {load()})")
    t = time.perf_counter()
    s, c = store_box_counts(store)
    sec = time.perf_counter() - t
    rate = n_e * n_u / sec
    print(f"store_box_counts of {store} ({n_e} x {n_u} px, tile {info['tile']}): {sec:.2f} s "
          f"({rate / 1e6:.0f} M px/s); ratio to the in-memory rate: {rate / base_rate:.2f} ({load()})")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--points", type=int, default=1_000_000)
    p.add_argument("--max-iter", type=int, default=1000)
    p.add_argument("--store", default=None, help="a finished store to count (default: build 8192^2)")
    p.add_argument("--store-dir", default="/work/scratch/i12")
    p.add_argument("--resolution", type=int, default=8192)
    p.add_argument("--tile", type=int, default=1024)
    p.add_argument("--skip-uncertainty", action="store_true")
    p.add_argument("--skip-boxes", action="store_true")
    a = p.parse_args(argv)
    if not a.skip_uncertainty:
        bench_uncertainty(a.points, a.max_iter)
    if not a.skip_boxes:
        bench_boxes(a.store, a.store_dir, a.resolution, a.tile)


if __name__ == "__main__":
    main()
