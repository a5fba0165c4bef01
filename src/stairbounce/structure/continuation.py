"""Continuation: the arcs of a region's boundary followed by pseudo-arclength
continuation on the margins of :func:`.itinerary._margins` (:class:`_Margins`,
:func:`_follow`, Newton's corrector :func:`_correct`), their corners located by
Newton's method on two margins (:func:`_corner`, :func:`_locate_corner`), and a
boundary walked from corner to corner (:func:`_walk`).  The points are fixed
by the margins' signs; the derivatives only steer Newton's method.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..model import SLIDING
from .itinerary import _margins


# --------------------------------------------------------------------------- #
# Continuation                                                                #
# --------------------------------------------------------------------------- #

_EPS = np.finfo(float).eps
# largest turn of the tangent per step (radians): keeps the chords' sagitta small
# and the cubic Hermite area correction accurate to O(h^5) per step
_MAX_TURN = 0.08
_NEWTON = 8


class _Margins:
    """The margins of one prescribed itinerary (and a window) as a function of (e, u)."""

    def __init__(self, ks, window, y0=1.0, v0=0.0):
        self.ks = np.ascontiguousarray(ks, dtype=np.int64)
        self.n = self.ks.size
        self.win = np.asarray(window, dtype=float).reshape(4)
        self.y0, self.v0 = float(y0), float(v0)
        self.m = 2 * self.n + 4
        self.evals = 0

    def __call__(self, x):
        g = np.empty(self.m)
        ge = np.empty(self.m)
        gu = np.empty(self.m)
        if not (x[0] < 1.0 and x[1] > 0.0):
            # a Newton or continuation step out of the parameter domain (u <= 0 next to
            # a window at u = 1e-150: T = 1/u divided by zero, report round 3, R6): no
            # margins there, as where the itinerary leaves the domain (e an ulp below
            # 0, beside a window side at e = 0, is evaluated: the walk follows that side)
            g.fill(math.nan)
            ge.fill(math.nan)
            gu.fill(math.nan)
            self.evals += 1
            return g, ge, gu
        _margins(x[0], x[1], self.y0, self.v0, self.ks, self.n, self.win, g, ge, gu)
        self.evals += 1
        return g, ge, gu

    def inside(self, g):
        """Whether margins ``g`` say the point is in the region (lower >= 0, upper > 0)."""
        n2 = 2 * self.n
        return bool(np.all(g[0:n2:2] >= 0.0) and np.all(g[1:n2:2] > 0.0) and np.all(g[n2:] >= 0.0))

    def event(self, c):
        """(kind, step) of margin ``c``: step 0 and kind ``window`` for the window's sides."""
        if c >= 2 * self.n:
            return "window", 0
        j, side = divmod(c, 2)
        k = int(self.ks[j])
        if k == SLIDING:
            return "chatter", j + 1
        if side == 1:  # t_{k+1} = T
            return ("graze" if k == 0 else "edge"), j + 1
        return ("graze" if k == 1 else "edge"), j + 1


def _unit(a, b):
    n = math.hypot(a, b)
    return (a / n, b / n) if n > 0 and math.isfinite(n) else (math.nan, math.nan)


def _tangent(ge, gu, sign):
    """Unit tangent of ``g = 0`` with ``g >= 0`` on its left (sign +1) or right (-1)."""
    t0, t1 = _unit(gu, -ge)
    return sign * t0, sign * t1


def _ulps(x):
    return 4.0 * _EPS * max(abs(x[0]), abs(x[1]), 1e-300)


# a margin within this many ulps of the position (times its gradient) of zero is zero
# to rounding: along a long itinerary the margins are exact to about one ulp of the
# position, but their rounding errors are 1e-14 .. 1e-13 in value (gradients of 1e2 .. 1e3)
_ROUND_ULPS = 32.0


def _noise(g, x):
    """Per-margin rounding tolerance at ``x`` (margins ``g = (values, d/de, d/du)``):
    the change of each margin over ``_ROUND_ULPS`` ulps of the position."""
    return _ROUND_ULPS * _EPS * max(abs(x[0]), abs(x[1]), 1.0) * (np.abs(g[1]) + np.abs(g[2]))


