"""Itineraries and margins: the event kernels of the plane's structure.

The itinerary of a point is the list of impact numbers ``k_1, k_2, ...`` of
the steps from ``(y0, v0)`` (the departure at ``(1, 0)`` by default) up to the
first slide (:func:`itinerary`).  Along a fixed itinerary every event of a
step is measured by a signed time margin ``T - t_event`` (>= 0: the event
happens on the step, before or at its edge), with the arithmetic of
:func:`stairbounce.model._step`, so the margins' signs reproduce the impact
numbers: :func:`_margin` (one event of one step, for the bisection of
borders, :mod:`.borders`), :func:`_margins` (every margin of a word's region
with its derivatives, for the continuation, :mod:`.continuation`), and the
compiled itineraries the scans of words share (:func:`_itinerary_of`,
:func:`_hash_itinerary`, :func:`_words_grid`).  The event codes
``GRAZE, EDGE, CHATTER`` index ``KINDS``.

Nothing here imports matplotlib, Typer or the web stack.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr
from numba import njit, prange

from .. import _validate as _v
from ..model import (
    _COUNTED_IMPACTS,
    SLIDING,
    _constants,
    _geometric,
    _impact_time_log,
    _step,
    check_count,
    check_e,
    check_state,
    check_u,
)

__all__ = ["itinerary"]


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
    Stops at the first step that differs; returns ``(follows, steps done)``."""
    T, ratio = _constants(e, u)
    y, v = 1.0, 0.0
    for n in range(p):
        y, v, k = _step(y, v, e, T, ratio)
        if k != ref[n]:
            return False, n + 1
    return True, p


# --------------------------------------------------------------------------- #
# Public API                                                                  #
# --------------------------------------------------------------------------- #


def _check_max_iter(max_iter):
    max_iter = check_count("max_iter", max_iter, 1)
    if max_iter > 2**31 - 1:
        raise ValueError(f"max_iter must be an integer in [1, 2**31 - 1], got {max_iter}")
    return max_iter


_ITINERARY_NAMES = ("impacts", "y", "v", "contact", "next_impact", "accumulation")
_ITINERARY_BYTES = 8 * (len(_ITINERARY_NAMES) + 2)  # per step, at the peak of itinerary()


def _itinerary_args(e, u, max_iter, y0, v0):
    """The arguments of :func:`itinerary`, checked (ValueError naming one)."""
    e = check_e(e)
    u = check_u(u)
    max_iter = _check_max_iter(max_iter)
    y0, v0 = check_state(y0, v0, "y0", "v0")
    return e, u, max_iter, y0, v0


