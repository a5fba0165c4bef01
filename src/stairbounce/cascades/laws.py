"""The scaling law of a cascade's widths and the accumulation of its positions, and the
curves known in closed form an accumulation point may lie on.  Moved verbatim from
``cascades.py``; the asymptotic extrapolations (issue 43, item 4) added."""

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

    ``kind`` is ``"geometric"`` (``w_k ~ C r^k``), ``"algebraic"``
    (``w_k ~ C k^-gamma``) or ``"undecided"`` (neither straight line fits
    ``threshold`` times better than the other, or too few members).  Both
    parameters are always given, each three ways (the extrapolations use the
    members from half the last k on, at least those of the law):

    - ``ratio`` / ``exponent`` with ``ratio_interval`` / ``exponent_interval``:
      the **asymptotic** value (k -> inf), an *extrapolation* (numerical, not an
      enclosure): the local values of the members (``w_{k+1} / w_k``, and
      ``-log(w_{k+1}/w_k) / log((k+1)/k)``) fitted as ``V + c_1/k + c_2/k^2``
      (the finite-k corrections a law ``C k^-p (1 + a/k + b/k^2 + ...)``
      produces: for ``C/(k(k+1))`` the local exponent is ``2 - 1/k + O(1/k^2)``),
      the interval the estimate +- (its difference from the fit without the
      ``1/k^2`` term + 3 standard errors);
    - ``ratio_fit`` / ``exponent_fit``: the slopes of the straight lines (log w
      against k, against log k) whose RMS residuals, ``residual_geometric`` and
      ``residual_algebraic``, decide ``kind``;
    - ``ratio_local`` / ``exponent_local``: the range of the local values on
      ``ks_used`` (finite-k values: they drift where the law holds only
      asymptotically, and need not contain the asymptotic value).

    ``limit`` (with ``limit_interval``) is the accumulation point of the
    positions, an *extrapolation* too: the local limits (one per triple of
    consecutive members, by the positions' own law ``approach_kind``, decided
    by the same criterion on the gaps: Aitken's delta-squared for the
    geometric law, ``a_k = L + C k^-beta`` through the three points for the
    algebraic one) extrapolated to k -> inf as above in powers ``k^-(beta+1)``,
    ``k^-(beta+2)``; ``limit_local`` is the last triple's.  ``approach`` is the
    positions' local parameter at the last triple (the ratio of successive
    gaps, or beta), ``approach_interval`` the range of the local values.  All
    numerical; the enclosure of an accumulation point is
    :attr:`stairbounce.Cascade.limit_enclosure`.
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
    ratio_fit: float = math.nan
    exponent_fit: float = math.nan
    ratio_local: tuple[float, float] = (math.nan, math.nan)
    exponent_local: tuple[float, float] = (math.nan, math.nan)
    limit_local: float = math.nan

    @property
    def criterion(self) -> str:
        """The rule that decided ``kind``, and what the intervals are, in words."""
        return (f"geometric if the RMS residual of log w against k is {self.threshold:g} times smaller "
                f"than that of log w against log k on the last {len(self.ks_used)} members, algebraic "
                "if the reverse, undecided otherwise; the asymptotic ratio / exponent and limit are "
                "extrapolations (numerical, not enclosures): the members' local values fitted as "
                "V + c1/k + c2/k^2, interval +- (the change from dropping c2 + 3 standard errors)")

    def text(self) -> str:
        """One line: the law, its asymptotic parameter with its interval (an
        extrapolation), the members' local values, and the residuals."""
        def rng(iv, d=4):
            return f"[{iv[0]:.{d}g}, {iv[1]:.{d}g}]"

        if self.kind == "geometric":
            law = (f"geometric: ratio -> {self.ratio:.6g} in {rng(self.ratio_interval, 6)} (extrapolated to "
                   f"k -> inf, numerical); local ratios {rng(self.ratio_local)}")
        elif self.kind == "algebraic":
            law = (f"algebraic: exponent -> {self.exponent:.6g} in {rng(self.exponent_interval, 6)} "
                   f"(extrapolated to k -> inf, numerical); local exponents {rng(self.exponent_local)}")
        else:
            law = (f"undecided (neither straight line fits: slopes ratio {self.ratio_fit:.4g}, exponent "
                   f"{self.exponent_fit:.4g})")
        k = self.ks_used
        span = f"k = {k[0]}..{k[-1]}" if k else "no members"
        return (f"{law}; residuals geometric {self.residual_geometric:.2g}, algebraic "
                f"{self.residual_algebraic:.2g} ({span})")


