"""Borders in proven tubes: each traced arc enclosed, piece by piece, by a theorem.

Along a fixed itinerary ``k_1, ..., k_{j-1}`` from ``(y, v) = (1, 0)`` (the
state carried as ``(v, s)``, ``s = sqrt(v^2 + 2y)``, as in
``structure/verify.py``): ``v_{i+1} = v_i - T + B_{k}(e) s_i`` and
``s_{i+1}^2 = 2 + e^{2k} s_i^2`` with ``T = 1/u``, ``B_k = (1+e)(1-e^k)/(1-e)``
(eq. (2.2), Prop. 2.3).  So ``s_i`` depends on e alone and
``v_{j-1} = -(j-1)/u + sum_{i<j-1} B_{k_{i+1}}(e) s_i(e)``, and the margin of
step j's event (``T - v - C s``: ``C = (1+e)/(1-e)`` for the slide, eq. (2.4),
``C = A_m = (1+e-2e^m)/(1-e)`` for the m-th impact, ``A_1 = 1`` the graze) is
exactly

    m(e, u) = j/u - G(e),   G(e) = sum_{i<j-1} B_{k_{i+1}}(e) s_i(e) + C(e) s_{j-1}(e).

Every factor of G is positive and increasing in e on [0, 1) (polynomials in
e with non-negative coefficients, ``s_i^2`` too, and ``(1+e)/(1-e)``), so G
increases, the zero set of m is the graph ``u*(e) = j / G(e)`` of a
non-increasing function, and on each vertical line m (strictly decreasing in
u, from +inf to -G < 0) vanishes exactly once.

A tube piece is ``e in [e_a, e_b]``, ``|u - l(e)| <= delta`` with ``l`` the
line through ``(e_a, u_a)`` and ``(e_b, u_b)``.  Mean-value form: with
``D = u* - l``, ``|D(e)| <= |D(e_m)| + max |D'| * h`` for e in the piece
(``e_m`` its midpoint, ``h`` the larger half), ``D' = -j G'/G^2 - slope``;
``G(e_m)`` is enclosed at the float ``e_m`` and ``G, G'`` over ``[e_a, e_b]``
by the factors' values at ``e_a`` and ``e_b`` (each increasing;
``s' = (s^2)'/(2s)`` with ``(s^2)'`` increasing and the root in the
denominator taken at the other end), all with the independent checker's
outward-rounded float64 intervals.  The piece is *proven* when, besides,
every decision of the prefix ``k_1 .. k_{j-1}`` is proven over the piece's
bounding box (``verify_codes``, corner checks: a decision along a fixed
itinerary holds on a box iff at its corners), and for an impact event the
step's other decisions too (no slide at step j; for the m-th impact with
m >= 2, the (m-1)-th impact happens).  Then (theorem) inside the piece's box
the orbit's first j - 1 impact numbers are the prefix's, the border of step
j's event is exactly the graph of ``u*`` over ``[e_a, e_b]``, and it lies in
the piece's tube: the tube contains the true border and no other point of
it on each vertical line (it is a graph).  Other borders (later steps) may
cross the tube; only this arc is claimed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import _validate as _v
from ..model import SLIDING
from .certificate import STATUSES
from .labels import _itineraries
from .verify import (
    _add,
    _div_pos,
    _mul_pos,
    _out,
    _over_box,
    _point,
    _pow_point,
    _sqrt,
    _sub,
    verify_codes,
)

__all__ = ["BorderTube", "border_tube"]

_UNDECIDED_S = STATUSES.index("undecided")
# pieces proven together (about 30 interval arrays of 3 x _CHUNK floats per step)
_CHUNK = 1 << 14
_FAIL_DEPTH = 24


def _mul(a, b):
    """Product of two intervals of any signs."""
    p = np.stack([a[0] * b[0], a[0] * b[1], a[1] * b[0], a[1] * b[1]])
    return _out(np.stack([p.min(axis=0), p.max(axis=0)]))


def _mag(a):
    """An upper bound of ``|x|`` over the interval ``a``."""
    return np.maximum(np.abs(a[0]), np.abs(a[1]))


def _up(x):
    return np.nextafter(x, np.inf)


def _ones(e):
    """At the floats ``e`` (exact): ``n = e.size`` and the enclosures of 1,
    ``1 + e``, ``1 - e`` and ``(1 - e)^2``."""
    n = e.size
    one = np.ones((2, n))
    ep = _point(e)
    one_p, one_m = _add(one, ep), _sub(one, ep)
    return n, one, one_p, one_m, _mul_pos(one_m, one_m)


def _coef(e, k):
    """At the floats ``e`` (exact), enclosures of ``e^k``, ``(e^k)'``,
    ``B_k``, ``B_k'`` (``B_k = (1+e) Q_k``, ``Q_k = (1 - e^k)/(1 - e)``,
    ``Q_k' = N_k / (1-e)^2``, ``N_k = 1 - k e^(k-1) + (k-1) e^k``)."""
    n, one, one_p, one_m, om2 = _ones(e)
    if k == 0:
        z = np.zeros((2, n))
        return one, z, z, z
    kk = np.full(n, k, np.int64)
    E = _pow_point(e, kk)
    Em1 = _pow_point(e, kk - 1)
    dE = _mul_pos(_point(np.full(n, float(k))), Em1)  # k e^(k-1)
    Q = _div_pos(np.maximum(_sub(one, E), 0.0), one_m)
    N = np.maximum(_add(_sub(one, dE), _mul_pos(_point(np.full(n, float(k - 1))), E)), 0.0)
    dQ = _div_pos(N, om2)
    B = _mul_pos(one_p, Q)
    dB = _add(Q, _mul_pos(one_p, dQ))
    return E, dE, B, dB


