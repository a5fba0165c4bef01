"""The (e, u) parameter plane: where periodic sliding solutions exist (Section 3).

For every point of a grid of restitution coefficients ``e`` and horizontal
speeds ``u`` the Poincare map (Prop. 2.3) is iterated until the sliding test
(2.3)/(2.4) holds; the word of the periodic sliding solution then gives the
colour of the point (the paper's Figures 3, 4 and 5).

The public wrappers validate, allocate and call a private numba kernel:

- ``_scan_fast``: the kernel used by :func:`scan`, :func:`scan_coords` and
  :func:`scan_points`, the map of :func:`stairbounce.model._step` (impacts
  counted along the geometric series, no log/pow below 8 impacts) evaluated
  on LANES pixels in lockstep, one unit of work per thread, each taking the
  plane's segments one at a time from a shared counter (so that cheap and
  expensive parts are shared evenly, and a thread's lanes idle only at its
  end).
- ``_scan_plain``: the plain kernel, one pixel at a time with the closed
  form :func:`stairbounce.model._step_closed`, ``prange`` over rows.  Speed
  is measured against the frozen copy of its first version,
  ``benchmarks/baseline_kernel.py``.

Pruning: above the curve of Corollary 2.1 no state with ``y >= 1`` slides,
so those pixels are status 1 whatever max_iter; ``_scan_fast`` stores that
without iterating (``prune=True``, the default), which leaves the arrays
unchanged bit for bit (``_never_slides`` has the proof, with its margin for
rounding).  On the paper's grid that is 98 % of the map steps.  The
Theorem 3.1 tongues are not short-cut: their answer, (n, 0^inf), costs
n <= 5 steps on the paper's plane, nothing to save.

Nothing here imports matplotlib, Typer or the web stack.
"""

from __future__ import annotations

import math
import os
import sys
import threading

import numpy as np
import xarray as xr
import numba
from numba import njit, prange

from ._version import __version__
from . import _validate as _v
from ._atomic import take_next
from ._interrupt import halted
from ._simd import prefer_wide_vectors
from .units import staircase_of, with_speed
from .model import (
    _COUNTED_IMPACTS,
    _MEMO_SIZE,
    _MEMO_SLOTS,
    SLIDING,
    _after_last_impact,
    _constants,
    _finite,
    _impacts_kept,
    _power_slot,
    _slide_or_steps_with,
    _step_closed,
    _step_closed_bounce,
    check_count,
    check_state,
)

__all__ = [
    "pixel_centres",
    "scan",
    "scan_coords",
    "scan_points",
    "prunable",
    "tongue_mask",
    "no_sliding_curve",
    "save",
    "load",
    "estimate_bytes",
    "estimate_points_bytes",
]

CONVENTION = (
    "word of the periodic sliding solution through (1, 0): jump numbers between "
    "consecutive impacts, the first counted from the departure (landing on the step "
    "right below is 1); a step with k >= 1 impacts gives its jump then k-1 zeros; the "
    "accumulation tail 0^inf is not a letter. word_length = impacts + 1; period = sum "
    "of letters = steps per period; jumps = non-zero letters; impacts = finite impacts "
    "per period. status 0: periodic sliding solution found, 1: no slide within max_iter "
    "steps (then word_length = jumps = period = impacts = 0). Coordinates are pixel "
    "centres; the image covers [e_min, e_max] x [u_min, u_max]."
)

# Output variables, their dtypes and meaning.  word_length and impacts can
# exceed 2**31 only for absurd max_iter near e = 1, but they are int64 anyway.
_FIELDS = {
    "status": (np.uint8, "0: periodic sliding solution found; 1: no slide within max_iter steps"),
    "word_length": (np.int64, "length of the word of the periodic sliding solution (impacts + 1)"),
    "jumps": (np.int32, "non-zero letters of the word (steps of a period with a landing)"),
    "period": (np.int32, "steps per period (sum of the letters)"),
    "impacts": (np.int64, "finite impacts per period (the accumulation not counted)"),
}
_BYTES_PER_PIXEL = sum(np.dtype(dt).itemsize for dt, _ in _FIELDS.values())
# Zarr's fill values, what a chunk that was never written (or was deleted) reads
# as: none is a value a scan can produce, so a missing chunk is never taken for
# data (status 0 means "found"; 0 is a valid word length where nothing is found).
FILL_VALUES = {"status": 255, "word_length": -1, "jumps": -1, "period": -1, "impacts": -1}


# --------------------------------------------------------------------------- #
# Kernels                                                                     #
# --------------------------------------------------------------------------- #


@njit(cache=True)
def _slide_or_steps_closed(y, v, e, T, ratio, max_steps):
    """:func:`stairbounce.model._slide_or_steps` with the plain closed form."""
    return _slide_or_steps_with(_step_closed, y, v, e, T, ratio, max_steps)


@njit(cache=True)
def _store(p, n, imp, jmp, status, word_length, jumps, period, impacts):
    """Write the answer of pixel ``p`` (flat index) into the flat outputs."""
    if n == 0:
        status[p] = 1
        word_length[p] = 0
        jumps[p] = 0
        period[p] = 0
        impacts[p] = 0
    else:
        status[p] = 0
        word_length[p] = imp + 1
        jumps[p] = jmp
        period[p] = n
        impacts[p] = imp


@njit(cache=True, parallel=True)
def _scan_plain(es, us, max_iter, y0, v0, status, word_length, jumps, period, impacts):
    """Baseline kernel: per pixel, the closed form of Prop. 2.2/2.3, prange over rows.

    Outputs are ``n_u x n_e`` arrays.  A transient from ``(y0, v0)`` up to its
    first slide, then one period from ``(1, 0)``; the transient is skipped
    when ``(y0, v0) = (1, 0)``.  No pruning: every pixel is iterated.
    """
    from_rest = y0 == 1.0 and v0 == 0.0
    for i in prange(us.shape[0]):
        for j in range(es.shape[0]):
            e = es[j]
            T, ratio = _constants(e, us[i])
            n = 1
            if not from_rest:
                n, _, _ = _slide_or_steps_closed(y0, v0, e, T, ratio, max_iter)
            imp = 0
            jmp = 0
            if n != 0:
                n, imp, jmp = _slide_or_steps_closed(1.0, 0.0, e, T, ratio, max_iter)
            _store(j, n, imp, jmp, status[i], word_length[i], jumps[i], period[i], impacts[i])


# The pruning test (_never_slides) wants T = 1/u below the Corollary 2.1
# threshold by a relative _PRUNE_MARGIN, plus _PRUNE_ROUNDING times the size of
# the numbers the map handles at that pixel: room for every rounding error.
_PRUNE_MARGIN = 2.0**-30
_PRUNE_ROUNDING = 2.0**-44


@njit(cache=True)
def _never_slides(e, T, ratio, energy0):
    """Whether Corollary 2.1 proves that no step of the scan slides at ``(e, u = 1/T)``.

    ``energy0 = y0 + v0^2`` of the start.  When True, iterating the pixel
    gives status 1 (no periodic sliding solution within any max_iter), and the
    kernels store that without iterating.

    The proof, redone for the computed test.  The kernels test (2.4),
    ``v + r s <= T`` with ``s = sqrt(v^2 + 2y)``, ``r = ratio``, the float
    ``(1+e)/(1-e)``.  Over all ``v``, ``v + r s`` is smallest at ``v = -s/r``,
    where it equals ``sqrt(2y (r^2-1))``.  Every state the map returns sits
    at an edge, ``y >= 1``; so no state passes the exact test when
    ``T < sqrt(2 (r^2-1))``, which for the exact ``r`` is
    ``u > (1-e)/(2 sqrt(2e))``: the paper's bound, strict.

    Equality: at ``u = (1-e)/(2 sqrt(2e))`` the state ``(1, -T/(r^2-1))``
    meets (2.4) with equality, which our convention counts as sliding
    (docs/design.md); the paper's "u >= ..." holds only for a strict test.
    So the curve itself is on the side that is iterated, never pruned.

    Rounding, on the safe side by a wide factor:

    - ``sqrt(2 (r-1)(r+1))``: ``r - 1`` is exact (``r >= 1``), the rest
      rounds by at most 3 eps (eps = 2**-53).
    - The computed ``v + r s`` is at least ``(v + r s)(1 - 5 eps r/(r-1))``
      (``v + r s >= (r-1) s`` bounds the cancellation).
    - A computed state can sit below the edge, ``y = 1 - delta``, by a few
      eps times the terms of the step, ``y + |v| T + T^2/2 + 1``.  Measured
      along orbits (``tests/test_prune.py``) these stay below a small
      multiple (< 16) of ``size = T^2 + (1/T^2 + 1 + y0 + v0^2)(r + r/(r-1))``:
      energy grows by one per step flown over (about ``2/T^2`` steps in a
      flight when ``T`` is small), impacts take a share ``1 - e^2`` of it
      (slowly when ``r`` is large).

    The test demands ``T`` smaller than the threshold by the relative
    ``_PRUNE_MARGIN + _PRUNE_ROUNDING * size``.  A height error ``delta`` is
    worth a relative change ``delta / 2`` of ``T`` (``y* ~ T^2``); with four
    roundings of terms below ``16 size``, ``delta / 2 <= 2**5 eps size``,
    and ``_PRUNE_ROUNDING * size = 2**9 eps size`` leaves a factor 16 to
    spare; ``_PRUNE_MARGIN`` (about 1e-9) covers the threshold and the test
    (errors of order ``eps r/(r-1)``, included in ``size`` too).  So a pruned
    pixel's computed test fails on every state the map reaches.

    Any start: the first step from ``(y0, v0)`` (``y0 < 1`` allowed) may
    slide, and then the orbit of ``(1, 0)`` never does; or it does not, and
    no later state slides.  Either way the answer is status 1.

    ``e = 0``: ``r = 1``, the bound is infinite: never pruned (nor where
    ``T^2`` underflows or anything overflows: the test is then False).
    """
    TT, a = _prune_row(T, energy0)
    rm1, threshold, c = _prune_column(ratio)
    return _prune_pixel(T, TT, a, rm1, threshold, c)


