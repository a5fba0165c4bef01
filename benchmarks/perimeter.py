"""Proven box counts of the paper's perimeter (issue 44 item 4): the border of the region
sliding within max_iter, bracketed per scale by a certified atlas with class-level proofs.

    python benchmarks/perimeter.py [--windows fig7,fig6] [--depths 10,12] [--max-iter 1000]
                                   [--store-from 12] [--tmp DIR] [--stores DIR]
                                   [--trap {none,on,fine}] [--focus K] [--streamed-only]

For each window (the figures' DIMENSION_WINDOWS) and depth: ``sb.certify(...,
classes=True)``, then ``CertifiedAtlas.perimeter_bracket()``, which runs the independent
checker ``sb.verify`` on every box and counts; from ``--store-from`` on the atlas is
streamed with ``sb.certify_to_zarr`` into ``--tmp`` instead, and the bracket is taken
twice, each in a fresh process: from the store tile by tile
(``CertifiedStore.perimeter_bracket``) and from the atlas loaded whole (the counts must
agree).  Printed: the wall time of each part, the peak memory of the process
(``ru_maxrss``), the proven points inside undecided boxes that the lower counts
used (``structure/witnesses.py``), the lower/upper counts per scale k = 3 .. depth, the slope bracket
between k = 3 and the depth, and the narrowest one between two scales whose lower counts
are > 0.  The machine is shared: its load is printed with the times.  ``--stores DIR``
keeps the stores in DIR, and a store already there is resumed (``certify_to_zarr`` checks
its tiles against their checksums and computes only what is missing) instead of written
again: to count an existing store with changed counting code.  ``--trap on`` / ``fine``
certifies with ``trap=True`` / ``trap="fine"`` as well (trapping regions prove boxes
below the Corollary 2.1 curve ``no_sliding``: fewer undecided boxes, lower upper counts).
``--streamed-only`` takes a store's bracket tile by tile only (not loaded whole as well).
``--focus K`` streams with ``certify_to_zarr(focus=K)``: certified to depth K, then
deepened to the depth only where the counts at k <= K can change
(``structure/focus.py``); the counts are then taken at k = 3 .. K, and the store's
boxes, its time and the number of boxes each round took up are printed.
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


def measure(name, e, u, depth, max_iter, store_from, tmp, keep=False, trap=False, ways=("streamed", "loaded"),
            focus=None):
    import stairbounce as sb

    t0 = time.perf_counter()
    if depth >= store_from or focus is not None:
        path = os.path.join(tmp, f"{name}-d{depth}" + ("" if focus is None else f"-focus{focus}") + ".zarr")
        if not keep:
            shutil.rmtree(path, ignore_errors=True)
        rounds = _count_rounds() if focus is not None else {}
        st = sb.certify_to_zarr(path, e=e, u=u, depth=depth, max_iter=max_iter, classes=True, trap=trap,
                                verify=False, focus=focus)
        print(f"{name} depth {depth} trap {trap} focus {focus}: store written (or resumed) in "
              f"{time.perf_counter() - t0:.1f} s, {st.boxes:,} boxes; {_uptime()}", flush=True)
        if rounds:
            print("  rounds (depth: rows certified again, rows whose trapping tries went one level further, rows): "
                  + ", ".join(f"{d}: {a:,}, {b:,}, {n:,}" for d, (a, b, n) in sorted(rounds.items())), flush=True)
        return _from_store(name, path, ways)
    else:
        atlas = sb.certify(e=e, u=u, depth=depth, max_iter=max_iter, classes=True, trap=trap)
    t1 = time.perf_counter()
    r = atlas.perimeter_bracket()
    t2 = time.perf_counter()
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
    print(f"{name} depth {depth} max_iter {max_iter} trap {trap}: {atlas.boxes.sizes['box']:,} boxes; certify "
          f"{t1 - t0:.1f} s, verify + counts {t2 - t1:.1f} s; peak {rss:.2f} GiB; basis {r['basis']} "
          f"(verified {r['verified']}), {r['witnesses']:,} proven points in undecided boxes; {_uptime()}")
    print("  k      " + " ".join(f"{k:>8d}" for k in r["k"]))
    print("  lower  " + " ".join(f"{x:>8d}" for x in r["lower"]))
    print("  upper  " + " ".join(f"{x:>8d}" for x in r["upper"]))
    print(f"  slope {r['slope_text']}")
    print(f"  narrowest between two scales with lower counts > 0: {r['finite_text']}", flush=True)
    return r


_CHILD = """
import json, resource, sys, time
import stairbounce as sb
t = time.perf_counter()
if sys.argv[2] == "streamed":
    r = sb.CertifiedStore(sys.argv[1]).perimeter_bracket()
