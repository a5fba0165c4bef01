"""The quadtree refined where the perimeter's box counts can still change (issue 44,
item 4): :func:`stairbounce.certify_to_zarr` with ``focus=K``.

The proven counts of the sliding region's border (:mod:`border_counts`) at a scale
``k``: ``lower`` the cells of side window/2^k holding a proven sliding and a proven
non-sliding point, ``upper`` those and the cells whose closure meets an undecided box.
A full quadtree splits every undecided box down to ``depth``.  Most of that work cannot
move the counts at the scales ``k <= K``:

    An undecided box ``b`` all of whose scale-K cells (the cells whose closure meets
    ``b``) are already in ``lower`` changes no count at any ``k <= K`` when it is split,
    whatever its children prove.  At ``K``: those cells stay in lower (proven points
    stay proven) and so in upper; the children touch no other cell.  At ``k < K``:
    every scale-k cell whose closure meets ``b`` holds one of those scale-K cells (a
    point of ``b`` on that closure lies on the closure of one of its scale-K cells),
    so it is in lower already; and every scale-k cell holding a point of ``b`` holds
    the scale-K cell of that point.

So a tile is certified in rounds.  Round 0 is the plain quadtree to depth ``K`` (the
tile of ``certify_to_zarr(depth=K)``, class-level proofs and trapping regions
included).  Each later round, ``D = K + 1, ..., depth``:

* **Lower cells.**  The tile's scale-K cells holding proven points of both classes:
  its proven boxes, and its witnesses (``witnesses.witness_rows`` with the counted
  depth K: points certified and re-verified by the independent checker).  A cell
  outside the tile counts as not in lower (its boxes are another tile's), so a box on
  the tile's edge is taken up: the choice is made from the tile alone, and the tiles
  stay independent (Dask, resuming).
* **The choice** (:func:`choose`).  Every undecided row with a scale-K cell outside
  them is taken up.  A cell can be in lower through a witness inside a row taken up,
  whose pieces have other candidate points; so the lower cells are found again
  without the witnesses of the rows taken up, and the choice grown, until it no longer
  changes.  Then every row left alone is next to lower cells only, and those stay
  lower whatever the round does: a cell holds a proven point of a class exactly when
  one of its candidates is provable (``witnesses.py``), and its candidates left alone
  are the same at the count.
* **Certified again.**  A row taken up is replaced with everything its quadtree box
  holds (the box the quadtree made: the row itself, or the box a trapping pass split
  into it and its pieces, proven or not; the column :data:`ROOT` carries it): that box
  is certified again as the quadtree to depth ``D`` below it (``certify._run_tile``,
  the class-level proofs and the trapping regions at depth ``D``), which is what the
  full quadtree to ``D`` holds below it (the box depends on its position alone, and a
  deeper quadtree splits at least every box a shallower one split).  A ``nonsliding``
  row whose box the quadtree to ``D`` stops again as it is (from level ``D - 4`` on,
  and not a box meeting the Corollary 2.1 curve above the last level with
  ``classes``, which is split on) keeps its row: only its trapping tries are carried
  one level further (``trapping.trap_atlas(tried=...)``: the tries made before are not
  made again; a test compares it with one pass to the deeper depth).

So at the scales ``k <= K`` the upper counts are at most the full quadtree's to
``depth``: the rows taken up are its rows; a row left alone is next to lower cells,
through which the border passes (every border point lies in an undecided box, so the
full quadtree counts them too); and a box proven in an earlier round that the full
quadtree splits further (a trapping region on a box of the Corollary 2.1 curve, split
on at a greater depth) only takes cells away.  The lower counts are not compared: the
full store's witnesses are sampled in its own, finer boxes.

What it proves, and what it does not: the store's boxes are certified boxes of the
window's quadtree that tile it, so its counts are proven bounds (``sb.verify`` checks
every box, whichever round made it).  The choice of boxes is not a proof and needs
none: a count bound holds for any tiling.  The counts at ``k > K`` are not kept
(coarse undecided boxes left in lower cells would make them meaningless), so the
store's counted depth is ``K`` (attribute ``focus``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from . import _kernel as K_
from .border_counts import closure_cells


@njit(cache=True, nogil=True)
def _cell_count(K, level):
    n = 0
    for b in range(level.size):
        L = np.int64(level[b])
        n += 1 if L >= K else np.int64(1) << (2 * (K - L))
    return n


@njit(cache=True, nogil=True)
def _fill_cells(K, level, ii, jj, out):
    """The scale-K cells (code ``ci * 2^K + cj``) holding the boxes' points."""
    n = np.int64(1) << K
    at = 0
    for b in range(level.size):
        L = np.int64(level[b])
        i, j = np.int64(ii[b]), np.int64(jj[b])
        if L >= K:
            sh = L - K
            out[at] = (i >> sh) * n + (j >> sh)
            at += 1
        else:
            f = np.int64(1) << (K - L)
            for a in range(i * f, (i + 1) * f):
                for c in range(j * f, (j + 1) * f):
                    out[at] = a * n + c
                    at += 1


