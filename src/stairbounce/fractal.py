"""Box-counting dimension of the border of the sliding region (Section 3, Figs. 6-7).

The paper measures "the fractal dimension of the perimeter" of the region of
parameters with periodic sliding solutions by box counting on its pictures and
reports 1.324 for the window ``[0, 0.333] x [0.4, 0.733]`` (Fig. 6) and 1.403
for ``[0.155, 0.2138] x [0.6, 0.658]`` (Fig. 7), with a correlation
coefficient above 0.99.

The estimator is built from public steps, so that each one can be checked and
replaced (as in FractalDimensions.jl):

``boundary`` / ``label_boundary``
    the border pixels of a region (or between the labels of an image);
``box_counts``
    ``N(s)``, the number of boxes of side ``s`` pixels that hold at least one
    pixel of the set, optionally reduced over shifted grids;
``slope_fit``
    least-squares slope of ``log N(s)`` against ``log(1/s)`` with its standard
    error, 95% confidence interval and correlation coefficient, over a range
    of sizes given or chosen by a documented heuristic;
``box_dimension``
    the three above composed; ``perimeter_dimension`` scans a window of the
    ``(e, u)`` plane first (:func:`stairbounce.plane.scan`).

A raster estimate depends on the resolution, on ``max_iter`` of the scan and on
the fit range; ``benchmarks/dimension_convergence.py`` measures how much.

Box counting runs on an OR-pyramid (each level pools 2 x 2 blocks of the one
below, a numba kernel over rows on all cores) for the default power-of-two
sizes on the unshifted grid, and on a direct numba kernel for any other size
or grid offset.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from numba import njit, prange

from . import _validate as _v
from .model import check_count
from .plane import pixel_centres, scan, scan_coords

__all__ = [
    "BoxDimension",
    "PerimeterDimension",
    "SlopeFit",
    "UncertainFraction",
    "UncertaintyDimension",
    "border_dimension_estimates",
    "boundary",
    "box_counts",
    "box_dimension",
    "box_dimension_from_counts",
    "label_boundary",
    "linear_region",
    "perimeter_dimension",
    "random_points",
    "sliding_classifier",
    "slope_fit",
    "uncertain_fraction",
    "uncertainty_dimension",
    "uncertainty_dimension_from_counts",
]


# --------------------------------------------------------------------------- #
# Borders                                                                     #
# --------------------------------------------------------------------------- #

_IMAGE_EDGES = ("ignore", "border")


def _check_image(name, image, ndim=2):
    a = np.asarray(image)
    if a.ndim != ndim:
        raise ValueError(f"{name} must be a {ndim}-D array, got shape {a.shape}")
    if a.size == 0:
        raise ValueError(f"{name} must not be empty, got shape {a.shape}")
    return a


def _check_connectivity(connectivity):
    if connectivity not in (4, 8):
        raise ValueError(f"connectivity must be 4 or 8, got {connectivity!r}")
    return connectivity


def _check_image_edge(image_edge):
    if image_edge not in _IMAGE_EDGES:
        raise ValueError(f"image_edge must be one of {_IMAGE_EDGES}, got {image_edge!r}")
    return image_edge


def _neighbour_differs(a, connectivity, pad_mode, pad_value=None):
    """``out[i, j]``: some neighbour of pixel ``(i, j)`` differs from it.

    The image is padded by one pixel (``edge``: a copy of the nearest pixel,
    so the image edge is never a border; ``constant``: ``pad_value``) and the
    comparison is made with each shifted copy: whole-array operations, no
    Python loop over pixels.
    """
    if pad_mode == "edge":
        p = np.pad(a, 1, mode="edge")
    else:
        p = np.pad(a, 1, mode="constant", constant_values=pad_value)
    h, w = a.shape
    out = np.zeros(a.shape, dtype=bool)
    shifts = [(0, 1), (2, 1), (1, 0), (1, 2)]
    if connectivity == 8:
        shifts += [(0, 0), (0, 2), (2, 0), (2, 2)]
    for di, dj in shifts:
        out |= p[di : di + h, dj : dj + w] != a
    return out


def boundary(mask: ArrayLike, connectivity: int = 4, image_edge: str = "ignore") -> np.ndarray:
    """boundary(mask, connectivity=4, image_edge="ignore") -> bool array

    The border pixels of a region: the pixels of the region with a neighbour
    outside it.

    ``B = {p in R : some neighbour q of p is not in R}``, with the
    4-neighbourhood (``connectivity=4``: the border is a thin 8-connected
    curve) or the 8-neighbourhood (``connectivity=8``: a thicker 4-connected
    curve).  Only pixels of the region are marked, so the border is one pixel
    thick.

    Parameters
    ----------
    mask : 2-D array, converted to bool
        The region (True).
    connectivity : 4 or 8, default 4
        Which neighbours count.
    image_edge : "ignore" or "border", default "ignore"
        What lies beyond the image edge.  ``"ignore"``: copies of the nearest
        pixel, so a region cut by the edge of the image (the edge of a window
        of the parameter plane) has no border there; this is the choice for
        measuring the perimeter of a set seen through a window, whose frame
        is not part of the set.  ``"border"``: outside the region, so region
        pixels on the image edge are border pixels (the closed outline of a
        region lying wholly inside the picture is the same either way).

    Used for the perimeter of the region of periodic sliding solutions
    (Section 3, Figs. 6 and 7).
    """
    m = _check_image("mask", mask).astype(bool, copy=False)
    _check_connectivity(connectivity)
    if _check_image_edge(image_edge) == "ignore":
        return m & _neighbour_differs(m, connectivity, "edge")
    return m & _neighbour_differs(m, connectivity, "constant", False)


def label_boundary(labels: ArrayLike, connectivity: int = 4) -> np.ndarray:
    """label_boundary(labels, connectivity=4) -> bool array

    The borders between any two labels of an integer image: the pixels with a
    neighbour of another label.

    ``B = {p : some neighbour q of p has labels[q] != labels[p]}``.  Both sides
    of a border are marked (a border between two labels is two pixels thick,
    which changes ``N(s)`` by at most a constant factor and not the
    dimension); for a two-label image it is
    ``boundary(m) | boundary(~m)``.  The image edge is never a border
    (``image_edge="ignore"`` of :func:`boundary`).

    Parameters
    ----------
    labels : 2-D integer (or bool) array
        For instance the word length of a scan, with one label for "no
        periodic sliding solution": its borders are the curves between the
        coloured regions of the paper's Figs. 4-7.
    connectivity : 4 or 8, default 4
    """
    lab = _check_image("labels", labels)
    if not (np.issubdtype(lab.dtype, np.integer) or lab.dtype == bool):
        raise ValueError(f"labels must be an integer or bool array, got dtype {lab.dtype}")
    _check_connectivity(connectivity)
    return _neighbour_differs(lab, connectivity, "edge")


# --------------------------------------------------------------------------- #
# Box counting kernels                                                        #
# --------------------------------------------------------------------------- #


@njit(cache=True)
def _pool_rows(a, out, i0, i1):
    """Rows ``i0..i1`` of one pyramid level: OR over 2 x 2 blocks of ``a``
    into ``out`` (the last row/column of an odd image alone); returns the
    number of True pixels written."""
    h, w = a.shape
    wo = out.shape[1]
    w2 = w // 2
    c = 0
    for i in range(i0, i1):
        r0 = a[2 * i]
        r1 = a[min(2 * i + 1, h - 1)]
        o = out[i]
        for j in range(w2):
            x = r0[2 * j] | r0[2 * j + 1] | r1[2 * j] | r1[2 * j + 1]
            o[j] = x
            c += x
        if wo > w2:
            x = r0[w - 1] | r1[w - 1]
            o[wo - 1] = x
            c += x
    return c


@njit(parallel=True, cache=True)
def _pool_count(a):
    """One pyramid level and its count of True pixels, bands of rows on all
    threads (each band's count is kept apart, so no thread writes shared
    state)."""
    h, w = a.shape
    ho = (h + 1) // 2
    out = np.empty((ho, (w + 1) // 2), dtype=np.uint8)
    band = 64
    nb = (ho + band - 1) // band
    counts = np.zeros(nb, dtype=np.int64)
    for b in prange(nb):
        counts[b] = _pool_rows(a, out, b * band, min((b + 1) * band, ho))
    return out, counts.sum()


@njit(cache=True)
def _pool_count_serial(a):
    """:func:`_pool_count` on one thread: for small levels, where a fork/join
    costs more than the work (and waits on a busy machine)."""
    h, w = a.shape
    ho = (h + 1) // 2
    out = np.empty((ho, (w + 1) // 2), dtype=np.uint8)
    return out, _pool_rows(a, out, 0, ho)


_PARALLEL_PIXELS = 1 << 22


@njit(parallel=True, cache=True)
def _count_boxes(a, s, oy, ox):
    """Boxes of side ``s`` on the grid with corners at ``(k s - oy, l s - ox)``
    that hold a nonzero pixel (boxes clipped by the image edge included).

    Each box row ORs its ``s`` image rows into one row, then looks along it box
    by box; box rows are independent (``prange``).
    """
    h, w = a.shape
    nby = (h + oy + s - 1) // s
    nbx = (w + ox + s - 1) // s
    counts = np.zeros(nby, dtype=np.int64)
    for r in prange(nby):
        i0 = max(r * s - oy, 0)
        i1 = min((r + 1) * s - oy, h)
        col = np.zeros(w, dtype=np.uint8)
        for i in range(i0, i1):
            row = a[i]
            for j in range(w):
                col[j] |= row[j]
        c = 0
        for b in range(nbx):
            j0 = max(b * s - ox, 0)
            j1 = min((b + 1) * s - ox, w)
            for j in range(j0, j1):
                if col[j]:
                    c += 1
                    break
        counts[r] = c
    return counts.sum()


def _as_uint8(image):
    a = _check_image("image", image)
    if a.dtype == bool:
        a = a.view(np.uint8)
    elif a.dtype != np.uint8:
        a = (a != 0).view(np.uint8)
    else:
        a = (a != 0).view(np.uint8) if a.max(initial=0) > 1 else a
    return np.ascontiguousarray(a)


def _default_sizes(shape):
    """Powers of two from 1 up to the shorter side of the image."""
    top = int(math.floor(math.log2(min(shape))))
    return 2 ** np.arange(top + 1, dtype=np.int64)


_MAX_BOX = 2**31


def _check_sizes(sizes, shape):
    if sizes is None:
        return _default_sizes(shape)
    s = np.asarray(sizes, dtype=object) if not isinstance(sizes, np.ndarray) else sizes
    if s.ndim != 1 or s.size == 0:
        raise ValueError(f"sizes must be a non-empty 1-D sequence of box sides in pixels, got {sizes!r}")
    # box sides beyond 2**31 would overflow the kernels' int64 corner arithmetic
    # (report D5: 2**63 - 1 counted 0 boxes)
    s = [check_count("sizes", x.item() if isinstance(x, np.generic) else x, 1, _MAX_BOX) for x in s]
    return np.unique(np.array(s, dtype=np.int64))


def _offsets_for(s, n):
    """``n`` grid shifts per axis for boxes of side ``s``: ``floor(k s / n)``,
    k = 0..n-1, distinct (fewer when ``s < n``)."""
    s = int(s)
    if n >= s:  # the shifts k s / n step by <= 1: every shift 0..s-1
        return list(range(s))
    return sorted({(k * s) // n for k in range(n)})


# Grid shifts per axis: each costs up to offsets^2 reads of the image per box
# size, so the bound keeps one call within minutes (report D12: 10**9 hung)
_MAX_OFFSETS = 64


_REDUCTIONS = ("mean", "min")


def box_counts(
    image: ArrayLike, sizes: ArrayLike | None = None, offsets: int = 1, reduce: str = "mean"
) -> tuple[np.ndarray, np.ndarray]:
    """box_counts(image, sizes=None, offsets=1, reduce="mean") -> (sizes, counts)

    The number of boxes of side ``s`` pixels that hold at least one nonzero
    pixel, for each size ``s``.

    ``N(s) = #{(k, l) : image has a nonzero pixel in rows [k s - o_y, (k+1) s - o_y)
    and columns [l s - o_x, (l+1) s - o_x)}``; boxes clipped by the image edge
    count.  The box-counting dimension is the slope of ``log N(s)`` against
    ``log(1/s)`` as ``s -> 0`` (:func:`box_dimension`).

    Parameters
    ----------
    image : 2-D array
        The set: nonzero (True) pixels.
    sizes : sequence of int >= 1, default None
        Box sides in pixels (sorted, duplicates dropped).  Default: the powers
        of two from 1 to the shorter side of the image.
    offsets : int in [1, 64], default 1
        Grid registration biases box counting (a set can straddle a grid line
        at one position and not at another).  With ``offsets = n`` the grid is
        shifted by ``(o_y, o_x)`` for every pair of shifts
        ``floor(k s / n)``, k = 0..n-1 (fewer when ``s < n``), and the counts
        are reduced over the shifts.  1: the grid starts at pixel (0, 0).
    reduce : "mean" or "min", default "mean"
        ``"mean"``: the average count over the shifts (then counts are
        floats); ``"min"``: the fewest boxes, the closest to the definition
        of ``N(s)`` as the smallest cover, but biased: small boxes have fewer
        distinct shifts to choose from than large ones.

    Returns
    -------
    sizes : int64 array
    counts : int64 array (float64 with ``reduce="mean"`` and ``offsets > 1``)

    Speed: the default sizes on the unshifted grid come from an OR-pyramid of
    2 x 2 blocks (numba, all cores): about 1.3 reads of the image for all sizes.
    Other sizes and shifts use a direct kernel, one read of the image each.
    """
    _v.check_array_memory("box counts of an image of {n} pixels", image, 3)  # the 0/1 copy, checks, pyramid
    a = _as_uint8(image)
    s = _check_sizes(sizes, a.shape)
    n = check_count("offsets", offsets, 1, _MAX_OFFSETS)
    if reduce not in _REDUCTIONS:
        raise ValueError(f"reduce must be one of {_REDUCTIONS}, got {reduce!r}")
    counts = np.zeros(len(s), dtype=np.float64 if (reduce == "mean" and n > 1) else np.int64)

    # Unshifted powers of two: walk up the pyramid once.
    pyramid = {}
    pow2 = [int(x) for x in s if x & (x - 1) == 0]
    if pow2:
        level, size = a, 1
        pyramid[1] = int(np.count_nonzero(a))
        top = max(pow2)
        while size < top:
            pool = _pool_count if level.size >= _PARALLEL_PIXELS else _pool_count_serial
            level, c = pool(level)
            size *= 2
            pyramid[size] = c

    for i, size in enumerate(s):
        size = int(size)
        shifts = _offsets_for(size, n)
        values = []
        for oy in shifts:
            for ox in shifts:
                if oy == 0 and ox == 0 and size in pyramid:
                    values.append(pyramid[size])
                else:
                    values.append(_count_boxes(a, size, oy, ox))
        counts[i] = min(values) if reduce == "min" else np.mean(values)
    return s, counts


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


def _check_xy(x, y) -> tuple[np.ndarray, np.ndarray]:
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


def linear_region(x: ArrayLike, y: ArrayLike, tol: float = 0.1, min_points: int = 3) -> tuple[int, int]:
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


def slope_fit(
    x: ArrayLike, y: ArrayLike, range: tuple[int, int] | None = None, tol: float = 0.1, min_points: int = 3
) -> SlopeFit:
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


# --------------------------------------------------------------------------- #
# Box-counting dimension                                                      #
# --------------------------------------------------------------------------- #


@dataclass(frozen=True)
class BoxDimension:
    """A box-counting dimension estimate.

    ``dimension`` is the fitted slope of ``log N(s)`` against ``log(1/s)``;
    ``stderr``, ``ci`` (95%) and ``r`` come from the fit.  ``sizes`` and
    ``counts`` are every size measured (``counts[k]`` boxes of side
    ``sizes[k]`` pixels); ``usable`` marks the sizes offered to the fit (more
    than one box); ``fit_range = (s_min, s_max)`` are the smallest and largest
    box sides fitted, in pixels; ``fit`` is the underlying :class:`SlopeFit`
    on the usable sizes.
    """

    dimension: float
    stderr: float
    ci: tuple[float, float]
    r: float
    sizes: np.ndarray
    counts: np.ndarray
    usable: np.ndarray
    fit_range: tuple[int, int]
    fit: SlopeFit = field(repr=False)

    @property
    def fitted(self) -> np.ndarray:
        """Boolean mask of the sizes used by the fit."""
        return (self.sizes >= self.fit_range[0]) & (self.sizes <= self.fit_range[1]) & self.usable

    def summary(self) -> str:
        """One line: D, its 95% CI, r and the fit range."""
        lo, hi = self.ci
        return (
            f"D = {self.dimension:.4f}  95% CI [{lo:.4f}, {hi:.4f}]  r = {self.r:.5f}  "
            f"(boxes of {self.fit_range[0]}..{self.fit_range[1]} px, {self.fit.n} sizes)"
        )


@dataclass(frozen=True)
class PerimeterDimension(BoxDimension):
    """:class:`BoxDimension` of the border of the region of periodic sliding
    solutions in a window of the ``(e, u)`` plane, with the border image
    (rows along u from ``u_min`` up, columns along e), the window, the
    resolution, ``max_iter`` and which border was measured."""

    border: np.ndarray = field(default_factory=lambda: np.zeros((0, 0), dtype=bool), repr=False)
    e: tuple[float, float] = (0.0, 0.0)
    u: tuple[float, float] = (0.0, 0.0)
    resolution: int = 0
    max_iter: int = 0
    which: str = "sliding"
    region_fraction: float = 0.0


def _fit_indices(sizes_used, fit_range):
    """Slice of the usable sizes between ``fit_range = (s_min, s_max)`` px."""
    try:
        lo, hi = (float(v) for v in fit_range)
    except (TypeError, ValueError):
        raise ValueError(f"fit_range must be a pair (s_min, s_max) of box sides in pixels, got {fit_range!r}") from None
    if not (lo >= 1 and hi >= lo):
        raise ValueError(f"fit_range must have 1 <= s_min <= s_max (pixels), got {fit_range!r}")
    idx = np.flatnonzero((sizes_used >= lo) & (sizes_used <= hi))
    if len(idx) < 3:
        raise ValueError(
            f"fit_range {fit_range!r} holds {len(idx)} usable box sizes; at least 3 are needed "
            f"(usable sizes: {sizes_used.tolist()})"
        )
    return int(idx[0]), int(idx[-1]) + 1


def box_dimension(
    image: ArrayLike,
    sizes: ArrayLike | None = None,
    offsets: int = 1,
    reduce: str = "mean",
    fit_range: tuple[float, float] | None = None,
    tol: float = 0.1,
    min_boxes: int = 32,
    min_points: int = 3,
) -> BoxDimension:
    """box_dimension(image, sizes=None, offsets=1, reduce="mean", fit_range=None, tol=0.1, min_boxes=32, min_points=3) -> BoxDimension

    The box-counting dimension of the set of nonzero pixels of an image.

    ``D = lim_{s -> 0} log N(s) / log(1/s)``, estimated as the least-squares
    slope of ``log N(s)`` against ``log(1/s)`` (:func:`box_counts` then
    :func:`slope_fit`).  Sizes with a single box (the whole set in one box)
    carry no information: they are never fitted.

    Parameters
    ----------
    image : 2-D array
        The set (nonzero pixels); for a perimeter pass ``boundary(region)``.
    sizes, offsets, reduce :
        Passed to :func:`box_counts` (default: powers of two, unshifted grid;
        ``reduce="mean"`` because the minimum over a number of shifts that
        grows with ``s`` lowers large-box counts more than small ones and
        steepens the slope: 1.30 instead of 1.26 for the Koch curve).
    fit_range : (s_min, s_max) or None, default None
        Box sides in pixels to fit (inclusive), chosen among the sizes with
        more than one box.  None: automatic, the largest linear region of
        :func:`linear_region` (``tol``, ``min_points``) among the sizes with
        at least ``min_boxes`` boxes.
    min_boxes : int >= 2, default 32
        Only for the automatic range: sizes with fewer boxes are dominated
        by the extent of the set and by where the grid falls on it (a box
        clipped by the edge of the set counts whole), so they bend the
        curve.  When fewer than ``min_points`` sizes have that many boxes,
        every size with more than one box is offered instead.

    The automatic range is a heuristic: it does not know that the smallest
    boxes (1-2 px) see the pixel staircase of a rasterised curve rather than
    the set; check the log-log plot.

    Raises
    ------
    ValueError
        When the image has no nonzero pixel, or fewer than 3 sizes have more
        than one box.

    The paper's numbers (Section 3): 1.324 (Fig. 6) and 1.403 (Fig. 7), r > 0.99.
    """
    a = _as_uint8(image)
    min_boxes = check_count("min_boxes", min_boxes, 2)
    min_points = check_count("min_points", min_points, 3)
    s, counts = box_counts(a, sizes=sizes, offsets=offsets, reduce=reduce)
    return box_dimension_from_counts(
        s, counts, fit_range=fit_range, tol=tol, min_boxes=min_boxes, min_points=min_points
    )


def box_dimension_from_counts(
    sizes: ArrayLike,
    counts: ArrayLike,
    fit_range: tuple[float, float] | None = None,
    tol: float = 0.1,
    min_boxes: int = 32,
    min_points: int = 3,
) -> BoxDimension:
    """box_dimension_from_counts(sizes, counts, fit_range=None, tol=0.1, min_boxes=32, min_points=3) -> BoxDimension

    The fit step of :func:`box_dimension` alone, on box counts measured
    elsewhere (for instance tile by tile,
    :func:`stairbounce.atlas_boxes.store_box_counts`).

    ``D`` = least-squares slope of ``log N(s)`` against ``log(1/s)`` over the
    sizes with more than one box, on ``fit_range`` or on the automatic range
    of :func:`box_dimension` (same parameters, same meaning).
    """
    min_boxes = check_count("min_boxes", min_boxes, 2)
    min_points = check_count("min_points", min_points, 3)
    s = np.asarray(sizes)
    counts = np.asarray(counts)
    if s.ndim != 1 or s.shape != counts.shape or s.size == 0:
        raise ValueError(
            f"sizes and counts must be 1-D arrays of the same length, got shapes {s.shape} and {counts.shape}"
        )
    if not np.any(counts > 0):
        raise ValueError("image has no nonzero pixel: there is no set to measure")
    usable = counts > 1
    if usable.sum() < 3:
        raise ValueError(
            f"fewer than 3 usable box sizes (sizes with more than one occupied box): "
            f"sizes {s.tolist()}, counts {np.asarray(counts).tolist()}"
        )
    su = s[usable]
    cu = np.asarray(counts, dtype=float)[usable]
    x = np.log(1.0 / su)
    y = np.log(cu)
    if fit_range is None:
        # Candidates: the sizes before the first one with too few boxes, so
        # that the indices of the fit carry over to all usable sizes.
        below = np.flatnonzero(cu < min_boxes)
        many = int(below[0]) if below.size else len(su)
        stop_all = many if many >= min_points else len(su)
        fit = slope_fit(x[:stop_all], y[:stop_all], range=None, tol=tol, min_points=min_points)
        fit = slope_fit(x, y, range=fit.range)
    else:
        fit = slope_fit(x, y, range=_fit_indices(su, fit_range))
    start, stop = fit.range
    return BoxDimension(
        dimension=fit.slope,
        stderr=fit.stderr,
        ci=fit.ci,
        r=fit.r,
        sizes=s,
        counts=counts,
        usable=usable,
        fit_range=(int(su[start]), int(su[stop - 1])),
        fit=fit,
    )


_WHICH = ("sliding", "words")
_METHODS = ("boxes", "uncertainty")


def _check_window(name, window):
    try:
        lo, hi = (float(v) for v in window)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a window (min, max), got {window!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise ValueError(f"{name} must be a finite window (min, max) with min < max, got {window!r}")
    return lo, hi


_PERIMETER_BYTES_PER_PIXEL = 30


def _scan_window(e, u, resolution, max_iter, y0, v0, progress, band=64, prune=True):
    """``status`` and ``word_length`` of the scan of the window, rows along u.

    With a ``progress`` callback the rows are scanned in bands cut out of the
    whole grid of pixel centres, which :mod:`stairbounce.plane` guarantees to
    be bit-identical to one scan of the window.
    """
    if progress is None:
        ds = scan(e=(e[0], e[1], resolution), u=(u[0], u[1], resolution), max_iter=max_iter, y0=y0, v0=v0,
                  prune=prune)
        return ds["status"].transpose("u", "e").values, ds["word_length"].transpose("u", "e").values
    es = pixel_centres(e[0], e[1], resolution)
    us = pixel_centres(u[0], u[1], resolution)
    status = np.empty((resolution, resolution), dtype=np.uint8)
    word_length = np.empty((resolution, resolution), dtype=np.int64)
    progress(0, resolution)
    for i0 in range(0, resolution, band):
        i1 = min(i0 + band, resolution)
        ds = scan_coords(es, us[i0:i1], max_iter=max_iter, y0=y0, v0=v0, prune=prune)
        status[i0:i1] = ds["status"].transpose("u", "e").values
        word_length[i0:i1] = ds["word_length"].transpose("u", "e").values
        progress(i1, resolution)
    return status, word_length


def perimeter_dimension(
    e=(0.0, 0.333),
    u=(0.4, 0.733),
    resolution=512,
    max_iter=1000,
    which="sliding",
    connectivity=4,
    sizes=None,
    offsets=1,
    reduce="mean",
    fit_range=None,
    tol=0.1,
    min_boxes=32,
    y0=1.0,
    v0=0.0,
    progress=None,
    method="boxes",
    n_points=100_000,
    eps=None,
    seed=0,
    prune=True,
):
    """perimeter_dimension(e=(0, 0.333), u=(0.4, 0.733), resolution=512, max_iter=1000, which="sliding", ..., method="boxes") -> PerimeterDimension or UncertaintyDimension

    The box-counting dimension of the perimeter of the region of periodic
    sliding solutions in a window of the ``(e, u)`` plane (Section 3,
    Figs. 6 and 7).

    Scans the window on ``resolution x resolution`` pixel centres
    (:func:`stairbounce.plane.scan`; status 0: the orbit of ``(y0, v0)``
    slides again within ``max_iter`` steps), takes the border of the status-0
    region (:func:`boundary`, ``image_edge="ignore"``: the frame of the
    window is not part of the perimeter) and measures it
    (:func:`box_dimension`).

    Parameters
    ----------
    e, u : (min, max)
        The window; default the paper's Fig. 6, ``[0, 0.333] x [0.4, 0.733]``.
        Fig. 7 is ``e=(0.155, 0.2138), u=(0.6, 0.658)``.
    resolution : int >= 8, default 512
        Pixels along each axis.
    max_iter : int >= 1, default 1000
        Steps of the Poincare map before a pixel counts as non-sliding.
    which : "sliding" or "words", default "sliding"
        ``"sliding"``: the border of the sliding region (the paper's
        "perimeter").  ``"words"``: the borders between regions of different
        word length, the non-sliding region as one more label
        (:func:`label_boundary`); every curve drawn in Figs. 4-7.
    connectivity, sizes, offsets, reduce, fit_range, tol, min_boxes :
        As in :func:`boundary` and :func:`box_dimension`.  The paper's
        numbers are reproduced (within 0.01 at 500 px) by
        ``fit_range=(1, 64)``, all boxes up to an eighth of the picture; the
        automatic range leaves out the pixel scale and gives larger values
        (docs/guide/dimension-study.md, "how far to trust one number").
    y0, v0 : float, default 1, 0
        Initial state of the scan (docs/design.md: ``(1, 0)`` is the state after
        sliding).
    progress : callable(done, total) or None, default None
        Called after each band of rows of the scan (the scan then runs in
        bands of :func:`stairbounce.plane.scan_coords`, bit-identical to one
        call); for a progress bar.
    method : "boxes" or "uncertainty", default "boxes"
        ``"boxes"``: box counting on a scanned picture (everything above).
        ``"uncertainty"``: the uncertainty exponent of random points of the
        window (:func:`uncertainty_dimension` with
        :func:`sliding_classifier`; no picture, so ``resolution``,
        ``connectivity``, ``sizes``, ``offsets``, ``reduce``, ``tol`` and
        ``min_boxes`` are not used, and ``fit_range`` is ``(eps_min, eps_max)``
        in window units); returns an :class:`UncertaintyDimension`.
    n_points, eps, seed :
        Only for ``method="uncertainty"``: as in :func:`uncertainty_dimension`
        (default 100_000 points, :data:`DEFAULT_EPS`, seed 0).
    prune : bool, default True
        As in :func:`stairbounce.plane.scan` (same answer; False iterates
        the pixels above the Corollary 2.1 curve too).

    The paper reports 1.324 (Fig. 6) and 1.403 (Fig. 7) with r > 0.99.
    """
    e = _check_window("e", e)
    u = _check_window("u", u)
    max_iter = check_count("max_iter", max_iter, 1)
    if which not in _WHICH:
        raise ValueError(f"which must be one of {_WHICH}, got {which!r}")
    if method not in _METHODS:
        raise ValueError(f"method must be one of {_METHODS}, got {method!r}")
    if method == "uncertainty":
        what = "sliding region" if which == "sliding" else "word-length regions"
        return uncertainty_dimension(
            sliding_classifier(max_iter=max_iter, which=which, y0=y0, v0=v0, prune=prune), (e, u), eps=eps,
            n_points=n_points, seed=seed, fit_range=fit_range, progress=progress,
            label=f"border of the {what}, max_iter {max_iter}",
        )
    resolution = check_count("resolution", resolution, 8)
    # measured peak (tracemalloc, resolution 1000): 25-28 bytes a pixel, the
    # scan's outputs or its status and word length and the border images; the
    # scan's own check saw only its outputs, and none with progress (report D3)
    if progress is not None and not callable(progress):
        raise ValueError(f"progress must be None or a callable progress(done, total), got {progress!r}")
    _v.check_memory(f"resolution = {resolution}", _PERIMETER_BYTES_PER_PIXEL * resolution * resolution)
    status, word_length = _scan_window(e, u, resolution, max_iter, y0, v0, progress, prune=prune)
    region = status == 0
    if not region.any():
        raise ValueError(
            f"no periodic sliding solution in the window e = {e}, u = {u} (max_iter = {max_iter}): "
            "the region is empty, it has no border"
        )
    if region.all():
        raise ValueError(
            f"every pixel of the window e = {e}, u = {u} has a periodic sliding solution: "
            "the region fills the window, it has no border inside it"
        )
    if which == "sliding":
        border = boundary(region, connectivity=connectivity)
    else:
        labels = np.where(region, word_length, -1).astype(np.int64)
        border = label_boundary(labels, connectivity=connectivity)
    est = box_dimension(
        border, sizes=sizes, offsets=offsets, reduce=reduce, fit_range=fit_range, tol=tol,
        min_boxes=min_boxes,
    )
    return PerimeterDimension(
        **{f: getattr(est, f) for f in BoxDimension.__dataclass_fields__},
        border=border,
        e=e,
        u=u,
        resolution=resolution,
        max_iter=max_iter,
        which=which,
        region_fraction=float(region.mean()),
    )


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


def random_points(
    window: tuple[tuple[float, float], tuple[float, float]], n_points: int, seed: int = 0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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
class UncertaintyDimension:
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
    """

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

    def table(self) -> str:
        """The measurement as text: eps, f, uncertain points, fitted or not."""
        lines = [f"{'eps':>10}  {'f(eps)':>11}  {'uncertain':>10}  fitted"]
        for e, f, c, m in zip(self.eps, self.fraction, self.uncertain, self.fitted):
            lines.append(f"{e:10.3g}  {f:11.4e}  {int(c):10d}  {'yes' if m else ''}")
        return "\n".join(lines)

    def summary(self) -> str:
        """One line: D, its 95% CI, r and the fit range."""
        lo, hi = self.ci
        return (
            f"D = {self.dimension:.4f}  95% CI [{lo:.4f}, {hi:.4f}]  r = {self.r:.5f}  "
            f"(uncertainty exponent alpha = {self.alpha:.4f}, eps {self.fit_range[0]:.3g}..{self.fit_range[1]:.3g}, "
            f"{self.fit.n} values, {self.n_points} points, seed {self.seed})"
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
        uf, fit_range=fit_range, min_uncertain=min_uncertain, label=label
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


def uncertainty_dimension_from_counts(measured, fit_range=None, min_uncertain=25, label=""):
    """uncertainty_dimension_from_counts(measured, fit_range=None, min_uncertain=25, label="") -> UncertaintyDimension

    The fit step of :func:`uncertainty_dimension` alone, on a measured
    :class:`UncertainFraction` (or any object with ``eps``, ``uncertain``,
    ``n_points`` and optionally ``seed``, ``direction``, ``window``): for
    instance to fit another range of eps of a stored measurement without
    classifying again.  Same fit, same interval, same parameters.
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
    )


class SlidingClassifier:
    """``classify(e, u) -> labels`` of the model for :func:`uncertain_fraction`;
    made by :func:`sliding_classifier`.  A plain object (not a closure), so it
    can be sent to Dask workers."""

    def __init__(self, max_iter, which, y0, v0, prune=True):
        self.max_iter, self.which, self.y0, self.v0, self.prune = max_iter, which, y0, v0, prune

    def __call__(self, e, u):
        from .plane import scan_points

        ds = scan_points(np.asarray(e, dtype=float), np.asarray(u, dtype=float),
                         max_iter=self.max_iter, y0=self.y0, v0=self.v0, prune=self.prune)
        name = "status" if self.which == "sliding" else "word_length"
        return np.asarray(ds[name])

    def __repr__(self):
        return (f"sliding_classifier(max_iter={self.max_iter}, which={self.which!r}, "
                f"y0={self.y0}, v0={self.v0}, prune={self.prune})")


def sliding_classifier(max_iter=1000, which="sliding", y0=1.0, v0=0.0, prune=True):
    """sliding_classifier(max_iter=1000, which="sliding", y0=1.0, v0=0.0, prune=True) -> classify(e, u)

    The model's classification of ``(e, u)`` points, for
    :func:`uncertain_fraction` and :func:`uncertainty_dimension`.

    ``which="sliding"``: the status of :func:`stairbounce.plane.scan_points`
    (0: the orbit of ``(y0, v0)`` reaches a periodic sliding solution within
    ``max_iter`` steps, 1: not); its border is the perimeter of the paper's
    Figs. 6 and 7 (Section 3).  ``which="words"``: the word length of the
    periodic sliding solution (0 where there is none), whose borders are
    every curve between the coloured regions of Figs. 4-7.  The labels are
    those of :func:`stairbounce.plane.scan` at the same points, bit for bit.

    Parameters
    ----------
    max_iter : int >= 1, default 1000
    which : "sliding" or "words", default "sliding"
    y0, v0 : float, default 1, 0
        As in :func:`stairbounce.plane.scan` (checked when the points are).
    prune : bool, default True
        As in :func:`stairbounce.plane.scan_points`: the same labels, without
        iterating points above the Corollary 2.1 curve.
    """
    from .model import _finite

    max_iter = check_count("max_iter", max_iter, 1)
    if which not in _WHICH:
        raise ValueError(f"which must be one of {_WHICH}, got {which!r}")
    return SlidingClassifier(max_iter, which, _finite("y0", y0), _finite("v0", v0), bool(prune))


def border_dimension_estimates(path: str | os.PathLike[str] | None = None) -> dict[str, Any]:
    """border_dimension_estimates(path=None) -> dict

    The measured dimension of the border of the sliding region in the
    paper's Fig. 6 and Fig. 7 windows, as written by
    ``benchmarks/dimension_study.py --json`` into the package's
    ``data/border_dimension.json`` (or into ``path``): per window
    (``"fig6"``, ``"fig7"``) the best estimate (``dimension``, ``ci95``,
    ``method``, ``details``), the paper's value, the uncertainty-exponent
    results per ``max_iter`` and the tiled box count; plus ``generated_by``
    and ``date``.
    """
    import json
    from pathlib import Path

    if path is not None:
        return json.loads(Path(path).read_text())
    from importlib.resources import files

    return json.loads(files("stairbounce").joinpath("data", "border_dimension.json").read_text())
