"""Slicing: the dimension of a border from its crossings along random lines.

Marstrand's slicing theorem: a line in a random position meets a set of
dimension ``D`` in the plane in a set of dimension ``D - 1`` (for almost every
line that meets it).  So the border's dimension follows from one-dimensional
box counting along lines, and a line can be refined far below any picture's
pixel: to 1e-10 of the window and below, at the cost of classifying a few
points per box.

The estimator, scale by scale (scales in units of the window: both axes are
mapped to [0, 1] first, as for the uncertainty exponent):

1. ``n_lines`` random lines (a uniform point of the window and a uniform
   direction), each cut to its chord in the window, sampled at spacing
   ``scale_max / samples``; a box of length ``scale_max`` along a line is
   *occupied* when two neighbouring samples in it differ in class.  ``N_0`` is
   the number of occupied boxes on all lines.
2. Level ``k -> k + 1``: up to ``max_boxes`` occupied boxes of level ``k``
   are drawn at random; each is cut into ``ratio`` children of length
   ``h_k / ratio`` and sampled ``samples`` times per child (the parent's own
   samples are among them, so an occupied parent has at least one occupied
   child).  The mean number ``b_k`` of occupied children estimates
   ``N_{k+1} / N_k``, and the local dimension between the two scales is
   ``D_k = 1 + log b_k / log ratio``, with the standard error of the mean
   number of children propagated.  The occupied children of the drawn
   parents are a uniform sample of the occupied boxes of level ``k + 1``; the
   next level draws from them.
3. ``D`` over a range of scales is the mean of the ``D_k`` there (the slope of
   ``log N`` against ``log(1/h)``, as ``log N`` is their cumulative sum), its
   statistical interval from the larger of their standard errors (clustered
   by line) and their scatter about the mean, and its systematic term
   the drift between the finer and the coarser half (as every estimate of
   :mod:`stairbounce.dimension.result`).

Two crossings closer than the sample spacing can hide each other, and a box
whose crossings all hide is never refined, so its children are lost at every
level: the estimate is biased low, by 0.01 to 0.04 at the default 32 samples
per box on Weierstrass graphs of dimension 1.3 to 1.75 (tests/test_slicing.py),
less with more samples.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..model import check_count
from .result import Estimate
from .uncertainty import _check_plane_window, _check_seed

__all__ = ["SlicingDimension", "slicing_dimension"]

# the smallest scale: far below it the window's coordinates (about 0.1 to 1)
# have no float64 digits left to tell the samples of a box apart
_SCALE_FLOOR = 1e-13


@dataclass(frozen=True)
class SlicingDimension(Estimate):
    """A slicing estimate of the dimension of a border (:func:`slicing_dimension`).

    ``scales[k]`` is the box length of level ``k`` (units of the window),
    ``counts[k]`` the estimated number of occupied boxes on all lines
    (``counts[0]`` counted, the others ``counts[0]`` times the measured
    branching), ``parents[k]`` the boxes refined at level ``k`` and
    ``children[k]`` their mean number of occupied children.  ``local`` is
    ``(scale_mid, D_local, stderr)`` between consecutive levels.  ``dimension``
    is the mean local dimension over ``fit_range = (scale_min, scale_max)``,
    ``ci`` its 95% statistical interval, ``systematic`` and ``halves`` the
    drift between the finer and the coarser half of the fitted scales;
    ``interval`` covers both.  ``evaluations`` counts the points classified.
    """

    scale_unit = "of the window (box length along the lines)"
    estimator = "slicing"

    dimension: float
    stderr: float
    ci: tuple[float, float]
    scales_measured: np.ndarray
    counts: np.ndarray
    parents: np.ndarray
    children: np.ndarray
    local: tuple
    fit_range: tuple[float, float]
    systematic: float = 0.0
    halves: tuple[float, float] = (math.nan, math.nan)
    max_iter: int | None = None
    n_lines: int = 0
    seed: int = 0
    samples: int = 0
    ratio: int = 0
    window: tuple = ()
    evaluations: int = 0
    label: str = ""

    @property
    def local_dimensions(self) -> tuple[np.ndarray, np.ndarray]:
        """``(scale_mid, D_local)`` between consecutive levels."""
        return self.local[0], self.local[1]

    def local_band(self):
        """``(scale_mid, D_local, half-width)``: the local dimensions with their
        95% statistical half-widths (normal)."""
        mid, dl, se = self.local
        return mid, dl, 1.96 * se

    def refit(self, fit_range) -> SlicingDimension:
        """The same measurement with ``dimension`` (and its intervals) over the
        levels whose midpoints lie in ``fit_range = (scale_min, scale_max)``:
        nothing is classified again.  Raises ValueError when fewer than 3
        levels are left."""
        mid, dl, se = self.local
        return replace(self, **_fit(mid, dl, se, self.scales_measured, fit_range))

    def table(self) -> str:
        """The measurement as text: scale, occupied boxes, refined parents,
        mean children, local dimension with its standard error."""
        mid, dl, se = self.local
        lines = [f"{'scale':>10}  {'N (est.)':>11}  {'parents':>8}  {'children':>8}  "
                 f"{'D local':>8}  {'stderr':>7}"]
        for k, h in enumerate(self.scales_measured):
            row = f"{h:10.3g}  {self.counts[k]:11.4g}"
            if k < len(dl):
                row += (f"  {int(self.parents[k]):8d}  {self.children[k]:8.3f}  {dl[k]:8.4f}  "
                        f"{se[k]:7.4f}")
            lines.append(row)
        return "\n".join(lines)

    def summary(self) -> str:
        """D with its drift-covering interval, the scales and max_iter; a
        second line warns when the drift exceeds the statistical interval."""
        line = (f"{self.interval_text()}  (slicing: {self.n_lines} lines, seed {self.seed}, "
                f"{self.evaluations} points classified)")
        warn = self.warning()
        return line + ("\n" + warn if warn else "")


def _lines(n, rng):
    """``n`` random chords of the unit square: start point, direction, length."""
    px, py = rng.random(n), rng.random(n)
    theta = math.pi * rng.random(n)
    dx, dy = np.cos(theta), np.sin(theta)
    # the chord through (px, py) along (dx, dy): t in [t0, t1] inside [0, 1]^2
    with np.errstate(divide="ignore"):
        tx = np.sort(np.stack([(0.0 - px) / dx, (1.0 - px) / dx]), axis=0)
    ty = np.sort(np.stack([(0.0 - py) / dy, (1.0 - py) / dy]), axis=0)
    t0 = np.maximum(tx[0], ty[0])
    t1 = np.minimum(tx[1], ty[1])
    return px + t0 * dx, py + t0 * dy, dx, dy, t1 - t0


def _classify(classify, window, ox, oy, dx, dy, t):
    """Labels of the points ``o + t d`` of the unit square, mapped to the window."""
    (x0, x1), (y0, y1) = window
    ux = np.clip(ox + t * dx, 0.0, 1.0)
    uy = np.clip(oy + t * dy, 0.0, 1.0)
    x = np.clip(x0 + (x1 - x0) * ux, x0, x1).ravel()
    y = np.clip(y0 + (y1 - y0) * uy, y0, y1).ravel()
    lab = np.asarray(classify(x, y))
    if lab.shape != x.shape:
        raise ValueError(f"classify must return one label per point (an array of shape {x.shape}), "
                         f"it returned shape {lab.shape}")
    return lab.reshape(t.shape)


def _check_scales(scale_min, scale_max, ratio):
    try:
        lo, hi = float(scale_min), float(scale_max)
    except (TypeError, ValueError):
        raise ValueError(f"scale_min and scale_max must be numbers, got {scale_min!r}, {scale_max!r}") from None
    if not (_SCALE_FLOOR <= lo < hi <= 0.25):
        raise ValueError(f"scale_min and scale_max must satisfy {_SCALE_FLOOR:g} <= scale_min < scale_max "
                         f"<= 0.25 (fractions of the window), got {scale_min!r}, {scale_max!r}")
    # enough levels to reach scale_min (the finest may lie just below it)
    levels = int(math.ceil(math.log(hi / lo) / math.log(ratio) - 1e-9))
    if levels < 3:
        raise ValueError(f"scale_min..scale_max must span at least 3 levels of ratio {ratio} "
                         f"(a factor {ratio ** 3}), got {scale_min!r}..{scale_max!r}")
    return hi * float(ratio) ** -np.arange(levels + 1)


def _line_se(line, values, n_lines):
    """Standard error of the mean of ``values`` (one per refined box) with the
    boxes clustered by ``line``: the boxes of one line share its structure
    (and deeper levels descend from few boxes), the lines are independent."""
    m = values.size
    if m < 2:
        return math.inf
    z = np.bincount(line, weights=values - values.mean(), minlength=n_lines)
    used = np.count_nonzero(np.bincount(line, minlength=n_lines))
    if used < 2:
        return math.inf
    return float(math.sqrt(used / (used - 1) * (z @ z)) / m)


def slicing_dimension(classify, window, n_lines=64, scale_min=1e-10, scale_max=1e-2, ratio=4,
                      samples=32, max_boxes=400, seed=0, fit_range=None, progress=None, label=""):
    """slicing_dimension(classify, window, n_lines=64, scale_min=1e-10, scale_max=1e-2, ratio=4, samples=32, max_boxes=400, seed=0, fit_range=None, progress=None, label="") -> SlicingDimension

    The dimension of the border between the classes of ``classify`` from
    its crossings along random lines (Marstrand's slicing; module docstring),
    scale by scale from ``scale_max`` down to ``scale_min`` of the window.

    Parameters
    ----------
    classify : callable ``classify(x, y) -> labels``
        As in :func:`stairbounce.dimension.uncertainty.uncertain_fraction`:
        vectorised, only ever called with points of the window; for the model
        :func:`stairbounce.dimension.classifier.sliding_classifier`.
    window : ((x_min, x_max), (y_min, y_max))
    n_lines : int >= 1, default 64
        Random lines (a uniform point of the window, a uniform direction).
    scale_min, scale_max : float, default 1e-10, 1e-2
        The smallest and largest box length along the lines, as fractions of
        the window (``1e-13 <= scale_min``, ``scale_max <= 0.25``); the
        levels are ``scale_max / ratio^k`` until one reaches ``scale_min``.
    ratio : int >= 2, default 4
        Children per box from one level to the next.
    samples : int >= 2, default 32
        Samples per box (per child when refining): crossings closer than
        ``box / samples`` can hide each other, and a box whose crossings all
        hide is not refined, so the estimate is biased low by an amount that
        shrinks as ``samples`` grows.  Measured on Weierstrass graphs
        (tests/test_slicing.py): D = 1.5 gives 1.37, 1.43, 1.46, 1.48, 1.48 at
        4, 8, 16, 32, 64 samples; at 32, D = 1.3 gives 1.29 and D = 1.75 gives
        1.71-1.72.
    max_boxes : int >= 10, default 400
        Occupied boxes refined per level, drawn at random (more: a smaller
        statistical error, proportionally more points classified).
    seed : int >= 0, default 0
        The lines and the draws; same seed, same answer.
    fit_range : (scale_min, scale_max) or None
        The scales averaged into ``dimension`` (inclusive, by the local
        dimensions' midpoints); None: every level measured.
    progress : callable(done, total) or None
        Called after each level.

    The standard errors are clustered by line (the boxes of one line, and at
    deep levels the descendants of few boxes, are not independent).  To see
    whether ``max_iter`` moves the answer, measure again with a larger one and
    the same seed (the same lines) and compare the local dimensions with both
    bands: comparing two classifications on the boxes one of them selected
    would favour that one.

    Raises
    ------
    ValueError
        A bad parameter (naming it and its range), no crossing on any line
        at ``scale_max`` (the border misses the lines: more lines or a
        window that holds the border), or fewer than 3 levels in the fit.

    Validated (tests/test_slicing.py) on a circle (dimension 1) and on the
    graph of a Weierstrass function (box dimension ``2 + ln a / ln b``,
    Kaplan, Mallet-Paret and Yorke 1984).
    """
    if not callable(classify):
        raise ValueError(f"classify must be a callable classify(x, y) -> labels, got {classify!r}")
    window = _check_plane_window(window)
    n_lines = check_count("n_lines", n_lines, 1, 100_000)
    ratio = check_count("ratio", ratio, 2, 64)
    samples = check_count("samples", samples, 2, 1024)
    max_boxes = check_count("max_boxes", max_boxes, 10, 10_000_000)
    rng = np.random.default_rng(_check_seed(seed))
    scales = _check_scales(scale_min, scale_max, ratio)
    if progress is not None and not callable(progress):
        raise ValueError(f"progress must be None or a callable progress(done, total), got {progress!r}")

    ox, oy, dx, dy, length = _lines(n_lines, rng)
    # level 0: every box of every chord, samples per box, the chord's end clipped
    h0 = scales[0]
    nbox = np.maximum(np.ceil(length / h0).astype(np.int64), 1)
    line_of = np.repeat(np.arange(n_lines), nbox)
    start = h0 * (np.arange(nbox.sum()) - np.repeat(np.cumsum(nbox) - nbox, nbox))
    t = start[:, None] + (h0 / samples) * np.arange(samples + 1)[None, :]
    t = np.minimum(t, length[line_of][:, None])
    labels = _classify(classify, window, ox[line_of][:, None], oy[line_of][:, None],
                       dx[line_of][:, None], dy[line_of][:, None], t)
    evaluations = t.size
    occupied = (labels[:, 1:] != labels[:, :-1]).any(axis=1)
    if not occupied.any():
        raise ValueError(f"no crossing of the border on {n_lines} lines at scale {h0:g}: the lines miss "
                         "it (use more lines, or a window that holds the border)")
    counts = [float(occupied.sum())]
    box_line, box_start = line_of[occupied], start[occupied]
    parents, children, local, stderr = [], [], [], []
    total = len(scales) - 1
    for k in range(total):
        h, hc = scales[k], scales[k + 1]
        if box_line.size > max_boxes:
            pick = rng.choice(box_line.size, size=max_boxes, replace=False)
            box_line, box_start = box_line[pick], box_start[pick]
        m = box_line.size
        per = ratio * samples
        t = box_start[:, None] + (h / per) * np.arange(per + 1)[None, :]
        t = np.minimum(t, length[box_line][:, None])
        lab = _classify(classify, window, ox[box_line][:, None], oy[box_line][:, None],
                        dx[box_line][:, None], dy[box_line][:, None], t)
        evaluations += t.size
        # child j holds gaps j*samples .. (j+1)*samples - 1
        change = (lab[:, 1:] != lab[:, :-1]).reshape(m, ratio, samples).any(axis=2)
        c = change.sum(axis=1).astype(float)
        b = float(c.mean())
        se_b = _line_se(box_line, c, n_lines)
        parents.append(m)
        children.append(b)
        counts.append(counts[-1] * b)
        if b > 0:
            local.append(1.0 + math.log(b) / math.log(ratio))
            stderr.append(se_b / (b * math.log(ratio)))
        else:
            local.append(math.nan)
            stderr.append(math.inf)
        j = np.nonzero(change)
        box_line = box_line[j[0]]
        box_start = box_start[j[0]] + hc * j[1]
        if progress is not None:
            progress(k + 1, total)
        if box_line.size == 0:  # the crossings vanished: the border is smooth here, or missed
            break
    levels = len(local)
    scales_measured = scales[: levels + 1]
    mid = np.sqrt(scales_measured[1:] * scales_measured[:-1])
    dl, se = np.asarray(local), np.asarray(stderr)
    fit = _fit(mid, dl, se, scales_measured, fit_range)
    return SlicingDimension(
        **fit,
        scales_measured=scales_measured,
        counts=np.asarray(counts[: levels + 1]),
        parents=np.asarray(parents),
        children=np.asarray(children),
        local=(mid, dl, se),
        max_iter=getattr(classify, "max_iter", None),
        n_lines=n_lines,
        seed=int(seed),
        samples=samples,
        ratio=ratio,
        window=window,
        evaluations=int(evaluations),
        label=label,
    )


def _fit(mid, dl, se, scales_measured, fit_range):
    """``D`` over the levels whose midpoints lie in ``fit_range`` (None: all):
    the fields ``dimension``, ``stderr``, ``ci``, ``fit_range``,
    ``systematic`` and ``halves`` of :class:`SlicingDimension`."""
    from scipy import stats

    keep = np.isfinite(dl)
    if fit_range is not None:
        try:
            flo, fhi = (float(v) for v in fit_range)
        except (TypeError, ValueError):
            raise ValueError(f"fit_range must be a pair (scale_min, scale_max), got {fit_range!r}") from None
        keep &= (mid >= flo) & (mid <= fhi)
    idx = np.flatnonzero(keep)
    if idx.size < 3:
        raise ValueError(f"fewer than 3 measured levels in the fit range (local dimensions at "
                         f"{', '.join(f'{x:.2g}' for x in mid)}): widen fit_range or the scales")
    d = float(dl[idx].mean())
    n = idx.size
    # the larger of two noises, as for the uncertainty exponent: the levels'
    # own standard errors, and the scatter of the local dimensions about
    # their mean (which also holds the correlation between levels that share
    # boxes)
    sd_levels = float(math.sqrt((se[idx] ** 2).sum()) / n)
    sd_scatter = float(dl[idx].std(ddof=1) / math.sqrt(n))
    if sd_scatter > sd_levels:
        sd, half = sd_scatter, float(stats.t.ppf(0.975, n - 1)) * sd_scatter
    else:
        sd, half = sd_levels, float(stats.norm.ppf(0.975)) * sd_levels
    # the finer and the coarser half (the middle level in both when odd)
    coarse, fine = idx[: (n + 1) // 2], idx[n - (n + 1) // 2:]
    halves = (float(dl[fine].mean()), float(dl[coarse].mean()))
    return {
        "dimension": d,
        "stderr": sd,
        "ci": (d - half, d + half),
        "fit_range": (float(scales_measured[idx[-1] + 1]), float(scales_measured[idx[0]])),
        "systematic": float(max(abs(d - h) for h in halves)),
        "halves": halves,
    }
