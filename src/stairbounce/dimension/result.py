"""What every dimension estimate states beside its number: the scales it
covers, ``max_iter``, the local dimension against scale, and an interval that
covers both the statistical noise of the fit and the drift of the local slope
across the fitted scales (a systematic term, reported separately).

A dimension is a limit ``s -> 0``; a fit over a finite range of scales gives
the average slope there, and the slope may drift with the scale (a border not
equally rough at all scales, a finite ``max_iter`` that truncates the fractal
below some scale, the pixel staircase).  The systematic term is the largest
distance from ``D`` of the slopes fitted over the finer and the coarser half of
the fitted scales (:func:`stairbounce.dimension.fit.half_slopes`):
``interval = (ci_low - systematic, ci_high + systematic)``.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

__all__ = ["Estimate", "KNOWN_BIAS", "disagree"]

#: The estimators' bias (estimate minus the exact box dimension): the lowest
#: and the highest mean over 3 seeds, measured by ``benchmarks/dimension_bias.py``
#: at the defaults for a window of the model
#: (``stairbounce.dimension.perimeter.MODEL_DEFAULTS``) on sets of known
#: dimension that resemble the border: graphs of Weierstrass functions of
#: dimension 1.3, 1.5 and 1.6 (Kaplan, Mallet-Paret and Yorke 1984) and a family
#: of slivers of widths 2^-6..2^-33 (dimension 1).  The noise of each estimate
#: (its spread over seeds) is in its own interval; this is the bias beyond it.
#: Slicing: -0.018..-0.006 on the graphs (crossings hidden below a box's samples),
#: 0.000 on the slivers; the uncertainty exponent: -0.005..+0.007 on the graphs,
#: +0.17 on the slivers (strips wider than eps count twice, thinner ones once);
#: box counting of a 2048 px picture (scales 2e-3..3e-2): -0.19..-0.11 on the
#: graphs, -0.03 on the slivers.  Table in docs/guide/dimension.md, "Bias on
#: sets of known dimension"; measured at no other settings than these and the
#: defaults before issue 37, and on no dimension above 1.6 (slicing reads 0.03-0.04
#: low at 1.75, tests/test_slicing.py).
KNOWN_BIAS = {
    "slicing": (-0.02, 0.0),
    "uncertainty": (-0.01, 0.17),
    "boxes": (-0.20, -0.03),
}


class Estimate:
    """Mixin of the dimension result types (fields ``dimension``, ``ci``,
    ``systematic``, ``halves``, ``max_iter``): the drift-covering interval,
    the scales in words and the one-line warnings."""

    #: unit of :attr:`scales` (set by each result type)
    scale_unit = ""
    #: which estimator, the key of :data:`KNOWN_BIAS` (set by each result type)
    estimator = ""

    if TYPE_CHECKING:  # the fields each result type declares (for the type checker only)
        dimension: float
        ci: tuple[float, float]
        systematic: float
        halves: tuple[float, float]
        max_iter: int | None
        fit_range: tuple[float, float]

    @property
    def scales(self) -> tuple[float, float]:
        """``(smallest, largest)`` fitted scale, in :attr:`scale_unit`."""
        lo, hi = self.fit_range
        return float(lo), float(hi)

    @property
    def statistical(self) -> float:
        """Half-width of the statistical 95% interval :attr:`ci`."""
        return 0.5 * (self.ci[1] - self.ci[0])

    @property
    def interval(self) -> tuple[float, float]:
        """The 95% interval widened on each side by :attr:`systematic`, the
        drift of the local slope across the fitted scales."""
        return (self.ci[0] - self.systematic, self.ci[1] + self.systematic)

    @property
    def known_bias(self) -> tuple[float, float]:
        """``(lowest, highest)`` bias of this estimator on sets of known
        dimension at the model's default settings (:data:`KNOWN_BIAS`)."""
        return KNOWN_BIAS.get(self.estimator, (math.nan, math.nan))

    @property
    def bias_interval(self) -> tuple[float, float]:
        """:attr:`interval` corrected for every bias in :attr:`known_bias`:
        ``(interval[0] - highest, interval[1] - lowest)``; it covers the noise,
        the drift across the fitted scales and the estimator's bias, not the
        effect of ``max_iter`` (measure it: ``convergence.max_iter_check``)."""
        lo, hi = self.interval
        blo, bhi = self.known_bias
        return (lo - bhi, hi - blo)

    def scales_text(self) -> str:
        lo, hi = self.scales
        return f"{_g(lo)}..{_g(hi)} {self.scale_unit}".rstrip()

    def warning(self) -> str:
        """One line when the drift exceeds the statistical interval, else ""."""
        if not math.isfinite(self.systematic) or self.systematic <= self.statistical:
            return ""
        fine, coarse = self.halves
        return (f"warning: the local slope drifts across the fitted scales ({fine:.3f} over the "
                f"finer half, {coarse:.3f} over the coarser) by more than the statistical "
                f"interval +-{self.statistical:.3f}: the number depends on the range of scales")

    def interval_text(self) -> str:
        lo, hi = self.interval
        mi = "" if self.max_iter is None else f", max_iter {self.max_iter}"
        return (f"D = {self.dimension:.4f}  interval [{lo:.4f}, {hi:.4f}] (95% statistical "
                f"+-{self.statistical:.4f}, systematic +-{self.systematic:.4f}) over "
                f"{self.scales_text()}{mi}")


def disagree(a, b) -> str:
    """One line when two estimates' intervals do not overlap, else ""."""
    (alo, ahi), (blo, bhi) = a.interval, b.interval
    if ahi < blo or bhi < alo:
        return (f"warning: two methods disagree beyond their intervals: {a.dimension:.3f} "
                f"[{alo:.3f}, {ahi:.3f}] against {b.dimension:.3f} [{blo:.3f}, {bhi:.3f}]")
    return ""


def _g(x):
    return f"{x:.3g}" if abs(x) < 1e-2 or abs(x) >= 1e4 else f"{x:g}"
