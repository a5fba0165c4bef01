"""Borders as curves: continuation of the arcs, their corners, each word's region
as a polygon (docs/guide/regions.md).

Along a fixed itinerary (the impact numbers ``k_1, k_2, ...`` of the steps from
the departure at ``(1, 0)``) the state at every edge is a smooth closed-form
function of ``(e, u)``, and so is every margin of the map's three decisions on a
step (the sliding test (2.4), the first contact, the next impact).  The region
of a word is therefore an intersection of smooth inequalities

    g_c(e, u) >= 0,   c = 1, 2, ...,

two per step (the step keeps its impact number ``k``: ``t_k <= T`` and
``T < t_{k+1}``; ``k = 0``: ``T < t_1``; the sliding step: ``t_inf <= T``)
and four for the window.  Its boundary is made of arcs ``g_c = 0`` joined at
corners where two margins vanish at once.  This module follows the arcs by
pseudo-arclength continuation, locates the corners by Newton's method on the
two margins, and walks each connected component of a region around its boundary.

The margins are evaluated by :func:`_margins` with exactly the arithmetic of
:func:`stairbounce.model._step` (the same operations in the same order, so the
sign of a margin is the map's decision bit for bit), and their derivatives by
forward-mode differentiation written out by hand (exact derivatives of the
closed forms, evaluated in floating point; they only steer Newton's method, the
points themselves are fixed by the margins' signs).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np
from numba import get_num_threads, njit, prange

from . import _validate as _v
from .model import (
    SLIDING,
    _COUNTED_IMPACTS,
    _constants,
    _geometric,
    _impact_time_log,
    _step,
    check_count,
    check_e,
    check_state,
    check_u,
)
from .symbolic import Word, parse_word, word_from_impacts

__all__ = ["BorderArc", "Corner", "Region", "RegionComponent", "BorderGraph",
           "trace_border", "word_region", "window_regions", "border_graph",
           "regions_geojson", "regions_svg", "write_regions", "band_similarity"]

# --------------------------------------------------------------------------- #
# Compiled margins along a prescribed itinerary                                #
# --------------------------------------------------------------------------- #


@njit(cache=True)
def _margins(e, u, y0, v0, ks, nsteps, win, g, ge, gu):
    """Every margin of the itinerary ``ks[:nsteps]`` and of the window at (e, u).

    Fills ``g[2j]`` (lower) and ``g[2j+1]`` (upper) for step ``j+1``, with
    ``ge``, ``gu`` their derivatives in e and u, and ``g[2n..2n+3]`` the window
    margins ``e - e_lo``, ``e_hi - e``, ``u - u_lo``, ``u_hi - u``.  The point
    belongs to the itinerary's region iff every lower margin is >= 0 and every
    upper margin is > 0 (exactly :func:`model._step`'s decisions):

    - ``k = 0``: upper ``t_1 - T`` (it flies over iff ``t_1 > T``), no lower;
    - ``1 <= k``: lower ``T - t_k``, upper ``t_{k+1} - T`` (``t`` summed along
      the geometric series as ``_step`` does, closed form past
      ``_COUNTED_IMPACTS`` impacts as ``_step_closed`` does);
    - ``SLIDING``: lower ``T - (v + (1+e)/(1-e) s)`` (the test (2.4)), no upper.

    A missing margin is +inf.  Returns the number of steps evaluated: less than
    ``nsteps`` when the prescribed itinerary leaves the domain (a negative
    ``v^2 + 2y``); the margins of the remaining steps are then NaN.
    """
    T, ratio = _constants(e, u)
    Tu = -T * T
    re_ = 2.0 / ((1.0 - e) * (1.0 - e))
    log_e = math.log(e) if e > 0.0 else -math.inf
    y, v = y0, v0
    ye = 0.0
    yu = 0.0
    ve = 0.0
    vu = 0.0
    m = 2 * nsteps
    g[m] = e - win[0]
    ge[m] = 1.0
    gu[m] = 0.0
    g[m + 1] = win[1] - e
    ge[m + 1] = -1.0
    gu[m + 1] = 0.0
    g[m + 2] = u - win[2]
    ge[m + 2] = 0.0
    gu[m + 2] = 1.0
    g[m + 3] = win[3] - u
    ge[m + 3] = 0.0
    gu[m + 3] = -1.0
    for j in range(nsteps):
        k = ks[j]
        q = v * v + 2.0 * y
        if not q >= 0.0 or (q == 0.0 and k != 0):
            for i in range(2 * j, m):
                g[i] = math.nan
                ge[i] = math.nan
                gu[i] = math.nan
            return j
        s = math.sqrt(q)
        se = (v * ve + ye) / s if s > 0.0 else 0.0
        su = (v * vu + yu) / s if s > 0.0 else 0.0
        lo = 2 * j
        hi = lo + 1
        if k == SLIDING:
            c = v + ratio * s
            g[lo] = T - c
            ge[lo] = -(ve + re_ * s + ratio * se)
            gu[lo] = Tu - (vu + ratio * su)
            g[hi] = math.inf
            ge[hi] = 0.0
            gu[hi] = 0.0
            y, v = 1.0, 0.0
            ye = yu = ve = vu = 0.0
            continue
        t = v + s
        te = ve + se
        tu = vu + su
        if k == 0:
            g[lo] = math.inf
            ge[lo] = 0.0
            gu[lo] = 0.0
            g[hi] = t - T
            ge[hi] = te
            gu[hi] = tu - Tu
            ny = y + v * T - 0.5 * T * T + 1.0
            nye = ye + ve * T
            nyu = yu + vu * T + v * Tu - T * Tu
            v = v - T
            vu = vu - Tu
            y, ye, yu = ny, nye, nyu
            continue
        # k >= 1: the bounces along the geometric series, as _step counts them
        w = e * s
        we = s + e * se
        wu = e * su
        kk = min(k, _COUNTED_IMPACTS)
        for _ in range(kk - 1):
            t = t + 2.0 * w
            te = te + 2.0 * we
            tu = tu + 2.0 * wu
            we = w + e * we
            wu = e * wu
            w *= e
        # lower margin: t_k (t_8 of the loop when k = 8, as _step decides 7 <-> 8)
        g[lo] = T - t
        ge[lo] = -te
        gu[lo] = Tu - tu
        if k < _COUNTED_IMPACTS:
            nt = t + 2.0 * w
            g[hi] = nt - T
            ge[hi] = te + 2.0 * we
            gu[hi] = tu + 2.0 * wu - Tu
            d = T - t
            de = -te
            du = Tu - tu
        else:
            # _step_closed: closed forms of eq. (2.2) with G(n) = (1 - e^n)/(1 - e)
            G = _geometric(e, k - 1, log_e)
            Ge = (G - (k - 1) * math.pow(e, float(k - 2))) / (1.0 - e)
            tk = _impact_time_log(v, s, e, k, log_e)
            tke = ve + se * (1.0 + 2.0 * e * G) + 2.0 * s * (G + e * Ge)
            tku = vu + su * (1.0 + 2.0 * e * G)
            if k > _COUNTED_IMPACTS:
                g[lo] = T - tk
                ge[lo] = -tke
                gu[lo] = Tu - tku
            G1 = _geometric(e, k, log_e)
            G1e = (G1 - k * math.pow(e, float(k - 1))) / (1.0 - e)
            g[hi] = _impact_time_log(v, s, e, k + 1, log_e) - T
            ge[hi] = ve + se * (1.0 + 2.0 * e * G1) + 2.0 * s * (G1 + e * G1e)
            gu[hi] = vu + su * (1.0 + 2.0 * e * G1) - Tu
            ek = math.pow(e, float(k))
            w = ek * s
            we = k * math.pow(e, float(k - 1)) * s + ek * se
            wu = ek * su
            d = min(max(T - tk, 0.0), 2.0 * w)
            de = -tke
            du = Tu - tku
        ny = -0.5 * d * d + w * d + 1.0
        nye = -d * de + we * d + w * de
        nyu = -d * du + wu * d + w * du
        v = w - d
        ve = we - de
        vu = wu - du
        y, ye, yu = ny, nye, nyu
    return nsteps


@njit(cache=True)
def _itinerary_of(e, u, y0, v0, max_iter, ks):
    """Impact numbers from (y0, v0) with :func:`model._step` until the slide:
    fills ``ks`` and returns the step count (the sliding step included), or
    ``-max_iter`` when it does not slide within ``max_iter`` steps."""
    T, ratio = _constants(e, u)
    y, v = y0, v0
    for n in range(max_iter):
        y, v, k = _step(y, v, e, T, ratio)
        ks[n] = k
        if k == SLIDING:
            return n + 1
    return -max_iter


@njit(cache=True, parallel=True)
def _words_grid(es, us, y0, v0, max_iter, h1, h2, steps):
    """Two independent 64-bit hashes of every pixel's itinerary (0, 0 and steps 0
    when it does not slide within max_iter): the word labels of a small scan.
    Rows in parallel, each pixel independent of the others."""
    for i in prange(us.size):
        ks = np.empty(max_iter, dtype=np.int64)
        for j in range(es.size):
            n = _itinerary_of(es[j], us[i], y0, v0, max_iter, ks)
            if n <= 0:
                h1[i, j] = 0
                h2[i, j] = 0
                steps[i, j] = 0
                continue
            h1[i, j], h2[i, j] = _hash_itinerary(ks, n)
            steps[i, j] = n


@njit(cache=True)
def _hash_itinerary(ks, n):
    """Two independent 64-bit hashes of ``ks[:n]`` (the word labels of a scan)."""
    a = np.uint64(1469598103934665603)
    b = np.uint64(7)
    for t in range(n):
        x = np.uint64(ks[t] + 2)
        a = (a ^ x) * np.uint64(1099511628211)
        b = b * np.uint64(6364136223846793005) + x * np.uint64(1442695040888963407)
    return a | np.uint64(1), b


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


_GAUSS = ((0.5 - math.sqrt(0.15), 5.0 / 18.0), (0.5, 8.0 / 18.0), (0.5 + math.sqrt(0.15), 5.0 / 18.0))


def _hermite_area(p0, p1, t0, t1):
    """Signed areas between the chords p0 -> p1 (arrays N x 2) and the cubic
    Hermite curves with unit tangents t0, t1 (scaled by the chord), exact by
    3-point Gauss (the integrand has degree 5)."""
    d = p1 - p0
    L = np.hypot(d[:, 0], d[:, 1])[:, None]
    m0, m1 = L * t0, L * t1
    total = np.zeros(len(p0))
    for s, w in _GAUSS:
        h10, h01, h11 = s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2
        d10, d01, d11 = 3 * s**2 - 4 * s + 1, -6 * s**2 + 6 * s, 3 * s**2 - 2 * s
        # position and velocity relative to p0 (the chord's own term cancels)
        r = h10 * m0 + h01 * d + h11 * m1
        v = d10 * m0 + d01 * d + d11 * m1
        total += w * 0.5 * (r[:, 0] * v[:, 1] - r[:, 1] * v[:, 0])
    return total


def _arc_area(pts, tans, stride=1, origin=(0.0, 0.0)):
    """Shoelace contribution of an arc plus the Hermite correction of its chords,
    on every ``stride``-th point (the ends always kept), on coordinates relative
    to ``origin`` (a point near the curve: on absolute coordinates each product
    rounds by about 1e-17, more than the whole area of a region below 1e-13;
    report round 3, R2).  Returns (area, sum of the magnitudes of its terms)."""
    idx = list(range(0, len(pts), stride))
    if idx[-1] != len(pts) - 1:
        idx.append(len(pts) - 1)
    P = np.asarray(pts, dtype=float)[idx] - np.asarray(origin, dtype=float)
    Tg = np.asarray(tans, dtype=float)[idx]
    p, q = P[:-1], P[1:]
    shoe = 0.5 * (p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1])
    herm = _hermite_area(p, q, Tg[:-1], Tg[1:])
    size = 0.5 * (np.abs(p[:, 0] * q[:, 1]) + np.abs(q[:, 0] * p[:, 1])) + np.abs(herm)
    return float(np.sum(shoe + herm)), float(np.sum(size))


def _position_rounding(arc, win, nsteps):
    """How far the points of ``arc`` may lie from the exact curve: for a side of
    the window (a margin ``e - e_lo`` etc., exact) the largest distance of a
    point from that line, computed; for a margin of the dynamics
    ``_ROUND_ULPS`` ulps of the position (the margins' zeros are exact to about
    an ulp of the position, ``_noise``; numerical, not proven)."""
    P = np.asarray(arc.pts, dtype=float)
    side = arc.slot - 2 * nsteps
    if win is not None and 0 <= side < 4:
        return float(np.abs(P[:, side // 2] - win[side]).max())
    return _ROUND_ULPS * _EPS * float(np.abs(P).max())


def _curve_area(arcs, F=None):
    """Signed area of a closed curve of arcs and an error estimate: the Hermite
    area on every point against every other point (the error is O(h^4),
    Richardson's factor 15), plus rounding: the points' distance from the
    exact curve times the arcs' lengths (:func:`_position_rounding`) and the
    floating-point sum's own rounding.  Coordinates are taken relative to the
    curve's first point, so a region of any size keeps its digits (the area
    of a closed curve does not depend on the origin).  Returns (area, error,
    the rounding part of the error)."""
    origin = np.array(arcs[0].pts[0], dtype=float)
    fine = coarse = size = moved = 0.0
    npts = 0
    win, nsteps = (F.win, F.n) if F is not None else (None, 0)
    for a in arcs:
        A, S = _arc_area(a.pts, a.tans, 1, origin)
        fine += A
        size += S
        coarse += _arc_area(a.pts, a.tans, 2, origin)[0]
        P = np.asarray(a.pts, dtype=float)
        length = float(np.hypot(*np.diff(P, axis=0).T).sum())
        moved += length * _position_rounding(a, win, nsteps)
        npts += len(a.pts)
    # pairwise sums (numpy) and the products and differences before them: a few
    # roundings of each term, plus log2 of their number
    rounding = moved + (8.0 + math.log2(max(npts, 2))) * _EPS * size
    return fine, abs(fine - coarse) / 15.0 + rounding, rounding


# --------------------------------------------------------------------------- #
# Regions                                                                     #
# --------------------------------------------------------------------------- #


def itinerary_of_word(word) -> np.ndarray:
    """The impact numbers of the steps of one period of ``word`` (the last one
    ``SLIDING``): the inverse of :func:`stairbounce.symbolic.word_from_impacts`."""
    letters = _as_word(word).letters
    ks = []
    i = 0
    while i < len(letters):
        ks.extend([0] * (letters[i] - 1))
        if i == len(letters) - 1:
            ks.append(SLIDING)
            break
        z = 0
        while letters[i + 1 + z] == 0:
            z += 1
        ks.append(1 + z)
        i += 1 + z
    return np.array(ks, dtype=np.int64)


def _as_word(word) -> Word:
    if isinstance(word, Word):
        w = word
    elif isinstance(word, str):
        try:
            w = parse_word(word)
        except ValueError as exc:  # the parser's message, named after the parameter
            if str(exc).startswith("word"):
                raise
            raise ValueError(f"word: {exc}") from None
    elif isinstance(word, (tuple, list, np.ndarray)):
        try:
            w = Word(tuple(word))
        except ValueError as exc:  # the letters' own message, named after the parameter
            raise ValueError(f"word: {exc}") from None
    else:  # bytes are not letters (report round 3, R6), None is not a word
        raise ValueError(f"word must be a Word, a string such as '(2, 0, 1, 0^inf)' or a tuple of "
                         f"letters such as (2, 0, 1), got {_v._show(word)}")
    # one step per letter's unit (its period): refused before a list of that length
    _check_steps("word", w.period, f"a word of period {w.period}")
    return w


@dataclass(frozen=True)
class Corner:
    """A point where two margins vanish at once: the events of both (kind, step)."""

    e: float
    u: float
    events: tuple

    def __repr__(self):
        a, b = self.events
        return f"Corner(e={self.e:.17g}, u={self.u:.17g}, {a[0]}@{a[1]} x {b[0]}@{b[1]})"


@dataclass
class BorderArc:
    """One traced arc: points ``e``, ``u`` on the curve where the margin of one
    event (``kind`` at ``step``) vanishes, between two ends."""

    e: np.ndarray
    u: np.ndarray
    kind: str
    step: int
    inside: str = ""        # the word on the side where the margin is >= 0
    outside: str = ""       # the word on the other side ("" where not computed)
    ends: tuple = ("", "")  # how each end was reached: corner, window, junction, domain, limit
    corners: tuple = (None, None)

    def __repr__(self):
        return (f"BorderArc({self.kind} at step {self.step}, {self.e.size} points, "
                f"{self.inside or '?'} | {self.outside or '?'}, ends {self.ends[0]}/{self.ends[1]})")


@dataclass
class RegionComponent:
    """One connected component of a word's region: its outer boundary and holes
    (closed curves of arcs, counter-clockwise and clockwise), exact area."""

    area: float
    area_error: float
    boundary: list           # BorderArc list of the outer curve
    holes: list              # list of BorderArc lists
    corners: list

    @property
    def kinds(self):
        """Counts of the outer boundary's arcs by kind."""
        out = {}
        for a in self.boundary + [a for h in self.holes for a in h]:
            out[a.kind] = out.get(a.kind, 0) + 1
        return out

    def polygon(self, hole=None):
        """``(e, u)`` of the closed outer boundary (or of hole number ``hole``)."""
        arcs = self.boundary if hole is None else self.holes[hole]
        e = np.concatenate([a.e[:-1] for a in arcs] + [arcs[0].e[:1]])
        u = np.concatenate([a.u[:-1] for a in arcs] + [arcs[0].u[:1]])
        return e, u

    def __repr__(self):
        return (f"RegionComponent(area={self.area:.6e} +- {self.area_error:.1e}, "
                f"{len(self.boundary)} arcs, {len(self.holes)} holes, kinds {self.kinds})")


