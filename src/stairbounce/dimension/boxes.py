"""Box counting: ``N(s)``, the number of boxes of side ``s`` pixels holding a
pixel of the set, and the box-counting dimension fitted to it.

Box counting runs on an OR-pyramid (each level pools 2 x 2 blocks of the one
below, a numba kernel over rows on all cores) for the default power-of-two
sizes on the unshifted grid, and on a direct numba kernel for any other size
or grid offset.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numba import njit, prange
from numpy.typing import ArrayLike

from .. import _validate as _v
from ..model import check_count
from .borders import _check_image
from .fit import SlopeFit, half_slopes, slope_fit, systematic_term
from .result import Estimate

__all__ = ["BoxDimension", "box_counts", "box_dimension", "box_dimension_from_counts"]


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
# Box-counting dimension                                                      #
# --------------------------------------------------------------------------- #


@dataclass(frozen=True)
class BoxDimension(Estimate):
    """A box-counting dimension estimate.

    ``dimension`` is the fitted slope of ``log N(s)`` against ``log(1/s)``;
    ``stderr``, ``ci`` (95%) and ``r`` come from the fit.  ``sizes`` and
    ``counts`` are every size measured (``counts[k]`` boxes of side
    ``sizes[k]`` pixels); ``usable`` marks the sizes offered to the fit (more
    than one box); ``fit_range = (s_min, s_max)`` are the smallest and largest
    box sides fitted, in pixels; ``fit`` is the underlying :class:`SlopeFit`
    on the usable sizes.

    ``systematic`` is the drift of the local slope across the fitted sizes
    (the largest distance from ``dimension`` of the slopes over the finer
    and the coarser half, ``halves``), reported beside the statistical
    ``ci``; ``interval`` covers both (:class:`stairbounce.dimension.result.Estimate`).
    ``max_iter`` is the scan's when the image came from one (else None).
    """

    scale_unit = "px"
    estimator = "boxes"

    dimension: float
    stderr: float
    ci: tuple[float, float]
    r: float
    sizes: np.ndarray
    counts: np.ndarray
    usable: np.ndarray
    fit_range: tuple[int, int]
    fit: SlopeFit = field(repr=False)
    systematic: float = 0.0
    halves: tuple[float, float] = (math.nan, math.nan)
    max_iter: int | None = None

    @property
    def fitted(self) -> np.ndarray:
        """Boolean mask of the sizes used by the fit."""
        return (self.sizes >= self.fit_range[0]) & (self.sizes <= self.fit_range[1]) & self.usable

    @property
    def local_dimensions(self) -> tuple[np.ndarray, np.ndarray]:
        """``(s_mid, D_local)``: the slope of ``log N`` against ``log(1/s)``
        between consecutive usable sizes (geometric midpoints, pixels)."""
        s = np.asarray(self.sizes, float)[self.usable]
        c = np.asarray(self.counts, float)[self.usable]
        if s.size < 2:
            return np.empty(0), np.empty(0)
        ls, lc = np.log(s), np.log(c)
        return np.exp(0.5 * (ls[1:] + ls[:-1])), -np.diff(lc) / np.diff(ls)

    def local_band(self):
        """``(s_mid, D_local, half-width)``: box counts carry no per-size noise
        model, so the half-width is NaN (the drift across sizes is the
        measure of their scatter)."""
        mid, dl = self.local_dimensions
        return mid, dl, np.full(dl.shape, np.nan)

    def summary(self) -> str:
        """D with its drift-covering interval, the scales and max_iter, r
        and the 95% CI of the fit; a second line warns when the drift
        exceeds the statistical interval."""
        lo, hi = self.ci
        line = (f"{self.interval_text()}  (95% CI of the fit [{lo:.4f}, {hi:.4f}], r = {self.r:.5f}, "
                f"{self.fit.n} sizes)")
        warn = self.warning()
        return line + ("\n" + warn if warn else "")


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
    pixel_size: tuple[float, float] | None = None,
) -> "BoxDimension":
    """box_dimension(image, sizes=None, offsets=1, reduce="mean", fit_range=None, tol=0.1, min_boxes=32, min_points=3, pixel_size=None) -> BoxDimension

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

    pixel_size : (width, height) or None, default None
        The size of a pixel in the plane (for a scan: the step along e and
        along u).  Pixels more than 5% from square draw a warning: an
        ``s x s``-pixel box is then a rectangle in the plane, which leaves
        the limit unchanged but not the estimate over a finite range of
        scales (the whole Fig. 4 plane at 500 x 350 px, pixels 0.002 x
        0.0043, gives 1.27, below every square sub-window); scan with square
        pixels (as many pixels along each axis as the window's sides are
        long).  A 2-D xarray DataArray with 1-D ``e`` and ``u`` coordinates
        gives its own pixel size.

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
    if pixel_size is None:
        pixel_size = _coordinate_pixel(image)
    _warn_non_square(pixel_size)
    a = _as_uint8(getattr(image, "values", image))
    min_boxes = check_count("min_boxes", min_boxes, 2)
    min_points = check_count("min_points", min_points, 3)
    s, counts = box_counts(a, sizes=sizes, offsets=offsets, reduce=reduce)
    return box_dimension_from_counts(
        s, counts, fit_range=fit_range, tol=tol, min_boxes=min_boxes, min_points=min_points
    )


def _coordinate_pixel(image):
    """The pixel size of a DataArray with 1-D ``e`` and ``u`` coordinates, else None."""
    coords = getattr(image, "coords", None)
    if coords is None or "e" not in coords or "u" not in coords:
        return None
    e, u = np.asarray(coords["e"], float), np.asarray(coords["u"], float)
    if e.ndim != 1 or u.ndim != 1 or e.size < 2 or u.size < 2:
        return None
    return float(abs(e[1] - e[0])), float(abs(u[1] - u[0]))


def _warn_non_square(pixel_size):
    if pixel_size is None:
        return
    import warnings

    try:
        w, h = (float(v) for v in pixel_size)
    except (TypeError, ValueError):
        raise ValueError(f"pixel_size must be a pair (width, height) of positive numbers, got {pixel_size!r}") from None
    if not (w > 0 and h > 0 and math.isfinite(w) and math.isfinite(h)):
        raise ValueError(f"pixel_size must be a pair (width, height) of positive numbers, got {pixel_size!r}")
    if abs(w / h - 1.0) > 0.05:
        warnings.warn(f"box_dimension: non-square pixels (width/height = {w / h:.3g}): each box is a "
                      f"rectangle in the plane, which changes the estimate over a finite range of "
                      f"scales; scan with square pixels (pixels along each axis in proportion to the "
                      f"window's sides)", RuntimeWarning, stacklevel=3)


def box_dimension_from_counts(sizes, counts, fit_range=None, tol=0.1, min_boxes=32, min_points=3):
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
    halves = half_slopes(x, y, start, stop)
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
        systematic=systematic_term(fit.slope, halves),
        halves=halves,
    )
