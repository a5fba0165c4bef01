"""The checker's step loops as they were before they were compiled (numpy,
vectorised over boxes only, a Python loop over steps and impact numbers): the
reference that tests/test_verify_fast.py compares structure/_check_kernel.py
with, verdict for verdict.  Kept here, not in the package (issue 43, item 3).

The interval helpers and the checks without arithmetic (``_structure``,
``_corollary``) are the package's own (unchanged); what is copied is what
the compiled kernel replaced: ``_coefficients``, ``_follow`` and the loops of
``verify_trapping.verify_region`` (whose argument checks, ``_region_inputs``,
are the package's).
"""

from __future__ import annotations

import numpy as np

from stairbounce.structure.verify import (_NOSLIDING_S, _add, _COR, _div_pos, _IMPACT, _mul_pos,
                                          _NOIMPACT, _out, _over_box, _point, _pow_point, _SLIDE, _sqrt,
                                          _sub, _corollary, _structure)
from stairbounce.structure.verify_trapping import _IMPACT_CAP, _region_inputs

_CHUNK = 1 << 15
_ENTRIES = 1 << 18


def _coefficients(e, k):
    """At the floats ``e`` (exact), enclosures of ``e^k``, ``A_k``, ``A_{k+1}``
    and ``B_k`` (see the module's docstring)."""
    one = np.ones((2, len(e)))
    ep = _point(e)
    one_p, one_m = _add(one, ep), _sub(one, ep)
    E = _pow_point(e, k)
    eE = _mul_pos(ep, E)
    A = _div_pos(_sub(one_p, 2.0 * E), one_m)  # 2 E exact: a power of two
    A1 = _div_pos(_sub(one_p, 2.0 * eE), one_m)
    omE = np.maximum(_sub(one, E), 0.0)  # 1 - e^k >= 0
    B = _div_pos(_mul_pos(one_p, omE), one_m)
    return E, A, A1, B


def verify_codes(e0, e1, u0, u1, status, max_iter, itinerary, offsets):
    """The previous ``verify.verify_codes`` on arrays already checked and converted
    (float64 boxes, int64 status, itinerary and offsets)."""
    code, step = _structure(e0, e1, u0, u1, status, max_iter, itinerary, offsets)
    nos = (code == 0) & (status == _NOSLIDING_S)
    code[nos & ~_corollary(e0, u0)] = _COR
    # the dynamics, along each itinerary; boxes sorted by itinerary length, so
    # that the boxes still running at step n are a prefix
    length = np.diff(offsets)
    run = np.flatnonzero((code == 0) & (length > 0))
    run = run[np.argsort(-length[run], kind="stable")]
    # in chunks of boxes of similar length, so that memory stays bounded
    for c in range(0, len(run), _CHUNK):
        part = run[c:c + _CHUNK]
        _follow(e0[part], e1[part], u0[part], u1[part], itinerary, offsets[part], length[part],
                code, step, part)
    return code, step


def _follow(e0, e1, u0, u1, itinerary, start, length, code, step, index):
    """Re-decide every step of the boxes (sorted by decreasing ``length``);
    writes the first failure of box ``index[i]`` into ``code`` and ``step``.

    The itinerary entries are laid out step-major (at step n the boxes still
    running are a prefix, so their entries are one contiguous slice); the
    coefficients of a block of steps are computed in one pass, then the loop
    over the block's steps only carries the state ``(v, s)``.
    """
    m = len(e0)
    counts = np.bincount(length, minlength=int(length[0]) + 1)
    still = m - np.cumsum(counts)[:-1]  # boxes with length > n, n = 0 .. max - 1
    edges = np.concatenate([[0], np.cumsum(still)])
    one = np.ones((2, m))
    two = 2.0 * one
    T = np.stack([_div_pos(one, _point(u1))[0], _div_pos(one, _point(u0))[1]])  # 1/u decreases
    # ratio = (1+e)/(1-e) over the box: its value at e0 (lower) and e1 (upper)
    R = _over_box(*(_div_pos(_add(one, _point(x)), _sub(one, _point(x))) for x in (e0, e1)))
    V = np.zeros((2, m))
    S = _sqrt(two)
    fail = np.zeros(m, dtype=np.int8)
    fstep = np.zeros(m, dtype=np.int64)
    nsteps = len(still)
    n0 = 0
    while n0 < nsteps:  # blocks of steps of at most _ENTRIES entries (or one step)
        n1 = int(np.searchsorted(edges, edges[n0] + _ENTRIES, side="right")) - 1
        n1 = min(max(n1, n0 + 1), nsteps)
        rank = np.concatenate([np.arange(still[j]) for j in range(n0, n1)])
        k = itinerary[start[rank] + np.repeat(np.arange(n0, n1), still[n0:n1])]
        kk = np.maximum(k, 0)
        # over [e0, e1] each coefficient lies between its values at e0 and e1
        E, A, A1, B = (_over_box(x, y) for x, y in zip(_coefficients(e0[rank], kk), _coefficients(e1[rank], kk)))
        A = np.maximum(A, 0.0)  # A_k >= 1 where k >= 1, its only use
        for n in range(n0, n1):
            a = int(still[n])
            at = slice(edges[n] - edges[n0], edges[n + 1] - edges[n0])
            kn = k[at]
            t, v, s = T[:, :a], V[:, :a], S[:, :a]
            tv = _sub(t, v)  # T - v
            slide = _sub(tv, _mul_pos(R[:, :a], s))  # (2.4)
            hit = _sub(tv, _mul_pos(A[:, at], s))  # T - t_k, t_k = v + A_k s
            miss = _sub(tv, _mul_pos(A1[:, at], s))  # T - t_{k+1}
            sliding = kn == -1
            ok_slide = np.where(sliding, slide[0] >= 0.0, slide[1] < 0.0)
            ok_hit = (kn < 1) | (hit[0] >= 0.0)
            ok_miss = sliding | (miss[1] < 0.0)
            bad = ~(ok_slide & ok_hit & ok_miss)
            if bad.any():
                new_fail = np.where(~ok_slide, _SLIDE, np.where(~ok_hit, _IMPACT, _NOIMPACT))
                first = (fail[:a] == 0) & bad
                fail[:a][first] = new_fail[first]
                fstep[:a][first] = n + 1
            # the next state: v' = v - T + B_k s, s' = sqrt(2 + (e^k s)^2)
            es = _mul_pos(E[:, at], s)
            V[:, :a] = _add(_sub(v, t), _mul_pos(B[:, at], s))
            S[:, :a] = _sqrt(_add(_mul_pos(es, es), two[:, :a]))
        n0 = n1
    failed = fail != 0
    code[index[failed]] = fail[failed]
    step[index[failed]] = fstep[failed]