@dataclass
class Region:
    """Every component of the region of one word in a window."""

    word: Word
    e: tuple
    u: tuple
    components: list = field(default_factory=list)
    complete: bool = True    # False when a seed's walk failed (see ``failures``)
    failures: int = 0

    @property
    def area(self) -> float:
        return float(sum(c.area for c in self.components))

    @property
    def area_error(self) -> float:
        return float(sum(c.area_error for c in self.components))

    @property
    def corners(self):
        return [c for comp in self.components for c in comp.corners]

    @property
    def found(self) -> bool:
        """Whether the word was found in the window (at least one component traced)."""
        return bool(self.components)

    def __repr__(self):
        if not self.found and self.complete:
            return (f"Region({self.word.format(ascii=True)}: not found in the window "
                    f"e = [{self.e[0]:g}, {self.e[1]:g}], u = [{self.u[0]:g}, {self.u[1]:g}])")
        return (f"Region({self.word.format(ascii=True)}: area {self.area:.6e} +- "
                f"{self.area_error:.1e} in {len(self.components)} components"
                f"{'' if self.complete else ', INCOMPLETE'})")


_MAX_STEPS = 2**31 - 1  # as every max_iter of the package (borders, plane)


def _check_steps(name, steps, what):
    """``steps`` (an itinerary's length: a max_iter or a word's period) within
    ``[1, 2**31 - 1]`` and within memory: a buffer of that many int64 per
    thread of the seed scan, and the margins (two per step, with their two
    derivatives) of the walks."""
    if steps > _MAX_STEPS:
        raise ValueError(f"{name} must have at most {_MAX_STEPS} (2**31 - 1) steps, got {what}")
    _v.check_memory(what, 8 * steps * (get_num_threads() + 1) + 48 * steps)
    return steps


