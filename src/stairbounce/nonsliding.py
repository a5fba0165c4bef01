"""Non-sliding motion: impacts per step and Lyapunov exponents of the Poincare map.

Three quarters of the paper's (e, u) plane are white in its Fig. 4: the orbit of
``(1, 0)`` never slides again.  This module gives that region its structure
with two numbers per point, measured on the Poincare map P of Prop. 2.3:

- ``<k>``, the mean number of impacts per step (the staircase's rotation
  number: impacts per step taken), and the mean jump (steps per landing);
- the Lyapunov exponents ``lambda_1 >= lambda_2`` of P, from the product of
  its exact 2x2 Jacobians (:func:`step_jacobian`).

The Jacobian of one step (derivation)
-------------------------------------
Write ``s = sqrt(v^2 + 2y)`` (first impact speed), ``t_k``, ``v_k = e^k s``
the time and take-off speed of the last impact (eq. 2.2, ``t_k = v + c_k s``
with ``c_k = (1+e-2e^k)/(1-e)``), ``d = T - t_k`` and ``(y', v')`` the image
(Prop. 2.3: ``y' = -d^2/2 + v_k d + 1``, ``v' = v_k - d``).  With
``ds = (dy + v dv)/s``, ``dt_k = dv + c_k ds``, ``dv_k = e^k ds``,
``dd = -dt_k``:

- **0 impacts** (flies over): ``J = [[1, T], [0, 1]]``, ``det J = 1``.
- **k >= 1 impacts**: ``dy' = -v' dt_k + d e^k ds``, ``dv' = dt_k + e^k ds``, so
  with ``c = a + v b`` for a tangent vector ``(a, b)``,
  ``J (a, b) = (J11 c - v' b, J21 c + b)`` where
  ``J11 = (d v_k - v' (t_k - v)) / s^2`` and ``J21 = (v_k + t_k - v) / s^2``.
  Its determinant is ``J11 + v' J21 = v_k (d + v') / s^2 = (v_k / s)^2``, i.e.
  **det J = e^k (v_k / s) = e^(2k)**: the flights are Hamiltonian (area
  preserving) and each impact multiplies areas by ``e^2`` (its saltation
  matrix ``[[-e, 0], [-(1+e)/v_-, -e]]`` in ``(y, v)``, from the reset
  ``v+ = -e v-`` at ``y = 0`` with the flow's correction, has determinant
  ``e * (v+ / |v-|) = e^2``).
- **infinitely many impacts** (sliding, Prop. 2.1): the image is the constant
  ``(1, 0)`` on an open set, ``J = 0``, both exponents are ``-inf``; the orbit
  is then the periodic sliding solution of Section 3.
- **grazing** (an impact exactly at the edge, ``t_j = T``): P is
  discontinuous there.  Just before the edge the ball lands and leaves at
  ``v' = e |v_-|``; just after, it flies on with ``v' = -|v_-|``; ``y' = 1`` on
  both sides.  Only one-sided Jacobians exist; the code takes the side of
  Prop. 2.2 (``t_k <= T`` counts as an impact).  These states form curves of
  zero area, met with probability zero by an orbit.

lambda_1 = 0: the answer to "chaotic or just complicated?"
----------------------------------------------------------
The impacts are on horizontal floors, so shifting a whole non-sliding
trajectory horizontally by a small ``delta`` gives another solution (as long as
no impact or flight comes within ``delta`` of an edge, i.e. away from grazing).
At an edge the shifted trajectory is the old one ``delta/u`` earlier, so the
tangent map carries the vertical vector field along the orbit:

    ``J (v, -1) = (v', -1)``  (0 impacts: ``v' = v - T``; k impacts: direct
    substitution in the formulas above, tested to rounding).

Its norm ``sqrt(1 + v^2)`` stays bounded on a bounded orbit, so one Lyapunov
exponent is exactly 0; with ``lambda_1 + lambda_2 = 2 <k> log e < 0`` the
spectrum of every bounded non-sliding orbit that avoids grazing is
``(0, 2 <k> log e)``: never chaotic in the Lyapunov sense.  The finite-N
estimate is ``lambda_1 ~ (1/2N) log((1 + v_N^2)/(1 + v_0^2))``, O(1/N); the
measured values are that (``tests/test_motion.py``).  The complication is in
``<k>`` and its dependence on (e, u).

Identities every long orbit obeys (tested in ``tests/test_motion.py``)
---------------------------------------------------------------------
Over ``N`` steps with ``K`` impacts in all:

1. *determinant*: ``lambda_1 + lambda_2 = (1/N) sum log|det J| = 2 <k> log e``
   (exact for the finite product, up to rounding).
2. *energy*: with ``E = v^2/2 + y = s^2/2`` at an edge, one step gives
   ``E' = e^(2k) E + 1`` (the last take-off energy plus the descent of 1).  The
   energy lost at impacts in a step is ``(1 - e^(2k)) s^2 / 2`` and its mean,
   ``dissipation``, equals ``1 + (E_0 - E_N)/N``: the ball loses on average
   exactly the height it descends.
3. *time (momentum)*: gravity removes ``T`` of vertical velocity per step and
   each impact adds ``(1 + e) |v_-|``, so the mean impulse per step,
   ``impulse = (1+e) <sum |v_-|>``, equals ``T + (v_N - v_0)/N``: the total
   flight time between impacts is the time elapsed.

A lower bound on <k> (Cauchy-Schwarz)
------------------------------------
With ``K`` impacts of speeds ``|v_-|`` in ``N`` steps, (2) and (3) give
``sum |v_-|^2 = 2 N dissipation / (1 - e^2)`` and ``sum |v_-| = N impulse / (1 + e)``,
and ``(sum |v_-|)^2 <= K sum |v_-|^2``, so exactly, for every finite orbit,

    ``<k> >= impulse^2 (1 - e) / (2 (1 + e) dissipation)``,

which tends to ``<k>_0 = (1 - e) / (2 (1 + e) u^2)`` (:func:`k_mean_bound`) on long
orbits.  Equality needs all impact speeds equal: the one-impact families
(:func:`one_impact_family`, where ``<k>_0 = 1/n``).  ``<k> / <k>_0 - 1``
measures the spread of the impact speeds; at finite N the exact form is
:func:`speed_spread`, ``Var |v_-| / <|v_-|>^2`` over the kept impacts.  It is
where the complication lives.

The kernels iterate every pixel they are given (no pruning: the motion is the
point here).  Nothing here imports matplotlib, Typer or the web stack.

References: the paper (Campos, Romero-Valles, Torres), Props. 2.1-2.3 and
Cor. 2.1; Gruiz, Meszena, Tel, "Chaotic or just complicated? Ball bouncing down
the stairs", Eur. J. Phys. 38 (2017) 055003, who report quasi-periodic,
non-chaotic stationary bouncing on this staircase.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import xarray as xr
from numba import njit, prange

from ._simd import prefer_wide_vectors
from ._version import __version__
from .units import staircase_of, with_speed
from .model import (
    _COUNTED_IMPACTS,
    SLIDING,
    _constants,
    _finite,
    _impact_time,
    _step_closed,
    check_count,
    check_e,
    check_state,
    check_u,
)

__all__ = [
    "Motion",
    "motion",
    "motion_scan",
    "motion_coords",
    "step_jacobian",
    "lyapunov_exponents",
    "one_impact_family",
    "one_impact_state",
    "k_mean_bound",
    "speed_spread",
    "MOTION_FIELDS",
]

# Per-pixel output, in the order of the kernels' output columns.
MOTION_FIELDS = {
    "slide_step": "first step (1-based, transient included) on which the orbit slides; 0: none",
    "k_mean": "<k>, mean impacts per kept step (rotation number); NaN where it slides",
    "k_err": "|<k> over the first half - <k> over the second half| of the kept steps",
    "jump_mean": "mean non-zero jump: kept steps per step with a landing; inf if none",
    "lyap1": "largest Lyapunov exponent lambda_1 of the Poincare map (per step); -inf where it slides",
    "lyap1_err": "|lambda_1 over the first half - over the second half| of the kept steps",
    "lyap2": "second exponent lambda_2 = 2 <k> log e - lambda_1 (determinant identity)",
    "dissipation": "mean energy lost at impacts per kept step (-> 1, the height descended)",
    "impulse": "mean impulse of impacts per kept step, (1+e) <sum |v_-|> (-> T = 1/u)",
}
_NF = len(MOTION_FIELDS)
_LN2 = math.log(2.0)
# tangent vectors are rescaled by exact powers of two outside [2^-SCALE, 2^SCALE]
_SCALE = 400
_BIG = 2.0**_SCALE
_SMALL = 2.0**-_SCALE


# --------------------------------------------------------------------------- #
# Compiled scalar functions                                                    #
# --------------------------------------------------------------------------- #


@njit(cache=True, error_model="numpy")
def _tangent_step(y, v, e, T, ratio):
    """Prop. 2.3 with what the Jacobian needs: ``(y', v', k, s, t_k, v_k)``.

    The same operations in the same order as :func:`stairbounce.model._step`
    (tested bit for bit), plus the first impact speed ``s``, the last impact
    time ``t_k`` and take-off speed ``v_k`` (eq. 2.2).  On a sliding step
    ``k = SLIDING``; on a flight ``t_k = v_k = 0``.
    """
    s = math.sqrt(v * v + 2.0 * y)
    if v + ratio * s <= T:
        return 1.0, 0.0, SLIDING, s, 0.0, 0.0
    t = v + s
    if t > T:
        return y + v * T - 0.5 * T * T + 1.0, v - T, 0, s, 0.0, 0.0
    w = e * s
    k = 1
    while k < _COUNTED_IMPACTS:
        nt = t + 2.0 * w
        if nt > T:
            d = T - t
            return -0.5 * d * d + w * d + 1.0, w - d, k, s, t, w
        t = nt
        w *= e
        k += 1
    yn, vn, k = _step_closed(y, v, e, T, ratio)
    if k == SLIDING:
        return yn, vn, k, s, 0.0, 0.0
    return yn, vn, k, s, _impact_time(v, s, e, k), e**k * s


@njit(cache=True, error_model="numpy")
def _apply_jacobian(a, b, y, v, vn, k, s, t, w, T):
    """``J (a, b)`` for the step from ``(y, v)`` (module docstring)."""
    if k == 0:
        return a + T * b, b
    inv = 1.0 / (v * v + 2.0 * y)
    d = T - t
    j11 = (d * w - vn * (t - v)) * inv
    j21 = (w + t - v) * inv
    c = a + v * b
    return j11 * c - vn * b, j21 * c + b


@njit(cache=True, error_model="numpy")
def _rescale(a, b, ex):
    """Keep ``(a, b)`` within [2^-400, 2^400] by exact powers of two; ``ex`` counts them."""
    m = max(abs(a), abs(b))
    big = m > _BIG
    small = (m < _SMALL) and (m > 0.0)
    f = _SMALL if big else (_BIG if small else 1.0)
    return a * f, b * f, ex + (_SCALE if big else (-_SCALE if small else 0))


@njit(cache=True, error_model="numpy")
def _log_norm(a, b, ex):
    return 0.5 * math.log(a * a + b * b) + ex * _LN2


@njit(cache=True, error_model="numpy")
def _gram_schmidt(na, nb, ra, rb):
    """Second column of Q and ``|R22|`` of the QR of ``[(na, nb), (ra, rb)]``."""
    nn = math.sqrt(na * na + nb * nb)
    ua = na / nn
    ub = nb / nn
    p = ra * ua + rb * ub
    ra -= p * ua
    rb -= p * ub
    r22 = math.sqrt(ra * ra + rb * rb)
    return ra / r22, rb / r22, r22


@njit(cache=True, error_model="numpy")
def _product_exponents_kernel(Js):
    a = 1.0
    b = 0.0
    ex = 0
    qa = 0.0
    qb = 1.0
    l2 = 0.0
    L0 = _log_norm(a, b, ex)
    for n in range(Js.shape[0]):
        J = Js[n]
        na = J[0, 0] * a + J[0, 1] * b
        nb = J[1, 0] * a + J[1, 1] * b
        ra = J[0, 0] * qa + J[0, 1] * qb
        rb = J[1, 0] * qa + J[1, 1] * qb
        qa, qb, r22 = _gram_schmidt(na, nb, ra, rb)
        l2 += math.log(r22)
        a, b, ex = _rescale(na, nb, ex)
    return (_log_norm(a, b, ex) - L0) / Js.shape[0], l2 / Js.shape[0]


def _product_exponents(jacobians):
    """The kernels' Lyapunov algorithm (first vector rescaled by powers of two,
    second by Gram-Schmidt) on any sequence of 2x2 matrices, for tests."""
    Js = np.ascontiguousarray(np.asarray(jacobians, dtype=np.float64))
    return _product_exponents_kernel(Js)


@njit(cache=True, error_model="numpy")
def _finish(out, imp, imp_half, land, diss, kick, L0, Lh, Le, e, steps):
    """The fields of :data:`MOTION_FIELDS` of a non-sliding orbit from its sums."""
    N = steps
    half = N // 2
    h2 = N - half
    out[0] = 0
    out[1] = imp / N
    out[2] = abs(imp_half / half - (imp - imp_half) / h2)
    out[3] = N / land if land > 0 else math.inf
    lam1 = (Le - L0) / N
    out[4] = lam1
    out[5] = abs((Lh - L0) / half - (Le - Lh) / h2)
    out[6] = 2.0 * (imp / N) * math.log(e) - lam1 if e > 0.0 else -math.inf
    out[7] = diss / N
    out[8] = kick / N


@njit(cache=True, error_model="numpy")
def _finish_slide(out, n):
    """Fields of an orbit that slides on step ``n`` (1-based): J = 0 there."""
    out[0] = n
    for f in range(1, _NF):
        out[f] = math.nan
    out[4] = -math.inf
    out[6] = -math.inf


@njit(cache=True, error_model="numpy")
def _motion_orbit(y, v, e, T, ratio, transient, steps, out, extra):
    """Iterate ``transient + steps`` steps from ``(y, v)``, fill ``out[0:_NF]``.

    ``out`` gets the fields of :data:`MOTION_FIELDS` in order.  When
    ``extra.shape[0] >= 6`` (the single-point path) it also gets the states at
    the start and at the end of the kept steps and lambda_2 from a second,
    Gram-Schmidt-orthonormalised tangent vector (QR) with its halves'
    difference: ``[y_0, v_0, y_N, v_N, lambda_2, lambda_2 error]``.
    """
    qr = extra.shape[0] > 0
    a = 1.0  # tangent vector of lambda_1, unnormalised
    b = 0.0
    ex = 0
    qa = 0.0  # QR: the second orthonormal vector
    qb = 1.0
    l2 = 0.0
    l2_half = 0.0
    half = steps // 2
    imp = 0
    imp_half = 0
    land = 0
    diss = 0.0
    kick = 0.0
    L0 = 0.0
    Lh = 0.0
    for n in range(transient + steps):
        if n == transient:
            L0 = _log_norm(a, b, ex)
            if qr:
                extra[0] = y
                extra[1] = v
        if n == transient + half:
            Lh = _log_norm(a, b, ex)
            imp_half = imp
            l2_half = l2
        yn, vn, k, s, t, w = _tangent_step(y, v, e, T, ratio)
        if k == SLIDING:
            _finish_slide(out, n + 1)
            if qr:
                extra[2] = yn
                extra[3] = vn
            return
        na, nb = _apply_jacobian(a, b, y, v, vn, k, s, t, w, T)
        if qr:
            # second column of Q: J q2 minus its component along J q1, normalised
            ra, rb = _apply_jacobian(qa, qb, y, v, vn, k, s, t, w, T)
            qa, qb, r22 = _gram_schmidt(na, nb, ra, rb)
            if n >= transient:
                l2 += math.log(r22)
        a, b, ex = _rescale(na, nb, ex)
        if n >= transient and k > 0:
            imp += k
            land += 1
            diss += 0.5 * (s * s - w * w)  # (1 - e^2k) s^2 / 2, w = e^k s
            kick += ratio * (s - w)  # (1+e) s (1 - e^k)/(1-e)
        y = yn
        v = vn
    _finish(out, imp, imp_half, land, diss, kick, L0, Lh, _log_norm(a, b, ex), e, steps)
    if qr:
        h2 = steps - half
        extra[2] = y
        extra[3] = v
        extra[4] = l2 / steps
        extra[5] = abs(l2_half / half - (l2 - l2_half) / h2)


# Pixels advanced in lockstep by one thread, in a branch-free loop that LLVM
# vectorises (8 float64 per AVX-512 register with _simd.prefer_wide_vectors,
# 4 without it or with AVX2; it enters the vector body from 16 lanes); lanes
# with two impacts or more on a step fall back to the scalar step.  Every
# pixel sees the operations of _motion_orbit, bit for bit.
LANES = 32
# Pixels per unit of parallel work, in an interleaved order so that both
# threads see cheap (sliding) and expensive (non-sliding) parts of the plane.
_CHUNK = 256


@njit(cache=True, error_model="numpy")
def _load(l, p, es, us, y0, v0, E, TT, R, HTT, Y, V, A, B, EX, N, IMP, IMPH, LAND, DISS, KICK, L0, LH, PIX):
    ne = es.shape[0]
    e = es[p % ne]
    T, ratio = _constants(e, us[p // ne])
    E[l] = e
    TT[l] = T
    R[l] = ratio
    HTT[l] = 0.5 * T * T  # as _tangent_step evaluates it
    Y[l] = y0
    V[l] = v0
    A[l] = 1.0
    B[l] = 0.0
    EX[l] = 0
    N[l] = 0
    IMP[l] = 0
    IMPH[l] = 0
    LAND[l] = 0
    DISS[l] = 0.0
    KICK[l] = 0.0
    L0[l] = 0.0
    LH[l] = 0.0
    PIX[l] = p


@njit(cache=True, error_model="numpy")
def _motion_lanes(es, us, y0, v0, transient, steps, start, stop, out):
    """Pixels ``start..stop-1`` (row-major), LANES at a time in lockstep.

    A lane takes the next pixel as soon as its own is done (slid, or ran
    ``transient + steps`` steps), so cheap and expensive pixels mix freely.
    """
    prefer_wide_vectors()  # eight float64 per vector where the machine has them (_simd)
    L = LANES
    ne = es.shape[0]
    total = transient + steps
    half = steps // 2
    E = np.zeros(L)
    TT = np.ones(L)
    R = np.ones(L)
    HTT = np.full(L, 0.5)
    Y = np.ones(L)
    V = np.zeros(L)
    A = np.ones(L)
    B = np.zeros(L)
    EX = np.zeros(L, np.int64)
    N = np.zeros(L, np.int64)
    IMP = np.zeros(L, np.int64)
    IMPH = np.zeros(L, np.int64)
    LAND = np.zeros(L, np.int64)
    DISS = np.zeros(L)
    KICK = np.zeros(L)
    L0 = np.zeros(L)
    LH = np.zeros(L)
    PIX = np.full(L, -1, np.int64)
    LIVE = np.zeros(L, np.int64)
    YN = np.empty(L)
    VN = np.empty(L)
    AN = np.empty(L)
    BN = np.empty(L)
    K = np.zeros(L, np.int64)
    SS = np.empty(L)
    WW = np.empty(L)
    MORE = np.zeros(L, np.int64)
    TS = np.empty(L)
    INV = np.empty(L)
    SC = np.zeros(L, np.int64)
    LAST = np.zeros(L, np.int64)
    CLOSED = np.zeros(L, np.int64)

    nxt = start
    active = 0
    for l in range(L):
        if nxt < stop:
            _load(l, nxt, es, us, y0, v0, E, TT, R, HTT, Y, V, A, B, EX, N, IMP, IMPH, LAND,
                  DISS, KICK, L0, LH, PIX)
            if transient == 0:
                L0[l] = _log_norm(1.0, 0.0, 0)
            LIVE[l] = 1
            nxt += 1
            active += 1

    while active > 0:
        # one step of every lane: slide, fly over or one impact, branch-free
        nmore = 0
        for l in range(L):
            y = Y[l]
            v = V[l]
            e = E[l]
            T = TT[l]
            a = A[l]
            b = B[l]
            s = math.sqrt(v * v + 2.0 * y)
            slide = v + R[l] * s <= T
            t = v + s
            fly = t > T
            w = e * s
            more = (t + 2.0 * w <= T) and not fly and not slide
            d = T - t
            yb = -0.5 * d * d + w * d + 1.0
            vb = w - d
            yf = y + v * T - HTT[l] + 1.0
            vf = v - T
            YN[l] = 1.0 if slide else (yf if fly else yb)
            vn = 0.0 if slide else (vf if fly else vb)
            VN[l] = vn
            K[l] = SLIDING if slide else (0 if fly else 1)
            # tangent map, as _apply_jacobian
            inv = 1.0 / (v * v + 2.0 * y)
            INV[l] = inv
            j11 = (d * w - vb * (t - v)) * inv
            j21 = (w + t - v) * inv
            c = a + v * b
            AN[l] = (a + T * b) if fly else (j11 * c - vb * b)
            BN[l] = b if fly else (j21 * c + b)
            SS[l] = s
            TS[l] = t
            WW[l] = w
            MORE[l] = more
            nmore += more
        if nmore > 0:
            # lanes with two impacts or more: count on along t += 2w, w *= e as
            # _tangent_step does, branch-free, up to _COUNTED_IMPACTS; past that
            # the scalar step (closed form) for that lane
            nclosed = 0
            while nmore > 0:
                nmore = 0
                # count one more impact where it happens (two short loops
                # vectorise better than one)
                for l in range(L):
                    m = MORE[l]
                    T = TT[l]
                    t = TS[l] + 2.0 * WW[l] if m else TS[l]
                    w = WW[l] * E[l] if m else WW[l]
                    k = K[l] + m
                    closed = m & (k >= _COUNTED_IMPACTS)
                    more = m & (1 - closed) & (t + 2.0 * w <= T)
                    LAST[l] = m & (1 - closed) & (1 - more)
                    TS[l] = t
                    WW[l] = w
                    K[l] = k
                    CLOSED[l] = CLOSED[l] | closed
                    MORE[l] = more
                    nmore += more
                    nclosed += closed
                # lanes whose last impact this was: the image and the tangent map
                for l in range(L):
                    last = LAST[l]
                    v = V[l]
                    t = TS[l]
                    w = WW[l]
                    d = TT[l] - t
                    yb = -0.5 * d * d + w * d + 1.0
                    vb = w - d
                    inv = INV[l]
                    j11 = (d * w - vb * (t - v)) * inv
                    j21 = (w + t - v) * inv
                    a = A[l]
                    b = B[l]
                    c = a + v * b
                    YN[l] = yb if last else YN[l]
                    VN[l] = vb if last else VN[l]
                    AN[l] = (j11 * c - vb * b) if last else AN[l]
                    BN[l] = (j21 * c + b) if last else BN[l]
            if nclosed > 0:
                for l in range(L):
                    if CLOSED[l]:
                        CLOSED[l] = 0
                        y = Y[l]
                        v = V[l]
                        T = TT[l]
                        yn, vn, k, s, t, w = _tangent_step(y, v, E[l], T, R[l])
                        na, nb = _apply_jacobian(A[l], B[l], y, v, vn, k, s, t, w, T)
                        YN[l] = yn
                        VN[l] = vn
                        K[l] = k
                        AN[l] = na
                        BN[l] = nb
                        WW[l] = w
        # commit, branch-free, in short loops (rescaled tangent vector,
        # accumulators, state, integers): each of them vectorises, where one
        # loop over all these arrays did not (measured x1.6 on the whole kernel)
        for l in range(L):
            a = AN[l]
            b = BN[l]
            aa = abs(a)
            ab = abs(b)
            big = (aa > _BIG) | (ab > _BIG)  # as _rescale: max(|a|, |b|) > 2^400
            small = (aa < _SMALL) & (ab < _SMALL) & ((aa > 0.0) | (ab > 0.0))
            f = _SMALL if big else (_BIG if small else 1.0)
            A[l] = a * f
            B[l] = b * f
            SC[l] = _SCALE if big else (-_SCALE if small else 0)
        for l in range(L):
            kept = (N[l] >= transient) & (K[l] > 0)
            s = SS[l]
            w = WW[l]
            DISS[l] += 0.5 * (s * s - w * w) if kept else 0.0
            KICK[l] += R[l] * (s - w) if kept else 0.0
        for l in range(L):
            Y[l] = YN[l]
            V[l] = VN[l]
        nev = 0
        for l in range(L):
            k = K[l]
            n = N[l]
            kept = (n >= transient) & (k > 0)
            EX[l] += SC[l]
            IMP[l] += k if kept else 0
            LAND[l] += 1 if kept else 0
            n += 1
            N[l] = n
            nev += LIVE[l] & ((k == SLIDING) | (n == transient) | (n == transient + half) | (n == total))
        if nev == 0:
            continue
        for l in range(L):
            if LIVE[l] == 0:
                continue
            n = N[l]
            if K[l] != SLIDING and n != total:
                if n == transient:
                    L0[l] = _log_norm(A[l], B[l], EX[l])
                if n == transient + half:
                    LH[l] = _log_norm(A[l], B[l], EX[l])
                    IMPH[l] = IMP[l]
                continue
            p = PIX[l]
            if K[l] == SLIDING:
                _finish_slide(out[p // ne, p % ne], n)
            else:
                _finish(out[p // ne, p % ne], IMP[l], IMPH[l], LAND[l], DISS[l], KICK[l],
                        L0[l], LH[l], _log_norm(A[l], B[l], EX[l]), E[l], steps)
            if nxt < stop:
                _load(l, nxt, es, us, y0, v0, E, TT, R, HTT, Y, V, A, B, EX, N, IMP, IMPH, LAND,
                      DISS, KICK, L0, LH, PIX)
                if transient == 0:
                    L0[l] = _log_norm(1.0, 0.0, 0)
                nxt += 1
            else:
                # an idle lane keeps stepping a harmless state until the others finish
                LIVE[l] = 0
                Y[l] = 1.0
                V[l] = 0.0
                active -= 1


@njit(cache=True, parallel=True, error_model="numpy")
def _motion_fast(es, us, y0, v0, transient, steps, order, chunk, out):
    """Fast kernel: chunks of ``chunk`` pixels in the interleaved order
    ``order`` over threads, LANES pixels of a chunk in lockstep."""
    npix = es.shape[0] * us.shape[0]
    for c in prange(order.shape[0]):
        s = order[c] * chunk
        _motion_lanes(es, us, y0, v0, transient, steps, s, min(s + chunk, npix), out)


@njit(cache=True, parallel=True, error_model="numpy")
def _motion_plain(es, us, y0, v0, transient, steps, out):
    """Baseline kernel: one pixel at a time (:func:`_motion_orbit`), prange over rows."""
    ne = es.shape[0]
    for i in prange(us.shape[0]):
        noextra = np.empty(0)
        for j in range(ne):
            T, ratio = _constants(es[j], us[i])
            _motion_orbit(y0, v0, es[j], T, ratio, transient, steps, out[i, j], noextra)


def _chunking(npix):
    """Chunk order ``0, 16, 32, ..., 1, 17, ...``: every thread's contiguous
    block of prange iterations samples the whole plane.  Results do not
    depend on it."""
    n = -(-npix // _CHUNK)
    return np.concatenate([np.arange(k, n, 16) for k in range(min(16, n))]).astype(np.int64)


# --------------------------------------------------------------------------- #
# Public API                                                                  #
# --------------------------------------------------------------------------- #


def step_jacobian(y, v, e, u):
    """step_jacobian(y, v, e, u) -> (J, impacts)

    The exact 2x2 Jacobian of one step of the Poincare map (Prop. 2.3).

    ``[[1, T], [0, 1]]`` on a flight (0 impacts); on ``k >= 1`` impacts
    ``J = [[J11, -v' + J11 v], [J21, 1 + J21 v]]`` with
    ``J11 = (d v_k - v'(t_k - v))/s^2``, ``J21 = (v_k + t_k - v)/s^2``
    (module docstring), ``det J = e^(2k)``; the zero matrix on a sliding step.
    At a grazing state (``t_j = T`` exactly) the map is discontinuous and this
    is the Jacobian of the side Prop. 2.2 takes (the impact at the edge counts).

    Parameters: as :func:`stairbounce.poincare_map`.
    """
    y, v = check_state(y, v)
    e = check_e(e)
    T, ratio = _constants(e, check_u(u))
    yn, vn, k, s, t, w = _tangent_step(y, v, e, T, ratio)
    if k == SLIDING:
        return np.zeros((2, 2)), SLIDING
    c1 = _apply_jacobian(1.0, 0.0, y, v, vn, k, s, t, w, T)
    c2 = _apply_jacobian(0.0, 1.0, y, v, vn, k, s, t, w, T)
    return np.array([[c1[0], c2[0]], [c1[1], c2[1]]]), int(k)


def lyapunov_exponents(jacobians):
    """lyapunov_exponents(jacobians) -> (lambda_1, lambda_2)

    Lyapunov exponents of a product of 2x2 matrices by QR re-orthonormalisation.

    ``Q_n R_n = J_n Q_{n-1}``, ``lambda_i = (1/N) sum_n log |R_n[i, i]|``: the
    textbook algorithm (Benettin et al. 1980; Eckmann and Ruelle 1985), in
    NumPy, for checking the kernels' exponents on maps with known ones.

    Parameters
    ----------
    jacobians : array (N, 2, 2), or an iterable of 2x2 matrices
    """
    Js = np.asarray(list(jacobians) if not isinstance(jacobians, np.ndarray) else jacobians, float)
    if Js.ndim != 3 or Js.shape[1:] != (2, 2) or Js.shape[0] == 0:
        raise ValueError(f"jacobians must have shape (N, 2, 2) with N >= 1, got {Js.shape}")
    Q = np.eye(2)
    sums = np.zeros(2)
    for J in Js:
        Q, R = np.linalg.qr(J @ Q)
        sums += np.log(np.abs(np.diag(R)))
    return float(sums[0] / len(Js)), float(sums[1] / len(Js))


def _check_steps(steps, transient):
    steps = check_count("steps", steps, 2)
    transient = check_count("transient", transient, 0)
    if steps + transient > 2**31 - 1:
        raise ValueError(f"steps + transient must be <= 2**31 - 1, got {steps + transient}")
    return steps, transient


def motion(e, u, steps=1000, transient=1000, y0=1.0, v0=0.0):
    """motion(e, u, steps=1000, transient=1000, y0=1.0, v0=0.0) -> Motion

    Whether the orbit slides, and if not its impacts per step and Lyapunov exponents.

    The Poincare map (Prop. 2.3) is iterated ``transient + steps`` times from
    ``(y0, v0)``, with the tangent map (:func:`step_jacobian`) applied to a
    vector (rescaled by exact powers of two) for ``lambda_1`` and to a second,
    Gram-Schmidt-orthonormalised vector for ``lambda_2`` (QR).  Averages are
    over the kept ``steps``; each has a convergence estimate, the difference
    between its values over the first and the second half of the kept steps.

    Returns a :class:`Motion` (attributes, or keys as the dict it used to
    be; its repr is one line): ``slides`` (bool), ``slide_step`` (first sliding step,
    1-based, transient included; 0 if none), ``k_mean`` (<k>), ``k_err``,
    ``jump_mean`` (kept steps per landing), ``lyap1``, ``lyap1_err``,
    ``lyap2`` (QR), ``lyap2_err``, ``lyap2_identity`` (``2 <k> log e -
    lambda_1``, what :func:`motion_scan` reports), ``dissipation``
    (-> 1), ``impulse`` (-> 1/u), and ``state_start``, ``state_end`` (the
    states ``(y, v)`` at the start and end of the kept steps).  On a sliding
    orbit the averages are NaN and the exponents ``-inf`` (J = 0 on that step).

    Parameters
    ----------
    e : float in [0, 1); u : float > 0
    steps : int >= 2, default 1000
        Kept steps.
    transient : int >= 0, default 1000
        Steps iterated first and discarded (the tangent vector aligns too).
    y0, v0 : float, default 1.0, 0.0
        Initial state at a step edge (the paper's ``(1, 0)``).

    Identities (module docstring): ``lyap1 + lyap2 = 2 k_mean log e``,
    ``dissipation = 1 + (E_0 - E_N)/N``, ``impulse = 1/u + (v_N - v_0)/N``.
    """
    e = check_e(e)
    u = check_u(u)
    y0, v0 = check_state(y0, v0, "y0", "v0")
    steps, transient = _check_steps(steps, transient)
    T, ratio = _constants(e, u)
    out = np.empty(_NF)
    extra = np.full(6, np.nan)
    _motion_orbit(y0, v0, e, T, ratio, transient, steps, out, extra)
    r = {name: float(out[i]) for i, name in enumerate(MOTION_FIELDS)}
    r["slide_step"] = int(out[0])
    r["slides"] = r["slide_step"] > 0
    r["lyap2_identity"] = r.pop("lyap2")
    r["lyap2"] = float(extra[4]) if not r["slides"] else -math.inf
    r["lyap2_err"] = float(extra[5])
    if r["slides"]:
        r["lyap2"] = -math.inf
    r["speed_spread"] = speed_spread(r["k_mean"], r["impulse"], r["dissipation"], e)
    r["state_start"] = (float(extra[0]), float(extra[1]))
    r["state_end"] = (float(extra[2]), float(extra[3]))
    r["steps"] = steps
    r["transient"] = transient
    return Motion(e=e, u=u, **r)


@dataclass(frozen=True, repr=False)
class Motion(Mapping):
    """What :func:`motion` measured on one orbit, with a one-line repr.

    The fields are those :func:`motion` documents; they read as attributes
    (``r.k_mean``) or, as the dict this used to be, by key (``r["k_mean"]``,
    ``dict(r)``, ``"lyap1" in r``).  ``e`` and ``u`` are the parameters.
    """

    e: float
    u: float
    steps: int
    transient: int
    slides: bool
    slide_step: int
    k_mean: float
    k_err: float
    jump_mean: float
    lyap1: float
    lyap1_err: float
    lyap2: float
    lyap2_err: float
    lyap2_identity: float
    dissipation: float
    impulse: float
    speed_spread: float
    state_start: tuple
    state_end: tuple

    def __getitem__(self, key):
        if not isinstance(key, str) or key not in self.__dataclass_fields__:
            raise KeyError(key)
        return getattr(self, key)

    def __iter__(self):
        return iter(self.__dataclass_fields__)

    def __len__(self):
        return len(self.__dataclass_fields__)

    def __repr__(self) -> str:
        head = f"Motion(e={self.e:g}, u={self.u:g}, {self.transient} + {self.steps} steps: "
        if self.slides:
            return head + f"slides on step {self.slide_step})"
        return head + (f"no slide, <k> = {self.k_mean:.6g}, mean jump {self.jump_mean:.6g}, "
                       f"lambda_1 = {self.lyap1:.2e}, lambda_2 = {self.lyap2:.6g})")


def _check_memory(npix):
    """The kernel's output and the dataset's copy of it: 2 x 9 float64 per pixel."""
    from .plane import _available_memory, _human

    need = 2 * 8 * _NF * npix
    avail = _available_memory()
    if avail is not None and need > avail:
        raise ValueError(
            f"a motion scan of {npix} pixels needs about {_human(need)}, more than the "
            f"{_human(avail)} of memory available: reduce the size or scan tiles (motion_coords)"
        )


def _coords(name, values):
    from .plane import _coords as plane_coords

    return plane_coords(name, values)


def motion_coords(e_values, u_values, steps=1000, transient=1000, y0=1.0, v0=0.0, kernel="fast"):
    """motion_coords(e_values, u_values, steps=1000, transient=1000, y0=1.0, v0=0.0) -> xarray.Dataset

    :func:`motion_scan` on arbitrary 1-D coordinate arrays.

    Pixels are independent and every pixel runs the arithmetic of
    :func:`motion` (minus its QR lambda_2), so a tile cut out of a
    :func:`stairbounce.plane.pixel_centres` grid gives the same values, bit
    for bit, as the whole scan, whatever the number of threads.
    ``kernel="plain"`` runs the one-pixel-at-a-time baseline (same values).
    """
    es = _coords("e", e_values)
    us = _coords("u", u_values)
    steps, transient = _check_steps(steps, transient)
    y0, v0 = check_state(y0, v0, "y0", "v0")
    if kernel not in ("fast", "plain"):
        raise ValueError(f"kernel must be 'fast' or 'plain', got {kernel!r}")
    _check_memory(es.size * us.size)
    out = np.empty((us.size, es.size, _NF))
    if kernel == "fast":
        _motion_fast(es, us, y0, v0, transient, steps, _chunking(es.size * us.size), _CHUNK, out)
    else:
        _motion_plain(es, us, y0, v0, transient, steps, out)

    data_vars = {}
    for f, (name, desc) in enumerate(MOTION_FIELDS.items()):
        a = out[:, :, f]
        if name == "slide_step":
            a = a.astype(np.int32)
        data_vars[name] = (("u", "e"), np.ascontiguousarray(a), {"long_name": desc})
    coords = {
        "e": ("e", es, {"long_name": "restitution coefficient e"}),
        "u": ("u", us, {"long_name": "horizontal speed u (normalised units)"}),
    }
    attrs = {
        "title": "non-sliding motion: impacts per step and Lyapunov exponents in the (e, u) plane",
        "steps": steps,
        "transient": transient,
        "y0": y0,
        "v0": v0,
        "kernel": f"stairbounce.nonsliding._motion_{kernel}",
        "stairbounce_version": __version__,
        "reference": "Campos, Romero-Valles, Torres, Prop. 2.3; issue 13",
    }
    return with_speed(xr.Dataset(data_vars, coords=coords, attrs=attrs), staircase_of(u_values))


def motion_scan(e=(0.0, 1.0, 500), u=(0.0, 1.5, 350), steps=1000, transient=1000, y0=1.0, v0=0.0,
                *, progress=None, kernel="fast"):
    """motion_scan(e=(e_min, e_max, n_e), u=(u_min, u_max, n_u), steps=1000, transient=1000, y0=1.0, v0=0.0, *, progress=None) -> xarray.Dataset

    :func:`motion` at every pixel centre of an ``n_u x n_e`` grid of the (e, u) plane.

    Data variables (dims ``("u", "e")``): the fields of :data:`MOTION_FIELDS`
    (``slide_step`` int32, the rest float64; averages NaN where the orbit
    slides, ``lyap1 = lyap2 = -inf`` where it slides: J = 0 on that step).
    ``lyap2`` is ``2 <k> log e - lambda_1`` (the determinant identity).

    Kernel ``_motion_fast``: every pixel iterated (no pruning), chunks of 64
    pixels interleaved over threads, four pixels of a chunk in lockstep;
    ``_motion_plain`` (one pixel at a time) is its baseline and gives the same
    values bit for bit.  Tiles: pass sub-arrays of the
    :func:`stairbounce.plane.pixel_centres` coordinates to
    :func:`motion_coords`; results are the same bit for bit.

    Parameters
    ----------
    e, u : (lo, hi, n) or (lo, hi), default (0, 1, 500) and (0, 1.5, 350), as in
        :func:`stairbounce.plane.scan` (the paper's Fig. 4 grid; a count left
        out makes square pixels).
    steps : int >= 2, default 1000; transient : int >= 0, default 1000
    y0, v0 : float, default 1.0, 0.0
    progress : callable ``progress(rows_done, rows_total)``, optional
        Rows are then computed in about 50 blocks (same values).
    """
    from .plane import _windows, pixel_centres

    (e_min, e_max, n_e), (u_min, u_max, n_u) = _windows(e, u)
    es = pixel_centres(e_min, e_max, n_e)
    us = pixel_centres(u_min, u_max, n_u)
    if progress is None:
        ds = motion_coords(es, us, steps, transient, y0, v0, kernel)
    else:
        progress(0, n_u)
        block = max(1, -(-n_u // 50))
        parts = []
        for r in range(0, n_u, block):
            parts.append(motion_coords(es, us[r : r + block], steps, transient, y0, v0, kernel))
            progress(min(r + block, n_u), n_u)
        ds = xr.concat(parts, dim="u", combine_attrs="override") if len(parts) > 1 else parts[0]
    ds.attrs.update(e_min=e_min, e_max=e_max, n_e=n_e, u_min=u_min, u_max=u_max, n_u=n_u)
    return with_speed(ds, staircase_of(u))


# --------------------------------------------------------------------------- #
# One impact every n steps                                                    #
# --------------------------------------------------------------------------- #


def one_impact_family(n, e):
    """one_impact_family(n, e) -> u

    The curve ``u_n(e) = sqrt(n (1-e) / (2 (1+e)))`` on which the ball can land once every n steps forever.

    Derivation.  Take off from a floor with speed ``w``; land ``n`` steps
    (height ``n``) lower after ``tau = w + sqrt(w^2 + 2n)`` with impact speed
    ``sqrt(w^2 + 2n)``.  The motion repeats when the take-off speed comes back,
    ``e sqrt(w^2 + 2n) = w``, i.e. ``w = e S`` with ``S = sqrt(2n / (1-e^2))``,
    and ``tau = w + w/e = (1+e) S = sqrt(2n (1+e)/(1-e))``; the ball has moved
    exactly n steps when ``tau = n T = n/u``, which gives ``u_n(e)``.

    On the curve the impact point ``x_0`` within a step is free: with
    ``delta = x_0 T`` (time from the edge to the impact) the flight clears every
    edge iff ``delta >= T - 2w`` (first edge) and ``delta^2 - 2 S delta + 2 <= 0``
    (last edge; in between the flight is concave against the staircase's
    corners), and that interval meets ``[0, T)`` for every e in (0, 1) and
    n >= 1.  So a one-parameter family of n-periodic orbits with one impact per
    period (:func:`one_impact_state`): ``<k> = 1/n`` exactly; ``P^n`` has
    eigenvalues 1 (along the family) and ``e^2`` (the determinant), so
    ``lambda_1 = 0`` and ``lambda_2 = (2/n) log e``.

    Compare Theorem 3.1's tongue edge ``sqrt(n/2) (1-e)/(1+e)``: ``u_n`` is its
    geometric mean with ``sqrt(n/2)``, so the families lie above the tongues.

    Parameters: n int >= 1; e float or array in (0, 1).
    """
    n = check_count("n", n, 1)
    e_arr = np.asarray(e, dtype=float)
    if not np.all((e_arr > 0.0) & (e_arr < 1.0)):
        raise ValueError("e (restitution coefficient) must be in (0, 1) for a one-impact family")
    r = np.sqrt(n * (1.0 - e_arr) / (2.0 * (1.0 + e_arr)))
    return float(r) if r.ndim == 0 else r


def one_impact_state(n, e, phase=0.5):
    """one_impact_state(n, e, phase=0.5) -> (u, y, v)

    A member of the one-impact-per-n-steps family (:func:`one_impact_family`): its ``u`` and the edge state just after a landing.

    ``phase`` in (0, 1) picks the impact time ``delta`` within the feasible
    interval ``[max(T - 2w, S - sqrt(S^2 - 2), 0), min(T, S + sqrt(S^2 - 2))]``
    (0: its start, 1: its end).  The state returned is the one at the first
    edge after the impact: ``y = w tau_1 - tau_1^2/2 + 1``, ``v = w - tau_1``
    with ``tau_1 = T - delta``; P^n maps it to itself with one impact.
    """
    n = check_count("n", n, 1)
    e = check_e(e)
    if e == 0.0:
        raise ValueError("e (restitution coefficient) must be in (0, 1) for a one-impact family")
    phase = _finite("phase", phase)
    if not 0.0 < phase < 1.0:
        raise ValueError(f"phase must be in (0, 1), got {phase}")
    u = one_impact_family(n, e)
    T = 1.0 / u
    S = math.sqrt(2.0 * n / (1.0 - e * e))
    w = e * S
    r = math.sqrt(S * S - 2.0)
    lo = max(T - 2.0 * w, 2.0 / (S + r), 0.0)
    hi = min(T, S + r)
    delta = lo + phase * (hi - lo)
    tau1 = T - delta
    return u, w * tau1 - 0.5 * tau1 * tau1 + 1.0, w - tau1


def k_mean_bound(e, u):
    """k_mean_bound(e, u) -> float or array

    The lower bound ``<k>_0 = (1 - e) / (2 (1 + e) u^2)`` of the impacts per step of a long non-sliding orbit.

    From the energy and momentum balances and Cauchy-Schwarz (module
    docstring); equality exactly on the one-impact families, where it is
    ``1/n``.  Vectorised over ``e`` in [0, 1) and ``u > 0``.
    """
    e = np.asarray(e, dtype=float)
    u = np.asarray(u, dtype=float)
    if not (np.all((e >= 0) & (e < 1)) and np.all(u > 0)):
        raise ValueError("e (restitution coefficient) must be in [0, 1) and u (horizontal speed) > 0")
    r = (1.0 - e) / (2.0 * (1.0 + e) * u * u)
    return float(r) if r.ndim == 0 else r


def speed_spread(k_mean, impulse, dissipation, e):
    """speed_spread(k_mean, impulse, dissipation, e) -> float or array

    The relative variance ``Var|v_-| / <|v_-|>^2`` of the impact speeds over the kept steps.

    ``= 2 (1+e) <k> dissipation / ((1-e) impulse^2) - 1`` (module docstring:
    the balances give ``sum |v_-|`` and ``sum |v_-|^2``), >= 0 exactly, 0 on
    the one-impact families.  Takes the fields of :func:`motion` or
    :func:`motion_scan` (arrays broadcast); NaN where the orbit slides.
    """
    k = np.asarray(k_mean, dtype=float)
    e = np.asarray(e, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        r = 2.0 * (1.0 + e) * k * np.asarray(dissipation, float) / (
            (1.0 - e) * np.asarray(impulse, float) ** 2) - 1.0
    return float(r) if r.ndim == 0 else r
