"""The certifier's compiled kernel: outward-rounded float64 intervals along the
itinerary of ``(1, 0)`` (issue 36, items 1-3; the argument is in docs/design.md,
"Certified boxes").

Every quantity of the map is carried as an *MV number*, eight floats::

    (c0, c1,  x0, x1,  a0, a1,  b0, b1)

``[c0, c1]`` encloses its value at the box's centre point ``(ec, uc)``,
``[x0, x1]`` its values over the whole box, ``[a0, a1]`` and ``[b0, b1]`` its
partial derivatives in ``e`` and ``u`` over the whole box.  Each interval
operation rounds to nearest (IEEE-754: +, -, *, / and sqrt are correctly
rounded) and moves each bound one float outward (``np.nextafter``), so it
contains the exact result of the exact operation on any points of its
operands.  With ``mv`` set, the box enclosure is intersected with the
mean-value form ``c + a (E - ec) + b (U - uc)`` (valid because the itinerary is
frozen: every decision up to here is proven over the box, so the quantity is
one smooth formula of (e, u) on the box).

The corners form (:func:`_corners`, the default of ``certify``) carries no
MV numbers: along a frozen itinerary every margin is monotone in e and u, so
one-sided point bounds at the box's two corners ``(E1, U1)`` and ``(E0, U0)``
decide the whole box (the argument is in :func:`_corners` and in
``certify_box``'s docstring).

Min and max propagate NaN (``np.minimum``/``np.maximum``), so a bound is
either NaN or valid; a NaN bound never passes a decision's test (``lo >= 0``,
``hi < 0``), and an intersection keeps the other bound (``np.fmax``/``np.fmin``).
"""

from __future__ import annotations

import math

import numpy as np
from llvmlite import ir
from numba import njit, prange, types
from numba.extending import intrinsic

from .._interrupt import halted
from ..model import _constants, _slide_or_steps

# status codes: indices into certificate.STATUSES
WORD, NO_SLIDING, NO_SLIDE_WITHIN, UNDECIDED = 0, 1, 2, 3
# reason codes: indices into REASON_CODES (-1: none)
GRAZE, EDGE, CHATTER, IMPACTS, NONSLIDING, RANGE = 0, 1, 2, 3, 4, 5
REASON_CODES = ("graze", "edge", "chatter", "impacts", "nonsliding", "range")
# the least u a box may hold (the valid numeric range, stairbounce._validate.U_MIN)
_U_MIN = 1e-150
SLIDING = -1
# the enclosures (certify.FORMS, in this order)
NAIVE, MEAN_VALUE, CORNERS = 0, 1, 2

# impacts followed one by one on a step; a step proven to have more is left
# undecided with reason "impacts" (its bounces are shorter than the enclosures)
IMPACT_CAP = 4096
# boxes of a level handed to one thread at a time (one itinerary buffer each)
_CHUNK = 32
# boxes whose kept itineraries are copied between two looks at the halt flag
_COPY_CHUNK = 1 << 16


@intrinsic
def _bits(typingctx, x):
    """The float64 ``x``'s bits as an int64 (a bitcast)."""
    if x != types.float64:
        return None

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.IntType(64))

    return types.int64(x), codegen


@intrinsic
def _float(typingctx, b):
    """The float64 with the bits ``b`` (a bitcast)."""
    if b != types.int64:
        return None

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.DoubleType())

    return types.float64(b), codegen


@njit(cache=True, inline="always")
def _up(x):
    """``np.nextafter(x, inf)`` by the bits, without a branch (the call to libm's
    cost 8 times more; tests/test_certify.py compares the two).

    ``x + 0.0`` turns -0 into +0; the bits of a float >= 0 count up with it,
    those of a float < 0 count down.  ``+inf`` and ``-inf`` step to NaN (no
    bound, which no decision reads as one), NaN stays NaN.
    """
    x = x + 0.0
    return _float(_bits(x) + (1 if x >= 0.0 else -1))


@njit(cache=True, inline="always")
def _dn(x):
    """``np.nextafter(x, -inf)``: ``-up(-x)``."""
    return -_up(-x)


