"""Proven, not only computed: certified boxes of the (e, u) plane (issue 36).

:func:`certify_box` states what is proven over one box of parameters,
:func:`certify` covers a window with an adaptive quadtree of such boxes and
returns a :class:`CertifiedAtlas`.  The decisions are taken with outward-rounded
float64 bounds along the itinerary of the edge state ``(1, 0)``, by default at the
box's two corners, where each margin takes its least and largest value
(:func:`certify_box`; :mod:`stairbounce.structure._kernel`; the argument for
rigour is in docs/design.md, "Certified boxes").
"""

from __future__ import annotations

import math
import time
import warnings

import numpy as np

from .. import _validate as _v
from ..model import check_count
from ..symbolic import Word, word_from_impacts
from . import _kernel as K
from .certificate import STATUSES, Certificate, Decisions, _check_e, _check_u

__all__ = ["certify_box", "certify", "CertifiedAtlas", "UNDECIDED_REASONS"]

UNDECIDED_REASONS = K.REASON_CODES
"""Why a box is undecided: the three border events (``graze``: the first
impact, ``edge``: a later impact, ``chatter``: the slide test (2.4)), then
``impacts`` (a step proven to have more than ``IMPACT_CAP`` impacts, whose
bounces are shorter than the enclosures), ``nonsliding`` (numerical, atlases
only: the float map does not slide within max_iter at the box's corners and
centre, so the box is taken for non-sliding motion and not split further) and
``range`` (atlases only: the box touches ``e = 0``, ``e = 1`` or ``u = 0``, outside
the open range 0 < e < 1, u > 0 of a certified box; it is split down to the last
level like a border)."""

def _check_atlas_variables(ds, path):
    """ValueError naming the variables and attributes a loaded atlas lacks (the text
    columns as ``word`` or ``word_code``, ``reason`` or ``reason_code``)."""
    need = ["e0", "e1", "u0", "u1", "status", "level", "i", "j", "offsets", "itinerary"]
    missing = [k for k in need if k not in ds.variables]
    missing += [k for k in ("word", "reason") if k not in ds.variables and f"{k}_code" not in ds.variables]
    missing += [k for k in ("e_range", "u_range", "depth", "max_iter", "form") if k not in ds.attrs]
    if missing:
        raise ValueError(f"{path} is not a whole certified atlas: it lacks {', '.join(missing)}")


# CF attributes of the saved atlas's variables (long_name, units; status as CF flags)
_CF = {
    "e0": ("restitution coefficient e at the box's lower edge (a binary float)", "1"),
    "e1": ("restitution coefficient e at the box's upper edge (a binary float)", "1"),
    "u0": ("normalised horizontal speed u at the box's lower edge (a binary float)", "1"),
    "u1": ("normalised horizontal speed u at the box's upper edge (a binary float)", "1"),
    "status": ("what is proven over the box", None),
    "word": ("the proven word of the periodic sliding solution through (1, 0) (status word)", None),
    "word_code": ("index into the attribute word_names of the proven word (status word)", None),
    "reason": ("why the box is undecided, or 'trapping' (no_sliding by a trapping region)", None),
    "reason_code": ("index into the attribute reason_names", None),
    "step": ("the step (1-based) of the undecided decision, 0 where decided", "1"),
    "level": ("quadtree level of the box (its side is the window's / 2^level)", "1"),
    "i": ("column of the box in its level's grid (along e)", "1"),
    "j": ("row of the box in its level's grid (along u)", "1"),
    "offsets": ("box b's itinerary is itinerary[offsets[b]:offsets[b + 1]]", "1"),
    "itinerary": ("impact numbers of the decided steps, every box's in turn (-1: the slide)", "1"),
}


def _with_cf_attributes(ds):
    """``ds`` with CF attributes on its variables (:data:`_CF`): ``long_name``,
    ``units`` ("1": dimensionless), and for ``status`` ``flag_values`` /
    ``flag_meanings`` (the codes of STATUSES)."""
    ds = ds.copy()
    for name, (long_name, units) in _CF.items():
        if name in ds.variables:
            ds[name].attrs["long_name"] = long_name
            if units is not None:
                ds[name].attrs["units"] = units
    if "status" in ds.variables and ds["status"].dtype.kind in "iu":
        ds["status"].attrs["flag_values"] = np.arange(len(STATUSES), dtype=np.int8)
        ds["status"].attrs["flag_meanings"] = " ".join(STATUSES)
    ds.attrs.setdefault("Conventions", "CF-1.10")
    return ds


# what CertifiedAtlas.save writes, picked by the path's suffix (case ignored: _io.suffix_of)
ATLAS_SUFFIXES = (".nc", ".zarr", ".geojson")
FORMS = ("corners", "mean-value", "naive")
"""The enclosures a box can be certified with (the first is the default;
:func:`certify_box`)."""
_FORM_CODES = {"corners": K.CORNERS, "mean-value": K.MEAN_VALUE, "naive": K.NAIVE}
_FORM_NAMES = {c: f for f, c in _FORM_CODES.items()}
# levels (counted up from the deepest) at which an undecided box may stop as
# "nonsliding" (benchmarks/certify.py measured the choice)
_NONSLIDING_LEVELS = 4
# the quadtree starts from 2^_START_LEVEL boxes a side (tiles up to that many)
_START_LEVEL = 3
_MAX_DEPTH = 26
# itinerary entries kept per box by the level kernel (int16: impact numbers <= IMPACT_CAP);
# longer itineraries are computed again at the end (64 bytes a box of a level, about
# twice what the rest of a level holds)
_KEPT = 32
# what one box of a level holds while the level is computed (its status, reason, step,
# length, kept itinerary, position and its children's positions), in bytes: the
# measured peak of certify over the boxes of its largest level (benchmarks/README.md,
# "certify's memory"); a run whose level would need more than _WARN_BYTES says so
_LEVEL_BYTES_PER_BOX = 250
_WARN_BYTES = 1 << 30
_SLIDING_STATUS = STATUSES.index("sliding")


def _available_memory():
    """Bytes of memory available now (``_validate.available_memory``), or None: a level
    whose estimate (its boxes x :data:`_LEVEL_BYTES_PER_BOX`) exceeds it is refused
    before its work (ValueError naming ``certify_to_zarr``)."""
    return _v.available_memory()


class CertifyMemoryWarning(UserWarning):
    """A certified atlas's level is about to hold more than a gigabyte
    (:data:`_WARN_BYTES`): the run goes on, and says so with its estimate."""


# --------------------------------------------------------------------------- #
# Validation                                                                  #
# --------------------------------------------------------------------------- #


def _check_form(form):
    if not isinstance(form, str) or form not in FORMS:
        raise ValueError(f"form must be one of {', '.join(FORMS)}, got {form!r}")
    return _FORM_CODES[form]


def _check_request(e, u, depth, max_iter, form):
    """The window, depth, max_iter and form of an atlas, checked (ValueError by
    name): ``(e_lo, e_hi, u_lo, u_hi, depth, max_iter, form code)``."""
    e_lo, e_hi = _check_e(e, window=True)
    u_lo, u_hi = _check_u(u, window=True)
    depth = check_count("depth", depth, 0, _MAX_DEPTH)
    max_iter = check_count("max_iter", max_iter, 1)
    _itinerary_buffer(max_iter)
    return e_lo, e_hi, u_lo, u_hi, depth, max_iter, _check_form(form)


def _itinerary_buffer(max_iter):
    _v.check_memory(f"max_iter = {max_iter}", 8 * max_iter)
    return np.empty(max_iter, np.int64)


# --------------------------------------------------------------------------- #
# One box                                                                     #
# --------------------------------------------------------------------------- #


def _run_box(e0, e1, u0, u1, max_iter, form, itin):
    """Certify one box twice: once to size the record, once recording it."""
    dummy_d = np.empty(0, np.int64)
    dummy_m = np.empty((0, 2))
    st, rs, sp, ni, nd = K._certify_box(e0, e1, u0, u1, max_iter, K.IMPACT_CAP, form, itin, False, dummy_d, dummy_m)
    dec = np.empty(nd, np.int64)
    marg = np.empty((nd, 2))
    again = K._certify_box(e0, e1, u0, u1, max_iter, K.IMPACT_CAP, form, itin, True, dec, marg)
    assert again == (st, rs, sp, ni, nd)  # the same computation, the same answer
    return st, rs, sp, itin[:ni].copy(), dec, marg


def _certificate(e0, e1, u0, u1, max_iter, st, rs, sp, itin, dec, marg):
    status = STATUSES[st]
    return Certificate(
        e=(e0, e1), u=(u0, u1), max_iter=max_iter, status=status,
        word=word_from_impacts(itin) if status == "word" else None,
        reason=UNDECIDED_REASONS[rs] if status == "undecided" else None,
        step=int(sp) if status == "undecided" else None,
        itinerary=tuple(int(k) for k in itin),
        decisions=Decisions(dec),
        margins=marg,
    )


