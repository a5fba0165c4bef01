"""What the safety of issue 17 costs, against baselines in the same process.

    python benchmarks/store_safety.py [--repeat 5] [--size 1024] [--tile 128]

1. The halt flag the scan kernel reads once per lockstep step (Ctrl-C,
   ``stairbounce._interrupt``): ``_scan_fast`` against a copy of itself
   compiled from the same source without the check, interleaved, on the
   paper's grid (500 x 350, max_iter 1000).  The answers are compared bit for
   bit, then the time ratio is printed.
2. The helper thread of ``run_kernel``: ``scan_coords`` (kernel in a helper
   thread, main thread waiting) against the kernel called in place.
3. Resuming a complete tiled store: the checksum read of every tile
   (``verify=True``) against the same call with ``verify=False``, and against
   the time the store took to compute.
4. ``load`` of that store (issue 23: its coordinates are checked against its
   window) and a ``figures`` run from a warm cache (issue 23: an entry is
   checked against its request and a checksum of its data).  Absolute times:
   to compare two versions, run this script under each back to back
   (``--only 3,4``; PYTHONPATH selects the version), as benchmarks/README.md says.
5. ``--baseline-src DIR`` (a checkout's ``src``, e.g. ``git archive ce04da2 src``):
   parts 3 and 4 for this version and that one in the same process,
   interleaved (the baseline imported as ``stairbounce_baseline``), on one
   store: resume (verify=True), load, and a warm-cache ``figures`` run;
   the ratio this / baseline of the best times.
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
import time
import types
from pathlib import Path

import numba
import numpy as np

import stairbounce.plane as P
from stairbounce.atlas import scan_to_zarr
from _timing import wall_times


def no_check_copy():
    """``stairbounce.plane`` compiled again with the per-step halt check removed (not cached)."""
    src = Path(P.__file__).read_text()
    check = "        if halted(halt):\n            return pos[2]\n        g += 1\n"
    if check not in src:
        sys.exit("the halt check of _run_unit is not where this script expects it")
    src = src.replace(check, "        g += 1\n").replace("cache=True", "cache=False")
    src = src.replace("from . import", "from stairbounce import").replace("from .", "from stairbounce.")
    mod = types.ModuleType("plane_without_halt_check")
    exec(compile(src, "plane_without_halt_check.py", "exec"), mod.__dict__)
    return mod


def best(f, repeat):
    times, _ = wall_times(f, repeat)
    return min(times), float(np.median(times))


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--repeat", type=int, default=5)
    p.add_argument("--size", type=int, default=1024, help="side of the tiled store (pixels)")
    p.add_argument("--tile", type=int, default=128)
    p.add_argument("--only", default="1,2,3,4", help="parts to run, e.g. 3,4")
    p.add_argument("--figures", default="fig4,fig8", help="figures of part 4's cached run")
    p.add_argument("--baseline-src", default=None, help="part 5: a baseline version's src folder")
    args = p.parse_args()
    parts = set(args.only.split(","))
    print(f"load {os.getloadavg()[0]:.2f}, numba threads {numba.get_num_threads()}, stairbounce from "
          f"{Path(P.__file__).parent}")
    if parts & {"1", "2"}:
        kernel_parts(args)
    if parts & {"3", "4"}:
        store_parts(args, parts)
    if args.baseline_src:
        against_baseline(args)


def _baseline(src):
    """The package in ``src`` imported as ``stairbounce_baseline`` (relative imports only)."""
    import importlib

    where = Path(tempfile.mkdtemp(prefix="stairbounce-baseline-"))
    shutil.copytree(Path(src) / "stairbounce", where / "stairbounce_baseline")
    sys.path.insert(0, str(where))
    return importlib.import_module("stairbounce_baseline"), where


def against_baseline(args):
    import stairbounce as new

    old, where = _baseline(args.baseline_src)
    work = Path(tempfile.mkdtemp(prefix="stairbounce-bench-"))
    try:
        store = work / "a.zarr"
        kw = dict(e=(0, 1, args.size), u=(0, 1.5, args.size), max_iter=1000, tile=args.tile)
        new.scan_to_zarr(store, **kw)
        names = args.figures.split(",")
        figs = {}
        for tag, pkg in (("new", new), ("old", old)):
            F = importlib_figures(pkg)
            (work / f"figs-{tag}").mkdir()
            figs[tag] = (F, F.Settings(out=work / f"figs-{tag}", dpi=60, cache_dir=work / f"cache-{tag}",
                                       overwrite=True))
            F.make_figures(figs[tag][1], names)  # fills its cache (and compiles)
            pkg.scan_to_zarr(store, **kw)
            pkg.load(store)
        times = {(tag, what): [] for tag in ("new", "old") for what in ("resume", "load", "figures")}
        cpu = {key: [] for key in times}  # CPU time of this process: less moved by other processes
        for i in range(args.repeat):  # interleaved, in turn first: load changes hit both alike
            for tag, pkg in ((("new", new), ("old", old)) if i % 2 == 0 else (("old", old), ("new", new))):
                for what, f in (("resume", lambda: pkg.scan_to_zarr(store, **kw)),
                                ("load", lambda: pkg.load(store)),
                                ("figures", lambda: figs[tag][0].make_figures(figs[tag][1], names))):
                    t, c = time.perf_counter(), time.process_time()
                    f()
                    times[tag, what].append(time.perf_counter() - t)
                    cpu[tag, what].append(time.process_time() - c)
        print(f"5. this version against {args.baseline_src}, same process, interleaved, best of {args.repeat} "
              f"(load {os.getloadavg()[0]:.2f}):")
        for what in ("resume", "load", "figures"):
            a, b = min(times["new", what]), min(times["old", what])
            ca, cb = min(cpu["new", what]), min(cpu["old", what])
            print(f"   {what:8s} wall: this {a:.3f} s, baseline {b:.3f} s, ratio {a / b:.3f} "
                  f"(medians {np.median(times['new', what]):.3f} / {np.median(times['old', what]):.3f}); "
                  f"CPU: {ca:.3f} / {cb:.3f} s, ratio {ca / cb:.3f}")
    finally:
        shutil.rmtree(work, ignore_errors=True)
        shutil.rmtree(where, ignore_errors=True)


def importlib_figures(pkg):
    import importlib

    return importlib.import_module(pkg.__name__ + ".figures")


def kernel_parts(args):

    es = P.pixel_centres(0, 1, 500)
    us = P.pixel_centres(0, 1.5, 350)
    chunk, units = P._chunking(es.size * us.size, numba.get_num_threads())
    base = no_check_copy()

    def run(kernel):
        outs = [np.empty(es.size * us.size, dt) for dt, _ in P._FIELDS.values()]
        kernel(es, us, True, 1000, 1.0, 0.0, True, units, chunk, *outs, np.zeros(1, np.int64))
        return outs

    a, b = run(P._scan_fast), run(base._scan_fast)  # also compiles the copy
    assert all(np.array_equal(x, y) for x, y in zip(a, b)), "the halt check changed an answer"
    with_check, without = [], []
    for _ in range(args.repeat):  # interleaved: load changes hit both alike
        with_check.append(best(lambda: run(P._scan_fast), 1)[0])
        without.append(best(lambda: run(base._scan_fast), 1)[0])
    print(f"1. scan kernel, paper's grid: with halt check {min(with_check):.3f} s, without {min(without):.3f} s"
          f" (best of {args.repeat}); ratio {min(with_check) / min(without):.3f}; answers identical")

    in_place = best(lambda: run(P._scan_fast), args.repeat)[0]
    helper = best(lambda: P.scan_coords(es, us, 1000), args.repeat)[0]
    print(f"2. scan_coords through the helper thread {helper:.3f} s, kernel in place {in_place:.3f} s;"
          f" ratio {helper / in_place:.3f} (includes building the Dataset)")



def store_parts(args, parts):
    work = Path(tempfile.mkdtemp(prefix="stairbounce-bench-"))
    try:
        store = work / "a.zarr"
        kw = dict(e=(0, 1, args.size), u=(0, 1.5, args.size), max_iter=1000, tile=args.tile)
        t = time.perf_counter()
        scan_to_zarr(store, **kw)
        compute = time.perf_counter() - t
        verify = best(lambda: scan_to_zarr(store, **kw), args.repeat)[0]
        skip = best(lambda: scan_to_zarr(store, verify=False, **kw), args.repeat)[0]
        n_tiles = (-(-args.size // args.tile)) ** 2
        if "3" in parts:
            print(f"3. resume of a complete {args.size}^2 store ({n_tiles} tiles of {args.tile}): "
                  f"verify {verify:.3f} s, verify=False {skip:.3f} s, computing it took {compute:.2f} s; "
                  f"checksum read = {(verify - skip) / compute:.1%} of the compute time, "
                  f"{args.size ** 2 / max(verify - skip, 1e-9) / 1e6:.0f} M px/s")
        if "4" in parts:
            from stairbounce import figures as F
            from stairbounce.plane import load

            loaded = best(lambda: load(store), args.repeat)[0]
            names = args.figures.split(",")
            settings = F.Settings(out=work / "figs", dpi=60, cache_dir=work / "cache", overwrite=True)
            (work / "figs").mkdir()
            t = time.perf_counter()
            F.make_figures(settings, names)  # fills the cache
            cold = time.perf_counter() - t
            warm = best(lambda: F.make_figures(settings, names), args.repeat)[0]
            print(f"4. load of the {args.size}^2 store {loaded:.3f} s; figures {args.figures} from a warm "
                  f"cache {warm:.3f} s (best of {args.repeat}; filling the cache took {cold:.1f} s)")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
