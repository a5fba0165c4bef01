"""The model's classification of ``(e, u)`` points (slides or not, or with
which word length), for the estimators that need no picture."""

from __future__ import annotations

import numpy as np

from ..model import check_count

__all__ = ["SlidingClassifier", "sliding_classifier"]

_WHICH = ("sliding", "words")


class SlidingClassifier:
    """``classify(e, u) -> labels`` of the model for :func:`uncertain_fraction`;
    made by :func:`sliding_classifier`.  A plain object (not a closure), so it
    can be sent to Dask workers."""

    def __init__(self, max_iter, which, y0, v0, prune=True):
        self.max_iter, self.which, self.y0, self.v0, self.prune = max_iter, which, y0, v0, prune

    def __call__(self, e, u):
        from ..plane import scan_points

        from .._validate import E_MIN

        e = np.asarray(e, dtype=float)
        # a random point or a line refined next to a window's edge e = 0 may land in
        # (0, 2^-53), outside the valid numeric range: there (1+e)/(1-e) rounds to 1 and
        # the model cannot tell e from 0. Such a point is evaluated at e = 0; the exact
        # answer differs only within about e|v| ~ 1e-16 in time of a graze (the rebound
        # of e < 2^-53 accumulates at once), far below every scale the estimators fit.
        e = np.where((e > 0.0) & (e < E_MIN), 0.0, e)
        ds = scan_points(e, np.asarray(u, dtype=float),
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
    from ..model import _finite

    max_iter = check_count("max_iter", max_iter, 1)
    if which not in _WHICH:
        raise ValueError(f"which must be one of {_WHICH}, got {which!r}")
    return SlidingClassifier(max_iter, which, _finite("y0", y0), _finite("v0", v0), bool(prune))