@njit(cache=True, inline="always")
def _add(a0, a1, b0, b1):
    return _dn(a0 + b0), _up(a1 + b1)


@njit(cache=True, inline="always")
def _sub(a0, a1, b0, b1):
    return _dn(a0 - b1), _up(a1 - b0)


@njit(cache=True, inline="always")
def _mul(a0, a1, b0, b1):
    # the usual signs first: both >= 0 (e, s, T, the ratio, w), or a scale k >= 0
    if a0 >= 0.0:
        if b0 >= 0.0:
            return _dn(a0 * b0), _up(a1 * b1)
        if a0 == a1:
            return _dn(a0 * b0), _up(a0 * b1)
    p = a0 * b0
    q = a0 * b1
    r = a1 * b0
    s = a1 * b1
    return (_dn(np.minimum(np.minimum(p, q), np.minimum(r, s))),
            _up(np.maximum(np.maximum(p, q), np.maximum(r, s))))


@njit(cache=True, inline="always")
def _div(a0, a1, b0, b1):
    """``a / b`` for ``b`` not containing 0 (else the whole line)."""
    if not (b0 > 0.0 or b1 < 0.0):
        return -np.inf, np.inf
    p = a0 / b0
    q = a0 / b1
    r = a1 / b0
    s = a1 / b1
    return (_dn(np.minimum(np.minimum(p, q), np.minimum(r, s))),
            _up(np.maximum(np.maximum(p, q), np.maximum(r, s))))


@njit(cache=True, inline="always")
def _sqr(a0, a1):
    """``a^2`` (the square, not ``a * a``: its lower bound is >= 0)."""
    p = a0 * a0
    q = a1 * a1
    if a0 >= 0.0:
        return np.maximum(_dn(p), 0.0), _up(q)
    if a1 <= 0.0:
        return np.maximum(_dn(q), 0.0), _up(p)
    return 0.0, _up(np.maximum(p, q))


@njit(cache=True, inline="always")
def _sqrt(a0, a1):
    """``sqrt(a)`` of an exact value known to be >= 0 (bounds below 0 clamped)."""
    return np.maximum(_dn(math.sqrt(np.maximum(a0, 0.0))), 0.0), _up(math.sqrt(np.maximum(a1, 0.0)))


# ---- MV numbers ------------------------------------------------------------


@njit(cache=True)
def _const(k):
    return (k, k, k, k, 0.0, 0.0, 0.0, 0.0)


@njit(cache=True)
def _m_add(A, B):
    c0, c1 = _add(A[0], A[1], B[0], B[1])
    x0, x1 = _add(A[2], A[3], B[2], B[3])
    a0, a1 = _add(A[4], A[5], B[4], B[5])
    b0, b1 = _add(A[6], A[7], B[6], B[7])
    return (c0, c1, x0, x1, a0, a1, b0, b1)


@njit(cache=True)
def _m_sub(A, B):
    c0, c1 = _sub(A[0], A[1], B[0], B[1])
    x0, x1 = _sub(A[2], A[3], B[2], B[3])
    a0, a1 = _sub(A[4], A[5], B[4], B[5])
    b0, b1 = _sub(A[6], A[7], B[6], B[7])
    return (c0, c1, x0, x1, a0, a1, b0, b1)


@njit(cache=True)
def _m_mul(A, B):
    c0, c1 = _mul(A[0], A[1], B[0], B[1])
    x0, x1 = _mul(A[2], A[3], B[2], B[3])
    # d(AB) = dA B + A dB, both over the box
    p0, p1 = _mul(A[4], A[5], B[2], B[3])
    q0, q1 = _mul(A[2], A[3], B[4], B[5])
    a0, a1 = _add(p0, p1, q0, q1)
    p0, p1 = _mul(A[6], A[7], B[2], B[3])
    q0, q1 = _mul(A[2], A[3], B[6], B[7])
    b0, b1 = _add(p0, p1, q0, q1)
    return (c0, c1, x0, x1, a0, a1, b0, b1)


