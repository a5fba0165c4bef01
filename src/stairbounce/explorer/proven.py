"""The explorer's "proven" overlay: the certified atlas of the view (issue 36, item 8).

Pure Python like :mod:`.view` (no Panel, no Bokeh):

- :func:`proven_depth`: the atlas's depth for a view, its smallest boxes no
  smaller than :data:`MIN_BOX_PX` pixels a side;
- :func:`proven_slices`: :func:`stairbounce.certify` of the view's window
  (corners form, the view's max_iter) as scheduler slices of bounded work,
  returning the same :class:`~stairbounce.CertifiedAtlas` box for box;
- :func:`proven_overlay`: the atlas as quads to draw (proven words in the
  scan's colours, the other statuses and the undecided reasons marked, see
  :data:`STYLES`), and :func:`proven_summary` (area shares);
- :func:`proven_at`: what a tap shows: the certificate of the atlas's box
  containing the point, re-verified by :func:`stairbounce.verify`, or why the
  box is undecided.
"""

from __future__ import annotations

import importlib
import math

import numpy as np
import xarray as xr

from . import view as V

__all__ = ["MIN_BOX_PX", "BOX_WORK", "STYLES", "proven_depth", "proven_slices", "proven_overlay",
           "proven_summary", "proven_at"]

MIN_BOX_PX = 2
"""The atlas's smallest boxes are at least this many pixels a side: its depth
is ``floor(log2(min(width, height) / MIN_BOX_PX))`` (8 for a 600 x 600 view:
boxes of window/256, 2.3 pixels)."""

BOX_WORK = 7
"""Potential map steps per box of a level, in units of ``max_iter``: the box's
two corners walked (the corners form) and up to five points of the float map
(the "nonsliding" test of the deepest levels)."""

STYLES = {
    # status or reason: (fill colour or None for the word's own, fill alpha, hatch, hatch colour, legend)
    "word": (None, 1.0, " ", "#000000", "proven: every point of the box has the periodic sliding solution "
                                         "of one word (interval arithmetic); the scan's colour of that word"),
    "no_sliding": ("#ffffff", 1.0, ".", "#1f5fbf", "proven: no periodic sliding solution (Corollary 2.1 "
                                                   "over the whole box)"),
    "no_slide_within": ("#ffffff", 1.0, "o", "#1f5fbf", "proven: no slide within max_iter steps (a finite "
                                                        "claim)"),
    "graze": ("#ffffff", 0.45, "/", "#8000ff", "undecided, graze: a first impact's sign not decided"),
    "edge": ("#ffffff", 0.45, "\\", "#ff1493", "undecided, edge: a later impact's sign not decided"),
    "chatter": ("#ffffff", 0.45, "x", "#0f5a00", "undecided, chatter: the slide test (2.4) not decided"),
    "nonsliding": ("#ffffff", 0.45, "-", "#6b6b6b", "undecided, nonsliding: the float map slides at none of "
                                                    "the box's corners and centre (numerical)"),
    "range": ("#ffffff", 0.45, "|", "#6b6b6b", "undecided, range: the box touches e = 0, e = 1 or u = 0"),
    "impacts": ("#ffffff", 0.45, "+", "#6b6b6b", "undecided, impacts: a step with more bounces than the "
                                                 "enclosures resolve"),
}
"""How the overlay draws each status of a box (and each reason of an undecided
one): the border events' reasons in the border kinds' colours (``_colours.py``),
the proven non-sliding statuses in blue over white."""


def proven_depth(view: V.View) -> int:
    """proven_depth(view) -> int: the atlas's depth, its boxes at least
    :data:`MIN_BOX_PX` pixels a side along both axes."""
    return max(0, int(math.floor(math.log2(min(view.width, view.height) / MIN_BOX_PX))))


