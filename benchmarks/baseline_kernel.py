"""The frozen baseline of every scan speed ratio (issue 26): a plain per-pixel kernel.

    FROZEN: never edit this file when the production kernels (stairbounce.plane,
    stairbounce.model) change.  It is the yardstick the speed ratios of
    benchmarks/README.md are measured against, in the same process; a ratio
    means something across rounds only while this kernel stays the same.  If it
    must ever change (a numba API going away), say so in benchmarks/README.md
    with the ratio of the old and new versions measured side by side.

It is the kernel ``_scan_plain`` of the first speed issue (issue 3, commit
864c12e), self-contained: per pixel, the paper's closed form as printed
(Prop. 2.2 with ``log``, eq. (2.2) with ``e**k``, Prop. 2.3), one pixel after
another, ``prange`` over rows, every pixel iterated (no pruning, no lanes).
It imports nothing from stairbounce, so later changes of the model (the
cancellation-free closed form of issue 17 made today's ``_scan_plain``
1.6-1.7x slower) cannot move it.

Its answers are those of the production scan wherever the printed form's
rounding does not matter (tests/test_baseline_kernel.py checks a grid of the
paper's plane): it is a yardstick of speed, not a reference of values.

    from baseline_kernel import baseline_scan
    out = baseline_scan(es, us, max_iter)   # dict of (n_u, n_e) arrays
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

_SLIDING = -1


@njit(cache=True)
def _constants(e, u):
    return 1.0 / u, (1.0 + e) / (1.0 - e)


@njit(cache=True)
def _slides(y, v, T, ratio):
    """(2.4): v + (1+e)/(1-e) sqrt(v^2 + 2y) <= T."""
    return v + ratio * math.sqrt(v * v + 2.0 * y) <= T


@njit(cache=True)
def _impact_time(v, s, e, k):
    """Eq. (2.2) as printed: t_k = v + (1+e-2e^k)/(1-e) s."""
    return v + (1.0 + e - 2.0 * e**k) / (1.0 - e) * s


@njit(cache=True)
def _impact_number(y, v, e, T):
    """Prop. 2.2 as printed, k = E[log_e((v - T)(1-e)/(2s) + (1+e)/2)], corrected by one or two."""
    s = math.sqrt(v * v + 2.0 * y)
    if v + s > T:
        return 0
    if e == 0.0:
        return _SLIDING
    arg = (v - T) * (1.0 - e) / (2.0 * s) + 0.5 * (1.0 + e)
    if arg <= 0.0:
        return _SLIDING
    kf = math.floor(math.log(arg) / math.log(e))
    if kf > 1.0e6:
        kf = 1.0e6
    k = max(int(kf), 1)
    for _ in range(4):
        if k > 1 and _impact_time(v, s, e, k) > T:
            k -= 1
        elif _impact_time(v, s, e, k + 1) <= T:
            k += 1
        else:
            break
    return k


@njit(cache=True)
def _step(y, v, e, T, ratio):
    """Prop. 2.3 with the impact number of Prop. 2.2: log and pow on every step with impacts."""
    if _slides(y, v, T, ratio):
        return 1.0, 0.0, _SLIDING
    s = math.sqrt(v * v + 2.0 * y)
    k = _impact_number(y, v, e, T)
    if k == _SLIDING:
        return 1.0, 0.0, _SLIDING
    if k == 0:
        return y + v * T - 0.5 * T * T + 1.0, v - T, 0
    tk = _impact_time(v, s, e, k)
    vk = e**k * s
    d = T - tk
    return -0.5 * d * d + vk * d + 1.0, vk - d, k


@njit(cache=True)
def _slide_or_steps(y, v, e, T, ratio, max_steps):
    impacts = 0
    jumps = 0
    for n in range(1, max_steps + 1):
        y, v, k = _step(y, v, e, T, ratio)
        if k == _SLIDING:
            return n, impacts, jumps + 1
        if k > 0:
            impacts += k
            jumps += 1
    return 0, impacts, jumps


@njit(cache=True)
def _store(i, j, n, imp, jmp, status, word_length, jumps, period, impacts):
    if n == 0:
        status[i, j] = 1
        word_length[i, j] = 0
        jumps[i, j] = 0
        period[i, j] = 0
        impacts[i, j] = 0
    else:
        status[i, j] = 0
        word_length[i, j] = imp + 1
        jumps[i, j] = jmp
        period[i, j] = n
        impacts[i, j] = imp


@njit(cache=True, parallel=True)
def baseline_kernel(es, us, max_iter, y0, v0, status, word_length, jumps, period, impacts):
    """Per pixel the printed closed form, ``prange`` over rows; outputs ``n_u x n_e``."""
    from_rest = y0 == 1.0 and v0 == 0.0
    for i in prange(us.shape[0]):
        for j in range(es.shape[0]):
            e = es[j]
            T, ratio = _constants(e, us[i])
            n = 1
            if not from_rest:
                n, _, _ = _slide_or_steps(y0, v0, e, T, ratio, max_iter)
            imp = 0
            jmp = 0
            if n != 0:
                n, imp, jmp = _slide_or_steps(1.0, 0.0, e, T, ratio, max_iter)
            _store(i, j, n, imp, jmp, status, word_length, jumps, period, impacts)


FIELDS = {
    "status": np.uint8,
    "word_length": np.int64,
    "jumps": np.int32,
    "period": np.int32,
    "impacts": np.int64,
}


def baseline_scan(es, us, max_iter, y0=1.0, v0=0.0):
    """The frozen kernel on the grid ``us x es``: a dict of ``(n_u, n_e)`` arrays."""
    es = np.ascontiguousarray(es, dtype=np.float64)
    us = np.ascontiguousarray(us, dtype=np.float64)
    out = {k: np.empty((us.size, es.size), dtype=dt) for k, dt in FIELDS.items()}
    baseline_kernel(es, us, int(max_iter), float(y0), float(v0), out["status"], out["word_length"],
                    out["jumps"], out["period"], out["impacts"])
    return out
