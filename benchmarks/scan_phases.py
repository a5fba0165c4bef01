"""Where the scan kernel's cycles go, phase by phase (issue 26).

    python benchmarks/scan_phases.py [--repeat 15] [--fence]

The machine gives no hardware counters to ``perf stat`` (a virtual machine),
so this is numba-level timing in a benchmark build: ``stairbounce.plane`` is
compiled again (not cached) with every ``# phase N: ...`` comment of
``_run_unit`` replaced by a read of the time-stamp counter
(``llvm.readcyclecounter``) that adds the cycles since the previous mark to
counter N.  The counters live in the kernel's halt array past ``halt[0]``
(the flag itself stays 0), so no signature changes.  Phases:

1. listing the first segments (pruning test, pruned pixels stored) and loading the lanes;
2. the common step and its bookkeeping with all LANES lanes live;
3. the same in the tail of a unit (fewer live lanes than LANES);
4. impacts 4 to 7 (the counting continuation; 2 to 7 before the common step took impacts 2 and 3;
   only after a common step that stopped at the third impact, since the sixth round);
5. the closed form past ``model._COUNTED_IMPACTS`` impacts (lane by lane);
6. finished pixels: store, reload, and the listing of later segments.

One thread, so the counters add up to the kernel's time.  The counter
ticks on while the process waits for a core, so each phase's figure is its
least over the repeats.  The timer reads
cost cycles themselves: the total with marks is printed beside the total of
the production kernel (timed with the same counter), and the difference is
the measuring overhead.  Cycles are time-stamp counter ticks (the nominal
clock: 2.1 GHz on the Xeon of 2026-11, 2.6 GHz on the EPYC before).  Steps:
map steps done (useful iterations of the pixels iterated).

A read of the counter does not wait for the instructions before it, so work
still in flight at a mark (a common step's square roots) is counted in the
next phase.  ``--fence`` puts an ``lfence`` before each read: each phase
then gets its own work, but every mark drains the pipeline, so the marked
total rises well above the production kernel's (about 40 % on the paper
grid); the shares are the thing to read then.  Where the two runs agree, the
phase really costs that.  For where the cycles go inside a phase, ``perf
record -e cpu-clock`` on a running scan and the kernel's disassembly (read
from ``/proc/<pid>/mem``) work on this virtual machine (no hardware
counters, but the timer samples); benchmarks/README.md has what that found.
"""

from __future__ import annotations

import argparse
import os
import re
import types
from pathlib import Path

import numba
import numpy as np
from llvmlite import ir
from numba.core import cgutils
from numba.core import types as nt
from numba.extending import intrinsic

import stairbounce.plane as P

NAMES = {1: "list + first loads", 2: "common step, full lanes", 3: "common step, tail",
         4: "impacts 4-7", 5: "closed form (>= 8)", 6: "finish, store, reload"}


FENCE = False  # set by --fence before anything using the timer is compiled


@intrinsic
def _rdtsc(typingctx):
    def codegen(context, builder, signature, args):
        if FENCE:
            fence = cgutils.get_or_insert_function(builder.module, ir.FunctionType(ir.VoidType(), []),
                                                   "llvm.x86.sse2.lfence")
            builder.call(fence, [])
        fn = cgutils.get_or_insert_function(builder.module, ir.FunctionType(ir.IntType(64), []),
                                            "llvm.readcyclecounter")
        return builder.call(fn, [])

    return nt.int64(), codegen


@numba.njit(inline="always")
def _lap(halt, idx, t):
    now = _rdtsc()
    halt[idx] += now - t
    return now


def phase_build():
    """``stairbounce.plane`` compiled again with the phase marks turned into timer reads."""
    src = Path(P.__file__).read_text()
    n = 0

    def mark(m):
        nonlocal n
        n += 1
        indent, what = m.group(1), m.group(2)
        if what.startswith("start"):
            return f"{indent}_t = _rdtsc()"
        return f"{indent}_t = _lap(halt, {what.split(':')[0]}, _t)"

    src = re.sub(r"^( *)# phase (.*)$", mark, src, flags=re.M)
    if n < 7:
        raise SystemExit(f"found {n} phase marks in plane.py, expected 7 or more")
    src = src.replace("cache=True", "cache=False")
    src = src.replace("from . import", "from stairbounce import").replace("from .", "from stairbounce.")
    mod = types.ModuleType("plane_phases")
    mod.__dict__.update(_rdtsc=_rdtsc, _lap=_lap)
    exec(compile(src, "plane_phases.py", "exec"), mod.__dict__)
    return mod


def run(mod, e, u, prune, counters):
    es, us = P.pixel_centres(*e), P.pixel_centres(*u)
    npix = es.size * us.size
    outs = [np.empty(npix, dtype=dt) for dt, _ in P._FIELDS.values()]
    chunk, units = mod._chunking(npix, 1)
    mod._scan_fast(es, us, True, 1000, 1.0, 0.0, prune, units, chunk, *outs, counters)
    return outs


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeat", type=int, default=15)
    p.add_argument("--fence", action="store_true", help="an lfence before each read of the counter (see above)")
    a = p.parse_args(argv)
    global FENCE
    FENCE = a.fence
    numba.set_num_threads(1)
    mod = phase_build()
    cases = [("paper grid 500 x 350, pruned", (0.0, 1.0, 500), (0.0, 1.5, 350), True),
             ("Fig. 5e window 768 x 768", (0.04, 0.065, 768), (0.92, 0.945, 768), True)]
    print(f"load average {os.getloadavg()[0]:.1f}; one thread; cycles = time-stamp counter ticks; "
          f"marks {'fenced' if FENCE else 'not fenced'}")
    for name, e, u, prune in cases:
        ds = P.scan(e, u, 1000, prune=prune)
        per = np.where(ds.status.values == 0, ds.period.values, 1000)
        E, U = np.meshgrid(ds.e.values, ds.u.values)
        steps = int(per[~P.prunable(E, U)].sum()) if prune else int(per.sum())
        best, best_plain = None, None
        for _ in range(a.repeat):
            c = np.zeros(16, np.int64)
            outs = run(mod, e, u, prune, c)
            # preemption on a shared machine only adds: the least per phase
            best = c.copy() if best is None else np.minimum(best, c)
            t0 = _rdtsc_py()
            run(P, e, u, prune, np.zeros(1, np.int64))
            plain = _rdtsc_py() - t0
            best_plain = plain if best_plain is None else min(best_plain, plain)
        for k, o in zip(P._FIELDS, outs):
            assert np.array_equal(o.reshape(ds[k].shape), ds[k].values), k
        marked = best[1:7].sum()
        print(f"\n{name}: {steps / 1e6:.2f} M steps done; production kernel {best_plain / steps:.2f} "
              f"cycles/step (wall, load {os.getloadavg()[0]:.1f}); with marks {marked / steps:.2f} (best of {a.repeat})")
        for i in range(1, 7):
            print(f"  {i}. {NAMES[i]:26s} {best[i] / steps:7.2f} cycles/step  {100 * best[i] / marked:5.1f} %")


@numba.njit
def _rdtsc_py():
    """The counter the marks read, read from Python."""
    return _rdtsc()


if __name__ == "__main__":
    main()
