"""Witness points: proven points inside the undecided boxes of an atlas, for the lower
box counts of the paper's perimeter (issue 44, item 4).

A closed cell of side window/2^k meets the border of the region sliding within
``max_iter`` as soon as it holds one point where the orbit of (1, 0) slides within
``max_iter`` steps and one where it does not: a segment between the two, inside the
cell, crosses the border.  :meth:`CertifiedAtlas.border_box_counts` counted such cells
from proven *boxes* only.  Near the border most boxes are undecided, so at fine scales
almost no cell held proven boxes of both classes (Fig. 7 at depth 12: lower count 0
from k = 11).  A point is far easier to prove than a box: along a frozen itinerary
the corners form's two evaluations coincide, the state's rounding errors add up step
by step (``v' = v - T + B_k s``, ``s'^2 = 2 + e^(2k) s^2`` do not amplify them), and a
decision fails only where its margin at that very point is within rounding of 0.

**Candidates** (numerical).  Each undecided box is cut into its cells of the deepest
counted level ``depth`` (a box finer than that, from the trapping pass, is one region
in its level-``depth`` cell); in each, ``g x g`` points strictly inside (``e = E0 +
(E1 - E0) (a + 1/2) / g``, kept only when ``E0 < e < E1`` as floats, likewise u; ``g``
is :data:`GRID` = 3 in a box of the counted depth or finer, :data:`GRID_COARSE` = 2 in
the cells of a coarser one, the ``nonsliding`` boxes below the Corollary 2.1 curve,
whose cells seldom hold both classes: Fig. 7 at depth 10, 3 there would add 2 % to the
lower count at k = 10 for 1.5 times the time) are run by the float map
(``stairbounce.model``), and the first of each class (sliding within ``max_iter`` or
not) is a candidate.

**Proof.**  A candidate is a witness when the certifier proves it as a degenerate box
(``_kernel._certify_box``, corners form: ``word`` for a sliding one, ``no_slide_within``
or ``no_sliding`` for the other) and the independent checker (``verify.verify_codes``)
re-verifies that certificate; a candidate that fails either is dropped.

**Which candidates are proven.**  Only as many as the counts need: from the finest
scale to the coarsest, a cell of scale k that may hold both classes (proven boxes,
witnesses found so far, untried candidates) but lacks a proven one of a class has its
candidates of that class tried, in a fixed order, until one is proven or none is left.
So a cell ends up holding a proven point of class c exactly when one of its candidates
of class c is provable (or a proven box of class c lies in it): a property of the cell,
whatever the order or the grouping.  That is what lets :class:`border_counts.StreamedCounts`
find the witnesses tile by tile and get the in-memory counts: a cell of a scale
coarser than the store's tile level spans tiles, so there each tile proves one
candidate of each class its part holds (``exact_from``), and the union is the same.

What a witness proves: at that point, the orbit of (1, 0) slides within ``max_iter``
steps (with the word of its itinerary) or does not.  It proves nothing about the rest
of its cell.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from .._interrupt import halted
from ..model import _constants, _slide_or_steps
from . import _kernel as K

# the points a side of a level-depth cell of an undecided box of that level or finer
GRID = 3
# the points a side in the cells of an undecided box coarser than the counted depth (the
# "nonsliding" boxes below the Corollary 2.1 curve, whose cells seldom hold both classes)
GRID_COARSE = 2
# the most level-depth cells of undecided boxes looked at in one call (about 40 bytes each)
MAX_CELLS = 1 << 26


@njit(cache=True, inline="always")
def _inside(lo, hi, a, g):
    """The ``a``-th of ``g`` points strictly inside ``[lo, hi]`` (nan when rounding puts it
    on an edge)."""
    x = lo + (hi - lo) * ((a + 0.5) / g)
    if lo < x < hi:
        return x
    return np.nan


@njit(cache=True, parallel=True, nogil=True)
def _sample(win, depth, level, bi, bj, start, g, g_coarse, max_iter, rci, rcj, ce, cu, cn, halt):
    """The candidates of the undecided boxes ``(level[b], bi[b], bj[b])``: box ``b``'s
    regions are ``start[b] .. start[b + 1] - 1`` (its level-``depth`` cells in row order
    of e, or the box itself when finer); region ``r``'s cell is ``(rci[r], rcj[r])`` and
    its first inner point of class ``c`` (0: the float map does not slide within
    ``max_iter``, 1: it does) is ``(ce[r, c], cu[r, c])`` when ``cn[r, c]`` is 1."""
    nb = level.shape[0]
    ew = win[1] - win[0]
    uw = win[3] - win[2]
    for c in prange((nb + K._CHUNK - 1) // K._CHUNK):
        if halted(halt):
            continue
        for b in range(c * K._CHUNK, min(nb, (c + 1) * K._CHUNK)):
            L = np.int64(level[b])
            if L > depth:
                sh = L - depth
                f = 1
            else:
                sh = 0
                f = np.int64(1) << (depth - L)
            gb = g if L >= depth else g_coarse
            for r in range(start[b], start[b + 1]):
                q = r - start[b]
                if L > depth:
                    lv, ci, cj = L, np.int64(bi[b]), np.int64(bj[b])
                    rci[r], rcj[r] = ci >> sh, cj >> sh
                else:
                    lv, ci, cj = depth, np.int64(bi[b]) * f + q // f, np.int64(bj[b]) * f + q % f
                    rci[r], rcj[r] = ci, cj
                E0 = K._edge(win[0], ew, win[1], ci, lv)
                E1 = K._edge(win[0], ew, win[1], ci + 1, lv)
                U0 = K._edge(win[2], uw, win[3], cj, lv)
                U1 = K._edge(win[2], uw, win[3], cj + 1, lv)
                cn[r, 0] = 0
                cn[r, 1] = 0
                for a in range(gb):
                    if cn[r, 0] + cn[r, 1] == 2:
                        break
                    e = _inside(E0, E1, a, gb)
                    if not (e > 0.0 and e < 1.0):  # also nan
                        continue
                    for p in range(gb):
                        u = _inside(U0, U1, p, gb)
                        if not u >= K._U_MIN:
                            continue
                        T, ratio = _constants(e, u)
                        cls = 1 if _slide_or_steps(1.0, 0.0, e, T, ratio, max_iter)[0] > 0 else 0
                        if cn[r, cls] == 0:
                            ce[r, cls] = e
                            cu[r, cls] = u
                            cn[r, cls] = 1
                            if cn[r, 0] + cn[r, 1] == 2:
                                break


@njit(cache=True, parallel=True, nogil=True)
def _certify_points(es, us, max_iter, cap, st, ni, pit, halt):
    """The certifier on the points ``(es[p], us[p])`` as degenerate boxes (corners
    form): status ``st[p]``, itinerary ``pit[p, :ni[p]]``."""
    n = es.shape[0]
    dec = np.empty(1, np.int64)
    marg = np.empty((1, 2))
    for c in prange((n + K._CHUNK - 1) // K._CHUNK):
        if halted(halt):
            continue
        itin = np.empty(max_iter, np.int64)
        for p in range(c * K._CHUNK, min(n, (c + 1) * K._CHUNK)):
            s, rs, sp, m, nd = K._certify_box(es[p], es[p], us[p], us[p], max_iter, cap, K.CORNERS, itin, False,
                                              dec, marg)
            st[p] = s
            ni[p] = m
            for k in range(m):
                pit[p, k] = itin[k]


@njit(cache=True)
def _morton(ci, cj, depth):
    """The Z-order codes of the level-``depth`` cells ``(ci, cj)`` (the bits of ci, cj
    interleaved): the cell of scale k holding one is its code ``>> 2 (depth - k)``, so
    the cells of every scale are runs of codes sorted once."""
    out = np.empty(ci.shape[0], np.int64)
    for p in range(ci.shape[0]):
        a, b = np.int64(ci[p]), np.int64(cj[p])
        m = np.int64(0)
        for t in range(depth):
            m |= ((a >> t) & 1) << (2 * t + 1)
            m |= ((b >> t) & 1) << (2 * t)
        out[p] = m
    return out


def _check(es, us, st, max_iter, itin, offsets):
    """The independent checker's codes (``verify.verify_codes``) of the point
    certificates, in two threads (its loop releases Python's lock)."""
    from concurrent.futures import ThreadPoolExecutor

    from .verify import verify_codes

    n = es.size
    if n < 512:
        return verify_codes(es, es, us, us, st, max_iter, itin, offsets)[0]
    h = n // 2
    o = int(offsets[h])
    parts = ((es[:h], us[:h], st[:h], itin[:o], offsets[:h + 1]),
             (es[h:], us[h:], st[h:], itin[o:], offsets[h:] - o))
    with ThreadPoolExecutor(2) as pool:
        codes = list(pool.map(lambda p: verify_codes(p[0], p[0], p[1], p[1], p[2], max_iter, p[3], p[4])[0], parts))
    return np.concatenate(codes)


def prove_points(es, us, cls, max_iter):
    """prove_points(es, us, cls, max_iter) -> bool array: whether each point ``(es[p],
    us[p])`` is proven to be of class ``cls[p]`` (1: the orbit of (1, 0) slides within
    ``max_iter`` steps, 0: it does not): its certificate (the certifier on the point)
    says so and the independent checker re-verifies it.  In chunks (bounded memory;
    Ctrl-C between the compiled loops' slices)."""
    from .._interrupt import run_kernel

    es = np.ascontiguousarray(es, np.float64)
    us = np.ascontiguousarray(us, np.float64)
    cls = np.asarray(cls)
    ok = np.zeros(es.size, bool)
    step = max(64, (1 << 22) // int(max_iter))
    for lo in range(0, es.size, step):
        e, u, c = es[lo:lo + step], us[lo:lo + step], cls[lo:lo + step]
        m = e.size
        st, ni = np.empty(m, np.int64), np.empty(m, np.int64)
        pit = np.empty((m, int(max_iter)), np.int16)  # impact numbers <= IMPACT_CAP = 4096
        run_kernel(_certify_points, e, u, int(max_iter), K.IMPACT_CAP, st, ni, pit)
        claim = np.where(c == 1, st == K.WORD, (st == K.NO_SLIDE_WITHIN) | (st == K.NO_SLIDING))
        if not claim.any():
            continue
        idx = np.flatnonzero(claim)
        offsets = np.zeros(idx.size + 1, np.int64)
        np.cumsum(ni[idx], out=offsets[1:])
        itin = pit[idx][np.arange(int(max_iter))[None, :] < ni[idx][:, None]].astype(np.int64)
        ok[lo + idx] = _check(e[idx], u[idx], st[idx], max_iter, itin, offsets) == 0
    return ok


def candidates(window, depth, max_iter, level, ii, jj, grid=GRID, grid_coarse=GRID_COARSE):
    """candidates(window, depth, max_iter, level, ii, jj, grid=3, grid_coarse=2) -> (ci, cj, cls, e, u)

    The candidate points of the undecided boxes ``(level, ii, jj)`` (numerical: the
    float map's class; see the module's docstring): each with its level-``depth`` cell
    ``(ci, cj)`` and class (1: slides within ``max_iter``, 0: not)."""
    from .._interrupt import run_kernel

    (e_lo, e_hi), (u_lo, u_hi) = window
    win = np.array([e_lo, e_hi, u_lo, u_hi], np.float64)
    level = np.ascontiguousarray(level, np.int64)
    ii, jj = np.ascontiguousarray(ii, np.int64), np.ascontiguousarray(jj, np.int64)
    per = np.where(level >= depth, 1, np.left_shift(1, 2 * np.maximum(depth - level, 0)))
    start = np.zeros(level.size + 1, np.int64)
    np.cumsum(per, out=start[1:])
    nr = int(start[-1])
    if nr > MAX_CELLS:
        raise ValueError(f"witnesses: the undecided boxes cover {nr:,} cells of level {depth} (coarse undecided "
                         f"boxes far above the depth), more than the limit {MAX_CELLS:,} "
                         "(stairbounce.structure.witnesses.MAX_CELLS): count with witnesses=False")
    rci, rcj = np.empty(nr, np.int64), np.empty(nr, np.int64)
    ce, cu, cn = np.empty((nr, 2)), np.empty((nr, 2)), np.empty((nr, 2), np.int8)
    run_kernel(_sample, win, int(depth), level, ii, jj, start, int(grid), int(grid_coarse), int(max_iter), rci, rcj,
               ce, cu, cn)
    r, c = np.nonzero(cn)
    return rci[r], rcj[r], c.astype(np.int8), ce[r, c], cu[r, c]


def witness_rows(window, depth, max_iter, level, ii, jj, cls, exact_from=0, grid=GRID):
    """witness_rows(window, depth, max_iter, level, ii, jj, cls, exact_from=0, grid=3)
    -> (wi, wj, wcls, we, wu, tried)

    The witnesses the box counts need among the boxes ``(level, ii, jj)`` with classes
    ``cls`` (-1 undecided, 0 proven not sliding, 1 proven sliding): each its
    level-``depth`` cell ``(wi, wj)``, class and point ``(we, wu)``; ``tried``: the
    candidates certified.
    From scale ``exact_from`` on, every cell of the boxes is whole here (all its boxes
    given); coarser cells may hold boxes not given (a store's other tiles).  See the
    module's docstring."""
    level = np.asarray(level, np.int64)
    ii, jj = np.asarray(ii, np.int64), np.asarray(jj, np.int64)
    cls = np.asarray(cls)
    und = cls < 0
    ci, cj, cc, ce, cu = candidates(window, depth, max_iter, level[und], ii[und], jj[und], grid)
    z = np.zeros(0, np.int64)
    if ci.size == 0:
        return z, z.copy(), z.copy(), np.zeros(0), np.zeros(0), 0
    # the candidates and the proven boxes in Z order of their level-depth cells (a box
    # finer than depth by its cell; a coarser one by its first cell: it lies in the
    # scale-k cell of that code for every k <= its level)
    cm = _morton(ci, cj, int(depth))
    order = np.lexsort((cu, ce, cm))
    ci, cj, cc, ce, cu, cm = ci[order], cj[order], cc[order], ce[order], cu[order], cm[order]
    pv = ~und
    pl = level[pv]
    sh = np.maximum(pl - depth, 0)
    up = np.maximum(depth - pl, 0)
    bm = _morton((ii[pv] >> sh) << up, (jj[pv] >> sh) << up, int(depth))
    bc = cls[pv]
    state = np.zeros(ci.size, np.int8)  # 0 untried, 1 proven (a witness), 2 failed
    tried = 0
    for k in range(int(depth), -1, -1):
        s = 2 * (int(depth) - k)
        y = cm >> s
        have, may = [], []
        for c in (0, 1):
            h = np.union1d(bm[(bc == c) & (pl >= k)] >> s, y[(cc == c) & (state == 1)])
            have.append(h)
            may.append(np.union1d(h, y[(cc == c) & (state == 0)]))
        both = np.intersect1d(may[0], may[1], assume_unique=True)
        for c in (0, 1):
            if k >= exact_from:
                targets = np.setdiff1d(both, have[c], assume_unique=True)
            else:
                targets = np.setdiff1d(np.unique(y[(cc == c) & (state == 0)]), have[c], assume_unique=True)
            while targets.size:
                pend = np.flatnonzero((cc == c) & (state == 0))
                pend = pend[np.isin(y[pend], targets, assume_unique=False)]
                if pend.size == 0:
                    break
                first = pend[np.r_[True, y[pend][1:] != y[pend][:-1]]]  # the first of each cell (sorted)
                ok = prove_points(ce[first], cu[first], np.full(first.size, c), max_iter)
                tried += first.size
                state[first] = np.where(ok, 1, 2)
                targets = np.setdiff1d(targets, y[first[ok]], assume_unique=True)
    w = state == 1
    return ci[w], cj[w], cc[w].astype(np.int64), ce[w], cu[w], tried
