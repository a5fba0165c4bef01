"""The paper's closed forms: one step of the staircase, edge to edge.

Normalised units (docs/design.md): step height = step length = g = 1, restitution
``e`` in [0, 1), horizontal speed ``u > 0``, so one step takes ``T = 1/u``.
The state at a step edge is ``(y, v)``: the height above the floor of the step
the ball is entering and the vertical velocity.

Everything the numba kernels of :mod:`stairbounce.plane` and
:mod:`stairbounce.orbits` need is a ``@njit`` scalar function here (names with a
leading underscore, taking the per-parameter constants ``T = 1/u`` and
``ratio = (1+e)/(1-e)`` precomputed).  The public functions validate their
input, raise :class:`ValueError` naming the parameter and its allowed range, and
call the same compiled functions, so Python and the kernels share one
implementation of the map.

References are to Campos, Romero-Valles and Torres, "A fractal structure in a
bouncing ball model" (the paper), and its reference [1]: Campos,
Romero-Valles, Torres and Veerman, Chaos, Solitons & Fractals 32 (2007) 415-426.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from . import _validate as _v
from ._validate import Real

__all__ = [
    "SLIDING",
    "poincare_map",
    "slides",
    "impact_number",
    "impact_times",
    "no_sliding_bound",
    "tongue",
    "iterate",
]

SLIDING = -1
"""Impact number of a step on which the impacts accumulate (Prop. 2.1)."""

# Impacts on one step are first counted one by one (one multiply-add each); past
# this many the closed form of Prop. 2.2 takes over.  Most steps of the paper's
# parameter plane have 0, 1 or 2 impacts.
_COUNTED_IMPACTS = 8


# --------------------------------------------------------------------------- #
# Compiled scalar functions (one source of truth for Python and the kernels)   #
# --------------------------------------------------------------------------- #


@njit(cache=True)
def _constants(e, u):
    """Per-parameter constants ``(T, ratio) = (1/u, (1+e)/(1-e))``."""
    return 1.0 / u, (1.0 + e) / (1.0 - e)


@njit(cache=True)
def _impact_speed(y, v):
    """Speed at the first impact on the floor, ``sqrt(v^2 + 2y)`` (eq. 2.1)."""
    return math.sqrt(v * v + 2.0 * y)


@njit(cache=True)
def _slides(y, v, T, ratio):
    """Prop. 2.1 in the form (2.4): ``v + (1+e)/(1-e) sqrt(v^2+2y) <= T``.

    Equality counts as sliding (docs/design.md).
    """
    return v + ratio * math.sqrt(v * v + 2.0 * y) <= T


@njit(cache=True)
def _geometric(e, n, log_e):
    """``1 + e + ... + e^(n-1) = (1 - e^n)/(1 - e)`` without cancellation.

    ``1 - e^n = -expm1(n log e)`` with ``log_e = log(e)``, accurate to an ulp
    for the float ``e`` itself (even one ulp below 1); ``expm1`` keeps every
    digit of ``1 - e^n`` where ``e^n`` is close to 1, which is where
    ``1 - e^n`` written out loses them all (e near 1, reliability report D4).
    At ``e = 0`` (``log_e = -inf``) it is 1 for every n >= 1.
    """
    if n <= 0:
        return 0.0
    return -math.expm1(n * log_e) / (1.0 - e)


@njit(cache=True)
def _impact_time(v, s, e, k):
    """Eq. (2.2), ``t_k = v + (1+e-2e^k)/(1-e) s``, evaluated without cancellation.

    ``(1+e-2e^k)/(1-e) = 1 + 2e (1 - e^(k-1))/(1-e)``, so
    ``t_k = t_1 + 2 e s G(k-1)`` with the first impact ``t_1 = v + s`` and the
    geometric sum :func:`_geometric`: every term is >= 0, the relative error is
    a few ulp for every ``e`` in [0, 1) and every k (the form of eq. (2.2)
    itself has a relative error of about eps/(1-e)).
    """
    return _impact_time_log(v, s, e, k, math.log(e) if e > 0.0 else -math.inf)


@njit(cache=True)
def _impact_time_log(v, s, e, k, log_e):
    """:func:`_impact_time` with ``log e`` given (computed once per step)."""
    return v + s + 2.0 * e * s * _geometric(e, k - 1, log_e)


@njit(cache=True)
def _impact_velocity(s, e, k):
    """Eq. (2.2): the velocity after the k-th impact, ``v_k = e^k s``.

    ``math.pow`` is correctly rounded to about an ulp for any k; repeated
    squaring (what ``e ** k`` with an integer k may compile to) loses about
    ``log2 k`` bits.
    """
    return math.pow(e, float(k)) * s


# The impact number never exceeds log(2^-53) / log(1 - 2^-53) < 3.4e17 < 2^63
# (below): no cap is needed, and k fits an int64 with room to spare.
_MAX_IMPACTS = 3.4e17


@njit(cache=True)
def _impact_number_closed(y, v, e, T):
    """Prop. 2.2, ``k = E[log_e(((v - T)(1-e)) / (2 s) + (1+e)/2)]``.

    Returns ``SLIDING`` when the argument of the logarithm is not positive
    (the solution slides, docs/design.md).  The argument is ``1 - q`` with
    ``q = (1-e)(T - v + s)/(2s)``, a product of non-negative factors, and the
    logarithm is taken as ``log1p(-q)``: written as in the paper the argument
    rounds to an absolute error of eps, a relative error of eps/q in the
    logarithm (report D4).  Since ``q < 1`` is a float, ``1 - q >= 2^-53`` and
    ``k <= 36.8 / |log e| < 3.4e17`` for every float ``e < 1``.

    The floor of a rounded logarithm can be one off; the result is corrected
    so that ``t_k <= T < t_{k+1}`` holds with the impact times of
    :func:`_impact_time`, which is the definition in the proof.
    """
    s = math.sqrt(v * v + 2.0 * y)
    if v + s > T:  # first impact after the edge: the ball flies over
        return 0
    if e == 0.0:  # plastic impact: it sticks at its first contact
        return SLIDING
    return _impacts_and_time(v, s, e, T, math.log(e), None, 0)[0]


# Values kept per pixel by the scan's lanes (``memo``, a float array of
# _MEMO_SIZE, -1 where nothing is kept): [0] the last impact number k of a
# closed-form step and [1] its e^k; then _MEMO_SLOTS slots of G(n) (tag n,
# value) and of e^n, direct-mapped by n mod _MEMO_SLOTS.  An orbit's many-
# impact steps keep to a narrow band of k (on the paper's grid 99.6 % of the
# G values and 99.7 % of the powers are found kept with 8 slots, 50 % with
# the one-per-parity memo this replaces).
_MEMO_SLOTS = 8
_MEMO_SIZE = 2 + 4 * _MEMO_SLOTS
# Tags are floats: only impact numbers below 2^52 are kept (exact as floats)
_MEMO_N_MAX = 2**52


@njit(cache=True, inline="always")
def _geometric_memo(e, n, log_e, memo, base):
    """:func:`_geometric`, or with ``memo`` (not None) its value kept from an earlier call.

    ``memo``: the values kept for one ``e`` (layout at ``_MEMO_SIZE``).  The
    kept value is the one :func:`_geometric` computed, so the answer is the
    same bits either way; it saves the ``expm1``.
    """
    if memo is None or n >= _MEMO_N_MAX:
        return _geometric(e, n, log_e)
    slot = 2 + (n & (_MEMO_SLOTS - 1))
    if memo[base + slot] == n:
        return memo[base + slot + _MEMO_SLOTS]
    g = _geometric(e, n, log_e)
    memo[base + slot] = n
    memo[base + slot + _MEMO_SLOTS] = g
    return g


@njit(cache=True, inline="always")
def _power_slot(k):
    """Where ``memo`` keeps ``k`` (a tag) for ``e^k`` (``_MEMO_SLOTS`` further on)."""
    return 2 + 2 * _MEMO_SLOTS + (k & (_MEMO_SLOTS - 1))


@njit(cache=True, inline="always")
def _power_memo(s, e, k, memo, base):
    """:func:`_impact_velocity`, with ``e^k`` kept in ``memo`` (:func:`_geometric_memo`);
    ``k`` and ``e^k`` become the kept impact number ``memo[0:2]`` (from ``base``)."""
    if memo is None:
        return _impact_velocity(s, e, k)
    if k >= _MEMO_N_MAX:
        memo[base + 0] = -1.0
        return _impact_velocity(s, e, k)
    slot = _power_slot(k)
    if memo[base + slot] != k:
        memo[base + slot] = k
        memo[base + slot + _MEMO_SLOTS] = math.pow(e, float(k))
    p = memo[base + slot + _MEMO_SLOTS]
    memo[base + 0] = k
    memo[base + 1] = p
    return p * s


@njit(cache=True, inline="always")
def _impact_time_memo(v, s, e, k, log_e, memo, base):
    """:func:`_impact_time_log` through :func:`_geometric_memo` (the same operations)."""
    return v + s + 2.0 * e * s * _geometric_memo(e, k - 1, log_e, memo, base)


# Bounds of the kept-k shortcut (_impacts_kept): the speed e^(k+2) s of a
# late bounce against the size of the impact times, and e^(k+3) |log e|, must
# exceed this; and k at most _KEPT_K_MAX.  The proof needs 2^-45 and 2^-12.
_KEPT_MARGIN = 2.0**-40
_KEPT_K_MAX = 2.0**20


@njit(cache=True)
def _impacts_and_time(v, s, e, T, log_e, memo, base):
    """The impact number ``k`` of :func:`_impact_number_closed` and ``t_k``, given
    ``s``, ``log_e = log(e)``, ``e > 0`` and a first impact before the edge
    (``v + s <= T``); ``(SLIDING, 0)`` where the logarithm's argument is not
    positive.  ``t_k`` is the value :func:`_impact_time` gives: the one the
    correction loop computed for the final ``k`` when it did, so it is not
    computed twice.  ``memo``: None, or the values kept for this ``e``
    (:func:`_geometric_memo`); with a memo, the impact number kept in it is
    tried first (:func:`_impacts_kept`), which gives the same answer where
    it answers at all.
    """
    if memo is not None:
        k, t = _impacts_kept(v, s, e, T, log_e, memo, base)
        if k > 0:
            return k, t
        k, t = _impacts_and_time_log(v, s, e, T, log_e, memo, base)
        if k >= 3:  # keep what the kept path will ask for next time
            for n in range(k - 3, k + 3):
                _geometric_memo(e, n, log_e, memo, base)
        return k, t
    return _impacts_and_time_log(v, s, e, T, log_e, memo, base)


@njit(cache=True, inline="always")
def _kept_g(n, memo, base):
    """``(G(n), found)``: the value kept for ``n`` in ``memo``'s slots (:func:`_geometric_memo`)."""
    slot = 2 + (n & (_MEMO_SLOTS - 1))
    return memo[base + slot + _MEMO_SLOTS], memo[base + slot] == n


