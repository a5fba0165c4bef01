"""Cost of the cancellation-free closed form of Prop. 2.2/2.3 (issue 17, item 4).

``model._step_closed`` now evaluates eq. (2.2) as ``t_1 + 2 e s (1 - e^(k-1))/(1-e)``
with ``expm1``/``log1p`` and ``e^k`` with ``math.pow``; the form it replaced
(below, kept only as the baseline: eq. (2.2) as printed, the logarithm of the
rounded argument, ``e ** k``) was wrong near e = 1.  Both run here on the same
random states (e in [0, 1), u in [0.05, 1.5], y in [1, 3], v in [-2, 2]), best
of three, and the ratio is printed.  The closed form serves the plain baseline
kernel ``plane._scan_plain`` on every step and the fast map only past 8 impacts.

Run: ``python benchmarks/closed_form.py [--n 2000000]``.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
from numba import njit

from stairbounce import model


@njit
def old_time(v, s, e, k):
    """Eq. (2.2) as printed: cancels near e = 1."""
    return v + (1.0 + e - 2.0 * e**k) / (1.0 - e) * s


@njit
def old_impact_number(y, v, e, T):
    s = math.sqrt(v * v + 2.0 * y)
    if v + s > T:
        return 0
    if e == 0.0:
        return -1
    arg = (v - T) * (1.0 - e) / (2.0 * s) + 0.5 * (1.0 + e)
    if arg <= 0.0:
        return -1
    kf = min(math.floor(math.log(arg) / math.log(e)), 1.0e15)
    k = max(int(kf), 1)
    for _ in range(4):
        if k > 1 and old_time(v, s, e, k) > T:
            k -= 1
        elif old_time(v, s, e, k + 1) <= T:
            k += 1
        else:
            break
    return k


@njit
def old_step_closed(y, v, e, T, ratio):
    s = math.sqrt(v * v + 2.0 * y)
    if v + ratio * s <= T:
        return 1.0, 0.0, -1
    k = old_impact_number(y, v, e, T)
    if k == -1:
        return 1.0, 0.0, -1
    if k == 0:
        return y + v * T - 0.5 * T * T + 1.0, v - T, 0
    tk = old_time(v, s, e, k)
    vk = e**k * s
    d = min(max(T - tk, 0.0), 2.0 * vk)
    return -0.5 * d * d + vk * d + 1.0, vk - d, k


@njit
def run(new, ys, vs, es, us):
    acc = 0.0
    for i in range(ys.size):
        T, r = 1.0 / us[i], (1.0 + es[i]) / (1.0 - es[i])
        if new:
            a, b, k = model._step_closed(ys[i], vs[i], es[i], T, r)
        else:
            a, b, k = old_step_closed(ys[i], vs[i], es[i], T, r)
        acc += a + b + k
    return acc


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--n", type=int, default=2_000_000, help="random states (default 2e6)")
    n = p.parse_args().n
    rng = np.random.default_rng(0)
    es, us = rng.uniform(0, 1, n), rng.uniform(0.05, 1.5, n)
    ys, vs = rng.uniform(1, 3, n), rng.uniform(-2, 2, n)
    run(True, ys[:10], vs[:10], es[:10], us[:10])  # compile
    best = {True: math.inf, False: math.inf}
    for _ in range(3):
        for new in (False, True):
            t = time.perf_counter()
            run(new, ys, vs, es, us)
            best[new] = min(best[new], time.perf_counter() - t)
    print(f"_step_closed on {n} random states: printed form {n / best[False] / 1e6:.1f} M steps/s, "
          f"cancellation-free {n / best[True] / 1e6:.1f} M steps/s, time ratio {best[True] / best[False]:.2f}")


if __name__ == "__main__":
    main()