def _extrapolate(ks, values, q=1.0):
    """The limit k -> inf of ``values`` (one per ``ks``), fitted as
    ``V + c_1 k^-q + c_2 k^-(q+1)`` by least squares: ``(V, (lo, hi))``, the
    interval ``V`` +- (``|V - V_1|`` + 3 standard errors of ``V``), ``V_1``
    the fit without ``c_2``.  With fewer than 4 values, ``V_1`` +-
    (``|V_1 - values[-1]|`` + 3 standard errors).  An extrapolation, not an
    enclosure: it assumes the corrections are powers of 1/k from ``q`` on."""
    ks = np.asarray(ks, float)
    v = np.asarray(values, float)
    ok = np.isfinite(v) & np.isfinite(ks)
    ks, v = ks[ok], v[ok]
    nan2 = (math.nan, math.nan)
    if v.size == 0:
        return math.nan, nan2
    if v.size == 1:
        return float(v[0]), nan2
    x = ks ** -float(q)
    scale = float(np.max(np.abs(v))) or 1.0

    def fit(cols):
        a = np.vstack(cols).T
        coef, *_ = np.linalg.lstsq(a, v, rcond=None)
        dof = v.size - a.shape[1]
        if dof > 0:
            res = v - a @ coef
            sigma2 = float(res @ res) / dof
            cov = sigma2 * np.linalg.pinv(a.T @ a)
            se = math.sqrt(max(float(cov[0, 0]), 0.0))
        else:
            se = 0.0
        return float(coef[0]), se

    v1, se1 = fit([np.ones_like(x), x])
    if v.size >= 4:
        v2, se2 = fit([np.ones_like(x), x, x / ks])
        est, d = v2, abs(v2 - v1) + 3.0 * se2
    else:
        est, d = v1, abs(v1 - float(v[-1])) + 3.0 * se1
    d += 8 * float(np.finfo(float).eps) * scale  # rounding of the values themselves
    return float(est), (float(est - d), float(est + d))


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
    parameter, one per triple of consecutive members, and the triples' middle k."""
    lims, pars, kk = [], [], []
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
            kk.append(ks[i + 1])
        else:
            b = _algebraic_beta(float(ks[i]), a)
            if not math.isfinite(b):
                continue
            c = d0 / ((ks[i] + 1) ** -b - ks[i] ** -b)
            lims.append(a[2] - c * (ks[i] + 2) ** -b)
            pars.append(b)
            kk.append(ks[i + 1])
    return np.asarray(lims), np.asarray(pars), np.asarray(kk, float)


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
    fails on sequences that follow neither.  The reported ratio and exponent
    are asymptotic: the local values on those members, ``w_{k+1} / w_k`` and
    ``-log(w_{k+1}/w_k) / log((k+1)/k)``, drift like 1/k where the law has
    finite-k corrections (``C k^-p (1 + a/k + ...)``; the widths
    ``1/(k(k+1))`` have local exponents ``2 - 1/k + ...``, all below 2), so
    they are extrapolated to k -> inf as ``V + c_1/k + c_2/k^2`` (least
    squares), with the interval ``V`` +- (the change from dropping ``c_2`` + 3
    standard errors); the straight lines' slopes and the local values' range
    are kept (``*_fit``, ``*_local``).  The extrapolations use the members from
    half the last k on (at least the last ``tail``): a few members at large k
    span too little of 1/k.  With ``positions`` (an edge of each
    member), a local limit is found from each triple of consecutive members
    with the positions' law (decided by the same criterion on their gaps,
    ``approach_kind``: Aitken's delta-squared for geometric,
    ``a_k = L + C k^-beta`` through the three points for algebraic), and the
    local limits of the last ``tail`` triples are extrapolated the same way
    in powers ``k^-(beta+1)``, ``k^-(beta+2)`` (``limit``, ``limit_interval``).
    Every interval here is an extrapolation, numerical and not proven (an
    enclosure of the accumulation point is :attr:`stairbounce.Cascade.limit_enclosure`); checked
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
    ratio_fit, exponent_fit = float(np.exp(slope_g)), float(-slope_a)
    r_loc = (float(loc_r.min()), float(loc_r.max())) if loc_r.size else nan2
    g_loc = (float(loc_g.min()), float(loc_g.max())) if loc_g.size else nan2
    # the asymptotic values: the local ones (between k and k+1, at k + 1/2) extrapolated in 1/k
    # on the members from half the last k on (at least the law's): eight members at k ~ 200 span
    # too little of 1/k to extrapolate to 0 (their rounding is amplified hundreds of times)
    ext = ks >= min(kt[0], ks[-1] / 2)
    ke, we = ks[ext], w[ext]
    cons_e = np.diff(ke) == 1
    kmid_w = (ke[:-1] + 0.5)[cons_e]
    ratio, r_int = _extrapolate(kmid_w, (we[1:] / we[:-1])[cons_e])
    exponent, g_int = _extrapolate(kmid_w, (-np.log(we[1:] / we[:-1]) / np.log(ke[1:] / ke[:-1]))[cons_e])
    fits = dict(ratio_fit=ratio_fit, exponent_fit=exponent_fit, ratio_local=r_loc, exponent_local=g_loc)
    floor = 1e-14  # residuals below rounding of log w are ties
    if max(res_g, floor) * threshold < max(res_a, floor):
        kind = "geometric"
    elif max(res_a, floor) * threshold < max(res_g, floor):
        kind = "algebraic"
    else:
        kind = "undecided"
    law = CascadeLaw(kind, ratio, r_int, exponent, g_int, res_g, res_a, threshold, used, **fits)
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
    lims, pars, kl = _limits(approach_kind, ks, pos)
    if lims.size == 0:
        return law
    keep = kl >= min(kt[0] + 1, ks[-1] / 2)  # the triples' middle k, as the widths' range above
    if keep.sum() < min(tail, kl.size):
        keep = np.arange(kl.size) >= kl.size - tail
    lt, pt, kl = lims[keep], pars[keep], kl[keep]
    # the local limits' own corrections: powers of 1/k from beta + 1 on (algebraic approach)
    q = float(pt[-1]) + 1.0 if approach_kind == "algebraic" else 1.0
    limit, l_int = _extrapolate(kl, lt, q)
    if not all(math.isfinite(b) for b in l_int):  # one triple: its own limit, no interval
        l_int = (float(lt[-1]), float(lt[-1]))
    return CascadeLaw(kind, ratio, r_int, exponent, g_int, res_g, res_a, threshold, used,
                      limit, l_int, float(pt[-1]), (float(pt.min()), float(pt.max())), approach_kind,
                      limit_local=float(lt[-1]), **fits)


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


