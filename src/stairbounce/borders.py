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
from numba import njit

from . import _validate as _v
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