@njit(cache=True, inline="always")
def _prune_row(T, energy0):
    """The factors of :func:`_never_slides` that depend on ``u`` only: ``(T^2, 1/T^2 + 1 + energy0)``."""
    TT = T * T
    return TT, (1.0 / TT + 1.0 + energy0) if TT > 0.0 else 0.0


@njit(cache=True, inline="always")
def _prune_column(ratio):
    """The factors of :func:`_never_slides` that depend on ``e`` only:
    ``(r - 1, sqrt(2 (r-1)(r+1)), r + r/(r-1))``."""
    rm1 = ratio - 1.0  # exact for ratio >= 1
    threshold = math.sqrt(2.0 * (rm1 * (ratio + 1.0)))
    return rm1, threshold, (ratio + ratio / rm1) if rm1 > 0.0 else 0.0


@njit(cache=True, inline="always")
def _prune_pixel(T, TT, a, rm1, threshold, c):
    """:func:`_never_slides` from its row and column factors (the same operations, the same bits)."""
    if not (rm1 > 0.0 and TT > 0.0):  # e = 0, or u so large that T^2 underflows
        return False
    if not T < threshold:  # below the curve (most iterated pixels): the test below is False too
        return False
    size = TT + a * c
    return T * (1.0 + _PRUNE_MARGIN + _PRUNE_ROUNDING * size) < threshold


@njit(cache=True)
def _prunable(es, us, energy0, out):
    for p in range(es.shape[0]):
        T, ratio = _constants(es[p], us[p])
        out[p] = _never_slides(es[p], T, ratio, energy0)


# The fast kernel runs LANES pixels in lockstep.  The lane loops below are
# written branch-free (selects only) so that LLVM vectorises them: 8 float64
# per AVX-512 register with _simd.prefer_wide_vectors (4 without it, LLVM's
# tuning for these Xeons), 4 per AVX2 register; 32 measured fastest on the
# development machine, 64 no faster with 8-wide vectors (benchmarks/README.md).
LANES = 32
# Pixels listed at a time (the segments that units of parallel work take, _chunking)
_CHUNK_MAX = 1024
# The fewest pixels per unit of parallel work (one per thread, _chunking)
_UNIT_MIN = 4096
# Lanes with a fourth impact after which the next common step counts to the seventh (_run_unit)
_LONG_MIN = 1
# the counting continuation of _run_unit takes impacts two at a time, 2-3, 4-5, ...
assert _COUNTED_IMPACTS % 2 == 0
# Rows of the lane state block of _run_unit (one float64 row of LANES per field)
_Y, _V, _E, _T, _R, _H, _TS, _WS, _LOGE, _SS = range(10)
# and of its integer block (_N: the lockstep step the lane's pixel, or its
# period, started after; its step count is the current lockstep step less that)
_N, _IMP, _FLY, _MORE, _LIVE, _PER, _PIX, _FIN = range(8)
_FLOAT_ROWS, _INT_ROWS = 10, 8


@njit(cache=True)
def _grid_factors(es, us, energy0):
    """Per column ``(e, ratio, r - 1, threshold, c)`` and per row ``(T, T^2, a, T^2/2)`` of a grid:
    the constants of :func:`stairbounce.model._constants`, the half ``0.5 T T`` of
    ``model._step`` and the factors of the pruning test, computed once per scan."""
    cols = np.empty((5, es.shape[0]))
    rows = np.empty((4, us.shape[0]))
    for j in range(es.shape[0]):
        _, ratio = _constants(es[j], 1.0)
        rm1, threshold, c = _prune_column(ratio)
        cols[0, j] = es[j]
        cols[1, j] = ratio
        cols[2, j] = rm1
        cols[3, j] = threshold
        cols[4, j] = c
    for i in range(us.shape[0]):
        T, _ = _constants(0.0, us[i])
        TT, a = _prune_row(T, energy0)
        rows[0, i] = T
        rows[1, i] = TT
        rows[2, i] = a
        rows[3, i] = 0.5 * T * T  # as model._step evaluates it
    return cols, rows


@njit(cache=True)
def _list_chunk(es, us, grid, cols, rows, prune, y0, v0, start, stop, todo, F,
                status, word_length, jumps, period, impacts):
    """The pixels ``start..stop-1`` that need iterating, listed; the others answered.

    With ``prune``, a pixel that :func:`_never_slides` proves gets status 1
    here (by its row and column factors on a grid, :func:`_prune_pixel`).
    A pixel whose first step slides, from ``(y0, v0)`` and from ``(1, 0)``
    (the sliding test (2.4) of ``model._step``, the same operations as a
    lane's common step), is answered here too: period 1, no finite impact,
    one letter (the whole ``(1, 0^inf)`` tongue of Theorem 3.1 on the
    paper's grid, 18 % of its pixels).  The others go to ``todo[:n]`` (flat
    index) with their constants in ``F[0:4, :n]`` (e, T, ratio, 0.5 T T).
    Returns ``(n, pruned)``.
    """
    n = 0
    pruned = 0
    energy0 = y0 + v0 * v0
    s0 = math.sqrt(v0 * v0 + 2.0 * y0)  # the first step's s from the start
    s1 = math.sqrt(0.0 * 0.0 + 2.0 * 1.0)  # and from (1, 0), as model._step computes them
    if grid:
        ne = es.shape[0]
        i = start // ne
        j = start - i * ne
        p = start
        while p < stop:
            jend = min(ne, j + (stop - p))
            T = rows[0, i]
            TT = rows[1, i]
            a = rows[2, i]
            half = rows[3, i]
            for jj in range(j, jend):
                q = p + jj - j
                ratio = cols[1, jj]
                if prune and _prune_pixel(T, TT, a, cols[2, jj], cols[3, jj], cols[4, jj]):
                    _store(q, 0, 0, 0, status, word_length, jumps, period, impacts)
                    pruned += 1
                elif v0 + ratio * s0 <= T and 0.0 + ratio * s1 <= T:
                    _store(q, 1, 0, 1, status, word_length, jumps, period, impacts)
                else:
                    todo[n] = q
                    F[0, n] = cols[0, jj]
                    F[1, n] = T
                    F[2, n] = cols[1, jj]
                    F[3, n] = half
                    n += 1
            p += jend - j
            i += 1
            j = 0
    else:
        for q in range(start, stop):
            e = es[q]
            T, ratio = _constants(e, us[q])
            if prune and _never_slides(e, T, ratio, energy0):
                _store(q, 0, 0, 0, status, word_length, jumps, period, impacts)
                pruned += 1
            elif v0 + ratio * s0 <= T and 0.0 + ratio * s1 <= T:
                _store(q, 1, 0, 1, status, word_length, jumps, period, impacts)
            else:
                todo[n] = q
                F[0, n] = e
                F[1, n] = T
                F[2, n] = ratio
                F[3, n] = 0.5 * T * T  # as model._step evaluates it
                n += 1
    return n, pruned