def certify_box(e, u, max_iter=1000, *, form="corners") -> Certificate:
    """certify_box(e=(e0, e1), u=(u0, u1), max_iter=1000, *, form="corners") -> Certificate

    What is proven over the box ``[e0, e1] x [u0, u1]`` of the (e, u) plane (a
    point when ``e0 == e1`` and ``u0 == u1``), with the evidence.

    Proven (docs/design.md, "Certified boxes"): the orbit of the edge state
    ``(1, 0)`` is followed step by step, every decision of the Poincare map
    (Prop. 2.3) taken as the sign of its margin enclosed over the whole box by
    outward-rounded float64 interval arithmetic: the slide test (2.4)
    ``T - (v + (1+e)/(1-e) s)``, the first impact ``T - (v + s)`` and the
    later ones ``T - t_j`` with ``t_{j+1} = t_j + 2 e^j s`` (eq. 2.2).  A
    decision is proven when its enclosure has ``lo >= 0`` (it happens, equality
    included) or ``hi < 0``.  Because a slide resets the state exactly to
    ``(1, 0)``, a proven itinerary ending in a slide proves the periodic sliding
    solution's word at every point of the box.

    ``status``: ``"word"`` (with ``word``), ``"no_sliding"`` (Corollary 2.1 over
    the whole box, nothing iterated), ``"no_slide_within"`` (no slide in the
    first ``max_iter`` steps anywhere in the box) or ``"undecided"`` (with
    ``reason``, see :data:`UNDECIDED_REASONS`, and the ``step``).  The
    certificate lists every decision taken and the enclosure of its margin
    (:class:`stairbounce.Certificate`).

    The corners form (proven).  Along a frozen itinerary carry ``(v, s)``,
    ``s = sqrt(v^2 + 2y)``, from ``v = 0``, ``s = sqrt 2``: a step with k
    impacts (k = 0: a fly-over) gives ``v' = v - T + B_k s`` with ``B_0 = 0``,
    ``B_k = (1+e)(1 + e + ... + e^(k-1))``, and ``s'^2 = 2 + e^(2k) s^2``
    (Prop. 2.3, eq. (2.2); energy over the flight).  ``T = 1/u`` decreases in
    u, ``B_k >= 0`` and ``e^(2k)`` do not decrease in e, ``s >= 0``: by
    induction v and s do not decrease in e nor in u.  The margins
    ``T - v - ratio s`` (slide, ``ratio = (1+e)/(1-e)``) and
    ``T - v - A_j s`` (impact j, ``A_j = 1 + 2(e + ... + e^(j-1)) >= 1``) do
    not increase in e and decrease strictly in u.  So over the box a margin
    is >= 0 everywhere iff it is at ``(e1, u1)``, and < 0 everywhere iff it is
    at ``(e0, u0)``: each decision is taken from a lower bound of the margin
    at ``(e1, u1)`` and an upper bound at ``(e0, u0)`` (outward-rounded point
    evaluations), both corners walking the same itinerary; the recorded
    enclosure is ``[lo at (e1, u1), hi at (e0, u0)]``.  These are the margin's
    exact range up to rounding, so no enclosure over the box decides more.

    Parameters
    ----------
    e : pair (e0, e1), 0 <= e0 <= e1 < 1, each 0 or >= 2^-53; e0 = 0 with the corners
        form only (the coefficients above increase with e on [0, 1), so its two corners
        bound the box with e = 0 in it; e = 0 is the perfectly plastic impact: a ball
        that lands before the edge slides, eq. (2.4) with ratio 1)
    u : pair (u0, u1), 1e-150 <= u0 <= u1 <= 1e150
    max_iter : int >= 1, default 1000
        Steps followed before the claim ``no_slide_within``.
    form : "corners" (default), "mean-value" or "naive"
        The enclosures, all rigorous.  ``"corners"``: two point evaluations,
        at ``(e1, u1)`` and ``(e0, u0)`` (below); ``"naive"``: interval
        arithmetic over the box on ``(y, v)``; ``"mean-value"``: naive
        intersected with the first-order form about the box's centre along
        the frozen itinerary.

    Examples
    --------
    >>> import stairbounce as sb
    >>> c = sb.certify_box(e=(0.18, 0.1801), u=(0.62, 0.6201))
    >>> c.status, str(c.word)
    ('word', '(1, 1, 1, 2, 0^∞)')
    """
    e0, e1 = _check_e(e, zero=True)
    u0, u1 = _check_u(u)
    max_iter = check_count("max_iter", max_iter, 1)
    code = _check_form(form)
    if e0 == 0.0 and code != K.CORNERS:
        raise ValueError(f"e0 = 0 is certified by form='corners' only (its enclosures hold on [0, e1]), "
                         f"got form={form!r}")
    st, rs, sp, itin, dec, marg = _run_box(e0, e1, u0, u1, max_iter, code, _itinerary_buffer(max_iter))
    return _certificate(e0, e1, u0, u1, max_iter, st, rs, sp, itin, dec, marg)


# --------------------------------------------------------------------------- #
# The atlas                                                                   #
# --------------------------------------------------------------------------- #


def certify(e=(0.155, 0.2138), u=(0.6, 0.658), depth=10, max_iter=1000, progress=None, *, tiles=1,
            form="corners", trap=False, classes=False, phase=None) -> CertifiedAtlas:
    """certify(e=(lo, hi), u=(lo, hi), depth=10, max_iter=1000, progress=None, *, tiles=1, form="corners", trap=False, classes=False, phase=None) -> CertifiedAtlas

    Cover a window of the (e, u) plane with boxes, each certified
    (:func:`certify_box`): an adaptive quadtree down to boxes of
    window/2^depth.

    The window is first cut into 8 x 8 boxes; a box proven ``word``,
    ``no_sliding`` (Corollary 2.1 over the box, nothing iterated) or
    ``no_slide_within`` stops, an undecided one is split into four until
    ``depth``.  From ``depth - 4`` on, an undecided box at none of whose
    corners nor centre the float map slides within ``max_iter`` steps stops
    with the reason ``"nonsliding"`` (numerical: the enclosures of a long
    non-sliding orbit widen, and splitting cannot help there), so the atlas
    tells the undecided area of a border from that of non-sliding motion, at
    the last level too (the corners are shared between boxes and iterated
    once).  A
    box touching ``e = 1`` or ``u = 0`` is undecided (reason ``"range"``) and split
    down to the last level, so only a strip one box wide stays so; a box touching
    ``e = 0`` is certified like the others by the corners form (e = 0 is the
    perfectly plastic impact, inside the corners form's monotonicity on [0, 1);
    the other forms leave it "range").

    Every box is computed from its integer position in the window's quadtree
    alone, in parallel (numba ``prange`` over the boxes of a level): any number
    of threads and any tiling give the same boxes.

    Parameters
    ----------
    e : pair (lo, hi), 0 <= lo < hi <= 1
    u : pair (lo, hi), 0 <= lo < hi <= 1e150
    depth : int in [0, 26], default 10
        The smallest boxes are window/2^depth a side.
    max_iter : int >= 1, default 1000
    progress : callable ``progress(done, total)``, optional
        Called after each level of each tile, then (with ``trap``) every 1024
        boxes tried for a trapping region: ``done`` and ``total`` count the
        current phase.
    tiles : 1, 2, 4 or 8 (at most 2^depth), default 1
        Tiles a side, certified one after the other (the same boxes).
    form : "corners" (default), "mean-value" or "naive"
        The enclosures (:func:`certify_box`).
    trap : bool or "fine", default False
        Try a trapping region (:func:`stairbounce.trapping_region`) on every
        undecided ``"nonsliding"`` box; a box with one becomes ``no_sliding``
        with reason ``"trapping"`` (proven: the orbit of (1, 0) never slides
        there, so no periodic sliding solution), its region stored in the
        table (``trap_*`` variables) for ``sb.verify``.  A box whose region
        fails is split into its quadtree children, tried in turn, down to
        ``trapping.SPLIT_LEVELS`` (1) levels below ``depth`` (attribute
        ``trap_split``); where a piece is proven the box is replaced by the
        pieces, the unproven ones keeping its label
        (:func:`stairbounce.structure.trapping.trap_atlas`).  ``"fine"`` (for
        the perimeter's counts) makes the default pass's tries, then, where the
        spread of T = 1/u over the box is narrow, the grids their gates skipped
        and grids of 1024 to 8192 cells a side: the paper's plane at depth 12:
        84.7 -> 95.0 % of the non-sliding area below the curve proven, the pass
        about 14 times the atlas (about twice on Fig. 7's window at depth 10),
        its regions about 40 million cells (8 bytes each).

    classes : bool, default False
        Class-level proofs (:mod:`stairbounce.structure.classes`): an undecided
        border box (graze, edge, chatter) of the last level (coarser ones are
        split on, so the words keep their proven areas) has both sides of its undecided
        decisions followed; it becomes ``sliding`` (every point slides within
        ``max_iter``, its possible words in ``word``, separated by " | ") or
        ``no_slide_within`` (reason ``"branches"``) when that is proven, so what
        stays undecided is the border of the region sliding within ``max_iter``.
        A box meeting the Corollary 2.1 curve is split down to the last level
        rather than stopped as "nonsliding".  ``sb.verify`` re-checks them
        (``structure/verify_branches.py``).
    phase : callable ``phase(name)``, optional
        Called as each pass begins, so that a progress display can say what it
        counts: ``"levels 3-14"`` (the quadtree's levels, from the 8 x 8
        start level to ``depth``), then ``"class-level proofs"``,
        ``"trapping regions"`` and ``"re-checking trapping regions"`` when
        those passes run.

    Returns
    -------
    CertifiedAtlas

    Raises
    ------
    ValueError
        A bad parameter (naming it), or a level whose memory estimate (its
        boxes x 250 B) exceeds the memory available now, before its work:
        :func:`stairbounce.certify_to_zarr` streams the same atlas to a store
        with the memory of a tile.
    """
    from .._interrupt import run_interruptible

    # the levels and the numpy work between them off the main thread: Ctrl-C within 0.05 s
    return run_interruptible(_certify, e, u, depth, max_iter, progress, tiles, form, trap=trap, classes=classes,
                             phase=phase)