def _solve2(a, b, c, d, r0, r1):
    """Solve [[a, b], [c, d]] z = (r0, r1); None when singular (Python floats:
    an overflow is inf, quietly, and then rejected by the caller)."""
    a, b, c, d, r0, r1 = float(a), float(b), float(c), float(d), float(r0), float(r1)
    det = a * d - b * c
    if not det or not math.isfinite(det):
        return None
    return (r0 * d - b * r1) / det, (a * r1 - c * r0) / det


def _correct(F, a, xp, t):
    """Pseudo-arclength corrector: ``g_a(x) = 0`` on the line through ``xp`` normal
    to ``t``.  Returns (x, margins, iterations) or None when Newton fails."""
    x = np.array(xp, dtype=float)
    for it in range(1, _NEWTON + 1):
        g, ge, gu = F(x)
        if not math.isfinite(g[a]):
            return None
        z = _solve2(ge[a], gu[a], t[0], t[1], -g[a], -(t[0] * (x[0] - xp[0]) + t[1] * (x[1] - xp[1])))
        if z is None:
            return None
        x[0] += z[0]
        x[1] += z[1]
        if abs(z[0]) + abs(z[1]) <= _ulps(x):
            return x, F(x), it
    return None


def _corner(F, a, b, x):
    """Newton's method on ``g_a = g_b = 0`` from ``x``: the corner to rounding, or None."""
    x = np.array(x, dtype=float)
    for _ in range(40):
        g, ge, gu = F(x)
        z = _solve2(ge[a], gu[a], ge[b], gu[b], -g[a], -g[b])
        if z is None or not (math.isfinite(z[0]) and math.isfinite(z[1])):
            return None
        x[0] += z[0]
        x[1] += z[1]
        if abs(z[0]) + abs(z[1]) <= _ulps(x):
            return x, F(x)
    return None


def _corner_on_arc(F, a, b, x, y):
    """The corner of ``g_a = 0`` and ``g_b = 0`` between the points ``x`` and ``y``
    of ``g_a = 0`` (``g_b(x) >= 0 > g_b(y)``) by bisection along the arc: points
    of the chord projected onto ``g_a = 0`` along its normal, halved until they
    are a few ulps apart.  Where the two curves cross at a very small angle (the
    margins of the same step in consecutive repeats of a long word), 2-D Newton
    cannot settle: the crossing is then fixed along the arc only to the
    margins' rounding, and this finds a point of ``g_a = 0`` where ``g_b``
    changes sign.  Returns (x, margins) at the end where ``g_b >= 0``, or None."""
    x = np.array(x, dtype=float)
    y = np.array(y, dtype=float)
    gx = F(x)
    if not gx[0][b] >= 0.0:
        return x, gx
    t = _unit(y[0] - x[0], y[1] - x[1])
    for _ in range(200):
        if math.hypot(y[0] - x[0], y[1] - x[1]) <= _ulps(x):
            break
        mid = 0.5 * (x + y)
        r = _correct(F, a, mid, t)
        if r is None:
            return None
        m = r[0]
        if (m == x).all() or (m == y).all():
            break
        if r[1][0][b] >= 0.0:
            x, gx = m, r[1]
        else:
            y = m
    return x, gx


def _into_window(F, x, g):
    """``x`` (margins ``g``) moved onto the window where rounding left it just
    outside: a point located where several margins vanish at once (a corner on
    e = 0, where the margins of many steps meet) is accepted with every other
    margin >= -its rounding, the window's too (report round 3, R13: e =
    -2.7e-17).  The window's sides are exact lines, so the point is clipped to
    them and its margins evaluated again; unchanged inside."""
    w = F.win
    c = np.array([min(max(x[0], w[0]), w[1]), min(max(x[1], w[2]), w[3])])
    if c[0] == x[0] and c[1] == x[1]:
        return x, g
    return c, F(c)


@dataclass
class _Arc:
    slot: int
    pts: list
    tans: list
    end: str = ""            # corner, closed, window, junction, domain, limit
    end_slot: int = -1
    area: tuple | None = None  # (area, error) of the closed curve that starts with this arc