def _event_coef(e, index):
    """``C`` and ``C'`` of the event: index 0 the slide, ``(1+e)/(1-e)``; index
    m >= 1 the m-th impact, ``A_m = (1+e-2e^m)/(1-e)`` (``A_m' = 2 N_m/(1-e)^2``)."""
    n, one, one_p, one_m, om2 = _ones(e)
    if index == 0:
        return _div_pos(one_p, one_m), _div_pos(2.0 * one, om2)
    if index == 1:
        return one, np.zeros((2, n))
    E, dE, _, _ = _coef(e, index)
    C = np.maximum(_div_pos(_sub(one_p, 2.0 * E), one_m), 1.0)  # A_m >= 1
    N = np.maximum(_add(_sub(one, dE), _mul_pos(_point(np.full(n, float(index - 1))), E)), 0.0)
    return C, _div_pos(2.0 * N, om2)


def _over(x, n):
    """An increasing function over ``[e_a, e_b]`` from its enclosures at the
    points laid out ``[e_a; e_m; e_b]`` (blocks of n)."""
    return _over_box(x[:, :n], x[:, 2 * n:])


def _deriv_term(dF, S, F, dP, n):
    """``F' s + F s'`` over the pieces, ``s' = P'/(2 s)`` (all factors
    increasing in e and >= 0; the root in the denominator at the other end)."""
    dFo, So, Fo, dPo = (_over(x, n) for x in (dF, S, F, dP))
    ds = _div_pos(dPo, 2.0 * So)
    return _add(_mul_pos(dFo, So), _mul_pos(Fo, ds))


def _g(e, prefix, index, derivative=True):
    """Along the prefix, at the floats ``e`` (exact; with ``derivative``
    laid out ``[e_a; e_m; e_b]`` in blocks of ``n``): ``(G, G over each
    [e_a, e_b], G' over it, H, s)`` with ``H = sum B s`` the prefix's part
    of ``G`` and ``s = s_{j-1}``.  ``(s^2)' = P'`` follows
    ``P_{i+1} = 2 + E^2 P_i``, ``P'_{i+1} = 2 E E' P_i + E^2 P'_i``."""
    m = e.size
    n = m // 3
    two = 2.0 * np.ones((2, m))
    S = _sqrt(two)
    P = two
    dP = np.zeros((2, m))
    H = np.zeros((2, m))
    dG = np.zeros((2, n))
    cache = {}
    for k in prefix:
        k = int(k)
        if k not in cache:
            cache[k] = _coef(e, k)
        E, dE, B, dB = cache[k]
        H = _add(H, _mul_pos(B, S))
        if derivative:
            dG = _add(dG, _deriv_term(dB, S, B, dP, n))
            E2 = _mul_pos(E, E)
            dP = _add(_mul_pos(_mul_pos(2.0 * E, dE), P), _mul_pos(E2, dP))
        else:
            E2 = _mul_pos(E, E)
        P = _add(two, _mul_pos(E2, P))
        S = _sqrt(P)
    C, dC = _event_coef(e, index)
    G = _add(H, _mul_pos(C, S))
    if not derivative:
        return G, None, None, H, S
    dG = _add(dG, _deriv_term(dC, S, C, dP, n))
    return G, _over(G, n), dG, H, S


