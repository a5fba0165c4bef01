"""The slope fit shared by the estimators: least squares with a 95% interval,
the automatic linear region, and the drift of the local slope across the
fitted scales (a systematic term beside the statistical one)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import _validate as _v
from ..model import check_count

__all__ = ["SlopeFit", "linear_region", "slope_fit"]


# --------------------------------------------------------------------------- #
# Slope fit                                                                   #
# --------------------------------------------------------------------------- #


@dataclass(frozen=True)
class SlopeFit:
    """A least-squares line ``y = intercept + slope x`` over ``x[start:stop]``.

    ``ci`` is the 95% confidence interval of the slope (Student t with
    ``n - 2`` degrees of freedom), ``stderr`` its standard error, ``r`` the
    correlation coefficient of the fitted points, ``range = (start, stop)``
    the fitted points (a Python slice of the input) and ``n`` their number.
    """

    slope: float
    intercept: float
    stderr: float
    ci: tuple[float, float]
    r: float
    range: tuple[int, int]
    n: int


def _check_xy(x, y):
    # the float copies and the fit's temporaries, before a zero-copy view is copied
    _v.check_array_memory("x and y of {n} points", (x, y), 64)
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if x.ndim != 1 or x.shape != y.shape:
        raise ValueError(f"x and y must be 1-D arrays of the same length, got shapes {x.shape} and {y.shape}")
    if len(x) < 3:
        raise ValueError(f"x and y must have at least 3 points for a slope with an error, got {len(x)}")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise ValueError("x and y must be finite")
    return x, y


def _fit(x, y):
    """Slope, intercept, standard error of the slope and r of ``y ~ x``."""
    n = len(x)
    xm, ym = x.mean(), y.mean()
    dx, dy = x - xm, y - ym
    sxx, syy, sxy = dx @ dx, dy @ dy, dx @ dy
    if sxx == 0.0:
        raise ValueError("x must not be constant over the fit range")
    slope = sxy / sxx
    intercept = ym - slope * xm
    resid = dy - slope * dx
    stderr = math.sqrt(max(resid @ resid, 0.0) / (n - 2) / sxx)
    r = sxy / math.sqrt(sxx * syy) if syy > 0.0 else 1.0
    return slope, intercept, stderr, r


def linear_region(x, y, tol=0.1, min_points=3):
    """linear_region(x, y, tol=0.1, min_points=3) -> (start, stop)

    The largest run of consecutive points that lie on one line, by a heuristic.

    A window ``x[start:stop]`` (at least ``min_points`` points) is accepted when
    every local slope ``(y[k+1] - y[k]) / (x[k+1] - x[k])`` inside it is within
    ``tol * |b|`` of the window's least-squares slope ``b``.  The longest
    accepted window wins; among equally long ones, the smallest standard error
    of the slope.  If no window is accepted the one with the smallest spread of
    local slopes is returned.

    This is a heuristic, like every automatic choice of a scaling range: it
    finds where ``log N(s)`` is straight, not where the box-counting limit is
    reached.  Look at the log-log plot (:func:`stairbounce.plot.plot_box_dimension`)
    and pass an explicit range when it matters.

    Parameters
    ----------
    x, y : 1-D arrays, at least 3 points
    tol : float > 0, default 0.1
        Allowed relative deviation of a local slope from the window's slope.
        Box counts of self-similar sets oscillate with the scale (lacunarity:
        the Koch curve's local slopes at powers of two range over 1.19-1.36),
        so a few percent would reject the whole curve; 0.15 lets the
        pixel-scale bend of a rasterised circle into the fit.
    min_points : int >= 3, default 3
    """
    x, y = _check_xy(x, y)
    tol = _v.real("tol", tol)
    if not tol > 0.0:
        raise ValueError(f"tol must be > 0, got {tol}")
    min_points = check_count("min_points", min_points, 3)
    n = len(x)
    if min_points > n:
        raise ValueError(f"min_points must be <= the number of points ({n}), got {min_points}")
    if np.ptp(x) == 0.0:
        raise ValueError("x must not be constant: there is no slope to find")
    return _linear_region(x, y, tol, min_points)


def _linear_region(x, y, tol, min_points):
    """:func:`linear_region` in O(n^2) at worst: every window's least-squares
    fit from prefix sums and its extreme local slopes from a sparse table, one
    vectorised pass per length, longest first, stopping at the first length
    with an accepted window (the plain search refitted every window: O(n^3),
    > 30 s at n = 2000)."""
    n = len(x)
    with np.errstate(divide="ignore", invalid="ignore"):
        local = np.diff(y) / np.diff(x)
    # sums over windows of the data centred on its mean (less cancellation)
    xc, yc = x - x.mean(), y - y.mean()

    def prefix(a):
        return np.concatenate([[0.0], np.cumsum(a)])

    Sx, Sy, Sxx, Syy, Sxy = (prefix(a) for a in (xc, yc, xc * xc, yc * yc, xc * yc))
    bad = np.concatenate([[0], np.cumsum(~np.isfinite(local))])
    # hi[q][i] / lo[q][i]: max / min of local[i : i + 2**q]
    hi, lo = [local], [local]
    while 2 ** len(hi) <= len(local):
        h = 2 ** (len(hi) - 1)
        hi.append(np.maximum(hi[-1][:-h], hi[-1][h:]))
        lo.append(np.minimum(lo[-1][:-h], lo[-1][h:]))
    fallback = None
    for length in range(n, min_points - 1, -1):
        m = length - 1  # local slopes in a window
        i = np.arange(n - length + 1)
        j = i + length
        q = m.bit_length() - 1
        top = np.maximum(hi[q][i], hi[q][i + m - 2**q])
        bottom = np.minimum(lo[q][i], lo[q][i + m - 2**q])

        def window(S):
            return S[j] - S[i]

        sx, sy = window(Sx), window(Sy)
        sxx = window(Sxx) - sx * sx / length
        sxy = window(Sxy) - sx * sy / length
        syy = window(Syy) - sy * sy / length
        with np.errstate(divide="ignore", invalid="ignore"):
            slope = sxy / sxx
            stderr = np.sqrt(np.maximum(syy - slope * sxy, 0.0) / (length - 2) / sxx)
            dev = np.maximum(top - slope, slope - bottom)
        finite = ((bad[i + m] - bad[i]) == 0) & (sxx > 0.0) & np.isfinite(slope)
        with np.errstate(over="ignore"):  # tol |slope| past the largest float is inf: the test holds
            ok = finite & (dev <= tol * np.abs(slope))
        if ok.any():
            k = int(np.argmin(np.where(ok, stderr, np.inf)))
            return int(i[k]), int(i[k]) + length
        if length == min_points and finite.any():
            with np.errstate(divide="ignore", invalid="ignore"):
                spread = np.where(finite, dev / np.maximum(np.abs(slope), 1e-300), np.inf)
            k = int(np.argmin(spread))
            fallback = (int(i[k]), int(i[k]) + length)
    if fallback is None:
        return 0, n
    return fallback


def slope_fit(x, y, range=None, tol=0.1, min_points=3):
    """slope_fit(x, y, range=None, tol=0.1, min_points=3) -> SlopeFit

    Least-squares slope of ``y`` against ``x`` with its standard error, 95%
    confidence interval and correlation coefficient.

    ``b = S_xy / S_xx``, ``se(b) = sqrt(sum(res^2) / (n - 2) / S_xx)``,
    ``CI = b -+ t_{0.975, n-2} se(b)`` (``scipy.stats.t``),
    ``r = S_xy / sqrt(S_xx S_yy)``.

    Parameters
    ----------
    x, y : 1-D arrays of the same length (at least 3 finite points)
    range : (start, stop) or None, default None
        The points fitted, as a Python slice ``x[start:stop]`` (at least 3).
        None: the largest linear region, chosen by the heuristic of
        :func:`linear_region` with ``tol`` and ``min_points``.
    tol, min_points :
        Passed to :func:`linear_region` when ``range`` is None.

    The paper fits ``log N(s)`` against ``log(1/s)`` and quotes ``r > 0.99``
    (Section 3); with the interval one can see how much that pins ``D`` down.
    """
    from scipy import stats

    x, y = _check_xy(x, y)
    n_all = len(x)
    if range is None:
        start, stop = linear_region(x, y, tol=tol, min_points=min_points)
    else:
        try:
            start, stop = (int(v) for v in range)
        except (TypeError, ValueError):
            raise ValueError(f"range must be a pair (start, stop) of point indices, got {range!r}") from None
        start, stop, _ = slice(start, stop).indices(n_all)
        if stop - start < 3:
            raise ValueError(
                f"range must hold at least 3 of the {n_all} points (a slice start:stop), got {range!r}"
            )
    xs, ys = x[start:stop], y[start:stop]
    slope, intercept, stderr, r = _fit(xs, ys)
    n = stop - start
    half = float(stats.t.ppf(0.975, n - 2)) * stderr
    return SlopeFit(
        slope=float(slope),
        intercept=float(intercept),
        stderr=float(stderr),
        ci=(float(slope - half), float(slope + half)),
        r=float(r),
        range=(int(start), int(stop)),
        n=int(n),
    )


def _weighted_line(x, y, w):
    """Weighted least squares ``y ~ a + b x``: b, a, se(b) from the weights
    alone, se(b) from the residuals, weighted r, chi^2."""
    sw = w.sum()
    xm, ym = (w @ x) / sw, (w @ y) / sw
    dx, dy = x - xm, y - ym
    sxx, syy, sxy = w @ (dx * dx), w @ (dy * dy), w @ (dx * dy)
    if sxx == 0.0:
        raise ValueError("eps must not be constant over the fit range")
    b = sxy / sxx
    a = ym - b * xm
    res = dy - b * dx
    chi2 = float(w @ (res * res))
    se_w = math.sqrt(1.0 / sxx)
    se_res = math.sqrt(chi2 / (len(x) - 2) / sxx)
    r = sxy / math.sqrt(sxx * syy) if syy > 0.0 else 1.0
    return b, a, se_w, se_res, r


def half_slopes(x, y, start, stop, w=None):
    """half_slopes(x, y, start, stop, w=None) -> (slope_first, slope_second)

    Least-squares slopes over the first and the second half of the fitted
    points ``x[start:stop]`` (the middle point in both when their number is
    odd; at least 2 points a half), weighted by ``w`` when given: how far the
    local slope drifts across the fitted scales.
    """
    n = stop - start
    mid = start + (n + 1) // 2
    parts = ((start, mid), (stop - (n + 1) // 2, stop))
    out = []
    for a, b in parts:
        xs, ys = np.asarray(x[a:b], float), np.asarray(y[a:b], float)
        ws = np.ones_like(xs) if w is None else np.asarray(w[a:b], float)
        sw = ws.sum()
        xm, ym = (ws @ xs) / sw, (ws @ ys) / sw
        sxx = ws @ ((xs - xm) ** 2)
        out.append(float(ws @ ((xs - xm) * (ys - ym)) / sxx) if sxx > 0 else math.nan)
    return out[0], out[1]


def systematic_term(d, halves):
    """The largest distance from ``d`` of the two half-range estimates."""
    if not all(math.isfinite(h) for h in halves):
        return 0.0
    return float(max(abs(d - h) for h in halves))