def _check_run(y0, v0, max_iter):
    """The start and the step limit of word_region, window_regions and
    trace_border, checked as :func:`stairbounce.itinerary` checks them
    (:func:`stairbounce.model.check_state`: ``0 <= y0 <= 1e300``, ``|v0| <=
    1e150``; ``1 <= max_iter <= 2**31 - 1``, its buffers within memory)."""
    y0, v0 = check_state(y0, v0, "y0", "v0")
    max_iter = check_count("max_iter", max_iter, 1, _MAX_STEPS)
    _check_steps("max_iter", max_iter, f"max_iter = {max_iter}")
    return y0, v0, max_iter


def _check_centres(es):
    """The seed scan's pixel centres along e: none in (0, 2^-53), where e is
    lost to rounding (as :func:`stairbounce.scan` refuses them)."""
    tiny = es[_v.e_too_small(es)]
    if tiny.size:
        raise ValueError(f"{_v.E_TINY_RULE}, got a window whose pixel centres include e = {tiny[0]:.3g}")


# The margins need e < 1 and u > 0: a window's edges e = 1 and u = 0 (image
# edges, allowed as in stairbounce.scan, whose pixel centres lie inside) are
# traced at these instead (as the explorer and word_table's traced columns do)
_E_TOP = 1.0 - 1e-12
_DEFAULT_RESOLUTION = 256
_U_BOTTOM = 1e-9


def _check_window(e, u):
    """The windows ``e``, ``u`` (each ``(lo, hi)`` or ``(lo, hi, n)``, image
    edges within [0, 1] and [0, 1e150] as in :func:`stairbounce.scan`) ->
    the traced window ``(e_lo, e_hi), (u_lo, u_hi)``, e = 1 and u below the
    valid range (0) moved inside the domain (``_E_TOP``, ``_U_BOTTOM``)."""
    (e_lo, e_hi, _), (u_lo, u_hi, _) = _image_window(e, u)
    if _v.e_too_small(e_lo) or _v.e_too_small(e_hi):
        raise ValueError(f"{_v.E_TINY_RULE}, got the e window [{e_lo}, {e_hi}]")
    # only the edges outside the map's domain move: every window valid before
    # (e_max < 1, u_min >= 1e-150) is traced as it was
    return ((e_lo, _E_TOP if e_hi >= 1.0 else e_hi),
            (max(u_lo, _U_BOTTOM) if u_lo < _v.U_MIN else u_lo, u_hi))


def _image_window(e, u):
    """``e``, ``u`` as checked triples ``(lo, hi, n or None)`` of image edges."""
    e_lo, e_hi, n_e = _v.window("e", e)
    u_lo, u_hi, n_u = _v.window("u", u)
    e_lo, e_hi = float(_v.real("e_min", e_lo)), float(_v.real("e_max", e_hi))
    u_lo, u_hi = float(_v.real("u_min", u_lo)), float(_v.real("u_max", u_hi))
    if not 0.0 <= e_lo < e_hi <= 1.0:
        raise ValueError(f"e window must satisfy 0 <= e_min < e_max <= 1 (image edges), got [{e_lo}, {e_hi}]")
    # u_min below the valid range (the edge u = 0) is traced from _U_BOTTOM, so
    # u_max must lie above it; a window inside [1e-150, 1e-9] is traced as given
    if not (0.0 <= u_lo < u_hi <= _v.U_MAX) or (u_lo < _v.U_MIN and u_hi <= _U_BOTTOM):
        raise ValueError(f"u window must satisfy 0 <= u_min < u_max <= {_v.U_MAX:g} (image edges), and "
                         f"u_max > {_U_BOTTOM:g} when u_min < {_v.U_MIN:g}, got [{u_lo}, {u_hi}]")
    if e_lo >= _E_TOP:
        raise ValueError(f"e window must have e_min < {_E_TOP!r} (the margins need e < 1), got [{e_lo}, {e_hi}]")
    n_e = None if n_e is None else check_count("n_e", n_e, 2, 8192)
    n_u = None if n_u is None else check_count("n_u", n_u, 2, 8192)
    return (e_lo, e_hi, n_e), (u_lo, u_hi, n_u)


def _seed_grid(e, u, resolution):
    """The traced window and the seed scan's pixel centres of :func:`word_region`
    and :func:`window_regions`: ``(e, u, es, us)``.  The seed pixels are the
    windows' own counts ``(lo, hi, n)``, or ``resolution`` along each axis
    (default 256) for ``(lo, hi)``; a count given both ways is refused, never
    ignored."""
    ew, uw = _image_window(e, u)
    given = [w[2] for w in (ew, uw) if w[2] is not None]
    if given and resolution is not None:
        raise ValueError(f"resolution = {resolution!r} and the pixel counts of e = {tuple(e)!r}, u = "
                         f"{tuple(u)!r}: give the seed pixels once, as (lo, hi, n) windows or as resolution")
    resolution = _DEFAULT_RESOLUTION if resolution is None else check_count("resolution", resolution, 2, 8192)
    n_e = resolution if ew[2] is None else ew[2]
    n_u = resolution if uw[2] is None else uw[2]
    es, us = _grid(ew, uw, n_e, n_u)
    te, tu = _check_window(e, u)
    if es[-1] > te[1] or us[0] < tu[0]:
        raise ValueError(f"the window e = [{ew[0]}, {ew[1]}], u = [{uw[0]}, {uw[1]}] has seed pixel centres "
                         f"beyond e = {_E_TOP!r} or below u = {_U_BOTTOM:g}, where the margins are not "
                         "traced: narrow the window away from e = 1 and u = 0")
    return te, tu, es, us, ((ew[1] - ew[0]) / n_e, (uw[1] - uw[0]) / n_u)


def _grid(e, u, n_e, n_u=None):
    """The pixel centres of ``n_e`` x ``n_u`` (default ``n_e``) seed pixels of the window."""
    n_u = n_e if n_u is None else n_u
    es = e[0] + (np.arange(n_e) + 0.5) * (e[1] - e[0]) / n_e
    us = u[0] + (np.arange(n_u) + 0.5) * (u[1] - u[0]) / n_u
    return es, us


def _label_grid(es, us, max_iter, y0, v0):
    h1 = np.empty((us.size, es.size), dtype=np.uint64)
    h2 = np.empty_like(h1)
    steps = np.empty((us.size, es.size), dtype=np.int64)
    _words_grid(es, us, y0, v0, max_iter, h1, h2, steps)
    return h1, h2, steps


def _label_grid_slices(es, us, max_iter, y0, v0, slice_work):
    """:func:`_label_grid` in blocks of at most ``slice_work`` potential map
    steps (``max_iter`` per pixel; :func:`stairbounce.borders.grid_blocks`),
    yielding ``(0, None)`` after each block (nothing when ``slice_work`` is
    None: one call); returns the same arrays (pixels are independent)."""
    if slice_work is None:
        return _label_grid(es, us, max_iter, y0, v0)
    from .borders import grid_blocks

    h1 = np.empty((us.size, es.size), dtype=np.uint64)
    h2 = np.empty_like(h1)
    steps = np.empty((us.size, es.size), dtype=np.int64)
    for r, c in grid_blocks(es.size, us.size, max_iter, slice_work):
        h1[r, c], h2[r, c], steps[r, c] = _label_grid(es[c], us[r], max_iter, y0, v0)
        yield 0, None
    return h1, h2, steps


def _fill(P, es, us):
    """Even-odd fill of the closed polygon ``P`` (N x 2) at the pixel centres."""
    x1, y1 = P[:-1, 0], P[:-1, 1]
    x2, y2 = P[1:, 0], P[1:, 1]
    out = np.zeros((us.size, es.size), dtype=bool)
    lo, hi = np.minimum(y1, y2), np.maximum(y1, y2)
    rows = np.nonzero((us >= lo.min()) & (us <= hi.max()))[0]
    for i in rows:
        uu = us[i]
        sel = (y1 > uu) != (y2 > uu)
        if not sel.any():
            continue
        xc = x1[sel] + (uu - y1[sel]) * (x2[sel] - x1[sel]) / (y2[sel] - y1[sel])
        xc.sort()
        cnt = xc.size - np.searchsorted(xc, es, side="right")
        out[i] = (cnt % 2) == 1
    return out


def _inside_polygon(P, x):
    return bool(_fill(P, np.array([x[0]]), np.array([x[1]]))[0, 0])