# inlined: the scan's lanes call it in a loop of their own (plane._kept_pass),
# where a call per lane cost more than the work
@njit(cache=True, inline="always")
def _impacts_kept(v, s, e, T, log_e, memo, base):
    """The answer of :func:`_impacts_and_time_log` without its logarithm, or ``(0, 0)``.

    The impact number ``k`` kept in ``memo[0]`` (the last one of this pixel's
    closed-form steps, with ``e^k`` in ``memo[1]``; indices from ``base``) and its neighbours
    ``k - 1`` and ``k + 1`` are tried, without a branch: ``j`` among them
    with ``tau(j) <= T < tau(j+1)`` (``tau``: the computed impact times of
    :func:`_impact_time_memo`, the ones the correction loop compares, from
    the values ``G(k-2) .. G(k+1)`` kept in ``memo``) is returned with
    ``tau(j)``, provided ``3 <= k <= 2^20``, ``e^(k+2) s >= 2^-40 (T + |v| + s)``
    and ``e^(k+3) |log e| >= 2^-40``.  Otherwise (or when a value is not
    kept) ``(0, 0)``, and the caller takes the logarithm.

    Why it is the same answer (exact arithmetic on the floats v, s, e, T,
    eps = 2^-53; the error bounds of expm1, log1p, log and pow are an ulp;
    the bounds above imply ``e^(j+1) s >= 2^-40 (T + |v| + s)`` and
    ``e^(j+2) |log e| >= 2^-40``):

    1. Every computed time is close: for the i the correction loop can
       visit (within 7 of j), ``|tau(i) - t*(i)| <= 2^8 eps (T + |v| + s)``
       = ``E``, with ``t*(i) = v + s + 2 e s (1 - e^(i-1))/(1-e)`` exact
       (``expm1`` of ``(i-1) log e`` has a relative error of at most 3 eps from
       its argument, as ``x e^x/(1 - e^x) <= 1``, and 2 eps of its own).
    2. The gaps are wide: ``t*(i+1) - t*(i) = 2 e^i s``, and
       ``e^(j+1) s >= 2^-40 (...) > E``.  So from ``tau(j) <= T < tau(j+1)``,
       ``tau(i) <= T`` for every ``i < j`` and ``tau(i) > T`` for every
       ``i > j + 1``: along the loop's path the test ``tau(i) <= T`` is the
       step function ``i <= j``; and the exact impact number ``k*``
       (``t*(k*) <= T < t*(k*+1)``) is ``j - 1``, ``j`` or ``j + 1``.
    3. The logarithm's start is close: ``k* = floor(L*)``,
       ``L* = log(1 - q*)/log e`` with ``1 - q* = e^(L*) >= e^(j+2)``.  The
       computed ``q`` has a relative error of at most 5 eps, so the computed
       ``L`` is within ``6 eps L* + 5.1 eps / ((1 - q*) |log e|)`` of ``L*``:
       below ``1.4e-9 + 6e-4`` by ``j <= 2^20 + 1`` and
       ``e^(j+2) |log e| >= 2^-40``.  So the loop starts within 2 of ``j``
       (the clamp to ``[1, ...]`` only moves it towards ``j >= 1``), and
       ``q < 1``.
    4. The loop of :func:`_impacts_and_time_log` moves one step per pass
       towards the step of the function in 2 and stops there: from a start
       within 3 of ``j`` its four passes end at ``j``.

    ``tests/test_kernel_paths.py`` compares the two on millions of states,
    with kept numbers right, one off and far off, near e = 1 and near the
    bounds.
    """
    kf = memo[base + 0]
    if not (kf >= 3.0 and kf <= _KEPT_K_MAX):  # nothing kept (-1), or out of the bounds
        return 0, 0.0
    k = int(kf)
    gm, f0 = _kept_g(k - 2, memo, base)
    g0, f1 = _kept_g(k - 1, memo, base)
    g1, f2 = _kept_g(k, memo, base)
    g2, f3 = _kept_g(k + 1, memo, base)
    big = memo[base + 1] * e * e
    ok = (f0 and f1 and f2 and f3 and big * s >= _KEPT_MARGIN * (T + abs(v) + s)
          and big * e * (-log_e) >= _KEPT_MARGIN)
    # the operations of _impact_time_memo: (v + s) + ((2 e) s) G
    a = v + s
    b = 2.0 * e * s
    tm = a + b * gm
    t0 = a + b * g0
    t1 = a + b * g1
    t2 = a + b * g2
    cm = tm <= T
    c0 = t0 <= T
    c1 = t1 <= T
    c2 = t2 <= T
    j = k if (c0 and not c1) else (k - 1 if (cm and not c0) else (k + 1 if (c1 and not c2) else 0))
    t = t0 if j == k else (tm if j == k - 1 else t1)
    return (j, t) if ok else (0, 0.0)