def _certify(e, u, depth, max_iter, progress, tiles, form, reference=False, trap=False, classes=False,
             phase=None):
    """:func:`certify`; with ``reference`` the "nonsliding" check is taken box by box in
    the level kernel (:func:`_kernel._any_slides`, the algorithm before the shared
    check of :func:`_mark_nonsliding`; the tests compare the two)."""
    e_lo, e_hi, u_lo, u_hi, depth, max_iter, code = _check_request(e, u, depth, max_iter, form)
    if progress is not None and not callable(progress):
        raise ValueError(f"progress must be None or a callable progress(done, total), got {progress!r}")
    if phase is not None and not callable(phase):
        raise ValueError(f"phase must be None or a callable phase(name), got {phase!r}")
    from .trapping import check_trap

    trap = check_trap(trap)
    if not isinstance(classes, (bool, np.bool_)):
        raise ValueError(f"classes must be True or False, got {classes!r}")
    start = min(_START_LEVEL, depth)
    allowed = [t for t in (1, 2, 4, 8) if t <= 1 << start]
    tiles = check_count("tiles", tiles, 1)
    if tiles not in allowed:
        raise ValueError(f"tiles must be one of {', '.join(map(str, allowed))} (a power of 2, at most 2^depth "
                         f"and 8), got {tiles}")
    win = np.array([e_lo, e_hi, u_lo, u_hi])
    t0 = time.perf_counter()
    per_tile = (1 << start) // tiles
    levels = depth - start + 1
    total = tiles * tiles * levels
    done = [0]

    def tick():
        done[0] += 1
        if progress is not None:
            progress(done[0], total)

    if phase is not None:
        phase(f"levels {start}-{depth}")
    if progress is not None:
        progress(0, total)
    parts = []
    points = _SlideCache(win, depth, max_iter)
    for tj in range(tiles):
        for ti in range(tiles):
            # the tile's boxes of the start level, as one level-wide batch
            gi, gj = np.meshgrid(np.arange(ti * per_tile, (ti + 1) * per_tile),
                                 np.arange(tj * per_tile, (tj + 1) * per_tile))
            for _, level_done in _run_tile(win, depth, start, gi.ravel(), gj.ravel(), max_iter, code, parts,
                                           None if reference else points, classes=classes):
                if level_done:
                    tick()
    cols, kept, row = _box_table(parts)
    del parts
    ds = _atlas_dataset(win, depth, max_iter, code, *cols, kept, row)
    if classes:
        from .classes import mark_atlas

        if phase is not None:
            phase("class-level proofs")
        mark_atlas(ds)
    if trap:
        from .trapping import trap_atlas

        if phase is not None:
            phase("trapping regions")
        ds = trap_atlas(ds, progress=progress, fine=trap == "fine")
        if phase is not None:
            phase("re-checking trapping regions")
        _recheck_regions(ds)
    return CertifiedAtlas(ds, seconds=time.perf_counter() - t0)


def _recheck_regions(ds):
    """Re-verify the atlas's trapping regions with the independent checker
    (``structure/verify_trapping.py``) before the atlas is returned; a region that
    fails is a fault of the certifier: RuntimeError."""
    from .verify_trapping import check_atlas_regions

    status = ds["status"].values
    arrays = {"status": status, "max_iter": int(ds.attrs["max_iter"]),
              **{k: ds[k].values for k in ("e0", "e1", "u0", "u1", "itinerary", "offsets")}}
    code = np.zeros(status.size, np.int8)
    check_atlas_regions(ds, arrays, code, 1)
    if code.any():
        b = int(np.flatnonzero(code)[0])
        raise RuntimeError(f"the trapping region of box {b} failed the independent check "
                           f"({int(np.count_nonzero(code))} regions failed): a fault of the certifier, please report it")


def _run_tile(win, depth, start, gi, gj, max_iter, form, out, points=None, batch=None, classes=False):
    """The quadtree below a batch of boxes ``(gi, gj)`` of level ``start``, as a
    generator: it appends the final boxes to ``out`` as arrays ``(level, i, j, status,
    reason, step, nsteps, kept)``, one tuple per level (``kept``: the kept itineraries
    of the proven boxes only, in their order), and yields ``(level, level_done)`` after
    each kernel call: a level in one call, or with ``batch`` in calls of at most
    ``batch`` boxes (the explorer's bounded slices; boxes are independent, so the
    boxes are the same).

    ``points``: a :class:`_SlideCache` (the "nonsliding" check of many boxes at once,
    its box corners shared, :func:`_mark_nonsliding`), or None for the check box by
    box in the level kernel (the reference: the same boxes)."""
    from .._interrupt import run_kernel

    ii = gi.astype(np.int64)
    jj = gj.astype(np.int64)
    ns_level = max(0, depth - _NONSLIDING_LEVELS)
    held = 0  # bytes of the final boxes kept so far
    warned = False
    for level in range(start, depth + 1):
        n = ii.size
        need = n * _LEVEL_BYTES_PER_BOX + held
        if need > _WARN_BYTES and not warned:
            warned = True
            warnings.warn(f"certify: level {level} of {depth} holds {n:,} boxes, about {need / 2**30:.1f} GiB "
                          "with the boxes kept so far; each further level holds up to 4 times as many boxes "
                          "(about 3 times on the paper's windows)", CertifyMemoryWarning, stacklevel=2)
        avail = _available_memory()
        if avail is not None and n * _LEVEL_BYTES_PER_BOX > avail:
            raise ValueError(f"certify: depth {depth} needs about {need / 2**30:.1f} GiB at level {level}, more "
                             f"than this machine's {avail / 2**30:.1f} GiB available; use certify_to_zarr / --store")
        status = np.empty(n, np.int8)
        reason = np.empty(n, np.int8)
        step = np.empty(n, np.int64)
        nsteps = np.empty(n, np.int64)
        kept = np.empty((n, _KEPT), np.int16)
        # a box stops as "nonsliding" only when neither its centre nor a corner slides, at
        # every level from ns_level on, the last included (issue 43: the label's promise)
        ns_points = 0 if level < ns_level else 5
        size = max(1, n if batch is None else batch)
        for lo in range(0, n, size):
            s = slice(lo, min(n, lo + size))
            run_kernel(K._certify_level, win, level, ii[s], jj[s], max_iter, K.IMPACT_CAP, form,
                       ns_points if points is None else 0, status[s], reason[s], step[s], nsteps[s], kept[s])
            if classes and level == depth:  # class-level proofs (structure/classes.py) on the leaves:
                # coarser undecided boxes are split on, so the words keep their proven areas
                from .classes import classify_level

                classify_level(win, level, ii[s], jj[s], max_iter, status[s], reason[s], nsteps[s])
            if ns_points and points is not None:
                _mark_nonsliding(win, level, depth, ii[s], jj[s], status[s], reason[s], ns_points, points,
                                 keep_curve=classes and level < depth)
            if s.stop < n:
                yield level, False
        final = (status != K.UNDECIDED) | (reason == K.NONSLIDING) | (level == depth)
        keep = final & ((status == K.WORD) | (status == K.NO_SLIDE_WITHIN)) & (nsteps <= _KEPT)
        out.append((np.full(int(final.sum()), level, np.int8), ii[final], jj[final], status[final],
                    reason[final], step[final], nsteps[final], kept[keep]))
        held += sum(a.nbytes for a in out[-1])
        del kept
        split = ~final
        parents_i, parents_j = ii[split], jj[split]
        ii = np.empty(4 * parents_i.size, np.int64)
        jj = np.empty(4 * parents_i.size, np.int64)
        K._children(parents_i, parents_j, ii, jj)  # in the atlas's order when the parents are
        del parents_i, parents_j
        yield level, True


def _box_table(parts):
    """The final boxes of :func:`_run_tile`'s tuples as the columns ``(level, i, j,
    status, reason, step, nsteps)`` in the atlas's order (by level, then j, then i), the
    kept itineraries and each box's row of them (-1: computed again), for
    :func:`_atlas_dataset`."""
    cols = [np.concatenate([p[k] for p in parts]) for k in range(8)]
    level, ii, jj = cols[:3]
    # by level, then j, then i (np.lexsort((ii, jj, level))'s order) by one int64 key
    from ._store_read import row_key

    key = row_key(level, ii, jj)
    # the kept rows follow their proven boxes (kept for the proven boxes only, in box order)
    st = cols[3]
    keep = ((st == K.WORD) | (st == K.NO_SLIDE_WITHIN)) & (cols[6] <= _KEPT)
    row = np.full(st.size, -1, np.int64)
    row[keep] = np.arange(int(keep.sum()))
    if bool(np.all(key[1:] > key[:-1])):  # one tile: the levels' boxes came in this order (_run_tile)
        return cols[:7], cols[7], row
    # tiles, or boxes given in another order: sorted runs, merged (the keys are distinct)
    order = np.argsort(key, kind="stable")
    del key
    return [c[order] for c in cols[:7]], cols[7], row[order]