def _follow(F, a, x, g, sign, scale, *, others, stop_at=None, max_points=20000, junction=None):
    """Follow ``g_a = 0`` from ``x`` (margins ``g``) with the region on the left
    (sign +1) or right (-1), until another margin in ``others`` turns negative
    (a corner, located to rounding), the start ``stop_at`` is passed again (a
    closed curve), ``junction(x_prev, x)`` reports a change, or the curve
    leaves the domain (a margin turns NaN)."""
    gg, ge, gu = g
    t = _tangent(ge[a], gu[a], sign)
    tol = _noise(g, x)
    arc = _Arc(a, [np.array(x, float)], [t])
    h = 1e-3 * scale
    hmin = 1e-14 * scale
    hmax = 0.02 * scale
    labour = 0  # consecutive points where Newton barely settled
    while True:
        if len(arc.pts) > max_points:
            arc.end = "limit"
            return arc
        xp = (x[0] + h * t[0], x[1] + h * t[1])
        res = _correct(F, a, xp, t)
        ok = res is not None
        if ok:
            y, gy, it = res
            tn = _tangent(gy[1][a], gy[2][a], sign)
            cos = t[0] * tn[0] + t[1] * tn[1]
            ok = math.isfinite(cos) and cos > math.cos(_MAX_TURN) and \
                math.hypot(y[0] - xp[0], y[1] - xp[1]) <= 0.25 * h
        if ok and np.isnan(gy[0][others]).any():
            ok = False
        if not ok:
            h *= 0.25
            if h < hmin:
                arc.end = "domain"
                return arc
            continue
        gyv = gy[0]
        # a margin that is zero to rounding at x (at a corner, or along a curve that
        # coincides with this one to rounding) crosses only when clearly negative
        to, go, yo = tol[others], gg[others], gyv[others]
        active = np.abs(go) <= to
        neg = others[np.where(active, yo < -to, (yo < 0.0) & ((go > 0.0) | (yo < go)))]
        if stop_at is not None:
            # closed when the start lies on the chord x -> y
            dx, dy = y[0] - x[0], y[1] - x[1]
            L2 = dx * dx + dy * dy
            tau = ((stop_at[0] - x[0]) * dx + (stop_at[1] - x[1]) * dy) / L2 if L2 > 0.0 else math.nan
            if 0.0 < tau <= 1.0 and abs((stop_at[0] - x[0]) * dy - (stop_at[1] - x[1]) * dx) <= \
                    1e-6 * L2 and len(arc.pts) > 2:
                arc.pts.append(np.array(stop_at, float))
                arc.tans.append(arc.tans[0])
                arc.end = "closed"
                return arc
        if neg.size:
            cx = _locate_corner(F, a, x, gg, y, gyv, neg, others)
            if cx is None:
                h *= 0.25
                if h < hmin:
                    arc.end = "domain"
                    return arc
                continue
            xc, b, gc = cx
            arc.pts.append(xc)
            arc.tans.append(_tangent(gc[1][a], gc[2][a], sign))
            arc.end, arc.end_slot = "corner", b
            arc.corner_margins = gc
            return arc
        if junction is not None:
            jx = junction(x, y)
            if jx is not None:
                arc.pts.append(jx[0])
                arc.tans.append(_tangent(jx[1][1][a], jx[1][2][a], sign))
                arc.end = "junction"
                arc.junction = jx
                return arc
        arc.pts.append(y)
        arc.tans.append(tn)
        x, gg, t = y, gyv, tn
        tol = _noise(gy, y)
        # Newton converging only linearly point after point: the margin is not smooth
        # to rounding here (a step whose k-th and (k+1)-th impacts coincide to rounding,
        # a sliver of no width): the step would never grow, so the arc ends
        labour = labour + 1 if it >= _NEWTON - 1 else 0
        if labour > 50:
            arc.end = "domain"
            return arc
        if it <= 2 and cos > math.cos(0.5 * _MAX_TURN):
            h = min(1.6 * h, hmax)


