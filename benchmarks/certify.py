"""Certified atlases (issue 36): throughput and proven fractions, against baselines in the same process.

    python benchmarks/certify.py [--windows fig7,fig5e,fig6,paper] [--depths 10,14] [--repeat 1]
                                 [--baselines reference,order,mean-value,threads,naive]

For each window and depth (max_iter 1000):

* ``sb.certify`` (the default form, "corners") with every thread (numba's
  default), its wall and CPU time (``getrusage``, all threads) and boxes per
  second (boxes evaluated, every level, per second of wall time), against, in
  the same process (``--baselines``): the mean-value form (the previous
  default: time, proven area, words), the same call with one thread (the ratio
  is the parallel speed-up; the boxes must be identical) and the naive
  interval form; and the reference, the same atlas with the float map's "nonsliding"
  check taken box by box in the level kernel (the algorithm before the shared check:
  the boxes must be identical);
* ``order`` (a baseline): the same call with the quadtree's children made in the
  order before (four runs a level, so the table is sorted by a full argsort and the
  shared corners' cache by ``np.unique``) and the kept itineraries copied by numpy's
  fancy indexing, as before (the boxes must be identical);
* the proven fractions by status, the undecided area by reason, the number of
  proven words;
* "the sliding area" and the share of it proven.  The sliding area is the
  proven-word area plus, for every undecided box, its area times the share of
  the pixels of a ``sb.scan`` of the window at 2^depth x 2^depth (pixel centres,
  max_iter 1000) inside it whose orbit of (1, 0) slides within max_iter (status
  0).  The boxes of the last level are exactly those pixels.  A box proven
  ``no_sliding`` or ``no_slide_within`` holds no sliding pixel (checked).  Past
  depth 12 (the scan would not fit in memory) the share is that of a grid of
  at most 4 x 4 points inside each undecided box (its centre for a box of the
  last level: its pixel).

Timings are the best of ``--repeat`` runs after a warm-up at depth 8 in every form.
The machine is shared: ``uptime`` is printed before and after.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import resource
import time

import numba
import numpy as np

import stairbounce as sb
from stairbounce.structure import _kernel as K

C = importlib.import_module("stairbounce.structure.certify")

WINDOWS = {
    "fig7": ((0.155, 0.2138), (0.6, 0.658)),
    "fig5e": ((0.04, 0.065), (0.92, 0.945)),
    "fig6": ((0.0, 0.333), (0.4, 0.733)),
    "paper": ((0.0, 1.0), (0.0, 1.5)),
}


def _uptime():
    with open("/proc/loadavg") as f:
        return f.read().split()[:3]


def _cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


@contextlib.contextmanager
def _previous_order():
    """The Python steps of the table as they were before the quadtree kept the atlas's
    order (the baseline ``order``): children in four runs, ``np.unique`` and a quicksort
    argsort, the kept itineraries copied by fancy indexing."""
    saved = K._children, K._kept_itineraries, C._unique_runs, C._box_table

    def children(ii, jj, out_i, out_j):
        i2, j2 = 2 * ii, 2 * jj
        out_i[:] = np.concatenate([i2, i2 + 1, i2, i2 + 1])
        out_j[:] = np.concatenate([j2, j2, j2 + 1, j2 + 1])

    def kept_itineraries(itinerary, offsets, kept, row, halt):
        short = row >= 0
        lengths = (offsets[1:] - offsets[:-1])[short]
        ranks = np.arange(int(lengths.sum())) - np.repeat(np.cumsum(lengths) - lengths, lengths)
        rows = kept[row[short]]
        itinerary[np.repeat(offsets[:-1][short], lengths) + ranks] = \
            rows[np.arange(kept.shape[1])[None, :] < lengths[:, None]]

    def unique(keys):
        new, inverse = np.unique(keys, return_inverse=True)
        return new, inverse.ravel()

    def box_table(parts):
        from stairbounce.structure._store_read import row_key

        cols = [np.concatenate([p[k] for p in parts]) for k in range(8)]
        order = np.argsort(row_key(*cols[:3]))
        st = cols[3]
        keep = ((st == K.WORD) | (st == K.NO_SLIDE_WITHIN)) & (cols[6] <= C._KEPT)
        row = np.full(st.size, -1, np.int64)
        row[keep] = np.arange(int(keep.sum()))
        return [c[order] for c in cols[:7]], cols[7], row[order]

    K._children, K._kept_itineraries, C._unique_runs, C._box_table = children, kept_itineraries, unique, box_table
    try:
        yield
    finally:
        K._children, K._kept_itineraries, C._unique_runs, C._box_table = saved


def _run(e, u, depth, threads=None, form="corners", repeat=1, reference=False):
    evaluated = []
    best = None
    old = numba.get_num_threads()
    try:
        if threads:
            numba.set_num_threads(threads)
        for _ in range(repeat):
            c = _cpu()
            t = time.perf_counter()
            if reference:  # the "nonsliding" check box by box in the level kernel (the algorithm before)
                a = C._certify(e, u, depth, 1000, None, 1, form, reference=True)
            else:
                a = sb.certify(e=e, u=u, depth=depth, form=form)
            dt = time.perf_counter() - t
            if best is None or dt < best[0]:
                best = (dt, a, _cpu() - c)
    finally:
        numba.set_num_threads(old)
    dt, a, cpu = best
    a.cpu_seconds = cpu
    # boxes evaluated: the final boxes plus every split parent (a quarter of the children)
    lv = a.boxes["level"].values.astype(np.int64)
    start = int(lv.min()) if lv.size else 0
    n_final = lv.size
    n_eval = n_final + (n_final - (1 << start) ** 2) // 3
    evaluated.append(n_eval)
    return dt, a, n_eval


def _sampled_shares(a, depth, max_iter):
    """Past depth 12 (a 2^depth scan would not fit): the share of sliding points among the
    centres of a g x g grid of sub-boxes of each undecided box (g = min(2^(depth - level), 4);
    a box of the last level is its centre, its pixel)."""
    b = a.boxes
    st = b["status"].values
    und = np.flatnonzero(st == K.UNDECIDED)
    lv = b["level"].values.astype(np.int64)[und]
    g = np.minimum(np.left_shift(1, depth - lv), 4)
    e0, e1, u0, u1 = (b[k].values for k in ("e0", "e1", "u0", "u1"))
    share = np.zeros(st.size)
    for gk in np.unique(g):
        sel = und[g == gk]
        t = (np.arange(gk) + 0.5) / gk
        E = e0[sel, None] + (e1[sel] - e0[sel])[:, None] * t[None, :]
        U = u0[sel, None] + (u1[sel] - u0[sel])[:, None] * t[None, :]
        EE = np.broadcast_to(E[:, None, :], (sel.size, gk, gk)).ravel()
        UU = np.broadcast_to(U[:, :, None], (sel.size, gk, gk)).ravel()
        ok = (UU > 0) & (EE < 1)
        slid = np.zeros(EE.size)
        slid[ok] = sb.scan_points(EE[ok], UU[ok], max_iter=max_iter)["status"].values == 0
        share[sel] = slid.reshape(sel.size, gk * gk).mean(axis=1)
    return share


def sliding_area(a, depth, max_iter=1000):
    """The proven-word area plus the scan-sliding share of every undecided box (fractions of the window)."""
    if depth > 12:
        share = _sampled_shares(a, depth, max_iter)
        b = a.boxes
        (e0, e1), (u0, u1) = a.window
        area = (b["e1"].values - b["e0"].values) * (b["u1"].values - b["u0"].values) / ((e1 - e0) * (u1 - u0))
        st = b["status"].values
        word = float(area[st == K.WORD].sum())
        sliding = word + float((area * share)[st == K.UNDECIDED].sum())
        return word, sliding, -1, -1, float("nan")
    (e0, e1), (u0, u1) = a.window
    n = 1 << depth
    ds = sb.scan(e=(e0, e1, n), u=(u0, u1, n), max_iter=max_iter)
    slid = (ds["status"].values == 0).astype(np.int64)  # [u, e]
    sat = np.zeros((n + 1, n + 1), np.int64)
    sat[1:, 1:] = slid.cumsum(0).cumsum(1)
    b = a.boxes
    lv = b["level"].values.astype(np.int64)
    f = np.left_shift(1, depth - lv)
    i0, j0 = b["i"].values * f, b["j"].values * f
    i1, j1 = i0 + f, j0 + f
    count = sat[j1, i1] - sat[j0, i1] - sat[j1, i0] + sat[j0, i0]
    share = count / (f * f)
    area = (b["e1"].values - b["e0"].values) * (b["u1"].values - b["u0"].values) / ((e1 - e0) * (u1 - u0))
    st = b["status"].values
    word = float(area[st == K.WORD].sum())
    und = st == K.UNDECIDED
    sliding = word + float((area * share)[und].sum())
    bad = int(count[(st == K.NO_SLIDING) | (st == K.NO_SLIDE_WITHIN)].sum())
    # the proven word boxes' pixels that the scan calls non-sliding (rounding at a border, or none)
    word_not = int((f * f - count)[st == K.WORD].sum())
    return word, sliding, bad, word_not, float(slid.mean())


def _superset(base, corners):
    """Print whether every point proven by ``base`` is proven alike by ``corners`` (box by box:
    each proven box of ``base`` lies in boxes of ``corners`` of the same status and word)."""
    b, c = base.boxes, corners.boxes
    lb, lc = b["level"].values.astype(np.int64), c["level"].values.astype(np.int64)
    deep = int(max(lb.max(), lc.max()))
    key_c = {}
    for k in range(c.sizes["box"]):
        key_c[(int(lc[k]), int(c["i"].values[k]), int(c["j"].values[k]))] = k
    sb_, sc = b["status"].values, c["status"].values
    wb, wc = b["word"].values, c["word"].values
    bad = 0
    for k in np.flatnonzero(sb_ != K.UNDECIDED):
        L, i, j = int(lb[k]), int(b["i"].values[k]), int(b["j"].values[k])
        # the corners box holding it: the same box or an ancestor (a proven box stops)
        for up in range(L, -1, -1):
            m = key_c.get((up, i >> (L - up), j >> (L - up)))
            if m is not None:
                break
        if m is None or sc[m] != sb_[k] or wc[m] != wb[k]:
            bad += 1
    print(f"  every box proven by the mean-value form is proven alike by corners: {bad == 0} "
          f"({bad} exceptions; depth {deep})")


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--windows", default="fig7")
    p.add_argument("--depths", default="10")
    p.add_argument("--repeat", type=int, default=1)
    p.add_argument("--baselines", default="mean-value,threads,naive",
                   help="comma-separated: reference, order, mean-value, threads, naive (or none)")
    args = p.parse_args()
    print(f"numba threads {numba.get_num_threads()}, cpus {os.cpu_count()}, load before {_uptime()}")
    for form in ("corners", "mean-value", "naive"):  # compile / load every kernel (depth 8 reaches them all)
        sb.certify(e=(0.155, 0.2138), u=(0.6, 0.658), depth=8, form=form)
    baselines = [b for b in args.baselines.split(",") if b and b != "none"]
    for name in args.windows.split(","):
        e, u = WINDOWS[name]
        for depth in map(int, args.depths.split(",")):
            dt, a, n_eval = _run(e, u, depth, repeat=args.repeat)
            f = a.fraction()
            r = a.fraction("reason")
            words = a.words()
            w, sliding, bad, word_not, scan_share = sliding_area(a, depth)
            print(f"\n{name} e={e} u={u} depth {depth} (corners): {dt:.2f} s wall, {a.cpu_seconds:.2f} s CPU, "
                  f"{n_eval} boxes evaluated, "
                  f"{n_eval / dt:,.0f} boxes/s, {a.boxes.sizes['box']} final boxes")
            print("  status  " + ", ".join(f"{k} {100 * v:.2f}%" for k, v in f.items()))
            print("  undecided by reason  " + ", ".join(f"{k} {100 * v:.2f}%" for k, v in r.items() if v))
            print(f"  proven words {len(words)}; by period {words.attrs['by_period']}")
            print(f"  sliding area {100 * sliding:.2f}% of the window (scan: {100 * scan_share:.2f}% of pixels); "
                  f"proven {100 * w / sliding:.1f}% of it; scan pixels sliding inside proven non-sliding "
                  f"boxes: {bad}; scan pixels not sliding inside proven word boxes: {word_not}")
            print(f"  peak RSS of the process so far {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20:.2f} GiB")
            if "reference" in baselines:
                dtr, ar, _ = _run(e, u, depth, reference=True)
                same = ar.boxes.drop_attrs().identical(a.boxes.drop_attrs())
                print(f"  reference (nonsliding check box by box): {dtr:.2f} s wall, {ar.cpu_seconds:.2f} s CPU; "
                      f"x{dtr / dt:.2f} in wall, x{ar.cpu_seconds / a.cpu_seconds:.2f} in CPU; same boxes: {same}")
                del ar
            if "order" in baselines:
                with _previous_order():
                    dto, ao, _ = _run(e, u, depth, repeat=args.repeat)
                same = ao.boxes.drop_attrs().identical(a.boxes.drop_attrs())
                print(f"  order before (children in four runs, the table sorted): {dto:.2f} s wall, "
                      f"{ao.cpu_seconds:.2f} s CPU; x{dto / dt:.2f} in wall; same boxes: {same}")
                del ao
            if "threads" in baselines:
                dt1, a1, _ = _run(e, u, depth, threads=1)
                same = a1.boxes.drop_attrs().identical(a.boxes.drop_attrs())
                print(f"  one thread: {dt1:.2f} s ({n_eval / dt1:,.0f} boxes/s): x{dt1 / dt:.2f} for "
                      f"{numba.get_num_threads()} threads; same boxes: {same}")
            for form in ("mean-value", "naive"):
                if form not in baselines:
                    continue
                dtn, an, n_n = _run(e, u, depth, form=form)
                fn = an.fraction()
                wn, _, _, _, _ = sliding_area(an, depth)
                print(f"  {form} form: {dtn:.2f} s wall, {an.cpu_seconds:.2f} s CPU ({n_n} boxes, "
                      f"{n_n / dtn:,.0f} boxes/s; corners x{dtn / dt:.2f} faster in wall, "
                      f"x{an.cpu_seconds / a.cpu_seconds:.2f} in CPU); word {100 * fn['word']:.2f}%, "
                      f"undecided {100 * fn['undecided']:.2f}%, {len(an.words())} words; proven "
                      f"{100 * wn / sliding:.1f}% of the sliding area (corners: {100 * w / sliding:.1f}%)")
                if form == "mean-value":
                    _superset(an, a)
    print(f"\nload after {_uptime()}")


if __name__ == "__main__":
    main()
