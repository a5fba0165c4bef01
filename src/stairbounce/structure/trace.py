"""One border arc from a point near it (:func:`trace_border`): the point where
the outcome changes is searched along the axes and bisected to rounding, the
event that separates the two sides' itineraries found (the one-sided
itineraries :func:`_side_itinerary`), and its margin's level set followed in
both directions by the continuation of :mod:`.continuation`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .. import _validate as _v
from ..model import (
    _COUNTED_IMPACTS,
    SLIDING,
    _constants,
    _impact_time_log,
    _step,
    check_count,
    check_e,
    check_u,
)
from ..symbolic import word_from_impacts
from .continuation import _Margins, _correct, _follow, _into_window, _ulps, _unit
from .itinerary import _itinerary_of
from .regions import BorderArc, Corner, _check_run, _check_window

__all__ = ["trace_border"]


# --------------------------------------------------------------------------- #
# One arc from a point near it                                                #
# --------------------------------------------------------------------------- #


@njit(cache=True)
def _prescribed_step(y, v, e, T, ratio, k):
    """:func:`model._step` with the impact number ``k`` imposed (same arithmetic):
    the one-sided limit of the map on a border where ``k`` changes."""
    if k == SLIDING:
        return 1.0, 0.0
    if k == 0:
        return y + v * T - 0.5 * T * T + 1.0, v - T
    s = math.sqrt(v * v + 2.0 * y)
    if k < _COUNTED_IMPACTS:
        t = v + s
        w = e * s
        for _ in range(k - 1):
            t = t + 2.0 * w
            w *= e
        d = T - t
        return -0.5 * d * d + w * d + 1.0, w - d
    log_e = math.log(e)
    tk = _impact_time_log(v, s, e, k, log_e)
    vk = math.pow(e, float(k)) * s
    d = min(max(T - tk, 0.0), 2.0 * vk)
    return -0.5 * d * d + vk * d + 1.0, vk - d


@njit(cache=True)
def _side_itinerary(e, u, y0, v0, prefix, k, max_iter, ks):
    """The itinerary on one side of a border of step ``len(prefix) + 1``: the
    prefix, then ``k`` imposed, then :func:`model._step` until the slide.
    Fills ``ks``; returns the step count, or ``-max_iter`` without a slide."""
    T, ratio = _constants(e, u)
    y, v = y0, v0
    n = prefix.size
    for j in range(n):
        y, v = _prescribed_step(y, v, e, T, ratio, prefix[j])
        ks[j] = prefix[j]
    ks[n] = k
    if k == SLIDING:
        return n + 1
    y, v = _prescribed_step(y, v, e, T, ratio, k)
    for m in range(n + 1, max_iter):
        y, v, kk = _step(y, v, e, T, ratio)
        ks[m] = kk
        if kk == SLIDING:
            return m + 1
    return -max_iter


def _outcome(e, u, y0, v0, max_iter, buf):
    n = _itinerary_of(e, u, y0, v0, max_iter, buf)
    return buf[:abs(n)].copy(), n > 0


def _same(ka, sa, kb, sb):
    """Whether two outcomes are the same: the same word, or both no slide within
    max_iter (however their bounces differ)."""
    return sa == sb and (not sa or np.array_equal(ka, kb))


def _word_text(ks, slides):
    return word_from_impacts(ks).format(ascii=True) if slides else "none within max_iter"


def _event_between(ka, kb):
    """(kind, k on the side where the margin is >= 0, slot side) of the event that
    separates impact numbers ``ka`` and ``kb`` on one step."""
    if SLIDING in (ka, kb):
        return "chatter", SLIDING, 0
    lo = min(ka, kb)
    return ("graze" if lo == 0 else "edge"), lo, 1


def trace_border(e, u, *, window=None, max_iter=1000, y0=1.0, v0=0.0, search=1e-3,
                 max_points=20000):
    """trace_border(e, u, *, window=None, max_iter=1000, search=1e-3) -> BorderArc

    The border arc nearest to ``(e, u)`` along the axes, followed in both
    directions by pseudo-arclength continuation.

    A point where the outcome (the whole word, or "none within max_iter")
    differs is searched along the four axis directions at distances doubling
    up to ``search``, and the pair bisected to rounding.  The two itineraries
    first differ at step j, by one event: ``graze`` (0 <-> 1 impacts),
    ``edge`` (k <-> k+1) or ``chatter`` (finite <-> sliding).  The arc is the
    level set ``F = 0`` of that event's margin along the common prefix (a
    closed-form function of (e, u), :func:`_margins`), followed with an
    adaptive step until a corner (a margin of the prefix, or the step's other
    margin, vanishes: the prefix changes), a junction (the word on one side
    changes: another border ends on this one, located by bisection along the
    arc), the window's edge, or the curve leaving the domain.

    Every point is a Newton solution of ``F = 0`` converged to a few ulps.

    Returns
    -------
    BorderArc
        ``e``, ``u`` arrays, ``kind``, ``step``, the words ``inside`` (where
        the margin is >= 0) and ``outside``, and how each end was reached.
    """
    e = check_e(e)
    u = check_u(u)
    max_iter = check_count("max_iter", max_iter, 1)
    search = _v.real("search", search)
    if not 0.0 < search <= 1.0:
        raise ValueError(f"search must be in (0, 1], got {search}")
    y0, v0, max_iter = _check_run(y0, v0, max_iter)
    max_points = check_count("max_points", max_points, 2)
    if window is None:
        window = ((max(0.0, e - 0.5), min(1.0 - 1e-9, e + 0.5)), (max(1e-3, u - 0.5), u + 0.5))
    if isinstance(window, (str, bytes)):
        raise ValueError(f"window must be ((e_min, e_max), (u_min, u_max)), got {_v._show(window)}")
    try:
        we, wu = window
    except (TypeError, ValueError):
        raise ValueError(f"window must be ((e_min, e_max), (u_min, u_max)), got {window!r}") from None
    if _v.window("e", we)[2] is not None or _v.window("u", wu)[2] is not None:
        raise ValueError(f"window must be ((e_min, e_max), (u_min, u_max)): trace_border follows one "
                         f"arc and takes no pixel count, got {window!r}")
    we, wu = _check_window(we, wu)
    if not (we[0] <= e <= we[1] and wu[0] <= u <= wu[1]):
        raise ValueError(f"(e, u) = ({e}, {u}) must lie in the window {window}")
    buf = np.empty(max_iter, dtype=np.int64)
    p = np.array([e, u])
    kp, sp = _outcome(e, u, y0, v0, max_iter, buf)
    q = None
    d = 1e-12
    while q is None and d <= search * 1.0001:
        for de, du in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            c = p + d * np.array([de, du])
            if not (we[0] <= c[0] <= we[1] and wu[0] <= c[1] <= wu[1]):
                continue
            kc, sc = _outcome(c[0], c[1], y0, v0, max_iter, buf)
            if not _same(kc, sc, kp, sp):
                q = c
                break
        d *= 2.0
    if q is None:
        raise ValueError(f"no border within search = {search} of ({e}, {u}) along the axes")
    a, b = p.copy(), q
    while True:
        m = 0.5 * (a + b)
        if (m == a).all() or (m == b).all():
            break
        km, sm = _outcome(m[0], m[1], y0, v0, max_iter, buf)
        if _same(km, sm, kp, sp):
            a = m
        else:
            b = m
    ka, sa = _outcome(a[0], a[1], y0, v0, max_iter, buf)
    kb, sb_ = _outcome(b[0], b[1], y0, v0, max_iter, buf)
    n = min(ka.size, kb.size)
    diff = np.nonzero(ka[:n] != kb[:n])[0]
    if diff.size == 0:
        raise ValueError(f"the outcomes near ({e}, {u}) differ only beyond max_iter = {max_iter}")
    j = int(diff[0])
    kind, k_in, side = _event_between(int(ka[j]), int(kb[j]))
    x0 = a if ka[j] == k_in else b
    prefix = ka[:j].copy()
    F = _Margins(np.append(prefix, k_in), (we[0], we[1], wu[0], wu[1]), y0, v0)
    slot = 2 * j + side
    k_out = int(kb[j]) if ka[j] == k_in else int(ka[j])
    scale = max(we[1] - we[0], wu[1] - wu[0])
    sides_buf = np.empty(max_iter + 1, dtype=np.int64)

    # across a chatter border the non-sliding side's impact number is unbounded
    # (edge borders k <-> k+1 accumulate on it, each a sliver of another word):
    # its one-sided limit is the slide itself, so only the sliding side is followed
    watched = (k_in,) if kind == "chatter" else (k_in, k_out)

    def sides(x):
        out = []
        for k in watched:
            nn = _side_itinerary(x[0], x[1], y0, v0, prefix, k, max_iter, sides_buf)
            # two points that never slide are not separated by a border
            out.append((sides_buf[:nn].tobytes() if nn > 0 else b"", nn > 0))
        return out

    def junction(x, y):
        sx, sy = sides(x), sides(y)
        if sx == sy:
            return None
        for _ in range(200):
            mid = 0.5 * (np.asarray(x) + np.asarray(y))
            t = _unit(y[0] - x[0], y[1] - x[1])
            r = _correct(F, slot, mid, t)
            if r is None or math.hypot(y[0] - x[0], y[1] - x[1]) <= _ulps(mid):
                break
            mid = r[0]
            if (mid == x).all() or (mid == y).all():
                break
            if sides(mid) == sx:
                x = mid
            else:
                y = mid
        y = np.asarray(y, float)
        return _into_window(F, y, F(y))

    allc = np.arange(F.m)
    others = allc[allc != slot]
    g0 = F(x0)
    halves = [_follow(F, slot, x0, g0, sgn, scale, others=others, max_points=max_points,
                      junction=junction) for sgn in (-1, 1)]
    back, fwd = halves
    P = np.array(back.pts[::-1] + fwd.pts[1:])
    # rounding may leave a point an ulp outside the window (e = -2.7e-17 next to a
    # corner on e = 0, report round 3, R13): the window's sides are exact lines
    P[:, 0] = np.clip(P[:, 0], we[0], we[1])
    P[:, 1] = np.clip(P[:, 1], wu[0], wu[1])

    def end(h):
        if h.end == "corner":
            ev = F.event(h.end_slot)
            x = h.pts[-1]
            return ("window" if ev[0] == "window" else "corner"), \
                Corner(float(x[0]), float(x[1]), (F.event(slot), ev))
        return h.end, None

    (eb, cb), (ef, cf) = end(back), end(fwd)
    k_a, s_a = _outcome(x0[0], x0[1], y0, v0, max_iter, buf)
    other = b if x0 is a else a
    k_b, s_b = _outcome(other[0], other[1], y0, v0, max_iter, buf)
    arc = BorderArc(P[:, 0].copy(), P[:, 1].copy(), kind, j + 1, _word_text(k_a, s_a),
                    _word_text(k_b, s_b), (eb, ef), (cb, cf))
    arc.evaluations = F.evals
    return arc