@njit(cache=True, inline="always")
def _load(l, pos, todo, F, y0, v0, from_rest, S, I):
    """Lane ``l`` takes the next listed pixel (:func:`_list_chunk`; ``pos``
    as in :func:`_refill`, which must have left one), from ``(y0, v0)``."""
    q = pos[0]
    pos[0] = q + 1
    g = pos[3]
    S[_E, l] = F[0, q]
    S[_T, l] = F[1, q]
    S[_R, l] = F[2, q]
    S[_H, l] = F[3, q]
    S[_LOGE, l] = 1.0  # log(e) not computed yet (it is <= 0)
    S[_Y, l] = 1.0 if from_rest else y0
    S[_V, l] = 0.0 if from_rest else v0
    I[_PER, l] = 1 if from_rest else 0
    I[_PIX, l] = todo[q]
    I[_N, l] = g  # the lockstep step the pixel starts after (steps done: g' - g after step g')
    I[_IMP, l] = 0
    I[_FLY, l] = 0
    I[_LIVE, l] = 1


@njit(cache=True)
def _refill(queue, chunk, npix, pos, todo, F, es, us, grid, cols, rows, prune, y0, v0,
            status, word_length, jumps, period, impacts):
    """The list of a unit's pixels to iterate used up: take and list the
    plane's next segments until one has such a pixel; False when none is left.

    ``pos = (next listed, listed, pruned, lockstep step)``; ``queue = (next
    segment, segments)``, shared by the units: a segment ``k`` is the
    ``chunk`` pixels from ``k * chunk``, taken by one unit only
    (:func:`stairbounce._atomic.take_next`) and listed by
    :func:`_list_chunk`.  A call, not inlined: an inlined
    function counts a reference to each of its array arguments on entry and
    on exit (two atomic operations each), and this one has fifteen; it runs
    once per segment, a lane's reload (:func:`_load`) once per pixel.
    """
    while pos[0] == pos[1]:
        k = take_next(queue)
        if k >= queue[1]:
            return False
        start = k * chunk
        n, pruned = _list_chunk(es, us, grid, cols, rows, prune, y0, v0, start, min(start + chunk, npix),
                                todo, F, status, word_length, jumps, period, impacts)
        pos[0] = 0
        pos[1] = n
        pos[2] += pruned
    return True


@njit(cache=True, inline="always")
def _impact_pair(ta, wa, e, T, tl, wl, kl, j):
    """Impacts ``j`` and ``j + 1`` after the one at ``ta`` (speed ``wa``), as
    model._step counts them (t += 2w, w *= e); (tl, wl, kl): the last one
    before the edge so far."""
    ta = ta + 2.0 * wa
    wa = wa * e
    n = ta <= T
    tl = ta if n else tl
    wl = wa if n else wl
    kl = j if n else kl
    ta = ta + 2.0 * wa
    wa = wa * e
    n = ta <= T
    tl = ta if n else tl
    wl = wa if n else wl
    kl = j + 1 if n else kl
    return ta, wa, tl, wl, kl


@njit(cache=True, inline="always")
def _common_step(seventh, S, I):
    """The common step of every lane: model._step up to its third impact
    (its seventh when ``seventh``, a constant where it is called) and its
    bookkeeping, in one loop over the lanes that the compiler vectorises.
    Returns the number of lanes with MORE impacts to count, a number that
    is not 0 when a lane FINishes (slides: the end by max_iter is set by
    :func:`_max_iter_ends`), and the number whose step has a fourth impact
    (deep)."""
    Y = S[_Y]
    V = S[_V]
    E = S[_E]
    TT = S[_T]
    RATIO = S[_R]
    HALF = S[_H]
    TS = S[_TS]
    SS = S[_SS]
    WS = S[_WS]
    IMP = I[_IMP]
    FLY = I[_FLY]
    MORE = I[_MORE]
    LIVE = I[_LIVE]
    FIN = I[_FIN]
    nmore = 0
    nfin = 0
    deep = 0
    for l in range(LANES):
        y = Y[l]
        v = V[l]
        e = E[l]
        T = TT[l]
        s = math.sqrt(v * v + 2.0 * y)
        slide = v + RATIO[l] * s <= T
        t = v + s
        fly = t > T
        w = e * s
        ta, wa, tl, wl, kl = _impact_pair(t, w, e, T, t, w, 1, 2)
        if seventh:
            ta, wa, tl, wl, kl = _impact_pair(ta, wa, e, T, tl, wl, kl, 4)
            ta, wa, tl, wl, kl = _impact_pair(ta, wa, e, T, tl, wl, kl, 6)
        more = (ta + 2.0 * wa <= T) and not fly and not slide
        d = T - tl
        y_bounce = -0.5 * d * d + wl * d + 1.0
        v_bounce = wl - d
        y_fly = y + v * T - HALF[l] + 1.0
        v_fly = v - T
        yn = 1.0 if slide else (y_fly if fly else y_bounce)
        vn = 0.0 if slide else (v_fly if fly else v_bounce)
        # a lane with MORE ends its step below, in this lockstep step, and
        # writes Y there; what it needs of its state is V, s, t and w
        Y[l] = yn
        V[l] = v if more else vn
        TS[l] = ta  # the passes go on from the last impact counted
        WS[l] = wa
        SS[l] = s  # and the closed form from s
        live = LIVE[l]
        m = live if more else 0
        MORE[l] = m
        nmore += m
        IMP[l] += 0 if (more or slide or fly) else kl
        FLY[l] += 1 if fly else 0  # jumps = steps - flights, at the end
        # every live lane ends a step in this lockstep step (here, in
        # the passes or in the closed form): its last one when it slides
        # (FIN 2) or reaches max_iter (FIN 1, _max_iter_ends)
        f = (live + live) if slide else 0
        FIN[l] = f
        nfin += f
        if seventh:  # counted to the seventh: a fourth impact with or without MORE
            deep += live if (more or (kl >= 4 and not (fly or slide))) else 0
    # counted to the third: the lanes with a fourth impact are those with MORE
    return nmore, nfin, (deep if seventh else nmore)


@njit(cache=True, inline="always")
def _max_iter_ends(last_start, I):
    """FIN 1 for the live lanes whose pixel (or transient) started after
    step ``last_start`` or before, so ends with max_iter steps in this one,
    unless the common step ended it by a slide (FIN 2); returns how many."""
    N = I[_N]
    LIVE = I[_LIVE]
    FIN = I[_FIN]
    n = 0
    for l in range(LANES):
        f = LIVE[l] if (N[l] <= last_start and FIN[l] == 0) else 0
        FIN[l] = FIN[l] + f
        n += f
    return n