def _crossing(F, mask, es, us, i, j, e, u):
    """From pixel (i, j), the first pixel of the other class along a row or a
    column, bisected to rounding on the region's margins: (x_in, slot) or None."""
    m0 = mask[i, j]
    for di, dj in ((0, 1), (0, -1), (1, 0), (-1, 0)):
        ii, jj = i + di, j + dj
        while 0 <= ii < us.size and 0 <= jj < es.size and mask[ii, jj] == m0:
            ii += di
            jj += dj
        a = np.array([es[j], us[i]])
        if 0 <= ii < us.size and 0 <= jj < es.size:
            b = np.array([es[jj], us[ii]])
        elif m0:  # the window's side
            b = np.array([e[1] if dj > 0 else e[0] if dj < 0 else es[j],
                          u[1] if di > 0 else u[0] if di < 0 else us[i]])
            if F.inside(F(b)[0]):
                return b, F.m - 4 + (1 if dj > 0 else 0 if dj < 0 else 3 if di > 0 else 2)
        else:
            continue
        xin, xout = (a, b) if m0 else (b, a)
        gin, gout = F(xin)[0], F(xout)[0]
        if not F.inside(gin) or F.inside(gout):
            continue
        while True:
            mid = 0.5 * (xin + xout)
            if (mid == xin).all() or (mid == xout).all():
                break
            gm = F(mid)[0]
            if F.inside(gm):
                xin, gin = mid, gm
            else:
                xout, gout = mid, gm
        viol = np.nonzero(~(gout >= 0.0) | (np.arange(F.m) % 2 == 1) & (np.arange(F.m) < F.m - 4)
                          & (gout <= 0.0))[0]
        if viol.size == 0:
            continue
        slot = int(viol[np.argmin(np.abs(gin[viol]))])
        return xin, slot
    return None


def _to_arcs(F, curve, word_text):
    out = []
    for i, arc in enumerate(curve):
        kind, step = F.event(arc.slot)
        P = np.array(arc.pts)
        # in the window: a point rounding left an ulp outside is put on its side (R13)
        P[:, 0] = np.clip(P[:, 0], F.win[0], F.win[1])
        P[:, 1] = np.clip(P[:, 1], F.win[2], F.win[3])
        out.append(BorderArc(P[:, 0].copy(), P[:, 1].copy(), kind, step, inside=word_text,
                             ends=("corner", "corner") if arc.end == "corner" else ("closed", "closed")))
        out[-1]._tans = arc.tans
        out[-1]._slot = arc.slot
        out[-1]._end_slot = arc.end_slot
    return out


def _chord_positions(P, X, tol):
    """Where the points ``X`` (M x 2) lie along the polyline ``P`` (N x 2) of a
    traced arc: ``i + tau`` for the nearest chord ``P[i] -> P[i+1]`` that has the
    point beside it within its sagitta (a turn of at most ``_MAX_TURN`` per step
    bends the curve at most 0.01 of the chord away from it) or within ``tol`` of
    its ends (past them, another piece of the same level set may start); NaN
    where none has."""
    A, AB = P[:-1], P[1:] - P[:-1]
    L2 = (AB ** 2).sum(1)
    rel = X[:, None, :] - A[None, :, :]
    raw = (rel * AB).sum(2) / np.where(L2 > 0, L2, 1)
    tau = np.clip(raw, 0.0, 1.0)
    off = rel - tau[:, :, None] * AB
    d = np.hypot(off[:, :, 0], off[:, :, 1])
    near = np.where((raw > 0) & (raw < 1), np.maximum(tol, 0.015 * np.sqrt(L2)), tol)
    d = np.where(d <= near, d, np.inf)
    i = np.argmin(d, axis=1)
    rows = np.arange(len(X))
    return np.where(np.isfinite(d[rows, i]), i + tau[rows, i], np.nan)


def _chord_position(P, x, tol):
    """:func:`_chord_positions` of one point, None for NaN."""
    pos = _chord_positions(P, np.asarray(x, dtype=float)[None], tol)[0]
    return None if math.isnan(pos) else float(pos)


def _on_curves(x, slot, curves, tol):
    """Whether ``x`` lies on a traced arc of margin ``slot`` (any margin: None),
    within ``tol`` or, beside a chord, within the chord's sagitta."""
    for curve in curves:
        for arc in curve:
            if slot is not None and arc.slot != slot:
                continue
            P = np.array(arc.pts)
            if np.hypot(P[:, 0] - x[0], P[:, 1] - x[1]).min() <= tol or \
                    _chord_position(P, x, tol) is not None:
                return True
    return False


def _closed(curve):
    """The closed polygon (N x 2, first point repeated) of a curve of arcs."""
    return np.concatenate([np.array(a.pts[:-1]) for a in curve] + [np.array(curve[0].pts[:1])])


def _new_curve(F, x, slot, curves, scale):
    """Walk the boundary through ``x`` (margin ``slot``) unless a traced curve
    already passes there: the new curve (appended to ``curves``), None when
    known, False when the walk failed."""
    if _on_curves(x, slot, curves, 1e-9 * scale):
        return None
    curve = _walk(F, slot, x, scale)
    if curve is None or _below_rounding(curve, F):
        return False
    curves.append(curve)
    return curve


def _below_rounding(curve, F=None):
    """Whether a closed curve encloses no more than the rounding of its points
    allows to tell from nothing (:func:`_curve_area`'s rounding part: the
    points' distance from the exact curves, ``_ROUND_ULPS`` ulps along the
    dynamics' margins, times the perimeter): a sliver of no width to rounding
    (the k-th and (k+1)-th impacts of a step coinciding, ``2 e^k s`` below an
    ulp), whose traced area would be rounding noise.  The window's sides are
    exact, so a region bounded by them alone is kept at any size."""
    A, err, rounding = _curve_area(curve, F)
    curve[0].area = (A, err)  # kept for the region's area
    return abs(A) <= rounding


def _trace_word(ks, word, e, u, es, us, mask, y0, v0, max_failures=20, seeds=()):
    """Every component of the region of itinerary ``ks`` seen by the pixel mask,
    and those through the border points ``seeds`` (points of the region at
    its border, e.g. the word's end of a bisected bracket of a finer scan)."""
    F = _Margins(ks, (e[0], e[1], u[0], u[1]), y0, v0)
    scale = max(e[1] - e[0], u[1] - u[0])
    curves, fill = [], np.zeros_like(mask)
    tried = np.zeros_like(mask)
    failures = 0
    while True:
        todo = np.argwhere((mask ^ fill) & ~tried)
        if todo.size == 0 or failures > max_failures:
            break
        i, j = (int(t) for t in todo[0])
        tried[i, j] = True
        if fill[i, j] and _on_curves(np.array([es[j], us[i]]), None, curves, 1e-9 * scale):
            # a pixel centre between a traced curve and its chord (within the sagitta):
            # the polygon's chords, not a missed piece of boundary
            continue
        c = _crossing(F, mask, es, us, i, j, e, u)
        if c is None:
            failures += 1
            continue
        curve = _new_curve(F, *c, curves, scale)
        if curve is False:
            failures += 1
        elif curve is not None:
            fill ^= _fill(_closed(curve), es, us)
    n2 = 2 * F.n
    for x in seeds:
        x = np.asarray(x, dtype=float)
        g = F(x)[0]
        if not F.inside(g):  # the margins disagree with the map there: not traced
            failures += 1
            continue
        slot = int(np.argmin(np.where(np.isfinite(g[:n2]), np.abs(g[:n2]), np.inf)))
        failures += _new_curve(F, x, slot, curves, scale) is False
    text = word.format(ascii=True)
    outer, holes = [], []
    for curve in curves:
        A, err = curve[0].area
        P = _closed(curve)
        (outer if A > 0 else holes).append((A, err, curve, P))
    comps = []
    outer.sort(key=lambda t: t[0])
    members = [[] for _ in outer]
    for h in holes:
        for k, o in enumerate(outer):
            if _inside_polygon(o[3], h[3][0]):
                members[k].append(h)
                break
    for (A, err, curve, P), hs in zip(outer, members):
        corners = []
        for arc in curve:
            if arc.end == "corner":
                x = arc.pts[-1]
                corners.append(Corner(float(x[0]), float(x[1]), (F.event(arc.slot), F.event(arc.end_slot))))
        comps.append(RegionComponent(A + sum(h[0] for h in hs), err + sum(h[1] for h in hs),
                                     _to_arcs(F, curve, text), [_to_arcs(F, h[2], text) for h in hs],
                                     corners))
    comps.sort(key=lambda c: -c.area)
    return comps, failures


def word_region(word, e=(0.0, 1.0 - 1e-9), u=(0.05, 1.5), *, resolution=None, max_iter=1000,
                y0=1.0, v0=0.0):
    """word_region(word, e=(0, 1), u=(0.05, 1.5), *, resolution=None, max_iter=1000) -> Region

    The region of the parameter plane where the periodic sliding solution
    through (1, 0) has the word ``word``, as closed polygons of traced arcs.

    The region is ``{g_c(e, u) >= 0}`` for the margins of the word's itinerary
    (two per step, see :mod:`stairbounce.regions`) and of the window.  A scan
    of ``resolution`` x ``resolution`` pixel centres finds the pixels of the
    word; from each pixel not yet inside a traced curve the first border along
    its row (or column) is bisected to rounding and the boundary of that
    component walked by pseudo-arclength continuation, corner to corner, until
    it closes.  Areas are the shoelace sum of the dense curve plus the cubic
    Hermite correction of every chord (the tangents are known), on
    coordinates relative to the curve's first point, with an error estimate
    from the same sum on every other point plus rounding (the points'
    distance from the exact curves times the arcs' lengths, and the sum's).

    What it can miss: a component (or hole) that contains no pixel centre of
    the scan, i.e. narrower than a pixel everywhere.  Raise ``resolution`` to
    find smaller ones.  A component narrower than rounding (its area below the
    rounding of its points, about its perimeter times 32 ulps along the
    dynamics' borders), or one whose walk stalls, is not traced and the
    region is marked ``complete=False`` (docs/guide/regions.md).

    A word the seed scan does not see in the window gives a region with no
    component whose ``found`` is False (its repr says "not found"), and a
    :class:`UserWarning` saying so.

    Parameters
    ----------
    word : Word, str such as ``"(2, 0, 1, 0^inf)"`` or ``"(2, 0, 1)"``, or letters such as ``(2, 0, 1)``
    e, u : (min, max) or (min, max, n)
        The window's edges, as in :func:`stairbounce.scan` (0 <= e_min <
        e_max <= 1, 0 <= u_min < u_max; the edges e = 1 and u = 0, where the
        margins are not defined, are traced at 1 - 1e-12 and 1e-9), and the
        seed scan's pixels along that axis.
    resolution : int >= 2, default 256 (for windows given as (min, max))
        Pixels per side of the seeding scan, for windows given without
        counts; giving both is refused.
    max_iter : int, default 1000
        Only matters for the seeding scan's labels (steps per pixel).

    Returns
    -------
    Region
        ``area``, ``area_error``, ``components`` (each with ``area``,
        ``boundary`` arcs, ``holes``, ``corners``, ``kinds``, ``polygon()``),
        ``found``.
    """
    w = _as_word(word)
    e, u, es, us, _ = _seed_grid(e, u, resolution)
    max_iter = check_count("max_iter", max_iter, 1)
    y0, v0, max_iter = _check_run(y0, v0, max_iter)
    ks = itinerary_of_word(w)
    _check_centres(es)
    h1, h2, _ = _label_grid(es, us, max(max_iter, ks.size), y0, v0)
    a, b = _hash_itinerary(ks, ks.size)
    mask = (h1 == a) & (h2 == b)
    if not mask.any():
        warnings.warn(f"word {w.format(ascii=True)} not found in the window e = [{e[0]:g}, {e[1]:g}], "
                      f"u = [{u[0]:g}, {u[1]:g}] (no pixel of the {es.size} x {us.size} seed scan has it): "
                      "its region is empty or narrower than a seed pixel; raise resolution to look closer",
                      UserWarning, stacklevel=2)
    comps, failures = _trace_word(ks, w, e, u, es, us, mask, y0, v0)
    return Region(w, e, u, comps, complete=failures == 0, failures=failures)