else:
    r = sb.CertifiedAtlas.load(sys.argv[1]).perimeter_bracket()
print(json.dumps({"seconds": time.perf_counter() - t, "peak_gib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20,
                  "lower": r["lower"], "upper": r["upper"], "k": r["k"], "basis": r["basis"],
                  "slope_text": r["slope_text"], "finite_text": r["finite_text"],
                  "witnesses": r["witnesses"], "tried": r["witnesses_tried"]}))
"""


def _count_rounds():
    """The rows each round of ``focus.refine`` took up, summed over the tiles of this
    process (``{depth: [again, deeper, rows]}``)."""
    from stairbounce.structure import focus

    rounds = {}
    plain = focus.refine

    def refine(*args, report=None, **kw):
        def each(d, again, deeper, rows):
            r = rounds.setdefault(d, [0, 0, 0])
            r[0] += again
            r[1] += deeper
            r[2] += rows

        return plain(*args, report=each, **kw)

    focus.refine = refine
    return rounds


def _from_store(name, path, ways=("streamed", "loaded")):
    """The store's perimeter bracket two ways, each in a fresh process (its own peak
    memory): tile by tile (``CertifiedStore.perimeter_bracket``: the checker on the store,
    then the counts) and loaded whole (``CertifiedAtlas.load(path).perimeter_bracket()``);
    the counts must be equal."""
    import json
    import subprocess
    import sys

    got = {}
    for how in ways:
        out = subprocess.run([sys.executable, "-c", _CHILD, path, how], capture_output=True, text=True, check=True)
        got[how] = r = json.loads(out.stdout.strip().splitlines()[-1])
        print(f"  {how}: verify + counts {r['seconds']:.1f} s, peak {r['peak_gib']:.2f} GiB (the process), "
              f"basis {r['basis']}, {r['witnesses']:,} proven points in undecided boxes ({r['tried']:,} "
              f"certified); {_uptime()}", flush=True)
    r = got["streamed"]
    if "loaded" in got:
        same = all(got["streamed"][k] == got["loaded"][k] for k in ("lower", "upper", "k"))
        print(f"  the same counts both ways: {same}")
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
    p.add_argument("--stores", default=None)
    p.add_argument("--trap", choices=("none", "on", "fine"), default="none")
    p.add_argument("--streamed-only", action="store_true")
    p.add_argument("--focus", type=int, default=None)
    a = p.parse_args(argv)
    trap = {"none": False, "on": True, "fine": "fine"}[a.trap]
    print(f"{time.strftime('%Y-%m-%d %H:%M')} UTC, {os.cpu_count()} cores, {_uptime()}", flush=True)
    with tempfile.TemporaryDirectory(dir=a.tmp) as tmp:
        if a.stores:
            os.makedirs(a.stores, exist_ok=True)
        for name in a.windows.split(","):
            (e, u), _ = DIMENSION_WINDOWS[name]
            for depth in (int(d) for d in a.depths.split(",")):
                measure(name, e, u, depth, a.max_iter, a.store_from, a.stores or tmp, keep=bool(a.stores),
                        trap=trap, ways=("streamed",) if a.streamed_only else ("streamed", "loaded"), focus=a.focus)
    print(f"done, {_uptime()}")


if __name__ == "__main__":
    main()