@njit(cache=True)
def _m_scale(k, A):
    """``k A`` for a float constant ``k``."""
    c0, c1 = _mul(k, k, A[0], A[1])
    x0, x1 = _mul(k, k, A[2], A[3])
    a0, a1 = _mul(k, k, A[4], A[5])
    b0, b1 = _mul(k, k, A[6], A[7])
    return (c0, c1, x0, x1, a0, a1, b0, b1)


@njit(cache=True)
def _m_div(A, B):
    c0, c1 = _div(A[0], A[1], B[0], B[1])
    x0, x1 = _div(A[2], A[3], B[2], B[3])
    # d(A/B) = (dA - (A/B) dB) / B
    p0, p1 = _mul(x0, x1, B[4], B[5])
    p0, p1 = _sub(A[4], A[5], p0, p1)
    a0, a1 = _div(p0, p1, B[2], B[3])
    p0, p1 = _mul(x0, x1, B[6], B[7])
    p0, p1 = _sub(A[6], A[7], p0, p1)
    b0, b1 = _div(p0, p1, B[2], B[3])
    return (c0, c1, x0, x1, a0, a1, b0, b1)


@njit(cache=True)
def _m_sqr(A):
    c0, c1 = _sqr(A[0], A[1])
    x0, x1 = _sqr(A[2], A[3])
    t0, t1 = _mul(2.0, 2.0, A[2], A[3])  # d(A^2) = 2 A dA
    a0, a1 = _mul(t0, t1, A[4], A[5])
    b0, b1 = _mul(t0, t1, A[6], A[7])
    return (c0, c1, x0, x1, a0, a1, b0, b1)


@njit(cache=True)
def _m_sqrt(A):
    c0, c1 = _sqrt(A[0], A[1])
    x0, x1 = _sqrt(A[2], A[3])
    t0, t1 = _mul(2.0, 2.0, x0, x1)  # d sqrt(A) = dA / (2 sqrt(A)); A >= 2 here
    a0, a1 = _div(A[4], A[5], t0, t1)
    b0, b1 = _div(A[6], A[7], t0, t1)
    return (c0, c1, x0, x1, a0, a1, b0, b1)


@njit(cache=True)
def _m_tight(A, mv, de0, de1, du0, du1):
    """``A`` with its box enclosure cut to the mean-value form ``c + a dE + b dU``."""
    if not mv:
        return A
    p0, p1 = _mul(A[4], A[5], de0, de1)
    q0, q1 = _mul(A[6], A[7], du0, du1)
    p0, p1 = _add(p0, p1, q0, q1)
    p0, p1 = _add(A[0], A[1], p0, p1)
    return (A[0], A[1], np.fmax(A[2], p0), np.fmin(A[3], p1), A[4], A[5], A[6], A[7])


@njit(cache=True)
def _m_clip(A, lo, hi):
    """``A`` with its value enclosures cut to ``[lo, hi]``, a range its exact value is known to lie in."""
    return (np.fmax(A[0], lo), np.fmin(A[1], hi), np.fmax(A[2], lo), np.fmin(A[3], hi),
            A[4], A[5], A[6], A[7])


@njit(cache=True)
def _sign(A):
    """1 where the box enclosure is proven >= 0, -1 where proven < 0, else 0."""
    if A[2] >= 0.0:
        return 1
    if A[3] < 0.0:
        return -1
    return 0


@njit(cache=True)
def _record(rec, dec, marg, nd, code, A):
    if rec and nd < dec.shape[0]:
        dec[nd] = code
        marg[nd, 0] = A[2]
        marg[nd, 1] = A[3]
    return nd + 1


@njit(cache=True)
def _no_sliding(E0, U0):
    """Corollary 2.1 over the whole box: ``u0 > (1 - e0) / (2 sqrt(2 e0))``, the bound enclosed from above."""
    if not E0 > 0.0:
        return False
    num = _up(1.0 - E0)
    den = _dn(2.0 * _dn(math.sqrt(_dn(2.0 * E0))))
    return U0 > _up(num / den)


@njit(cache=True)
def _record2(rec, dec, marg, nd, code, lo, hi):
    if rec and nd < dec.shape[0]:
        dec[nd] = code
        marg[nd, 0] = lo
        marg[nd, 1] = hi
    return nd + 1