def _covered(flags, ev, es, a0, a1, b0, b1):
    """Whether each rectangle ``[a0, a1] x [b0, b1]`` lies in the union of the flagged cells."""
    nv, ns = len(ev) - 1, len(es) - 1
    with np.errstate(invalid="ignore"):
        inside = (a0 >= ev[0]) & (a1 <= ev[-1]) & (b0 >= es[0]) & (b1 <= es[-1]) & (a0 <= a1) & (b0 <= b1)
    i0 = np.clip(np.searchsorted(ev, a0, "right") - 1, 0, nv - 1)
    i1 = np.clip(np.searchsorted(ev, a1, "left") - 1, 0, nv - 1)
    j0 = np.clip(np.searchsorted(es, b0, "right") - 1, 0, ns - 1)
    j1 = np.clip(np.searchsorted(es, b1, "left") - 1, 0, ns - 1)
    i1 = np.maximum(i1, i0)
    j1 = np.maximum(j1, j0)
    # flagged cells in the rectangle by a 2-D prefix sum
    P = np.zeros((ns + 1, nv + 1), np.int64)
    P[1:, 1:] = np.cumsum(np.cumsum(flags.reshape(ns, nv), axis=0), axis=1)
    count = P[j1 + 1, i1 + 1] - P[j0, i1 + 1] - P[j1 + 1, i0] + P[j0, i0]
    return inside & (count == (i1 - i0 + 1) * (j1 - j0 + 1))


def _entered(e0, e1, u0, u1, itinerary):
    """The enclosure ``(v0, v1, s0, s1)`` of the state after the itinerary."""
    one = np.ones((2, 1))
    T = np.stack([_div_pos(one, _point(np.array([u1])))[0], _div_pos(one, _point(np.array([u0])))[1]])
    V = np.zeros((2, 1))
    S = _sqrt(2.0 * one)
    k = np.asarray(itinerary, dtype=np.int64)
    if k.size:
        lo = _coefficients(np.full(k.size, e0), k)
        hi = _coefficients(np.full(k.size, e1), k)
        E = np.stack([lo[0][0], hi[0][1]])
        B = np.stack([lo[3][0], hi[3][1]])
        for n in range(k.size):
            es = _mul_pos(E[:, n:n + 1], S)
            V = _add(_sub(V, T), _mul_pos(np.maximum(B[:, n:n + 1], 0.0), S))
            S = _sqrt(_add(_mul_pos(es, es), 2.0 * one))
    return V[0, 0], V[1, 0], S[0, 0], S[1, 0]