@njit(cache=True)
def _impacts_and_time_log(v, s, e, T, log_e, memo, base):
    """:func:`_impacts_and_time` by the logarithm of Prop. 2.2 and the correction loop."""
    q = (1.0 - e) * ((T - v + s) / (2.0 * s))
    if q >= 1.0:
        return SLIDING, 0.0
    kf = math.floor(math.log1p(-q) / log_e)
    k = max(int(min(kf, _MAX_IMPACTS)), 1)
    # rounding of log: move k until t_k <= T < t_{k+1}, a step or two at most
    # wherever the bounces are longer than the rounding of t_k (elsewhere k is
    # only known to a relative 1e-15, and so is the answer's phase)
    known, t_known = 0, 0.0  # the last impact time computed, and its index
    for _ in range(4):
        if k > 1:
            t = _impact_time_memo(v, s, e, k, log_e, memo, base)
            known, t_known = k, t
            if t > T:
                k -= 1
                continue
        t = _impact_time_memo(v, s, e, k + 1, log_e, memo, base)
        known, t_known = k + 1, t
        if t <= T:
            k += 1
        else:
            break
    return k, (t_known if known == k else _impact_time_memo(v, s, e, k, log_e, memo, base))


@njit(cache=True)
def _step_closed(y, v, e, T, ratio):
    """Prop. 2.3, the Poincare map with the impact number of Prop. 2.2.

    The plain closed-form evaluation: log and pow on every step with impacts.
    :func:`_step` gives the same map faster; both are tested against the
    impact-by-impact loop of ``tests/naive.py`` and against a 60-digit
    reference (``tests/test_precision.py``).
    """
    return _step_closed_log(y, v, e, T, ratio, math.log(e) if e > 0.0 else -math.inf, None, 0)