def _delta(j, prefix, index, e_a, e_b, u_a, u_b):
    """A rigorous upper bound of ``|u*(e) - l(e)|`` over each piece, and
    ``G`` enclosures for the step's other decisions."""
    n = e_a.size
    e_m = 0.5 * (e_a + e_b)
    pts = np.concatenate([e_a, e_m, e_b])
    G, GE, dGE, H, S = _g(pts, prefix, index)
    jj = _point(np.full(n, float(j)))
    # slope of l, enclosed: (u_b - u_a) / (e_b - e_a), e_b > e_a
    lam = _div_pos(_sub(_point(u_b), _point(u_a)), _sub(_point(e_b), _point(e_a)))
    l_m = _add(_point(u_a), _mul(lam, _sub(_point(e_m), _point(e_a))))
    D_m = _sub(_div_pos(jj, G[:, n:2 * n]), l_m)
    dD = _sub(_mul(_point(np.full(n, -1.0)), _div_pos(_mul_pos(jj, dGE), _mul_pos(GE, GE))), lam)
    h = np.maximum(_sub(_point(e_m), _point(e_a))[1], _sub(_point(e_b), _point(e_m))[1])
    delta = _up(_mag(D_m) + _up(_mag(dD) * h))
    return delta, H, S, pts


@dataclass
class BorderTube:
    """A traced border arc enclosed in proven pieces.

    The arc is the zero set of the margin of ``kind`` at ``step`` along the
    itinerary ``prefix`` (``index``: 0 the slide, m >= 1 the m-th impact).
    Piece i is ``e in [e_a[i], e_b[i]]``, ``|u - l_i(e)| <= delta[i]``,
    ``l_i`` the line through ``(e_a, u_a)`` and ``(e_b, u_b)``; ``proven[i]``
    says it is a theorem (``stairbounce.structure.tubes``).  ``window`` is
    the size the widths are measured against.
    """

    kind: str
    step: int
    prefix: tuple
    index: int
    e_a: np.ndarray
    e_b: np.ndarray
    u_a: np.ndarray
    u_b: np.ndarray
    delta: np.ndarray
    proven: np.ndarray
    window: float

    @property
    def max_width(self):
        """The widest proven piece's width ``2 delta``, relative to ``window``."""
        if not self.proven.any():
            return math.inf
        return float(2.0 * self.delta[self.proven].max() / self.window)

    @property
    def proven_fraction(self):
        """The share of the arc's e-range covered by proven pieces."""
        span = self.e_b - self.e_a
        return float(span[self.proven].sum() / span.sum()) if span.sum() > 0 else float(self.proven.all())

    def contains(self, e, u):
        """Whether each point ``(e, u)`` lies in a proven piece (float test,
        the line evaluated in float64: for checking, not a proof)."""
        e = np.atleast_1d(np.asarray(e, float))
        u = np.atleast_1d(np.asarray(u, float))
        order = np.argsort(self.e_a)
        ea, eb = self.e_a[order], self.e_b[order]
        out = np.zeros(e.size, bool)
        # the pieces containing e: the last one starting at or before it, and its left neighbour
        i = np.searchsorted(ea, e, side="right") - 1
        for shift in (0, -1):
            k = np.clip(i + shift, 0, ea.size - 1)
            p = order[k]
            inside = (e >= ea[k]) & (e <= eb[k]) & self.proven[p]
            l = self.u_a[p] + (self.u_b[p] - self.u_a[p]) * (e - self.e_a[p]) / (self.e_b[p] - self.e_a[p])
            out |= inside & (np.abs(u - l) <= self.delta[p])
        return out

    def bounds(self, e):
        """bounds(e) -> (u_lo, u_hi): the arc's u proven to lie in
        ``[u_lo, u_hi]`` at every real e' in ``[e, next float above e]``, for
        floats e in a proven piece (NaN elsewhere).

        ``u*(e') = j / G(e')`` with G increasing: ``u_lo = j / G(e+)`` and
        ``u_hi = j / G(e)``, G enclosed at the two floats and the quotients
        rounded outward.  The width is the arc's drop over one ulp of e plus
        rounding: a tube of a few ulps, evaluated where it is asked for.
        """
        e = np.atleast_1d(np.asarray(e, float))
        e_up = np.nextafter(e, np.inf)
        inside = np.zeros(e.size, bool)
        order = np.argsort(self.e_a)
        ea, eb = self.e_a[order], self.e_b[order]
        i = np.clip(np.searchsorted(ea, e, side="right") - 1, 0, ea.size - 1)
        for shift in (0, 1):  # [e, e+] may end in the next piece
            k = np.clip(i + shift, 0, ea.size - 1)
            inside |= (ea[k] <= e) & (e_up <= eb[k]) & self.proven[order[k]]
        lo = np.full(e.size, np.nan)
        hi = np.full(e.size, np.nan)
        if inside.any():
            x, x_up = e[inside], e_up[inside]
            G_lo = _g(x, self.prefix, self.index, derivative=False)[0][0]
            G_hi = _g(x_up, self.prefix, self.index, derivative=False)[0][1]
            lo[inside] = np.nextafter(self.step / G_hi, -np.inf)
            hi[inside] = np.nextafter(self.step / G_lo, np.inf)
        return lo, hi

    def verify(self):
        """Re-prove every piece as stored (a tampered piece is rejected):
        a bool per piece."""
        ok = np.zeros(self.e_a.size, bool)
        for c in range(0, ok.size, _CHUNK):
            at = slice(c, c + _CHUNK)
            ok[at] = _prove(self.step, self.prefix, self.index, self.kind, self.e_a[at], self.e_b[at],
                            self.u_a[at], self.u_b[at], self.delta[at])
        return ok

    def to_dataframe(self):
        """The pieces as a pandas DataFrame."""
        import xarray as xr

        cols = {"e_a": self.e_a, "e_b": self.e_b, "u_a": self.u_a, "u_b": self.u_b,
                "delta": self.delta, "proven": self.proven}
        return xr.Dataset({k: ("piece", v) for k, v in cols.items()}).to_dataframe()