class _SlideCache:
    """Whether the float map slides from ``(1, 0)`` within ``max_iter`` steps at grid
    points of a window's quadtree (box corners: the same floats at every level,
    :func:`_kernel._edge`), kept by the point's index at the deepest level, so that
    a corner shared by neighbouring boxes, or by a box and its parent, is iterated once."""

    def __init__(self, win, depth, max_iter):
        self.win, self.depth, self.max_iter = win, depth, max_iter
        self.keys = np.zeros(0, np.int64)
        self.slid = np.zeros(0, bool)

    def slides(self, es, us):
        """The float map's verdict at the points ``(es, us)`` (:func:`_slides_at`)."""
        return _slides_at(es, us, self.max_iter)

    def corners(self, level, gi, gj):
        """The verdict at the grid points ``(gi, gj)`` of ``level``."""
        sh = self.depth - level
        # by j, then i: the corners of boxes in the atlas's order come as four sorted runs
        keys = (gj << sh) * ((1 << self.depth) + 1) + (gi << sh)
        new, inverse = _unique_runs(keys)
        pos = np.minimum(np.searchsorted(self.keys, new), max(self.keys.size - 1, 0))
        known = (self.keys[pos] == new) if self.keys.size else np.zeros(new.size, bool)
        slid = np.zeros(new.size, bool)
        slid[known] = self.slid[pos[known]]
        todo = np.flatnonzero(~known)
        if todo.size:
            n = (1 << self.depth) + 1
            tj, ti = new[todo] // n >> sh, new[todo] % n >> sh
            es, us = np.empty(todo.size), np.empty(todo.size)
            K._grid_points(self.win, level, ti, tj, es, us)
            slid[todo] = self.slides(es, us)
            keys_all = np.concatenate([self.keys, new[todo]])
            order = np.argsort(keys_all, kind="stable")
            self.keys = keys_all[order]
            self.slid = np.concatenate([self.slid, slid[todo]])[order]
        return slid[inverse.ravel()]


def _unique_runs(keys):
    """``np.unique(keys, return_inverse=True)`` by a stable sort, which merges sorted
    runs (timsort) instead of sorting from scratch: the same arrays.  (``np.unique``
    sorts by quicksort, or by the merging sort only with ``return_index``, which on
    12 million keys in four runs took 0.85 s against 0.27 s here.)"""
    if not keys.size:
        return keys.copy(), np.zeros(0, np.int64)
    order = np.argsort(keys, kind="stable")
    ordered = keys[order]
    first = np.empty(keys.size, bool)
    first[0] = True
    np.not_equal(ordered[1:], ordered[:-1], out=first[1:])
    inverse = np.empty(keys.size, np.int64)
    inverse[order] = np.cumsum(first) - 1
    return ordered[first], inverse


def _slides_at(es, us, max_iter, chunk=1 << 20):
    """Whether the float map (``model._slide_or_steps`` from ``(1, 0)``) slides within
    ``max_iter`` steps at each point: the scan's lane kernel (``plane._run``, pixel by
    pixel the same iteration, tests/test_plane.py), no pruning, in chunks; fewer points
    than a unit of the scan's parallel work by :func:`_kernel._slides_each`."""
    from ..plane import _UNIT_MIN, _run

    out = np.zeros(es.size, bool)
    if es.size < _UNIT_MIN:  # too few for the lanes' threads to pay: one loop here
        K._slides_each(es, us, max_iter, out)
        return out
    for a in range(0, es.size, chunk):
        res, _ = _run(es[a:a + chunk], us[a:a + chunk], False, max_iter, 1.0, 0.0, False)
        out[a:a + chunk] = res["status"] == 0
    return out


def _mark_nonsliding(win, level, depth, ii, jj, status, reason, ns_points, points, keep_curve=False):
    """Give the reason "nonsliding" to the undecided boxes of a level (not "range" nor
    "impacts") at none of whose first ``ns_points`` points (1: the centre; 5: the centre
    and the corners) the float map slides: the verdict of :func:`_kernel._any_slides`,
    taken for all the boxes at once, each corner once (``points``, a :class:`_SlideCache`)."""
    cand = np.flatnonzero((status == K.UNDECIDED) & (reason != K.RANGE) & (reason != K.IMPACTS))
    if keep_curve and cand.size:  # boxes meeting the Corollary 2.1 curve are split on
        cand = cand[~_meets_curve(win, level, ii[cand], jj[cand])]
    if not cand.size:
        return
    es, us = np.empty(cand.size), np.empty(cand.size)
    K._centres(win, level, ii[cand], jj[cand], es, us)
    rest = cand[~points.slides(es, us)]
    if ns_points > 1 and rest.size:
        ci, cj = ii[rest], jj[rest]
        gi = np.concatenate([ci, ci + 1, ci, ci + 1])
        gj = np.concatenate([cj, cj, cj + 1, cj + 1])
        rest = rest[~points.corners(level, gi, gj).reshape(4, -1).any(axis=0)]
    reason[rest] = K.NONSLIDING


def _meets_curve(win, level, ii, jj):
    """Whether part of each box ``(ii, jj)`` of a level is above the Corollary 2.1 curve
    (proven at its corner ``(e1, u1)``: a child there would be ``no_sliding``)."""
    e0, e1, u0, u1 = (np.empty(ii.size) for _ in range(4))
    K._box_edges(win, np.full(ii.size, level, np.int64), ii, jj, e0, e1, u0, u1)
    with np.errstate(divide="ignore", invalid="ignore"):
        bound = (1.0 - e1) / (2.0 * np.sqrt(2.0 * e1))
    return (e1 < 1.0) & (u1 > bound * (1.0 + 1e-12))


def _atlas_dataset(win, depth, max_iter, form, level, ii, jj, status, reason, step, nsteps, kept, row):
    """The atlas's table: one row per box, with the array form of certificate.py
    (the itineraries from ``kept[row[b]]`` where ``row[b] >= 0``, else computed again).
    Words and reasons are Python strings, one object per distinct text (8 bytes a box)."""
    import xarray as xr

    from .._interrupt import run_kernel
    from .._version import __version__

    e0, e1, u0, u1 = (np.empty(level.size) for _ in range(4))
    K._box_edges(win, level.astype(np.int64), ii, jj, e0, e1, u0, u1)
    proven_path = (status == K.WORD) | (status == K.NO_SLIDE_WITHIN)
    lengths = np.where(proven_path, nsteps, 0)
    offsets = np.zeros(level.size + 1, np.int64)
    np.cumsum(lengths, out=offsets[1:])
    itinerary = np.empty(int(offsets[-1]), np.int64)
    short = row >= 0  # (proven, with at most _KEPT steps: lengths = nsteps)
    if short.any():
        run_kernel(K._kept_itineraries, itinerary, offsets, kept, row)
    sel = np.flatnonzero(proven_path & ~short)
    if sel.size:
        run_kernel(K._itineraries, win, level[sel].astype(np.int64), ii[sel], jj[sel], max_iter, K.IMPACT_CAP, form,
                   offsets[sel], offsets[sel + 1], itinerary)
    words = _word_texts(status, itinerary, offsets)
    reasons = np.array([""] + list(UNDECIDED_REASONS), dtype=object)[np.where(status == K.UNDECIDED, reason + 1, 0)]
    ds = xr.Dataset(
        {
            "e0": ("box", e0), "e1": ("box", e1), "u0": ("box", u0), "u1": ("box", u1),
            "status": ("box", status.astype(np.int8, copy=False)),
            "word": ("box", words),
            "reason": ("box", reasons),
            "step": ("box", np.where(status == K.UNDECIDED, step, 0).astype(np.int64, copy=False)),
            "level": ("box", level.astype(np.int8, copy=False)),
            "i": ("box", ii.astype(np.int64, copy=False)), "j": ("box", jj.astype(np.int64, copy=False)),
            "offsets": ("offset", offsets),
            "itinerary": ("itinerary_step", itinerary),
        },
        attrs={
            "e_range": [float(win[0]), float(win[1])], "u_range": [float(win[2]), float(win[3])],
            "depth": int(depth), "max_iter": int(max_iter), "form": _FORM_NAMES[form],
            "statuses": ",".join(STATUSES), "impact_cap": int(K.IMPACT_CAP),
            "nonsliding_levels": int(_NONSLIDING_LEVELS), "stairbounce_version": __version__,
            "kind": "stairbounce certified atlas",
        },
    )
    return ds


# text rows written to a netCDF file per call (_to_netcdf_in_slices)
_TEXT_SLICE = 1 << 18


def _to_netcdf_in_slices(ds, path, encoding):
    """``ds.to_netcdf(path)`` (netCDF4), its text columns (``word``, ``reason``:
    variable-length strings) written afterwards in slices of :data:`_TEXT_SLICE`
    rows: the netCDF library converts a text column holding Python's lock, which
    for the 4.4 million boxes of a depth-13 atlas was 0.54 s in one call, so long
    that a Ctrl-C waited for it (issue 45, item 5).  The file is the one
    ``to_netcdf`` writes: the same variables, types and attributes."""
    import netCDF4

    texts = [k for k in ds.data_vars if ds[k].dtype.kind == "O"]
    ds.drop_vars(texts).to_netcdf(path, engine="netcdf4", format="NETCDF4", encoding=encoding)
    with netCDF4.Dataset(path, "a") as nc:
        for k in texts:
            var = nc.createVariable(k, str, ds[k].dims)
            var.setncatts({a: v for a, v in ds[k].attrs.items()})
            values = ds[k].values
            for lo in range(0, values.size, _TEXT_SLICE):
                var[lo:lo + _TEXT_SLICE] = values[lo:lo + _TEXT_SLICE]