@njit(cache=True)
def _corners(E0, E1, U0, U1, max_iter, cap, itin, rec, dec, marg):
    """The corners form of :func:`_certify_box`: two point evaluations.

    Along a frozen itinerary the state ``(v, s)``, ``s = sqrt(v^2 + 2y)``,
    starts at ``(0, sqrt 2)`` and a step with k impacts gives
    ``v' = v - T + B_k s`` (``B_0 = 0``, ``B_k = (1+e)(1 + e + ... + e^(k-1))``)
    and ``s'^2 = 2 + e^(2k) s^2``; by induction v and s do not decrease with e
    nor with u, so every margin ``T - v - C s`` (``C`` = ratio, or
    ``A_j = 1 + 2(e + ... + e^(j-1))``) does not increase with e and decreases
    with u.  Its least value over the box is at ``(E1, U1)``, its largest at
    ``(E0, U0)``: a decision happens on the whole box when a lower bound of the
    margin at ``(E1, U1)`` is >= 0, and nowhere when an upper bound at
    ``(E0, U0)`` is < 0.  So the kernel carries upper bounds of ``v, s, t_j,
    w_j = e^j s`` at ``(E1, U1)`` (names ending in ``h``) and lower bounds at
    ``(E0, U0)`` (``l``), each operation rounded to nearest and stepped one
    float outward (up for ``h``, down for ``l``) on the side it bounds.  The
    recorded enclosure of a margin is ``[lo at (E1, U1), hi at (E0, U0)]``.
    Both corners take the same decisions, so the itinerary is frozen for both.
    """
    Tl = _dn(1.0 / U1)  # T = 1/u: a lower bound at U1, an upper one at U0
    Th = _up(1.0 / U0)
    Rh = _up(_up(1.0 + E1) / _dn(1.0 - E1))  # ratio = (1+e)/(1-e) > 0
    Rl = _dn(_dn(1.0 + E0) / _up(1.0 - E0))
    vh = 0.0
    vl = 0.0
    sh = _up(math.sqrt(2.0))
    sl = _dn(math.sqrt(2.0))
    nd = 0
    for n in range(max_iter):
        step = n + 1
        # the slide test (2.4): T - (v + ratio s) >= 0
        lo = _dn(_dn(Tl - vh) - _up(Rh * sh))
        hi = _up(_up(Th - vl) - np.maximum(_dn(Rl * sl), 0.0))
        nd = _record2(rec, dec, marg, nd, 0, lo, hi)
        if lo >= 0.0:
            itin[n] = SLIDING
            return WORD, -1, step, n + 1, nd
        if not hi < 0.0:
            return UNDECIDED, CHATTER, step, n, nd
        # first impact t_1 = v + s
        th = _up(vh + sh)
        tl = _dn(vl + sl)
        lo = _dn(Tl - th)
        hi = _up(Th - tl)
        nd = _record2(rec, dec, marg, nd, 1, lo, hi)
        if not lo >= 0.0:
            if not hi < 0.0:
                return UNDECIDED, GRAZE, step, n, nd
            # flies over: v' = v - T, s'^2 = 2 + s^2
            vh = _up(vh - Tl)
            vl = _dn(vl - Th)
            sh = _up(math.sqrt(_up(2.0 + _up(sh * sh))))
            sl = _dn(math.sqrt(_dn(2.0 + _dn(sl * sl))))
            itin[n] = 0
            continue
        # impacts: t_{j+1} = t_j + 2 w_j, w_j = e^j s (eq. 2.2); w >= 0
        wh = _up(E1 * sh)
        wl = np.maximum(_dn(E0 * sl), 0.0)
        k = 1
        while True:
            tnh = _up(th + 2.0 * wh)
            tnl = _dn(tl + 2.0 * wl)
            lo = _dn(Tl - tnh)
            hi = _up(Th - tnl)
            nd = _record2(rec, dec, marg, nd, k + 1, lo, hi)
            if not lo >= 0.0:
                if not hi < 0.0:
                    return UNDECIDED, EDGE, step, n, nd
                break
            if k >= cap:
                return UNDECIDED, IMPACTS, step, n, nd
            th = tnh
            tl = tnl
            wh = _up(E1 * wh)
            wl = np.maximum(_dn(E0 * wl), 0.0)
            k += 1
        # after k impacts: v' = w_k - (T - t_k), s'^2 = 2 + w_k^2
        vh = _up(_up(wh + th) - Tl)
        vl = _dn(_dn(wl + tl) - Th)
        sh = _up(math.sqrt(_up(2.0 + _up(wh * wh))))
        sl = _dn(math.sqrt(_dn(2.0 + _dn(wl * wl))))
        itin[n] = k
    return NO_SLIDE_WITHIN, -1, max_iter, max_iter, nd