def cells(K, level, ii, jj):
    """The distinct scale-K cells holding points of the boxes ``(level, i, j)``, sorted."""
    level = np.ascontiguousarray(level, np.int64)
    out = np.empty(_cell_count(K, level), np.int64)
    _fill_cells(K, level, np.ascontiguousarray(ii, np.int64), np.ascontiguousarray(jj, np.int64), out)
    return np.unique(out)


@njit(cache=True, nogil=True)
def _select(K, level, ii, jj, lower, out):
    """``out[b]``: whether a scale-K cell whose closure meets box ``b`` is not in the
    sorted ``lower`` (``border_counts.closure_cells``, as the upper counts take them)."""
    n = np.int64(1) << K
    for b in range(level.size):
        a0, a1, b0, b1 = closure_cells(np.int64(K), np.int64(level[b]), np.int64(ii[b]), np.int64(jj[b]))
        hit = False
        for a in range(max(a0, 0), min(a1, n - 1) + 1):
            for c in range(max(b0, 0), min(b1, n - 1) + 1):
                code = a * n + c
                k = np.searchsorted(lower, code)
                if k == lower.size or lower[k] != code:
                    hit = True
                    break
            if hit:
                break
        out[b] = hit


def lower_cells(ds, K, tile_level, moving=None):
    """The scale-K cells of the tile ``ds`` holding a proven sliding and a proven
    non-sliding point: of its proven boxes, and witnesses of its undecided boxes but
    those of ``moving`` (a mask: boxes about to be certified again, whose witnesses
    may not come back), sorted."""
    from .certify import _border_classes
    from .witnesses import witness_rows

    level = ds["level"].values.astype(np.int64)
    ii, jj = ds["i"].values.astype(np.int64), ds["j"].values.astype(np.int64)
    cls = _border_classes(ds["status"].values, None, "sliding") + 1  # -1 undecided, 0 not sliding, 1 sliding
    window = (tuple(ds.attrs["e_range"]), tuple(ds.attrs["u_range"]))
    given = np.ones(level.size, bool) if moving is None else ~moving
    wi, wj, wc, _, _, _ = witness_rows(window, K, int(ds.attrs["max_iter"]), level[given], ii[given], jj[given],
                                       cls[given], exact_from=tile_level)
    n = np.int64(1) << K
    held = []
    for c in (0, 1):
        s = cls == c
        held.append(np.union1d(cells(K, level[s], ii[s], jj[s]), wi[wc == c] * n + wj[wc == c]))
    return np.intersect1d(held[0], held[1], assume_unique=True)


def choose(ds, K, tile_level, depth, classes=False):
    """``(again, deeper)`` of :func:`selected` for the round to ``depth``, grown until
    the boxes left alone are next to cells whose proven points stay: the proven boxes'
    and the witnesses of the boxes left alone.  (A cell counted in lower through a
    witness inside a box that the round certifies again may lose it: the box's pieces
    have other candidate points.  At the fixed point every box left alone is next to
    lower cells only, and they stay lower whatever the round does, since a cell holds a
    proven point of a class exactly when one of its candidates is provable,
    ``witnesses.py``.)"""
    again = np.zeros(ds["status"].size, bool)  # nothing taken up yet: every witness counts
    deeper = again.copy()
    while True:
        a, d = selected(ds, K, lower_cells(ds, K, tile_level, again | deeper), depth, classes)
        a |= again
        d |= deeper
        if np.array_equal(a, again) and np.array_equal(d, deeper):
            return again, deeper
        again, deeper = a, d