def _itinerary_blocks(e, u, max_iter, y0, v0):
    """The steps of :func:`itinerary` (checked arguments, :func:`_itinerary_args`)
    in blocks of at most 65536: yields ``(block, slid)``, ``block`` a dict of
    the columns of those steps, ``slid`` whether the last of them slides.
    Memory: one block, whatever ``max_iter`` (the command line streams them)."""
    T, ratio = _constants(e, u)
    y, v, left, slid = y0, v0, max_iter, False
    while left > 0 and not slid:
        m = min(left, _BLOCK)
        block = {k: np.empty(m, dtype=np.int64 if k == "impacts" else np.float64) for k in _ITINERARY_NAMES}
        n, y, v, slid = _itinerary_block(y, v, e, T, ratio, m, *(block[k] for k in _ITINERARY_NAMES))
        left -= n
        yield {k: a[:n] for k, a in block.items()}, slid


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
        A parameter out of its range (naming it), or a ``max_iter`` whose
        itinerary could need more memory than is available (64 bytes a
        step; checked before it starts).
    """
    e, u, max_iter, y0, v0 = _itinerary_args(e, u, max_iter, y0, v0)
    # estimated before it starts (report round 3, R5: checked block by block against the
    # memory left, it refused at half the machine): 6 columns, the step numbers, and one
    # column at a time copied out of the blocks
    _v.check_memory(f"max_iter = {max_iter}: an itinerary of up to {max_iter} steps", _ITINERARY_BYTES * max_iter)
    parts = {k: [] for k in _ITINERARY_NAMES}
    slid = False
    for block, slid in _itinerary_blocks(e, u, max_iter, y0, v0):
        for k in _ITINERARY_NAMES:
            parts[k].append(block[k])
    data = {}
    for k in _ITINERARY_NAMES:
        data[k] = np.concatenate(parts.pop(k))
    steps = np.arange(1, data["impacts"].size + 1, dtype=np.int64)
    names = _ITINERARY_NAMES
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

# --------------------------------------------------------------------------- #
# Compiled margins along a prescribed itinerary                                #
# --------------------------------------------------------------------------- #


@njit(cache=True)
def _margins(e, u, y0, v0, ks, nsteps, win, g, ge, gu):
    """Every margin of the itinerary ``ks[:nsteps]`` and of the window at (e, u).

    Fills ``g[2j]`` (lower) and ``g[2j+1]`` (upper) for step ``j+1``, with
    ``ge``, ``gu`` their derivatives in e and u, and ``g[2n..2n+3]`` the window
    margins ``e - e_lo``, ``e_hi - e``, ``u - u_lo``, ``u_hi - u``.  The point
    belongs to the itinerary's region iff every lower margin is >= 0 and every
    upper margin is > 0 (exactly :func:`model._step`'s decisions):

    - ``k = 0``: upper ``t_1 - T`` (it flies over iff ``t_1 > T``), no lower;
    - ``1 <= k``: lower ``T - t_k``, upper ``t_{k+1} - T`` (``t`` summed along
      the geometric series as ``_step`` does, closed form past
      ``_COUNTED_IMPACTS`` impacts as ``_step_closed`` does);
    - ``SLIDING``: lower ``T - (v + (1+e)/(1-e) s)`` (the test (2.4)), no upper.

    A missing margin is +inf.  Returns the number of steps evaluated: less than
    ``nsteps`` when the prescribed itinerary leaves the domain (a negative
    ``v^2 + 2y``); the margins of the remaining steps are then NaN.
    """
    T, ratio = _constants(e, u)
    Tu = -T * T
    re_ = 2.0 / ((1.0 - e) * (1.0 - e))
    log_e = math.log(e) if e > 0.0 else -math.inf
    y, v = y0, v0
    ye = 0.0
    yu = 0.0
    ve = 0.0
    vu = 0.0
    m = 2 * nsteps
    g[m] = e - win[0]
    ge[m] = 1.0
    gu[m] = 0.0
    g[m + 1] = win[1] - e
    ge[m + 1] = -1.0
    gu[m + 1] = 0.0
    g[m + 2] = u - win[2]
    ge[m + 2] = 0.0
    gu[m + 2] = 1.0
    g[m + 3] = win[3] - u
    ge[m + 3] = 0.0
    gu[m + 3] = -1.0
    for j in range(nsteps):
        k = ks[j]
        q = v * v + 2.0 * y
        if not q >= 0.0 or (q == 0.0 and k != 0):
            for i in range(2 * j, m):
                g[i] = math.nan
                ge[i] = math.nan
                gu[i] = math.nan
            return j
        s = math.sqrt(q)
        se = (v * ve + ye) / s if s > 0.0 else 0.0
        su = (v * vu + yu) / s if s > 0.0 else 0.0
        lo = 2 * j
        hi = lo + 1
        if k == SLIDING:
            c = v + ratio * s
            g[lo] = T - c
            ge[lo] = -(ve + re_ * s + ratio * se)
            gu[lo] = Tu - (vu + ratio * su)
            g[hi] = math.inf
            ge[hi] = 0.0
            gu[hi] = 0.0
            y, v = 1.0, 0.0
            ye = yu = ve = vu = 0.0
            continue
        t = v + s
        te = ve + se
        tu = vu + su
        if k == 0:
            g[lo] = math.inf
            ge[lo] = 0.0
            gu[lo] = 0.0
            g[hi] = t - T
            ge[hi] = te
            gu[hi] = tu - Tu
            ny = y + v * T - 0.5 * T * T + 1.0
            nye = ye + ve * T
            nyu = yu + vu * T + v * Tu - T * Tu
            v = v - T
            vu = vu - Tu
            y, ye, yu = ny, nye, nyu
            continue
        # k >= 1: the bounces along the geometric series, as _step counts them
        w = e * s
        we = s + e * se
        wu = e * su
        kk = min(k, _COUNTED_IMPACTS)
        for _ in range(kk - 1):
            t = t + 2.0 * w
            te = te + 2.0 * we
            tu = tu + 2.0 * wu
            we = w + e * we
            wu = e * wu
            w *= e
        # lower margin: t_k (t_8 of the loop when k = 8, as _step decides 7 <-> 8)
        g[lo] = T - t
        ge[lo] = -te
        gu[lo] = Tu - tu
        if k < _COUNTED_IMPACTS:
            nt = t + 2.0 * w
            g[hi] = nt - T
            ge[hi] = te + 2.0 * we
            gu[hi] = tu + 2.0 * wu - Tu
            d = T - t
            de = -te
            du = Tu - tu
        else:
            # _step_closed: closed forms of eq. (2.2) with G(n) = (1 - e^n)/(1 - e)
            G = _geometric(e, k - 1, log_e)
            Ge = (G - (k - 1) * math.pow(e, float(k - 2))) / (1.0 - e)
            tk = _impact_time_log(v, s, e, k, log_e)
            tke = ve + se * (1.0 + 2.0 * e * G) + 2.0 * s * (G + e * Ge)
            tku = vu + su * (1.0 + 2.0 * e * G)
            if k > _COUNTED_IMPACTS:
                g[lo] = T - tk
                ge[lo] = -tke
                gu[lo] = Tu - tku
            G1 = _geometric(e, k, log_e)
            G1e = (G1 - k * math.pow(e, float(k - 1))) / (1.0 - e)
            g[hi] = _impact_time_log(v, s, e, k + 1, log_e) - T
            ge[hi] = ve + se * (1.0 + 2.0 * e * G1) + 2.0 * s * (G1 + e * G1e)
            gu[hi] = vu + su * (1.0 + 2.0 * e * G1) - Tu
            ek = math.pow(e, float(k))
            w = ek * s
            we = k * math.pow(e, float(k - 1)) * s + ek * se
            wu = ek * su
            d = min(max(T - tk, 0.0), 2.0 * w)
            de = -tke
            du = Tu - tku
        ny = -0.5 * d * d + w * d + 1.0
        nye = -d * de + we * d + w * de
        nyu = -d * du + wu * d + w * du
        v = w - d
        ve = we - de
        vu = wu - du
        y, ye, yu = ny, nye, nyu
    return nsteps


@njit(cache=True)
def _itinerary_of(e, u, y0, v0, max_iter, ks):
    """Impact numbers from (y0, v0) with :func:`model._step` until the slide:
    fills ``ks`` and returns the step count (the sliding step included), or
    ``-max_iter`` when it does not slide within ``max_iter`` steps."""
    T, ratio = _constants(e, u)
    y, v = y0, v0
    for n in range(max_iter):
        y, v, k = _step(y, v, e, T, ratio)
        ks[n] = k
        if k == SLIDING:
            return n + 1
    return -max_iter


@njit(cache=True, parallel=True)
def _words_grid(es, us, y0, v0, max_iter, h1, h2, steps):
    """Two independent 64-bit hashes of every pixel's itinerary (0, 0 and steps 0
    when it does not slide within max_iter): the word labels of a small scan.
    Rows in parallel, each pixel independent of the others."""
    for i in prange(us.size):
        ks = np.empty(max_iter, dtype=np.int64)
        for j in range(es.size):
            n = _itinerary_of(es[j], us[i], y0, v0, max_iter, ks)
            if n <= 0:
                h1[i, j] = 0
                h2[i, j] = 0
                steps[i, j] = 0
                continue
            h1[i, j], h2[i, j] = _hash_itinerary(ks, n)
            steps[i, j] = n


@njit(cache=True)
def _hash_itinerary(ks, n):
    """Two independent 64-bit hashes of ``ks[:n]`` (the word labels of a scan)."""
    a = np.uint64(1469598103934665603)
    b = np.uint64(7)
    for t in range(n):
        x = np.uint64(ks[t] + 2)
        a = (a ^ x) * np.uint64(1099511628211)
        b = b * np.uint64(6364136223846793005) + x * np.uint64(1442695040888963407)
    return a | np.uint64(1), b