@njit(cache=True)
def _run_unit(es, us, grid, cols, rows, max_iter, y0, v0, prune, queue, chunk, npix,
              status, word_length, jumps, period, impacts, halt, long_min):
    """The pixels of the segments this unit takes from ``queue`` (:func:`_refill`),
    LANES at a time in lockstep.

    The pixels that need iterating are listed a segment at a time
    (:func:`_list_chunk`, which answers the pruned ones); a lane takes the
    next listed pixel as soon as its own finishes, across segments, so lanes
    stay busy whatever the mix of cheap and expensive pixels and idle only at
    the end of the unit, once the segments are all taken.  Each pixel sees exactly the sequence of operations
    of ``_slide_or_steps`` with ``model._step``.  Returns the number of
    pixels pruned.  Returns early, leaving pixels unwritten, once ``halt[0]``
    is set (Ctrl-C, :mod:`stairbounce._interrupt`); it is read before the
    first segment is listed and then once per lockstep step.
    """
    prefer_wide_vectors()  # eight float64 per vector where the machine has them (_simd)
    L = LANES
    if halted(halt):  # before listing: a segment's listing writes the pixels it answers
        return 0
    # phase start (the "# phase" comments mark where benchmarks/scan_phases.py times phases)
    from_rest = y0 == 1.0 and v0 == 0.0
    todo = np.empty(chunk, np.int64)
    F = np.empty((4, chunk))
    pos = np.zeros(4, np.int64)  # (next listed, listed, pruned, lockstep step)
    # lane state: one block of float rows and one of integer rows (row indices
    # _Y.. and _N..), so that the compiler sees the rows cannot overlap
    S = np.zeros((_FLOAT_ROWS, L))
    S[_E] = 0.5
    S[_T] = 1.0
    S[_R] = 3.0
    I = np.zeros((_INT_ROWS, L), np.int64)
    M = np.empty(L * _MEMO_SIZE)  # kept values of the closed form, _MEMO_SIZE per lane (_closed sets them)
    active = 0
    # each lane takes the next pixel of the unit that needs iterating
    while active < L and (pos[0] < pos[1] or _refill(queue, chunk, npix, pos, todo, F, es, us, grid, cols, rows,
                                                     prune, y0, v0, status, word_length, jumps, period, impacts)):
        _load(active, pos, todo, F, y0, v0, from_rest, S, I)
        active += 1

    Y = S[_Y]
    V = S[_V]
    E = S[_E]
    TT = S[_T]
    TS = S[_TS]
    WS = S[_WS]
    # every live lane finishes exactly one map step per lockstep step (the
    # common step, the passes or the closed form), so a lane's step count is
    # the lockstep step g less the one its pixel (or its period) started
    # after, kept in N: no count is stored per step
    N = I[_N]
    g = 0
    IMP = I[_IMP]
    FLY = I[_FLY]  # steps that flew over (no landing): jumps = steps - FLY
    MORE = I[_MORE]
    LIVE = I[_LIVE]
    FIN = I[_FIN]  # the pixel (or its transient) ends with this step: 2 it slid, 1 max_iter
    seventh = long_min <= 0
    first_start = 0  # the least N over the lanes (all start after step 0); set again when N changes
    # phase 1: listing the first segments, loading the lanes
    while active > 0:
        if halted(halt):
            return pos[2]
        g += 1
        last_start = g - max_iter  # a pixel that started after this step or before has done max_iter
        # the common step (model._step up to its third impact, or its
        # seventh) and its bookkeeping, vectorised over lanes; a lane with
        # an impact past those keeps its state and goes on below.  Counting
        # to the seventh costs every lane about 1.3 cycles more, and saves
        # two passes over all the lanes when any one lane has a fourth
        # impact: so it is done after a lockstep step where long_min lanes
        # (1 in production) had one.  The same operations either way.
        k = 6 if seventh else 2  # impacts counted
        if seventh:
            nmore, nfin, deep = _common_step(True, S, I)
        else:
            nmore, nfin, deep = _common_step(False, S, I)
        seventh = deep >= long_min
        # the lanes that reach max_iter with this step: only when the oldest
        # start is that old (about once per pixel that runs to max_iter), not
        # a test per lane in every common step
        if first_start <= last_start:
            nfin += _max_iter_ends(last_start, I)
        # phase 2 if active == LANES else 3: the common step, all lanes live or a tail
        if nmore > 0:
            # impacts 4, 5, ... counted on along t += 2w, w *= e as model._step
            # does, up to its _COUNTED_IMPACTS; past that, its closed form
            # two impacts per pass (k and k + 1): the same operations as one
            # at a time, half the passes over the lanes
            while nmore > 0:
                k += 2
                if k == _COUNTED_IMPACTS:
                    # phase 4: impacts 4 to 7
                    _kept_pass(S, I, M)  # most closed-form steps; _closed the rest
                    for l in range(L):
                        if MORE[l]:
                            if _closed(l, S, I, M):  # it slid
                                nfin += 2
                                FIN[l] = 2
                    # phase 5: the closed form past _COUNTED_IMPACTS
                    break
                nmore = 0
                for l in range(L):
                    m = MORE[l]
                    T = TT[l]
                    e = E[l]
                    ta = TS[l] + 2.0 * WS[l]  # impact k
                    wa = WS[l] * e
                    tb = ta + 2.0 * wa  # impact k + 1
                    wb = wa * e
                    nxa = tb <= T
                    nxb = tb + 2.0 * wb <= T
                    lasta = m if not nxa else 0
                    lastb = m if (nxa and not nxb) else 0
                    last = lasta | lastb
                    t = ta if lasta else tb
                    w = wa if lasta else wb
                    d = T - t
                    Y[l] = (-0.5 * d * d + w * d + 1.0) if last else Y[l]
                    V[l] = (w - d) if last else V[l]
                    IMP[l] += k if lasta else (k + 1 if lastb else 0)
                    TS[l] = tb
                    WS[l] = wb
                    m = m if (nxa and nxb) else 0
                    MORE[l] = m
                    nmore += m
                # phase 4: impacts 4 to 7
        if nfin == 0:
            continue
        pos[3] = g  # a lane reloaded now starts after this step
        for l in range(L):
            f = FIN[l]
            if f == 0:
                continue
            FIN[l] = 0
            sl = f == 2
            if sl and I[_PER, l] == 0:
                # end of the transient: the ball leaves the edge at (1, 0)
                I[_PER, l] = 1
                N[l] = g
                IMP[l] = 0
                FLY[l] = 0
                continue
            _store(I[_PIX, l], g - N[l] if sl else 0, IMP[l], g - N[l] - FLY[l],
                   status, word_length, jumps, period, impacts)
            if pos[0] < pos[1] or _refill(queue, chunk, npix, pos, todo, F, es, us, grid, cols, rows, prune,
                                          y0, v0, status, word_length, jumps, period, impacts):
                _load(l, pos, todo, F, y0, v0, from_rest, S, I)  # the unit's next pixel
            else:
                LIVE[l] = 0
                active -= 1
        # N changes only above (a reload, a transient's end): the least start
        # again, over every lane (one no longer live keeps its last, which
        # can only bring _max_iter_ends forward, never skip it); a loop, as
        # N.min() puts a reference count in the loop (test_kernel_paths)
        first_start = N[0]
        for l in range(1, L):
            first_start = min(first_start, N[l])
        # phase 6: finished pixels stored, lanes reloaded (and segments listed)
    return pos[2]


@njit(cache=True, inline="always")
def _kept_pass(S, I, M):
    """The closed-form step of every lane with MORE that the kept impact
    number answers (``model._impacts_kept``, inlined) with ``e^j`` kept too:
    the operations of ``model._step_closed_bounce`` on that path, the same
    bits, and the same values kept (``j`` and ``e^j``).  The others (a new
    pixel, a number not kept or out of its bounds, ``e^j`` not kept: about
    1.6 % of its closed-form steps) keep MORE for :func:`_closed`.  In one loop over
    the lanes with no call, this costs about a third of :func:`_closed` on
    the same lanes (``benchmarks/README.md``); ``tests/test_kernel_paths.py``
    checks it against :func:`_closed` lane by lane."""
    E = S[_E]
    V = S[_V]
    Y = S[_Y]
    SS = S[_SS]
    TT = S[_T]
    LOGE = S[_LOGE]
    MORE = I[_MORE]
    IMP = I[_IMP]
    for l in range(LANES):
        if MORE[l] == 0 or LOGE[l] > 0.0:  # no step here, or a new pixel: nothing kept
            continue
        base = l * _MEMO_SIZE
        s = SS[l]
        T = TT[l]
        j, t = _impacts_kept(V[l], s, E[l], T, LOGE[l], M, base)
        sp = base + _power_slot(j)
        if j <= 0 or M[sp] != j:  # not answered, or e^j not kept: _closed
            continue
        p = M[sp + _MEMO_SLOTS]
        M[base] = j
        M[base + 1] = p
        # the rest of model._step_closed_bounce
        Y[l], V[l] = _after_last_impact(T, t, p * s)
        IMP[l] += j
        MORE[l] = 0


@njit(cache=True)
def _closed(l, S, I, M):
    """Lane ``l``'s step by the closed form of ``model._step`` (past
    ``_COUNTED_IMPACTS`` impacts), from its state before the step, and its
    bookkeeping as in the lane loops (the lanes :func:`_kept_pass` leaves).
    Returns whether it slid (a pixel's max_iter is told in the common step).  ``M[l * _MEMO_SIZE:][:_MEMO_SIZE]``: the
    values of ``expm1`` and ``pow`` and the impact number kept for the lane's
    pixel (``model._geometric_memo``), indexed in place (a view per call
    costs about 30 cycles)."""
    e = S[_E, l]
    base = l * _MEMO_SIZE
    if S[_LOGE, l] > 0.0:  # log(e) once per pixel, and nothing kept yet
        S[_LOGE, l] = math.log(e) if e > 0.0 else -math.inf
        for i in range(base, base + _MEMO_SIZE):
            M[i] = -1.0
    # a lane past its first impact neither slides by (2.4) nor flies over, and has e > 0
    yn, vn, k = _step_closed_bounce(S[_V, l], S[_SS, l], e, S[_T, l], S[_LOGE, l], M, base)
    S[_Y, l] = yn
    S[_V, l] = vn
    I[_MORE, l] = 0
    if k > 0:
        I[_IMP, l] += k
    return k == SLIDING