@njit(cache=True)
def _step_closed_log(y, v, e, T, ratio, log_e, memo, base):
    """:func:`_step_closed` with ``log_e = log(e)`` given (a kernel computes it once per pixel).

    The same operations on the same values, so the same bits, with ``t_k``
    taken from the correction loop of the impact number
    (:func:`_impacts_and_time`) instead of computed again, and with
    ``memo`` (None, or an array of ``_MEMO_SIZE`` kept for this ``e``, -1
    when new) the values ``expm1`` and ``pow`` gave at the same impact
    numbers before (:func:`_geometric_memo`) and the last impact number,
    tried first (:func:`_impacts_kept`).
    """
    if _slides(y, v, T, ratio):
        return 1.0, 0.0, SLIDING
    s = math.sqrt(v * v + 2.0 * y)
    if v + s > T:  # first impact after the edge: the ball flies over
        return y + v * T - 0.5 * T * T + 1.0, v - T, 0
    if e == 0.0:  # plastic impact: it sticks at its first contact
        return 1.0, 0.0, SLIDING
    return _step_closed_bounce(v, s, e, T, log_e, memo, base)


@njit(cache=True, inline="always")
def _step_closed_bounce(v, s, e, T, log_e, memo, base):
    """:func:`_step_closed_log` past its tests: a step that does not slide by
    (2.4), with its first impact before the edge and ``e > 0``; ``s`` is
    ``sqrt(v^2 + 2y)`` as computed there (a scan lane has it from its common
    step)."""
    k, tk = _impacts_and_time(v, s, e, T, log_e, memo, base)
    if k == SLIDING:  # rounding at the boundary of (2.4)
        return 1.0, 0.0, SLIDING
    yn, vn = _after_last_impact(T, tk, _power_memo(s, e, k, memo, base))
    return yn, vn, k