def _word_texts(status, itinerary, offsets):
    """The word (ASCII text, ``""`` unless proven) of every box, spelled once per distinct
    itinerary (told apart by a hash, the boxes of one hash checked to share the itinerary;
    where they do not, by the itineraries' bytes)."""
    words = np.full(status.size, "", dtype=object)
    wb = np.flatnonzero(status == K.WORD)
    if not wb.size:
        return words
    h = np.empty(wb.size, np.int64)
    K._itinerary_hashes(itinerary, offsets, wb, h)
    _, first, inverse = np.unique(h, return_index=True, return_inverse=True)
    inverse = inverse.ravel()
    if not K._same_itineraries(itinerary, offsets, wb, wb[first][inverse]):  # a collision: by the bytes
        keys = [itinerary[offsets[b]:offsets[b + 1]].tobytes() for b in wb]
        index = {}
        inverse = np.array([index.setdefault(k, len(index)) for k in keys], np.int64)
        first = np.zeros(len(index), np.int64)
        first[inverse[::-1]] = np.arange(wb.size)[::-1]
    names = np.array([word_from_impacts(itinerary[offsets[b]:offsets[b + 1]]).format(ascii=True)
                      for b in wb[first]] + [""], dtype=object)[:-1]
    words[wb] = names[inverse]
    return words


def _area(ds):
    return (ds["e1"].values - ds["e0"].values) * (ds["u1"].values - ds["u0"].values)


def counted_depth(attrs):
    """The finest scale an atlas's border counts are taken at: its ``depth``, or its
    ``focus`` when it was refined only where the counts at ``k <= focus`` can change
    (``certify_to_zarr(focus=...)``, :mod:`stairbounce.structure.focus`)."""
    focus = attrs.get("focus")
    return int(attrs["depth"]) if focus is None else int(focus)


def _border_classes(st, words, border):
    """The class of each box for :meth:`CertifiedAtlas.border_box_counts`: -2 undecided,
    -1 not sliding (``no_sliding``, ``no_slide_within``), >= 0 sliding (``"sliding"``:
    one class, 0; ``"words"``: one class per proven word, ``sliding`` boxes undecided)."""
    if border not in ("sliding", "words"):
        raise ValueError(f"border must be one of sliding, words, got {border!r}")
    cls = np.full(st.size, -1, np.int64)
    w = st == K.WORD
    if border == "sliding":
        cls[w | (st == _SLIDING_STATUS)] = 0
    else:
        if w.any():
            cls[w] = np.unique(words[w], return_inverse=True)[1]
        cls[st == _SLIDING_STATUS] = -2
    cls[st == K.UNDECIDED] = -2
    return cls


def _counts_frame(rows, of, border):
    """The table of :meth:`CertifiedAtlas.border_box_counts` from its rows (one dict a
    scale: k, size_e, size_u, lower, upper), with the slope brackets between scales."""
    import pandas as pd

    df = pd.DataFrame(rows)
    df["slope_lo"], df["slope_hi"] = _slope_bounds(df["lower"].to_numpy(float), df["upper"].to_numpy(float), 1)
    df.attrs["of"] = of
    df.attrs["border"] = border
    return df


def _scales(k1, k2, depth):
    """The scales of :meth:`CertifiedAtlas.perimeter_bracket` (default ``min(3, depth - 1)
    .. depth``), checked."""
    k1 = check_count("k1", min(3, depth - 1) if k1 is None else k1, 0, depth)
    k2 = check_count("k2", depth if k2 is None else k2, k1 + 1, depth)
    return k1, k2


def perimeter_result(df, k1, k2, depth, max_iter, verdict, focus=None):
    """The dict :meth:`CertifiedAtlas.perimeter_bracket` returns, from the sliding
    border's counts ``df`` and the independent checker's ``verdict`` on the boxes they
    were counted from (None: not run); :meth:`CertifiedStore.perimeter_bracket` builds
    the same from a store's tiles."""
    lower, upper = df["lower"].to_numpy(), df["upper"].to_numpy()
    lo, hi = CertifiedAtlas._slope_between(df, k1, k2)
    span = _finite_scales(lower, upper, k1, k2)
    if span is None:
        finite, finite_text = None, (f"no two scales of k = {k1} .. {k2} have a lower count > 0: every "
                                     "slope bracket there has an open end")
    else:
        a, b = span
        flo, fhi = CertifiedAtlas._slope_between(df, a, b)
        finite, finite_text = (a, b, flo, fhi), slope_text(flo, fhi, a, b, lower, upper)
    widest = _widest_scales(lower, k1, k2)
    if widest is None:
        across = None
    else:
        a, b = widest
        across = (a, b, *CertifiedAtlas._slope_between(df, a, b))
    refined = "" if focus is None else f", refined below depth {int(focus)} only where the counts at k <= {int(focus)} can change"
    what = f"certified boxes (interval arithmetic, certify depth {depth}{refined}, max_iter {max_iter})"
    if verdict is None:
        verified, basis = None, "numerical"
        proof = what + ", NOT re-verified (verify=False): the certifier's claim, not yet the checker's"
    else:
        v = verdict
        verified = bool(v.ok and v.atlas and v.complete)
        basis = "proven" if verified else "numerical"
        proof = (what + f"; all {v.checked} boxes re-verified by the independent checker sb.verify"
                 if verified else f"NOT proven: sb.verify did not pass the atlas ({v.message})")
    n_wit = int(df.attrs.get("witnesses", 0))
    if n_wit:
        proof += ("; the lower counts also use proven points inside undecided boxes (witnesses), each certified "
                  "as a degenerate box and re-verified by the independent checker")
    proof += ("; the counts bound the number of closed window/2^k cells meeting the border of the region "
              "sliding within max_iter")
    return {"k1": k1, "k2": k2, "k": list(range(k1, k2 + 1)),
            "lower": [int(x) for x in lower[k1:k2 + 1]], "upper": [int(x) for x in upper[k1:k2 + 1]],
            "slope": (lo, hi), "slope_text": slope_text(lo, hi, k1, k2, lower, upper),
            "finite": finite, "finite_text": finite_text, "across": across, "depth": depth,
            "focus": None if focus is None else int(focus), "max_iter": max_iter,
            "verified": verified, "basis": basis, "proof": proof, "not_proven": NOT_PROVEN,
            "witnesses": n_wit, "witnesses_tried": int(df.attrs.get("witnesses_tried", 0))}


NOT_PROVEN = ("the border of the region sliding at all (the limit max_iter -> infinity), nor the dimension "
              "(the limit of small scales: a slope between finite scales is not the dimension)")
"""What the proven box counts of the perimeter (:meth:`CertifiedAtlas.perimeter_bracket`) do not prove."""


def _slope_bounds(lower, upper, dk):
    """Brackets on the slopes ``log2(N_k / N_{k-1}) / dk`` between consecutive rows
    of proven counts ``lower <= N <= upper`` (nan first), rounded outward
    (:func:`tiling.log2_ratio_bounds`; dividing by a power of two is exact, by
    another ``dk`` moved one float outward)."""
    from .tiling import log2_ratio_bounds

    lo, _ = log2_ratio_bounds(lower[1:], upper[:-1])
    _, hi = log2_ratio_bounds(upper[1:], lower[:-1])
    with np.errstate(invalid="ignore"):
        lo, hi = lo / dk, hi / dk
    if dk & (dk - 1):
        lo, hi = np.nextafter(lo, -np.inf), np.nextafter(hi, np.inf)
    return np.concatenate([[np.nan], lo]), np.concatenate([[np.nan], hi])


def _finite_scales(lower, upper, k1, k2):
    """``(a, b)``: of the scales ``k1 <= a < b <= k2`` whose lower counts are both > 0
    (so that both ends of the slope bracket between them are finite), the pair with the
    narrowest bracket (ties: the wider range of scales); None when fewer than two
    scales of ``k1 .. k2`` have a lower count > 0."""
    ks = [k for k in range(k1, k2 + 1) if lower[k] > 0]
    best, key = None, None
    for i, a in enumerate(ks):
        for b in ks[i + 1:]:
            lo, hi = _slope_bounds(np.array([lower[a], lower[b]], float), np.array([upper[a], upper[b]], float),
                                   b - a)
            k = (hi[1] - lo[1], a - b)
            if key is None or k < key:
                best, key = (a, b), k
    return best


def _widest_scales(lower, k1, k2):
    """``(a, b)``: the coarsest and the finest scale of ``k1 .. k2`` whose lower counts
    are > 0 (the widest span with both ends of the slope bracket finite); None when
    fewer than two scales have one."""
    ks = [k for k in range(k1, k2 + 1) if lower[k] > 0]
    return (ks[0], ks[-1]) if len(ks) >= 2 else None


