"""Is an estimate converged in ``max_iter``?  Scale by scale, against the same
measurement at a larger ``max_iter``.

A point counts as sliding when its orbit reaches the sliding solution within
``max_iter`` steps; a finite ``max_iter`` misclassifies the points that would
need more, and they lie close to the border, so the fractal is truncated below
some scale and the local dimension there reads wrong.  The check: measure
again with a larger ``max_iter`` and the same random points, lines or picture
(same seed), and compare the local dimensions scale by scale.  Where the
difference exceeds the band it is held to (the two 95% bands combined and
widened for the number of scales compared, or :data:`NO_NOISE_MODEL_BAND` for
an estimator without a per-scale noise model, box counting), ``max_iter`` is
not converged at that scale.  The widening (Bonferroni) keeps the chance that a
converged estimate is called moved at *some* scale at 5 %, instead of 5 % per
scale: with ten scales, plain 95% bands would flag one by chance about four
times in ten, and a chance flag at a coarse scale would cut the whole range.

Non-convergence sets in below a scale (finer scales need longer orbits): it is
the run of moved scales that reaches the finest one (``truncated``), and the
*converged range* is every compared scale coarser than that run: a fit should
stay there (:meth:`MaxIterCheck.cut`).  A scale that moved while every finer
scale agrees cannot be truncation; it is reported as a chance flag.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["MaxIterCheck", "NO_NOISE_MODEL_BAND", "max_iter_check"]

#: the band a local dimension is held to where the estimator has no per-scale
#: noise model (box counting)
NO_NOISE_MODEL_BAND = 0.03


@dataclass(frozen=True)
class MaxIterCheck:
    """The local dimensions of one measurement at two ``max_iter``
    (:func:`max_iter_check`), at the scales both measured (coarse to fine as
    the estimates list them, in ``scale_unit``): ``local_a`` at
    ``max_iter[0]``, ``local_b`` at ``max_iter[1]``, ``difference = local_b -
    local_a``, and ``band`` the half-width the difference is held to."""

    max_iter: tuple[int | None, int | None]
    scales: np.ndarray
    local_a: np.ndarray
    local_b: np.ndarray
    difference: np.ndarray
    band: np.ndarray
    scale_unit: str = ""

    @property
    def moved(self) -> np.ndarray:
        """Per scale: the local dimension moves beyond its band (or is
        measured at one ``max_iter`` and not at the other)."""
        a, b = np.isfinite(self.local_a), np.isfinite(self.local_b)
        with np.errstate(invalid="ignore"):
            beyond = np.abs(self.difference) > self.band
        return (a != b) | (a & b & beyond)

    @property
    def truncated(self) -> np.ndarray:
        """Per scale: part of the run of moved scales that reaches the finest
        compared scale.  A finite ``max_iter`` truncates the border below some
        scale, so non-convergence is such a run; a scale that moved while every
        finer one agrees cannot be truncation and is a chance flag (listed by
        :meth:`text`, not cut)."""
        moved = self.moved
        out = np.zeros_like(moved)
        for i in np.argsort(self.scales):  # finest first
            if not moved[i]:
                break
            out[i] = True
        return out

    @property
    def converged(self) -> bool:
        """Some scale compared, and none truncated."""
        return self.scales.size > 0 and not bool(self.truncated.any())

    @property
    def not_converged(self) -> tuple[float, float] | None:
        """``(smallest, largest)`` truncated scale, or None."""
        s = self.scales[self.truncated]
        return None if s.size == 0 else (float(s.min()), float(s.max()))

    @property
    def converged_range(self) -> tuple[float, float] | None:
        """``(smallest, largest)`` compared scale coarser than every truncated
        scale (all of them when none is); None when none is left."""
        bad = self.not_converged
        s = self.scales if bad is None else self.scales[self.scales > bad[1]]
        return None if s.size == 0 else (float(s.min()), float(s.max()))

    def cut(self, fit_range) -> tuple[float, float] | None:
        """The part of ``fit_range = (smallest, largest)`` scale inside the
        converged range: the compared scales in both, as ``(smallest,
        largest)``; None when no compared scale is left."""
        good = self.converged_range
        if good is None:
            return None
        lo, hi = (float(v) for v in fit_range)
        s = self.scales[(self.scales >= max(lo, good[0])) & (self.scales <= min(hi, good[1]))]
        return None if s.size == 0 else (float(s.min()), float(s.max()))

    def rows(self):
        """Per compared scale: ``(scale, local_a, local_b, difference, band, moved)``."""
        return zip(self.scales, self.local_a, self.local_b, self.difference, self.band, self.moved)

    def text(self) -> str:
        """One line: ``max_iter A -> B: converged at scales a..b`` or ``not
        converged at scales a..b`` (scales that moved), with the converged
        range."""
        a, b = self.max_iter
        head = f"max_iter {a} -> {b}"
        chance = self.scales[self.moved & ~self.truncated]
        note = ("" if chance.size == 0 else
                f" (moved beyond its band at {', '.join(_g(x) for x in chance)} while every finer "
                f"scale agrees: a chance flag, not truncation)")
        if self.converged:
            return (f"{head}: converged at scales {_g(self.scales.min())}..{_g(self.scales.max())} "
                    f"{self.scale_unit}".rstrip() + note)
        bad = self.not_converged
        if bad is None:
            return f"{head}: no scale measured at both"
        lo, hi = bad
        good = self.converged_range
        rest = "none converged" if good is None else f"converged at {_g(good[0])}..{_g(good[1])}"
        return f"{head}: not converged at scales {_g(lo)}..{_g(hi)} {self.scale_unit}: {rest}{note}"


def max_iter_check(estimate_a, estimate_b, rtol=1e-9) -> MaxIterCheck:
    """max_iter_check(estimate_a, estimate_b, rtol=1e-9) -> MaxIterCheck

    Compare two estimates of one measurement (same method, window, seed,
    lines or picture) made at two ``max_iter``, scale by scale: their local
    dimensions (``local_band()``) at the scales both measured (equal within
    ``rtol``), the difference, and the band it is held to: the two 95% bands
    combined (``hypot``) and widened for the n scales compared so that the
    family of n comparisons has a 5 % false alarm rate (Bonferroni), or
    :data:`NO_NOISE_MODEL_BAND` where an estimator gives none.  ``estimate_b`` is the one at the larger ``max_iter``.

    Raises
    ------
    ValueError
        When the two estimates measure in different units of scale (different
        methods).
    """
    unit_a = getattr(estimate_a, "scale_unit", "")
    unit_b = getattr(estimate_b, "scale_unit", "")
    if unit_a != unit_b:
        raise ValueError(f"estimate_a and estimate_b must be one method (scales {unit_a!r} and "
                         f"{unit_b!r})")
    m1, d1, h1 = (np.asarray(x, dtype=float) for x in estimate_a.local_band())
    m2, d2, h2 = (np.asarray(x, dtype=float) for x in estimate_b.local_band())
    # the scales both measured, in the order of estimate_a
    ia, ib = [], []
    for i, m in enumerate(m1):
        j = np.flatnonzero(np.isclose(m2, m, rtol=rtol, atol=0.0))
        if j.size:
            ia.append(i)
            ib.append(int(j[0]))
    ia_, ib_ = np.asarray(ia, dtype=int), np.asarray(ib, dtype=int)
    band = np.hypot(h1[ia_], h2[ib_])
    band = band * _family_factor(int(np.isfinite(band).sum()))
    band = np.where(np.isfinite(band), band, NO_NOISE_MODEL_BAND)
    a, b = d1[ia_], d2[ib_]
    return MaxIterCheck(
        max_iter=(getattr(estimate_a, "max_iter", None), getattr(estimate_b, "max_iter", None)),
        scales=m1[ia_], local_a=a, local_b=b, difference=b - a, band=band, scale_unit=unit_a,
    )


def _family_factor(n):
    """How much a 95% half-width (1.96 sigma) widens so that ``n`` comparisons
    together flag a converged estimate with probability at most 5 %
    (Bonferroni: 1 - 0.05/n two-sided per scale); 1 for one comparison."""
    if n <= 1:
        return 1.0
    from scipy.stats import norm

    return float(norm.ppf(1.0 - 0.025 / n) / norm.ppf(0.975))


def _g(x):
    x = float(x)
    return f"{x:.3g}" if math.isfinite(x) else str(x)