def _locate_corner(F, a, x, gx, y, gy, neg, others):
    """The first margin of ``neg`` to vanish between x and y, and the corner where
    it meets ``g_a = 0`` (Newton from the linear estimate; retried with another
    margin when one of the others is then negative)."""
    lam = np.clip(gx[neg] / (gx[neg] - gy[neg]), 0.0, 1.0)
    order = np.argsort(lam)
    step = math.hypot(y[0] - x[0], y[1] - x[1])
    for i in order:
        b = int(neg[i])
        x0 = (x[0] + lam[i] * (y[0] - x[0]), x[1] + lam[i] * (y[1] - x[1]))
        # 2-D Newton; where it does not settle or lands off the arc (the curves cross
        # at a tiny angle), the crossing along the arc
        for solve in (lambda: _corner(F, a, b, x0), lambda: _corner_on_arc(F, a, b, x, y)):
            r = solve()
            if r is None:
                continue
            xc, gc = r
            rest = others[others != b]
            tol = np.maximum(_noise(gc, xc)[rest], 1e3 * _EPS * max(abs(xc[0]), abs(xc[1]), 1.0))
            if np.all(gc[0][rest] >= -tol) and math.hypot(xc[0] - x[0], xc[1] - x[1]) <= 1.5 * step:
                xc, gc = _into_window(F, xc, gc)
                return xc, b, gc
    return None


def _walk(F, a0, x0, scale, max_corners=2000, max_points=50000):
    """Walk the boundary of one connected piece of the region of ``F`` through the
    boundary point ``x0`` of margin ``a0``, with the region on the left: the
    list of arcs of one closed curve (counter-clockwise around an outer
    boundary, clockwise around a hole), or None when the walk fails."""
    allc = np.arange(F.m)
    g = F(x0)
    first = _follow(F, a0, x0, g, 1, scale, others=allc[allc != a0], stop_at=x0, max_points=max_points)
    if first.end == "closed":
        return [first]
    if first.end != "corner":
        return None
    start = (first.pts[-1], a0, first.end_slot)
    arcs = []
    x, g = first.pts[-1], first.corner_margins
    a = _outgoing(g, a0, first.end_slot, scale)
    start = (x, a0, a)
    used = len(first.pts)
    stuck = 0
    visited = {}
    for _ in range(max_corners):
        arc = _follow(F, a, x, g, 1, scale, others=allc[allc != a], max_points=max_points - used)
        used += len(arc.pts)
        if arc.end == "corner" and math.hypot(x[0] - arc.pts[-1][0], x[1] - arc.pts[-1][1]) == 0.0:
            stuck += 1
            if stuck > 8:  # turning in place at a point where many margins vanish
                return None
        else:
            stuck = 0
        if arc.end != "corner" or used > max_points:
            return None
        arc.start_slot = arcs[-1].slot if arcs else start[1]
        arcs.append(arc)
        x, g = arc.pts[-1], arc.corner_margins
        a = _outgoing(g, arc.slot, arc.end_slot, scale)
        if arc.slot == start[1] and a == start[2] and \
                math.hypot(x[0] - start[0][0], x[1] - start[0][1]) <= 1e-9 * scale:
            arc.pts[-1] = start[0]  # the same corner: close exactly
            return arcs
        # a corner passed before, but not the start: the walk goes round a loop that
        # does not lead back (two margins that coincide to rounding, a sliver of no
        # width): it fails now rather than at its point budget
        seen = visited.setdefault((arc.slot, a), [])
        if any(math.hypot(x[0] - p[0], x[1] - p[1]) <= 1e-9 * scale for p in seen):
            return None
        seen.append(x)
    return None


def _outgoing(g, a, b, scale):
    """The margin to follow out of a corner reached along ``a`` where ``b``
    vanished: where more than two margins vanish at once (a resonance of the
    itinerary), the one whose tangent keeps every other vanishing margin
    non-negative to first order (the edge of the region's tangent cone)."""
    gv, ge, gu = g
    cand = np.nonzero(np.abs(gv) <= 1e3 * _EPS * scale * (np.abs(ge) + np.abs(gu)))[0]
    cand = [int(c) for c in cand if c != a]
    if b not in cand:
        cand.insert(0, b)
    if len(cand) == 1:
        return b
    best, worst_best = b, -math.inf
    for c in cand:
        t = _tangent(ge[c], gu[c], 1)
        worst = min((ge[o] * t[0] + gu[o] * t[1]) / math.hypot(ge[o], gu[o])
                    for o in cand + [a] if o != c)
        if worst > worst_best + 1e-12:
            best, worst_best = c, worst
    return best