# the column that carries each row's quadtree box: the level of the box the quadtree
# made (the row itself, or for a piece of a trapping pass's split the box split), which
# the trapping pass's pieces inherit as they inherit every column of the box split
ROOT = "focus_root_level"


def ancestors(ds):
    """``(level, i, j)`` of each row's quadtree box (the row itself, or the box a
    trapping pass split into it): from the column :data:`ROOT`, else the row's own."""
    lv = ds["level"].values.astype(np.int64)
    ii, jj = ds["i"].values.astype(np.int64), ds["j"].values.astype(np.int64)
    if ROOT not in ds.variables:
        return lv, ii, jj
    root = ds[ROOT].values.astype(np.int64)
    return root, ii >> (lv - root), jj >> (lv - root)


def selected(ds, K, lower, depth, classes=False):
    """``(again, deeper)``: what the round to ``depth`` takes up, the undecided rows
    with a scale-K cell (whose closure meets them) outside ``lower``.

    ``deeper``: the ``nonsliding`` rows whose quadtree box (:func:`ancestors`) the
    quadtree to ``depth`` would stop again as it is (from level ``depth -
    certify._NONSLIDING_LEVELS`` on, and with ``classes`` not a box meeting the
    Corollary 2.1 curve above the last level, which is split on: the same corners and
    centre, so the same box): their trapping tries are carried one level further.
    ``again``: every row of a quadtree box any other taken row lies in (the box's
    trapping pieces, proven or not, with it), whose quadtree boxes are certified again
    to ``depth``."""
    from .certify import _NONSLIDING_LEVELS, _meets_curve

    st = ds["status"].values
    und = np.flatnonzero(st == K_.UNDECIDED)
    hit = np.zeros(st.size, bool)
    if und.size:
        h = np.zeros(und.size, np.bool_)
        _select(K, ds["level"].values[und].astype(np.int64), ds["i"].values[und].astype(np.int64),
                ds["j"].values[und].astype(np.int64), np.ascontiguousarray(lower, np.int64), h)
        hit[und] = h
    al, ai, aj = ancestors(ds)
    stays = (ds["reason"].values == "nonsliding") & (al >= depth - _NONSLIDING_LEVELS)
    if classes:
        on = np.flatnonzero(stays & (al < depth))
        win = np.array([*ds.attrs["e_range"], *ds.attrs["u_range"]], np.float64)
        for L in np.unique(al[on]):
            s = on[al[on] == L]
            stays[s[_meets_curve(win, int(L), ai[s], aj[s])]] = False
    deeper = hit & stays
    from ._store_read import row_key

    key = row_key(al, ai, aj)
    again = np.isin(key, key[hit & ~stays])
    return again, deeper


def _tile_form(ds):
    """``ds`` as a store's tile reads back (``_store_read.read_tile``): ``(arrays, attrs)``."""
    from ._store_read import encode

    enc = encode(ds)
    return {k: np.asarray(v.values) for k, v in enc.variables.items()}, dict(enc.attrs)


# the variables that are not one value a box
_RAGGED = ("offsets", "itinerary", "trap_box", "trap_grid", "trap_cell_offsets", "trap_cells")


