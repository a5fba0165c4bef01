"""What the explorer draws over the map: the tongues and the no-sliding curve
(:func:`overlay_curves`), the exact border points of the view
(:func:`border_overlay`), the traced borders (:func:`trace_slices`,
:func:`traced_overlay`) and the words' table row of a tapped word
(:func:`word_row`).

Pure Python, no Panel or Bokeh; :mod:`stairbounce.explorer.view` re-exports
everything here.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from .. import plane
from ..model import tongue
from .render import grid_scan_slices
from .window import _UNBOUNDED, BORDER_SIDE, SLICE_WORK, TRACE_SIDE, View

# --------------------------------------------------------------------------- #
# Overlays and the tapped point                                               #
# --------------------------------------------------------------------------- #


def overlay_curves(view: View, samples: int = 400, max_tongues: int = 400) -> dict:
    """overlay_curves(view, samples=400, max_tongues=400) -> dict

    Curves of the paper over the view's e range, as lists of polylines.

    ``"tongues"``: the outline of every (n, 0^inf) tongue of Theorem 3.1 that
    meets the window, ``sqrt((n-1)/2) < u <= sqrt(n/2) (1-e)/(1+e)`` (bounds
    from :func:`stairbounce.tongue`), closed at the e where the two bounds
    meet; ``"no_sliding"``: Corollary 2.1's ``u = (1-e)/(2 sqrt(2e))``
    (:func:`stairbounce.plane.no_sliding_curve`).  Each value is
    ``(xs, ys)``, two lists of 1-D arrays; at most ``max_tongues`` tongues
    (the ones nearest the window's bottom).
    """
    e = np.linspace(view.e_lo, min(view.e_hi, np.nextafter(1.0, 0.0)), samples)
    txs, tys = [], []
    n_first = max(1, int(2.0 * view.u_lo**2))  # sqrt(n/2) <= u_lo: the tongue lies below
    n_last = min(n_first + max_tongues, int(2.0 * view.u_hi**2) + 1)
    for n in range(n_first, n_last + 1):
        u_low, top0 = tongue(n, 0.0)
        if top0 <= view.u_lo or u_low >= view.u_hi:
            continue
        # the bounds meet where (1-e)/(1+e) = u_low / top0
        r = u_low / top0
        e_tip = (1.0 - r) / (1.0 + r)
        inside = e < e_tip
        if not inside.any():
            continue
        ee = np.concatenate([e[inside], [e_tip]]) if e_tip <= view.e_hi else e[inside]
        top = top0 * (1.0 - ee) / (1.0 + ee)
        xs = np.concatenate([ee, ee[::-1]])
        ys = np.concatenate([top, np.full(ee.size, u_low)[::-1]])
        txs.append(xs)
        tys.append(ys)
    with np.errstate(divide="ignore"):
        ns = plane.no_sliding_curve(e)
    ok = np.isfinite(ns)
    return {"tongues": (txs, tys), "no_sliding": ([e[ok]], [ns[ok]])}


def border_grid(view: View, side: int = BORDER_SIDE) -> tuple:
    """border_grid(view, side=BORDER_SIDE) -> ((e_lo, e_hi, n_e), (u_lo, u_hi, n_u))

    The window arguments of the grid of at most ``side`` x ``side`` pixels of
    the view's window on which the exact borders and the tap's word table row
    are computed (the view's own pixels when it is no larger).
    """
    n_e = max(2, min(side, view.width))
    n_u = max(2, min(side, view.height))
    return (view.e_lo, view.e_hi, n_e), (view.u_lo, view.u_hi, n_u)


def view_border_points(view: View, side: int = BORDER_SIDE) -> xr.Dataset:
    """:func:`stairbounce.border_points` of :func:`border_grid` (the view's max_iter)."""
    from ..structure.borders import border_points

    e, u = border_grid(view, side)
    return border_points(e=e, u=u, max_iter=view.max_iter)


def border_point_slices(view: View, side: int = BORDER_SIDE, slice_work: int | None = None):
    """border_point_slices(view, side=BORDER_SIDE, slice_work=SLICE_WORK) -> generator, returning xarray.Dataset

    :func:`view_border_points` in slices of at most ``slice_work`` map steps
    (the explorer's scheduler; issue 38, R1): the grid's scan
    (:func:`grid_scan_slices`, ``max_iter`` per pixel), then the pairs
    (:func:`stairbounce.structure.borders.border_point_slices`, a bound of
    :func:`stairbounce.structure.borders.pair_work` each).  Yields ``("scan", done,
    total)`` and ``("pairs", done, total)``; returns the same Dataset as
    :func:`view_border_points`.
    """
    from ..structure.borders import _grid_input, staged
    from ..structure.borders import border_point_slices as pair_slices

    slice_work = SLICE_WORK if slice_work is None else slice_work
    e, u = border_grid(view, side)
    ds = yield from staged("scan", grid_scan_slices(e, u, view.max_iter, slice_work))
    es, us, period, max_iter = _grid_input(ds)
    attrs = {k: ds.attrs[k] for k in ("e_min", "e_max", "n_e", "u_min", "u_max", "n_u")}
    return (yield from staged("pairs", pair_slices(es, us, period, max_iter, attrs, slice_work)))


def border_overlay(view: View, side: int = BORDER_SIDE, points: xr.Dataset | None = None) -> dict:
    """border_overlay(view, side=BORDER_SIDE, points=None) -> dict

    The exact borders of the view (:func:`stairbounce.border_points` on a grid
    of at most ``side`` x ``side`` pixels of its window, the view's
    max_iter; ``points`` when already computed: :func:`view_border_points`),
    as columns for a scatter: ``e``, ``u``, ``kind``, ``step``, ``word_low``,
    ``word_high``.
    """
    pts = view_border_points(view, side) if points is None else points
    return {k: pts[k].values.tolist() for k in ("e", "u", "kind", "step", "word_low", "word_high")}


def trace_window(view: View) -> tuple:
    """trace_window(view) -> ((e_lo, e_hi), (u_lo, u_hi))

    The window whose regions :func:`trace_slices` traces: the view's, with e
    below 1 and u above 0 (the margins of :mod:`stairbounce.structure.itinerary` need
    both; as :func:`stairbounce.word_table` with ``regions=True``).
    """
    return (view.e_lo, min(view.e_hi, 1.0 - 1e-12)), (max(view.u_lo, 1e-9), view.u_hi)


def trace_slices(view: View, side: int = TRACE_SIDE, slice_work: int | None = None):
    """trace_slices(view, side=TRACE_SIDE, slice_work=SLICE_WORK) -> generator of (done, total), returning list[Region]

    The regions of every word of the view (:func:`stairbounce.window_regions`'
    method, the words seen by ``side`` x ``side`` seed pixel centres of
    :func:`trace_window`, the view's max_iter), one word per ``next()``: the
    scheduler's slices, so a trace of many words stays cancellable and shares
    the worker.  The seed scan comes first, in slices of at most
    ``slice_work`` map steps, each yielding ``(0, None)``; then ``(0,
    total)`` once the words are known and ``(done, total)`` after each word;
    returns the regions, largest first.
    """
    from ..structure.regions import iter_window_regions

    e, u = trace_window(view)
    return (yield from iter_window_regions(e, u, resolution=side, max_iter=view.max_iter,
                                           slice_work=SLICE_WORK if slice_work is None else slice_work))


def _word_at(e, u, window, max_iter, buf, texts):
    """The word text of the orbit of (1, 0) at (e, u) as the border points write
    it, or "outside the view" outside ``window`` (``texts``: the texts found
    so far, by the itinerary's hashes)."""
    from ..structure.itinerary import _hash_itinerary, _itinerary_of
    from ..structure.words import NONE_WORD, _word_text

    (e0, e1), (u0, u1) = window
    if not (e0 <= e <= e1 and u0 <= u <= u1):
        return OUTSIDE_WORD
    n = _itinerary_of(e, u, 1.0, 0.0, max_iter, buf)
    if n <= 0:
        return NONE_WORD
    key = (n, *(int(h) for h in _hash_itinerary(buf, n)))
    if key not in texts:
        texts[key] = _word_text(buf[:n])
    return texts[key]


OUTSIDE_WORD = "outside the view"
"""The word of the outer side of a traced arc on the window's edge."""


def _arc_sides(arc, window, max_iter, buf, texts):
    """``(word_low, word_high)``: the map's words just off the middle of ``arc``
    on its two sides, the low side being the one of smaller u (smaller e where
    the arc is nearer vertical than horizontal, in the window's scaled units,
    as a border point's bisection axis would be)."""
    (e0, e1), (u0, u1) = window
    x = (np.asarray(arc.e) - e0) / (e1 - e0)
    y = (np.asarray(arc.u) - u0) / (u1 - u0)
    n = x.size
    if n >= 3:  # a traced point: on the curve to rounding
        m = n // 2
        px, py, tx, ty = x[m], y[m], x[m + 1] - x[m - 1], y[m + 1] - y[m - 1]
    else:  # two corners: the chord's middle, off the curve by its sagitta at most
        px, py, tx, ty = 0.5 * (x[0] + x[-1]), 0.5 * (y[0] + y[-1]), x[-1] - x[0], y[-1] - y[0]
    norm = math.hypot(tx, ty) or 1.0
    nx, ny = -ty / norm, tx / norm  # the left normal
    if abs(ny) >= abs(nx):
        low = -1.0 if ny > 0 else 1.0  # the side of smaller u
    else:
        low = -1.0 if nx > 0 else 1.0  # the side of smaller e
    words = None
    for d in (1e-9, 1e-7, 1e-5, 1e-3):  # the nearest offset that sees two words
        words = [_word_at(e0 + (px + s * d * nx) * (e1 - e0), u0 + (py + s * d * ny) * (u1 - u0), window,
                          max_iter, buf, texts)
                 for s in (low, -low)]
        if words[0] != words[1]:
            break
    return words[0], words[1]


def _on_arcs(points, arcs, window):
    """Which border points lie on a traced arc of their own kind and step: in
    the window's scaled units (its sides 1), within 1e-9 of one of the arc's
    points or beside one of its chords within 1.5 % of the chord's length
    (the arcs turn by at most 0.08 rad per chord, so a chord leaves its curve
    by at most 1 % of its length)."""
    (e0, e1), (u0, u1) = window
    pe = (np.asarray(points["e"]) - e0) / (e1 - e0)
    pu = (np.asarray(points["u"]) - u0) / (u1 - u0)
    kinds, steps = np.asarray(points["kind"]).astype(str), np.asarray(points["step"])
    hit = np.zeros(pe.size, dtype=bool)
    groups: dict = {}
    for arc in arcs:
        if arc.kind != "window":
            P = np.stack([(arc.e - e0) / (e1 - e0), (arc.u - u0) / (u1 - u0)], 1)
            groups.setdefault((arc.kind, arc.step), []).append(P)
    tol = 1e-9
    for (kind, step), polys in groups.items():
        A = np.concatenate([P[:-1] for P in polys])
        B = np.concatenate([P[1:] for P in polys])
        AB = B - A
        L2 = (AB**2).sum(1)
        near = np.maximum(tol, 0.015 * np.sqrt(L2))
        idx = np.flatnonzero((kinds == kind) & (steps == step))
        chunk = max(1, 2_000_000 // A.shape[0])
        for lo in range(0, idx.size, chunk):  # points x chords at a time, in bounded blocks
            i = idx[lo:lo + chunk]
            dx, dy = pe[i, None] - A[None, :, 0], pu[i, None] - A[None, :, 1]
            raw = (dx * AB[:, 0] + dy * AB[:, 1]) / np.where(L2 > 0, L2, 1.0)
            tau = np.clip(raw, 0.0, 1.0)
            d = np.hypot(dx - tau * AB[:, 0], dy - tau * AB[:, 1])
            hit[i] = np.any(d <= np.where((raw > 0) & (raw < 1), near, tol), axis=1)
    return hit


ARC_SIDE_WORK = 8
"""Most orbits of ``max_iter`` steps :func:`_arc_sides` follows per arc (two
sides at four offsets at most)."""


def traced_overlay(view: View, regions, points=None) -> dict:
    """traced_overlay(view, regions, points=None) -> dict

    :func:`traced_overlay_slices` run to its end in one call.
    """
    gen = traced_overlay_slices(view, regions, points, slice_work=_UNBOUNDED)
    while True:
        try:
            next(gen)
        except StopIteration as stop:
            return stop.value


def traced_overlay_slices(view: View, regions, points=None, slice_work=None):
    """traced_overlay_slices(view, regions, points=None, slice_work=SLICE_WORK) -> generator, returning dict

    The traced borders of the view as the overlay draws them: the edges of
    :func:`stairbounce.border_graph` of ``regions`` (from :func:`trace_slices`)
    as ``"arcs"``, columns ``xs``, ``ys`` (one polyline per arc), ``kind``
    (graze, edge, chatter, or window for the window's sides), ``step``,
    ``word_low``, ``word_high`` (the map's words just off the arc's middle,
    :func:`_arc_sides`); ``"covered"``, per border point of ``points`` (a
    :func:`view_border_points` Dataset or its :func:`border_overlay`
    columns), whether a traced arc of its kind and step passes through it
    and neither of its words is incomplete (those points are replaced by the
    arcs; the others stay); ``"words"`` (words traced), ``"incomplete"``
    (their texts: a walk gave up, their points are kept) and ``"counts"``
    (arcs by kind).  The words beside the arcs cost up to
    ``ARC_SIDE_WORK * max_iter`` map steps per arc: they are found for as
    many arcs per ``next()`` as ``slice_work`` map steps allow (one at
    least), yielding ``(arcs done, arcs)``.
    """
    from ..structure.graph import border_graph

    slice_work = SLICE_WORK if slice_work is None else slice_work
    per_slice = max(1, slice_work // (ARC_SIDE_WORK * view.max_iter))
    window = trace_window(view)
    graph = border_graph(regions)
    buf, texts = np.empty(view.max_iter, dtype=np.int64), dict[tuple, str]()
    cols: dict = {k: [] for k in ("xs", "ys", "kind", "step", "word_low", "word_high")}
    counts: dict = {}
    edges = list(graph.edges)
    for i, (_, _, arc) in enumerate(edges):
        if i and i % per_slice == 0:
            yield i, len(edges)
        low, high = _arc_sides(arc, window, view.max_iter, buf, texts)
        for k, v in (("xs", arc.e.tolist()), ("ys", arc.u.tolist()), ("kind", arc.kind), ("step", int(arc.step)),
                     ("word_low", low), ("word_high", high)):
            cols[k].append(v)
        counts[arc.kind] = counts.get(arc.kind, 0) + 1
    incomplete = sorted(r.word.format(ascii=True) for r in regions if not r.complete)
    covered = []
    if points is not None and len(points["e"]):
        covered = _on_arcs(points, [a for _, _, a in graph.edges], window)
        bad = set(incomplete)
        covered &= ~np.array([lo in bad or hi in bad for lo, hi in
                              zip(np.asarray(points["word_low"], dtype=object).tolist(),
                                  np.asarray(points["word_high"], dtype=object).tolist())], dtype=bool)
        covered = covered.tolist()
    return {"arcs": cols, "covered": covered, "words": len(regions), "incomplete": incomplete, "counts": counts}


WORD_ROW_FIELDS = ("text", "letters", "period", "impacts", "pixels", "area_fraction", "e_rep", "u_rep",
                   "e_min", "e_max", "u_min", "u_max", "graze", "edge", "chatter")
"""The columns of :func:`stairbounce.word_table` a tap reports (:func:`word_row`)."""


def word_row(view: View, text: str, side: int = BORDER_SIDE, points: xr.Dataset | None = None,
             table: xr.Dataset | None = None, scan: xr.Dataset | None = None) -> dict:
    """word_row(view, text, side=BORDER_SIDE, points=None, table=None, scan=None) -> dict

    :func:`word_row_slices` run to its end in one call.
    """
    gen = word_row_slices(view, text, side, points, table, scan, slice_work=_UNBOUNDED)
    while True:
        try:
            next(gen)
        except StopIteration as stop:
            return stop.value


def word_row_slices(view: View, text: str, side: int = BORDER_SIDE, points: xr.Dataset | None = None,
                    table: xr.Dataset | None = None, scan: xr.Dataset | None = None,
                    slice_work: int | None = None):
    """word_row_slices(view, text, side=BORDER_SIDE, points=None, table=None, scan=None, slice_work=SLICE_WORK) -> generator, returning dict

    The row of the word ``text`` (ASCII, as ``Word.format(ascii=True)``) in
    :func:`stairbounce.word_table` of the view: the grid :func:`border_grid`
    (at most ``side`` x ``side`` pixels of the window, the view's max_iter);
    ``points``: that grid's :func:`view_border_points` when already computed
    (the "exact borders" overlay); ``table``: that grid's word table when
    already computed (a previous tap in the same view); ``scan``: the view's
    own scan when its pixels are that grid (no scan is computed then).  Returns ``{"grid":
    (n_e, n_u), "words": number of distinct words there, "row": {column:
    value} or None, "table": the word table}`` (row None: the word has no
    pixel centre on that grid, e.g. a region smaller than its pixels).
    Computed in slices of at most ``slice_work`` map steps (the scan of
    the grid, its border points unless given, the words of its pixels:
    :func:`stairbounce.structure.borders.word_table_slices`), yielding ``(stage,
    done, total)``.
    """
    from ..structure.borders import staged, word_table_slices

    slice_work = SLICE_WORK if slice_work is None else slice_work
    e, u = border_grid(view, side)
    if table is not None:
        tab = table
    else:
        if scan is None:
            scan = yield from staged("scan", grid_scan_slices(e, u, view.max_iter, slice_work))
        tab = yield from word_table_slices(scan, points, slice_work)
    hit = np.flatnonzero(tab["text"].values == text)
    row = None
    if hit.size:
        r = tab.isel(word=int(hit[0]))
        row = {k: r[k].item() for k in WORD_ROW_FIELDS}
    return {"grid": (e[2], u[2]), "words": int(tab.sizes["word"]), "row": row, "table": tab}
