"""The export of traced regions as a planar partition (:func:`regions_geojson`,
:func:`regions_svg`, :func:`write_regions`; docs/guide/regions.md).

The faces are built from the edges of :func:`stairbounce.border_graph`: a
piece of border between two traced words is one edge, densified once and
used by both faces (forwards by one, backwards by the other), so neighbouring
words share the same vertices along their common arc: no overlap, no gap.

Densification.  Between two consecutive vertices of an edge the traced curve
is approximated by the cubic Hermite interpolant of the two points and their
unit tangents (scaled by the chord), which continuation provides; the chord
deviates from that cubic by

    L * max_s | s (1-s) ((1-s) a - s b) |,   a = t0 . n,  b = t1 . n

(``n`` the chord's unit normal, ``L`` its length), and the cubic from the
curve by O(L^4).  A chord deviating by more than the tolerance is halved: its
Hermite midpoint is moved onto the curve by Newton's method on the edge's
margin along the chord's normal (the corrector of the continuation), so every
vertex is a point of the border to rounding.  Then every pair of segments of
the whole partition is tested for intersection (segments binned on a grid);
two segments that meet other than at a shared vertex (where the border is
thinner than the tolerance) are halved again, until none does.  The faces are
therefore simple polygons that meet only along shared edges and at nodes.

This module was ``stairbounce._region_export`` (with the three public
functions of ``stairbounce.regions`` that call it); ``_rg`` below reads the
names the code used from the former ``stairbounce.regions``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .. import _validate as _v
from .._colours import KIND_COLOURS
from ..model import check_count
from . import graph as _graph
from . import itinerary as _itinerary
from . import regions as _regions
from .graph import _region_list
from .itinerary import _margins

__all__ = ["regions_geojson", "regions_svg", "write_regions"]


class _FormerRegions:
    """``_rg``: the names this module reads as ``_rg.NAME`` from the former
    ``stairbounce.regions``, each looked up, at its use, in the module of the
    structure package that defines it now (itinerary, regions, graph: none of
    the names is imported by a module before the one that defines it)."""

    def __getattr__(self, name):
        for module in (_itinerary, _regions, _graph):
            if name in vars(module):
                return getattr(module, name)
        raise AttributeError(f"no {name!r} in the former stairbounce.regions")


_rg = _FormerRegions()


FACE_COLOUR = "#e4e4e4"   # the traced regions' fill in the SVG (a grey outside the palette)

_EPS = np.finfo(float).eps
_S = np.linspace(0.0, 1.0, 17)[1:-1]
# default tolerance, relative to the larger side of the window
TOLERANCE = 1e-6
# the tolerance's floor, in ulps of the window's largest coordinate: below it a
# chord's deviation is rounding (regions_geojson)
_TOLERANCE_ULPS = 4
_MAX_ROUNDS = 60
# two chords closer to each other's curve than this (times the largest coordinate) are on
# the same curve to rounding (the margins are exact to about 32 ulps of the position)
_SAME = 256 * _EPS
# chords still crossing after untangling closer than this (times the window's
# size) are one tangle, clipped out as one box (regions_geojson)
_TANGLE_GAP = 0.01


@njit(cache=True)
def _project(ks, nsteps, win, y0, v0, slot, xp, td, half, out, tan):
    """Newton's method on ``g_slot = 0`` along the normal of ``td[i]`` through
    ``xp[i]`` (:func:`regions._correct`'s iteration), for every i: the point in
    ``out[i]``, the unit tangent (region on the left) in ``tan[i]``; returns a
    boolean array, False where Newton failed or moved more than ``half[i]``."""
    m = 2 * nsteps + 4
    g = np.empty(m)
    ge = np.empty(m)
    gu = np.empty(m)
    ok = np.zeros(xp.shape[0], dtype=np.bool_)
    eps = np.finfo(np.float64).eps
    for i in range(xp.shape[0]):
        x0, x1 = xp[i, 0], xp[i, 1]
        t0, t1 = td[i, 0], td[i, 1]
        for _ in range(8):
            _margins(x0, x1, y0, v0, ks, nsteps, win, g, ge, gu)
            a, b = ge[slot], gu[slot]
            det = a * t1 - b * t0
            if not (math.isfinite(g[slot]) and math.isfinite(det)) or det == 0.0:
                break
            r0 = -g[slot]
            r1 = -(t0 * (x0 - xp[i, 0]) + t1 * (x1 - xp[i, 1]))
            z0 = (r0 * t1 - b * r1) / det
            z1 = (a * r1 - t0 * r0) / det
            x0 += z0
            x1 += z1
            if abs(z0) + abs(z1) <= 4.0 * eps * max(abs(x0), abs(x1), 1e-300):
                _margins(x0, x1, y0, v0, ks, nsteps, win, g, ge, gu)
                n = math.hypot(ge[slot], gu[slot])
                if n > 0.0 and math.isfinite(n) and math.hypot(x0 - xp[i, 0], x1 - xp[i, 1]) <= half[i]:
                    out[i, 0], out[i, 1] = x0, x1
                    tan[i, 0], tan[i, 1] = gu[slot] / n, -ge[slot] / n
                    ok[i] = True
                break
    return ok


def _deviation(P, T):
    """How far each chord ``P[i] -> P[i+1]`` lies from the cubic Hermite curve of
    its ends and unit tangents ``T`` (the traced curve to O(L^4))."""
    d = P[1:] - P[:-1]
    L = np.hypot(d[:, 0], d[:, 1])
    n = np.stack([-d[:, 1], d[:, 0]], 1) / np.where(L > 0, L, 1.0)[:, None]
    a = (T[:-1] * n).sum(1)[:, None]
    b = (T[1:] * n).sum(1)[:, None]
    s = _S[None, :]
    return L * np.abs(s * (1 - s) * ((1 - s) * a - s * b)).max(1), L


class _Edge:
    """One edge of the border graph as a polyline being densified."""

    def __init__(self, arc, F, start, end):
        self.kind = arc.kind
        self.P = np.stack([arc.e, arc.u], 1).astype(float)
        self.P[0], self.P[-1] = start, end       # the nodes' own coordinates
        self.T = np.asarray(arc._tans, dtype=float).reshape(-1, 2)
        # a point repeated (an arc shorter than its points' spacing in floats, as
        # along the sides of a window a few hundred ulps wide) is a chord of length
        # zero, which meets its neighbours: dropped, the ends kept
        same = (self.P[1:] == self.P[:-1]).all(1)
        if same.any() and len(self.P) > 2:
            keep = np.concatenate([[True], ~same])
            if not keep[-1]:
                # the end repeats the point before it: keep the end (the node), drop that one
                last = np.flatnonzero(keep)[-1]
                keep[-1] = True
                keep[last] = last == 0
            self.P, self.T = self.P[keep], self.T[keep]
        self.F, self.slot = F, arc._slot
        self.failed = 0                          # midpoints Newton did not settle (Hermite kept)
        self.max_dev = 0.0
        self.fresh = np.ones(len(self.P) - 1, dtype=bool)   # chords not yet tested for crossings

    def splittable(self, i):
        """Whether halving chord ``i`` can help: a border's chord longer than rounding."""
        if self.kind == "window":
            return False
        d = self.P[i + 1] - self.P[i]
        return math.hypot(d[0], d[1]) > 64.0 * _EPS * float(np.abs(self.P[i]).max())

    def insert(self, idx, X, T):
        """Insert the points ``X`` (tangents ``T``) after vertices ``idx`` (sorted;
        within one chord in their order along it); the chords cut are fresh."""
        order = np.arange(len(idx))
        fresh = np.insert(self.fresh, idx + 1, True)
        fresh[idx + order] = True
        self.P = np.insert(self.P, idx + 1, X, axis=0)
        self.T = np.insert(self.T, idx + 1, T, axis=0)
        self.fresh = fresh

    def split(self, mask):
        """Halve the chords where ``mask``: Hermite midpoints moved onto the curve."""
        if self.kind == "window" or not mask.any():
            return 0
        P, T = self.P, self.T
        idx = np.nonzero(mask)[0]
        p0, p1, t0, t1 = P[idx], P[idx + 1], T[idx], T[idx + 1]
        d = p1 - p0
        L = np.hypot(d[:, 0], d[:, 1])
        keep = L > 64.0 * _EPS * np.abs(P[idx]).max(1)   # below that, rounding: nothing to gain
        idx, p0, p1, t0, t1, d, L = idx[keep], p0[keep], p1[keep], t0[keep], t1[keep], d[keep], L[keep]
        if idx.size == 0:
            return 0
        mid = 0.5 * (p0 + p1) + (L / 8.0)[:, None] * (t0 - t1)
        vel = 1.5 * d - 0.25 * L[:, None] * (t0 + t1)
        vel /= np.hypot(vel[:, 0], vel[:, 1])[:, None]
        td = d / L[:, None]
        out, tan = mid.copy(), vel.copy()
        F = self.F
        ok = _project(F.ks, F.n, F.win, F.y0, F.v0, self.slot, np.ascontiguousarray(mid), td, 0.5 * L, out, tan)
        self.failed += int((~ok).sum())
        self.insert(idx, out, tan)
        return idx.size

    def densify(self, tol):
        if self.kind == "window":
            return
        for _ in range(_MAX_ROUNDS):
            dev, _ = _deviation(self.P, self.T)
            if not self.split(dev > tol):
                break
        self.max_dev = float(_deviation(self.P, self.T)[0].max(initial=0.0))


@njit(cache=True)
def _orient(ax, ay, bx, by, cx, cy):
    v = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
    return (v > 0.0) - (v < 0.0)


@njit(cache=True)
def _on_segment(ax, ay, bx, by, cx, cy):
    """c (collinear with a-b) within the box of a-b."""
    return min(ax, bx) <= cx <= max(ax, bx) and min(ay, by) <= cy <= max(ay, by)


@njit(cache=True)
def _meet(s, t):
    """Whether segments ``s`` and ``t`` (x0, y0, x1, y1) meet other than at one
    shared end point (touching and collinear overlap count)."""
    ax, ay, bx, by = s[0], s[1], s[2], s[3]
    cx, cy, dx, dy = t[0], t[1], t[2], t[3]
    shared = (ax == cx and ay == cy) or (ax == dx and ay == dy) or (bx == cx and by == cy) or \
        (bx == dx and by == dy)
    o1 = _orient(ax, ay, bx, by, cx, cy)
    o2 = _orient(ax, ay, bx, by, dx, dy)
    o3 = _orient(cx, cy, dx, dy, ax, ay)
    o4 = _orient(cx, cy, dx, dy, bx, by)
    if shared:
        if (ax == cx and ay == cy and bx == dx and by == dy) or (ax == dx and ay == dy and bx == cx and by == cy):
            return True  # the same segment twice
        # only a collinear overlap beyond the shared point counts
        if o1 == 0 and o2 == 0:
            return (_on_segment(ax, ay, bx, by, cx, cy) and not ((cx == ax and cy == ay) or (cx == bx and cy == by))) or \
                (_on_segment(ax, ay, bx, by, dx, dy) and not ((dx == ax and dy == ay) or (dx == bx and dy == by))) or \
                (_on_segment(cx, cy, dx, dy, ax, ay) and not ((ax == cx and ay == cy) or (ax == dx and ay == dy))) or \
                (_on_segment(cx, cy, dx, dy, bx, by) and not ((bx == cx and by == cy) or (bx == dx and by == dy)))
        return False
    if o1 != o2 and o3 != o4:
        return True
    return (o1 == 0 and _on_segment(ax, ay, bx, by, cx, cy)) or (o2 == 0 and _on_segment(ax, ay, bx, by, dx, dy)) or \
        (o3 == 0 and _on_segment(cx, cy, dx, dy, ax, ay)) or (o4 == 0 and _on_segment(cx, cy, dx, dy, bx, by))


@njit(cache=True)
def _cells(S, k, origin, size, cell, seg, m, count_only):
    """The grid cells segment ``S[k]`` passes through (column by column: in each
    column of cells, the rows between the segment's least and largest u
    there), written to ``cell``/``seg`` from ``m`` unless ``count_only``;
    returns the new ``m``."""
    x0, y0, x1, y1 = S[k, 0], S[k, 1], S[k, 2], S[k, 3]
    if x1 < x0:
        x0, y0, x1, y1 = x1, y1, x0, y0
    i0 = int(math.floor((x0 - origin[0]) / size - 1e-9))
    i1 = int(math.floor((x1 - origin[0]) / size + 1e-9))
    for i in range(i0, i1 + 1):
        a = max(x0, origin[0] + i * size)
        b = min(x1, origin[0] + (i + 1) * size)
        if x1 > x0:
            ya = y0 + (y1 - y0) * ((a - x0) / (x1 - x0))
            yb = y0 + (y1 - y0) * ((b - x0) / (x1 - x0))
        else:
            ya, yb = y0, y1
        # a billionth of a cell of slack for the rounding of the interpolation
        j0 = int(math.floor((min(ya, yb) - origin[1]) / size - 1e-9))
        j1 = int(math.floor((max(ya, yb) - origin[1]) / size + 1e-9))
        for j in range(j0, j1 + 1):
            if not count_only:
                cell[m] = (i + 2) * 4294967296 + (j + 2)
                seg[m] = k
            m += 1
    return m


@njit(cache=True)
def _crossings(S, origin, size, active):
    """Indices ``(i, j)``, i < j, of the segments of ``S`` (N x 4) that meet other
    than at a shared end point, one of them ``active``: every segment entered
    in the cells of side ``size`` (from ``origin``) that it passes through, an
    active segment tested against the others of its cells (after their boxes)."""
    n = S.shape[0]
    box = np.empty((n, 4))
    for k in range(n):
        box[k, 0], box[k, 1] = min(S[k, 0], S[k, 2]), max(S[k, 0], S[k, 2])
        box[k, 2], box[k, 3] = min(S[k, 1], S[k, 3]), max(S[k, 1], S[k, 3])
    dummy = np.empty(0, dtype=np.int64)
    total = 0
    for k in range(n):
        total = _cells(S, k, origin, size, dummy, dummy, total, True)
    cell = np.empty(total, dtype=np.int64)
    seg = np.empty(total, dtype=np.int64)
    m = 0
    for k in range(n):
        m = _cells(S, k, origin, size, cell, seg, m, False)
    order = np.argsort(cell)
    pairs = []
    start = 0
    while start < total:
        stop = start
        while stop < total and cell[order[stop]] == cell[order[start]]:
            stop += 1
        for p in range(start, stop):
            i = seg[order[p]]
            if not active[i]:
                continue
            for q in range(start, stop):
                j = seg[order[q]]
                if j == i or (active[j] and q < p):   # an active pair once
                    continue
                if box[i, 0] > box[j, 1] or box[j, 0] > box[i, 1] or box[i, 2] > box[j, 3] or box[j, 2] > box[i, 3]:
                    continue
                if _meet(S[i], S[j]):
                    pairs.append((min(i, j), max(i, j)))
        start = stop
    out = np.empty((len(pairs), 2), dtype=np.int64)
    for k in range(len(pairs)):
        out[k, 0], out[k, 1] = pairs[k]
    return out


def _segments(edges):
    """Every segment of the edges (N x 4), with its edge and chord index, and
    whether it is fresh (not yet tested)."""
    S, owner, fresh = [], [], []
    for k, ed in enumerate(edges):
        P = ed.P
        S.append(np.concatenate([P[:-1], P[1:]], 1))
        owner.append(np.stack([np.full(len(P) - 1, k), np.arange(len(P) - 1)], 1))
        fresh.append(ed.fresh)
    if not S:
        return np.empty((0, 4)), np.empty((0, 2), dtype=np.int64), np.empty(0, dtype=bool)
    return np.concatenate(S), np.concatenate(owner), np.concatenate(fresh)


def _find_crossings(edges, window=None):
    """The segment pairs that meet other than at a shared vertex, one of them
    fresh (every pair of earlier rounds was tested then); every chord is then
    marked tested."""
    S, owner, fresh = _segments(edges)
    for ed in edges:
        ed.fresh[:] = False
    if len(S) < 2 or not fresh.any():
        return np.empty((0, 2), dtype=np.int64), owner
    lo = S.reshape(-1, 2).min(0)
    length = np.hypot(S[:, 2] - S[:, 0], S[:, 3] - S[:, 1])
    size = max(float(np.median(length)), 1e-12 * float(np.abs(S).max()))
    pairs = _crossings(np.ascontiguousarray(S), lo.astype(float), size, fresh)
    return (np.unique(pairs, axis=0) if len(pairs) else pairs), owner


def _node(edges, stuck, owner):
    """Node the segment pairs ``stuck`` (indices into ``owner``): where two
    segments cross, their intersection point becomes a vertex of both; where
    an end point of one lies on the other (touching, collinear overlap), it
    becomes a vertex of the other.  For chords within rounding of each other
    that halving cannot separate: both faces then pass through the same
    points (a sliver narrower than rounding is pinched there).  Returns the
    chords cut in each edge (``{edge: sorted chord indices, one per point}``)."""
    S, _, _ = _segments(edges)
    todo = {}

    def add(k, c, p0, p1, x):
        if (x[0] == p0[0] and x[1] == p0[1]) or (x[0] == p1[0] and x[1] == p1[1]):
            return
        d = (p1[0] - p0[0], p1[1] - p0[1])
        t = ((x[0] - p0[0]) * d[0] + (x[1] - p0[1]) * d[1]) / (d[0] * d[0] + d[1] * d[1])
        todo.setdefault(k, {})[(int(c), min(max(t, 0.0), 1.0), float(x[0]), float(x[1]))] = d

    for i, j in stuck:
        (ka, ca), (kb, cb) = owner[i], owner[j]
        a, b = S[i], S[j]
        A0, A1, B0, B1 = a[:2], a[2:], b[:2], b[2:]
        ends = False
        for seg, (k, c, p0, p1), q in ((a, (ka, ca, A0, A1), B0), (a, (ka, ca, A0, A1), B1),
                                      (b, (kb, cb, B0, B1), A0), (b, (kb, cb, B0, B1), A1)):
            if _orient(p0[0], p0[1], p1[0], p1[1], q[0], q[1]) == 0 and \
                    _on_segment(p0[0], p0[1], p1[0], p1[1], q[0], q[1]):
                add(k, c, p0, p1, q)
                ends = True
        if ends:
            continue
        r, s = A1 - A0, B1 - B0
        den = r[0] * s[1] - r[1] * s[0]
        if den == 0.0:
            continue
        w = B0 - A0
        t = min(max((w[0] * s[1] - w[1] * s[0]) / den, 0.0), 1.0)
        x = A0 + t * r
        add(ka, ca, A0, A1, x)
        add(kb, cb, B0, B1, x)
    cut = {}
    for k, points in todo.items():
        keys = sorted(points)
        idx = np.array([c for c, *_ in keys], dtype=np.int64)
        X = np.array([[x, y] for _, _, x, y in keys])
        T = np.array([points[key] for key in keys], dtype=float)
        T /= np.maximum(np.hypot(T[:, 0], T[:, 1]), 1e-300)[:, None]
        edges[k].insert(idx, X, T)
        cut[k] = idx
    return cut


def _same_curve(a, b, i, j, slack):
    """Whether chord ``i`` of edge ``a`` has both ends on the curve of edge ``b``
    (within ``slack`` of the position, times the margin's gradient), and chord
    ``j`` of ``b`` both ends on that of ``a``: the same border traced from both
    sides but not matched as one edge by border_graph (halving such chords
    only makes them cross again)."""
    for ed, P in ((b, a.P[i:i + 2]), (a, b.P[j:j + 2])):
        if ed.F is None:
            return False
        for x in P:
            g = ed.F(x)
            grad = math.hypot(g[1][ed.slot], g[2][ed.slot])
            if not abs(g[0][ed.slot]) <= slack * grad:
                return False
    return True


def _untangle(edges, window, slack):
    """Halve the segments that meet other than at a shared vertex until none does,
    the rounds run out or the vertices have doubled; pairs that halving cannot
    separate (chords on the same curve to rounding, :func:`_same_curve`, or
    both too short to halve) are noded instead (:func:`_node`).  Only the
    chords changed since a round are tested in the next.  Returns (rounds,
    crossing pairs found in the last round, points noded)."""
    budget = sum(len(ed.P) for ed in edges)
    added = noded = 0
    pairs = ()
    for rounds in range(_MAX_ROUNDS + 1):
        pairs, owner = _find_crossings(edges, window)
        if not len(pairs):
            return rounds, 0, noded
        marks, stuck = {}, []
        if rounds == _MAX_ROUNDS or added > budget:
            break
        for i, j in pairs:
            (ka, ca), (kb, cb) = owner[i], owner[j]
            ka, ca, kb, cb = int(ka), int(ca), int(kb), int(cb)
            A, B = edges[ka], edges[kb]
            if not (A.splittable(ca) or B.splittable(cb)) or _same_curve(A, B, ca, cb, slack):
                stuck.append((i, j))
                continue
            marks.setdefault(ka, set()).add(ca)
            marks.setdefault(kb, set()).add(cb)
        # node first (the pairs' indices are those of the segments found), then halve
        # the marked chords at their indices after the points noded before them
        cut = _node(edges, stuck, owner) if stuck else {}
        node = sum(len(c) for c in cut.values())
        noded += node
        split = 0
        for k, chords in marks.items():
            c = np.array(sorted(chords), dtype=np.int64)
            if k in cut:
                c = c + np.searchsorted(cut[k], c, side="left")
            mask = np.zeros(len(edges[k].P) - 1, dtype=bool)
            mask[c] = True
            split += edges[k].split(mask)
        added += split
        if not split and not node:
            break
    return rounds, int(len(pairs)), noded


def tolerance_floor(window):
    """The least tolerance of the export in ``window`` (e0, e1, u0, u1): a few
    ulps of its largest coordinate (a smaller deviation is rounding)."""
    return _TOLERANCE_ULPS * _EPS * max(max(map(abs, window)), np.finfo(float).tiny)


def _signed_area(R):
    """Shoelace area of the closed ring ``R``, about its first vertex (less cancellation)."""
    x, y = R[:, 0] - R[0, 0], R[:, 1] - R[0, 1]
    return 0.5 * float(np.dot(x[:-1], y[1:]) - np.dot(x[1:], y[:-1]))


class Partition:
    """The faces of traced regions built from densified border-graph edges."""

    def __init__(self, regions, tolerance=None, graph=None, untangle=True):
        regions = [regions] if isinstance(regions, _rg.Region) else list(regions)
        self.regions = regions
        self.graph = graph if graph is not None else _rg.border_graph(regions)
        if regions:
            e, u = regions[0].e, regions[0].u
        else:
            e, u = (0.0, 1.0), (0.0, 1.0)
        self.window = (float(e[0]), float(e[1]), float(u[0]), float(u[1]))
        self.scale = max(e[1] - e[0], u[1] - u[0])
        self.tolerance = max(TOLERANCE * self.scale if tolerance is None else float(tolerance),
                             tolerance_floor(self.window))
        margins = _rg._GraphMargins(regions)
        nodes = self.graph.nodes
        self.edges = []
        for a, b, arc in self.graph.edges:
            F = margins(arc) if arc.kind != "window" else None
            self.edges.append(_Edge(arc, F, (nodes[a].e, nodes[a].u), (nodes[b].e, nodes[b].u)))
        for ed in self.edges:
            ed.densify(self.tolerance)
        self.rounds, self.crossings, self.noded = \
            _untangle(self.edges, self.window, _SAME * max(map(abs, self.window))) if untangle else (0, None, 0)
        self.max_deviation = max((ed.max_dev for ed in self.edges), default=0.0)
        self.failed = sum(ed.failed for ed in self.edges)

    def ring(self, key):
        """The closed ring (N x 2, first point repeated) of ``graph.rings[key]``."""
        parts = []
        for index, rev in self.graph.rings[key]:
            P = self.edges[index].P
            parts.append((P[::-1] if rev else P)[:-1])
        R = np.concatenate(parts)
        return np.concatenate([R, R[:1]])

    def faces(self):
        """``{(region, component): [[shell, holes...], ...]}``: the polygons of each
        component (more than one where its boundary passes a node twice)."""
        rings = {}
        for (ri, ci, hi) in sorted(self.graph.rings):
            rings.setdefault((ri, ci), []).append(self.ring((ri, ci, hi)))
        return {key: _polygons(rs) for key, rs in rings.items()}


def _loops(R):
    """The closed ring ``R`` cut into loops that pass no vertex twice: where the
    ring comes back to a vertex (a node where the region touches itself), the
    loop since the first visit is taken out."""
    out, stack, seen = [], [], {}
    for x in map(tuple, R[:-1]):
        if x in seen:
            k = seen[x]
            loop = stack[k:]
            for y in loop[1:]:
                del seen[y]
            del stack[k + 1:]
            if len(loop) >= 3:
                out.append(np.array(loop + [loop[0]]))
        else:
            seen[x] = len(stack)
            stack.append(x)
    if len(stack) >= 3:
        out.append(np.array(stack + [stack[0]]))
    return out


def _perimeter(R):
    d = np.diff(R, axis=0)
    return float(np.hypot(d[:, 0], d[:, 1]).sum())


def _polygons(rings):
    """Simple polygons from the rings of one component (outer ring first):
    every ring cut into loops (:func:`_loops`), less those that turn against
    their ring with an area below rounding; the counter-clockwise loops
    are shells, the clockwise ones holes, each in the smallest shell around
    one of its vertices."""
    loops = []
    for R in rings:
        sign = _signed_area(R) > 0
        scale = float(np.abs(R).max())
        for L in _loops(R):
            # a loop turning against its ring and thinner than rounding is a sliver
            # pinched by _node where its sides cross to rounding: no face
            a = _signed_area(L)
            if (a > 0) != sign and abs(a) <= _SAME * scale * _perimeter(L):
                continue
            loops.append(L)
    shells = [L for L in loops if _signed_area(L) > 0]
    holes = [L for L in loops if _signed_area(L) <= 0]
    shells.sort(key=_signed_area)
    out = [[S] for S in shells]
    for H in holes:
        x = H[len(H) // 2]
        for poly in out:
            if _rg._inside_polygon(poly[0], x):
                poly.append(H)
                break
    return out


def coverage(regions, resolution, max_iter):
    """The sliding area of the seed scan (``resolution`` x ``resolution`` pixel
    centres of the regions' window, or ``resolution = (n_e, n_u)``, up to
    ``max_iter`` steps): (area, pixels)."""
    r = regions[0]
    n_e, n_u = (resolution, resolution) if np.ndim(resolution) == 0 else (int(resolution[0]), int(resolution[1]))
    es, us = _rg._grid(r.e, r.u, n_e, n_u)
    _, _, steps = _rg._label_grid(es, us, max_iter, 1.0, 0.0)
    sliding = int((steps > 0).sum())
    area = (r.e[1] - r.e[0]) * (r.u[1] - r.u[0]) * sliding / (n_e * n_u)
    return area, sliding


def untraced(part, max_iter=1000):
    """Words seen just outside a traced edge whose other side no traced word
    claims (``outside`` empty): ``{word text: (Word, [e, u])}``, probed at a
    distance of 1e-9 of the window's size along the margin's gradient."""
    regions = part.regions
    known = {r.word.format(ascii=True) for r in regions}
    # itineraries seen (the traced words' own first): a word is built once per itinerary
    seen = {np.asarray(_rg.itinerary_of_word(r.word), dtype=np.int64).tobytes() for r in regions}
    out = {}
    buf = np.empty(max_iter, dtype=np.int64)
    from ..symbolic import word_from_impacts

    for ed, (_, _, arc) in zip(part.edges, part.graph.edges):
        if arc.kind == "window" or arc.outside:
            continue
        mid = ed.P[len(ed.P) // 2]
        g = ed.F(mid)
        n = math.hypot(g[1][ed.slot], g[2][ed.slot])
        if not n > 0 or not math.isfinite(n):
            continue
        h = 1e-9 * part.scale
        x = (mid[0] - h * g[1][ed.slot] / n, mid[1] - h * g[2][ed.slot] / n)
        w = part.window
        if not (w[0] <= x[0] <= w[1] and w[2] <= x[1] <= w[3]):
            continue
        k = _rg._itinerary_of(x[0], x[1], 1.0, 0.0, buf.size, buf)
        if k <= 0:
            continue
        key = buf[:k].tobytes()
        if key in seen:
            continue
        seen.add(key)
        word = word_from_impacts(buf[:k].tolist())
        text = word.format(ascii=True)
        if text not in known and text not in out:
            out[text] = (word, [float(x[0]), float(x[1])])
    return out


def _reason(r):
    if r.complete:
        return None
    return (f"{r.failures} of the word's walks around a boundary did not close: "
            + ("no component traced" if not r.components else "components may be missing"))


def _untraced_reason():
    return ("not traced: seen just outside a traced arc at seen_at, but no seed pixel centre lies "
            "in its region")


def build(regions, tolerance=None, resolution=None, max_iter=1000, untangle=True, graph=None):
    """The partition of ``regions``, its faces, the untraced words and the
    metadata (see regions_geojson): ``(partition, faces, untraced, metadata)``;
    ``graph``: their :func:`stairbounce.border_graph` when the caller has it."""
    from .._version import __version__

    part = Partition(regions, tolerance, graph=graph, untangle=untangle)
    faces = part.faces()
    missing = untraced(part, max_iter)
    traced = sum(c.area for r in part.regions for c in r.components)
    polygon = sum(_signed_area(R) for polys in faces.values() for rings in polys for R in rings)
    e0, e1, u0, u1 = part.window
    meta = {
        "generator": f"stairbounce {__version__} regions_geojson",
        "coordinates": "[e, u]: restitution coefficient and normalised horizontal speed "
                       "(not longitude and latitude)",
        "window": {"e": [e0, e1], "u": [u0, u1]},
        "window_area": (e1 - e0) * (u1 - u0),
        "tolerance": part.tolerance,
        "max_deviation": part.max_deviation,
        "words": len(part.regions),
        "components": sum(len(r.components) for r in part.regions),
        "incomplete": [r.word.format(ascii=True) for r in part.regions if not r.complete],
        "untraced": sorted(missing),
        "traced_area": traced,
        "polygon_area": polygon,
        "edges": len(part.edges),
        "shared_edges": sum(1 for _, _, a in part.graph.edges if a.outside and a.outside != a.inside),
        "vertices": int(sum(len(ed.P) for ed in part.edges)),
        "newton_failures": part.failed,
        "crossings": part.crossings,
        "noded": part.noded,
        "seed_resolution": None, "max_iter": max_iter, "sliding_pixels": None,
        "sliding_area": None, "coverage": None,
    }
    if resolution is not None and part.regions:
        sliding, pixels = coverage(part.regions, resolution, max_iter)
        if np.ndim(resolution) == 1 and resolution[0] == resolution[1]:
            resolution = int(resolution[0])  # pixels per side; [n_e, n_u] where they differ
        meta.update({"seed_resolution": resolution if np.ndim(resolution) == 0 else [int(n) for n in resolution],
                     "sliding_pixels": pixels,
                     "sliding_area": sliding, "coverage": traced / sliding if sliding else None})
    return part, faces, missing, meta


def _tangles(part):
    """The boxes ``[e0, e1, u0, u1]`` where chords still cross after untangling
    (borders of different words within rounding of each other, near the tongue
    tips): the bounding boxes of every crossing pair's two segments, padded by
    the tolerance, merged where they overlap (into their common bounding box)."""
    import shapely

    for ed in part.edges:
        ed.fresh[:] = True
    pairs, _ = _find_crossings(part.edges, part.window)
    if not len(pairs):
        return []
    S, _, _ = _segments(part.edges)
    A, B = S[pairs[:, 0]], S[pairs[:, 1]]
    lo = np.minimum(np.minimum(A[:, :2], A[:, 2:]), np.minimum(B[:, :2], B[:, 2:])) - part.tolerance
    hi = np.maximum(np.maximum(A[:, :2], A[:, 2:]), np.maximum(B[:, :2], B[:, 2:])) + part.tolerance
    w = part.window
    lo = np.maximum(lo, [w[0], w[2]])
    hi = np.minimum(hi, [w[1], w[3]])
    # boxes closer than _TANGLE_GAP of the window's size form one tangle (the
    # accumulation at one tongue tip): the bounding box of them all
    gap = 0.5 * _TANGLE_GAP * part.scale
    while True:
        grown = shapely.box(lo[:, 0] - gap, lo[:, 1] - gap, hi[:, 0] + gap, hi[:, 1] + gap)
        # the merged groups' bounding boxes (a box in two of them joins both: they
        # then overlap and merge in the next pass)
        groups = shapely.envelope(shapely.get_parts(shapely.union_all(grown)))
        which = shapely.STRtree(groups).query(shapely.points(0.5 * (lo + hi)), predicate="intersects")
        n = len(groups)
        glo = np.full((n, 2), np.inf)
        ghi = np.full((n, 2), -np.inf)
        np.minimum.at(glo, which[1], lo[which[0]])
        np.maximum.at(ghi, which[1], hi[which[0]])
        # a group no box's centre falls in (degenerate boxes of zero width) has no extent
        member = np.isfinite(glo).all(1) & np.isfinite(ghi).all(1)
        glo, ghi = glo[member], ghi[member]
        if len(glo) == len(lo):
            break
        lo, hi = glo, ghi
    return sorted([float(a[0]), float(b[0]), float(a[1]), float(b[1])] for a, b in zip(lo, hi))


def _clip(geometry, boxes):
    """``geometry`` (GeoJSON) less the ``boxes``: its crossings, all inside them,
    resolved by shapely's make_valid first; outer rings counter-clockwise.
    Returns (geometry or None, its area, the area clipped)."""
    import shapely
    from shapely.geometry import mapping, shape
    from shapely.geometry.polygon import orient

    v = shapely.make_valid(shape(geometry))
    g = v.difference(shapely.MultiPolygon([shapely.box(b[0], b[2], b[1], b[3]) for b in boxes]))
    polys = [orient(p, 1.0) for p in shapely.get_parts(g) if p.geom_type == "Polygon" and p.area > 0]
    if not polys:
        return None, 0.0, float(v.area)
    out = polys[0] if len(polys) == 1 else shapely.MultiPolygon(polys)
    m = mapping(out)
    return {"type": m["type"], "coordinates": _lists(m["coordinates"])}, float(out.area), float(v.area - out.area)


def _meets(polys, boxes):
    """Whether the bounding box of the rings ``polys`` meets one of the ``boxes``."""
    P = np.concatenate([R for rings in polys for R in rings])
    (e0, u0), (e1, u1) = P.min(0), P.max(0)
    return any(e0 <= b[1] and b[0] <= e1 and u0 <= b[3] and b[2] <= u1 for b in boxes)


def _lists(c):
    return [_lists(x) for x in c] if isinstance(c, (list, tuple)) and c and isinstance(c[0], (list, tuple)) \
        else [float(x) for x in c]


def _tangle_reason(b):
    return (f"accumulation of borders in e {b[0]:.6g}..{b[1]:.6g} x u {b[2]:.6g}..{b[3]:.6g}: borders of "
            "different words closer than rounding whose chords still cross after untangling; clipped "
            "out of every polygon, not resolved at this tolerance")


def geojson(regions, tolerance=None, resolution=None, max_iter=1000, graph=None):
    """regions_geojson's work (see its docstring)."""
    part, faces, missing, meta = build(regions, tolerance, resolution, max_iter, graph=graph)
    boxes = _tangles(part) if part.crossings else []
    feats = []
    for ri, r in enumerate(part.regions):
        base = {"word": r.word.format(ascii=True), "period": r.word.period, "impacts": r.word.impacts,
                "complete": bool(r.complete), "reason": _reason(r)}
        if not r.components:
            feats.append({"type": "Feature", "geometry": None,
                          "properties": dict(base, component=None, area=None, area_error=None,
                                             polygon_area=0.0, clipped_area=0.0, kinds={}, corners=0)})
            continue
        for ci, comp in enumerate(r.components):
            polys = faces[(ri, ci)]
            coords = [[R.tolist() for R in rings] for rings in polys]
            geometry = ({"type": "Polygon", "coordinates": coords[0]} if len(coords) == 1 else
                        {"type": "MultiPolygon", "coordinates": coords})
            polygon_area = sum(_signed_area(R) for rings in polys for R in rings)
            clipped = 0.0
            if boxes and _meets(polys, boxes):
                geometry, polygon_area, clipped = _clip(geometry, boxes)
            feats.append({
                "type": "Feature", "geometry": geometry,
                "properties": dict(base, component=ci, area=comp.area, area_error=comp.area_error,
                                   polygon_area=polygon_area, clipped_area=clipped,
                                   kinds=comp.kinds, corners=len(comp.corners)),
            })
    for text, (word, x) in sorted(missing.items()):
        feats.append({"type": "Feature", "geometry": None, "properties": {
            "word": text, "period": word.period, "impacts": word.impacts, "complete": False,
            "reason": _untraced_reason(), "seen_at": x, "component": None, "area": None,
            "area_error": None, "polygon_area": 0.0, "clipped_area": 0.0, "kinds": {}, "corners": 0}})
    for b in boxes:
        ring = [[b[0], b[2]], [b[1], b[2]], [b[1], b[3]], [b[0], b[3]], [b[0], b[2]]]
        feats.append({"type": "Feature", "geometry": {"type": "Polygon", "coordinates": [ring]}, "properties": {
            "word": None, "period": None, "impacts": None, "complete": False, "reason": _tangle_reason(b),
            "component": None, "area": None, "area_error": None,
            "polygon_area": (b[1] - b[0]) * (b[3] - b[2]), "clipped_area": 0.0, "kinds": {}, "corners": 0}})
    if boxes:
        meta["polygon_area"] = sum(f["properties"]["polygon_area"] for f in feats if f["properties"]["word"])
    meta["clipped"] = boxes
    meta["overlap_bound"] = _OVERLAP_BOUND
    _check_finite(feats, part.window)
    return {"type": "FeatureCollection", "metadata": meta, "features": feats}


# what the export guarantees about two features' overlap (regions_geojson)
_OVERLAP_BOUND = ("two features overlap by at most max_deviation times the sum of their perimeters "
                  "(numerical: each ring lies within max_deviation of its traced borders, which do not "
                  "overlap); where borders of different words come within the tolerance of each other "
                  "(the tongue tips, e -> 0) such overlaps of about 1e-15 of the window remain")


def _check_finite(feats, window):
    """ValueError unless every coordinate of ``feats`` is a finite float (RFC 7946
    has no Infinity or NaN): the window is then too narrow to export."""
    for f in feats:
        g = f["geometry"]
        if g is not None and not all(np.isfinite(R).all() for R in _rings(g)):
            e0, e1, u0, u1 = window
            raise ValueError(f"the window e {e0!r}:{e1!r} x u {u0!r}:{u1!r} is too narrow to export: "
                             f"feature {f['properties']['word']!r} has non-finite coordinates")


def _rings(g):
    polys = [g["coordinates"]] if g["type"] == "Polygon" else g["coordinates"]
    return [np.asarray(R, dtype=float) for rings in polys for R in rings]


def _ticks(lo, hi, most=6):
    """Round tick values in [lo, hi] (steps 1, 2 or 5 times a power of ten) and their digits."""
    span = hi - lo
    step = 10.0 ** math.floor(math.log10(span / most))
    for f in (1.0, 2.0, 5.0, 10.0):
        if span / (f * step) <= most:
            step *= f
            break
    digits = max(0, -int(math.floor(math.log10(step) + 1e-9)))
    first = math.ceil(lo / step - 1e-9)
    vals = [k * step for k in range(first, int(math.floor(hi / step + 1e-9)) + 1)]
    return vals, digits


def svg(regions, size=800, tolerance=None, resolution=None, max_iter=1000, graph=None):
    """regions_svg's work (see its docstring)."""
    from html import escape

    part, faces, missing, meta = build(regions, tolerance, resolution, max_iter, untangle=False, graph=graph)
    e0, e1, u0, u1 = part.window
    left, top, right, bottom = 84, 48, 230, 64
    W, H = left + size + right, top + size + bottom
    sx, sy = size / (e1 - e0), size / (u1 - u0)

    def xy(P):
        return " ".join(f"{left + (x - e0) * sx:.3f},{top + (u1 - y) * sy:.3f}" for x, y in P)

    cov = meta["coverage"]
    title = (f"{meta['words']} words traced in e [{e0:g}, {e1:g}] x u [{u0:g}, {u1:g}]"
             + (f"; {100 * cov:.2f} % of the seed scan's sliding area" if cov is not None else ""))
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" viewBox="0 0 {W} {H}" '
           f'font-family="sans-serif" font-size="12">',
           f"<title>{escape(title)}</title>",
           f'<rect width="{W}" height="{H}" fill="white"/>',
           f'<clipPath id="window"><rect x="{left}" y="{top}" width="{size}" height="{size}"/></clipPath>',
           f'<g clip-path="url(#window)">']
    for (ri, ci), polys in sorted(faces.items()):
        r = part.regions[ri]
        d = " ".join("M" + xy(R[:-1]) + "Z" for rings in polys for R in rings)
        out.append(f'<path d="{d}" fill="{FACE_COLOUR}" fill-rule="evenodd" stroke="none">'
                   f"<title>{escape(r.word.format(ascii=True))}: area {r.components[ci].area:.6g}"
                   f"</title></path>")
    counts = {}
    for ed, (_, _, arc) in zip(part.edges, part.graph.edges):
        if arc.kind == "window":
            continue
        counts[arc.kind] = counts.get(arc.kind, 0) + 1
        sides = f"{arc.inside} | {arc.outside or 'not traced'}"
        out.append(f'<polyline fill="none" stroke="{KIND_COLOURS[arc.kind]}" stroke-width="0.8" '
                   f'points="{xy(ed.P)}"><title>{arc.kind} at step {arc.step}: {escape(sides)}</title></polyline>')
    out.append("</g>")
    # the window (the axes' frame), ticks and labels
    out.append(f'<rect x="{left}" y="{top}" width="{size}" height="{size}" fill="none" '
               f'stroke="{KIND_COLOURS["window"]}" stroke-width="1.5"/>')
    vals, dig = _ticks(e0, e1)
    for v in vals:
        x = left + (v - e0) * sx
        out.append(f'<line x1="{x:.2f}" y1="{top + size}" x2="{x:.2f}" y2="{top + size + 6}" stroke="black"/>'
                   f'<text x="{x:.2f}" y="{top + size + 20}" text-anchor="middle">{v:.{dig}f}</text>')
    vals, dig = _ticks(u0, u1)
    for v in vals:
        y = top + (u1 - v) * sy
        out.append(f'<line x1="{left - 6}" y1="{y:.2f}" x2="{left}" y2="{y:.2f}" stroke="black"/>'
                   f'<text x="{left - 9}" y="{y + 4:.2f}" text-anchor="end">{v:.{dig}f}</text>')
    out.append(f'<text x="{left + size / 2}" y="{top + size + 44}" text-anchor="middle">'
               f"e (restitution coefficient)</text>")
    out.append(f'<text transform="translate(18 {top + size / 2}) rotate(-90)" text-anchor="middle">'
               f"u (normalised horizontal speed)</text>")
    out.append(f'<text x="{left}" y="{top - 18}" font-size="13">{escape(title)}</text>')
    # the legend
    lx, ly = left + size + 20, top + 10
    out.append(f'<text x="{lx}" y="{ly}" font-weight="bold">border (event at a step)</text>')
    for i, k in enumerate(("graze", "edge", "chatter", "window")):
        y = ly + 22 + 20 * i
        what = {"graze": "graze: first contact", "edge": "edge: a later impact",
                "chatter": "chatter: accumulation", "window": "the window"}[k]
        n = f" ({counts.get(k, 0)})" if k != "window" else ""
        out.append(f'<line x1="{lx}" y1="{y - 4}" x2="{lx + 24}" y2="{y - 4}" stroke="{KIND_COLOURS[k]}" '
                   f'stroke-width="2.5"/><text x="{lx + 32}" y="{y}">{what}{n}</text>')
    y = ly + 22 + 20 * 4 + 8
    out.append(f'<rect x="{lx}" y="{y - 12}" width="24" height="14" fill="{FACE_COLOUR}"/>'
               f'<text x="{lx + 32}" y="{y}">traced region ({meta["components"]})</text>')
    y += 20
    out.append(f'<rect x="{lx}" y="{y - 12}" width="24" height="14" fill="white" stroke="#bbbbbb"/>'
               f'<text x="{lx + 32}" y="{y}">no slide, or not traced</text>')
    y += 20
    out.append(f'<text x="{lx}" y="{y}">({len(missing)} words seen beside</text>'
               f'<text x="{lx}" y="{y + 16}">arcs but not traced)</text>')
    out.append("</svg>")
    return "\n".join(out) + "\n", meta


def write(regions, path, overwrite=False, tolerance=None, resolution=None, max_iter=1000, graph=None):
    """write_regions's work: ``(path, metadata)``; ``graph`` as in :func:`build`."""
    import json
    from pathlib import Path

    from .._io import atomic_path

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".geojson", ".json", ".svg"):
        raise ValueError(f"out must end in .geojson, .json or .svg, got {path.name!r}")
    if suffix == ".svg":
        text, meta = svg(regions, tolerance=tolerance, resolution=resolution, max_iter=max_iter, graph=graph)
    else:
        doc = geojson(regions, tolerance, resolution, max_iter, graph=graph)
        text, meta = json.dumps(doc, allow_nan=False), doc["metadata"]
    with atomic_path(path, overwrite) as tmp:
        Path(tmp).write_text(text)
    return path, meta


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
    border_graph left as two edges, two borders of different words closer
    than rounding near the tongue tips, or a sliver narrower than rounding)
    or both too short to halve: their crossing point is made a vertex of
    both (noded, counted in ``metadata.noded``), and a ring's inverted loop
    thinner than rounding is dropped.  Pairs still crossing when the vertex
    budget is spent are counted in ``metadata.crossings``.  Where that count
    is 0, every polygon is simple and two polygons meet only along shared
    edges and at vertices (``shapely.is_valid`` and zero intersection area
    on the Fig. 5e window, with corners too, e 0.30-0.36 x u 0.32-0.38, and
    the Fig. 4 window seeded at 32: numerical, tests/test_regions_export.py).
    Where pairs are left (near the tongue tips, e -> 0, where infinitely many
    borders accumulate and borders of different words come within rounding
    of each other: the Fig. 4 window seeded at 128), the tangles are
    clipped: the bounding box of each pair's two segments, padded by the
    tolerance, boxes closer than 1 % of the window's size merged, is cut out
    of every polygon (shapely's make_valid, then the difference) and
    exported as its own feature (``word`` null, ``complete: false``, the
    reason: "accumulation of borders ...; not resolved at this
    tolerance"), listed in ``metadata.clipped``: the partition stays
    gap-free and every polygon valid (the Fig. 4 window seeded at 48 and
    128, e 0.30-0.36 x u 0.32-0.38 seeded at 500: numerical,
    docs/guide/regions.md).

    Properties of a polygon: ``word``, ``period``, ``impacts``,
    ``component``; ``area``, the traced area of the component (the shoelace
    sum of the dense traced curve plus the cubic Hermite correction of every
    chord: exact to ``area_error``) and ``polygon_area``, the area of the
    exported rings themselves (outer minus holes; it differs from ``area`` by
    at most about the perimeter times ``tolerance``, and the area clipped,
    ``clipped_area``, besides); ``kinds`` (arcs by
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
    ``crossings`` (segment pairs still meeting before clipping), ``clipped``
    (the boxes ``[e0, e1, u0, u1]`` cut out) and, with ``resolution``,
    the window's coverage: ``sliding_area``, the sliding area of a scan of
    ``resolution`` x ``resolution`` pixel centres (the seed scan of
    :func:`window_regions` when given its resolution and ``max_iter``), and
    ``coverage = traced_area / sliding_area``, and ``overlap_bound``, the
    overlap the export guarantees between two features: at most
    ``max_deviation`` times the sum of their perimeters (numerical; on the
    whole plane seeded at 24 one pair at a tongue tip overlaps by 1.9e-15 of
    the window, within that bound).  No coordinate is ever Infinity or NaN
    (the file is strict JSON); a window too narrow for that is refused by a
    ValueError naming it.

    Parameters
    ----------
    tolerance : float > 0, default 1e-6 times the larger side of the window
        Largest deviation of a chord from the traced curve; never below 4
        ulps of the window's largest coordinate (a smaller one is raised to
        that: ``metadata.tolerance`` is the one used).
    resolution : int >= 2, optional
        The seed scan's pixels per side, for ``coverage``.
    max_iter : int >= 1, default 1000
        Steps of that scan (and of the probes beside untraced arcs).
    """
    from . import export as _region_export

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
    from . import export as _region_export

    regions = _region_list("regions", regions)
    size = check_count("size", size, 16, 100000)
    tolerance, resolution, max_iter = _export_options(tolerance, resolution, max_iter)
    return _region_export.svg(regions, size, tolerance, resolution, max_iter)[0]


def write_regions(regions, path, overwrite=False, *, tolerance=None, resolution=None, max_iter=1000):
    """write_regions(regions, path, overwrite=False, *, tolerance=None, resolution=None, max_iter=1000) -> Path

    Write ``regions`` as GeoJSON (``.geojson``/``.json``, :func:`regions_geojson`)
    or SVG (``.svg``, :func:`regions_svg`), atomically; ValueError for
    another suffix."""
    from . import export as _region_export

    tolerance, resolution, max_iter = _export_options(tolerance, resolution, max_iter)
    return _region_export.write(regions, path, overwrite, tolerance, resolution, max_iter)[0]