@njit(cache=True, inline="always")
def _after_last_impact(T, tk, vk):
    """The state at the edge ``T`` after the last impact ``t_k`` with velocity ``v_k``."""
    # t_k <= T < t_{k+1} = t_k + 2 v_k up to the rounding of t_k and v_k (a
    # few ulp of T): the clamp keeps that rounding from putting the ball a few
    # ulp below the edge; it moves d by no more than the error of t_k
    d = min(max(T - tk, 0.0), 2.0 * vk)
    return -0.5 * d * d + vk * d + 1.0, vk - d


@njit(cache=True)
def _state_in_step(y, v, e, tau, ratio):
    """Height above the floor and velocity at time ``tau`` (``0 <= tau <= T``)
    after entering a step at ``(y, v)``: the continuous solution inside a step.

    A flight until ``t_1``, then the bounce ``k`` with ``t_k <= tau < t_{k+1}``
    (Prop. 2.2 with ``T`` replaced by ``tau``, exactly as :func:`_step_closed`
    evaluates it), or rest on the floor once the impacts have accumulated at
    ``t_inf = v + (1+e)/(1-e) s`` (Prop. 2.1).  Right limits at impacts.
    """
    s = math.sqrt(v * v + 2.0 * y)
    if tau < v + s:
        return y + v * tau - 0.5 * tau * tau, v - tau
    if e == 0.0 or v + ratio * s <= tau:
        return 0.0, 0.0
    k = _impact_number_closed(y, v, e, tau)
    if k == SLIDING:
        return 0.0, 0.0
    tk = _impact_time(v, s, e, k)
    vk = _impact_velocity(s, e, k)
    d = min(max(tau - tk, 0.0), 2.0 * vk)
    return -0.5 * d * d + vk * d, vk - d


@njit(cache=True)
def _step(y, v, e, T, ratio):
    """Prop. 2.3, the Poincare map ``(y, v) -> (y_T, v_T, k)``, fast form.

    After the sliding test (2.4) the impacts are counted one by one along the
    geometric series of eq. (2.2) (``t_{k+1} = t_k + 2 v_k``, ``v_{k+1} = e v_k``):
    one square root and a few flops for the usual 0, 1 or 2 impacts.  Past
    ``_COUNTED_IMPACTS`` impacts the closed form of Prop. 2.2 takes over.

    Returns ``(1, 0, SLIDING)`` when the impacts accumulate before the edge.
    """
    return _step_from(y, v, math.sqrt(v * v + 2.0 * y), e, T, ratio)


