"""How much of the Fig. 4 plane's non-sliding area below the Corollary 2.1 curve
trapping regions prove (issue 36, item 7).

Certifies the paper's plane (e in [0, 1], u in [0, 1.5]) at a depth with and
without ``trap=True`` (the same process), and prints: the time of each and of
the trapping pass, the boxes tried and proven, the area proven ``no_sliding``
by trapping, the area left undecided "nonsliding" (numerical), the share of
the non-sliding area below the curve that trapping proves (trapping /
(trapping + nonsliding)), the independent checker's re-check of the regions
(``certify._recheck_regions``, timed again on the result), and ``sb.verify``'s
verdict and time on the trapped atlas.  Boxes split below the depth
(``trap_split`` levels, issue 44 item 5) are counted by level.  Usage:
``python benchmarks/trapping.py [depth ...]`` (default 8).

``python benchmarks/trapping.py --rounds N depth`` measures the issue's ratio
only (issue 44 item 5: the trapping pass at most twice the atlas): N rounds in
one process, each the plain atlas, then ``trap_atlas`` on its table, and prints
every round's pass / atlas with their median and the ratio of the fastest of
each (the first round compiles nothing: one warm-up round runs before).
``--rounds N --fine depth`` runs the pass with ``fine=True`` too in every round
(the two finer grids, ``trap="fine"``) and prints both passes against the atlas,
with the trapped share of each.
"""

import os
import sys
import time

import numpy as np

import stairbounce as sb


def _areas(ds):
    """The shares of the window (floats, numerical) trapped (``no_sliding`` by a region) and
    left undecided ``nonsliding``."""
    (e0, e1), (u0, u1) = ds.attrs["e_range"], ds.attrs["u_range"]
    area = (ds["e1"].values - ds["e0"].values) * (ds["u1"].values - ds["u0"].values) / ((e1 - e0) * (u1 - u0))
    reason = ds["reason"].values
    return float(area[reason == "trapping"].sum()), float(area[reason == "nonsliding"].sum())


def main(depths):
    print(f"load {os.getloadavg()}")
    for depth in depths:
        t0 = time.perf_counter()
        plain = sb.certify(e=(0.0, 1.0), u=(0.0, 1.5), depth=depth, max_iter=1000)
        t1 = time.perf_counter()
        trapped = sb.certify(e=(0.0, 1.0), u=(0.0, 1.5), depth=depth, max_iter=1000, trap=True)
        t2 = time.perf_counter()
        ds = trapped.boxes
        reason = ds["reason"].values
        by_trap, left = _areas(ds)
        t3 = time.perf_counter()
        verdict = sb.verify(trapped)
        t4 = time.perf_counter()
        from stairbounce.structure.certify import _recheck_regions

        _recheck_regions(ds)
        t5 = time.perf_counter()
        again = sb.certify(e=(0.0, 1.0), u=(0.0, 1.5), depth=depth, max_iter=1000)
        t6 = time.perf_counter()
        level = ds["level"].values
        below = level > depth
        print(f"depth {depth}: certify {t1 - t0:.1f} s, with trap {t2 - t1:.1f} s "
              f"(trapping pass {ds.attrs['trap_seconds']:.1f} s, {ds.attrs['trap_tried']} boxes tried, "
              f"{int((reason == 'trapping').sum())} proven; {int(below.sum())} boxes below the depth, "
              f"{int((below & (reason == 'trapping')).sum())} of them trapped; trap_split "
              f"{ds.attrs.get('trap_split', 0)}); certify again {t6 - t5:.1f} s")
        print(f"  the pass / the atlas: {ds.attrs['trap_seconds'] / min(t1 - t0, t6 - t5):.2f}; re-check of "
              f"{int(ds['trap_box'].size)} regions {t5 - t4:.2f} s "
              f"({1e3 * (t5 - t4) / max(int(ds['trap_box'].size), 1):.3f} ms a region)")
        print(f"  share of the plane: trapped (no_sliding by a region) {100 * by_trap:.3f} %, "
              f"nonsliding left undecided {100 * left:.3f} %, proven share of the non-sliding area below "
              f"the curve {_share(ds):.1f} %")
        print(f"  fractions {trapped.fraction()}; failures: {ds.attrs['trap_failures']}")
        print(f"  sb.verify: {verdict.message} in {t4 - t3:.1f} s; the load now {os.getloadavg()}")
        # the pass's tries in one thread (the baseline) and in numba's thread count, the same
        # boxes (the whole boxes labelled nonsliding, not the split), the same process
        import numba

        from stairbounce.structure import trapping as T

        pdb = plain.boxes
        pick = pdb["reason"].values == "nonsliding"
        edges = [pdb[k].values[pick] for k in ("e0", "e1", "u0", "u1")]
        times = {}
        for n in (1, numba.get_num_threads(), 1, numba.get_num_threads()):
            ts = time.perf_counter()
            out = T._try_all(*edges, 1000, threads=n)
            times.setdefault(n, []).append(time.perf_counter() - ts)
        one, many = min(times[1]), min(times[numba.get_num_threads()])
        print(f"  the tries on the {int(pick.sum())} whole nonsliding boxes ({int((out[0] == 0).sum())} proven): "
              f"1 thread {one:.2f} s, {numba.get_num_threads()} threads {many:.2f} s, x{one / many:.2f} "
              f"(best of 2 each); the load now {os.getloadavg()}")
        np.seterr(all="ignore")


