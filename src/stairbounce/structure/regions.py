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

Here: the regions' types (:class:`Region`, :class:`RegionComponent`,
:class:`BorderArc`, :class:`Corner`), the checks of their arguments, the
polygons' areas, :func:`word_region` and :func:`window_regions` (the seeds
from a scan and from corners).  The margins are in :mod:`.itinerary`, the
continuation in :mod:`.continuation`, one arc through a point in :mod:`.trace`,
the planar graph in :mod:`.graph` and the export in :mod:`.export`.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np
from numba import get_num_threads, njit, prange

from .. import _validate as _v
from ..model import SLIDING, check_count, check_state
from ..symbolic import Word, parse_word, word_from_impacts
from .continuation import _EPS, _ROUND_ULPS, _Margins, _walk
from .itinerary import _hash_itinerary, _itinerary_of, _words_grid
from .slices import grid_blocks

__all__ = ["BorderArc", "Corner", "Region", "RegionComponent", "word_region", "window_regions"]


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
    steps (``max_iter`` per pixel; :func:`stairbounce.structure.slices.grid_blocks`),
    yielding ``(0, None)`` after each block (nothing when ``slice_work`` is
    None: one call); returns the same arrays (pixels are independent)."""
    if slice_work is None:
        return _label_grid(es, us, max_iter, y0, v0)
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