@njit(cache=True, parallel=True, nogil=True)
def _scan_fast(es, us, grid, max_iter, y0, v0, prune, units, chunk,
               status, word_length, jumps, period, impacts, halt, long_min=_LONG_MIN):
    """Fast kernel: ``units`` units of work in parallel (:func:`_run_unit`,
    LANES pixels of a unit in lockstep), which take the segments of ``chunk``
    pixels one at a time from a counter they share.

    ``grid``: the pixels are the row-major ``n_u x n_e`` grid ``us x es``;
    otherwise the points ``(es[p], us[p])``.  Outputs are flat, one entry per
    pixel.  ``prune``: skip the pixels :func:`_never_slides` proves.  Returns
    the number of pixels pruned.  Stops early once ``halt[0]`` is set (then
    the outputs are incomplete and must be dropped).  ``long_min``: a
    lockstep step counts to the seventh impact in its common step after one
    where that many lanes had a fourth impact (0: always, a huge number:
    never); the same arrays whatever its value, only the time changes.
    """
    npix = es.shape[0] * us.shape[0] if grid else es.shape[0]
    if grid:
        cols, rows = _grid_factors(es, us, y0 + v0 * v0)
    else:
        cols, rows = np.empty((5, 0)), np.empty((4, 0))
    queue = np.zeros(2, np.int64)  # (next segment, segments): _refill
    queue[1] = (npix + chunk - 1) // chunk
    pruned = np.zeros(units, np.int64)
    for c in prange(units):
        pruned[c] = _run_unit(es, us, grid, cols, rows, max_iter, y0, v0, prune, queue, chunk, npix,
                              status, word_length, jumps, period, impacts, halt, long_min)
    return pruned.sum()