@njit(cache=True)
def _step_from(y, v, s, e, T, ratio):
    """:func:`_step` given the state's impact speed ``s = math.sqrt(v * v + 2.0 * y)``
    (that float: a caller that has it already, e.g. for the state's hull, does not
    take the root twice; the same map, bit for bit)."""
    if v + ratio * s <= T:  # (2.4): accumulation before the edge
        return 1.0, 0.0, SLIDING
    t = v + s  # first impact
    if t > T:  # flies over the step
        return y + v * T - 0.5 * T * T + 1.0, v - T, 0
    w = e * s  # velocity after the current impact
    k = 1
    while k < _COUNTED_IMPACTS:
        nt = t + 2.0 * w
        if nt > T:
            d = T - t
            return -0.5 * d * d + w * d + 1.0, w - d, k
        t = nt
        w *= e
        k += 1
    return _step_closed(y, v, e, T, ratio)


@njit(cache=True)
def _slide_or_steps(y, v, e, T, ratio, max_steps):
    """:func:`_slide_or_steps_with` the fast map :func:`_step`."""
    return _slide_or_steps_with(_step, y, v, e, T, ratio, max_steps)


@njit(cache=True)
def _slide_or_steps_with(step, y, v, e, T, ratio, max_steps):
    """Iterate the map ``step`` from ``(y, v)`` until it slides, at most ``max_steps`` steps.

    Returns ``(steps, impacts, jumps)``: the number of steps up to and including
    the sliding step (0 when it did not slide), the finite impacts on the way
    and the number of non-zero jump numbers (steps with at least one impact,
    the sliding step included).  From ``(1, 0)`` these are the period, the
    impacts per period and the non-zero letters of the periodic sliding
    solution's word; its length is ``impacts + 1`` (docs/design.md).
    """
    impacts = 0
    jumps = 0
    for n in range(1, max_steps + 1):
        y, v, k = step(y, v, e, T, ratio)
        if k == SLIDING:
            return n, impacts, jumps + 1
        if k > 0:
            impacts += k
            jumps += 1
    return 0, impacts, jumps


@njit(cache=True)
def _iterate(y, v, e, T, ratio, steps, ys, vs, ks):
    """Fill ``ys[0..steps]``, ``vs``, ``ks[1..steps]`` with the Poincare iterates."""
    ys[0] = y
    vs[0] = v
    ks[0] = 0
    for n in range(1, steps + 1):
        y, v, k = _step(y, v, e, T, ratio)
        ys[n] = y
        vs[n] = v
        ks[n] = k


# --------------------------------------------------------------------------- #
# Validation                                                                  #
# --------------------------------------------------------------------------- #


def _finite(name: str, x) -> float:
    """``x`` as a finite float, or ValueError naming ``name`` (the contract of
    :mod:`stairbounce._validate`: numbers only, no bools or strings)."""
    return _v.real(name, x)


def check_e(e) -> float:
    """Validate the restitution coefficient: a float in [0, 1), 0 or at least
    2^-53 (:data:`stairbounce._validate.E_MIN`)."""
    e = _finite("e", e)
    if not 0.0 <= e < 1.0:
        raise ValueError(f"e (restitution coefficient) must be in [0, 1), got {e}")
    if _v.e_too_small(e):
        raise ValueError(f"{_v.E_TINY_RULE}, got {e}")
    return e


def check_u(u, name: str = "u") -> float:
    """Validate the horizontal speed: a float in [1e-150, 1e150] (> 0; the
    bounds keep ``T^2 = 1/u^2`` and ``v T`` far from overflow)."""
    u = _finite(name, u)
    if not u > 0.0:
        raise ValueError(f"{name} (horizontal speed) must be > 0, got {u}")
    if not _v.U_MIN <= u <= _v.U_MAX:
        raise ValueError(
            f"{name} (horizontal speed) must be in [{_v.U_MIN:g}, {_v.U_MAX:g}] "
            f"(the valid numeric range), got {u}"
        )
    return u


