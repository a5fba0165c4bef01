"""The scaling law of a cascade's widths and the accumulation of its positions, and the
curves known in closed form an accumulation point may lie on.  Moved verbatim from
``cascades.py``."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import _validate as _v
from ..model import check_count, no_sliding_bound

__all__ = ["CascadeLaw", "cascade_law"]


# --------------------------------------------------------------------------- #
# The law                                                                     #
# --------------------------------------------------------------------------- #


@dataclass(frozen=True)
class CascadeLaw:
    """How a cascade's members shrink and where they accumulate; see :func:`cascade_law`.

    ``kind`` is ``"geometric"`` (``w_k ~ C r^k``: ``ratio`` r and
    ``ratio_interval``), ``"algebraic"`` (``w_k ~ C k^-gamma``: ``exponent``
    gamma and ``exponent_interval``) or ``"undecided"`` (neither model fits
    ``threshold`` times better than the other, or too few members).  Both
    estimates are always given.  ``residual_geometric`` and
    ``residual_algebraic`` are the RMS residuals of the two straight-line fits
    (log w against k, log w against log k) on the members ``ks_used``.
    ``limit`` (with ``limit_interval``) is the extrapolated accumulation point
    of the positions, by their own law ``approach_kind`` (decided by the same
    criterion on the gaps between consecutive positions; three-point fits,
    Aitken's for the geometric law); ``approach`` is that law's local
    parameter there (the ratio of successive gaps, or the exponent beta of
    ``a_k = L + C k^-beta``), with ``approach_interval``.  All numerical.
    """

    kind: str
    ratio: float
    ratio_interval: tuple[float, float]
    exponent: float
    exponent_interval: tuple[float, float]
    residual_geometric: float
    residual_algebraic: float
    threshold: float
    ks_used: tuple[int, ...]
    limit: float = math.nan
    limit_interval: tuple[float, float] = (math.nan, math.nan)
    approach: float = math.nan
    approach_interval: tuple[float, float] = (math.nan, math.nan)
    approach_kind: str = "undecided"

    @property
    def criterion(self) -> str:
        """The rule that decided ``kind``, in words."""
        return (f"geometric if the RMS residual of log w against k is {self.threshold:g} times smaller "
                f"than that of log w against log k on the last {len(self.ks_used)} members, algebraic "
                "if the reverse, undecided otherwise; intervals span the local ratios / exponents of "
                "those members")

    def text(self) -> str:
        """One line: the law, its parameter with its interval, and the residuals."""
        if self.kind == "geometric":
            law = (f"geometric: ratio {self.ratio:.4g} in [{self.ratio_interval[0]:.4g}, "
                   f"{self.ratio_interval[1]:.4g}]")
        elif self.kind == "algebraic":
            law = (f"algebraic: exponent {self.exponent:.4g} in [{self.exponent_interval[0]:.4g}, "
                   f"{self.exponent_interval[1]:.4g}]")
        else:
            law = (f"undecided (ratio {self.ratio:.4g}, exponent {self.exponent:.4g})")
        k = self.ks_used
        span = f"k = {k[0]}..{k[-1]}" if k else "no members"
        return (f"{law}; residuals geometric {self.residual_geometric:.2g}, algebraic "
                f"{self.residual_algebraic:.2g} ({span})")


def _line_fit(x, y):
    a = np.vstack([np.ones_like(x), x]).T
    coef, *_ = np.linalg.lstsq(a, y, rcond=None)
    res = y - a @ coef
    return coef, float(np.sqrt(np.mean(res**2)))


def _algebraic_beta(k, a):
    """beta such that a_k = L + C k^-beta passes through three consecutive
    points (k, k+1, k+2): the ratio of the two gaps fixes beta (bisection)."""
    g = (a[2] - a[1]) / (a[1] - a[0])
    if not (0.0 < g < 1.0):
        return math.nan

    def ratio(b):
        return ((k + 2) ** -b - (k + 1) ** -b) / ((k + 1) ** -b - k**-b)

    lo, hi = 1e-6, 60.0
    if not (ratio(hi) < g < ratio(lo)):
        return math.nan
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if ratio(mid) > g:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _limits(kind, ks, pos):
    """Local estimates of the accumulation point and of the approach
    parameter, one per triple of consecutive members."""
    lims, pars = [], []
    for i in range(len(ks) - 2):
        if ks[i + 2] - ks[i] != 2:
            continue
        a = pos[i:i + 3]
        d0, d1 = a[1] - a[0], a[2] - a[1]
        if d0 == 0 or (d1 / d0) <= 0:
            continue
        if kind == "geometric":
            if d1 == d0:
                continue
            lims.append(a[2] - d1 * d1 / (d1 - d0))  # Aitken's delta-squared
            pars.append(d1 / d0)
        else:
            b = _algebraic_beta(float(ks[i]), a)
            if not math.isfinite(b):
                continue
            c = d0 / ((ks[i] + 1) ** -b - ks[i] ** -b)
            lims.append(a[2] - c * (ks[i] + 2) ** -b)
            pars.append(b)
    return np.asarray(lims), np.asarray(pars)


def cascade_law(k, widths, positions=None, *, tail=8, threshold=3.0):
    """cascade_law(k, widths, positions=None, *, tail=8, threshold=3.0) -> CascadeLaw

    Decide whether the widths of a cascade's members shrink geometrically or
    algebraically, and extrapolate where the members accumulate.

    On the last ``tail`` members (at least 4) two straight lines are fitted:
    ``log w_k = a + k log r`` (geometric: a hyperbolic limit orbit, multiplier
    1/r) and ``log w_k = a - gamma log k`` (algebraic: a neutral limit,
    multiplier 1; Jeffrey and Dankowicz's two scaling laws of discontinuity
    induced cascades).  The law whose RMS residual is ``threshold`` times
    smaller than the other's is chosen, else ``"undecided"``: the criterion
    fails on sequences that follow neither.  Intervals are the ranges of the
    local values on those members: ``w_{k+1} / w_k`` for the ratio,
    ``-log(w_{k+1}/w_k) / log((k+1)/k)`` for the exponent (they drift where
    the law holds only asymptotically; the interval shows the drift).  With
    ``positions`` (an edge of each member), the limit is extrapolated from
    each triple of consecutive members with the law decided (Aitken's
    delta-squared for geometric, ``a_k = L + C k^-beta`` through the three
    points for algebraic), the positions' law decided by the same criterion
    on their gaps (``approach_kind``); ``limit`` is the last triple's,
    ``limit_interval`` the range over the last ``tail`` triples.  Numerical, not proven; checked
    on maps whose laws are known in closed form (tests/test_cascades.py).

    Parameters
    ----------
    k : sequence of int
        The members' exponents, increasing.
    widths : sequence of float > 0
    positions : sequence of float, optional
    tail : int >= 4, default 8
    threshold : float > 1, default 3.0
    """
    ks = np.asarray(k, dtype=float)
    w = np.asarray(widths, dtype=float)
    if ks.ndim != 1 or w.shape != ks.shape:
        raise ValueError(f"k and widths must be 1-d sequences of equal length, got {ks.shape} and {w.shape}")
    if ks.size and (not np.all(np.isfinite(ks)) or np.any(np.diff(ks) <= 0) or ks[0] < 1):
        raise ValueError("k must be increasing integers >= 1")
    if not np.all(np.isfinite(w) & (w > 0)):
        raise ValueError("widths must be finite and > 0")
    tail = check_count("tail", tail, 4)
    threshold = _v.real("threshold", threshold)
    if not threshold > 1.0:
        raise ValueError(f"threshold must be a number > 1, got {threshold}")
    pos = None
    if positions is not None:
        pos = np.asarray(positions, dtype=float)
        if pos.shape != ks.shape or not np.all(np.isfinite(pos)):
            raise ValueError(f"positions must be finite, one per member, got shape {pos.shape}")
    nan2 = (math.nan, math.nan)
    sel = slice(max(0, ks.size - tail), None)
    kt, wt = ks[sel], w[sel]
    used = tuple(int(a) for a in kt)
    if kt.size < 4:
        return CascadeLaw("undecided", math.nan, nan2, math.nan, nan2, math.nan, math.nan,
                          threshold, used)
    lw = np.log(wt)
    (_, slope_g), res_g = _line_fit(kt, lw)
    (_, slope_a), res_a = _line_fit(np.log(kt), lw)
    consecutive = np.diff(kt) == 1
    loc_r = (wt[1:] / wt[:-1])[consecutive]
    loc_g = (-np.log(wt[1:] / wt[:-1]) / np.log(kt[1:] / kt[:-1]))[consecutive]
    ratio, exponent = float(np.exp(slope_g)), float(-slope_a)
    r_int = (float(loc_r.min()), float(loc_r.max())) if loc_r.size else nan2
    g_int = (float(loc_g.min()), float(loc_g.max())) if loc_g.size else nan2
    floor = 1e-14  # residuals below rounding of log w are ties
    if max(res_g, floor) * threshold < max(res_a, floor):
        kind = "geometric"
    elif max(res_a, floor) * threshold < max(res_g, floor):
        kind = "algebraic"
    else:
        kind = "undecided"
    law = CascadeLaw(kind, ratio, r_int, exponent, g_int, res_g, res_a, threshold, used)
    if pos is None:
        return law
    # the positions' own law, decided the same way on the gaps between consecutive members
    # (a family that ends at finite k can shrink faster than any law while its members'
    # positions still approach the limit by one)
    pt_, kt_ = pos[sel], kt
    ok = np.diff(kt_) == 1
    gaps = np.abs(np.diff(pt_))[ok]
    kmid = (kt_[:-1] + 0.5)[ok]
    if gaps.size < 3 or not np.all(gaps > 0):
        return law
    (_, _), dg = _line_fit(kmid, np.log(gaps))
    (_, _), da = _line_fit(np.log(kmid), np.log(gaps))
    if max(dg, floor) * threshold < max(da, floor):
        approach_kind = "geometric"
    elif max(da, floor) * threshold < max(dg, floor):
        approach_kind = "algebraic"
    else:
        return law
    lims, pars = _limits(approach_kind, ks, pos)
    if lims.size == 0:
        return law
    lt, pt = lims[-tail:], pars[-tail:]
    return CascadeLaw(kind, ratio, r_int, exponent, g_int, res_g, res_a, threshold, used,
                      float(lt[-1]), (float(lt.min()), float(lt.max())),
                      float(pt[-1]), (float(pt.min()), float(pt.max())), approach_kind)


# --------------------------------------------------------------------------- #
# Known curves an accumulation point may lie on                               #
# --------------------------------------------------------------------------- #


def _known_curves(n_max=8):
    """u(e) of the families the paper and the package know in closed form."""
    from ..nonsliding import one_impact_family

    curves = [("Corollary 2.1 no-sliding bound", lambda e: no_sliding_bound(e) if e > 0 else math.inf)]
    for n in range(1, n_max + 1):
        curves.append((f"neutral one-impact family u_{n}: one landing every {n} step(s) "
                       f"(sqrt({n}(1-e)/(2(1+e))))",
                       lambda e, n=n: one_impact_family(n, e) if 0 < e < 1 else math.sqrt(n / 2.0)))
        curves.append((f"tongue ({n}, 0^inf) upper edge (Theorem 3.1)",
                       lambda e, n=n: math.sqrt(n / 2.0) * (1 - e) / (1 + e)))
        if n > 1:
            curves.append((f"tongue ({n}, 0^inf) lower edge (Theorem 3.1)",
                           lambda e, n=n: math.sqrt((n - 1) / 2.0)))
    return curves


def _curve_at(curve, axis, fixed, lo, hi):
    """Where ``curve`` crosses the line, or None."""
    if axis == 1:
        x = curve(fixed)
        return x if lo <= x <= hi else None
    g_lo, g_hi = curve(lo) - fixed, curve(hi) - fixed
    if not (math.isfinite(g_lo) and math.isfinite(g_hi)) or (g_lo > 0) == (g_hi > 0):
        return None
    a, b = lo, hi
    for _ in range(200):  # every curve here is monotone in e
        m = 0.5 * (a + b)
        if m <= a or m >= b:
            break
        if (curve(m) - fixed > 0) == (g_lo > 0):
            a = m
        else:
            b = m
    return 0.5 * (a + b)