def _chunking(npix, threads, unit_min=_UNIT_MIN):
    """Segment size and the number of units of :func:`_scan_fast`: ``(chunk, units)``.

    One unit per thread (prange gives each thread one): a unit's lanes idle
    only at its end, while its last pixels run (up to max_iter steps), and a
    unit takes the next segment whenever its lanes have used up the pixels it
    listed, so the threads share the work however uneven the plane (low u
    slides in a step or two, high u runs to max_iter, above the Corollary 2.1
    curve nothing is iterated) and end together but for their last pixels.
    At least ``unit_min`` pixels per unit (_UNIT_MIN; the bisection rounds of
    :mod:`stairbounce.structure.borders` ask for less, to use every thread on a few
    thousand points).  Segments of at most _CHUNK_MAX pixels, about 16 per
    thread.  Results do not depend on any of these choices.
    """
    chunk = int(min(_CHUNK_MAX, max(LANES, -(-npix // (16 * max(threads, 1))))))
    nseg = -(-npix // chunk)
    units = int(max(1, min(max(threads, 1), npix // unit_min, nseg)))
    return chunk, units


# --------------------------------------------------------------------------- #
# Validation and memory                                                       #
# --------------------------------------------------------------------------- #


# Pixels along the longer side of a window given without pixel counts
# (square pixels; docs/design.md, "Conventions for windows and limits")
DEFAULT_SIDE = 500


def _window(name, spec, lo_min, hi_max, lo_text):
    """One window ``(lo, hi)`` or ``(lo, hi, n)`` -> ``(lo, hi, n)``, ``n`` None
    when not given (:func:`_windows` fills it in)."""
    lo, hi, n = _v.window(name, spec)
    lo = _finite(f"{name}_min", lo)
    hi = _finite(f"{name}_max", hi)
    if n is not None:
        n = check_count(f"n_{name}", n, 1)
    if lo < lo_min or hi > hi_max:
        raise ValueError(f"{name} window must lie in {lo_text}, got [{lo}, {hi}]")
    if not lo < hi:
        raise ValueError(f"{name}_min must be < {name}_max, got {name}_min = {lo}, {name}_max = {hi}")
    return lo, hi, n


def _windows(e, u, side=DEFAULT_SIDE):
    """The scan windows ``e``, ``u`` (each ``(lo, hi)`` or ``(lo, hi, n)``,
    image edges) checked, as two triples: a count not given makes square
    pixels (:func:`square_counts`)."""
    ew = _window("e", e, 0.0, 1.0, "[0, 1]")
    uw = _window("u", u, 0.0, math.inf, "[0, inf)")
    n_e, n_u = square_counts(ew, uw, side)
    return (ew[0], ew[1], n_e), (uw[0], uw[1], n_u)


def square_counts(e, u, side=DEFAULT_SIDE):
    """square_counts(e, u, side=500) -> (n_e, n_u)

    Pixel counts of the windows ``e = (lo, hi[, n])`` and ``u`` where a count
    is not given: square pixels, ``side`` pixels along the longer side when
    neither is given, else the given count's pixel size (at least 1 pixel).
    """
    n_e = e[2] if len(e) > 2 else None
    n_u = u[2] if len(u) > 2 else None
    we, wu = e[1] - e[0], u[1] - u[0]
    if n_e is None and n_u is None:
        pixel = max(we, wu) / side
    elif n_e is None or n_u is None:
        pixel = we / n_e if n_e is not None else wu / n_u
    else:
        return n_e, n_u

    def count(width):
        return max(1, int(round(width / pixel)))

    return (count(we) if n_e is None else n_e), (count(wu) if n_u is None else n_u)


def _coords(name, values):
    _v.check_array_memory(f"{name} of {{n}} values", values, 8)  # the float copy, before it is made
    a = np.asarray(values, dtype=np.float64)
    if a.ndim != 1 or a.size == 0:
        raise ValueError(f"{name} values must be a non-empty 1-D array, got shape {a.shape}")
    return _check_values(name, a)


def _point_coords(name, values):
    _v.check_array_memory(f"{name} of {{n}} values", values, 8)  # the float copy, before it is made
    try:
        a = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a 1-D array of real numbers") from None
    if a.ndim != 1:
        raise ValueError(f"{name} must be a 1-D array, got shape {a.shape}")
    if a.size == 0:
        return np.ascontiguousarray(a)
    return _check_values(name, a)


def _check_centres(es, us):
    """:func:`_check_values` on the pixel centres of windows that :func:`_window`
    accepted (finite), from the least and the largest centre (centres do not
    decrease, so the messages name the same values): Python floats, as a dozen
    numpy calls on arrays cost 50 us in a scan of 5 ms."""
    e_lo = float(es[0])
    _check_range("e", e_lo, float(es[-1]), e_lo if _v.e_too_small(e_lo) else None)
    _check_range("u", float(us[0]), float(us[-1]))


def _check_values(name, a):
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} values must be finite")
    tiny = a[_v.e_too_small(a)] if name == "e" else a[:0]
    _check_range(name, a.min(), a.max(), tiny.flat[0] if tiny.size else None)
    # C-contiguous and writeable (a copy only when not): numba compiles a kernel again for
    # each array layout and flag, and an xarray coordinate's .values is read-only
    # (scan_coords(ds.e.values, ..) compiled the scan kernel a second time, about 15 s in
    # a fresh install)
    return np.require(a, requirements=["C", "W"])


def _check_range(name, lo, hi, tiny=None):
    """The range of finite ``e`` or ``u`` values from their least ``lo`` and
    largest ``hi`` (and ``tiny``, the first e in (0, 2^-53), if any): ValueError
    naming the parameter and the range."""
    if name == "e" and not (lo >= 0.0 and hi < 1.0):
        raise ValueError(f"e (restitution coefficient) values must be in [0, 1), got [{lo}, {hi}]")
    if tiny is not None:
        raise ValueError(f"{_v.E_TINY_RULE}, got {tiny}")
    if name == "u" and not lo > 0.0:
        raise ValueError(f"u (horizontal speed) values must be > 0, got min {lo}")
    if name == "u" and not (lo >= _v.U_MIN and hi <= _v.U_MAX):
        raise ValueError(
            f"u (horizontal speed) values must be in [{_v.U_MIN:g}, {_v.U_MAX:g}] (the valid "
            f"numeric range), got [{lo}, {hi}]"
        )


def estimate_bytes(n_e, n_u):
    """estimate_bytes(n_e, n_u) -> int

    Memory the outputs of a scan of ``n_e x n_u`` pixels take: one uint8,
    two int32 and two int64 per pixel (25 bytes) plus the coordinates.  This
    is the peak of :func:`scan` (measured: 25.0 B/pixel without progress,
    26.6 with it).
    """
    n_e, n_u = check_count("n_e", n_e, 1), check_count("n_u", n_u, 1)
    return n_e * n_u * _BYTES_PER_PIXEL + 8 * (n_e + n_u)


def _available_memory():
    """Bytes of memory available now (:func:`stairbounce._validate.available_memory`)."""
    return _v.available_memory()


def estimate_points_bytes(n):
    """estimate_points_bytes(n) -> int

    Memory the outputs of :func:`scan_points` on ``n`` points take: 25 bytes
    per point for the fields plus 16 for the two coordinates.
    """
    return int(n) * (_BYTES_PER_PIXEL + 16)


def _check_memory(n_e, n_u, bytes_per_pixel=None):
    """Refuse a scan whose peak (:func:`estimate_bytes`, or ``bytes_per_pixel``
    per pixel when the caller does more with the result) exceeds the memory
    available."""
    need = estimate_bytes(n_e, n_u)
    if bytes_per_pixel is not None:
        need = max(need, n_e * n_u * bytes_per_pixel)
    return _check_need(need, f"a scan of {n_e} x {n_u} pixels")


def _check_need(need, what):
    avail = _available_memory()
    if avail is not None and need > avail:
        raise ValueError(
            f"{what} needs about {_human(need)} for its outputs, "
            f"more than the {_human(avail)} of memory available: reduce the size or scan tiles"
        )
    return need


def _human(n):
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if n < 1024 or unit == "TiB":
            return f"{n:.1f} {unit}" if unit != "B" else f"{n} B"
        n /= 1024.0
    return f"{n} B"  # pragma: no cover


# --------------------------------------------------------------------------- #
# Public API                                                                  #
# --------------------------------------------------------------------------- #


def pixel_centres(lo, hi, n):
    """pixel_centres(lo, hi, n) -> np.ndarray

    Centres of ``n`` equal pixels covering exactly ``[lo, hi]``.

    ``c_j = lo + (j + 1/2) (hi - lo) / n``, j = 0..n-1.  Sub-windows of a scan
    must be cut out of this array (not recomputed from their own bounds) to be
    bit-identical to the whole scan.
    """
    lo = _finite("lo", lo)
    hi = _finite("hi", hi)
    n = check_count("n", n, 1)
    if not (lo < hi and math.isfinite(hi - lo)):
        raise ValueError(f"lo must be < hi with hi - lo finite, got lo = {lo}, hi = {hi}")
    _v.check_memory(f"n = {n} pixel centres", 16 * n)
    return _centres(lo, hi, n)


def _centres(lo, hi, n):
    """:func:`pixel_centres` of a checked window."""
    return lo + (np.arange(n) + 0.5) * (hi - lo) / n


def _check_run(max_iter, y0, v0):
    max_iter = check_count("max_iter", max_iter, 1)
    if max_iter > 2**31 - 1:
        raise ValueError(f"max_iter must be an integer in [1, 2**31 - 1], got {max_iter}")
    # the map's valid range (docs/guide/numerics.md): v0^2, 2 y0 and 1/u^2 far from overflow
    y0, v0 = check_state(y0, v0, "y0", "v0")
    return max_iter, y0, v0


# The output arrays of the last two scans, taken back by a later scan of the
# same size once nothing else refers to them (_outputs); two, so that a loop
# ``ds = scan(...)`` (the last result alive while the next is made) finds the
# one before; only scans of at most _SPARE_BYTES_MAX
_SPARE_SCANS = 2
_SPARE_BYTES_MAX = 32 * 2**20
_spare: dict[str, list[np.ndarray]] = {}
_spare_lock = threading.Lock()


def _outputs(npix):
    """The flat output arrays of a scan of ``npix`` pixels (a dict by field).

    Arrays fresh from the system cost a page fault on the kernel's first
    write to each page: about 650 per scan of the paper's grid (25 bytes per
    pixel), 0.3-0.5 ms of its 5-6 ms.  So the arrays of the last
    ``_SPARE_SCANS`` scans (of at most ``_SPARE_BYTES_MAX`` each) are kept
    here, and a scan of the same size takes back one that nothing else
    refers to any more (the dataset that held it and every view of it are
    gone: its reference count says so, under a lock).  An array still in use
    is never taken.  The kernel writes every pixel of its outputs, so the
    values are the same as in new arrays.  What stays held once the results
    are dropped: the outputs of the last two scans, 64 MiB at most.
    """
    keep = 0 < npix * _BYTES_PER_PIXEL <= _SPARE_BYTES_MAX
    out = {}
    with _spare_lock:
        for k, (dt, _) in _FIELDS.items():
            kept = _spare.get(k, [])  # oldest first
            got = None
            for i in range(len(kept) - 1, -1, -1):
                # references: the list's and getrefcount's argument, nobody else's
                if kept[i].shape[0] == npix and sys.getrefcount(kept[i]) == 2:
                    got = kept.pop(i)
                    break
            if got is None:
                del kept[: max(0, len(kept) - (_SPARE_SCANS - 1))]  # released before a new one is made
                got = np.empty(npix, dtype=dt)
            kept.append(got)
            out[k] = got
            _spare[k] = kept[-_SPARE_SCANS:] if keep else kept[-_SPARE_SCANS:-1]
    return out


def _run(es, us, grid, max_iter, y0, v0, prune, unit_min=_UNIT_MIN):
    """Allocate flat outputs and run :func:`_scan_fast`; returns them and the
    number of pixels pruned (the kernel's own count, for tests and benchmarks).
    ``unit_min``: the fewest pixels in a unit of parallel work (:func:`_chunking`)."""
    npix = es.size * us.size if grid else es.size
    out = _outputs(npix)
    chunk, units = _chunking(npix, numba.get_num_threads(), unit_min)
    pruned = 0
    if npix:
        from ._interrupt import run_kernel

        # in a helper thread when called from the main thread: Ctrl-C stops it at once
        pruned = run_kernel(
            _scan_fast, es, us, grid, max_iter, y0, v0, bool(prune), units, chunk,
            out["status"], out["word_length"], out["jumps"], out["period"], out["impacts"],
        )
    return out, int(pruned)


def _dataset(data_vars, coords, attrs):
    """``xr.Dataset(data_vars, coords=coords, attrs=attrs)`` for the outputs of a scan.

    ``data_vars`` and ``coords`` map names to ``(dims, numpy array, attrs)``
    whose sizes agree (the scans make them so), ``attrs`` is a dict.  The
    public constructor merges and aligns its arguments: 0.27 ms of the paper
    grid's 5-6 ms :func:`scan`.  Nothing here needs that, so the variables
    and the default index of each dimension coordinate are made as the
    constructor makes them and handed to xarray's own fast path,
    ``Dataset._construct_direct`` (0.11 ms).  It is private API: where it is
    missing or its signature changed, the public constructor is used;
    ``tests/test_plane.py`` checks that the two give identical datasets,
    xarray's internal invariants included.
    """
    try:
        from xarray.indexes import PandasIndex

        variables = {k: xr.Variable(dims, data, a) for k, (dims, data, a) in data_vars.items()}
        indexes = {}
        for k, (dims, data, a) in coords.items():
            var = xr.Variable(dims, data, a)
            if var.dims == (k,):  # a dimension coordinate: its default (pandas) index
                index = PandasIndex.from_variables({k: var}, options={})
                variables.update(index.create_variables({k: var}))
                indexes[k] = index
            else:
                variables[k] = var
        sizes = {}
        for var in variables.values():
            sizes.update(zip(var.dims, var.shape))
        return xr.Dataset._construct_direct(variables, set(coords), sizes, dict(attrs), indexes=indexes)
    except (AttributeError, TypeError, ImportError):  # pragma: no cover - an xarray without the fast path
        return xr.Dataset(data_vars, coords=coords, attrs=attrs)


def _attrs(max_iter, y0, v0):

    return {
        "title": "periodic sliding solutions in the (e, u) plane",
        "max_iter": max_iter,
        "y0": y0,
        "v0": v0,
        "kernel": "stairbounce.plane._scan_fast",
        "stairbounce_version": __version__,
        "convention": CONVENTION,
        "reference": "Campos, Romero-Valles, Torres, A fractal structure in a bouncing ball model, Section 3",
    }


_E_ATTRS = {"long_name": "restitution coefficient e"}
_U_ATTRS = {"long_name": "horizontal speed u (normalised units)"}


def scan_coords(e_values, u_values, max_iter=1000, y0=1.0, v0=0.0, *, prune=True):
    """scan_coords(e_values, u_values, max_iter=1000, y0=1.0, v0=0.0, *, prune=True) -> xarray.Dataset

    The scan of :func:`scan` on arbitrary 1-D coordinate arrays.

    Same kernel, same data variables and attributes as :func:`scan`, without
    the window bounds (the coordinates need not be evenly spaced).  Pixels are
    independent, so a tile cut out of a :func:`pixel_centres` grid gives the
    same values, bit for bit, as the whole scan.

    Parameters
    ----------
    e_values : 1-D array of floats in [0, 1)
    u_values : 1-D array of floats > 0
    max_iter, y0, v0, prune : as in :func:`scan`.
    """
    es = _coords("e", e_values)
    us = _coords("u", u_values)
    max_iter, y0, v0 = _check_run(max_iter, y0, v0)
    _check_memory(es.size, us.size)
    return with_speed(_scan_grid(es, us, max_iter, y0, v0, prune, {}), staircase_of(u_values))


def _scan_grid(es, us, max_iter, y0, v0, prune, window):
    """The scan of the grid ``us x es`` (checked) as a Dataset, the attributes ``window`` added."""
    out, _ = _run(es, us, True, max_iter, y0, v0, prune)
    shape = (us.size, es.size)
    data_vars = {
        k: (("u", "e"), out[k].reshape(shape), {"long_name": desc})
        for k, (_, desc) in _FIELDS.items()
    }
    coords = {"e": ("e", es, _E_ATTRS), "u": ("u", us, _U_ATTRS)}
    return _dataset(data_vars, coords, {**_attrs(max_iter, y0, v0), **window})


def scan_points(e, u, max_iter=1000, y0=1.0, v0=0.0, *, prune=True):
    """scan_points(e, u, max_iter=1000, y0=1.0, v0=0.0, *, prune=True) -> xarray.Dataset

    The scan of :func:`scan` at a list of arbitrary points ``(e[i], u[i])``.

    Same kernel (``_scan_fast``, its index-free path), same data variables,
    attributes and answers, bit for bit, as :func:`scan` and
    :func:`scan_coords` at the same coordinates, with one dimension
    ``point`` instead of ``("u", "e")``; ``e`` and ``u`` are coordinates
    along it.  Empty arrays give an empty dataset.

    Parameters
    ----------
    e : 1-D array of floats in [0, 1)
        Restitution coefficients of the points.
    u : 1-D array of floats > 0, the same length as ``e``
        Horizontal speeds of the points.
    max_iter, y0, v0, prune : as in :func:`scan`.

    Raises
    ------
    ValueError
        Arrays that are not 1-D or differ in length, a value out of range
        (naming it), outputs that would not fit in memory.

    Reference: Section 3 of the paper (the scheme of Figures 4 and 5, point by point).
    """
    # the outputs, contiguous copies of the inputs and their range checks
    _v.check_array_memory("a scan of {n} points", (e, u), _BYTES_PER_PIXEL + 16 + 20)
    es = _point_coords("e", e)
    us = _point_coords("u", u)
    if es.size != us.size:
        raise ValueError(f"e and u must have the same length, got {es.size} and {us.size}")
    max_iter, y0, v0 = _check_run(max_iter, y0, v0)
    _check_need(estimate_points_bytes(es.size), f"a scan of {es.size} points")
    out, _ = _run(es, us, False, max_iter, y0, v0, prune)
    data_vars = {k: (("point",), out[k], {"long_name": desc}) for k, (_, desc) in _FIELDS.items()}
    coords = {"e": ("point", es, _E_ATTRS), "u": ("point", us, _U_ATTRS)}
    return _dataset(data_vars, coords, _attrs(max_iter, y0, v0))


def scan(e=(0.0, 1.0, 500), u=(0.0, 1.5, 350), max_iter=1000, y0=1.0, v0=0.0, *, prune=True,
         progress=None):
    """scan(e=(e_min, e_max, n_e), u=(u_min, u_max, n_u), max_iter=1000, y0=1.0, v0=0.0, *, prune=True, progress=None) -> xarray.Dataset

    Periodic sliding solutions on an ``n_u x n_e`` grid of the (e, u) plane.

    At every pixel centre (:func:`pixel_centres`) the Poincare map (Prop. 2.3)
    is iterated with the sliding test (2.3)/(2.4) as stop criterion.  From
    ``(y0, v0) = (1, 0)`` the steps up to the first slide are one period of
    the periodic sliding solution.  From any other state the orbit is first
    iterated up to its first slide (a transient); the ball then leaves the edge
    at ``(1, 0)``, so the periodic sliding solution is the orbit of ``(1, 0)``
    and its period is measured from there until it slides again.  ``status``
    is 0 only when both happen, each within ``max_iter`` steps.

    Data variables (dims ``("u", "e")``): ``status`` (0 found, 1 not),
    ``word_length`` (impacts + 1), ``jumps`` (non-zero letters), ``period``
    (steps per period), ``impacts`` (finite impacts per period); all zero
    where ``status`` is 1.  Attributes record every input, the window, the
    package version and the word convention.

    Kernel: ``_scan_fast`` (the fast map of :func:`stairbounce.model._step`,
    several pixels in lockstep, interleaved over threads, pixels above the
    Corollary 2.1 curve answered without iterating); ``_scan_plain`` is the
    closed-form baseline, every pixel iterated, it is tested and benchmarked
    against.

    Parameters
    ----------
    e : (e_min, e_max, n_e) or (e_min, e_max), default (0, 1, 500)
        Image edges along e, within [0, 1] (pixel centres lie inside, < 1),
        and the pixels along e.
    u : (u_min, u_max, n_u) or (u_min, u_max), default (0, 1.5, 350)
        Image edges along u, u_min >= 0 (pixel centres lie inside, > 0).
        A count left out makes square pixels: 500 along the longer side of
        the window when both are left out, else the other axis's pixel size
        (:func:`square_counts`; the window convention of every function,
        docs/design.md).
    max_iter : int >= 1, default 1000
        Steps allowed for the transient and for the period, each.
    y0, v0 : float, default 1.0, 0.0
        Initial state at a step edge (y0 >= 0).
    prune : bool, default True
        Give status 1 without iterating to the pixels where Corollary 2.1
        proves it (:func:`prunable`: above the curve by a margin for
        rounding).  The dataset is the same, bit for bit, either way (so
        nothing in it records the choice); pass False only to iterate every
        pixel (e.g. timing the kernel, or code that wants the orbits' work
        done).
    progress : callable ``progress(rows_done, rows_total)``, optional
        When given, the rows are scanned in blocks (about 1/50 of the rows
        each; the values are the same, pixels are independent) and it is
        called after each block, and once with 0 before the first.

    Raises
    ------
    ValueError
        A bound or size out of range (naming it), or outputs that would not
        fit in the memory available (with the estimate).

    Reference: Section 3 of the paper (the scheme behind Figures 4 and 5).
    """
    (e_min, e_max, n_e), (u_min, u_max, n_u) = _windows(e, u)
    if progress is not None and not callable(progress):
        raise ValueError(f"progress must be None or a callable progress(done, total), got {progress!r}")
    # the outputs and the pixel centres (estimate_bytes counts both): the
    # memory available is read once (a read of /proc/meminfo is 10-40 us)
    _check_memory(n_e, n_u)
    es = _centres(e_min, e_max, n_e)
    us = _centres(u_min, u_max, n_u)
    window = dict(e_min=e_min, e_max=e_max, n_e=n_e, u_min=u_min, u_max=u_max, n_u=n_u)
    if progress is None:
        _check_centres(es, us)
        max_iter, y0, v0 = _check_run(max_iter, y0, v0)
        return with_speed(_scan_grid(es, us, max_iter, y0, v0, prune, window), staircase_of(u))
    else:
        progress(0, n_u)
        block = max(1, -(-n_u // 50))
        # blocks are copied into the whole arrays as they come: the peak stays
        # at the outputs plus one block (concatenating the blocks doubled it)
        full = first = None
        for r in range(0, n_u, block):
            part = scan_coords(es, us[r : r + block], max_iter, y0, v0, prune=prune)
            if first is None:
                first = part
                full = {k: np.empty((n_u, n_e), dtype=part[k].dtype) for k in _FIELDS}
            for k in _FIELDS:
                full[k][r : r + block] = part[k].values
            progress(min(r + block, n_u), n_u)
        ds = xr.Dataset(
            {k: (("u", "e"), full[k], first[k].attrs) for k in _FIELDS},
            coords={"e": first["e"], "u": ("u", us, first["u"].attrs)},
            attrs=first.attrs,
        )
    ds.attrs.update(window)
    return with_speed(ds, staircase_of(u))


def tongue_mask(e, u, n_max):
    """tongue_mask(e, u, n_max) -> np.ndarray of bool

    Theorem 3.1: where a periodic solution of type ``(n, 0^inf)`` exists for some n <= n_max.

    True where ``sqrt((n-1)/2) < u <= sqrt(n/2) (1-e)/(1+e)`` for some
    ``1 <= n <= n_max`` (inequalities (3.1), the bounds evaluated as in
    :func:`stairbounce.tongue`).  ``e`` and ``u`` broadcast against each other.
    """
    n_max = check_count("n_max", n_max, 1)
    e, u = _coords_any("e", e), _coords_any("u", u)
    try:
        shape = np.broadcast_shapes(e.shape, u.shape)
    except ValueError:
        raise ValueError(f"e and u must broadcast against each other, got shapes {e.shape} and {u.shape}") from None
    # the broadcast is a view; n, its tests and the float temporaries are not (about 6 floats a point)
    _v.check_memory(f"tongue_mask of {math.prod(shape)} points", 48 * math.prod(shape))
    e, u = np.broadcast_arrays(e, u)
    # u lies in at most one tongue: the last n with sqrt((n-1)/2) < u (the upper
    # bound grows with n), so one test per point, whatever n_max (report D12)
    n = np.minimum(np.maximum(np.ceil(2.0 * u * u), 1.0), n_max)
    n = np.where(np.sqrt((n - 1.0) / 2.0) < u, n, n - 1.0)
    n = np.where((n + 1.0 <= n_max) & (np.sqrt(n / 2.0) < u), n + 1.0, n)
    shrink = (1.0 - e) / (1.0 + e)
    return (n >= 1.0) & (np.sqrt((n - 1.0) / 2.0) < u) & (u <= np.sqrt(n / 2.0) * shrink)


def _coords_any(name, values):
    """``e`` or ``u`` values of any shape, checked as :func:`_coords` does."""
    a = _v.real_array(name, values)
    return _coords(name, a.ravel()).reshape(a.shape) if a.size else a


def no_sliding_curve(e):
    """no_sliding_curve(e) -> np.ndarray

    Corollary 2.1: above ``u = (1-e) / (2 sqrt(2e))`` no solution slides.

    Vectorised over ``e`` in [0, 1]; infinite at ``e = 0``, 0 at ``e = 1``.
    """
    # a float copy, its range checks and the curve
    _v.check_array_memory("no_sliding_curve of {n} values of e", e, 8 + 4 + 8)
    e = _v.real_array("e", e)
    # the curve is drawn over the closed window [0, 1]: e = 1 (u = 0) is its end
    if not np.all(np.isfinite(e) & (e >= 0.0) & (e <= 1.0)):
        raise ValueError(f"e (restitution coefficient) values must be finite and in [0, 1], got {e!r}")
    with np.errstate(divide="ignore"):
        return (1.0 - e) / (2.0 * np.sqrt(2.0 * e))


def prunable(e, u, y0=1.0, v0=0.0):
    """prunable(e, u, y0=1.0, v0=0.0) -> np.ndarray of bool

    The pixels a scan with ``prune=True`` answers without iterating: status 1 by Corollary 2.1.

    True where ``u`` lies above the bound ``(1-e)/(2 sqrt(2e))`` of
    Corollary 2.1 by more than the relative margin that covers rounding
    (``_never_slides``: ``2**-30`` plus ``2**-44`` times the size of the
    numbers the map handles, so about 1e-9 on the paper's plane).  Never on
    the curve itself (equality in (2.4) slides, docs/design.md), never at
    ``e = 0``.  For any start ``(y0, v0)``: its first step may slide (when
    ``y0 < 1``), but the orbit of ``(1, 0)`` cannot.  ``e`` and ``u``
    broadcast.
    """
    y0 = _finite("y0", y0)
    v0 = _finite("v0", v0)
    e, u = np.broadcast_arrays(np.asarray(e, dtype=np.float64), np.asarray(u, dtype=np.float64))
    shape = e.shape
    # copies: broadcast views warn when their flags are read (_check_values reads them)
    es = np.array(e.ravel())
    us = np.array(u.ravel())
    if es.size:
        _check_values("e", es)
        _check_values("u", us)
    out = np.empty(es.size, dtype=np.bool_)
    _prunable(es, us, y0 + v0 * v0, out)
    return out.reshape(shape)


# --------------------------------------------------------------------------- #
# Files                                                                       #
# --------------------------------------------------------------------------- #


def _format(path):
    s = str(path).rstrip("/")
    if s.endswith(".zarr"):
        return "zarr"
    if s.endswith(".nc"):
        return "nc"
    raise ValueError(f"path must end in .zarr or .nc, got {str(path)!r}")


def save(ds, path, chunks=256, overwrite=False):
    """save(ds, path, chunks=256, overwrite=False) -> None

    Write a scan to ``.zarr`` (chunked ``chunks x chunks``) or ``.nc`` (netCDF4,
    compressed), atomically: under a temporary name, renamed when complete.

    An existing ``path`` is replaced only with ``overwrite=True``, and an
    existing folder only when it is a store this package wrote
    (:func:`stairbounce._io.atomic_path`); otherwise ``ValueError`` names it.
    In a Zarr store a chunk that is missing reads as :data:`FILL_VALUES`
    (status 255, counts -1), never as a valid result.
    """
    from ._io import atomic_path, write_shielded

    fmt = _format(path)
    chunks = check_count("chunks", chunks, 1)
    with atomic_path(path, overwrite=overwrite) as tmp:
        if fmt == "zarr":
            enc = {
                k: {"chunks": tuple(min(chunks, s) for s in ds[k].shape)}
                for k in ds.data_vars
            }
            for k in enc:
                if k in FILL_VALUES and ds[k].dtype == _FIELDS[k][0]:
                    enc[k]["fill_value"] = FILL_VALUES[k]
            write_shielded(lambda: ds.to_zarr(tmp, mode="w", encoding=enc, consolidated=False), tmp)
        else:
            enc = {k: {"zlib": True, "complevel": 4} for k in ds.data_vars}
            write_shielded(lambda: ds.to_netcdf(tmp, engine="netcdf4", format="NETCDF4", encoding=enc), tmp)


def load(path):
    """load(path) -> xarray.Dataset

    Read a scan written by :func:`save` (``.zarr`` or ``.nc``) into memory.

    A tiled store (:func:`stairbounce.atlas.scan_to_zarr`) reads the same way;
    where a tile is not computed yet (or a chunk was deleted) it reads as
    :data:`FILL_VALUES` (status 255), never as a result.  A file or chunk that
    cannot be decoded raises ``ValueError`` naming the file.
    """
    fmt = _format(path)
    if not os.path.exists(path):
        raise ValueError(f"no such file: {path}")
    if fmt == "zarr":
        from ._io import check_store_metadata

        check_store_metadata(path)
    engine = "zarr" if fmt == "zarr" else "netcdf4"
    kw = {"consolidated": False} if fmt == "zarr" else {}
    try:
        with xr.open_dataset(path, engine=engine, chunks=None, **kw) as ds:
            ds = ds.load()
    except (OSError, RuntimeError, ValueError, KeyError, TypeError) as exc:
        # a damaged file or chunk (a decompression error, a truncated file):
        # one line naming the file, not the reader's traceback
        reason = " ".join(str(exc).split()) or type(exc).__name__
        raise ValueError(f"cannot read {path} as a scan ({type(exc).__name__}: {reason})") from None
    _check_grid(ds, path)
    return ds


def _check_grid(ds, source):
    """_check_grid(ds, source) -> None

    Refuse a scan whose ``e``/``u`` coordinates are not the pixel centres of
    the window its attributes record (``e_min``, ``e_max``, ``n_e``; a part
    of a window, of another length, is checked for finite values only): the
    coordinates of a store are outside its tiles' checksums, and a deleted or
    rewritten chunk of them read as nan or as another window (report N2).
    ``ValueError`` names ``source`` and the coordinate.
    """
    for name in ("e", "u"):
        if name not in ds.coords or ds[name].ndim != 1:
            continue
        c = np.asarray(ds[name].values)
        if c.dtype.kind != "f":
            continue
        if not np.all(np.isfinite(c)):
            raise ValueError(f"cannot read {source} as a scan: its {name} coordinates are damaged (not "
                             "finite); a tiled store repairs them when its scan is run again")
        a = ds.attrs
        keys = (f"{name}_min", f"{name}_max", f"n_{name}")
        if all(k in a for k in keys) and c.size == a[keys[2]]:
            try:
                want = pixel_centres(float(a[keys[0]]), float(a[keys[1]]), int(a[keys[2]]))
            except (TypeError, ValueError):
                continue
            if not np.array_equal(c, want):
                raise ValueError(
                    f"cannot read {source} as a scan: its {name} coordinates do not match its window "
                    f"[{a[keys[0]]}, {a[keys[1]]}] of {a[keys[2]]} pixels (damaged); a tiled store "
                    "repairs them when its scan is run again"
                )