@njit(cache=True)
def _certify_box(E0, E1, U0, U1, max_iter, cap, form, itin, rec, dec, marg):
    """Certify the box ``[E0, E1] x [U0, U1]`` with the enclosures of ``form``
    (:data:`NAIVE`, :data:`MEAN_VALUE` or :data:`CORNERS`).

    Returns ``(status, reason, step, n_itinerary, n_decisions)``; the itinerary
    (impact number per decided step, -1 for the slide) is written to
    ``itin``, and with ``rec`` the decisions (0: slide, j: impact j) and
    their margins' enclosures to ``dec`` and ``marg`` (as far as they fit).
    """
    if _no_sliding(E0, U0):
        return NO_SLIDING, -1, 0, 0, 0
    if form == CORNERS:
        return _corners(E0, E1, U0, U1, max_iter, cap, itin, rec, dec, marg)
    mv = form == MEAN_VALUE
    ec = 0.5 * (E0 + E1)
    uc = 0.5 * (U0 + U1)
    de0, de1 = _dn(E0 - ec), _up(E1 - ec)
    du0, du1 = _dn(U0 - uc), _up(U1 - uc)
    e = (ec, ec, E0, E1, 1.0, 1.0, 0.0, 0.0)
    u = (uc, uc, U0, U1, 0.0, 0.0, 1.0, 1.0)
    one = _const(1.0)
    T = _m_tight(_m_div(one, u), mv, de0, de1, du0, du1)
    ratio = _m_tight(_m_div(_m_add(one, e), _m_sub(one, e)), mv, de0, de1, du0, du1)
    y = one
    v = _const(0.0)
    nd = 0
    for n in range(max_iter):
        step = n + 1
        # s = sqrt(v^2 + 2y), eq. (2.1)
        s = _m_tight(_m_sqrt(_m_add(_m_sqr(v), _m_scale(2.0, y))), mv, de0, de1, du0, du1)
        # the slide test (2.4): T - (v + ratio s) >= 0
        m = _m_tight(_m_sub(T, _m_add(v, _m_mul(ratio, s))), mv, de0, de1, du0, du1)
        nd = _record(rec, dec, marg, nd, 0, m)
        sg = _sign(m)
        if sg > 0:
            itin[n] = SLIDING
            return WORD, -1, step, n + 1, nd
        if sg == 0:
            return UNDECIDED, CHATTER, step, n, nd
        # first impact t_1 = v + s
        t = _m_add(v, s)
        m = _m_tight(_m_sub(T, t), mv, de0, de1, du0, du1)
        nd = _record(rec, dec, marg, nd, 1, m)
        sg = _sign(m)
        if sg == 0:
            return UNDECIDED, GRAZE, step, n, nd
        if sg < 0:  # flies over: y' = y + v T - T^2/2 + 1 >= 1, v' = v - T
            h = _m_sub(_m_add(y, _m_mul(v, T)), _m_scale(0.5, _m_sqr(T)))
            y = _m_clip(_m_tight(_m_add(h, one), mv, de0, de1, du0, du1), 1.0, np.inf)
            v = _m_tight(_m_sub(v, T), mv, de0, de1, du0, du1)
            itin[n] = 0
            continue
        # impacts: t_{j+1} = t_j + 2 w_j, w_j = e^j s (eq. 2.2)
        w = _m_tight(_m_mul(e, s), mv, de0, de1, du0, du1)
        k = 1
        while True:
            tn = _m_add(t, _m_scale(2.0, w))
            m = _m_tight(_m_sub(T, tn), mv, de0, de1, du0, du1)
            nd = _record(rec, dec, marg, nd, k + 1, m)
            sg = _sign(m)
            if sg == 0:
                return UNDECIDED, EDGE, step, n, nd
            if sg < 0:
                break
            if k >= cap:
                return UNDECIDED, IMPACTS, step, n, nd
            t = _m_tight(tn, mv, de0, de1, du0, du1)
            w = _m_tight(_m_mul(e, w), mv, de0, de1, du0, du1)
            k += 1
        # after the last impact: d = T - t_k in [0, 2 w_k) (the decisions k >= 0, k+1 < 0)
        w2 = _m_scale(2.0, w)
        d = _m_clip(_m_tight(_m_sub(T, t), mv, de0, de1, du0, du1), 0.0, w2[3])
        # y' = 1 + d (w - d/2) >= 1, v' = w - d in (-w, w]
        y = _m_add(one, _m_mul(d, _m_sub(w, _m_scale(0.5, d))))
        y = _m_clip(_m_tight(y, mv, de0, de1, du0, du1), 1.0, np.inf)
        v = _m_tight(_m_sub(w, d), mv, de0, de1, du0, du1)
        v = _m_clip(v, -w[3], w[3])
        itin[n] = k
    return NO_SLIDE_WITHIN, -1, max_iter, max_iter, nd