def check_state(y, v, yname: str = "y", vname: str = "v") -> tuple[float, float]:
    """Validate an edge state: ``0 <= y <= 1e300`` (the paper's domain is y >= 1;
    heights in [0, 1) are accepted as initial states, as in Section 4) and
    ``|v| <= 1e150``, where ``v^2 + 2y`` cannot overflow."""
    y = _finite(yname, y)
    if y < 0.0:
        raise ValueError(f"{yname} (height above the step's floor) must be >= 0, got {y}")
    if y > _v.Y_MAX:
        raise ValueError(
            f"{yname} (height above the step's floor) must be in [0, {_v.Y_MAX:g}] "
            f"(the valid numeric range), got {y}"
        )
    v = _finite(vname, v)
    if not abs(v) <= _v.V_MAX:
        raise ValueError(
            f"{vname} (vertical velocity) must be in [-{_v.V_MAX:g}, {_v.V_MAX:g}] "
            f"(the valid numeric range), got {v}"
        )
    return y, v


def check_count(name: str, n, minimum: int, maximum: int | None = None) -> int:
    """Validate an integer count ``minimum <= n (<= maximum)``; bools are refused."""
    return _v.count(name, n, minimum, maximum)


# --------------------------------------------------------------------------- #
# Public API                                                                  #
# --------------------------------------------------------------------------- #


def poincare_map(y: Real, v: Real, e: Real, u: Real) -> tuple[float, float, int]:
    """poincare_map(y, v, e, u) -> (y_next, v_next, impacts)

    One step of the staircase, edge to edge (Prop. 2.3).

    ``P(y, v) = (y(T) + 1, y'(T+))`` with ``T = 1/u``: fly until the first impact
    ``t_1 = v + sqrt(v^2 + 2y)``, bounce with impact times and velocities of
    eq. (2.2), and measure the state when the ball passes the next edge.  If the
    impacts accumulate before the edge (Prop. 2.1) the ball slides off it with
    zero vertical velocity: ``P = (1, 0)`` and ``impacts = SLIDING``.

    Parameters
    ----------
    y : float >= 0
        Height above the floor of the step being entered (the paper's domain is
        y >= 1; smaller heights are accepted as initial states).
    v : float
        Vertical velocity (positive upwards).
    e : float in [0, 1)
        Restitution coefficient (0: plastic, the ball sticks at first contact).
    u : float > 0
        Horizontal speed; one step takes ``T = 1/u``.

    Returns
    -------
    (y_next, v_next, impacts) : (float, float, int)
        ``impacts`` is 0 when the ball flies over the step, k >= 1 impacts, or
        ``SLIDING`` (-1).
    """
    y, v = check_state(y, v)
    e = check_e(e)
    T, ratio = _constants(e, check_u(u))
    yn, vn, k = _step(y, v, e, T, ratio)
    return float(yn), float(vn), int(k)


def slides(y: Real, v: Real, e: Real, u: Real) -> bool:
    """slides(y, v, e, u) -> bool

    Whether the impacts accumulate on the first step (Prop. 2.1).

    Evaluated as (2.4), ``v + (1+e)/(1-e) sqrt(v^2 + 2y) <= 1/u``, which is
    equivalent to the parabola (2.3).  Equality counts as sliding.

    Note: the paper prints the constant term of (2.3) as
    ``(1+e)^2 / (2 u^2 (1-e)^2)``; squaring (2.4) gives
    ``(1-e)^2 / (2 u^2 (1+e)^2)``, the only one consistent with the vertex
    ``y* = (1-e)^2 / (8 e u^2)`` of Corollary 2.1.  We use (2.4), which needs
    no correction (``tests/test_model.py`` checks both statements).
    """
    y, v = check_state(y, v)
    T, ratio = _constants(check_e(e), check_u(u))
    return bool(_slides(y, v, T, ratio))


def impact_number(y: Real, v: Real, e: Real, u: Real) -> int:
    """impact_number(y, v, e, u) -> int

    Number of impacts on the first step (Prop. 2.2).

    ``k = E[log_e((v - 1/u)(1-e) / (2 sqrt(v^2+2y)) + (1+e)/2)]``, corrected
    for rounding so that ``t_k <= T < t_{k+1}`` with the times of eq. (2.2);
    0 when the ball flies over the step.

    Raises
    ------
    ValueError
        When the solution slides on this step (the impact number is infinite).
    """
    y, v = check_state(y, v)
    e = check_e(e)
    T, ratio = _constants(e, check_u(u))
    if _slides(y, v, T, ratio):
        raise ValueError(
            f"the solution from (y, v) = ({y!r}, {v!r}) with e = {e!r}, u = {u!r} slides on this "
            "step (Prop. 2.1): its impact number is infinite (test with slides(y, v, e, u) first)"
        )
    k = _impact_number_closed(y, v, e, T)
    if k == SLIDING:
        raise ValueError(
            f"the solution from (y, v) = ({y!r}, {v!r}) with e = {e!r}, u = {u!r} slides on this "
            "step (Prop. 2.1): its impact number is infinite (test with slides(y, v, e, u) first)"
        )
    return int(k)


