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

Here: the bisection kernels (:func:`_bisect_pair`, :func:`_bisect_sliding_pair`,
the event of a pair, :func:`_first_difference`), :func:`border_points` and
:func:`word_table` over a scan, and the slices of both that the explorer and
the tiles share (:func:`border_point_slices`, :func:`word_table_slices`).
The itinerary and its margins are in :mod:`.itinerary`, the words of points in
:mod:`.words`.

Nothing here imports matplotlib, Typer or the web stack.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr
from numba import njit, prange

from .. import _validate as _v
from .._interrupt import halted
from ..model import SLIDING, _constants, _step
from .itinerary import (
    CHATTER,
    EDGE,
    GRAZE,
    KINDS,
    _check_max_iter,
    _event_margin,
    _follows,
    _impacts_from_rest,
)
from .slices import _work_blocks, grid_blocks  # noqa: F401  (grid_blocks: also reached here)
from .words import _word_groups, _word_text, _words

__all__ = ["border_points", "word_table"]


@njit(cache=True)
def _at(x, f, axis):
    """``(e, u)`` of the point at ``x`` along ``axis`` (0: e varies, 1: u) and
    ``f`` across it."""
    if axis == 0:
        return x, f
    return f, x


@njit(cache=True)
def _trial(x, f, axis, ref, pc, j, kind, index):
    """Follow the orbit of ``(1, 0)`` at ``x`` along ``ref[:pc]``.

    Returns ``(follows, dev, kdev, F, G)``: whether all ``pc`` impact numbers
    are ``ref``'s (the outcome of ``ref``); else ``dev``, the first step that
    differs, and its impact number ``kdev``.  ``F``: the margin of the event ``(kind, index)`` at step ``j``
    (NaN when the orbit deviates before step ``j``); ``G``: when the orbit
    deviates at step ``dev``, the margin there of the event that separates
    its impact number from ``ref``'s (NaN otherwise).
    """
    e, u = _at(x, f, axis)
    T, ratio = _constants(e, u)
    y, v = 1.0, 0.0
    F = math.nan
    for n in range(pc):
        if n == j - 1:
            F = _event_margin(y, v, e, T, ratio, kind, index)
        yn, vn, k = _step(y, v, e, T, ratio)
        if k != ref[n]:
            kd, idx = _event_of(ref[n], k)
            return False, n + 1, k, F, _event_margin(y, v, e, T, ratio, kd, idx)
        y, v = yn, vn
    return True, 0, 0, F, math.nan


@njit(cache=True)
def _event_of(ka, kb):
    """The event (kind, index) that separates impact numbers ``ka != kb`` of one step."""
    if ka == SLIDING or kb == SLIDING:
        return CHATTER, 0
    if min(ka, kb) == 0:
        return GRAZE, 1
    return EDGE, max(ka, kb)


@njit(cache=True)
def _shrink_secant(xc, xo, f, axis, ref, pc):
    """Shrink the bracket ``[xc, xo]`` (``xc`` has the outcome ``ref``, ``xo``
    another one) to adjacent floats.

    Every trial point is decided by the exact outcome test, as in bisection;
    only its place differs: where the first step ``j`` at which ``xo``
    deviates from ``ref`` and its event are known at both ends, the trial is
    the secant root of the event's margin (Illinois: the margin of an end kept
    twice is halved), a bisection otherwise, and whenever two trials in a row
    shrank the bracket by less than half.  The margin is smooth along the
    bracket while the two ends share their first ``j - 1`` impact numbers, so
    this converges superlinearly; the bisection steps bound the work by about
    twice plain bisection.
    """
    _, j, ko, _, Fo = _trial(xo, f, axis, ref, pc, 0, 0, 0)
    kind, index = _event_of(ref[j - 1], ko)
    Fc = _trial(xc, f, axis, ref, pc, j, kind, index)[3]
    trials = 2
    steps = j + pc
    slow = 0
    last = 0  # which end moved last: 1 c, -1 o
    while True:
        width = abs(xo - xc)
        m = 0.5 * (xc + xo)
        if m == xc or m == xo:
            break
        if slow < 2 and math.isfinite(Fc) and math.isfinite(Fo) and Fc != Fo and (Fc >= 0.0) != (Fo >= 0.0):
            s = xc - Fc * (xo - xc) / (Fo - Fc)
            if min(xc, xo) < s < max(xc, xo):
                m = s
        follows, dev, kdev, F, G = _trial(m, f, axis, ref, pc, j, kind, index)
        trials += 1
        steps += pc if follows else dev
        if follows:
            xc, Fc = m, F
            if last == 1:
                Fo *= 0.5
            last = 1
        else:
            xo = m
            if dev == j:
                Fo = F
            else:  # a border of an earlier step: its event, at both ends
                j = dev
                kind, index = _event_of(ref[j - 1], kdev)
                Fo = G
                Fc = _trial(xc, f, axis, ref, pc, j, kind, index)[3]
                trials += 1
                steps += pc
            if last == -1:
                Fc *= 0.5
            last = -1
        slow = slow + 1 if abs(xo - xc) > 0.5 * width else 0
    return xc, xo, trials, steps


