"""Proven box counts of the paper's perimeter (issue 44 item 4): the border of the region
sliding within max_iter, bracketed per scale by a certified atlas with class-level proofs.

    python benchmarks/perimeter.py [--windows fig7,fig6] [--depths 10,12] [--max-iter 1000]
                                   [--store-from 12] [--tmp DIR]

For each window (the figures' DIMENSION_WINDOWS) and depth: ``sb.certify(...,
classes=True)`` (from ``--store-from`` on streamed with ``sb.certify_to_zarr`` into
``--tmp`` and loaded back: the same boxes, less memory while certifying), then
``CertifiedAtlas.perimeter_bracket()``, which runs the independent checker
``sb.verify`` on every box and counts; the wall time of each part, the peak memory of
the process so far (``ru_maxrss``), the lower/upper counts per scale k = 3 .. depth, the
slope bracket between k = 3 and the depth, and the narrowest one between two scales
whose lower counts are > 0.  The machine is shared: ``uptime`` is printed before and after.
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import tempfile
import time


def _uptime():
    with open("/proc/loadavg") as f:
        return "load " + " ".join(f.read().split()[:3])


def measure(name, e, u, depth, max_iter, store_from, tmp):
    import stairbounce as sb

    t0 = time.perf_counter()
    if depth >= store_from:
        path = os.path.join(tmp, f"{name}-d{depth}.zarr")
        shutil.rmtree(path, ignore_errors=True)
        sb.certify_to_zarr(path, e=e, u=u, depth=depth, max_iter=max_iter, classes=True, verify=False)
        atlas = sb.CertifiedAtlas.load(path)
    else:
        atlas = sb.certify(e=e, u=u, depth=depth, max_iter=max_iter, classes=True)
    t1 = time.perf_counter()
    r = atlas.perimeter_bracket()
    t2 = time.perf_counter()
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
    print(f"{name} depth {depth} max_iter {max_iter}: {atlas.boxes.sizes['box']:,} boxes; certify "
          f"{t1 - t0:.1f} s, verify + counts {t2 - t1:.1f} s; peak {rss:.2f} GiB; basis {r['basis']} "
          f"(verified {r['verified']}); {_uptime()}")
    print("  k      " + " ".join(f"{k:>8d}" for k in r["k"]))
    print("  lower  " + " ".join(f"{x:>8d}" for x in r["lower"]))
    print("  upper  " + " ".join(f"{x:>8d}" for x in r["upper"]))
    print(f"  slope {r['slope_text']}")
    print(f"  narrowest between two scales with lower counts > 0: {r['finite_text']}", flush=True)
    return r


def main(argv=None):
    from stairbounce.figures import DIMENSION_WINDOWS

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--windows", default="fig7,fig6")
    p.add_argument("--depths", default="10,12")
    p.add_argument("--max-iter", type=int, default=1000)
    p.add_argument("--store-from", type=int, default=12)
    p.add_argument("--tmp", default=None)
    a = p.parse_args(argv)
    print(f"{time.strftime('%Y-%m-%d %H:%M')} UTC, {os.cpu_count()} cores, {_uptime()}", flush=True)
    with tempfile.TemporaryDirectory(dir=a.tmp) as tmp:
        for name in a.windows.split(","):
            (e, u), _ = DIMENSION_WINDOWS[name]
            for depth in (int(d) for d in a.depths.split(",")):
                measure(name, e, u, depth, a.max_iter, a.store_from, tmp)
    print(f"done, {_uptime()}")


if __name__ == "__main__":
    main()