def verify_region(e0, e1, u0, u1, max_iter, itinerary, grid, cells):
    """The previous ``verify_trapping.verify_region`` (its verdict names)."""
    args = _region_inputs(e0, e1, u0, u1, max_iter, itinerary, grid, cells)
    if args is None:
        return "box"
    e0, e1, u0, u1, itinerary, nv, ns, cells, ev, es = args
    flags = np.zeros(nv * ns, np.int64)  # this reference's coverage test is a prefix sum over the grid
    flags[cells] = 1
    code, _ = verify_codes(np.array([e0]), np.array([e1]), np.array([u0]), np.array([u1]), np.array([3]), max_iter,
                           itinerary, np.array([0, len(itinerary)]))
    if code[0] != 0:
        return "entry"
    a0, a1, b0, b1 = _entered(e0, e1, u0, u1, itinerary)
    if not _covered(flags, ev, es, np.array([a0]), np.array([a1]), np.array([b0]), np.array([b1]))[0]:
        return "entered"
    i, j = cells % nv, cells // nv
    v0, v1, s0, s1 = ev[i], ev[i + 1], es[j], es[j + 1]
    m = cells.size
    one = np.ones((2, m))
    # the corners: "lo" quantities at (v0, s0, e0, u0), "hi" at (v1, s1, e1, u1)
    Th = _div_pos(one[:, :1], _point(np.array([u0])))[1, 0]  # T at u0, upper bound
    Tl = _div_pos(one[:, :1], _point(np.array([u1])))[0, 0]  # T at u1, lower bound
    ratio0 = _div_pos(_add(one[:, :1], _point(np.array([e0]))), _sub(one[:, :1], _point(np.array([e0]))))[0, 0]
    slide_hi = _out(np.stack([Th - v0, Th - v0]))[1]
    slide_hi = _out(np.stack([slide_hi - _out(np.stack([ratio0 * s0, ratio0 * s0]))[0]] * 2))[1]
    if not np.all(slide_hi < 0.0):
        return "slide"

    def at(x, n):
        return np.full(n, x)

    def margin_lo(A1_hi):  # T - v - A s at the upper corner, a lower bound
        t = _out(np.stack([v1 + _out(np.stack([A1_hi * s1] * 2))[1]] * 2))[1]
        return _out(np.stack([Tl - t] * 2))[0]

    def margin_hi(A0_lo):  # at the lower corner, an upper bound
        t = _out(np.stack([v0 + np.maximum(_out(np.stack([A0_lo * s0] * 2))[0], 0.0)] * 2))[0]
        return _out(np.stack([Th - t] * 2))[1]

    boxes = []
    live = np.ones(m, bool)  # cells where impact k may happen (k = 0: all)
    hi_prev = np.full(m, np.inf)
    for k in range(_IMPACT_CAP + 1):
        kk = np.full(1, k, np.int64)
        E_lo, A_lo, A1_lo, B_lo = (c[0, 0] for c in _coefficients(np.array([e0]), kk))
        E_hi, A_hi, A1_hi, B_hi = (c[1, 0] for c in _coefficients(np.array([e1]), kk))
        lo_next = margin_lo(A1_hi)  # T - t_{k+1}, least
        lo_k = margin_lo(A_hi) if k else np.full(m, -np.inf)
        hi_k = hi_prev if k == 0 else margin_hi(A_lo)
        can = live & ~(lo_next >= 0.0)
        if k:
            can &= ~(hi_k < 0.0)
        if can.any():
            c = np.flatnonzero(can)
            # v' = v - T + B_k s, s' = sqrt(2 + (e^k s)^2), increasing: the corners
            a0 = _out(np.stack([_out(np.stack([v0[c] - Th] * 2))[0]
                                + np.maximum(_out(np.stack([B_lo * s0[c]] * 2))[0], 0.0)] * 2))[0]
            a1 = _out(np.stack([_out(np.stack([v1[c] - Tl] * 2))[1] + _out(np.stack([B_hi * s1[c]] * 2))[1]] * 2))[1]
            w_lo = np.maximum(_out(np.stack([E_lo * s0[c]] * 2))[0], 0.0)
            w_hi = _out(np.stack([E_hi * s1[c]] * 2))[1]
            if k:  # v' = w_k - d, d = T - t_k in [max(lo_k, 0), hi_k] and [0, 2 w_k)
                a0 = np.maximum(np.maximum(a0, _out(np.stack([w_lo - hi_k[c]] * 2))[0]), -w_hi)
                a1 = np.minimum(a1, _out(np.stack([w_hi - np.maximum(lo_k[c], 0.0)] * 2))[1])
            else:  # v' = -(T - t_1) - s with T - t_1 < 0 and >= its lower bound
                lo1 = lo_next[c]
                hi1 = margin_hi(np.float64(1.0))[c]
                a0 = np.maximum(a0, _out(np.stack([-np.minimum(hi1, 0.0) - s1[c]] * 2))[0])
                a1 = np.minimum(a1, _out(np.stack([-lo1 - s0[c]] * 2))[1])
            b0 = _sqrt(_add(_mul_pos(np.stack([w_lo, w_lo]), np.stack([w_lo, w_lo])), 2.0 * np.ones((2, c.size))))[0]
            b1 = _sqrt(_add(_mul_pos(np.stack([w_hi, w_hi]), np.stack([w_hi, w_hi])), 2.0 * np.ones((2, c.size))))[1]
            boxes.append((a0, a1, b0, b1))
        # impact k + 1 may happen where T - t_{k+1} is not proven < 0
        hi_prev = margin_hi(A1_lo)
        live = ~(hi_prev < 0.0)
        if not live.any():
            break
    else:
        return "invariant"
    a0, a1, b0, b1 = (np.concatenate([b[q] for b in boxes]) for q in range(4))
    if not np.all(_covered(flags, ev, es, a0, a1, b0, b1)):
        return "invariant"
    return "ok"
