"""Throughput of tiled scans written to Zarr (issue 8): local and on Dask workers.

The paper's window (e in [0, 1], u in [0, 1.5]) at ``--size`` pixels and
``--max-iter`` steps, cut into ``--tile`` tiles.  Measured in this process,
against baselines run here too (so the ratios hold on a busy machine):

- in-memory: :func:`stairbounce.plane.scan` on the whole window, numba on one
  thread and on all of them;
- local tiles: :func:`stairbounce.atlas.scan_to_zarr` with no client: on one
  core; the default (tiles side by side in a pool of threads, one numba
  thread each); one tile at a time on all numba threads;
- Dask: ``LocalCluster`` s of 1 and 2 worker processes with one thread each,
  and of 1 process with 2 threads (two tiles side by side), one numba thread
  per tile, warmed up first (numba's cache loaded);
- per-tile overhead: (tiled time - in-memory time on as many cores) / tiles,
  and the time per tile of the same tiled scan with ``max_iter = 1`` (no work:
  store creation, task round trip, five region writes and the done flag).

Every tiled run writes a fresh store, store creation included.  The cases run in
turn, ``--repeat`` rounds, best of each reported, so that a change in the load
from other jobs hits all of them alike.

Run: ``python benchmarks/distributed.py [--size 1024x768] [--max-iter 2000] [--tile 128] [--repeat 3]``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
import uuid

# this file's name would shadow the distributed package when run as a script
_HERE = os.path.dirname(os.path.abspath(__file__))
sys.path[:] = [p for p in sys.path if os.path.abspath(p or os.curdir) != _HERE]

import numba  # noqa: E402

from stairbounce.atlas import scan_to_zarr  # noqa: E402
from stairbounce.plane import scan  # noqa: E402


def interleaved(cases, repeat):
    """Wall times of every case, ``repeat`` rounds, the cases in turn within a
    round (so that load from other jobs hits all of them alike)."""
    times = {name: [] for name in cases}
    for _ in range(repeat):
        for name, fn in cases.items():
            t = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - t)
    return {name: (min(ts), statistics.median(ts)) for name, ts in times.items()}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default="1024x768", help="pixels along e x along u")
    parser.add_argument("--max-iter", type=int, default=2000)
    parser.add_argument("--tile", type=int, default=128)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="sb-bench-") as tmp:
        bench(args, tmp)


def bench(args, tmp):
    n_e, n_u = (int(x) for x in args.size.lower().split("x"))
    window = dict(e=(0.0, 1.0, n_e), u=(0.0, 1.5, n_u), max_iter=args.max_iter)
    n_tiles = -(-n_e // args.tile) * -(-n_u // args.tile)
    all_threads = numba.config.NUMBA_NUM_THREADS

    def fresh():
        return os.path.join(tmp, f"{uuid.uuid4().hex}.zarr")

    print(f"window {n_e} x {n_u}, max_iter {args.max_iter}, tile {args.tile}: {n_tiles} tiles; "
          f"numba {numba.__version__}, {all_threads} threads, layer ", end="")
    scan(e=(0.0, 1.0, 8), u=(0.0, 1.5, 8), max_iter=10)  # JIT warm
    print(numba.threading_layer())
    from distributed import Client, LocalCluster

    def in_memory(threads):
        def run():
            numba.set_num_threads(threads)
            try:
                scan(**window)
            finally:
                numba.set_num_threads(all_threads)
        return run

    def tiled(client=None, threads=None, max_iter=args.max_iter, cores=all_threads):
        def run():
            numba.set_num_threads(cores)
            try:
                scan_to_zarr(fresh(), tile=args.tile, client=client, numba_threads=threads,
                             **dict(window, max_iter=max_iter))
            finally:
                numba.set_num_threads(all_threads)
        return run

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as c1, \
         LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as c2, \
         LocalCluster(n_workers=1, threads_per_worker=2, processes=True, dashboard_address=None) as c3, \
         Client(c1) as one, Client(c2) as two, Client(c3) as threaded:
        for client in (one, two, threaded):  # numba's cache loaded in every worker
            scan_to_zarr(fresh(), e=(0.0, 1.0, 8), u=(0.0, 1.5, 8), max_iter=10, tile=4, client=client)
        cases = {
            "in-memory scan, 1 numba thread": in_memory(1),
            f"in-memory scan, {all_threads} numba threads": in_memory(all_threads),
            "local tiles, 1 core": tiled(cores=1),
            f"local tiles, {all_threads} side by side (default)": tiled(),
            f"local tiles, one at a time on {all_threads} threads": tiled(threads=all_threads),
            "Dask, 1 worker process x 1 thread": tiled(one),
            "Dask, 2 worker processes x 1 thread": tiled(two),
            "Dask, 1 worker process x 2 threads": tiled(threaded),
            "local tiles, max_iter = 1 (overhead)": tiled(max_iter=1),
            "Dask, 1 worker, max_iter = 1 (overhead)": tiled(one, max_iter=1),
            "Dask, 2 workers, max_iter = 1 (overhead)": tiled(two, max_iter=1),
        }
        res = interleaved(cases, args.repeat)
    # the in-memory scan on as many cores is the reference of each tiled case
    ref = {
        "local tiles, 1 core": res["in-memory scan, 1 numba thread"][0],
        f"local tiles, {all_threads} side by side (default)": res[f"in-memory scan, {all_threads} numba threads"][0],
        f"local tiles, one at a time on {all_threads} threads": res[f"in-memory scan, {all_threads} numba threads"][0],
        "Dask, 1 worker process x 1 thread": res["in-memory scan, 1 numba thread"][0],
        "Dask, 2 worker processes x 1 thread": res[f"in-memory scan, {all_threads} numba threads"][0],
        "Dask, 1 worker process x 2 threads": res[f"in-memory scan, {all_threads} numba threads"][0],
    }
    for name, (best, med) in res.items():
        extra = f"  overhead {1e3 * (best - ref[name]) / n_tiles:+6.1f} ms/tile" if name in ref else ""
        print(f"{name:<42} best {best:7.3f} s  median {med:7.3f} s  {n_tiles / best:7.1f} tiles/s{extra}")
    d1, d2 = res["Dask, 1 worker process x 1 thread"][0], res["Dask, 2 worker processes x 1 thread"][0]
    m1, m2 = res["in-memory scan, 1 numba thread"][0], res[f"in-memory scan, {all_threads} numba threads"][0]
    print(f"scaling 1 -> 2 Dask workers: x{d1 / d2:.2f}; in-memory scan 1 -> {all_threads} threads: x{m1 / m2:.2f}")
    print(f"load average at the end: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
