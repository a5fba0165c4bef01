"""The explorer's "proven" overlay: the certified atlas of the view (issue 36, item 8).

Pure Python like :mod:`.view` (no Panel, no Bokeh):

- :func:`proven_depth`: the atlas's depth for a view, its smallest boxes no
  smaller than :data:`MIN_BOX_PX` pixels a side;
- :func:`proven_slices`: :func:`stairbounce.certify` of the view's window
  (corners form, the view's max_iter) as scheduler slices of bounded work,
  returning the same :class:`~stairbounce.CertifiedAtlas` box for box;
- :func:`proven_overlay`: the atlas's boxes with their marks (proven words in
  the scan's colours, the other statuses and the undecided reasons marked, see
  :data:`STYLES`), :func:`proven_image`: the same drawn as one RGBA picture
  with its hatching (what the page shows: one image, not a glyph per box,
  issue 46 item 2), and :func:`proven_summary` (area shares);
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
           "proven_summary", "proven_at", "proven_image", "HATCH_PERIOD", "CERTIFICATE_STEP_WORK",
           "TAP_CERTIFICATE_STEPS", "certificate_steps"]

MIN_BOX_PX = 2
"""The atlas's smallest boxes are at least this many pixels a side: its depth
is ``floor(log2(min(width, height) / MIN_BOX_PX))`` (8 for a 600 x 600 view:
boxes of window/256, 2.3 pixels)."""

BOX_WORK = 7
"""Potential map steps per box of a level, in units of ``max_iter``: the box's
two corners walked (the corners form) and up to five points of the float map
(the "nonsliding" test of the deepest levels)."""

CERTIFICATE_STEP_WORK = 20_000
"""What one step of a box's certificate is charged, in potential map steps (the
unit of :data:`~stairbounce.explorer.view.SLICE_WORK`).  Set when
:func:`stairbounce.certify_box` and :func:`stairbounce.verify` walked the steps
in Python (85 us a step at load 3.5); both are compiled now (a 100,000-step
``no_slide_within`` certificate: certify_box 0.037 s, verify 0.011 s, about
0.5 us a step, at load 0.7 on 2026-11-28), so the charge is about 100 times
what a step costs and the bound below defers taps that would now fit in a
slice: conservative, kept until the explorer's tests are sized for a larger
bound."""

TAP_CERTIFICATE_STEPS = V.SLICE_WORK // CERTIFICATE_STEP_WORK
"""The most steps a tap's certificate may walk on the explorer's shared worker
(5,000; a few milliseconds of work today, see above); a longer one (a box proven
not to slide within a max_iter of up to 1e6) is deferred: the tap says so and
how to compute it (issue 43 item 3)."""

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
    "range": ("#ffffff", 0.45, "|", "#6b6b6b", "undecided, range: the box touches e = 1 or u = 0"),
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

    The boxes of a :class:`~stairbounce.CertifiedAtlas` and their marks, one
    entry per box (what :func:`proven_image` paints): ``left``,
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


HATCH_PERIOD = 7
"""The hatching's period in pixels of :func:`proven_image` (as Bokeh's
``hatch_scale`` 7 the quads had)."""


def _hatch_masks(height: int, width: int) -> dict:
    """{hatch character: boolean (height, width) mask of its marks}, in the
    picture's pixels (row 0 at the bottom, as ``image_rgba`` draws it), so the
    hatching runs on across neighbouring boxes as Bokeh's did."""
    y, x = np.ogrid[:height, :width]
    p = HATCH_PERIOD
    xm, ym = x % p, y % p
    up, down = (x - y) % p == 0, (x + y) % p == 0  # "/" rises to the right (rows go up)
    horizontal, vertical = np.broadcast_to(ym == 0, (height, width)), np.broadcast_to(xm == 0, (height, width))
    r2 = (xm - p // 2) ** 2 + (ym - p // 2) ** 2
    return {" ": np.zeros((height, width), bool), ".": (xm < 2) & (ym < 2), "o": (r2 >= 2) & (r2 <= 5),
            "/": up, "\\": down, "x": up | down, "-": horizontal, "|": vertical, "+": horizontal | vertical}


def _edges(lo, hi, v, n):
    """Pixel indices of the box edges ``v`` on an axis from ``lo`` to ``hi`` of
    ``n`` pixels: a shared edge gives one index, so neighbouring boxes meet
    without a gap or an overlap."""
    return np.clip(np.rint((np.asarray(v) - lo) / (hi - lo) * n), 0, n).astype(np.int64)


def proven_image(atlas, width: int, height: int, var: str = "word_length") -> dict:
    """proven_image(atlas, width, height, var="word_length") -> dict

    The atlas drawn as one RGBA picture of ``width`` x ``height`` pixels over
    its window: each box filled as :func:`proven_overlay` says (its fill at its
    alpha) with its hatch over it in the hatch colour (opaque), transparent
    where no box is.  Keys: ``image`` (uint32 (height, width), Bokeh's
    ``image_rgba`` byte order, row 0 at the bottom), ``code`` (int16 or int32 (height,
    width): the index into ``names`` of the pixel's box label, -1 none, for the
    hover), ``names`` (the distinct labels, :func:`proven_overlay`'s ``what``),
    ``x``, ``y``, ``dw``, ``dh`` (the window).  Raises :class:`ValueError` for
    a side below 1."""
    width, height = int(width), int(height)
    if width < 1 or height < 1:
        raise ValueError(f"width and height must be at least 1 pixel, got {width} x {height}")
    quads = proven_overlay(atlas, var)
    (e_lo, e_hi), (u_lo, u_hi) = atlas.window
    c0, c1 = _edges(e_lo, e_hi, quads["left"], width), _edges(e_lo, e_hi, quads["right"], width)
    r0, r1 = _edges(u_lo, u_hi, quads["bottom"], height), _edges(u_lo, u_hi, quads["top"], height)
    # each pixel's box (the atlas's boxes do not overlap; finer boxes painted last)
    owner = np.full((height, width), -1, np.int64)
    for b in np.argsort(atlas.boxes["level"].values, kind="stable").tolist():
        owner[r0[b]:r1[b], c0[b]:c1[b]] = b
    names, code_of_box = np.unique(np.asarray(quads["what"], dtype=object).astype(str), return_inverse=True)
    fill = V._rgba32(quads["fill"]) if quads["fill"] else np.zeros(0, np.uint32)
    alpha = np.rint(255 * np.asarray(quads["alpha"], float)).astype(np.uint32)
    fill = (fill & np.uint32(0x00FFFFFF)) | (alpha << np.uint32(24)) if fill.size else fill
    hatch_rgba = V._rgba32(quads["hatch_color"]) if quads["hatch_color"] else np.zeros(0, np.uint32)
    inside = owner >= 0
    image = np.zeros((height, width), np.uint32)
    image[inside] = fill[owner[inside]]
    hatches = np.asarray(quads["hatch"], dtype=object)
    for ch, mask in _hatch_masks(height, width).items():
        boxes = np.flatnonzero(hatches == ch)
        if ch == " " or not boxes.size:
            continue
        mine = np.zeros(len(hatches) + 1, bool)
        mine[boxes] = True
        on = mask & mine[owner]  # owner -1 reads the extra False
        image[on] = hatch_rgba[owner[on]]
    code = np.where(inside, code_of_box[np.maximum(owner, 0)], -1)
    code = code.astype(np.int16 if names.size < 2**15 else np.int32)  # half the bytes on the websocket
    return {"image": image, "code": code, "names": names.tolist(), "x": e_lo, "y": u_lo,
            "dw": e_hi - e_lo, "dh": u_hi - u_lo}


def proven_summary(atlas) -> dict:
    """proven_summary(atlas) -> {style key: share of the window's area}, the
    keys of :data:`STYLES` present, largest first."""
    ds = atlas.boxes
    area = (ds["e1"].values - ds["e0"].values) * (ds["u1"].values - ds["u0"].values)
    labels = _labels(ds)
    total = float(area.sum()) or 1.0
    shares = {k: float(area[labels == k].sum()) / total for k in STYLES if (labels == k).any()}
    return dict(sorted(shares.items(), key=lambda kv: -kv[1]))


def certificate_steps(atlas, b: int) -> int:
    """certificate_steps(atlas, b) -> int: the steps that the certificate of the
    atlas's box ``b`` walks: ``max_iter`` for a box proven not to slide within
    them, the length of its itinerary for a proven word, 0 for an undecided box
    or one Corollary 2.1 settles (no walk)."""
    from ..structure.certificate import STATUSES

    ds = atlas.boxes
    status = STATUSES[int(ds["status"].values[b])]
    if status == "no_slide_within":
        return int(atlas.max_iter)
    if status == "word":
        off = ds["offsets"].values
        return int(off[b + 1] - off[b])
    return 0


def proven_at(atlas, e: float, u: float, verify: bool = True, max_steps: int | None = None) -> dict | None:
    """proven_at(atlas, e, u, verify=True, max_steps=None) -> dict or None

    What the atlas says at ``(e, u)``: its box containing the point (the
    smallest certified box there: the atlas's boxes do not overlap; on a
    shared edge the first in the table), ``None`` outside the window.  Keys:
    ``box`` ((e0, e1), (u0, u1)), ``level``, ``status``, ``word``,
    ``reason``, ``step``, ``max_iter``, and for a proven box its
    :class:`~stairbounce.Certificate` (``certificate``, computed again by
    :func:`stairbounce.certify_box` on the box's edges, the computation the
    atlas made) and, with ``verify``, the verdict of the independent checker
    :func:`stairbounce.verify` on it (``verdict``).  With ``max_steps``, a
    certificate that walks more steps (:func:`certificate_steps`) is not
    computed: ``deferred`` holds its steps instead (``None`` otherwise), and
    ``certificate`` and ``verdict`` are ``None``.  Raises :class:`ValueError`
    for a ``max_steps`` below 0.
    """
    if max_steps is not None and max_steps < 0:
        raise ValueError(f"max_steps must be at least 0, got {max_steps}")
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
           "max_iter": atlas.max_iter, "certificate": None, "verdict": None, "deferred": None}
    steps = certificate_steps(atlas, b)
    if max_steps is not None and steps > max_steps:
        out["deferred"] = steps
        return out
    if status != "undecided":
        from ..structure.certify import certify_box
        from ..structure.verdict import verify as check

        cert = certify_box(e=out["box"][0], u=out["box"][1], max_iter=atlas.max_iter, form=str(ds.attrs["form"]))
        out["certificate"] = cert
        if verify:
            out["verdict"] = check(cert)
    return out