def _share(ds):
    """The trapped share of the non-sliding area below the curve (trapping / (trapping + nonsliding))."""
    by_trap, left = _areas(ds)
    return 100 * by_trap / max(by_trap + left, 1e-300)


def rounds(depth, n, fine=False):
    from stairbounce.structure.trapping import trap_atlas

    win = dict(e=(0.0, 1.0), u=(0.0, 1.5), depth=depth, max_iter=1000)
    warm = sb.certify(**win).boxes  # warm-up: every kernel compiled or loaded
    trap_atlas(warm)
    if fine:
        trap_atlas(warm, fine=True)
    print(f"load {os.getloadavg()}")
    atlas, trap, trap_fine = [], [], []
    for r in range(n):
        t0 = time.perf_counter()
        plain = sb.certify(**win)
        t1 = time.perf_counter()
        ds = trap_atlas(plain.boxes)
        t2 = time.perf_counter()
        atlas.append(t1 - t0)
        trap.append(t2 - t1)
        line = (f"round {r + 1}: the atlas {t1 - t0:.2f} s, the trapping pass {t2 - t1:.2f} s "
                f"({ds.attrs['trap_tried']} boxes tried, share {_share(ds):.2f} %), pass / atlas "
                f"{(t2 - t1) / (t1 - t0):.2f}")
        if fine:
            t3 = time.perf_counter()
            dsf = trap_atlas(plain.boxes, fine=True)
            t4 = time.perf_counter()
            trap_fine.append(t4 - t3)
            line += (f"; fine pass {t4 - t3:.2f} s (share {_share(dsf):.2f} %), fine / atlas "
                     f"{(t4 - t3) / (t1 - t0):.2f}")
            # the independent checker on each pass's regions (certify's re-check)
            from stairbounce.structure.certify import _recheck_regions

            t5 = time.perf_counter()
            _recheck_regions(ds)
            t6 = time.perf_counter()
            _recheck_regions(dsf)
            t7 = time.perf_counter()
            line += (f"; re-check {t6 - t5:.2f} s ({int(ds['trap_box'].size)} regions, "
                     f"{int(ds['trap_cells'].size):,} cells), fine {t7 - t6:.2f} s ({int(dsf['trap_box'].size)} "
                     f"regions, {int(dsf['trap_cells'].size):,} cells)")
        print(line)
    ratios = np.array(trap) / np.array(atlas)
    print(f"depth {depth}, {n} rounds: pass / atlas median {np.median(ratios):.2f}, largest {ratios.max():.2f}; "
          f"fastest pass / fastest atlas {min(trap) / min(atlas):.2f}; the load now {os.getloadavg()}")
    if fine:
        rf = np.array(trap_fine) / np.array(atlas)
        print(f"  fine pass / atlas median {np.median(rf):.2f}, largest {rf.max():.2f}; fine pass / pass median "
              f"{np.median(np.array(trap_fine) / np.array(trap)):.2f}")


if __name__ == "__main__":
    args = sys.argv[1:]
    if args[:1] == ["--rounds"]:
        fine = "--fine" in args
        rest = [a for a in args[2:] if a != "--fine"]
        rounds(int(rest[0]) if rest else 12, int(args[1]), fine)
    else:
        main([int(a) for a in args] or [8])