@njit(cache=True)
def _bisect_pair(xa, xb, f, axis, pa, pb, max_iter, ref, out, halt, secant):
    """One pair of neighbouring pixels at ``xa``, ``xb`` along ``axis`` (the
    other coordinate ``f``), with the periods ``pa``, ``pb`` of their words
    (0: no slide within max_iter).

    Returns False when the two have the same outcome.  Otherwise bisects to
    adjacent floats and writes into ``out`` (float64[11]): the low end of the
    bracket, its width, the step j, the kind code, the event index, the impact
    numbers at step j on the low and high side, the period of the low and high
    side (0: none within max_iter), and for the benchmarks the outcome tests
    (trial points) and the map steps they took.

    The reference end ``c`` is a sliding one (the shorter period): a point has
    its outcome exactly when its first ``p_c`` impact numbers are ``c``'s, so
    every bisection step costs at most ``p_c`` map steps; the other end keeps
    a different outcome.  The bracket ``[c, o]`` always has different outcomes
    at its ends, so it ends on a border.  ``secant``: the trial points are
    placed by :func:`_shrink_secant` (same invariant, fewer steps); otherwise
    at the midpoints (plain bisection).
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
    if pa != 0 and pb != 0 and pa == pb and _follows(eo, uo, ref, pc)[0]:
        return False
    if secant:
        xc, xo, trials, steps = _shrink_secant(xc, xo, f, axis, ref, pc)
    else:
        trials = steps = 0
        while True:
            m = 0.5 * (xc + xo)
            if m == xc or m == xo:
                break
            em, um = _at(m, f, axis)
            follows, n = _follows(em, um, ref, pc)
            trials += 1
            steps += n
            if follows:
                xc = m
            else:
                xo = m
    j, kc, ko, yo, vo = _first_difference(xc, xo, f, axis, pc)
    # the other end's outcome: its period, or 0 when it does not slide within max_iter
    po = 0
    if ko == SLIDING:
        po = j
    else:
        eo, uo = _at(xo, f, axis)
        To, ro = _constants(eo, uo)
        for n in range(j, max_iter):
            if (n & 0xFFFF) == 0 and halted(halt):  # Ctrl-C on a long max_iter
                break
            yo, vo, k = _step(yo, vo, eo, To, ro)
            if k == SLIDING:
                po = n + 1
                break
    _write_point(out, xc, xo, j, kc, ko, pc, po, trials, steps)
    return True


@njit(cache=True)
def _first_difference(xc, xo, f, axis, pc):
    """Follow the orbits of ``(1, 0)`` at both ends (``xc`` slides at step
    ``pc``, ``xo`` has another outcome) to the first step ``j`` whose impact
    numbers ``kc``, ``ko`` differ; returns ``(j, kc, ko, y, v)`` with the
    state of ``xo`` after step ``j``."""
    ec, uc = _at(xc, f, axis)
    eo, uo = _at(xo, f, axis)
    Tc, rc = _constants(ec, uc)
    To, ro = _constants(eo, uo)
    yc, vc, yo, vo = 1.0, 0.0, 1.0, 0.0
    kc = ko = 0
    for n in range(pc):
        yc, vc, kc = _step(yc, vc, ec, Tc, rc)
        yo, vo, ko = _step(yo, vo, eo, To, ro)
        if kc != ko:
            return n + 1, kc, ko, yo, vo
    return 0, kc, ko, yo, vo


@njit(cache=True)
def _write_point(out, xc, xo, j, kc, ko, pc, po, trials, steps):
    """One row of the border kernels (layout in :func:`_bisect_pair`), the
    sides ordered low/high along the axis."""
    kind, index = _event_of(kc, ko)
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
    out[9] = trials
    out[10] = steps


_OUT = 11

# what a kernel call locates: word borders (trial points at the secant root, or
# plain midpoints), or the border of the sliding region (midpoints)
_WORD, _WORD_BISECT, _SLIDING = 0, 1, 2


@njit(cache=True)
def _slide_period(e, u, max_iter, halt):
    """The period of the orbit of ``(1, 0)`` (steps up to and including its
    slide), 0 when it does not slide within ``max_iter`` steps (or once
    ``halt[0]`` is set, read every 2**16 steps)."""
    T, ratio = _constants(e, u)
    y, v = 1.0, 0.0
    for n in range(max_iter):
        if (n & 0xFFFF) == 0xFFFF and halted(halt):
            return 0
        y, v, k = _step(y, v, e, T, ratio)
        if k == SLIDING:
            return n + 1
    return 0


@njit(cache=True)
def _bisect_sliding_pair(xa, xb, f, axis, pa, pb, max_iter, out, halt):
    """A pair of pixels of which exactly one slides within ``max_iter``:
    bisected with the outcome "slides within max_iter" (not the word), so it
    ends on the border of the sliding region.  Writes ``out`` as
    :func:`_bisect_pair` does; returns False for any other pair."""
    if (pa == 0) == (pb == 0):
        return False
    if pa != 0:
        xc, xo, pc = xa, xb, pa
    else:
        xc, xo, pc = xb, xa, pb
    trials = steps = 0
    while True:
        m = 0.5 * (xc + xo)
        if m == xc or m == xo:
            break
        em, um = _at(m, f, axis)
        pm = _slide_period(em, um, max_iter, halt)
        trials += 1
        steps += pm if pm else max_iter
        if pm:
            xc, pc = m, pm
        else:
            xo = m
    _write_sliding_point(out, xc, xo, f, axis, pc, trials, steps)
    return True


@njit(cache=True)
def _write_sliding_point(out, xc, xo, f, axis, pc, trials, steps):
    """The row of a bisected crossing of the sliding region's border: the first
    step where its ends differ (:func:`_first_difference`), the other end not sliding."""
    j, kc, ko, _, _ = _first_difference(xc, xo, f, axis, pc)
    _write_point(out, xc, xo, j, kc, ko, pc, 0, trials, steps)


@njit(cache=True, parallel=True, nogil=True)
def _border_kernel(es, us, period, a_idx, b_idx, axis, max_iter, ref_len, method, found, out, halt):
    """Pairs ``(a_idx[p], b_idx[p])`` of 4-neighbouring pixels (flat row-major
    indices of the ``n_u x n_e`` grid ``us x es``; ``axis[p]`` 0 along e, 1 along
    u), each bisected by :func:`_bisect_pair` (``method`` ``_WORD`` or
    ``_WORD_BISECT``) or :func:`_bisect_sliding_pair` (``_SLIDING``) into
    ``out[p]``; ``found[p]`` says whether the outcomes differ.  Pairs are independent: the answers do not
    depend on the thread count or on which pairs are computed together.  Returns
    early once ``halt[0]`` is set (the outputs are then incomplete)."""
    ne = es.shape[0]
    npair = a_idx.shape[0]
    for p in prange(npair):
        if halted(halt):
            continue
        a = a_idx[p]
        b = b_idx[p]
        if axis[p] == 0:
            xa, xb, f = es[a % ne], es[b % ne], us[a // ne]
        else:
            xa, xb, f = us[a // ne], us[b // ne], es[a % ne]
        if method == _SLIDING:
            found[p] = _bisect_sliding_pair(xa, xb, f, axis[p], period[a], period[b], max_iter,
                                            out[p], halt)
        else:
            ref = np.empty(ref_len, np.int64)
            found[p] = _bisect_pair(xa, xb, f, axis[p], period[a], period[b], max_iter, ref,
                                    out[p], halt, method == _WORD)

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
    from ..plane import _coords

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


def _pairs(period, n_u, n_e, sliding=False):
    """Flat indices ``(a, b)`` and axis of the 4-neighbour pairs where at least
    one pixel slides (``sliding``: exactly one), in the order of ``a`` then
    axis (e before u)."""
    idx = np.arange(n_u * n_e, dtype=np.int64).reshape(n_u, n_e)
    s = period.reshape(n_u, n_e) != 0
    if sliding:
        ah = idx[:, :-1][s[:, :-1] != s[:, 1:]]
        av = idx[:-1, :][s[:-1, :] != s[1:, :]]
    else:
        ah = idx[:, :-1][s[:, :-1] | s[:, 1:]]
        av = idx[:-1, :][s[:-1, :] | s[1:, :]]
    a = np.concatenate([ah, av])
    axis = np.concatenate([np.zeros(ah.size, np.int64), np.ones(av.size, np.int64)])
    order = np.argsort(2 * a + axis, kind="stable")
    a, axis = a[order], axis[order]
    b = np.where(axis == 0, a + 1, a + n_e)
    return a, b, axis


def _run_pairs(es, us, period, a, b, axis, max_iter, progress, secant=True, sliding=False, lanes=True):
    """:func:`_border_kernel` over the pairs, in blocks (progress, Ctrl-C);
    with ``sliding``, ``lanes`` and at least ``_ROUND_LANES_MIN`` pairs
    :func:`_sliding_rounds` instead, the same rows (the tests compare them)."""
    from .._interrupt import run_kernel

    if sliding and lanes and a.size >= _ROUND_LANES_MIN:
        return _sliding_rounds(es, us, period, a, b, axis, max_iter, progress)
    n = a.size
    found = np.zeros(n, np.bool_)
    out = np.zeros((n, _OUT))
    ref_len = int(max(period.max(initial=0), 1))
    method = _SLIDING if sliding else (_WORD if secant else _WORD_BISECT)
    block = max(1, -(-n // 50)) if progress is not None else max(n, 1)
    if progress is not None:
        progress(0, n)
    for s in range(0, n, block):
        sl = slice(s, min(s + block, n))
        run_kernel(_border_kernel, es, us, period, a[sl], b[sl], axis[sl], max_iter, ref_len,
                   method, found[sl], out[sl])
        if progress is not None:
            progress(sl.stop, n)
    return found, out


# The rounds of _sliding_rounds decide their midpoints with the scan's kernel in
# units of at least this many points (plane._chunking), so that both threads
# work on a round of a few hundred midpoints.  Under _ROUND_LANES_MIN crossings
# the per-pair kernel is used, and a round with fewer midpoints (its last
# ones) runs one orbit per point (_slide_periods).  With 4-wide vectors and
# units of 512 the rounds lost below about 1000 crossings (x0.81-0.97 at
# 400-950); with the 8-wide ones (_simd) and units of 128 they win from about
# 150 (best of 3, two runs each: x1.1 at 153 crossings, x1.1-1.3 at 233,
# x1.5 at 401, x1.6 at 1001, x1.7-1.8 at 2860; benchmarks/README.md)
_ROUND_UNIT_MIN = 128
_ROUND_LANES_MIN = _ROUND_UNIT_MIN


def _sliding_rounds(es, us, period, a, b, axis, max_iter, progress):
    """``outcome="sliding"``: the rows of :func:`_bisect_sliding_pair` for every
    pair, its brackets halved together, one round at a time.

    Each round takes the midpoint of every bracket that still holds a float
    and decides all of them with the scan's kernel on points
    (:func:`stairbounce.plane._run`: LANES points in lockstep, pruned by
    Corollary 2.1, kept values of the closed form), whose status and period
    are those of :func:`_slide_period` bit for bit (the scan's tests against
    ``model._step`` point by point); a round of fewer than
    ``_ROUND_LANES_MIN`` midpoints calls :func:`_slide_period` itself.  The
    same midpoints in the same order, so the same brackets, trial and step
    counts.  Then :func:`_finish_sliding`
    finds each pair's first differing step, as the per-pair kernel does.
    ``progress(done, total)``: rounds, ``total`` from the widest bracket (a
    bracket of width ``w`` at ``x`` holds no float after about
    ``log2(w / ulp(x))`` halvings).
    """
    from .. import plane
    from .._interrupt import run_kernel

    n = a.size
    ne = es.size
    found = (period[a] == 0) != (period[b] == 0)
    along_e = axis == 0
    xa = np.where(along_e, es[a % ne], us[a // ne])
    xb = np.where(along_e, es[b % ne], us[b // ne])
    f = np.where(along_e, us[a // ne], es[a % ne])
    c_is_a = period[a] != 0
    xc = np.where(c_is_a, xa, xb)
    xo = np.where(c_is_a, xb, xa)
    pc = np.where(c_is_a, period[a], period[b]).astype(np.int64)
    trials = np.zeros(n, np.int64)
    steps = np.zeros(n, np.int64)
    live = found.copy()
    total = 1
    if live.any():
        w = np.abs(xo[live] - xc[live])
        total = int(np.ceil(np.log2(w / np.spacing(np.minimum(np.abs(xc[live]), np.abs(xo[live]))))).max()) + 2
    if progress is not None:
        progress(0, total)
    done = 0
    while True:
        m = 0.5 * (xc + xo)  # as the per-pair kernel computes it (IEEE, no fast-math there)
        live &= (m != xc) & (m != xo)
        idx = np.flatnonzero(live)
        if idx.size == 0:
            break
        mi = m[idx]
        ax = along_e[idx]
        em = np.where(ax, mi, f[idx])
        um = np.where(ax, f[idx], mi)
        pm = np.empty(idx.size, np.int64)
        if idx.size >= _ROUND_LANES_MIN:
            # in order of e, then u: the lanes run neighbouring points side by
            # side (about 1.5x faster than in the pairs' order; no answer depends on it)
            o = np.lexsort((um, em))
            res, _ = plane._run(em[o], um[o], False, max_iter, 1.0, 0.0, True, _ROUND_UNIT_MIN)
            pm[o] = np.where(res["status"] == 0, res["period"], 0)
        else:  # too few to keep the lanes of every thread busy: one orbit at a time
            run_kernel(_slide_periods, em, um, max_iter, pm)
        slides = pm != 0
        trials[idx] += 1
        steps[idx] += np.where(slides, pm, max_iter)
        xc[idx[slides]] = mi[slides]
        pc[idx[slides]] = pm[slides]
        xo[idx[~slides]] = mi[~slides]
        done += 1
        if progress is not None:
            progress(min(done, total - 1), total)
    out = np.zeros((n, _OUT))
    run_kernel(_finish_sliding, xc, xo, f, axis, pc, trials, steps, found, out)
    if progress is not None:
        progress(total, total)
    return found, out


@njit(cache=True, parallel=True, nogil=True)
def _slide_periods(e, u, max_iter, out, halt):
    """``out[i] = _slide_period(e[i], u[i], max_iter)``, the points in parallel."""
    for i in prange(e.shape[0]):
        out[i] = 0 if halted(halt) else _slide_period(e[i], u[i], max_iter, halt)


@njit(cache=True, parallel=True, nogil=True)
def _finish_sliding(xc, xo, f, axis, pc, trials, steps, found, out, halt):
    """The end of :func:`_bisect_sliding_pair` for the brackets of
    :func:`_sliding_rounds`: the first step where the two ends differ, the row."""
    for p in prange(xc.shape[0]):
        if not found[p] or halted(halt):
            continue
        _write_sliding_point(out[p], xc[p], xo[p], f[p], axis[p], pc[p], trials[p], steps[p])


def border_points(e=(0.0, 1.0, 500), u=(0.0, 1.5, 350), max_iter=1000, *, outcome="word",
                  progress=None, prove=False):
    """border_points(e=(e_min, e_max, n_e), u=(u_min, u_max, n_u), max_iter=1000, *, outcome="word", progress=None) -> xarray.Dataset

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
    - ``"edge"``: the ``index``-th impact (``index - 1`` <-> ``index``, index >= 2;
      where the bounces are shorter than the rounding of ``T``, as for small
      ``e`` after a few impacts, several impacts reach the edge within one ulp
      and the impact number jumps by more than one, up to ``index``);
    - ``"chatter"``: the accumulation point (finite <-> sliding on step j).

    ``outcome="sliding"`` takes "slides within max_iter" as the outcome
    instead of the word: only the pairs of which one pixel slides and the
    other does not are bisected, and every point lies on the border of the
    sliding region (between some word and "none within max_iter"), one per
    crossing.  With the word as the outcome such a pair may end on the border
    of another word met on the way (the sliding region's border is made of
    many words' borders).

    Kernel: pairs in parallel (numba ``prange``), each independent of the
    others, so the thread count and the tiling change no bit.  Each trial
    point is decided exactly (its whole word against the sliding end's, which
    follows the orbit at most that word's period); it is placed at the root
    of the secant through the two ends' margins of the event that separates
    them (the margins of :func:`itinerary`; a bisection step whenever that
    does not shrink the bracket by half), about 24 trial points per border
    point on the paper's grid instead of 46.  ``outcome="sliding"`` bisects
    at midpoints, a trial on the non-sliding side costing max_iter steps:
    from 128 crossings every bracket is halved in the same round, and each
    round's midpoints are decided together by the scan's kernel (LANES points
    in lockstep, pruned by Corollary 2.1), bit for bit the answers of the
    per-pair loop (x1.7-2.6 faster on the paper's grid and the Fig. 6 and 7
    windows, x1.1-1.6 at 150-1000 crossings, ``benchmarks/README.md``).

    Parameters
    ----------
    e, u : as in :func:`stairbounce.scan`, or ``e`` a scan Dataset (from
        ``(y0, v0) = (1, 0)``, its ``max_iter`` attribute used; ``u`` and
        ``max_iter`` are then ignored).
    max_iter : int >= 1, default 1000
    outcome : "word" (default) or "sliding"
        What two sides must differ in: the word, or whether they slide.
    progress : callable ``progress(done, total)``, optional
        Called for the scan's rows (as :func:`stairbounce.scan` does) and
        then for the pairs, in about 50 blocks each (``outcome="sliding"``:
        for the rounds of the bisection, about 50).

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
        (one side of the point does not slide within max_iter: the point is
        on the border of the sliding region), ``sliding_pair`` (one pixel of
        the pair slides, the other does not: the pair crosses that border),
        ``i_e``, ``i_u`` (the pixel of the pair with the smaller indices).  ``.to_dataframe()``
        gives the table as pandas.  With ``prove=True`` also ``proven``,
        ``reason`` and ``unproven_step``: whether the label is proven by
        intervals at both ends of the bracket (:func:`stairbounce.prove_labels`).

    Raises
    ------
    ValueError
        A window, size or max_iter out of range (naming it), a Dataset that
        is not a complete scan from (1, 0).
    """
    from .. import plane

    if progress is not None and not callable(progress):
        raise ValueError(f"progress must be None or a callable progress(done, total), got {progress!r}")
    _v.among("outcome", (outcome,), ("word", "sliding"))
    sliding = outcome == "sliding"
    if isinstance(e, xr.Dataset):
        es, us, period, max_iter = _grid_input(e)
        attrs = {k: e.attrs[k] for k in ("e_min", "e_max", "n_e", "u_min", "u_max", "n_u") if k in e.attrs}
    else:
        (e_min, e_max, n_e), (u_min, u_max, n_u) = plane._windows(e, u)
        max_iter = _check_max_iter(max_iter)
        ds = plane.scan(e=(e_min, e_max, n_e), u=(u_min, u_max, n_u), max_iter=max_iter,
                        progress=progress)
        es, us, period, _ = _grid_input(ds)
        attrs = dict(e_min=e_min, e_max=e_max, n_e=n_e, u_min=u_min, u_max=u_max, n_u=n_u)
    n_e, n_u = es.size, us.size
    a, b, axis = _pairs(period, n_u, n_e, sliding)
    found, out = _run_pairs(es, us, period, a, b, axis, max_iter, progress, sliding=sliding)
    pair = (period[a[found]] == 0) != (period[b[found]] == 0)
    table = _table(es, us, a[found], axis[found], out[found], max_iter,
                   {**attrs, "outcome": outcome}, pair)
    if prove:  # issue 36, item 6 (stairbounce.structure.labels)
        from .labels import prove_labels

        table = prove_labels(table)
    return table


def _table(es, us, a, axis, out, max_iter, attrs, pair=None):
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
        "sliding_pair": (dim, np.zeros(x.size, bool) if pair is None else pair,
                         {"long_name": "one pixel of the pair slides within max_iter, the other not"}),
        "i_e": (dim, i_e, {"long_name": "e index of the pair's first pixel"}),
        "i_u": (dim, i_u, {"long_name": "u index of the pair's first pixel"}),
    }
    return xr.Dataset(data, attrs={"title": "borders of the (e, u) plane to rounding",
                                   "max_iter": max_iter, "convention": _CONVENTION, **attrs})


# --------------------------------------------------------------------------- #
# The same answers in slices of bounded work (the explorer's shared worker)   #
# --------------------------------------------------------------------------- #

PAIR_TRIALS = 192
"""Most trial points one pair of :func:`border_points` takes (``outcome="word"``):
a bracket of two neighbouring pixel centres holds at most 2**55 floats (its
ends differ by a factor 3 at most), so it is halved at most about 56 times;
:func:`_shrink_secant` halves it at least every third trial (two slow secant
steps force a bisection) and adds a trial when the separating step changes.
Proven for the halvings; the resets are counted by the kernel (``out[:, 9]``)
and stay far below (tests/test_faults_round3.py checks them)."""


def pair_work(period, a, b, max_iter):
    """pair_work(period, a, b, max_iter) -> int64 array

    A bound on the map steps of each pair in :func:`_border_kernel`
    (:func:`border_points`, word outcome): ``PAIR_TRIALS p_c + max_iter``,
    where ``p_c`` is the shorter non-zero period of the two pixels (each
    trial follows the reference word at most ``p_c`` steps) and the other
    end's period is looked for up to ``max_iter`` steps.  0 for a pair of
    which neither pixel slides (not bisected).  Writing the point's two
    words out costs at most ``p_c + max_iter`` more.
    """
    pa, pb = period[a], period[b]
    pc = np.where(pa == 0, pb, np.where(pb == 0, pa, np.minimum(pa, pb))).astype(np.int64)
    return np.where(pc == 0, 0, PAIR_TRIALS * pc + int(max_iter))


def border_point_slices(es, us, period, max_iter, attrs, slice_work):
    """border_point_slices(es, us, period, max_iter, attrs, slice_work) -> generator, returning xarray.Dataset

    :func:`border_points` (``outcome="word"``) of the grid ``us x es`` whose
    pixels have the periods ``period`` (flat, row-major; 0: no slide within
    ``max_iter``), computed in slices: each ``next()`` bisects a block of
    consecutive pairs whose :func:`pair_work` and words (``p_c + max_iter``
    each) sum to at most ``slice_work`` (a single pair over it alone) and
    writes their rows; yields ``(pairs
    done, pairs)``.  The returned Dataset equals :func:`border_points` of
    the same scan (pairs are independent: which are computed together
    changes no bit); ``attrs``: its window attributes.
    """
    period = np.asarray(period, np.int64)
    a, b, axis = _pairs(period, us.size, es.size)
    parts = []
    work = pair_work(period, a, b, max_iter)
    work = np.where(work == 0, 0, work + (work - max_iter) // PAIR_TRIALS + max_iter)  # + p_c + max_iter
    for sl in _work_blocks(work, slice_work):
        found, out = _run_pairs(es, us, period, a[sl], b[sl], axis[sl], max_iter, None)
        aa, bb = a[sl][found], b[sl][found]
        parts.append(_table(es, us, aa, axis[sl][found], out[found], max_iter,
                            {**attrs, "outcome": "word"}, (period[aa] == 0) != (period[bb] == 0)))
        yield sl.stop, a.size
    if len(parts) == 1:
        return parts[0]
    return xr.concat(parts, dim="point", data_vars="all", combine_attrs="override")


def word_group_slices(e, u, periods, slice_work):
    """word_group_slices(e, u, periods, slice_work) -> generator, returning (ids, rows)

    :func:`_word_groups` in slices: blocks of consecutive points whose
    periods (the map steps of their words) sum to at most ``slice_work``,
    grouped block by block, then merged by comparing the words whole (the
    same groups; the ids may be numbered in another order).  Yields
    ``(points done, points)``.
    """
    periods = np.asarray(periods, np.int64)
    ids = np.full(e.size, -1, np.int64)
    rows, where = [], {}
    for sl in _work_blocks(periods, slice_work):
        local, local_rows = _word_groups(e[sl], u[sl], periods[sl])
        glob = np.empty(len(local_rows) + 1, np.int64)
        glob[-1] = -1
        for i, r in enumerate(local_rows):
            key = r.tobytes()
            if key not in where:
                where[key] = len(rows)
                rows.append(r)
            glob[i] = where[key]
        ids[sl] = glob[local]
        yield sl.stop, e.size
    return ids, rows


def staged(stage, gen):
    """Yield ``(stage, *value)`` for each value of the generator ``gen``;
    return its return value (``yield from`` with a label)."""
    while True:
        try:
            value = next(gen)
        except StopIteration as stop:
            return stop.value
        yield (stage, *value)


def word_table_slices(ds, points, slice_work):
    """word_table_slices(ds, points, slice_work) -> generator, returning xarray.Dataset

    :func:`word_table` of the scan Dataset ``ds`` in slices of at most
    ``slice_work`` map steps: the border points (unless ``points`` is given)
    by :func:`border_point_slices`, the words of the pixels by
    :func:`word_group_slices`; the rest costs no map steps.  Yields
    ``(stage, done, total)``, stage ``"points"`` or ``"words"``; returns the
    same Dataset as ``word_table(ds, points=points)``.
    """
    es, us, period, max_iter = _grid_input(ds)
    if points is None:
        attrs = {k: ds.attrs[k] for k in ("e_min", "e_max", "n_e", "u_min", "u_max", "n_u") if k in ds.attrs}
        points = yield from staged("points", border_point_slices(es, us, period, max_iter, attrs, slice_work))
    elif not (isinstance(points, xr.Dataset) and "kind" in points and "word_low" in points):
        raise ValueError("points must be a Dataset from border_points")
    E, U = np.meshgrid(es, us)
    E, U = E.ravel(), U.ravel()
    ids, rows = yield from staged("words", word_group_slices(E, U, period, slice_work))
    return _word_table_rows(ds, es, us, E, U, ids, rows, points, max_iter, False, False)


def _scan_input(e, u, max_iter, progress):
    """A scan Dataset from window arguments (as :func:`stairbounce.scan`) or the
    Dataset itself, with the window attributes to carry on."""
    from .. import plane

    if isinstance(e, xr.Dataset):
        _grid_input(e)  # checked here, once
        return e
    (e_min, e_max, n_e), (u_min, u_max, n_u) = plane._windows(e, u)
    max_iter = _check_max_iter(max_iter)
    return plane.scan(e=(e_min, e_max, n_e), u=(u_min, u_max, n_u), max_iter=max_iter,
                      progress=progress)


def word_table(e=(0.0, 1.0, 500), u=(0.0, 1.5, 350), max_iter=1000, *, points=None, progress=None,
               regions=False, prove=False):
    """word_table(e=(e_min, e_max, n_e), u=(u_min, u_max, n_u), max_iter=1000, *, points=None, progress=None) -> xarray.Dataset

    The distinct words of the periodic sliding solutions in a window, one row each,
    and the number of distinct words by period, N(p).

    Every pixel centre of the window (as :func:`stairbounce.scan`; or pass a
    scan Dataset as ``e``) gets the whole word of its periodic sliding
    solution (not only its length).  The border points (:func:`border_points`
    of the same pixels, or ``points`` when given) are counted per word on
    either side, by kind.

    Returns
    -------
    xarray.Dataset
        Dimension ``word`` (most pixels first, then by text): ``text`` (ASCII,
        ``(2, 0, 1, 0^inf)``), ``letters`` (number of letters = word length),
        ``period`` (steps per period = sum of the letters), ``impacts``
        (finite impacts per period), ``pixels``, ``area_fraction`` (of all the
        window's pixels), ``e_rep``, ``u_rep`` (a pixel centre of the word, the
        nearest to the centroid of its pixels), ``e_min``, ``e_max``,
        ``u_min``, ``u_max`` (the bounding box of its pixel centres),
        ``graze``, ``edge``, ``chatter`` (its border points by kind).
        Dimension ``p`` (the periods present): ``distinct_words`` = N(p).
        Attributes: ``pixels`` (all), ``sliding_pixels``, ``max_iter`` and the
        window.  With ``regions=True`` also ``traced_area``, ``traced_area_error``,
        ``components`` and ``complete`` per word, from
        :func:`stairbounce.window_regions` seeded at the larger side of the grid
        (NaN / 0 for a word it did not see).  With ``prove=True`` also
        ``proven`` per word (its point certificate re-verified by the
        independent checker at one of up to 8 of its pixel centres, which
        ``e_proven``, ``u_proven`` give; :mod:`stairbounce.structure.labels`),
        ``proven_words`` by ``p`` (a proven lower bound on N(p)) and the
        attribute ``proven_distinct_words``.

    Raises
    ------
    ValueError
        As :func:`border_points`.
    """
    if progress is not None and not callable(progress):
        raise ValueError(f"progress must be None or a callable progress(done, total), got {progress!r}")
    ds = _scan_input(e, u, max_iter, progress)
    es, us, period, max_iter = _grid_input(ds)
    if points is None:
        points = border_points(ds, progress=progress)
    elif not (isinstance(points, xr.Dataset) and "kind" in points and "word_low" in points):
        raise ValueError("points must be a Dataset from border_points")
    E, U = np.meshgrid(es, us)
    E, U = E.ravel(), U.ravel()
    ids, rows = _word_groups(E, U, period)
    return _word_table_rows(ds, es, us, E, U, ids, rows, points, max_iter, regions, prove)


def _word_table_rows(ds, es, us, E, U, ids, rows, points, max_iter, regions, prove):
    """The Dataset of :func:`word_table` once every pixel centre ``(E, U)``
    (flat) of the scan ``ds`` has its word: ``rows[ids[i]]`` (-1: none)."""
    nw = len(rows)
    texts = [_word_text(r) for r in rows]
    sliding = ids >= 0
    idx = ids[sliding]
    pix = np.bincount(idx, minlength=nw)
    Es, Us = E[sliding], U[sliding]

    def per_word(values, fn):
        out = np.full(nw, np.nan)
        order = np.argsort(idx, kind="stable")
        starts = np.concatenate([[0], np.cumsum(pix)])
        sv = values[order]
        for w in range(nw):
            out[w] = fn(sv[starts[w]:starts[w + 1]])
        return out, order, starts

    e_min, order, starts = per_word(Es, np.min)
    e_max = per_word(Es, np.max)[0]
    u_min = per_word(Us, np.min)[0]
    u_max = per_word(Us, np.max)[0]
    ce = np.bincount(idx, Es, minlength=nw) / np.maximum(pix, 1)
    cu = np.bincount(idx, Us, minlength=nw) / np.maximum(pix, 1)
    # a pixel of the word nearest its centroid, in units of the window's pixels
    de = (es[-1] - es[0]) / max(es.size - 1, 1) or 1.0
    du = (us[-1] - us[0]) / max(us.size - 1, 1) or 1.0
    e_rep = np.empty(nw)
    u_rep = np.empty(nw)
    for w in range(nw):
        sel = order[starts[w]:starts[w + 1]]
        d = ((Es[sel] - ce[w]) / de) ** 2 + ((Us[sel] - cu[w]) / du) ** 2
        k = sel[int(np.argmin(d))]
        e_rep[w], u_rep[w] = Es[k], Us[k]
    counts = {k: np.zeros(nw, np.int64) for k in KINDS}
    where = {t: i for i, t in enumerate(texts)}
    for side in ("word_low", "word_high"):
        for t, kind in zip(points[side].values, points["kind"].values):
            w = where.get(t)
            if w is not None:
                counts[kind][w] += 1
    letters = np.array([t.count(",") for t in texts], np.int64)  # "(a, b, 0^inf)": letters + 1 items
    periods = np.array([int(r.size) for r in rows], np.int64)
    impacts = np.array([int(np.sum(np.where(r > 0, r, 0))) for r in rows], np.int64)
    rank = np.lexsort((np.array(texts, dtype=object).astype(str), -pix)) if nw else np.zeros(0, np.int64)
    dim = ("word",)
    p_values, n_p = np.unique(periods, return_counts=True)
    data = {
        "text": (dim, np.array(texts, dtype=object)[rank], {"long_name": "the word (ASCII)"}),
        "letters": (dim, letters[rank], {"long_name": "letters (word length, impacts + 1)"}),
        "period": (dim, periods[rank], {"long_name": "steps per period (sum of the letters)"}),
        "impacts": (dim, impacts[rank], {"long_name": "finite impacts per period"}),
        "pixels": (dim, pix[rank], {"long_name": "pixel centres with this word"}),
        "area_fraction": (dim, pix[rank] / E.size, {"long_name": "share of the window's pixels"}),
        "e_rep": (dim, e_rep[rank], {"long_name": "e of a representative pixel centre"}),
        "u_rep": (dim, u_rep[rank], {"long_name": "u of a representative pixel centre"}),
        "e_min": (dim, e_min[rank], {"long_name": "bounding box of its pixel centres"}),
        "e_max": (dim, e_max[rank], {"long_name": "bounding box of its pixel centres"}),
        "u_min": (dim, u_min[rank], {"long_name": "bounding box of its pixel centres"}),
        "u_max": (dim, u_max[rank], {"long_name": "bounding box of its pixel centres"}),
        **{k: (dim, counts[k][rank], {"long_name": f"{k} border points with this word on a side"})
           for k in KINDS},
        "distinct_words": (("p",), n_p, {"long_name": "N(p): distinct words of period p"}),
    }
    attrs = {k: ds.attrs[k] for k in ("e_min", "e_max", "n_e", "u_min", "u_max", "n_u") if k in ds.attrs}
    tab = xr.Dataset(data, coords={"p": ("p", p_values, {"long_name": "period (steps)"})},
                     attrs={"title": "words of the periodic sliding solutions in a window",
                            "pixels": E.size, "sliding_pixels": int(sliding.sum()),
                            "max_iter": max_iter, **attrs})
    if prove:  # proven words (stairbounce.structure.labels)
        from .labels import word_proofs

        proven, e_p, u_p = (a[rank] for a in word_proofs(E, U, ids, rows))
        n_proven = np.array([int(np.sum(proven & (periods[rank] == p))) for p in p_values], np.int64)
        tab = tab.assign(
            proven=(dim, proven, {"long_name": "word proven at a pixel centre (point certificate)"}),
            e_proven=(dim, e_p, {"long_name": "e of the pixel centre where it is proven"}),
            u_proven=(dim, u_p, {"long_name": "u of the pixel centre where it is proven"}),
            proven_words=(("p",), n_proven, {"long_name": "proven distinct words of period p (<= N(p))"}))
        tab.attrs["proven_distinct_words"] = int(proven.sum())
    if regions:  # traced areas (stairbounce.regions)
        from .regions import traced_columns

        tab = traced_columns(tab)
    return tab
