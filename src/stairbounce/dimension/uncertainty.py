"""The uncertainty exponent: a second estimator of the dimension of a border,
sharing nothing with box counting (no picture, no pixel, no grid)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..model import check_count
from .fit import SlopeFit, _weighted_line, half_slopes, systematic_term
from .result import Estimate

__all__ = ["DEFAULT_EPS", "UncertainFraction", "UncertaintyDimension", "random_points",
           "uncertain_fraction", "uncertainty_dimension", "uncertainty_dimension_from_counts"]


# --------------------------------------------------------------------------- #
# The uncertainty exponent                                                    #
# --------------------------------------------------------------------------- #
#
# A second estimator of the dimension of a border, sharing nothing with box
# counting: no picture, no pixel, no grid.  Random points are classified, and
# moved by a small distance eps; the fraction f(eps) of points whose class
# changes scales as eps^alpha, and the border has dimension d - alpha in the
# d-dimensional plane (Grebogi, McDonald, Ott, Yorke, Phys. Lett. A 99 (1983)
# 415; McDonald, Grebogi, Ott, Yorke, Physica D 17 (1985) 125, where D is the
# box-counting dimension of the boundary).

_DIRECTIONS = ("random", "x", "y", "both")

DEFAULT_EPS = np.logspace(-6.0, -1.0, 11)
"""Default perturbations of :func:`uncertainty_dimension`: 11 values over five
decades, 1e-6 to 0.1 of the window (half a decade apart)."""

# Points classified per call of ``classify`` (times 2 or 4 perturbed copies):
# bounds the memory of a call whatever n_points is.
_CHUNK = 1 << 18


def _check_plane_window(window):
    """``((x_min, x_max), (y_min, y_max))`` as floats, finite, min < max."""
    try:
        (x0, x1), (y0, y1) = window
        x0, x1, y0, y1 = float(x0), float(x1), float(y0), float(y1)
    except (TypeError, ValueError):
        raise ValueError(f"window must be ((x_min, x_max), (y_min, y_max)), got {window!r}") from None
    for axis, lo, hi in (("x", x0, x1), ("y", y0, y1)):
        if not (math.isfinite(lo) and math.isfinite(hi)):
            raise ValueError(f"window must have finite bounds, got {axis} in [{lo}, {hi}]")
        if not lo < hi:
            raise ValueError(
                f"window must have min < max along each axis (an empty or degenerate window has no "
                f"border to measure), got {axis} in [{lo}, {hi}]"
            )
    return (x0, x1), (y0, y1)


def _check_eps(eps):
    try:
        a = np.atleast_1d(np.asarray(eps, dtype=float))
    except (TypeError, ValueError):
        raise ValueError(f"eps must be a number or a 1-D sequence of numbers in (0, 1), got {eps!r}") from None
    if a.ndim != 1 or a.size == 0:
        raise ValueError(f"eps must be a number or a non-empty 1-D sequence, got shape {a.shape}")
    if not (np.all(np.isfinite(a)) and np.all(a > 0.0) and np.all(a < 1.0)):
        raise ValueError(
            "eps must lie in (0, 1): a perturbation in units of the window's width and height, "
            f"less than the window itself; got {np.asarray(eps).tolist()!r}"
        )
    return np.unique(a)


def _check_seed(seed):
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"seed must be an integer >= 0 (the points are reproducible from it), got {seed!r}")
    return int(seed)


def _check_direction(direction):
    if direction not in _DIRECTIONS:
        raise ValueError(f"direction must be one of {_DIRECTIONS}, got {direction!r}")
    return direction


def random_points(window, n_points, seed=0):
    """random_points(window, n_points, seed=0) -> (x, y, angle)

    The points of :func:`uncertain_fraction`: ``n_points`` independent
    uniform points of the window, and for each an angle uniform in
    ``[0, 2 pi)`` (its perturbation direction when ``direction="random"``).

    Drawn with ``numpy.random.default_rng(seed)`` in a fixed order (all x,
    then all y, then all angles), so a seed gives the same points on any
    machine and thread count, whatever the direction.
    """
    (x0, x1), (y0, y1) = _check_plane_window(window)
    n = check_count("n_points", n_points, 1)
    rng = np.random.default_rng(_check_seed(seed))
    x = x0 + (x1 - x0) * rng.random(n)
    y = y0 + (y1 - y0) * rng.random(n)
    angle = 2.0 * math.pi * rng.random(n)
    return x, y, angle


def _reflect(v, lo, hi):
    """Fold a perturbed coordinate back into ``[lo, hi]`` by mirroring at the
    edge it crossed (one fold suffices: the perturbation is less than the
    window)."""
    v = np.where(v < lo, 2.0 * lo - v, v)
    v = np.where(v > hi, 2.0 * hi - v, v)
    return np.clip(v, lo, hi)


def _labels(classify, x, y):
    lab = np.asarray(classify(x, y))
    if lab.shape != x.shape:
        raise ValueError(
            f"classify must return one label per point (an array of shape {x.shape}), "
            f"it returned shape {lab.shape}"
        )
    return lab


def _offsets(direction, eps, wx, wy, angle):
    """The perturbations of one point set, in coordinates: a list of (dx, dy)."""
    if direction == "random":
        dx, dy = eps * wx * np.cos(angle), eps * wy * np.sin(angle)
        return [(dx, dy), (-dx, -dy)]
    if direction == "x":
        return [(eps * wx, 0.0), (-eps * wx, 0.0)]
    if direction == "y":
        return [(0.0, eps * wy), (0.0, -eps * wy)]
    return [(eps * wx, 0.0), (-eps * wx, 0.0), (0.0, eps * wy), (0.0, -eps * wy)]


@dataclass(frozen=True)
class UncertainFraction:
    """The measured ``f(eps)``: for each ``eps[k]`` the number ``uncertain[k]``
    of the ``n_points`` random points whose class changes when moved by
    ``eps[k]``, and ``fraction[k] = uncertain[k] / n_points``."""

    eps: np.ndarray
    fraction: np.ndarray
    uncertain: np.ndarray
    n_points: int
    seed: int
    direction: str
    window: tuple

    @property
    def stderr(self) -> np.ndarray:
        """Binomial standard error of each fraction, ``sqrt(f (1 - f) / n)``."""
        f = self.fraction
        return np.sqrt(f * (1.0 - f) / self.n_points)


def uncertain_fraction(classify, window, eps, n_points=100_000, seed=0, direction="random", progress=None):
    """uncertain_fraction(classify, window, eps, n_points=100_000, seed=0, direction="random", progress=None) -> UncertainFraction

    The fraction of random points whose class changes when they are moved by
    ``eps``: the uncertain fraction ``f(eps)`` of Grebogi et al. (1983).

    ``f(eps) = #{p : c(p + d) != c(p) or c(p - d) != c(p)} / n`` for ``n``
    uniform points ``p`` of the window and perturbations ``d`` of length
    ``eps`` in window-relative units: ``d = eps (w_x cos t, w_y sin t)`` with
    ``w_x, w_y`` the window's width and height.  A point is uncertain when it
    lies within ``eps`` of the border (along ``d``), so ``f`` is the relative
    area of a neighbourhood of the border and ``f(eps) ~ eps^(2 - D)`` for a
    border of box-counting dimension ``D`` (McDonald et al. 1985).

    Parameters
    ----------
    classify : callable ``classify(x, y) -> labels``
        Vectorised: 1-D float arrays in, one label per point out (any dtype
        compared with ``!=``).  It is only ever called with points of the
        window: a perturbed point that leaves it is mirrored back in at the
        edge it crossed (which leaves ``f`` unchanged where the border does
        not meet the window's edge, and changes it by O(eps) where it does).
    window : ((x_min, x_max), (y_min, y_max))
        Where the points are drawn; finite, min < max.
    eps : float or 1-D sequence in (0, 1)
        Perturbation lengths as fractions of the window (sorted, duplicates
        dropped).  The base classification is done once and reused for all.
    n_points : int >= 100, default 100_000
        Random points per eps (the same points for every eps).
    seed : int >= 0, default 0
        Seed of :func:`random_points`; the points, hence the answer, are the
        same on any thread count.
    direction : "random", "x", "y" or "both", default "random"
        ``"random"``: each point along its own uniform random angle ``t``
        (isotropic in window-relative units; 2 perturbed copies per point);
        ``"x"``, ``"y"``: along one axis (2 copies); ``"both"``: along both
        axes, uncertain when any of the 4 copies differs.
    progress : callable(done, total) or None
        Called after each block of points and eps (can raise to interrupt).

    Raises
    ------
    ValueError
        A bad parameter (naming it and its range), or ``classify`` returning
        an array of the wrong shape.
    """
    if not callable(classify):
        raise ValueError(f"classify must be a callable classify(x, y) -> labels, got {classify!r}")
    window = _check_plane_window(window)
    eps = _check_eps(eps)
    n = check_count("n_points", n_points, 100)
    seed = _check_seed(seed)
    direction = _check_direction(direction)
    (x0, x1), (y0, y1) = window
    wx, wy = x1 - x0, y1 - y0
    x, y, angle = random_points(window, n, seed)
    uncertain = np.zeros(eps.size, dtype=np.int64)
    starts = range(0, n, _CHUNK)
    total = len(starts) * (eps.size + 1)
    done = 0
    if progress is not None:
        progress(0, total)
    for a in starts:
        b = min(a + _CHUNK, n)
        xs, ys, ts = x[a:b], y[a:b], angle[a:b]
        base = _labels(classify, xs, ys)
        done += 1
        if progress is not None:
            progress(done, total)
        for k, e in enumerate(eps):
            moves = _offsets(direction, e, wx, wy, ts)
            # one call for all copies: the classifier's fixed cost is paid once
            px = np.concatenate([_reflect(xs + dx, x0, x1) for dx, _ in moves])
            py = np.concatenate([_reflect(ys + dy, y0, y1) for _, dy in moves])
            moved = _labels(classify, px, py).reshape(len(moves), b - a)
            uncertain[k] += int(np.count_nonzero((moved != base).any(axis=0)))
            done += 1
            if progress is not None:
                progress(done, total)
    return UncertainFraction(
        eps=eps,
        fraction=uncertain / n,
        uncertain=uncertain,
        n_points=n,
        seed=seed,
        direction=direction,
        window=window,
    )


@dataclass(frozen=True)
class UncertaintyDimension(Estimate):
    """An uncertainty-exponent estimate of the dimension of a border; the
    same core fields as :class:`BoxDimension`.

    ``dimension = 2 - alpha`` where ``alpha`` is the fitted slope of
    ``log f`` against ``log eps``; ``stderr`` and ``ci`` (95%) are of the
    dimension and cover the larger of two noises (see
    :func:`uncertainty_dimension`): ``stderr_binomial`` (the binomial noise of
    each ``f``, propagated) and ``stderr_fit`` (the scatter about the line).
    ``r`` is the weighted correlation coefficient of the fitted points.
    ``eps``, ``fraction`` and ``uncertain`` are the table;
    ``usable`` marks the eps offered to the fit (at least ``min_uncertain``
    uncertain points, not all), ``fit_range = (eps_min, eps_max)`` the fitted
    eps; ``fit`` is the :class:`SlopeFit` of ``log f`` on ``log eps``
    (slope ``alpha``, its CI).  ``n_points``, ``seed``, ``direction`` and
    ``window`` reproduce the measurement; ``label`` says what was measured.
    ``systematic`` and ``halves`` (D over the finer and the coarser half of
    the fitted eps) measure the drift of the local dimension across the
    fitted scales; ``interval`` covers it and the statistical ``ci``.
    ``max_iter`` is the classifier's when it has one.
    """

    scale_unit = "of the window (eps)"
    estimator = "uncertainty"

    dimension: float
    stderr: float
    ci: tuple[float, float]
    r: float
    eps: np.ndarray
    fraction: np.ndarray
    uncertain: np.ndarray
    usable: np.ndarray
    fit_range: tuple[float, float]
    fit: SlopeFit = field(repr=False)
    alpha: float = 0.0
    stderr_binomial: float = 0.0
    stderr_fit: float = 0.0
    n_points: int = 0
    seed: int = 0
    direction: str = "random"
    window: tuple = ()
    label: str = ""
    systematic: float = 0.0
    halves: tuple[float, float] = (math.nan, math.nan)
    max_iter: int | None = None

    @property
    def fitted(self) -> np.ndarray:
        """Boolean mask of the eps used by the fit."""
        lo, hi = self.fit_range
        return self.usable & (self.eps >= lo) & (self.eps <= hi)

    @property
    def local_dimensions(self) -> tuple[np.ndarray, np.ndarray]:
        """``(eps_mid, D_local)``: ``2 - d log f / d log eps`` between
        consecutive eps with uncertain points (geometric midpoints)."""
        ok = self.uncertain > 0
        e, f = self.eps[ok], self.fraction[ok]
        if e.size < 2:
            return np.empty(0), np.empty(0)
        le, lf = np.log(e), np.log(f)
        return np.exp(0.5 * (le[1:] + le[:-1])), 2.0 - np.diff(lf) / np.diff(le)

    def local_band(self):
        """``(eps_mid, D_local, half-width)``: :attr:`local_dimensions` with the
        95% half-width of the binomial noise of the two fractions behind each."""
        ok = self.uncertain > 0
        e, f, c = self.eps[ok], self.fraction[ok], self.uncertain[ok]
        if e.size < 2:
            return np.empty(0), np.empty(0), np.empty(0)
        var = (1.0 - f) / np.maximum(c, 1)  # variance of log f (delta method)
        mid, dl = self.local_dimensions
        half = 1.96 * np.sqrt(var[1:] + var[:-1]) / np.diff(np.log(e))
        return mid, dl, half

    def table(self) -> str:
        """The measurement as text: eps, f, uncertain points, fitted or not."""
        lines = [f"{'eps':>10}  {'f(eps)':>11}  {'uncertain':>10}  fitted"]
        for e, f, c, m in zip(self.eps, self.fraction, self.uncertain, self.fitted):
            lines.append(f"{e:10.3g}  {f:11.4e}  {int(c):10d}  {'yes' if m else ''}")
        return "\n".join(lines)

    def summary(self) -> str:
        """D with its drift-covering interval, the scales and max_iter, r
        and the fit; a second line warns when the drift exceeds the
        statistical interval."""
        lo, hi = self.ci
        line = (
            f"{self.interval_text()}  (95% CI of the fit [{lo:.4f}, {hi:.4f}], r = {self.r:.5f}, "
            f"uncertainty exponent alpha = {self.alpha:.4f}, {self.fit.n} values, {self.n_points} points, "
            f"seed {self.seed})"
        )
        warn = self.warning()
        return line + ("\n" + warn if warn else "")


def uncertainty_dimension(
    classify,
    window,
    eps=None,
    n_points=100_000,
    seed=0,
    fit_range=None,
    direction="random",
    min_uncertain=25,
    progress=None,
    label="",
):
    """uncertainty_dimension(classify, window, eps=None, n_points=100_000, seed=0, fit_range=None, direction="random", min_uncertain=25, progress=None) -> UncertaintyDimension

    The dimension of the border between the classes of ``classify`` from
    its uncertainty exponent (Grebogi, McDonald, Ott, Yorke 1983; McDonald
    et al. 1985).

    ``f(eps) ~ eps^alpha`` (:func:`uncertain_fraction`) and
    ``D = d - alpha`` with ``d = 2``, the box-counting dimension of the
    border.  ``alpha`` is the weighted least-squares slope of ``log f``
    against ``log eps``, each point weighted by the inverse of the binomial
    variance of ``log f``, ``n f / (1 - f)`` (delta method).  Two standard
    errors of the slope are computed: ``stderr_binomial = 1 / sqrt(S_xx)``
    (weighted), the binomial noise of the fractions alone, and
    ``stderr_fit = stderr_binomial sqrt(chi^2 / (m - 2))``, the scatter of the
    ``m`` fitted points about the line (which also holds curvature and the
    log-periodic wiggle of a self-similar border).  The reported ``stderr``
    is the larger one and the 95% interval is
    ``D -+ z stderr`` (normal ``z = 1.96`` when the binomial noise dominates,
    Student ``t_{0.975, m-2}`` when the scatter does).  It does not cover a
    bias of the scaling itself (a range of eps where ``f`` is not yet a
    power law): look at :attr:`UncertaintyDimension.local_dimensions`.

    Parameters
    ----------
    classify, window, n_points, seed, direction, progress :
        As in :func:`uncertain_fraction`.
    eps : 1-D sequence in (0, 1) or None, default None
        Perturbations in window-relative units; None: :data:`DEFAULT_EPS`,
        11 values from 1e-6 to 0.1 (five decades).
    fit_range : (eps_min, eps_max) or None, default None
        The eps fitted (inclusive), among the usable ones.  None: every
        usable eps.
    min_uncertain : int >= 1, default 25
        An eps is usable when at least this many points are uncertain (and
        not all of them): below it ``log f`` is too noisy and biased for the
        normal approximation of the weights.
    label : str
        What the classifier measures, kept in the result.

    Raises
    ------
    ValueError
        A bad parameter, or fewer than 3 usable eps in the fit range (with
        the table of counts: use more points or larger eps).

    Validated (tests/test_uncertainty.py) on a half-plane and a disk
    (border dimension 1) and on a border ``C x [0, 1]`` with ``C`` the
    middle-thirds Cantor set (dimension ``1 + log 2 / log 3``).
    """
    eps = DEFAULT_EPS if eps is None else eps
    _check_fit_range_eps(fit_range)
    check_count("min_uncertain", min_uncertain, 1)
    uf = uncertain_fraction(classify, window, eps, n_points, seed, direction, progress=progress)
    return uncertainty_dimension_from_counts(
        uf, fit_range=fit_range, min_uncertain=min_uncertain, label=label,
        max_iter=getattr(classify, "max_iter", None),
    )


def _check_fit_range_eps(fit_range):
    if fit_range is None:
        return None
    try:
        flo, fhi = (float(v) for v in fit_range)
    except (TypeError, ValueError):
        raise ValueError(f"fit_range must be a pair (eps_min, eps_max), got {fit_range!r}") from None
    if not (0.0 < flo <= fhi < 1.0):
        raise ValueError(f"fit_range must have 0 < eps_min <= eps_max < 1, got {fit_range!r}")
    return flo, fhi


def uncertainty_dimension_from_counts(measured, fit_range=None, min_uncertain=25, label="", max_iter=None):
    """uncertainty_dimension_from_counts(measured, fit_range=None, min_uncertain=25, label="", max_iter=None) -> UncertaintyDimension

    The fit step of :func:`uncertainty_dimension` alone, on a measured
    :class:`UncertainFraction` (or any object with ``eps``, ``uncertain``,
    ``n_points`` and optionally ``seed``, ``direction``, ``window``): for
    instance to fit another range of eps of a stored measurement without
    classifying again.  Same fit, same interval, same parameters;
    ``max_iter`` (of the classification, when there is one) is recorded.
    """
    from scipy import stats

    rng = _check_fit_range_eps(fit_range)
    min_uncertain = check_count("min_uncertain", min_uncertain, 1)
    eps = np.asarray(measured.eps, dtype=float)
    uncertain = np.asarray(measured.uncertain, dtype=np.int64)
    n = check_count("n_points", measured.n_points, 1)
    if eps.ndim != 1 or eps.shape != uncertain.shape:
        raise ValueError(f"eps and uncertain must be 1-D of one length, got {eps.shape} and {uncertain.shape}")
    fraction = uncertain / n
    usable = (uncertain >= min_uncertain) & (uncertain < n)
    fitted = usable if rng is None else usable & (eps >= rng[0]) & (eps <= rng[1])
    if fitted.sum() < 3:
        rows = ", ".join(f"{e:.3g}: {int(c)}" for e, c in zip(eps, uncertain))
        raise ValueError(
            f"fewer than 3 eps with at least {min_uncertain} uncertain points (and not all {n}) in the "
            f"fit range; uncertain points per eps: {rows}. Use more points, larger eps or a wider fit_range"
        )
    idx = np.flatnonzero(fitted)
    x = np.log(eps[fitted])
    f = fraction[fitted]
    y = np.log(f)
    w = n * f / (1.0 - f)
    alpha, intercept, se_binom, se_fit, r = _weighted_line(x, y, w)
    m = len(x)
    if se_fit > se_binom:
        stderr, half = se_fit, float(stats.t.ppf(0.975, m - 2)) * se_fit
    else:
        stderr, half = se_binom, float(stats.norm.ppf(0.975)) * se_binom
    fit = SlopeFit(
        slope=float(alpha),
        intercept=float(intercept),
        stderr=float(stderr),
        ci=(float(alpha - half), float(alpha + half)),
        r=float(r),
        range=(int(idx[0]), int(idx[-1]) + 1),
        n=int(m),
    )
    dim = 2.0 - float(alpha)
    a_fine, a_coarse = half_slopes(x, y, 0, m, w)
    halves = (2.0 - a_fine, 2.0 - a_coarse)
    return UncertaintyDimension(
        dimension=dim,
        stderr=float(stderr),
        ci=(dim - half, dim + half),
        r=float(r),
        eps=eps,
        fraction=fraction,
        uncertain=uncertain,
        usable=usable,
        fit_range=(float(eps[idx[0]]), float(eps[idx[-1]])),
        fit=fit,
        alpha=float(alpha),
        stderr_binomial=float(se_binom),
        stderr_fit=float(se_fit),
        n_points=n,
        seed=getattr(measured, "seed", 0),
        direction=getattr(measured, "direction", "random"),
        window=getattr(measured, "window", ()),
        label=label,
        systematic=systematic_term(dim, halves),
        halves=halves,
        max_iter=None if max_iter is None else int(max_iter),
    )