def slope_text(lo, hi, k1, k2, lower, upper):
    """The proven bracket ``(lo, hi)`` on the box-counting slope between the scales
    ``k1 < k2`` as text, its ends rounded outward to 3 decimals; an end that a zero
    count leaves open is said so (``lower``, ``upper``: the counts, indexed by k): a
    zero lower count at ``k1`` gives no upper bound, one at ``k2`` no lower bound, and
    an upper count 0 at ``k1`` means no cell there can meet the border."""
    if upper[k1] == 0:
        return (f"undefined between k = {k1} and {k2}: the upper count at k = {k1} is 0 (no cell there "
                "can meet the border)")
    a = f"{math.floor(lo * 1000) / 1000:.3f}" if math.isfinite(lo) else "-inf"
    b = f"{math.ceil(hi * 1000) / 1000:.3f}" if math.isfinite(hi) else "+inf"
    open_ = [f"no upper bound: the lower count at k = {k1} is 0"] if not math.isfinite(hi) else []
    open_ += [f"no lower bound: the lower count at k = {k2} is 0"] if not math.isfinite(lo) else []
    text = f"in [{a}, {b}] between k = {k1} and {k2}"
    return text + (f" ({'; '.join(open_)})" if open_ else "")


def slope_verdict(dimension, finite):
    """``(verdict, why)``: does a numerical dimension lie inside the proven slope
    bracket ``finite = (a, b, lo, hi)``, its ends rounded outward to 3 decimals?
    "differs" when outside, "not comparable" when there is no finite bracket or when
    it holds all of [1, 2] (too wide to decide: every dimension a border in the plane
    can have), "agrees" when inside a narrower one.  A slope between finite scales is
    not the dimension: the verdict compares the two.  The callers pass
    :meth:`CertifiedAtlas.perimeter_bracket`'s ``across``, the slope from the coarsest
    to the finest scale with a lower count > 0, not the narrowest bracket
    (``finite``): at the coarsest scales the border fills much of the window's cells
    and the slope between two of them is pulled away from the dimension (the Fig. 6
    window at depth 12 with ``trap="fine"``: [1.403, 1.421] between k = 3 and 4, while
    between 3 and 12 it is [1.451, 1.639]; the pictures' D is about 1.55)."""
    if finite is None:
        return "not comparable", ("no finite proven bracket: fewer than two scales have a lower count > 0, "
                                  "and a zero lower count leaves the slope unbounded")
    a, b, lo, hi = finite
    lo_r, hi_r = math.floor(lo * 1000) / 1000, math.ceil(hi * 1000) / 1000
    where = f"the proven bracket [{lo_r:.3f}, {hi_r:.3f}] of the slope between k = {a} and {b}"
    if not lo_r <= dimension <= hi_r:
        return "differs", f"the numerical D = {dimension:.3f} is outside {where}"
    if lo_r <= 1.0 and hi_r >= 2.0:
        return "not comparable", (f"bracket too wide to decide: {where} holds every dimension 1 .. 2 a border "
                                  f"in the plane can have (the numerical D = {dimension:.3f} is inside it)")
    return "agrees", f"the numerical D = {dimension:.3f} is inside {where}"


