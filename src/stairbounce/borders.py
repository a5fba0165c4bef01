"""The borders of the (e, u) plane, located to rounding and labelled by their event.

Along a fixed itinerary (the impact numbers ``k_1, k_2, ...`` of the steps from
the departure at ``(1, 0)``) the state after each step is a smooth closed-form
function of ``(e, u)`` (Prop. 2.3).  Two neighbouring regions of the plane are
therefore separated by a piece of a smooth curve on which one event of one step
``j`` happens exactly at the edge of that step (``T = 1/u``):

- ``graze``: the first contact falls on the edge (``k_j`` changes 0 <-> 1,
  ``t_1 = T``);
- ``edge``: the ``(k+1)``-th impact falls on the edge (``k_j`` changes
  k <-> k+1 with k >= 1, ``t_{k+1} = T``);
- ``chatter``: the accumulation point of the impacts falls on the edge
  (``k_j`` changes from finite to sliding, equality in (2.4)).

Every event is measured by a signed time margin, ``T - t_event``: the event
happens on the step (before or at its edge) exactly when the margin is >= 0, with
the arithmetic of :func:`stairbounce.model._step` (one source of truth), so the
margins' signs reproduce the impact numbers.

Nothing here imports matplotlib, Typer or the web stack.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr
from numba import njit, prange

from . import _validate as _v
from ._interrupt import halted
from .model import (
    _COUNTED_IMPACTS,
    SLIDING,
    _constants,
    _impact_time_log,
    _step,
    check_count,
    check_e,
    check_state,
    check_u,
)

__all__ = ["itinerary", "border_points"]

GRAZE, EDGE, CHATTER = 0, 1, 2
"""Event codes of the compiled functions (``kind`` argument of :func:`_margin`)."""
KINDS = ("graze", "edge", "chatter")
"""Event names, indexed by the codes above."""

# steps per call of the itinerary kernel: memory grows with the steps taken,
# not with max_iter, and Ctrl-C is seen between blocks
_BLOCK = 1 << 16


# --------------------------------------------------------------------------- #
# Compiled scalars                                                            #
# --------------------------------------------------------------------------- #


@njit(cache=True)
def _impact_time_at(v, s, e, index):
    """Time ``t_index`` of the ``index``-th impact (index >= 1) on a step
    entered with velocity ``v`` and first impact speed ``s``, as
    :func:`stairbounce.model._step` computes it: ``t_1 = v + s``, then
    ``t_{i+1} = t_i + 2 w_i``, ``w_1 = e s``, ``w_{i+1} = e w_i`` up to
    ``_COUNTED_IMPACTS``; past that, the closed form that
    :func:`stairbounce.model._step_closed` uses (eq. 2.2)."""
    if index <= _COUNTED_IMPACTS:
        t = v + s
        w = e * s
        for _ in range(index - 1):
            t = t + 2.0 * w
            w *= e
        return t
    log_e = math.log(e) if e > 0.0 else -math.inf
    return _impact_time_log(v, s, e, index, log_e)


@njit(cache=True)
def _event_margin(y, v, e, T, ratio, kind, index):
    """Signed time margin ``T - t_event`` of one event on a step entered at ``(y, v)``.

    ``kind``: ``GRAZE`` (the first contact ``t_1 = v + s``), ``EDGE`` (the
    ``index``-th impact, :func:`_impact_time_at`; index 1 is the first
    contact), ``CHATTER`` (the accumulation point ``t_inf = v + ratio s``,
    Prop. 2.1).  The event happens on the step exactly when the margin is >= 0:
    ``_step`` flies over iff ``t_1 > T``, slides iff ``v + ratio s <= T``, and
    has at least ``i`` impacts iff ``t_i <= T`` (float subtraction keeps the
    sign of a comparison, so the tests agree bit for bit).
    """
    s = math.sqrt(v * v + 2.0 * y)
    if kind == CHATTER:
        return T - (v + ratio * s)
    if kind == GRAZE:
        return T - (v + s)
    return T - _impact_time_at(v, s, e, index)


@njit(cache=True)
def _next_margin(y, v, e, T, k):
    """``T - t_{k+1}``: the margin of the impact after the last one on a step
    with ``k >= 0`` finite impacts (negative; NaN for a sliding step)."""
    if k == SLIDING:
        return math.nan
    s = math.sqrt(v * v + 2.0 * y)
    return T - _impact_time_at(v, s, e, k + 1)


@njit(cache=True)
def _itinerary_block(y, v, e, T, ratio, steps, ks, ys, vs, contact, nxt, accum):
    """Up to ``steps`` steps from ``(y, v)``, stopping after a slide.

    Fills, per step ``n`` (0-based), the entry state ``ys[n], vs[n]``, the
    margins of the first contact, of the next impact and of the accumulation
    point, and the impact number ``ks[n]`` of :func:`stairbounce.model._step`.
    Returns ``(filled, y, v, slid)``.
    """
    for n in range(steps):
        ys[n] = y
        vs[n] = v
        contact[n] = _event_margin(y, v, e, T, ratio, GRAZE, 1)
        accum[n] = _event_margin(y, v, e, T, ratio, CHATTER, 0)
        yn, vn, k = _step(y, v, e, T, ratio)
        ks[n] = k
        nxt[n] = _next_margin(y, v, e, T, k)
        y, v = yn, vn
        if k == SLIDING:
            return n + 1, y, v, True
    return steps, y, v, False


@njit(cache=True)
def _margin(e, u, j, kind, index, y0, v0, prefix):
    """Signed margin of event ``kind`` at step ``j`` (1 = the first step from
    ``(y0, v0)``) as a function of ``(e, u)``: ``F(e, u) = 0`` is the border arc.

    ``kind``: ``GRAZE`` (0), ``EDGE`` (1) with ``index`` the impact (its
    border separates ``index - 1`` from ``index`` impacts, ``index >= 2``), or
    ``CHATTER`` (2); see :func:`_event_margin`.  Steps ``1..j-1`` are iterated
    with :func:`stairbounce.model._step`; ``prefix`` (an int64 array) holds
    their expected impact numbers: where one differs (the point has left the
    arc's domain) or a step before ``j`` slides, the result is NaN.  An empty
    ``prefix`` checks only for slides.  >= 0: the event happens on step ``j``.
    """
    T, ratio = _constants(e, u)
    y, v = y0, v0
    for i in range(j - 1):
        y, v, k = _step(y, v, e, T, ratio)
        if k == SLIDING or (i < prefix.shape[0] and prefix[i] != k):
            return math.nan
    return _event_margin(y, v, e, T, ratio, kind, index)


# --------------------------------------------------------------------------- #
# The border kernel                                                           #
# --------------------------------------------------------------------------- #


@njit(cache=True)
def _impacts_from_rest(e, u, steps, ks):
    """Impact numbers of the orbit of ``(1, 0)`` into ``ks[:n]``, up to the first
    slide; returns ``n`` (0 when it does not slide within ``steps`` steps)."""
    T, ratio = _constants(e, u)
    y, v = 1.0, 0.0
    for n in range(steps):
        y, v, k = _step(y, v, e, T, ratio)
        ks[n] = k
        if k == SLIDING:
            return n + 1
    return 0


@njit(cache=True)
def _follows(e, u, ref, p):
    """Whether the orbit of ``(1, 0)`` at ``(e, u)`` has the impact numbers
    ``ref[:p]`` (the last one ``SLIDING``): the same outcome, word for word.
    Stops at the first step that differs."""
    T, ratio = _constants(e, u)
    y, v = 1.0, 0.0
    for n in range(p):
        y, v, k = _step(y, v, e, T, ratio)
        if k != ref[n]:
            return False
    return True


@njit(cache=True)
def _at(x, f, axis):
    """``(e, u)`` of the point at ``x`` along ``axis`` (0: e varies, 1: u) and
    ``f`` across it."""
    if axis == 0:
        return x, f
    return f, x


@njit(cache=True)
def _bisect_pair(xa, xb, f, axis, pa, pb, max_iter, ref, out, halt):
    """One pair of neighbouring pixels at ``xa``, ``xb`` along ``axis`` (the
    other coordinate ``f``), with the periods ``pa``, ``pb`` of their words
    (0: no slide within max_iter).

    Returns False when the two have the same outcome.  Otherwise bisects to
    adjacent floats and writes into ``out`` (float64[9]): the low end of the
    bracket, its width, the step j, the kind code, the event index, the impact
    numbers at step j on the low and high side, the period of the low and high
    side (0: none within max_iter).

    The reference end ``c`` is a sliding one (the shorter period): a point has
    its outcome exactly when its first ``p_c`` impact numbers are ``c``'s, so
    every bisection step costs at most ``p_c`` map steps; the other end keeps
    a different outcome.  The bracket ``[c, o]`` always has different outcomes
    at its ends, so it ends on a border.
    """
    if pa == 0 and pb == 0:
        return False
    if pa != 0 and (pb == 0 or pa <= pb):
        xc, xo, pc = xa, xb, pa
    else:
        xc, xo, pc = xb, xa, pb
    ec, uc = _at(xc, f, axis)
    _impacts_from_rest(ec, uc, pc, ref)
    eo, uo = _at(xo, f, axis)
    if pa != 0 and pb != 0 and pa == pb and _follows(eo, uo, ref, pc):
        return False
    while True:
        m = 0.5 * (xc + xo)
        if m == xc or m == xo:
            break
        em, um = _at(m, f, axis)
        if _follows(em, um, ref, pc):
            xc = m
        else:
            xo = m
    # the first step where the two ends differ, and the event there
    ec, uc = _at(xc, f, axis)
    eo, uo = _at(xo, f, axis)
    Tc, rc = _constants(ec, uc)
    To, ro = _constants(eo, uo)
    yc, vc, yo, vo = 1.0, 0.0, 1.0, 0.0
    j = 0
    kc = ko = 0
    for n in range(pc):
        yc, vc, kc = _step(yc, vc, ec, Tc, rc)
        yo, vo, ko = _step(yo, vo, eo, To, ro)
        if kc != ko:
            j = n + 1
            break
    # the other end's outcome: its period, or 0 when it does not slide within max_iter
    po = 0
    if ko == SLIDING:
        po = j
    else:
        for n in range(j, max_iter):
            if (n & 0xFFFF) == 0 and halted(halt):  # Ctrl-C on a long max_iter
                break
            yo, vo, k = _step(yo, vo, eo, To, ro)
            if k == SLIDING:
                po = n + 1
                break
    if kc == SLIDING or ko == SLIDING:
        kind, index = CHATTER, 0
    elif min(kc, ko) == 0:
        kind, index = GRAZE, 1
    else:
        kind, index = EDGE, max(kc, ko)
    low_is_c = xc < xo
    out[0] = min(xc, xo)
    out[1] = abs(xo - xc)
    out[2] = j
    out[3] = kind
    out[4] = index
    out[5] = kc if low_is_c else ko
    out[6] = ko if low_is_c else kc
    out[7] = pc if low_is_c else po
    out[8] = po if low_is_c else pc
    return True


_OUT = 9


@njit(cache=True, parallel=True, nogil=True)
def _border_kernel(es, us, period, a_idx, b_idx, axis, max_iter, ref_len, found, out, halt):
    """Pairs ``(a_idx[p], b_idx[p])`` of 4-neighbouring pixels (flat row-major
    indices of the ``n_u x n_e`` grid ``us x es``; ``axis[p]`` 0 along e, 1 along
    u), each bisected by :func:`_bisect_pair` into ``out[p]``; ``found[p]`` says
    whether the outcomes differ.  Pairs are independent: the answers do not
    depend on the thread count or on which pairs are computed together.  Returns
    early once ``halt[0]`` is set (the outputs are then incomplete)."""
    ne = es.shape[0]
    npair = a_idx.shape[0]
    for p in prange(npair):
        if halted(halt):
            continue
        a = a_idx[p]
        b = b_idx[p]
        ref = np.empty(ref_len, np.int64)
        if axis[p] == 0:
            xa, xb, f = es[a % ne], es[b % ne], us[a // ne]
        else:
            xa, xb, f = us[a // ne], us[b // ne], es[a % ne]
        found[p] = _bisect_pair(xa, xb, f, axis[p], period[a], period[b], max_iter, ref, out[p], halt)


# --------------------------------------------------------------------------- #
# Public API                                                                  #
# --------------------------------------------------------------------------- #


def _check_max_iter(max_iter):
    max_iter = check_count("max_iter", max_iter, 1)
    if max_iter > 2**31 - 1:
        raise ValueError(f"max_iter must be an integer in [1, 2**31 - 1], got {max_iter}")
    return max_iter


def itinerary(e, u, max_iter=1000, y0=1.0, v0=0.0):
    """itinerary(e, u, max_iter=1000, y0=1.0, v0=0.0) -> xarray.Dataset

    The impact numbers of the steps from ``(y0, v0)`` up to the first slide,
    with the signed time margins of the three events that can change them.

    Iterates :func:`stairbounce.model._step` (Prop. 2.3) until a step slides
    (that step included) or ``max_iter`` steps.  At every step, entered at
    ``(y, v)`` with ``T = 1/u`` and ``s = sqrt(v^2 + 2y)``, three margins
    ``T - t`` (time units; >= 0: the event happens on this step, at or before
    its edge; < 0: after it):

    - ``contact``: the first contact, ``t_1 = v + s``. The step has an impact
      (``impacts != 0``) iff ``contact >= 0``; where it crosses 0 a *graze*
      border.
    - ``next_impact``: the impact after the last one, ``t_{k+1}`` (eq. 2.2,
      as ``_step`` sums it); always < 0 on a step with ``k`` finite impacts
      (it equals ``contact`` when ``k = 0``), NaN on the sliding step; where
      it crosses 0 an *edge* border.
    - ``accumulation``: the accumulation point, ``t_inf = v + (1+e)/(1-e) s``
      (Prop. 2.1); the step slides (``impacts == SLIDING``) iff
      ``accumulation >= 0`` (test (2.4)); where it crosses 0 a *chatter*
      border.

    Returns
    -------
    xarray.Dataset
        Dimension ``step`` (coordinate 1, 2, ...: 1 is the first step after
        the start). Variables ``impacts`` (int64: 0, k >= 1 or ``SLIDING``),
        ``y``, ``v`` (the state entering the step), ``contact``,
        ``next_impact``, ``accumulation`` (float64 margins).  Attributes:
        ``e``, ``u``, ``max_iter``, ``y0``, ``v0`` and ``slid`` (1 when the
        last step slides, 0 when ``max_iter`` steps passed without a slide).

    Raises
    ------
    ValueError
        A parameter out of its range (naming it).
    """
    e = check_e(e)
    u = check_u(u)
    max_iter = _check_max_iter(max_iter)
    y0, v0 = check_state(y0, v0, "y0", "v0")
    T, ratio = _constants(e, u)
    names = ("impacts", "y", "v", "contact", "next_impact", "accumulation")
    parts = {k: [] for k in names}
    y, v, left, slid = y0, v0, max_iter, False
    while left > 0 and not slid:
        m = min(left, _BLOCK)
        _v.check_memory(f"an itinerary of {max_iter - left + m} steps", 48 * (max_iter - left + m))
        block = {k: np.empty(m, dtype=np.int64 if k == "impacts" else np.float64) for k in names}
        n, y, v, slid = _itinerary_block(y, v, e, T, ratio, m, *(block[k] for k in names))
        for k in names:
            parts[k].append(block[k][:n])
        left -= n
    data = {k: np.concatenate(parts[k]) for k in names}
    steps = np.arange(1, data["impacts"].size + 1, dtype=np.int64)
    desc = {
        "impacts": "impact number of the step (0 flies over, k >= 1, -1 = SLIDING)",
        "y": "height above the step's floor entering the step",
        "v": "vertical velocity entering the step",
        "contact": "T - t_1: margin of the first contact (>= 0: the step has an impact)",
        "next_impact": "T - t_(k+1): margin of the impact after the last one (< 0; NaN when sliding)",
        "accumulation": "T - t_inf: margin of the accumulation point (>= 0: the step slides)",
    }
    ds = xr.Dataset(
        {k: (("step",), data[k], {"long_name": desc[k]}) for k in names},
        coords={"step": ("step", steps, {"long_name": "step (1 = the first after the start)"})},
        attrs={"e": e, "u": u, "max_iter": max_iter, "y0": y0, "v0": v0, "slid": int(slid),
               "margins": "T - t_event in time units; >= 0: the event happens on the step"},
    )
    return ds


NONE_WORD = "none within max_iter"
"""The word given to a side whose orbit of ``(1, 0)`` does not slide within max_iter steps."""

_CONVENTION = (
    "one point per pair of 4-neighbouring pixel centres whose outcomes differ (the outcome is "
    "the whole word of the periodic sliding solution through (1, 0), or 'none within max_iter'), "
    "bisected along the pair's axis until the bracket [x, x + width] has no float inside; "
    "e, u: the low end of the bracket (the other coordinate is the pixels' own); low/high: the "
    "sides of smaller/larger coordinate along the axis; step: the first step (1 = the first after "
    "the departure at (1, 0)) whose impact numbers differ on the two sides; kind: graze (0 <-> 1 "
    "impacts, first contact t_1 = T), edge (k <-> k+1 impacts, k >= 1, t_index = T), chatter "
    "(finite <-> sliding, accumulation point t_inf = T); sliding_border: one side does not "
    "slide within max_iter (the border of the sliding region)"
)


def _grid_input(data):
    """Coordinates, status and period of a scan Dataset, checked."""
    for name in ("status", "period"):
        if name not in getattr(data, "data_vars", {}):
            raise ValueError(f"data must be a scan Dataset with a {name!r} variable (sb.scan)")
    if data.status.dims != ("u", "e"):
        raise ValueError(f"data must be a scan Dataset with dims ('u', 'e'), got {data.status.dims}")
    from .plane import _coords

    es = _coords("e", data.e.values)
    us = _coords("u", data.u.values)
    status = np.asarray(data.status.values)
    if not np.all((status == 0) | (status == 1)):
        raise ValueError("data has pixels that are not computed (status not 0 or 1): a missing tile?")
    y0, v0 = data.attrs.get("y0", 1.0), data.attrs.get("v0", 0.0)
    if y0 != 1.0 or v0 != 0.0:
        raise ValueError(f"data must be a scan from (y0, v0) = (1, 0), got ({y0}, {v0})")
    if "max_iter" not in data.attrs:
        raise ValueError("data must carry its max_iter attribute (a Dataset made by sb.scan)")
    max_iter = _check_max_iter(int(data.attrs["max_iter"]))
    period = np.where(status == 0, np.asarray(data.period.values), 0).astype(np.int64)
    return es, us, period.ravel(), max_iter


def _pairs(period, n_u, n_e):
    """Flat indices ``(a, b)`` and axis of the 4-neighbour pairs where at least
    one pixel slides, in the order of ``a`` then axis (e before u)."""
    idx = np.arange(n_u * n_e, dtype=np.int64).reshape(n_u, n_e)
    p = period.reshape(n_u, n_e)
    ah = idx[:, :-1][(p[:, :-1] != 0) | (p[:, 1:] != 0)]
    av = idx[:-1, :][(p[:-1, :] != 0) | (p[1:, :] != 0)]
    a = np.concatenate([ah, av])
    axis = np.concatenate([np.zeros(ah.size, np.int64), np.ones(av.size, np.int64)])
    order = np.argsort(2 * a + axis, kind="stable")
    a, axis = a[order], axis[order]
    b = np.where(axis == 0, a + 1, a + n_e)
    return a, b, axis


def _run_pairs(es, us, period, a, b, axis, max_iter, progress):
    """:func:`_border_kernel` over the pairs, in blocks (progress, Ctrl-C)."""
    from ._interrupt import run_kernel

    n = a.size
    found = np.zeros(n, np.bool_)
    out = np.zeros((n, _OUT))
    ref_len = int(max(period.max(initial=0), 1))
    block = max(1, -(-n // 50)) if progress is not None else max(n, 1)
    if progress is not None:
        progress(0, n)
    for s in range(0, n, block):
        sl = slice(s, min(s + block, n))
        run_kernel(_border_kernel, es, us, period, a[sl], b[sl], axis[sl], max_iter, ref_len,
                   found[sl], out[sl])
        if progress is not None:
            progress(sl.stop, n)
    return found, out


@njit(cache=True, parallel=True)
def _fill_impacts(e, u, periods, offsets, flat):
    """Impact numbers of the orbit of ``(1, 0)`` at each ``(e[i], u[i])`` into
    ``flat[offsets[i]:offsets[i] + periods[i]]`` (sides that slide only)."""
    for i in prange(e.shape[0]):
        p = periods[i]
        if p > 0:
            _impacts_from_rest(e[i], u[i], p, flat[offsets[i]:offsets[i] + p])


def _word_text(ks):
    """ASCII text of the word of one period from its impact numbers (the last
    ``SLIDING``): the text of ``symbolic.word_from_impacts(ks).format(ascii=True)``
    (a test compares them) without validating every letter again."""
    letters = []
    jump = 0
    for k in ks.tolist():
        jump += 1
        if k == 0:
            continue
        letters.append(str(jump))
        jump = 0
        if k > 1:
            letters.extend(["0"] * (k - 1))
    return "(" + ", ".join(letters) + ", 0^inf)"


def _words(e, u, periods):
    """Word text of each side: ASCII ``(2, 0, 1, 0^inf)`` or :data:`NONE_WORD`.

    The impact numbers of all sides are computed in one parallel pass; sides
    with the same period are grouped and their distinct rows formatted once
    (exact: rows are compared whole, no hashing)."""
    periods = np.asarray(periods, np.int64)
    texts = np.full(e.size, NONE_WORD, dtype=object)
    offsets = np.concatenate([[0], np.cumsum(periods)]).astype(np.int64)
    _v.check_memory(f"the words of {e.size} border sides", 8 * int(offsets[-1]))
    flat = np.empty(int(offsets[-1]), np.int64)
    _fill_impacts(np.ascontiguousarray(e), np.ascontiguousarray(u), periods, offsets, flat)
    for p in np.unique(periods[periods > 0]):
        where = np.flatnonzero(periods == p)
        rows = flat[offsets[where][:, None] + np.arange(p)]
        distinct, inverse = np.unique(rows, axis=0, return_inverse=True)
        names = np.array([_word_text(r) for r in distinct], dtype=object)
        texts[where] = names[inverse.ravel()]
    return texts


def border_points(e=(0.0, 1.0, 500), u=(0.0, 1.5, 350), max_iter=1000, *, progress=None):
    """border_points(e=(e_min, e_max, n_e), u=(u_min, u_max, n_u), max_iter=1000, *, progress=None) -> xarray.Dataset

    Every border between neighbouring pixels of a scan, located to rounding and
    labelled by the event that makes it.

    The window is that of :func:`stairbounce.scan` (the same pixel centres), or
    pass a scan Dataset as the first argument (``sb.border_points(ds)``; a tile
    cut out of a whole scan gives the same points as the whole scan on its
    pairs).  For every pair of 4-neighbouring pixel centres whose outcomes
    differ (the outcome is the whole word; "no slide within max_iter" is one
    outcome, so two pixels that never slide have no border between them) the
    segment between them is bisected until no float lies inside the bracket.
    At the end the two sides' itineraries (:func:`stairbounce.model._step`
    from ``(1, 0)``) agree up to a step ``j - 1`` and differ at step ``j`` by
    one event at the step's edge ``T = 1/u``:

    - ``"graze"``: the first contact (0 <-> 1 impacts on step j);
    - ``"edge"``: the ``index``-th impact (``index - 1`` <-> ``index``, index >= 2);
    - ``"chatter"``: the accumulation point (finite <-> sliding on step j).

    Kernel: pairs in parallel (numba ``prange``), each independent of the
    others, so the thread count and the tiling change no bit.  Each bisection
    step follows the orbit of the midpoint only as long as the sliding end's
    word, at most its period.

    Parameters
    ----------
    e, u : as in :func:`stairbounce.scan`, or ``e`` a scan Dataset (from
        ``(y0, v0) = (1, 0)``, its ``max_iter`` attribute used; ``u`` and
        ``max_iter`` are then ignored).
    max_iter : int >= 1, default 1000
    progress : callable ``progress(done, total)``, optional
        Called for the scan's rows (as :func:`stairbounce.scan` does) and
        then for the pairs, in about 50 blocks each.

    Returns
    -------
    xarray.Dataset
        Dimension ``point``, one per border crossing, in the order of the
        pairs' first pixel (row-major) then axis.  Variables: ``e``, ``u``
        (the low end of the final bracket along ``axis``), ``width`` (the
        bracket, about an ulp), ``axis`` (``"e"`` or ``"u"``: the coordinate
        bisected), ``kind``, ``step`` (j), ``index`` (the impact whose time
        equals T: 1 for graze, k + 1 for edge, 0 for chatter),
        ``impacts_low``, ``impacts_high`` (the impact numbers at step j on the
        sides of smaller and larger coordinate), ``word_low``, ``word_high``
        (ASCII words, or ``"none within max_iter"``), ``sliding_border``
        (one side does not slide within max_iter), ``i_e``, ``i_u`` (the
        pixel of the pair with the smaller indices).  ``.to_dataframe()``
        gives the table as pandas.

    Raises
    ------
    ValueError
        A window, size or max_iter out of range (naming it), a Dataset that
        is not a complete scan from (1, 0).
    """
    from . import plane

    if progress is not None and not callable(progress):
        raise ValueError(f"progress must be None or a callable progress(done, total), got {progress!r}")
    if isinstance(e, xr.Dataset):
        es, us, period, max_iter = _grid_input(e)
        attrs = {k: e.attrs[k] for k in ("e_min", "e_max", "n_e", "u_min", "u_max", "n_u") if k in e.attrs}
    else:
        e_min, e_max, n_e = plane._window("e", e, 0.0, 1.0, "[0, 1]")
        u_min, u_max, n_u = plane._window("u", u, 0.0, math.inf, "[0, inf)")
        max_iter = _check_max_iter(max_iter)
        ds = plane.scan(e=(e_min, e_max, n_e), u=(u_min, u_max, n_u), max_iter=max_iter,
                        progress=progress)
        es, us, period, _ = _grid_input(ds)
        attrs = dict(e_min=e_min, e_max=e_max, n_e=n_e, u_min=u_min, u_max=u_max, n_u=n_u)
    n_e, n_u = es.size, us.size
    a, b, axis = _pairs(period, n_u, n_e)
    found, out = _run_pairs(es, us, period, a, b, axis, max_iter, progress)
    return _table(es, us, a[found], axis[found], out[found], max_iter, attrs)


def _table(es, us, a, axis, out, max_iter, attrs):
    """The labelled Dataset of :func:`border_points` from the kernel's rows."""
    n_e = es.size
    i_e, i_u = a % n_e, a // n_e
    along_e = axis == 0
    x = out[:, 0]
    e = np.where(along_e, x, es[i_e])
    u = np.where(along_e, us[i_u], x)
    width = out[:, 1]
    e_high = np.where(along_e, x + width, e)
    u_high = np.where(along_e, u, x + width)
    kinds = np.array(KINDS, dtype=object)[out[:, 3].astype(np.int64)]
    p_low = out[:, 7].astype(np.int64)
    p_high = out[:, 8].astype(np.int64)
    dim = ("point",)
    data = {
        "e": (dim, e, {"long_name": "restitution coefficient e of the bracket's low end"}),
        "u": (dim, u, {"long_name": "horizontal speed u of the bracket's low end"}),
        "width": (dim, width, {"long_name": "width of the final bracket along axis"}),
        "axis": (dim, np.where(along_e, "e", "u").astype(object), {"long_name": "coordinate bisected"}),
        "kind": (dim, kinds, {"long_name": "event at the edge: graze, edge or chatter"}),
        "step": (dim, out[:, 2].astype(np.int64), {"long_name": "step j where the itineraries first differ"}),
        "index": (dim, out[:, 4].astype(np.int64),
                  {"long_name": "impact whose time equals T (1 graze, k+1 edge, 0 chatter)"}),
        "impacts_low": (dim, out[:, 5].astype(np.int64), {"long_name": "impact number at step j, low side"}),
        "impacts_high": (dim, out[:, 6].astype(np.int64), {"long_name": "impact number at step j, high side"}),
        "word_low": (dim, _words(e, u, p_low), {"long_name": "word on the low side"}),
        "word_high": (dim, _words(e_high, u_high, p_high), {"long_name": "word on the high side"}),
        "sliding_border": (dim, (p_low == 0) | (p_high == 0),
                           {"long_name": "one side does not slide within max_iter"}),
        "i_e": (dim, i_e, {"long_name": "e index of the pair's first pixel"}),
        "i_u": (dim, i_u, {"long_name": "u index of the pair's first pixel"}),
    }
    return xr.Dataset(data, attrs={"title": "borders of the (e, u) plane to rounding",
                                   "max_iter": max_iter, "convention": _CONVENTION, **attrs})