def _prove(j, prefix, index, kind, e_a, e_b, u_a, u_b, delta_stated=None):
    """The pieces' proof: the bound of ``|u* - l|`` (<= the stated delta when
    given), the prefix over each piece's box and the step's other decisions.
    Returns ``ok`` (and the bound when no delta is stated)."""
    n = e_a.size
    if n == 0:
        return (np.zeros(0, bool), np.zeros(0)) if delta_stated is None else np.zeros(0, bool)
    good = (e_a < e_b) & (e_a > 0) & (e_b < 1) & np.isfinite(u_a) & np.isfinite(u_b) & (u_a > 0) & (u_b > 0)
    delta, H, S, pts = _delta(j, prefix, index, e_a, e_b, u_a, u_b)
    d = delta if delta_stated is None else np.asarray(delta_stated, float)
    ok = good & (delta <= d)
    # the piece's box
    u0 = np.nextafter(np.minimum(u_a, u_b) - d, -np.inf)
    u1 = np.nextafter(np.maximum(u_a, u_b) + d, np.inf)
    ok &= u0 > 0
    u0 = np.where(u0 > 0, u0, 1.0)
    if len(prefix):
        itin = np.tile(np.asarray(prefix, np.int64), n)
        offsets = np.arange(n + 1, dtype=np.int64) * len(prefix)
        code, _ = verify_codes(e_a, e_b, u0, u1, np.full(n, _UNDECIDED_S), len(prefix), itin, offsets)
        ok &= code == 0
    if index >= 1:  # an impact event: no slide at step j (largest at (e_a, u0)) ...
        jj = _point(np.full(n, float(j)))
        T = _div_pos(jj, _point(u0))
        R, _ = _event_coef(pts[:n], 0)
        ok &= _sub(T, _add(H[:, :n], _mul_pos(R, S[:, :n])))[1] < 0.0
        if index >= 2:  # ... and the (index-1)-th impact happens (least at (e_b, u1))
            A, _ = _event_coef(pts[2 * n:], index - 1)
            ok &= _sub(_div_pos(jj, _point(u1)), _add(H[:, 2 * n:], _mul_pos(A, S[:, 2 * n:])))[0] >= 0.0
    return (ok, delta) if delta_stated is None else ok


def _u_star(j, prefix, index, e):
    """``j / G(e)`` in float (the midpoint of G's enclosure): a chord's ends."""
    G = _g(e, prefix, index, derivative=False)[0]
    return j / (0.5 * (G[0] + G[1]))


def _event_of_arc(arc, prefix_and_step):
    """``(prefix, index)`` of the arc from its middle point's itinerary."""
    flat, step_k = prefix_and_step
    j = arc.step
    prefix = tuple(int(k) for k in flat[:j - 1])
    if arc.kind == "chatter":
        return prefix, 0
    if arc.kind == "graze":
        return prefix, 1
    k = int(step_k)
    if k == SLIDING:
        raise ValueError("the arc's middle point slides at its step: not an edge arc")
    i = len(arc.e) // 2
    e, u = np.array([arc.e[i]]), float(arc.u[i])
    best = min((m for m in (k, k + 1) if m >= 2), key=lambda m: abs(j / u - j / _u_star(j, prefix, m, e)[0]))
    return prefix, best