class CertifiedAtlas:
    """A window of the (e, u) plane covered by certified boxes (:func:`certify`).

    ``boxes`` is an ``xarray.Dataset`` with a ``box`` dimension: the box edges
    ``e0, e1, u0, u1``, ``status`` (int8, an index into
    :data:`stairbounce.structure.certificate.STATUSES`), ``word`` (ASCII, ``""``
    unless proven), ``reason`` and ``step`` (undecided boxes), the box's place
    in the quadtree ``level, i, j``, and the itineraries of the proven
    (``word``, ``no_slide_within``) boxes in the array form of
    :mod:`stairbounce.structure.certificate` (``itinerary``, ``offsets``; the
    attribute ``max_iter``).  Its areas and shares are proven bounds: sums of the
    boxes' exact areas rounded outward (``structure/tiling.py``); they are of the
    window when the boxes cover it (always, for an atlas of :func:`certify`), else of
    the covered part (:meth:`area_basis`).
    """

    def __init__(self, boxes, seconds=None):
        self.boxes = boxes
        self.seconds = seconds
        self._areas = None

    # -- what it says ------------------------------------------------------

    @property
    def window(self):
        """``((e_lo, e_hi), (u_lo, u_hi))``."""
        a = self.boxes.attrs
        return tuple(a["e_range"]), tuple(a["u_range"])

    @property
    def max_iter(self) -> int:
        return int(self.boxes.attrs["max_iter"])

    @property
    def depth(self) -> int:
        return int(self.boxes.attrs["depth"])

    def _book(self):
        """The proven areas of the boxes (:class:`tiling.AreaBook`), of the window when
        the boxes tile it (:func:`tiling.tiling`), else of the covered part."""
        if self._areas is None:
            from .tiling import AreaBook, deepest_level, tiling

            ds = self.boxes
            cols = [ds[k].values for k in ("e0", "e1", "u0", "u1")]
            t = tiling(self.window, deepest_level(self.depth, ds.attrs), ds["level"].values, ds["i"].values,
                       ds["j"].values, *cols)
            bad = int(np.count_nonzero(~t.placed | t.overlapping))
            if bad:
                raise ValueError(f"the atlas's boxes are not its window's quadtree ({bad} boxes misplaced or "
                                 "overlapping; sb.verify says which): its derived numbers are refused")
            self._areas = AreaBook(*cols, self.window, t.complete)
        return self._areas

    def area_basis(self) -> str:
        """area_basis() -> str: what the areas and shares are of and how they are proven."""
        return (f"proven bounds of {self._book().of}: sums of the boxes' exact areas rounded outward"
                + ("" if self._book().complete else " (the boxes do not cover the window)"))

    def to_dataframe(self):
        """The boxes as a pandas DataFrame, one row per box (status by name; the
        itineraries and the trapping regions left out: they are not per box)."""
        box_vars = [k for k, v in self.boxes.data_vars.items() if v.dims == ("box",)]
        df = self.boxes[box_vars].to_dataframe()
        df["status"] = np.array(STATUSES, dtype=object)[df["status"].to_numpy()]
        return df

    def fraction(self, by="status", bound="lower"):
        """fraction(by="status", bound="lower") -> dict: the window's area share of each
        status, or with ``by="reason"`` of each reason of the undecided boxes, or with
        ``by="word"`` of each proven word (largest first).

        Proven (``structure/tiling.py``): ``bound="lower"`` (default) a lower bound on
        each share, ``"upper"`` an upper bound, ``"both"`` the pair ``(lower, upper)``:
        the exact share of the boxes' area lies between them (a relative 1e-15 or so apart).
        Of the covered part when the boxes do not cover the window (:meth:`area_basis`).
        """
        if bound not in ("lower", "upper", "both"):
            raise ValueError(f"bound must be one of lower, upper, both, got {bound!r}")
        book = self._book()
        st = self.boxes["status"].values
        if by == "status":
            pairs = {name: book.share(st == k) for k, name in enumerate(STATUSES)}
        elif by == "reason":
            got = book.groups(self.boxes["reason"].values, st == K.UNDECIDED)
            pairs = {r: book._ratio(*got[r]) if r in got else (0.0, 0.0) for r in UNDECIDED_REASONS}
        elif by == "word":
            got = book.groups(self.boxes["word"].values, st == K.WORD)
            pairs = {str(w): book._ratio(*a) for w, a in sorted(got.items(), key=lambda p: (-p[1][0], str(p[0])))}
        else:
            raise ValueError(f"by must be one of status, reason, word, got {by!r}")
        if bound == "both":
            return pairs
        return {k: v[0 if bound == "lower" else 1] for k, v in pairs.items()}

    def word_area_bounds(self, word):
        """word_area_bounds(word) -> (lower, upper): proven bounds on the area of
        the window's points with periodic sliding solution ``word`` (a
        :class:`stairbounce.Word` or its text).

        Lower: the area of the boxes proven to have it.  Upper: the window less
        every box proven to be something else (another word, ``no_sliding``, or
        ``no_slide_within`` when the word's period is at most ``max_iter``).
        Both sums rounded outward (``structure/tiling.py``); of the covered part
        when the boxes do not cover the window (:meth:`area_basis`).
        """
        from ..symbolic import parse_word

        w = word if isinstance(word, Word) else parse_word(word)
        text = w.format(ascii=True)
        got = self._book().word_bounds(self.boxes["status"].values, self.boxes["word"].values, self.max_iter,
                                       lambda _: w.period, only=text)
        return got[text]

    def words(self):
        """words() -> pandas.DataFrame: the proven words (a proven lower bound on
        the number of distinct words in the window), largest proven area first,
        with ``period``, ``length``, ``boxes`` and ``area`` (the proven lower
        bound on the word's area, rounded down: ``structure/tiling.py``);
        ``.attrs["by_period"]`` counts them by period."""
        import pandas as pd

        from ..symbolic import parse_word
        from .tiling import unique_inverse

        words = self.boxes["word"].values
        sel = self.boxes["status"].values == K.WORD
        names, inverse = unique_inverse(words[sel])
        counts = np.bincount(inverse, minlength=names.size)
        got = self._book().groups(words, sel)
        sums = np.array([got[n][0] for n in names], dtype=np.float64)
        parsed = [parse_word(str(n)) for n in names]
        df = pd.DataFrame({
            "word": [str(n) for n in names], "period": [w.period for w in parsed],
            "length": [len(w) for w in parsed], "boxes": counts.astype(np.int64), "area": sums,
        }).sort_values(["area", "word"], ascending=[False, True], ignore_index=True)
        df.attrs["by_period"] = {int(p): int(c) for p, c in df["period"].value_counts().sort_index().items()}
        return df

    def certificates(self):
        """certificates() -> iterator of Certificate: the proven boxes'
        certificates, each decision and margin recomputed exactly as the atlas
        computed it."""
        ds = self.boxes
        form = _FORM_CODES[str(ds.attrs["form"])]
        st = ds["status"].values
        itin = _itinerary_buffer(self.max_iter)
        cols = [ds[k].values for k in ("e0", "e1", "u0", "u1")]
        trapped = ds["reason"].values == "trapping"
        branches = ds["reason"].values == "branches"  # no single itinerary: sb.verify(atlas) checks them
        for b in np.flatnonzero((st != K.UNDECIDED) & ~branches):
            if trapped[b]:  # a trapping region (structure/trapping.py)
                from .trapping import certificate_of, region_of

                yield certificate_of(region_of(ds, b), self.max_iter)
                continue
            e0, e1, u0, u1 = (float(c[b]) for c in cols)
            s, rs, sp, it, dec, marg = _run_box(e0, e1, u0, u1, self.max_iter, form, itin)
            yield _certificate(e0, e1, u0, u1, self.max_iter, s, rs, sp, it, dec, marg)

    def border_box_counts(self, border="sliding", *, witnesses=None):
        """border_box_counts(border="sliding", *, witnesses=None) -> pandas.DataFrame: for each scale
        s = window/2^k (k = 0 .. depth) proven bounds on N(s), the number of closed
        s-boxes of the window's grid that meet a border between classes of boxes.

        ``border="sliding"`` (the default since issue 44; the paper's perimeter,
        Figs. 6 and 7): two classes, the points whose orbit of (1, 0) slides
        within ``max_iter`` steps (boxes ``word``, and ``sliding`` of the
        class-level proofs, ``certify(classes=True)``) and those where it does not
        (``no_sliding``, ``no_slide_within``); ``undecided`` boxes (the numerical
        ``nonsliding`` ones too) are neither: the border of the region sliding
        within ``max_iter``.  ``border="words"`` (the default before): each word
        its own class (``sliding`` boxes, with several possible words, count as
        undecided there), ``no_sliding`` and ``no_slide_within`` together "not
        sliding": the union of all borders.

        ``lower``: s-boxes holding proven points of two classes (a segment
        between them, inside the s-box, crosses the border): points of proven
        boxes, and with ``witnesses`` (the default for ``border="sliding"``; not
        offered for ``"words"``) proven points inside the undecided boxes, each
        certified as a degenerate box and re-verified by the independent checker
        (:mod:`stairbounce.structure.witnesses`: only those the counts need are
        proven; ``df.attrs["witnesses"]`` says how many, ``df.attrs["witnesses_tried"]``
        how many were certified).  ``upper``:
        s-boxes whose closure meets an undecided box, or holding two classes
        (two proven boxes of different classes never touch, so every border
        point lies in an undecided box).  ``slope_lo, slope_hi``: the bracket
        on the finite-scale box-counting slope ``log2(N(s_k)/N(s_{k-1}))``
        between this scale and the one before: ``inf`` where the lower count
        of the scale before is 0 (no upper bound), ``-inf`` where this one's is
        (no lower bound); :func:`slope_text` says so in words.

        The counts are integers computed from the boxes; they are proven when the
        boxes are (:meth:`perimeter_bracket` runs the independent checker
        ``sb.verify`` and says whether it passed).  An atlas whose boxes are not
        its window's quadtree, or do not cover the window (an uncovered part may
        hold the border, so no upper count would hold), is refused (ValueError).

        What it does not prove: the border of the region sliding *at all* (the
        limit ``max_iter -> infinity``), nor the dimension (the limit of small
        scales): the bounds hold at the scales listed.
        """
        if witnesses is None:
            witnesses = border == "sliding"
        if witnesses not in (True, False):
            raise ValueError(f"witnesses must be True, False or None, got {witnesses!r}")
        if witnesses and border != "sliding":
            raise ValueError("witnesses: proven points are offered for border='sliding' only (a point's word "
                             "class would need its word)")
        book = self._book()  # refuses boxes that are not the window's quadtree, before the work
        if not book.complete:
            raise ValueError("border_box_counts: the boxes do not cover the window (sb.verify says how much is "
                             "uncovered): an uncovered part may hold the border, so no upper count is proven")
        ds = self.boxes
        depth = counted_depth(ds.attrs)  # the finest scale counted (focus.py: a refined store's focus)
        level = ds["level"].values.astype(np.int64)
        ii = ds["i"].values
        jj = ds["j"].values
        st = ds["status"].values
        cls = _border_classes(st, ds["word"].values, border)
        n_wit = tried = 0
        if witnesses:
            from .witnesses import witness_rows

            # cls + 1: witness_rows' classes (-1 undecided, 0 not sliding, 1 sliding)
            wi, wj, wc, _, _, tried = witness_rows(self.window, depth, self.max_iter, level, ii, jj, cls + 1)
            n_wit = wi.size
            wcls = wc - 1  # 1 sliding -> class 0, 0 not sliding -> -1
        rows = []
        for k in range(depth + 1):
            n = 1 << k
            fine = level >= k
            sh = level[fine] - k
            ci, cj = ii[fine] >> sh, jj[fine] >> sh
            cc = cls[fine]
            proven = cc != -2
            code = ci[proven] * n + cj[proven]
            pcls = cc[proven]
            if n_wit:
                ws = depth - k
                code = np.concatenate([code, (wi >> ws) * n + (wj >> ws)])
                pcls = np.concatenate([pcls, wcls])
            pairs = np.unique(np.stack([code, pcls]), axis=1) if code.size else np.zeros((2, 0), np.int64)
            cells, cnt = np.unique(pairs[0], return_counts=True)
            two = cells[cnt >= 2]
            touched = [two]
            und = ~proven
            if und.any():
                ui, uj, ush = ii[fine][und], jj[fine][und], sh[und]
                m = (np.int64(1) << ush) - 1
                ci_u, cj_u = ci[und], cj[und]
                left, right = (ui & m) == 0, (ui & m) == m
                down, up = (uj & m) == 0, (uj & m) == m
                for di, dmask in ((-1, left), (0, None), (1, right)):
                    for dj, emask in ((-1, down), (0, None), (1, up)):
                        sel = np.ones(ci_u.size, bool)
                        if dmask is not None:
                            sel &= dmask
                        if emask is not None:
                            sel &= emask
                        a, b = ci_u[sel] + di, cj_u[sel] + dj
                        ok = (a >= 0) & (a < n) & (b >= 0) & (b < n)
                        touched.append(a[ok] * n + b[ok])
            coarse = (level < k) & (st == K.UNDECIDED)
            for b in np.flatnonzero(coarse):
                f = 1 << (k - level[b])
                a0, a1 = max(ii[b] * f - 1, 0), min((ii[b] + 1) * f, n - 1)
                b0, b1 = max(jj[b] * f - 1, 0), min((jj[b] + 1) * f, n - 1)
                ga, gb = np.meshgrid(np.arange(a0, a1 + 1), np.arange(b0, b1 + 1))
                touched.append((ga * n + gb).ravel())
            upper = np.unique(np.concatenate(touched)).size
            (e_lo, e_hi), (u_lo, u_hi) = self.window
            rows.append({"k": k, "size_e": (e_hi - e_lo) / n, "size_u": (u_hi - u_lo) / n,
                         "lower": int(two.size), "upper": int(upper)})
        df = _counts_frame(rows, book.of, border)
        df.attrs["witnesses"], df.attrs["witnesses_tried"] = int(n_wit), int(tried)
        return df

    def slope_bracket(self, k1, k2, border="sliding"):
        """slope_bracket(k1, k2, border="sliding") -> (lo, hi): proven bracket on the
        box-counting slope ``log2(N(s_k2)/N(s_k1)) / (k2 - k1)`` between two scales
        of the border :meth:`border_box_counts` counts; ``hi`` is ``inf`` when the
        lower count at ``k1`` is 0 (no upper bound), ``lo`` is ``-inf`` when the one
        at ``k2`` is (no lower bound)."""
        k1 = check_count("k1", k1, 0, counted_depth(self.boxes.attrs))
        k2 = check_count("k2", k2, k1 + 1, counted_depth(self.boxes.attrs))
        df = self.border_box_counts(border)
        return self._slope_between(df, k1, k2)

    @staticmethod
    def _slope_between(df, k1, k2):
        L, U = df["lower"].to_numpy(float), df["upper"].to_numpy(float)
        lo, hi = _slope_bounds(L[[k1, k2]], U[[k1, k2]], k2 - k1)
        return float(lo[1]), float(hi[1])

    def perimeter_bracket(self, k1=None, k2=None, *, verify=True):
        """perimeter_bracket(k1=None, k2=None, *, verify=True) -> dict: the proven
        box counts of the paper's perimeter (:meth:`border_box_counts` with
        ``border="sliding"``) at the scales ``k1 .. k2`` (default ``min(3, depth - 1)
        .. depth``) and the slope brackets, with their basis.

        Keys: ``k1``, ``k2``, ``k`` (the scales), ``lower``, ``upper`` (lists of
        ints); ``slope`` ``(lo, hi)`` between ``k1`` and ``k2`` (``inf``/``-inf``
        where a zero lower count leaves an end open) and ``slope_text``;
        ``finite``: ``(a, b, lo, hi)``, the narrowest bracket between two scales
        ``k1 <= a < b <= k2`` whose lower counts are both > 0 (both ends finite), or
        None, and ``finite_text``; ``across``: ``(a, b, lo, hi)`` between the
        coarsest and the finest of those scales, or None (what a numerical dimension
        is compared with: :func:`slope_verdict`); ``depth``, ``max_iter``; ``verified`` (True when the
        independent checker ``sb.verify`` passed every box and the boxes cover
        the window, False when it rejected some, None with ``verify=False``);
        ``basis`` ``"proven"`` only when verified, else ``"numerical"``, with
        ``proof`` (by what, or why not) and ``not_proven`` (what it does not prove).
        """
        if verify not in (True, False):
            raise ValueError(f"verify must be True or False, got {verify!r}")
        k1, k2 = _scales(k1, k2, counted_depth(self.boxes.attrs))
        df = self.border_box_counts("sliding")
        verdict = None
        if verify:
            from .verdict import verify as check

            verdict = check(self)
        return perimeter_result(df, k1, k2, self.depth, self.max_iter, verdict, self.boxes.attrs.get("focus"))

    # -- files -------------------------------------------------------------

    def save(self, path, overwrite=False):
        """save(path, overwrite=False) -> None: write the atlas to ``.nc`` (netCDF4),
        ``.zarr`` or ``.geojson`` (:meth:`geojson`), atomically
        (:func:`stairbounce._io.atomic_path`)."""
        import json

        from .._io import atomic_path, check_output, suffix_of, write_shielded
        from .tiling import unique_inverse

        suffix = suffix_of(path, ATLAS_SUFFIXES)   # case ignored: the CLI's rule, checked first
        check_output(path, overwrite)
        if suffix == ".geojson":
            text = json.dumps(self.geojson(), allow_nan=False)
            with atomic_path(path, overwrite=overwrite) as tmp:
                tmp.write_text(text)
            return
        ds = _with_cf_attributes(self.boxes)
        ds.attrs = {k: (list(v) if isinstance(v, tuple) else v) for k, v in ds.attrs.items()}
        with atomic_path(path, overwrite=overwrite) as tmp:
            if suffix == ".zarr":
                # Zarr v3 specifies no string type: each text column as codes into a list kept in attrs
                for k in ("word", "reason"):
                    names, codes = unique_inverse(ds[k].values)
                    ds = ds.drop_vars(k).assign({f"{k}_code": ("box", codes.astype(np.int32))})
                    ds[f"{k}_code"].attrs["long_name"] = _CF[f"{k}_code"][0]
                    ds.attrs[f"{k}_names"] = [str(x) for x in names]
                write_shielded(lambda: ds.to_zarr(tmp, mode="w", consolidated=False), tmp)
            else:
                enc = {k: {"zlib": True, "complevel": 4} for k in ds.data_vars if ds[k].dtype.kind not in "UO"}
                write_shielded(lambda: _to_netcdf_in_slices(ds, tmp, enc), tmp)

    @classmethod
    def load(cls, path):
        """load(path) -> CertifiedAtlas: read an atlas written by :meth:`save` (.nc or .zarr)."""
        from .certificate import decode_atlas, read_atlas_file

        ds = read_atlas_file(path)
        if ds.attrs.get("kind") != "stairbounce certified atlas":
            raise ValueError(f"{path} is not a certified atlas written by stairbounce")
        _check_atlas_variables(ds, path)
        ds = decode_atlas(ds)
        for k in ("e_range", "u_range"):
            ds.attrs[k] = [float(x) for x in np.atleast_1d(ds.attrs[k])]
        atlas = cls(ds)
        from .._io import checksum

        atlas._source = (str(path), checksum(path))   # named by the geojson view
        return atlas

    def geojson(self):
        """geojson() -> dict: a GeoJSON FeatureCollection (RFC 7946) in (e, u)
        coordinates: the proven boxes merged per word (valid polygons, by
        shapely's union, outer rings counter-clockwise and holes clockwise),
        and one feature each for ``no_sliding`` by Corollary 2.1 (``reason``
        null), ``no_sliding`` by a trapping region (``reason`` "trapping": the
        orbit of (1, 0) never slides there, a different theorem) and
        ``no_slide_within``; the undecided boxes are not drawn, their area
        (and by reason) is in the metadata.

        The top-level member ``metadata`` (a foreign member, as in the regions
        file): ``generator`` and ``version``, the window, depth, max_iter,
        ``proven`` (what each feature states), the area proven and undecided
        (``undecided_area``, ``undecided_by_reason``: float sums,
        numerical), and ``verify``: this file is a view, not a certificate
        (it holds no itineraries); for an atlas read by :meth:`load` it names
        that ``source`` file and its SHA-256 ``source_sha256`` and says how to
        re-verify it (``stairbounce certify --verify SOURCE``).
        """
        from shapely.geometry import box as shp_box
        from shapely.geometry import mapping
        from shapely.geometry.polygon import orient
        from shapely.ops import unary_union

        from .._version import __version__

        ds = self.boxes
        st = ds["status"].values
        words = ds["word"].values
        trapped = ds["reason"].values == "trapping"
        cols = [ds[k].values for k in ("e0", "u0", "e1", "u1")]
        area = _area(ds)
        groups = [(str(w), "word", None, (st == K.WORD) & (words == w)) for w in np.unique(words[st == K.WORD])]
        groups += [(None, "no_sliding", None, (st == K.NO_SLIDING) & ~trapped),
                   (None, "no_sliding", "trapping", (st == K.NO_SLIDING) & trapped),
                   (None, "no_slide_within", None, st == K.NO_SLIDE_WITHIN),
                   (None, "sliding", None, st == _SLIDING_STATUS)]
        features = []
        for word, status, reason, sel in groups:
            idx = np.flatnonzero(sel)
            if not idx.size:
                continue
            geom = unary_union([shp_box(cols[0][b], cols[1][b], cols[2][b], cols[3][b]) for b in idx])
            parts = [orient(p, 1.0) for p in getattr(geom, "geoms", [geom])]
            geom = parts[0] if len(parts) == 1 else type(geom)(parts)
            props = {"status": status, "word": word, "reason": reason, "boxes": int(idx.size),
                     "area": float(area[idx].sum())}
            features.append({"type": "Feature", "geometry": mapping(geom), "properties": props})
        (e_lo, e_hi), (u_lo, u_hi) = self.window
        window_area = float((e_hi - e_lo) * (u_hi - u_lo))
        book = self._book()
        und = st == K.UNDECIDED
        reasons = {str(r): float(area[und & (ds["reason"].values == r)].sum())
                   for r in np.unique(ds["reason"].values[und])}
        source = getattr(self, "_source", None)
        meta = {
            "generator": f"stairbounce {__version__} CertifiedAtlas.geojson",
            "version": __version__,
            "coordinates": "[e, u]: restitution coefficient and normalised horizontal speed "
                           "(not longitude and latitude; a GIS reads them as EPSG:4326 degrees: "
                           "ignore its areas' units)",
            "window": {"e": [e_lo, e_hi], "u": [u_lo, u_hi]}, "window_area": window_area,
            "depth": self.depth, "max_iter": self.max_iter,
            "proven": {
                "word": "every point of the box has the periodic sliding solution through (1, 0) "
                        "with this word (interval arithmetic)",
                "no_sliding": "no periodic sliding solution at any point (Corollary 2.1 over the box)",
                "no_sliding, reason trapping": "the orbit of (1, 0) never slides (a trapping region), "
                                               "so no periodic sliding solution",
                "no_slide_within": "the orbit of (1, 0) does not slide within max_iter steps",
                "sliding": "every point of the box has a periodic sliding solution through (1, 0), "
                           "its word one of a list (a class-level proof, certify(classes=True))",
            },
            "proven_area": float(area[~und].sum()),
            "undecided_area": float(area[und].sum()),
            "undecided_by_reason": reasons,
            "areas": "window_area, proven_area, undecided_area and the features' areas: float sums "
                     "of the boxes' areas (numerical); proven bounds [lower, upper], sums of the boxes' "
                     "exact areas rounded outward, in window_area_bounds, proven_area_bounds and "
                     "undecided_area_bounds",
            "window_area_bounds": list(book.window),
            "proven_area_bounds": list(book.area(~und)),
            "undecided_area_bounds": list(book.area(und)),
            "verify": ("a view, not a certificate: it holds no itineraries and cannot be re-verified; "
                       + (f"re-verify its source with: stairbounce certify --verify {source[0]}"
                          if source else "save the atlas as .nc or .zarr and re-verify that file with "
                                         "stairbounce certify --verify FILE")),
            "source": source[0] if source else None,
            "source_sha256": source[1] if source else None,
        }
        return {"type": "FeatureCollection", "metadata": meta, "features": features,
                "properties": {"e": [e_lo, e_hi], "u": [u_lo, u_hi], "depth": self.depth,
                               "max_iter": self.max_iter, "coordinates": "(e, u)"}}

    def __repr__(self):
        n = self.boxes.sizes["box"]
        try:
            f = self.fraction()
        except ValueError:
            return f"CertifiedAtlas({n} boxes, depth {self.depth}: not its window's quadtree, numbers refused)"
        parts = ", ".join(f"{k} {100 * v:.1f}%" for k, v in f.items())
        return f"CertifiedAtlas({n} boxes, depth {self.depth}: {parts})"