def _point_seeds(points, e, u, y0, v0, max_iter):
    """Border points (:func:`stairbounce.border_points`) as seeds: for each end of
    each bracket inside the window whose outcome slides, ``{(hash1, hash2):
    (itinerary, [points])}``."""
    seeds = {}
    buf = np.empty(max_iter, dtype=np.int64)
    pe, pu, w = (np.asarray(points[k].values, float) for k in ("e", "u", "width"))
    along_u = np.asarray(points["axis"].values).astype(str) == "u"
    for x0, y0_, d, au in zip(pe, pu, w, along_u):
        for x in ((x0, y0_), (x0, y0_ + d) if au else (x0 + d, y0_)):
            if not (e[0] <= x[0] <= e[1] and u[0] <= x[1] <= u[1]):
                continue
            n = _itinerary_of(x[0], x[1], y0, v0, max_iter, buf)
            if n <= 0:
                continue
            key = tuple(int(h) for h in _hash_itinerary(buf, n))
            seeds.setdefault(key, (buf[:n].copy(), []))[1].append(x)
    return seeds


@njit(cache=True, parallel=True)
def _words_points(pe, pu, y0, v0, max_iter, h1, h2):
    """The two itinerary hashes of :func:`_words_grid` at the points ``(pe, pu)``
    (0, 0 where the map does not slide within max_iter)."""
    for i in prange(pe.size):
        ks = np.empty(max_iter, dtype=np.int64)
        n = _itinerary_of(pe[i], pu[i], y0, v0, max_iter, ks)
        if n <= 0:
            h1[i] = 0
            h2[i] = 0
        else:
            h1[i], h2[i] = _hash_itinerary(ks, n)


# corner seeding: probes on a ring around every corner, at this fraction of the
# seed spacing (per axis), in the four sectors between the corner's two arcs and
# at _CORNER_DIRECTIONS equally spaced directions; at most _CORNER_ROUNDS rounds.
# Measured on Fig. 5e seeded at 32 x 32 (benchmarks/README.md): one ring at 1/4
# finds 392 of the 411 words of >= 16 pixels at 512 x 512 (15 s in that trial);
# adding rings at 1/20 (410 of 411, 27 s) or at 1/128 and 1/4096 (410, 48 s)
# finds a few more words of a pixel's size and many smaller ones, at two to three
# times the cost.
_CORNER_RADII = (0.25,)
_CORNER_DIRECTIONS = 12
_CORNER_ROUNDS = 8
_CORNER_SEEDS = 8          # border points kept per new word and round
# only the corners of components of at least this fraction of a seed pixel's area
# are probed (a cascade through ever smaller regions would not end: the plane is
# fractal)
_CORNER_MIN_AREA = 1.0 / 16


def _corner_rings(regs, pixel):
    """The corners of ``regs`` and, for each, rings of probe points around it:
    (centres C x 2, probes C x R x D x 2), directions in angular order, in
    coordinates scaled by the seed pixel ``pixel`` = (de, du)."""
    centres, dirs = [], []
    uni = 2.0 * math.pi * (np.arange(_CORNER_DIRECTIONS) + 0.5) / _CORNER_DIRECTIONS
    for r in regs:
        for comp in r.components:
            if comp.area < _CORNER_MIN_AREA * pixel[0] * pixel[1]:
                continue
            for curve in [comp.boundary] + comp.holes:
                if len(curve) < 2:
                    continue
                for i, arc in enumerate(curve):
                    nxt = curve[(i + 1) % len(curve)]
                    t_in, t_out = arc._tans[-1], nxt._tans[0]
                    # the two arcs' directions away from the corner, in pixel units
                    d1 = np.array([-t_in[0] / pixel[0], -t_in[1] / pixel[1]])
                    d2 = np.array([t_out[0] / pixel[0], t_out[1] / pixel[1]])
                    n1, n2 = np.hypot(*d1), np.hypot(*d2)
                    if not (n1 > 0 and n2 > 0 and math.isfinite(n1 + n2)):
                        continue
                    d1, d2 = d1 / n1, d2 / n2
                    # the bisectors of the four sectors between the two tangent lines
                    bis = [d1 + d2, d2 - d1, -d1 - d2, d1 - d2]
                    ang = [math.atan2(b[1], b[0]) for b in bis if np.hypot(*b) > 1e-12]
                    a = np.sort(np.mod(np.concatenate([uni, ang]), 2.0 * math.pi))
                    centres.append((arc.e[-1], arc.u[-1]))
                    dirs.append(a)
    if not centres:
        return np.zeros((0, 2)), np.zeros((0, len(_CORNER_RADII), 0, 2))
    D = max(len(a) for a in dirs)
    ang = np.array([np.concatenate([a, np.full(D - len(a), a[-1])]) for a in dirs])
    C = np.array(centres, dtype=float)
    rad = np.array(_CORNER_RADII)
    P = np.empty((len(C), rad.size, D, 2))
    P[..., 0] = C[:, None, None, 0] + rad[None, :, None] * np.cos(ang)[:, None, :] * pixel[0]
    P[..., 1] = C[:, None, None, 1] + rad[None, :, None] * np.sin(ang)[:, None, :] * pixel[1]
    return C, P


def _bisect_into(F, xin, xout):
    """Bisect between ``xin`` (inside the region of ``F``) and ``xout`` (outside)
    with the region's own margins, to rounding: the inside end, on its border."""
    xin, xout = np.array(xin, float), np.array(xout, float)
    while True:
        mid = 0.5 * (xin + xout)
        if (mid == xin).all() or (mid == xout).all():
            return xin
        if F.inside(F(mid)[0]):
            xin = mid
        else:
            xout = mid