def proven_slices(view: V.View, slice_work: int | None = None):
    """proven_slices(view, slice_work=SLICE_WORK) -> generator, returning CertifiedAtlas

    :func:`stairbounce.certify` of the view's window at :func:`proven_depth`
    and the view's max_iter (corners form, one tile), cut into slices of at
    most ``slice_work`` potential map steps for the explorer's scheduler: each
    level of the quadtree in batches of ``slice_work // (BOX_WORK * max_iter)``
    boxes (one at least), then the itineraries longer than the level kernel
    keeps, in batches of at most ``slice_work`` corner steps.  Boxes are
    independent (each computed from its place in the quadtree), so the atlas
    is :func:`stairbounce.certify`'s box for box.  Yields ``(stage, done,
    total)``: ``("level", level, depth)`` or ``("itineraries", done, total)``.
    Raises :class:`ValueError` for a window :func:`stairbounce.certify` refuses.
    """
    from ..structure import _kernel as K

    C = importlib.import_module("..structure.certify", __package__)  # the module (the package exports the function)

    slice_work = V.SLICE_WORK if slice_work is None else slice_work
    depth = proven_depth(view)
    max_iter = view.max_iter
    e_lo, e_hi = C._check_e((view.e_lo, view.e_hi), window=True)
    u_lo, u_hi = C._check_u((view.u_lo, view.u_hi), window=True)
    win = np.array([e_lo, e_hi, u_lo, u_hi])
    form = C._FORM_CODES["corners"]
    # certify()'s quadtree (one tile, the check box by box in the level kernel: the same
    # boxes), each level's kernel calls in batches of bounded work
    start = min(C._START_LEVEL, depth)
    gi, gj = np.meshgrid(np.arange(1 << start), np.arange(1 << start))
    out: list[tuple] = []
    for level, _ in C._run_tile(win, depth, start, gi.ravel(), gj.ravel(), max_iter, form, out,
                                batch=max(1, slice_work // (BOX_WORK * max_iter))):
        yield "level", level, depth
    cols, kept, row = C._box_table(out)
    # the table, in batches whose itineraries computed again (longer than the
    # level kernel keeps: two corners walked per step) stay within the bound
    status, nsteps = cols[3], cols[6]
    again = np.where(((status == K.WORD) | (status == K.NO_SLIDE_WITHIN)) & (nsteps > C._KEPT), 2 * nsteps, 0)
    bounds, acc, lo = [], 0, 0
    for b, w in enumerate(again.tolist()):
        if acc and acc + w > slice_work:
            bounds.append((lo, b))
            lo, acc = b, 0
        acc += w
    bounds.append((lo, status.size))
    parts = []
    for k, (a, b) in enumerate(bounds):
        parts.append(C._atlas_dataset(win, depth, max_iter, form, *(c[a:b] for c in cols), kept, row[a:b]))
        if k + 1 < len(bounds):
            yield "itineraries", b, status.size
    return C.CertifiedAtlas(_join(parts))


def _join(parts):
    """Tables of consecutive batches of boxes as one (offsets shifted by the
    itineraries before them)."""
    if len(parts) == 1:
        return parts[0]
    shift = np.cumsum([0] + [int(p["offsets"].values[-1]) for p in parts[:-1]])
    offsets = np.concatenate([parts[0]["offsets"].values[:1]]
                             + [p["offsets"].values[1:] + s for p, s in zip(parts, shift)])
    boxes = xr.concat([p.drop_vars(["offsets", "itinerary"]) for p in parts], dim="box")
    itinerary = np.concatenate([p["itinerary"].values for p in parts])
    return boxes.assign(offsets=("offset", offsets), itinerary=("itinerary_step", itinerary)).assign_attrs(
        parts[0].attrs)


def _labels(ds):
    """Each box's style key: ``word``, ``no_sliding``, ``no_slide_within`` or
    the undecided box's reason."""
    from ..structure.certificate import STATUSES

    names = np.array(STATUSES, dtype=object)[ds["status"].values]
    return np.where(names == "undecided", ds["reason"].values.astype(object), names)


def _word_colours(words, var):
    """The scan's colour of each word (ASCII text) for the colouring variable
    ``var``: a count's class colour, the "found" colour for ``status``, the
    "slides" grey for a motion field."""
    from ..symbolic import parse_word

    if var in V.MOTION_COLOR_VARS:
        return [V.SLIDES_COLOR] * len(words)
    if var == "status":
        return [V.color_key("status").colors[0]] * len(words)
    distinct = sorted(set(words))
    parsed = [parse_word(w) for w in distinct]
    values = {"word_length": [len(w) for w in parsed], "period": [w.period for w in parsed],
              "impacts": [w.impacts for w in parsed], "jumps": [w.jumps for w in parsed]}[var]
    ds = xr.Dataset({"status": ("box", np.zeros(len(distinct), np.int8)), var: ("box", np.asarray(values))})
    colours = np.asarray(V.color_key(var).colors, dtype=object)[V.classes(ds, var)] if distinct else []
    lookup = dict(zip(distinct, colours))
    return [lookup[w] for w in words]


def proven_overlay(atlas, var: str = "word_length") -> dict:
    """proven_overlay(atlas, var="word_length") -> dict of columns

    The boxes of a :class:`~stairbounce.CertifiedAtlas` as quads: ``left``,
    ``right``, ``bottom``, ``top``, ``fill``, ``alpha``, ``hatch``,
    ``hatch_color`` (:data:`STYLES`; a proven word in the scan's colour of
    that word for the colouring variable ``var``), ``what`` (the box's status,
    word or reason, for the hover)."""
    ds = atlas.boxes
    labels = _labels(ds)
    words = ds["word"].values.astype(str)
    is_word = labels == "word"
    fill = np.array([STYLES[k][0] for k in labels], dtype=object)
    if is_word.any():
        fill[is_word] = _word_colours(words[is_word].tolist(), var)
    what = np.where(is_word, np.char.add("proven word ", words), labels)
    what = np.where(np.isin(labels, ("no_sliding", "no_slide_within")), np.char.add("proven ", labels.astype(str)),
                    np.where(is_word, what, np.char.add("undecided (numerical): ", labels.astype(str))))
    return {
        "left": ds["e0"].values.tolist(), "right": ds["e1"].values.tolist(),
        "bottom": ds["u0"].values.tolist(), "top": ds["u1"].values.tolist(),
        "fill": fill.tolist(), "alpha": [STYLES[k][1] for k in labels],
        "hatch": [STYLES[k][2] for k in labels], "hatch_color": [STYLES[k][3] for k in labels],
        "what": what.astype(str).tolist(),
    }


def proven_summary(atlas) -> dict:
    """proven_summary(atlas) -> {style key: share of the window's area}, the
    keys of :data:`STYLES` present, largest first."""
    ds = atlas.boxes
    area = (ds["e1"].values - ds["e0"].values) * (ds["u1"].values - ds["u0"].values)
    labels = _labels(ds)
    total = float(area.sum()) or 1.0
    shares = {k: float(area[labels == k].sum()) / total for k in STYLES if (labels == k).any()}
    return dict(sorted(shares.items(), key=lambda kv: -kv[1]))


def proven_at(atlas, e: float, u: float, verify: bool = True) -> dict | None:
    """proven_at(atlas, e, u, verify=True) -> dict or None

    What the atlas says at ``(e, u)``: its box containing the point (the
    smallest certified box there: the atlas's boxes do not overlap; on a
    shared edge the first in the table), ``None`` outside the window.  Keys:
    ``box`` ((e0, e1), (u0, u1)), ``level``, ``status``, ``word``,
    ``reason``, ``step``, ``max_iter``, and for a proven box its
    :class:`~stairbounce.Certificate` (``certificate``, computed again by
    :func:`stairbounce.certify_box` on the box's edges, the computation the
    atlas made) and, with ``verify``, the verdict of the independent checker
    :func:`stairbounce.verify` on it (``verdict``).
    """
    from ..structure.certificate import STATUSES

    ds = atlas.boxes
    e0, e1, u0, u1 = (ds[k].values for k in ("e0", "e1", "u0", "u1"))
    hit = np.flatnonzero((e0 <= e) & (e <= e1) & (u0 <= u) & (u <= u1))
    if not hit.size:
        return None
    b = int(hit[np.argmax(ds["level"].values[hit])])
    status = STATUSES[int(ds["status"].values[b])]
    out = {"box": ((float(e0[b]), float(e1[b])), (float(u0[b]), float(u1[b]))),
           "level": int(ds["level"].values[b]), "status": status,
           "word": str(ds["word"].values[b]) or None, "reason": str(ds["reason"].values[b]) or None,
           "step": int(ds["step"].values[b]) if status == "undecided" else None,
           "max_iter": atlas.max_iter, "certificate": None, "verdict": None}
    if status != "undecided":
        from ..structure.certify import certify_box
        from ..structure.verdict import verify as check

        cert = certify_box(e=out["box"][0], u=out["box"][1], max_iter=atlas.max_iter, form=str(ds.attrs["form"]))
        out["certificate"] = cert
        if verify:
            out["verdict"] = check(cert)
    return out