def without(ds, drop):
    """The table ``ds`` less the rows ``drop`` (a mask), as ``(arrays, attrs)``: the
    itineraries and trapping regions of the rows kept, renumbered."""
    from ._store_read import _take_rows

    arrays, attrs = _tile_form(ds)
    keep = np.flatnonzero(~drop)
    off = arrays.pop("offsets")
    lengths = np.diff(off)[keep]
    arrays["itinerary"] = _take_rows(arrays["itinerary"], off[:-1][keep], lengths)
    new_off = np.zeros(keep.size + 1, np.int64)
    np.cumsum(lengths, out=new_off[1:])
    arrays["offsets"] = new_off
    if "trap_box" in arrays:
        rank = np.full(drop.size, -1, np.int64)
        rank[keep] = np.arange(keep.size)
        box = arrays["trap_box"].astype(np.int64)
        t = np.flatnonzero(rank[box] >= 0)
        coff = arrays["trap_cell_offsets"]
        clen = np.diff(coff)[t]
        arrays["trap_cells"] = _take_rows(arrays["trap_cells"], coff[:-1][t], clen)
        arrays["trap_cell_offsets"] = np.concatenate([[0], np.cumsum(clen)]).astype(np.int64)
        arrays["trap_box"] = rank[box[t]]
        arrays["trap_grid"] = arrays["trap_grid"].reshape(-1, 6)[t]
    for name in list(arrays):
        if name not in _RAGGED:  # a column of the boxes
            arrays[name] = arrays[name][keep]
    return arrays, attrs


# the column that carries, through a round's merge, the level down to which each row's
# trapping tries were made (trapping.trap_atlas's ``tried``)
_TRIED = "focus_trap_level"


def refine(ds, depth, focus, tile_level, rerun, trap=None, classes=False, report=None):
    """The tile ``ds`` (certified to depth ``focus``) refined round by round to
    ``depth`` where its counts at the scales ``k <= focus`` can change (the module's
    docstring).  ``rerun(level, ii, jj, D)``: the table of the boxes ``(level, ii, jj)``
    (all of one level) certified again as the quadtree to depth ``D`` below them.
    ``trap(table, tried)``: the table's ``nonsliding`` rows tried for trapping regions
    (``trapping.trap_atlas`` with its ``tried``; None: no trapping pass).
    ``classes``: the tile's ``certify(classes=...)`` (boxes meeting the Corollary 2.1
    curve are split on).  ``report(D, again, deeper, boxes)`` after each round's
    choice.  The tables carry the column :data:`ROOT` (``rerun``'s too: set before
    their trapping pass); the result does not."""
    from ._store_read import merge_tiles
    from .trapping import SPLIT_LEVELS

    tried = np.full(ds["status"].size, focus + SPLIT_LEVELS, np.int64)
    for D in range(focus + 1, depth + 1):
        again, deeper = choose(ds, focus, tile_level, D, classes)
        if trap is None:
            deeper[:] = False
        if report is not None:
            report(D, int(again.sum()), int(deeper.sum()), int(again.size))
        if not (again.any() or deeper.any()):
            break
        al, ai, aj = ancestors(ds)
        kept = without(ds, again | deeper)
        kept[0][_TRIED] = tried[~(again | deeper)]
        parts = [kept]
        boxes = np.unique(np.stack([al[again], aj[again], ai[again]]), axis=1)  # by level, then j, then i
        for L in np.unique(boxes[0]):
            s = boxes[0] == L
            new = _tile_form(rerun(int(L), boxes[2][s], boxes[1][s], D))
            new[0][_TRIED] = np.full(new[0]["offsets"].size - 1, D + SPLIT_LEVELS, np.int64)
            parts.append(new)
        if deeper.any():
            rows = without(ds, ~deeper)
            sub = merge_tiles([rows], rows[0]["offsets"].size - 1, rows[0]["itinerary"].size)
            sub.attrs["depth"] = int(D)
            new = _tile_form(trap(sub, tried[deeper]))
            new[0][_TRIED] = np.full(new[0]["offsets"].size - 1, D + SPLIT_LEVELS, np.int64)
            parts.append(new)
        n_boxes = sum(a["offsets"].size - 1 for a, _ in parts)
        n_steps = sum(a["itinerary"].size for a, _ in parts)
        ds = merge_tiles(parts, n_boxes, n_steps)
        tried = ds[_TRIED].values.astype(np.int64)
        ds = ds.drop_vars(_TRIED)
    if ROOT in ds.variables:
        ds = ds.drop_vars(ROOT)
    ds.attrs["depth"] = int(depth)
    ds.attrs["focus"] = int(focus)
    return ds