# ---- boxes of the quadtree ---------------------------------------------------


@njit(cache=True)
def _edge(lo, width, hi, i, level):
    """The ``i``-th of the ``2^level + 1`` edges of a window ``[lo, hi]``
    (``width = hi - lo``): the same float for every box that shares it, at
    every level, so boxes tile the window without gap or overlap."""
    n = 1 << level
    if i >= n:
        return hi
    return lo + width * (float(i) * (1.0 / n))


@njit(cache=True, inline="always")
def _lift(e):
    """The e at which the "nonsliding" check runs the float map: e in (0, 2^-53) lifted to 2^-53."""
    if e > 0.0 and e < 2.0**-53:
        return 2.0**-53
    return e


@njit(cache=True, parallel=True, nogil=True)
def _centres(win, level, ii, jj, es, us):
    """The centres of the boxes ``(ii[b], jj[b])`` of a level, as :func:`_any_slides`
    computes them (its first point), into ``es, us``."""
    ew = win[1] - win[0]
    uw = win[3] - win[2]
    for b in prange(ii.shape[0]):
        E0 = _edge(win[0], ew, win[1], ii[b], level)
        E1 = _edge(win[0], ew, win[1], ii[b] + 1, level)
        U0 = _edge(win[2], uw, win[3], jj[b], level)
        U1 = _edge(win[2], uw, win[3], jj[b] + 1, level)
        es[b] = _lift(0.5 * (E0 + E1))
        us[b] = 0.5 * (U0 + U1)


@njit(cache=True)
def _grid_points(win, level, gi, gj, es, us):
    """The grid points ``(gi[p], gj[p])`` of a level (box corners, the same floats at
    every level, :func:`_edge`), as :func:`_any_slides` takes a corner, into ``es, us``."""
    ew = win[1] - win[0]
    uw = win[3] - win[2]
    for p in range(gi.shape[0]):
        es[p] = _lift(_edge(win[0], ew, win[1], gi[p], level))
        us[p] = _edge(win[2], uw, win[3], gj[p], level)


@njit(cache=True, nogil=True)
def _children(ii, jj, out_i, out_j):
    """The four children of each box ``(ii[b], jj[b])`` of a level into ``out_i, out_j``
    (``4 n`` each), row by row: for each run of boxes with the same ``j``, the children
    of row ``2 j`` then those of row ``2 j + 1``, each run's boxes in their order.  When
    the boxes are in the atlas's order (by ``j``, then ``i``) so are their children
    (``i -> 2 i, 2 i + 1`` and ``j -> 2 j, 2 j + 1`` keep it), so the atlas's table,
    the float map's shared corners and their cache are sorted by merging runs
    (``certify._box_table``, ``certify._SlideCache``); any order gives the same boxes."""
    n = ii.shape[0]
    o = 0
    a = 0
    while a < n:
        b = a + 1
        while b < n and jj[b] == jj[a]:
            b += 1
        for r in range(2):
            for p in range(a, b):
                out_i[o] = 2 * ii[p]
                out_j[o] = 2 * jj[p] + r
                out_i[o + 1] = 2 * ii[p] + 1
                out_j[o + 1] = 2 * jj[p] + r
                o += 2
        a = b


