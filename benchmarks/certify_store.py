"""The streamed certified atlas (issue 44 item 1): writing a store and verifying it.

    python benchmarks/certify_store.py [--depth 14] [--repeat 2] [--modes write,write-serial,verify,verify-whole]
                                       [--store /tmp/certify_store_bench.zarr]

Each run is a fresh process (its peak RSS is its own, ``ru_maxrss``), Fig. 7's window,
max_iter 1000, the default tiles; the modes alternate, ``--repeat`` times:

* ``write``: ``sb.certify_to_zarr(store, depth=d)`` as it is (each tile written by a
  writer thread while the next one is computed);
* ``write-serial``: the same with the tiles computed and written one after another
  (``_local_tiles`` replaced by the loop before it): the same boxes;
* ``verify``: ``sb.verify(store)``, tile by tile (``verify-2``: its tiles in 2 processes);
* ``verify-whole``: the checker on the whole table in memory (``read_store``, then the
  table's check: ``sb.verify`` of a store before the tile-by-tile check).

The machine is shared: the 1-minute load from ``/proc/loadavg`` is printed before and
after each run, with the run's wall time, CPU time (all threads) and peak RSS.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import time


def _load():
    with open("/proc/loadavg") as f:
        return float(f.read().split()[0])


def child(mode, depth, store):
    import importlib

    import stairbounce as sb

    S = importlib.import_module("stairbounce.structure.certify_store")
    V = importlib.import_module("stairbounce.structure.verdict")
    R = importlib.import_module("stairbounce.structure._store_read")
    if mode == "write-serial":
        S._local_tiles = lambda args, each: [each(S._tile_task(*a)) for a in args]
    t, c = time.perf_counter(), time.process_time()
    if mode.startswith("write"):
        shutil.rmtree(store, ignore_errors=True)
        st = sb.certify_to_zarr(store, depth=depth)
        what = f"{st.boxes} boxes, {st.attrs['n_tiles']} tiles"
    elif mode == "verify-whole":
        v = V._verify_dataset(R.read_store(store))
        what = v.message[:60]
    else:
        v = V._verify_store(store, workers=2 if mode == "verify-2" else None)
        what = v.message[:60]
    wall, cpu = time.perf_counter() - t, time.process_time() - c
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    kids = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    print(json.dumps(dict(mode=mode, depth=depth, wall=round(wall, 1), cpu=round(cpu, 1), peak_mib=round(peak),
                          child_peak_mib=round(kids), what=what)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--depth", type=int, default=14)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--modes", default="write,write-serial,verify,verify-whole")
    ap.add_argument("--store", default="/tmp/certify_store_bench.zarr")
    ap.add_argument("--child", default=None)
    a = ap.parse_args()
    if a.child:
        child(a.child, a.depth, a.store)
        return
    for _ in range(a.repeat):
        for mode in a.modes.split(","):
            before = _load()
            out = subprocess.run([sys.executable, __file__, "--child", mode, "--depth", str(a.depth),
                                  "--store", a.store], capture_output=True, text=True, env=dict(os.environ))
            line = (out.stdout.strip().splitlines() or [out.stderr.strip()[-300:]])[-1]
            print(f"load {before:.2f}-{_load():.2f} {line}", flush=True)


if __name__ == "__main__":
    main()
