"""The numerical half of the reliability campaign (issue 17), rerunnable.

Random and extreme states through the Poincare map, against the 60-digit
impact-by-impact reference of ``tests/naive.py`` (``precise_step``, judged by
``classify``: "ok", "ok-conditioned" = right up to the rounding of T = 1/u,
"k-mismatch", "value-mismatch"), plus the cheap invariants over many more
states (no exception but ValueError, no NaN/inf, never below the edge).
Prints counts per regime and the worst cases; exits 1 when anything is wrong.

    python scripts/campaign_numeric.py            # about a minute on an idle 2-core machine
    python scripts/campaign_numeric.py --n 20000  # the report's sample size (much longer)

Regimes (as in the report's section 2): the stated ranges (e in [0, 1),
u in (0, 10], y in [0, 100], v in [-100, 100], half skewed towards many
impacts), e within 1e-12 of 1, u near 0, y = 1e12, e near 1 with u near 0,
e near 1 with u ~ (1 - e) (up to 1e17 impacts), and the accuracy grid of
1 - e from 1e-3 to 2^-53 against the number of impacts.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT / "src"), str(ROOT)]

import stairbounce as sb  # noqa: E402
from tests import naive  # noqa: E402


def stated(rng, n):
    half = n // 2
    e = np.concatenate([rng.uniform(0, 1, half), 1 - 10.0 ** rng.uniform(-12, 0, n - half)])
    u = np.concatenate([rng.uniform(1e-9, 10, half), 10.0 ** rng.uniform(-3, 1, n - half)])
    y = np.concatenate([rng.uniform(0, 100, half), 10.0 ** rng.uniform(-6, 2, n - half)])
    v = rng.uniform(-100, 100, n)
    return zip(y, v, e, u)


def near_one(rng, n):
    return zip(rng.uniform(0, 100, n), rng.uniform(-100, 100, n), 1 - 10.0 ** rng.uniform(-16, -12, n),
               rng.uniform(0.01, 10, n))


def u_small(rng, n):
    return zip(rng.uniform(0, 100, n), rng.uniform(-100, 100, n), rng.uniform(0, 1, n),
               10.0 ** rng.uniform(-150, -12, n))


def y_huge(rng, n):
    return zip(np.full(n, 1e12), rng.uniform(-100, 100, n), rng.uniform(0, 1, n), rng.uniform(1e-6, 10, n))


def near_one_u_small(rng, n):
    return zip(rng.uniform(0, 100, n), rng.uniform(-100, 100, n), 1 - 10.0 ** rng.uniform(-16, -9, n),
               10.0 ** rng.uniform(-18, -9, n))


def many_impacts(rng, n):
    d = 10.0 ** rng.uniform(-16, -3, n)
    y, v = rng.uniform(0, 100, n), rng.uniform(-100, 100, n)
    s = np.sqrt(v * v + 2 * y)
    # T a fraction of the accumulation time t_1 + 2 s e/(1-e): many impacts, no slide
    T = v + s + 2 * s * (1 - d) / d * rng.uniform(0.05, 0.999, n)
    return zip(y, v, 1 - d, 1 / np.maximum(T, 1e-300))


def extremes(rng, n):
    """Edges of the valid range: y up to 1e300, |v| up to 1e150, u down to 1e-150."""
    y = 10.0 ** rng.uniform(-300, 300, n)
    v = rng.choice([-1, 1], n) * 10.0 ** rng.uniform(-150, 150, n)
    u = 10.0 ** rng.uniform(-150, 150, n)
    return zip(y, v, rng.uniform(0, 1, n), u)


REGIMES = {
    "stated ranges": stated,
    "e within 1e-12 of 1": near_one,
    "u near 0": u_small,
    "y = 1e12": y_huge,
    "e near 1, u near 0": near_one_u_small,
    "e near 1, many impacts": many_impacts,
    "edges of the valid range": extremes,
}


def run_regime(name, states, compare_every):
    counts = Counter()
    worst = []
    t0 = time.perf_counter()
    for i, (y, v, e, u) in enumerate(states):
        try:
            res = sb.poincare_map(float(y), float(v), float(e), float(u))
        except ValueError:
            counts["refused (ValueError)"] += 1
            continue
        except Exception as exc:  # noqa: BLE001 - counting what the contract forbids
            counts[f"exception {type(exc).__name__}"] += 1
            continue
        counts["states"] += 1
        if not (math.isfinite(res[0]) and math.isfinite(res[1])):
            counts["NaN/inf"] += 1
        if res[0] < 1.0 - 1e-12 * (1 + abs(y) + v * v):
            counts["below the edge"] += 1
        if i % compare_every == 0:
            verdict, err = naive.classify(y, v, e, u, res)
            counts[f"vs reference: {verdict}"] += 1
            if verdict not in ("ok", "ok-conditioned"):
                worst.append((verdict, (float(y), float(v), float(e), float(u)), res))
    counts["seconds"] = round(time.perf_counter() - t0, 1)
    return counts, worst


def accuracy_grid(rng, per_cell):
    """Worst error of (y, v) per (1 - e, impact count) cell in units of
    eps (T + |v| + s + 1), the edge placed mid-bounce."""
    import mpmath

    deltas = [1e-3, 1e-6, 1e-9, 1e-12, 1e-13, 1e-14, 1e-15, 2.0**-53]
    ks = [5, 8, 20, 100, 10**4, 10**6, 10**9, 10**12, 10**15, 10**17]
    rows = []
    bad = 0
    for delta in deltas:
        row = []
        for kk in ks:
            if kk * delta > 30:
                row.append("-")
                continue
            errs, kwrong = [], 0
            for _ in range(per_cell):
                y, v = float(10.0 ** rng.uniform(-3, 2)), float(rng.uniform(-5, 5))
                with mpmath.workdps(60):
                    me = mpmath.mpf(1.0 - delta)
                    s = mpmath.sqrt(mpmath.mpf(v) ** 2 + 2 * mpmath.mpf(y))
                    tk = mpmath.mpf(v) + s + 2 * me * s * (1 - me ** (kk - 1)) / (1 - me)
                    u = float(1 / (tk + 2 * me**kk * s * mpmath.mpf(rng.uniform(0.1, 0.9))))
                res = sb.poincare_map(y, v, 1.0 - delta, u)
                verdict, err = naive.classify(y, v, 1.0 - delta, u, res)
                if verdict == "ok":
                    T, sp = 1.0 / u, math.sqrt(v * v + 2 * y)
                    errs.append(err / (naive.EPS * (T + abs(v) + sp + 1.0)))
                elif verdict == "ok-conditioned":
                    kwrong += 1
                else:
                    bad += 1
                    errs.append(float("inf"))
            cell = f"{max(errs):.2g}" if errs else "cond."
            if kwrong:
                cell += f" ({kwrong} cond.)"
            row.append(cell)
        rows.append((delta, row))
    return ks, rows, bad


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--n", type=int, default=20000, help="states per regime (default 20000)")
    p.add_argument("--compare", type=int, default=1000, help="states per regime compared with the reference")
    p.add_argument("--per-cell", type=int, default=4, help="states per cell of the accuracy grid")
    p.add_argument("--seed", type=int, default=17)
    args = p.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    failures = 0
    for name, gen in REGIMES.items():
        counts, worst = run_regime(name, gen(rng, args.n), max(1, args.n // args.compare))
        print(f"{name}: " + ", ".join(f"{k} {v}" for k, v in counts.items()))
        failures += sum(v for k, v in counts.items()
                        if k.startswith("exception") or k in ("NaN/inf", "below the edge")
                        or k.endswith("mismatch"))
        for w in worst[:5]:
            print("   ", w)
    ks, rows, bad = accuracy_grid(rng, args.per_cell)
    print("\naccuracy grid: worst error of (y, v) in units of eps (T + |v| + s + 1), the rounding of")
    print("T = 1/u alone (the problem's conditioning); '(n cond.)': n states whose k is off within")
    print("that rounding (right for an edge moved by eps T); '-': the impacts accumulate first")
    print("| 1 - e | " + " | ".join(f"k~{k:.0e}" if k >= 1e4 else f"k~{k}" for k in ks) + " |")
    for delta, row in rows:
        print(f"| {delta:.1e} | " + " | ".join(row) + " |")
    failures += bad
    print(f"\n{'FAILED' if failures else 'all good'}: {failures} wrong results")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
