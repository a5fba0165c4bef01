"""Throughput of tiled scans written to Zarr (issue 8): local and on Dask workers.

The paper's window (e in [0, 1], u in [0, 1.5]) at ``--size`` pixels and
``--max-iter`` steps, cut into ``--tile`` tiles.  Measured in this process,
against baselines run here too (so the ratios hold on a busy machine):

- in-memory: :func:`stairbounce.scan.scan` on the whole window, numba on one
  thread and on all of them;
- local tiles: :func:`stairbounce.atlas.scan_to_zarr` with no client (tile
  after tile in this process), one numba thread and all of them;
- Dask: a ``LocalCluster`` of 1 then 2 worker processes with one thread each
  (one numba thread per tile), warmed up first (numba's cache loaded);
- per-tile overhead: (tiled time - in-memory time on as many threads) / tiles,
  and the time per tile of the same tiled scan with ``max_iter = 1`` (no work:
  store creation, task round trip, five region writes and the done flag).

Every tiled run writes a fresh store, store creation included.

Run: ``python benchmarks/distributed.py [--size 512x384] [--max-iter 1000] [--tile 64] [--repeat 3]``.
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
from stairbounce.scan import scan  # noqa: E402


def timed(fn, repeat):
    """Best and median wall time of ``repeat`` calls."""
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return min(times), statistics.median(times)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default="512x384", help="pixels along e x along u")
    parser.add_argument("--max-iter", type=int, default=1000)
    parser.add_argument("--tile", type=int, default=64)
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
    rows = []

    def row(name, best, med, ref=None):
        rate = n_tiles / best
        extra = "" if ref is None else f"  overhead {1e3 * (best - ref) / n_tiles:+.1f} ms/tile"
        rows.append((name, best, med, rate))
        print(f"{name:<42} best {best:7.3f} s  median {med:7.3f} s  {rate:7.1f} tiles/s{extra}", flush=True)

    mem = {}
    for threads in (1, all_threads):
        numba.set_num_threads(threads)
        mem[threads] = timed(lambda: scan(**window), args.repeat)
        row(f"in-memory scan, {threads} numba thread(s)", *mem[threads])
    for threads in (1, all_threads):
        best, med = timed(
            lambda: scan_to_zarr(fresh(), tile=args.tile, numba_threads=threads, **window), args.repeat
        )
        row(f"local tiles, {threads} numba thread(s)", best, med, ref=mem[threads][0])
    numba.set_num_threads(all_threads)
    best, med = timed(
        lambda: scan_to_zarr(fresh(), tile=args.tile, **dict(window, max_iter=1)), args.repeat
    )
    row("local tiles, max_iter = 1 (overhead only)", best, med)

    from distributed import Client, LocalCluster

    dask_best = {}
    for workers in (1, 2):
        with LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster, Client(cluster) as client:
            scan_to_zarr(fresh(), e=(0.0, 1.0, 8), u=(0.0, 1.5, 8), max_iter=10, tile=4, client=client)
            best, med = timed(lambda: scan_to_zarr(fresh(), tile=args.tile, client=client, **window), args.repeat)
            dask_best[workers] = best
            row(f"Dask, {workers} worker process(es) x 1 thread", best, med, ref=mem[1][0] / workers)
            best, med = timed(
                lambda: scan_to_zarr(fresh(), tile=args.tile, client=client, **dict(window, max_iter=1)),
                args.repeat,
            )
            row(f"Dask, {workers} worker(s), max_iter = 1 (overhead)", best, med)
    print(f"scaling 1 -> 2 workers: x{dask_best[1] / dask_best[2]:.2f} "
          f"(in-memory 1 -> {all_threads} threads: x{mem[1][0] / mem[all_threads][0]:.2f})")
    print(f"load average at the end: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