def border_tube(arc, *, width=1e-12, window=None, max_pieces=200_000):
    """border_tube(arc, *, width=1e-12, window=None, max_pieces=200000) -> BorderTube

    A tube proven to contain the border arc that :func:`stairbounce.trace_border`
    followed, and on each vertical line no other point of it (issue 36, item 5).

    Along the arc's fixed itinerary the margin of its event at step ``j`` is
    exactly ``j/u - G(e)`` with ``G`` positive and increasing, so the arc is
    the graph ``u = j / G(e)``; the tube is cut into pieces over e, each a
    band ``|u - l(e)| <= delta`` around a chord, ``delta`` bounded by a
    mean-value form with outward-rounded intervals and the itinerary's
    decisions proven over the piece's box (the argument:
    ``stairbounce.structure.tubes``, docs/design.md).  Pieces are halved
    until ``2 delta <= width * window`` or ``max_pieces`` is reached.

    Parameters
    ----------
    arc : BorderArc from :func:`stairbounce.trace_border`
    width : float in (0, 1], default 1e-12
        The aimed tube width (``2 delta``) relative to ``window``.
    window : float > 0 or ((e0, e1), (u0, u1)), optional
        What widths are relative to: a size, or a window (its larger side).
        Default: the larger side of the arc's bounding box.
    max_pieces : int >= 1, default 200000

    Returns
    -------
    BorderTube
        The pieces, ``proven`` per piece, ``max_width`` (relative to the
        window), ``proven_fraction`` (of the arc's e-range), ``contains``
        and ``verify``.
    """
    width = _v.real("width", width)
    if not 0.0 < width <= 1.0:
        raise ValueError(f"width must be in (0, 1], got {width}")
    max_pieces = _v.count("max_pieces", max_pieces, 1)
    ae, au = np.asarray(arc.e, float), np.asarray(arc.u, float)
    if ae.size < 2 or not (np.isfinite(ae).all() and np.isfinite(au).all()):
        raise ValueError("arc must be a BorderArc with at least two finite points")
    if window is None:
        size = max(float(np.ptp(ae)), float(np.ptp(au)))
    elif np.ndim(window) == 0:
        size = _v.real("window", window)
    else:
        (e0, e1), (u0, u1) = window
        size = max(float(e1) - float(e0), float(u1) - float(u0))
    if not size > 0:
        raise ValueError(f"window must have a positive size, got {window!r}")
    j = int(arc.step)
    i = ae.size // 2
    flat, _, filled = _itineraries(ae[i:i + 1], au[i:i + 1], np.array([j]))
    if filled[0] < j - 1:
        raise ValueError("the arc's middle point slides before the arc's step")
    prefix, index = _event_of_arc(arc, (flat, flat[j - 1] if filled[0] >= j else SLIDING))
    target = 0.5 * width * size
    cuts = np.unique(ae)
    if cuts.size < 2:
        raise ValueError("the arc is vertical (one value of e): not a graph over e")
    e_a, e_b = cuts[:-1], cuts[1:]
    done = []
    n_done = 0
    fails = np.zeros(e_a.size, np.int64)
    while e_a.size:
        u_a = _u_star(j, prefix, index, e_a)
        u_b = _u_star(j, prefix, index, e_b)
        ok, delta = np.zeros(e_a.size, bool), np.zeros(e_a.size)
        for c in range(0, e_a.size, _CHUNK):  # bounded memory
            at = slice(c, c + _CHUNK)
            ok[at], delta[at] = _prove(j, prefix, index, arc.kind, e_a[at], e_b[at], u_a[at], u_b[at])
        mid = 0.5 * (e_a + e_b)
        split = ~(ok & (delta <= target)) & (mid > e_a) & (mid < e_b)
        # a piece whose decisions fail is halved at most _FAIL_DEPTH times in
        # a row (towards a corner, or where the decisions' margins shrink, as
        # the bounces e^k do near e = 0); then it stays unproven
        fails = np.where(ok, 0, fails + 1)
        split &= fails <= _FAIL_DEPTH
        if n_done + e_a.size + int(split.sum()) > max_pieces:
            split[:] = False  # the budget is spent: these pieces are final
        keep = ~split
        done.append((e_a[keep], e_b[keep], u_a[keep], u_b[keep], delta[keep], ok[keep]))
        n_done += int(keep.sum())
        e_a, e_b = np.concatenate([e_a[split], mid[split]]), np.concatenate([mid[split], e_b[split]])
        fails = np.concatenate([fails[split], fails[split]])
    cols = [np.concatenate(c) for c in zip(*done)]
    order = np.argsort(cols[0])
    ea, eb, ua, ub, dl, ok = (c[order] for c in cols)
    return BorderTube(arc.kind, j, prefix, index, ea, eb, ua, ub, dl, ok.astype(bool), size)