@njit(cache=True, parallel=True, nogil=True)
def _kept_itineraries(itinerary, offsets, kept, row, halt):
    """Copy the kept itinerary ``kept[row[b], :n]`` of each box with ``row[b] >= 0`` to
    ``itinerary[offsets[b]:offsets[b] + n]``, ``n = offsets[b + 1] - offsets[b]``
    (1.4 s at depth 14: in slices that a Ctrl-C stops, ``_interrupt.run_kernel``)."""
    n = row.shape[0]
    for c in prange((n + _COPY_CHUNK - 1) // _COPY_CHUNK):
        if halted(halt):
            continue
        for b in range(c * _COPY_CHUNK, min(n, (c + 1) * _COPY_CHUNK)):
            r = row[b]
            if r >= 0:
                o = offsets[b]
                for k in range(offsets[b + 1] - o):
                    itinerary[o + k] = kept[r, k]


@njit(cache=True, parallel=True)
def _box_edges(win, level, ii, jj, e0, e1, u0, u1):
    """The edges of the boxes ``(level[b], ii[b], jj[b])`` (:func:`_edge`), into ``e0, e1, u0, u1``."""
    ew = win[1] - win[0]
    uw = win[3] - win[2]
    for b in prange(ii.shape[0]):
        L = level[b]
        e0[b] = _edge(win[0], ew, win[1], ii[b], L)
        e1[b] = _edge(win[0], ew, win[1], ii[b] + 1, L)
        u0[b] = _edge(win[2], uw, win[3], jj[b], L)
        u1[b] = _edge(win[2], uw, win[3], jj[b] + 1, L)


@njit(cache=True)
def _itinerary_hashes(itin, offsets, boxes, out):
    """A 64-bit FNV-1a hash of each box's itinerary ``itin[offsets[b]:offsets[b+1]]``,
    ``b`` in ``boxes`` (to tell itineraries apart; equal ones are checked by
    :func:`_same_itineraries`)."""
    for k in range(boxes.shape[0]):
        b = boxes[k]
        h = np.uint64(14695981039346656037)
        for x in itin[offsets[b]:offsets[b + 1]]:
            h = (h ^ np.uint64(x & 0xFFFFFFFF)) * np.uint64(1099511628211)
        out[k] = np.int64(h)


@njit(cache=True)
def _same_itineraries(itin, offsets, boxes, rep):
    """Whether each box ``boxes[k]`` has the itinerary of the box ``rep[k]``."""
    for k in range(boxes.shape[0]):
        a, b = boxes[k], rep[k]
        n = offsets[a + 1] - offsets[a]
        if n != offsets[b + 1] - offsets[b]:
            return False
        for t in range(n):
            if itin[offsets[a] + t] != itin[offsets[b] + t]:
                return False
    return True


@njit(cache=True)
def _any_slides(E0, E1, U0, U1, max_iter, points):
    """Whether the float map slides from (1, 0) within max_iter steps at the
    centre of the box (``points = 1``) or at its centre or a corner
    (``points = 5``) (numerical: the reason "nonsliding")."""
    for p in range(points):
        if p == 0:  # the centre first: on a border box it is the likeliest to slide
            e = 0.5 * (E0 + E1)
            u = 0.5 * (U0 + U1)
        else:
            e = E0 if p & 1 else E1
            u = U0 if p & 2 else U1
        e = _lift(e)
        T, ratio = _constants(e, u)
        if _slide_or_steps(1.0, 0.0, e, T, ratio, max_iter)[0] > 0:
            return True
    return False


@njit(cache=True, nogil=True)
def _slides_each(es, us, max_iter, out):
    """Whether the float map slides from (1, 0) within max_iter steps at each point
    ``(es[p], us[p])`` (as :func:`_any_slides` tests a point), into ``out``."""
    for p in range(es.shape[0]):
        T, ratio = _constants(es[p], us[p])
        out[p] = _slide_or_steps(1.0, 0.0, es[p], T, ratio, max_iter)[0] > 0


@njit(cache=True, parallel=True, nogil=True)
def _certify_level(win, level, ii, jj, max_iter, cap, form, ns_points, status, reason, step, nsteps, kept, halt):
    """Certify the boxes ``(ii[b], jj[b])`` of one level of the window's
    quadtree (``win = (e_lo, e_hi, u_lo, u_hi)``), in parallel; a box left
    undecided gets the reason "nonsliding" when ``ns_points > 0`` and the
    float map slides at none of its first ``ns_points`` points (the centre,
    then the corners: :func:`_any_slides`).  The itinerary of a box whose
    itinerary fits ``kept``'s rows is kept there (the rest is computed again
    by :func:`_itineraries`)."""
    n = ii.shape[0]
    ew = win[1] - win[0]
    uw = win[3] - win[2]
    dec = np.empty(1, np.int64)
    marg = np.empty((1, 2))
    for c in prange((n + _CHUNK - 1) // _CHUNK):
        if halted(halt):
            continue
        itin = np.empty(max_iter, np.int64)
        for b in range(c * _CHUNK, min(n, (c + 1) * _CHUNK)):
            E0 = _edge(win[0], ew, win[1], ii[b], level)
            E1 = _edge(win[0], ew, win[1], ii[b] + 1, level)
            U0 = _edge(win[2], uw, win[3], jj[b], level)
            U1 = _edge(win[2], uw, win[3], jj[b] + 1, level)
            # touches u = 0 or e = 1 (outside the model), or e = 0 for a form other than the corners
            # (whose enclosures hold on [0, e1]: ratio, A_j, B_k and e^k increase with e on [0, 1))
            if U0 < _U_MIN or E1 >= 1.0 or E0 < 0.0 or (E0 == 0.0 and form != CORNERS):
                st, rs, sp, ni = UNDECIDED, RANGE, 0, 0
            else:
                st, rs, sp, ni, nd = _certify_box(E0, E1, U0, U1, max_iter, cap, form, itin, False, dec, marg)
            if (st == UNDECIDED and ns_points > 0 and rs != RANGE and rs != IMPACTS
                    and not _any_slides(E0, E1, U0, U1, max_iter, ns_points)):
                rs = NONSLIDING
            status[b] = st
            reason[b] = rs
            step[b] = sp
            nsteps[b] = ni
            if ni <= kept.shape[1]:
                for k in range(ni):
                    kept[b, k] = itin[k]


@njit(cache=True, parallel=True, nogil=True)
def _itineraries(win, level, ii, jj, max_iter, cap, form, starts, ends, out, halt):
    """Write the itineraries of the boxes ``(level[b], ii[b], jj[b])`` to
    ``out[starts[b]:ends[b]]`` (the same computation as :func:`_certify_level`)."""
    n = ii.shape[0]
    ew = win[1] - win[0]
    uw = win[3] - win[2]
    dec = np.empty(1, np.int64)
    marg = np.empty((1, 2))
    for c in prange((n + _CHUNK - 1) // _CHUNK):
        if halted(halt):
            continue
        itin = np.empty(max_iter, np.int64)
        for b in range(c * _CHUNK, min(n, (c + 1) * _CHUNK)):
            L = level[b]
            E0 = _edge(win[0], ew, win[1], ii[b], L)
            E1 = _edge(win[0], ew, win[1], ii[b] + 1, L)
            U0 = _edge(win[2], uw, win[3], jj[b], L)
            U1 = _edge(win[2], uw, win[3], jj[b] + 1, L)
            _certify_box(E0, E1, U0, U1, max_iter, cap, form, itin, False, dec, marg)
            o = starts[b]
            for k in range(ends[b] - o):
                out[o + k] = itin[k]
