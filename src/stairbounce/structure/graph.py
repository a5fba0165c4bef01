"""The planar graph of a window's borders (:func:`border_graph`,
:class:`BorderGraph`): the traced regions' arcs cut at every corner on them
(the junctions with another region's boundary), so that a piece of border
shared by two regions is one edge and edges meet only at nodes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .. import _validate as _v
from .continuation import _Margins, _correct, _noise, _tangent, _unit
from .regions import BorderArc, Corner, Region, _chord_position, itinerary_of_word

__all__ = ["BorderGraph", "border_graph"]


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