def impact_times(y: Real, v: Real, e: Real, k: int) -> tuple[np.ndarray, np.ndarray]:
    """impact_times(y, v, e, k) -> (times, velocities)

    The first ``k`` impact times and post-impact velocities on a step, eq. (2.2).

    ``t_j = v + (1+e-2e^j)/(1-e) sqrt(v^2+2y)``, ``v_j = e^j sqrt(v^2+2y)``,
    j = 1..k, measured from the edge, assuming every impact happens on this
    step (the horizontal speed does not enter).  Evaluated as
    ``t_1 + 2 e s (1 - e^(j-1))/(1-e)``, free of the cancellation of the
    printed form near e = 1 (:func:`_impact_time`).

    Returns two float arrays of length ``k``.
    """
    y, v = check_state(y, v)
    e = check_e(e)
    k = check_count("k", k, 0)
    _v.check_memory(f"k = {k}", 16 * k)
    times = np.empty(k)
    speeds = np.empty(k)
    _impact_times(v, math.sqrt(v * v + 2.0 * y), e, times, speeds)
    return times, speeds


@njit(cache=True)
def _impact_times(v, s, e, times, speeds):
    """Fill ``times[j-1] = t_j``, ``speeds[j-1] = v_j`` (eq. 2.2), j = 1..len."""
    for j in range(1, times.size + 1):
        times[j - 1] = _impact_time(v, s, e, j)
        speeds[j - 1] = _impact_velocity(s, e, j)


def no_sliding_bound(e: Real) -> float:
    """no_sliding_bound(e) -> float

    Corollary 2.1: for ``u >= (1-e) / (2 sqrt(2e))`` no solution slides.

    Infinite for ``e = 0`` (a plastic ball sticks at every speed).
    """
    e = check_e(e)
    if e == 0.0:
        return math.inf
    return (1.0 - e) / (2.0 * math.sqrt(2.0 * e))


def tongue(n: int, e: Real) -> tuple[float, float]:
    """tongue(n, e) -> (u_low, u_high)

    Theorem 3.1: the ``(n, 0^inf)`` sliding tongue at restitution ``e``.

    Periodic solutions of type ``(n, 0^inf)`` exist iff
    ``(n-1)/2 < u^2 <= n/2 ((1-e)/(1+e))^2``, i.e. ``u_low < u <= u_high`` with
    ``u_low = sqrt((n-1)/2)`` (excluded) and
    ``u_high = sqrt(n/2) (1-e)/(1+e)`` (included).  The interval is empty when
    ``u_high <= u_low``.
    """
    n = check_count("n", n, 1)
    e = check_e(e)
    return math.sqrt((n - 1) / 2.0), math.sqrt(n / 2.0) * (1.0 - e) / (1.0 + e)


def iterate(y: Real, v: Real, e: Real, u: Real, steps: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """iterate(y, v, e, u, steps) -> (ys, vs, impacts)

    Poincare iterates ``P^n(y, v)`` for n = 0..steps (Prop. 2.3).

    Returns float arrays ``ys``, ``vs`` of length ``steps + 1`` (index 0 is the
    initial state) and an int array ``impacts`` of the same length with the
    impact number of the step that led to each iterate (``impacts[0] = 0``).
    """
    y, v = check_state(y, v)
    e = check_e(e)
    T, ratio = _constants(e, check_u(u))
    steps = check_count("steps", steps, 0)
    # three arrays of steps + 1 eight-byte numbers
    _v.check_memory(f"steps = {steps}", 24 * (steps + 1))
    ys = np.empty(steps + 1)
    vs = np.empty(steps + 1)
    ks = np.empty(steps + 1, dtype=np.int64)
    _iterate(y, v, e, T, ratio, steps, ys, vs, ks)
    return ys, vs, ks