def _corner_seeds(regs, known, e, u, pixel, y0, v0, max_iter):
    """Probe around every corner of ``regs`` with the map: the words not in
    ``known`` (hash pairs) as ``{key: (itinerary, [border points])}``, each
    border point the word's end of a bisection towards a neighbouring probe of
    another outcome on the same ring."""
    C, P = _corner_rings(regs, pixel)
    if not len(C):
        return {}
    flat = P.reshape(-1, 2)
    inwin = (flat[:, 0] >= e[0]) & (flat[:, 0] <= e[1]) & (flat[:, 1] >= u[0]) & (flat[:, 1] <= u[1])
    h1 = np.zeros(len(flat), dtype=np.uint64)
    h2 = np.zeros(len(flat), dtype=np.uint64)
    sel = np.nonzero(inwin)[0]
    a1, a2 = np.empty(sel.size, np.uint64), np.empty(sel.size, np.uint64)
    _words_points(np.ascontiguousarray(flat[sel, 0]), np.ascontiguousarray(flat[sel, 1]),
                  y0, v0, max_iter, a1, a2)
    h1[sel], h2[sel] = a1, a2
    shape = P.shape[:3]
    H1, H2, W = h1.reshape(shape), h2.reshape(shape), inwin.reshape(shape)
    new = {}
    buf = np.empty(max_iter, dtype=np.int64)
    margins = {}
    for c, r, d in zip(*np.nonzero(W & (H1 != 0))):
        key = (int(H1[c, r, d]), int(H2[c, r, d]))
        if key in known:
            continue
        if key in new and len(new[key][1]) >= _CORNER_SEEDS:
            continue
        # the nearest probe of the same ring with another outcome, inside the window
        D = shape[2]
        other = None
        for step in range(1, D // 2 + 1):
            for dd in ((d + step) % D, (d - step) % D):
                if W[c, r, dd] and (H1[c, r, dd], H2[c, r, dd]) != (H1[c, r, d], H2[c, r, d]):
                    other = dd
                    break
            if other is not None:
                break
        if other is None:
            continue
        if key not in new:
            n = _itinerary_of(P[c, r, d, 0], P[c, r, d, 1], y0, v0, max_iter, buf)
            new[key] = (buf[:n].copy(), [])
            margins[key] = _Margins(new[key][0], (e[0], e[1], u[0], u[1]), y0, v0)
        F = margins[key]
        if not F.inside(F(P[c, r, d])[0]) or F.inside(F(P[c, r, other])[0]):
            continue  # the margins disagree with the map there
        new[key][1].append(_bisect_into(F, P[c, r, d], P[c, r, other]))
    return {k: v for k, v in new.items() if v[1]}


def window_regions(e, u, *, resolution=None, max_iter=1000, y0=1.0, v0=0.0, points=None, progress=None,
                   from_corners=False):
    """window_regions(e, u, *, resolution=None, max_iter=1000, points=None, from_corners=False) -> list[Region]

    Every word's region in a window (the words seen by a scan of
    ``resolution`` x ``resolution`` pixel centres, or of the windows' own
    counts ``e=(lo, hi, n_e)``, ``u=(lo, hi, n_u)``, as :func:`word_region`
    takes them, and, with ``points`` (a
    :func:`stairbounce.border_points` Dataset, e.g. of a finer scan), the
    words on either side of those border points, each traced from there),
    largest area first; see :func:`word_region` for the method.

    With ``from_corners=True``, regions smaller than a seed pixel are also
    found from the corners of their neighbours: after the seeded words are
    traced, the map is evaluated on a ring around every corner of every
    component of at least 1/16 of a seed pixel's area (radius a quarter of the
    seed spacing along each axis; 16 points: the bisectors of the four sectors
    between the corner's two arcs and 12 equally spaced directions); each word
    not traced yet is bisected (with its own margins) towards a neighbouring
    point of the ring with another outcome, and walked from that border point.
    The new regions' corners are probed in turn, for at most 8 rounds or until
    no new word appears.  On the Fig. 5e window seeded at 32 x 32 this finds
    159 of the 160 words of 1/4 of a seed pixel or more that a 512 x 512 scan
    sees (the seed scan alone: 95), and 392 of the 411 of 1/16 or more (121);
    it costs 3 to 13 times the seeded run (``benchmarks/README.md``).

    What it can still miss: a region (or a component, or a hole) that contains
    no seed pixel centre and either touches no corner of a traced component of
    at least 1/16 pixel (an island inside one region, or a region meeting its
    neighbours only along arcs, at corners of smaller regions, or at the
    corners of a component that was itself missed), or lies in a sector of a
    corner narrower than the ring's spacing of directions (a cusp) or entirely
    within a quarter pixel of it; and a further component of a word already
    traced (only words not yet traced are seeded from corners).
    """
    if progress is not None and not callable(progress):
        raise ValueError(f"progress must be None or a callable progress(done, total), got {_v._show(progress)}")
    gen = iter_window_regions(e, u, resolution=resolution, max_iter=max_iter, y0=y0, v0=v0,
                              points=points, from_corners=from_corners)
    while True:
        try:
            done, total = next(gen)
        except StopIteration as stop:
            return stop.value
        if progress is not None and done:
            progress(done, total)


def iter_window_regions(e, u, *, resolution=None, max_iter=1000, y0=1.0, v0=0.0, points=None,
                        from_corners=False, slice_work=None):
    """iter_window_regions(e, u, ..., slice_work=None) -> generator of (done, total), returning list[Region]

    :func:`window_regions` one word at a time: yields ``(0, total)`` once the
    seeded words are known, then ``(done, total)`` after each word traced
    (``total`` grows when corner seeding finds new words); returns the
    regions, largest area first.  For callers that share a worker between
    words (the explorer's scheduler).  ``slice_work`` (map steps): the seed
    scan (``max_iter`` per seed pixel) and the seeds' itineraries (their
    periods) are cut into slices of at most that much work, each yielding
    ``(0, None)`` (the words are not known yet) before ``(0, total)``.
    """
    e, u, es, us, pixel = _seed_grid(e, u, resolution)
    max_iter = check_count("max_iter", max_iter, 1)
    from_corners = _v.flag("from_corners", from_corners)
    y0, v0, max_iter = _check_run(y0, v0, max_iter)
    if points is not None and not all(k in getattr(points, "variables", ()) for k in ("e", "u", "width", "axis")):
        raise ValueError("points must be a Dataset from border_points (variables e, u, width, axis)")
    _check_centres(es)
    h1, h2, steps = yield from _label_grid_slices(es, us, max_iter, y0, v0, slice_work)
    keys, first = np.unique(np.stack([h1.ravel(), h2.ravel()], 1), axis=0, return_index=True)
    seeds = _point_seeds(points, e, u, y0, v0, max_iter) if points is not None else {}
    todo = {}
    buf = np.empty(max_iter, dtype=np.int64)
    spent = 0  # map steps of this slice's itineraries (each its word's period)
    for idx, (a, b) in zip(first, keys):
        if a == 0:
            continue
        i, j = divmod(int(idx), es.size)
        if slice_work is not None and spent and spent + int(steps[i, j]) > slice_work:
            yield 0, None
            spent = 0
        spent += int(steps[i, j])
        n = _itinerary_of(es[j], us[i], y0, v0, max_iter, buf)
        todo[(int(a), int(b))] = buf[:n].copy()
    for key, (ks, _) in seeds.items():
        todo.setdefault(key, ks)
    out = []
    total = len(todo)
    yield 0, total

    def trace(todo, seeds):
        regs = []
        for key, ks in todo.items():
            w = word_from_impacts(ks)
            mask = (h1 == np.uint64(key[0])) & (h2 == np.uint64(key[1]))
            comps, failures = _trace_word(ks, w, e, u, es, us, mask, y0, v0,
                                          seeds=seeds.get(key, (None, ()))[1])
            regs.append(Region(w, e, u, comps, complete=failures == 0, failures=failures))
            out.append(regs[-1])
            yield len(out), total
        return regs

    fresh = yield from trace(todo, seeds)
    known = set(todo)
    for _ in range(_CORNER_ROUNDS if from_corners else 0):
        seeds = _corner_seeds(fresh, known, e, u, pixel, y0, v0, max_iter)
        if not seeds:
            break
        known.update(seeds)
        total += len(seeds)
        fresh = yield from trace({k: v[0] for k, v in seeds.items()}, seeds)
    out.sort(key=lambda r: -r.area)
    return out


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


# --------------------------------------------------------------------------- #
# The planar graph of a window's borders                                      #
# --------------------------------------------------------------------------- #


@dataclass
class BorderGraph:
    """Nodes (corners) and edges (arcs between them) of a window's borders.

    ``edges`` are ``(i, j, arc)`` with node indices; a piece of border shared
    by two regions is one edge, its ``inside`` and ``outside`` the two words;
    arcs are cut at every corner on them, so edges meet only at nodes.
    ``junctions`` counts the cuts at corners of another region's boundary."""

    nodes: list
    edges: list
    regions: list
    junctions: int = 0       # arcs cut at a corner of another region's boundary (one-sided)
    # the closed curves of the regions as edges: ``rings[(region, component, ring)]``
    # (ring 0 the outer boundary, 1.. the holes) is the list of ``(edge index,
    # reversed)`` in the curve's order (the export's faces, regions_geojson)
    rings: dict = field(default_factory=dict)

    def counts(self):
        """Regions, arcs by kind and corners by their pair of kinds."""
        arcs, corners = {}, {}
        for _, _, a in self.edges:
            arcs[a.kind] = arcs.get(a.kind, 0) + 1
        for c in self.nodes:
            key = "+".join(sorted(ev[0] for ev in c.events))
            corners[key] = corners.get(key, 0) + 1
        comps = sum(len(r.components) for r in self.regions)
        return {"words": len(self.regions), "components": comps, "arcs": arcs, "corners": corners}

    def words_by_period(self):
        """N(p): the number of distinct words of period p among the regions."""
        out = {}
        for r in self.regions:
            out[r.word.period] = out.get(r.word.period, 0) + 1
        return dict(sorted(out.items()))

    def __repr__(self):
        c = self.counts()
        return (f"BorderGraph({c['words']} words, {c['components']} components, "
                f"{len(self.nodes)} corners, {len(self.edges)} arcs {c['arcs']})")


def _curves(region):
    for comp in region.components:
        yield comp.boundary
        yield from comp.holes


class _GraphMargins:
    """The margins of the word inside each arc (for the tests of a point against it)."""

    def __init__(self, regions):
        self.regions = {r.word.format(ascii=True): r for r in regions}
        self.cache = {}

    def __call__(self, arc):
        F = self.cache.get(arc.inside)
        if F is None:
            r = self.regions[arc.inside]
            F = self.cache[arc.inside] = _Margins(itinerary_of_word(r.word),
                                                  (r.e[0], r.e[1], r.u[0], r.u[1]))
        return F

    def middle(self, arc):
        """A point of the arc's curve in its middle: its middle traced point, or for
        an arc of two points the middle of its chord corrected onto the curve."""
        n = arc.e.size
        if n >= 3:
            return np.array([arc.e[n // 2], arc.u[n // 2]])
        x = np.array([0.5 * (arc.e[0] + arc.e[-1]), 0.5 * (arc.u[0] + arc.u[-1])])
        r = _correct(self(arc), arc._slot, x, _unit(arc.e[-1] - arc.e[0], arc.u[-1] - arc.u[0]))
        return x if r is None else r[0]


def _on_arc_curve(F, slot, x, slack):
    """Whether ``x`` lies on the curve ``g_slot = 0`` of margins ``F``: within four
    times the margin's rounding or ``slack`` of the position (times its gradient)."""
    g = F(np.asarray(x, dtype=float))
    if not math.isfinite(g[0][slot]):
        return False
    grad = abs(g[1][slot]) + abs(g[2][slot])
    return abs(g[0][slot]) <= max(4.0 * _noise(g, x)[slot], slack * grad)


def _split_arc(arc, cuts, nodes, F):
    """``arc`` cut at ``cuts`` (sorted ``(position along its chords, node)``): the
    pieces as new BorderArcs with the node's point inserted (its tangent from the
    margin's gradient there, region on the left)."""
    P = np.stack([arc.e, arc.u], 1)
    T = np.asarray(arc._tans, dtype=float)
    pieces, start, head, head_t = [], 0, [P[0]], [T[0]]
    for pos, n in cuts:
        i = int(pos)
        x = np.array([nodes[n].e, nodes[n].u])
        g = F(x)
        t = _tangent(g[1][arc._slot], g[2][arc._slot], 1)
        body = list(P[start + 1:i + 1]) if pos > i else list(P[start + 1:i])
        body_t = list(T[start + 1:i + 1]) if pos > i else list(T[start + 1:i])
        pieces.append((head + body + [x], head_t + body_t + [t]))
        start = i
        head, head_t = [x], [t]
    pieces.append((head + list(P[start + 1:]), head_t + list(T[start + 1:])))
    out = []
    for pts, tans in pieces:
        Q = np.array(pts)
        b = BorderArc(Q[:, 0].copy(), Q[:, 1].copy(), arc.kind, arc.step, arc.inside, arc.outside,
                      ("corner", "corner"))
        b._tans, b._slot = tans, arc._slot
        out.append(b)
    return out


def _corners_on_arcs(arcs, xy, corners, margins, tol, scale, bins=64):
    """For each arc ``(a, b, arc, closed)``, the corners (node indices ``corners``
    at ``xy``) other than its ends that lie on it: ``[(position along its
    chords, node), ...]``; beside a chord within its sagitta, and on the arc's
    curve (:func:`_on_arc_curve`)."""
    A, B, owner = [], [], []
    for k, (_, _, arc, _) in enumerate(arcs):
        P = np.stack([arc.e, arc.u], 1)
        A.append(P[:-1])
        B.append(P[1:])
        owner.append(np.stack([np.full(len(P) - 1, k), np.arange(len(P) - 1)], 1))
    A, B, owner = np.concatenate(A), np.concatenate(B), np.concatenate(owner)
    AB = B - A
    L2 = (AB ** 2).sum(1)
    pad = np.maximum(tol, 0.015 * np.sqrt(L2))
    size = scale / bins
    lo = np.floor((np.minimum(A, B) - pad[:, None]) / size).astype(np.int64)
    hi = np.floor((np.maximum(A, B) + pad[:, None]) / size).astype(np.int64)
    cells = {}
    for c in range(len(A)):
        for i in range(lo[c, 0], hi[c, 0] + 1):
            for j in range(lo[c, 1], hi[c, 1] + 1):
                cells.setdefault((i, j), []).append(c)
    out = [[] for _ in arcs]
    for n in corners:
        x = xy[n]
        cand = cells.get((int(math.floor(x[0] / size)), int(math.floor(x[1] / size))))
        if not cand:
            continue
        cand = np.array(cand)
        raw = ((x - A[cand]) * AB[cand]).sum(1) / np.where(L2[cand] > 0, L2[cand], 1)
        tau = np.clip(raw, 0.0, 1.0)
        off = x - (A[cand] + tau[:, None] * AB[cand])
        d = np.hypot(off[:, 0], off[:, 1])
        ok = d <= np.where((raw > 0) & (raw < 1), pad[cand], tol)
        best = {}
        for c, t, dd in zip(cand[ok], tau[ok], d[ok]):
            k, i = owner[c]
            if k not in best or dd < best[k][1]:
                best[k] = (i + t, dd)
        for k, (pos, _) in best.items():
            a, b, arc, _ = arcs[k]
            if n in (a, b) or not 0.0 < pos < arc.e.size - 1:
                continue
            if _on_arc_curve(margins(arc), arc._slot, x, 2.0 * tol):
                out[k].append((float(pos), int(n)))
    return out


def _region_list(name, regions):
    """``regions`` (a Region or an iterable of them) as a list, or ValueError."""
    if isinstance(regions, Region):
        return [regions]
    if isinstance(regions, (str, bytes)) or not hasattr(regions, "__iter__"):
        raise ValueError(f"{name} must be a list of Region (from window_regions or word_region), "
                         f"got {_v._show(regions)}")
    regions = list(regions)
    for i, r in enumerate(regions):
        if not isinstance(r, Region):
            raise ValueError(f"{name}[{i}] must be a Region (from window_regions or word_region), "
                             f"got {_v._show(r)}")
    return regions


def border_graph(regions):
    """border_graph(regions) -> BorderGraph

    The planar graph of the traced borders of ``regions`` (from
    :func:`window_regions`): nodes are the corners (shared by the regions that
    meet there, merged within 1e-11 of the window's size), edges the arcs
    between consecutive nodes.  An arc is split at every corner that lies on
    it, also one that only the region on its other side has (a one-sided
    junction: a third border ends on the arc), so that a piece of border
    between two regions is one edge, with the words on both sides
    (``inside`` and ``outside``; ``outside`` is "" where the other side was
    not traced: outside the window, no slide, or a region no seed found), and
    edges meet only at nodes.  A corner lies on an arc when it is beside the
    arc's chords (within their sagitta) and the arc's margin vanishes there to
    rounding (or within the merging distance, times its gradient).
    """
    regions = _region_list("regions", regions)
    if not any(r.components for r in regions):
        # nothing traced (a word seen by the seed scan whose walk failed, in a deep
        # window): a graph without nodes or edges (report round 3, R4)
        return BorderGraph([], [], regions)
    e, u = regions[0].e, regions[0].u
    scale = max(e[1] - e[0], u[1] - u[0])
    tol = 1e-11 * scale
    nodes, index = [], {}

    def node(x, events):
        key = (round(x[0] / tol), round(x[1] / tol))
        for dk in ((0, 0), (1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (-1, -1), (1, -1), (-1, 1)):
            k = (key[0] + dk[0], key[1] + dk[1])
            if k in index:
                return index[k]
        index[key] = len(nodes)
        nodes.append(Corner(float(x[0]), float(x[1]), events))
        return index[key]

    # every arc with its end nodes; a closed curve's start is no corner
    arcs, corner, owner = [], set(), []
    for ri, r in enumerate(regions):
        for ci, hi, curve in ((ci, hi, curve) for ci, comp in enumerate(r.components)
                              for hi, curve in enumerate([comp.boundary] + list(comp.holes))):
            for i, arc in enumerate(curve):
                prev, nxt = curve[i - 1], curve[(i + 1) % len(curve)]
                a = node((arc.e[0], arc.u[0]), ((prev.kind, prev.step), (arc.kind, arc.step)))
                b = node((arc.e[-1], arc.u[-1]), ((arc.kind, arc.step), (nxt.kind, nxt.step)))
                if len(curve) > 1:
                    corner.update((a, b))
                arcs.append((a, b, arc, len(curve) == 1))
                owner.append((ri, ci, hi))
    margins = _GraphMargins(regions)
    xy = np.array([(c.e, c.u) for c in nodes])

    # split every arc at the corners on it (chords binned on a grid: a corner is
    # compared with the chords of its cell only)
    cuts = _corners_on_arcs(arcs, xy, sorted(corner), margins, tol, scale)
    pieces, junctions, ring_of = [], 0, []
    for k, (a, b, arc, closed) in enumerate(arcs):
        if not cuts[k]:
            pieces.append((a, b, arc, closed))
            ring_of.append(owner[k])
            continue
        cut = sorted(cuts[k])
        junctions += len(cut)
        ends = [a] + [n for _, n in cut] + [b]
        for m, piece in enumerate(_split_arc(arc, cut, nodes, margins(arc))):
            pieces.append((ends[m], ends[m + 1], piece, False))
            ring_of.append(owner[k])

    # one edge per piece of border: the pieces of the same event between the same
    # nodes whose middles lie on each other's curve are its two sides
    edges, groups, rings = [], {}, {}
    for (a, b, arc, closed), ring in zip(pieces, ring_of):
        if arc.kind != "window":
            key = (arc.kind, arc.step) + (("closed",) if closed else (frozenset((a, b)),))
            mid = margins.middle(arc)
            twin = None
            for other, index in groups.get(key, ()):
                Q = np.stack([other.e, other.u], 1)
                if _chord_position(Q, mid, tol) is not None and \
                        _on_arc_curve(margins(other), other._slot, mid, 2.0 * tol):
                    twin = other
                    break
            if twin is not None:
                if twin.inside != arc.inside:
                    twin.outside = arc.inside
                # both sides keep their region on the left: the other side runs backwards
                rings.setdefault(ring, []).append((index, twin.inside != arc.inside))
                continue
            groups.setdefault(key, []).append((arc, len(edges)))
        rings.setdefault(ring, []).append((len(edges), False))
        edges.append((a, b, arc))
    return BorderGraph(nodes, edges, regions, junctions, rings)


# --------------------------------------------------------------------------- #
# Export                                                                      #
# --------------------------------------------------------------------------- #

from ._colours import KIND_COLOURS  # noqa: E402  (one definition for every output)


def regions_geojson(regions, *, tolerance=None, resolution=None, max_iter=1000) -> dict:
    """regions_geojson(regions, *, tolerance=None, resolution=None, max_iter=1000) -> dict

    A GeoJSON FeatureCollection (RFC 7946) of ``regions`` (from
    :func:`word_region` or :func:`window_regions`) that is a planar
    partition: one Polygon feature per connected component, coordinates
    ``[e, u]``, the outer ring counter-clockwise and the holes clockwise.

    The rings are built from the edges of :func:`border_graph`: a piece of
    border between two traced words is one edge, densified once and used by
    both faces, so neighbouring words share the same vertices along their
    common arc (no overlap, no gap).  Each edge is densified until every
    chord deviates from the traced curve by at most ``tolerance`` (the
    deviation from the cubic Hermite curve of the chord's ends and tangents,
    which matches the curve to O(L^4) for a chord of length L; each new vertex
    put on the border to rounding by Newton's method on the edge's margin).
    Then every pair of segments is tested for intersection, and two segments
    that meet other than at a shared vertex (where two borders come closer
    than the tolerance, near a corner where they meet at a small angle) are
    halved again until none does, except chords that lie on each other's
    curve to rounding (256 ulps: the two sides of one border that
    border_graph left as two edges, or a sliver narrower than rounding),
    which are left and counted in ``metadata.crossings``.  Where that count
    is 0, every polygon is simple and two polygons meet only along shared
    edges and at vertices (``shapely.is_valid`` and zero intersection area
    on the Fig. 5e window and e 0.30-0.36, u 0.32-0.38, numerical:
    tests/test_regions_export.py).

    Properties of a polygon: ``word``, ``period``, ``impacts``,
    ``component``; ``area``, the traced area of the component (the shoelace
    sum of the dense traced curve plus the cubic Hermite correction of every
    chord: exact to ``area_error``) and ``polygon_area``, the area of the
    exported rings themselves (outer minus holes; it differs from ``area`` by
    at most about the perimeter times ``tolerance``); ``kinds`` (arcs by
    kind), ``corners``, ``complete`` and ``reason``.  A word whose walks
    failed has ``complete: false`` and the reason on each of its features
    (with a null geometry when no component closed).  Words seen just
    outside a traced arc whose other side no traced word claims (regions
    that no seed pixel centre found) are features with a null geometry,
    ``complete: false``, the reason and ``seen_at``, a point beside them.

    The top-level member ``metadata`` (a foreign member, RFC 7946 section
    6.1) holds the window, ``tolerance`` and the largest chord deviation
    left (``max_deviation``), the counts (``words``, ``components``,
    ``edges``, ``shared_edges``, ``vertices``), ``incomplete`` and
    ``untraced`` (word lists), ``traced_area`` and ``polygon_area`` (sums),
    ``crossings`` (segment pairs still meeting: 0) and, with ``resolution``,
    the window's coverage: ``sliding_area``, the sliding area of a scan of
    ``resolution`` x ``resolution`` pixel centres (the seed scan of
    :func:`window_regions` when given its resolution and ``max_iter``), and
    ``coverage = traced_area / sliding_area``.

    Parameters
    ----------
    tolerance : float > 0, default 1e-6 times the larger side of the window
        Largest deviation of a chord from the traced curve.
    resolution : int >= 2, optional
        The seed scan's pixels per side, for ``coverage``.
    max_iter : int >= 1, default 1000
        Steps of that scan (and of the probes beside untraced arcs).
    """
    from . import _region_export

    regions = _region_list("regions", regions)
    tolerance, resolution, max_iter = _export_options(tolerance, resolution, max_iter)
    return _region_export.geojson(regions, tolerance, resolution, max_iter)


def _export_options(tolerance, resolution, max_iter):
    if tolerance is not None:
        tolerance = _v.real("tolerance", tolerance)
        if not (tolerance > 0.0 and math.isfinite(tolerance)):
            raise ValueError(f"tolerance must be a finite number > 0, got {tolerance!r}")
    if resolution is not None:
        resolution = check_count("resolution", resolution, 2, 8192)
    return tolerance, resolution, check_count("max_iter", max_iter, 1)


def regions_svg(regions, size=800, *, tolerance=None, resolution=None, max_iter=1000) -> str:
    """regions_svg(regions, size=800, *, tolerance=None, resolution=None, max_iter=1000) -> str

    An SVG figure of ``regions`` in their window (``size`` x ``size`` pixels
    of plot, e to the right and u upwards): the faces of the planar
    partition of :func:`regions_geojson` filled light grey (each with its
    word and area as a tooltip), every edge of :func:`border_graph` drawn
    once in the colour of its kind (graze violet, edge pink, chatter dark
    green; the colours of the ``borders`` PNG and the explorer, outside the
    scans' word-length palette), the window as the frame, ticks and labels
    on both axes, a title (words, and with ``resolution`` the coverage of
    the seed scan's sliding area) and a legend.  Options as in
    :func:`regions_geojson` (here the segments are not untangled: a figure
    needs no valid polygons).
    """
    from . import _region_export

    regions = _region_list("regions", regions)
    size = check_count("size", size, 16, 100000)
    tolerance, resolution, max_iter = _export_options(tolerance, resolution, max_iter)
    return _region_export.svg(regions, size, tolerance, resolution, max_iter)[0]


def write_regions(regions, path, overwrite=False, *, tolerance=None, resolution=None, max_iter=1000):
    """write_regions(regions, path, overwrite=False, *, tolerance=None, resolution=None, max_iter=1000) -> Path

    Write ``regions`` as GeoJSON (``.geojson``/``.json``, :func:`regions_geojson`)
    or SVG (``.svg``, :func:`regions_svg`), atomically; ValueError for
    another suffix."""
    from . import _region_export

    tolerance, resolution, max_iter = _export_options(tolerance, resolution, max_iter)
    return _region_export.write(regions, path, overwrite, tolerance, resolution, max_iter)[0]


# --------------------------------------------------------------------------- #
# Self-similarity on the exact borders                                        #
# --------------------------------------------------------------------------- #


def band_similarity(n=(2, 3, 4, 5, 6), repeats=(2, 3), *, resolution=256):
    """band_similarity(n=(2, ..., 6), repeats=(2, 3), *, resolution=256) -> dict

    Self-similarity between the bands ``sqrt((n-1)/2) < u <= sqrt(n/2)`` of
    Figs. 5a-c, measured on exact borders: in band n, the region of the word
    ``(n, ..., n)`` (``m`` letters, m in ``repeats``; the first members of the
    family the band shows), its area and its corner of largest e (its tip),
    and the ratios of both between consecutive bands.  A constant scale factor
    would make each row of ratios constant.

    Returns a dict ``{m: {"n": [...], "area": [...], "tip_e": [...],
    "tip_u": [...], "area_ratio": [...], "tip_ratio": [...]}}`` and
    ``"tongue_tip_ratio"``, the ratio e_{n+1}/e_n of Theorem 3.1's tips.
    """
    ns = [check_count("n", k, 2, 50) for k in n]
    out = {}
    for m in repeats:
        m = check_count("repeats", m, 1, 20)
        rows = {"n": [], "area": [], "area_error": [], "tip_e": [], "tip_u": []}
        for k in ns:
            lo, hi = math.sqrt((k - 1) / 2.0), math.sqrt(k / 2.0)
            tip = (math.sqrt(k) - math.sqrt(k - 1)) ** 2
            r = word_region((k,) * m, e=(1e-9, min(0.999, 2.0 * tip)), u=(lo, hi),
                            resolution=resolution, max_iter=max(1000, 2 * k * m))
            xs = [(c.e, c.u) for c in r.corners if c.events[0][0] != "window" or
                  c.events[1][0] != "window"]
            te, tu = max(xs) if xs else (math.nan, math.nan)
            rows["n"].append(k)
            rows["area"].append(r.area)
            rows["area_error"].append(r.area_error)
            rows["tip_e"].append(te)
            rows["tip_u"].append(tu)
        rows["area_ratio"] = [b / a if a else math.nan for a, b in zip(rows["area"], rows["area"][1:])]
        rows["tip_ratio"] = [b / a if a else math.nan for a, b in zip(rows["tip_e"], rows["tip_e"][1:])]
        out[m] = rows
    tips = [(math.sqrt(k) - math.sqrt(k - 1)) ** 2 for k in ns]
    out["tongue_tip_ratio"] = [b / a for a, b in zip(tips, tips[1:])]
    return out


def traced_columns(tab):
    """Add ``traced_area``, ``traced_area_error``, ``components`` and ``complete``
    to a word table (:func:`stairbounce.word_table` with ``regions=True``):
    :func:`window_regions` of its window, seeded by a square scan of the larger
    side of the table's grid, matched to the rows by the word's text."""
    import xarray as xr

    try:
        e = (float(tab.attrs["e_min"]), float(tab.attrs["e_max"]))
        u = (float(tab.attrs["u_min"]), float(tab.attrs["u_max"]))
        res = max(int(tab.attrs["n_e"]), int(tab.attrs["n_u"]))
    except KeyError:
        raise ValueError("regions=True needs the scan's window (attributes e_min, e_max, u_min, "
                         "u_max, n_e, n_u)") from None
    e = (e[0], min(e[1], 1.0 - 1e-12))
    u = (max(u[0], 1e-9), u[1])
    found = {r.word.format(ascii=True): r for r in
             window_regions(e, u, resolution=res, max_iter=int(tab.attrs.get("max_iter", 1000)))}
    rows = [found.get(str(t)) for t in tab.text.values]
    dim = ("word",)
    return tab.assign(
        traced_area=(dim, np.array([r.area if r else np.nan for r in rows]),
                     {"long_name": "area of the traced region (stairbounce.regions)"}),
        traced_area_error=(dim, np.array([r.area_error if r else np.nan for r in rows]),
                           {"long_name": "error estimate of traced_area"}),
        components=(dim, np.array([len(r.components) if r else 0 for r in rows], np.int64),
                    {"long_name": "connected components traced"}),
        complete=(dim, np.array([bool(r and r.complete) for r in rows]),
                  {"long_name": "every seed's walk closed"}),
    ) if isinstance(tab, xr.Dataset) else tab
