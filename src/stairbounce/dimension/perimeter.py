"""The dimension of the border of the sliding region in a window of the
``(e, u)`` plane (Section 3, Figs. 6 and 7): a scan and box counting, or the
uncertainty exponent or slicing of the model's classification."""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from .. import _validate as _v
from ..model import check_count
from ..plane import pixel_centres, scan, scan_coords
from .borders import boundary, label_boundary
from .boxes import BoxDimension, box_dimension
from .classifier import _WHICH, sliding_classifier
from .uncertainty import uncertainty_dimension

__all__ = ["MODEL_DEFAULTS", "PerimeterDimension", "perimeter_dimension"]


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

    def scales_text(self) -> str:
        lo, hi = self.fit_range
        n = max(self.resolution, 1)
        return f"boxes {lo}..{hi} px of {n} (= {lo / n:.3g}..{hi / n:.3g} of the window)"


_METHODS = ("boxes", "uncertainty", "slicing")


def _check_window(name, window):
    """``(min, max)`` or ``(min, max, n)`` -> ``((min, max), n or None)``."""
    try:
        lo, hi, n = _v.window(name, window)
        lo, hi = float(lo), float(hi)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a window (min, max) or (min, max, n), got {window!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise ValueError(f"{name} must be a finite window (min, max) with min < max, got {window!r}")
    return (lo, hi), (None if n is None else check_count(f"n_{name}", n, 8))


# the parameters of box counting alone, and their defaults (None: not given)
_BOX_DEFAULTS = dict(resolution=2048, connectivity=4, sizes=None, offsets=1, reduce="mean", tol=0.1, min_boxes=32)

#: The defaults of :func:`perimeter_dimension` and ``stairbounce dimension``
#: for a window of the model, per method (issue 37): the package's best answer
#: within about a minute on 2 cores (measured CPU time of one process in the Fig. 6
#: window, the costliest: uncertainty 11.6 s, slicing 8.0 s, boxes 1.8 s; wall up
#: to 99 s on the shared 2-core machine at load 23; docs/guide/dimension.md,
#: "The defaults").  Fine scales, where the local dimension has stopped
#: drifting (1e-8..1e-4 of the window), at ``max_iter`` 4000, which moves the
#: local dimension there by at most about 0.02 against 16000 (the guide's table);
#: a picture reaches only coarse scales, so box counting fits 2e-3..3e-2 of the
#: window, clear of the pixel scale.  The defaults before issue 37 (``max_iter``
#: 1000; 10^5 points at eps 1e-6..0.1; 64 lines fitted 1e-10..1e-2; 512 px with
#: the automatic fit range) are reached by giving those values.
MODEL_DEFAULTS = {
    "uncertainty": dict(max_iter=4000, n_points=300_000, eps=tuple(np.logspace(-8.0, -4.0, 9))),
    "slicing": dict(max_iter=4000, n_lines=128, scales=(1e-8, 1e-2), fit_range=(1e-8, 1e-4)),
    "boxes": dict(max_iter=1000, resolution=2048, fit_range=(4, 64)),
}


def _method_and_boxes(method, counts, boxes):
    """The method (None: slicing, unless parameters of box
    counting alone are given: then box counting, with a DeprecationWarning)
    and the box parameters with their defaults; box parameters or pixel
    counts given to another method are refused, never ignored."""
    given = sorted(k for k, v in boxes.items() if v is not None)
    if method is None:
        if given:
            warnings.warn(
                f"perimeter_dimension: {', '.join(given)} given without method: measured by box "
                "counting as before, but the default method is now slicing (as "
                "on the command line); pass method='boxes' to keep box counting",
                DeprecationWarning, stacklevel=3)
            method = "boxes"
        else:
            method = "slicing"
    if method not in _METHODS:
        raise ValueError(f"method must be one of {_METHODS}, got {method!r}")
    n_e, n_u = counts
    if method != "boxes":
        if given or n_e is not None or n_u is not None:
            what = ", ".join(given + [f"n_{a}" for a, n in zip("eu", counts) if n is not None])
            raise ValueError(f"{what} are parameters of box counting (method='boxes'); method = "
                             f"{method!r} classifies points and uses no pixels: leave them out")
        return method, boxes
    boxes = {k: (_BOX_DEFAULTS[k] if v is None else v) for k, v in boxes.items()}
    if n_e is not None or n_u is not None:
        if given and "resolution" in given:
            raise ValueError(f"resolution = {boxes['resolution']!r} and the pixel counts of the windows: "
                             "give the pixels once, as (min, max, n) windows or as resolution")
        if n_e is None or n_u is None or n_e != n_u:
            raise ValueError(f"box counting scans a square grid: give the same n along e and u, got "
                             f"n_e = {n_e}, n_u = {n_u}")
        boxes["resolution"] = n_e
    return method, boxes


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
    resolution=None,
    max_iter=None,
    which="sliding",
    connectivity=None,
    sizes=None,
    offsets=None,
    reduce=None,
    fit_range=None,
    tol=None,
    min_boxes=None,
    y0=1.0,
    v0=0.0,
    progress=None,
    method=None,
    n_points=None,
    eps=None,
    seed=0,
    prune=True,
    n_lines=None,
    scales=None,
):
    """perimeter_dimension(e=(0, 0.333), u=(0.4, 0.733), max_iter=None, which="sliding", ..., method="slicing") -> SlicingDimension, UncertaintyDimension, PerimeterDimension or SlicingDimension

    The dimension of the perimeter of the region of periodic sliding
    solutions in a window of the ``(e, u)`` plane (Section 3, Figs. 6 and 7),
    by default slicing along random lines, as ``stairbounce dimension``:
    of the three estimators it has the smallest bias on sets of known
    dimension that resemble the border (-0.02 to 0.00 on Weierstrass graphs
    of dimension 1.3 to 1.6, 0.00 on a sliver family, where the uncertainty
    exponent reads up to 0.2 high; docs/guide/dimension.md, "Bias on sets of
    known dimension"; issue 37).

    Every default is the package's best answer within about a minute on 2
    idle cores (``stairbounce.dimension.perimeter.MODEL_DEFAULTS``, issue 37): fine scales (1e-8..1e-4 of
    the window) at ``max_iter`` 4000 for the uncertainty exponent and slicing,
    a 2048 px picture fitted over 4..64 px for box counting.  The result's
    :attr:`~stairbounce.dimension.result.Estimate.bias_interval` also covers
    the estimator's bias measured on sets of known dimension
    (``stairbounce.dimension.result.KNOWN_BIAS``).

    With ``method="boxes"``: scans the window on ``resolution x resolution`` pixel centres
    (:func:`stairbounce.plane.scan`; status 0: the orbit of ``(y0, v0)``
    slides again within ``max_iter`` steps), takes the border of the status-0
    region (:func:`boundary`, ``image_edge="ignore"``: the frame of the
    window is not part of the perimeter) and measures it
    (:func:`box_dimension`).

    Parameters
    ----------
    e, u : (min, max) or (min, max, n)
        The window; default the paper's Fig. 6, ``[0, 0.333] x [0.4, 0.733]``.
        Fig. 7 is ``e=(0.155, 0.2138), u=(0.6, 0.658)``.  ``n`` (the same
        along both) is the pixel count of box counting, as ``resolution``.
    resolution : int >= 8, default 2048
        Pixels along each axis (box counting only).  With the default picture
        and no ``fit_range`` or ``sizes``, boxes of 4..64 px are fitted
        (2e-3..3e-2 of the window); a ``resolution`` given without
        ``fit_range`` gets the automatic range (512: the default before 0.4).
    max_iter : int >= 1, default None
        Steps of the Poincare map before a pixel counts as non-sliding; None:
        4000 for the uncertainty exponent and slicing, 1000 for box counting
        (whose scales, above 1e-3 of the window, it does not move).
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
    method : "slicing", "uncertainty" or "boxes", default "slicing"
        ``"slicing"`` (the default, as on the command line; before issue 37
        the default was ``"uncertainty"``, still chosen when ``n_points`` or
        ``eps`` is given without ``method``): see below.
        ``"uncertainty"``: the
        uncertainty exponent of random points of the window
        (:func:`uncertainty_dimension` with :func:`sliding_classifier`; no
        picture, so ``resolution``, ``connectivity``, ``sizes``, ``offsets``,
        ``reduce``, ``tol``, ``min_boxes`` and pixel counts are refused, and
        ``fit_range`` is ``(eps_min, eps_max)`` in window units); returns an
        :class:`UncertaintyDimension`.
        ``"boxes"``: box counting on a scanned picture (everything above);
        returns a :class:`PerimeterDimension`.  Box parameters given without
        ``method`` (the spelling of the old default) still select box
        counting, with a DeprecationWarning.
        ``"slicing"``: crossings of the border along ``n_lines`` random lines
        refined from ``scales[1]`` down to ``scales[0]`` of the window
        (:func:`stairbounce.dimension.slicing.slicing_dimension`; ``fit_range``
        is ``(scale_min, scale_max)``); returns a ``SlicingDimension``.
    n_points, eps, seed :
        Only for ``method="uncertainty"``: as in :func:`uncertainty_dimension`
        (default 300_000 points at 9 eps from 1e-8 to 1e-4 of the window, seed
        0; before 0.4: 100_000 points at :data:`DEFAULT_EPS`); ``seed`` also
        for ``method="slicing"``.
    n_lines, scales :
        Only for ``method="slicing"`` (default 128 lines refined from 1e-2 to
        1e-8 of the window, fitted over 1e-8..1e-4 when neither ``scales`` nor
        ``fit_range`` is given; before 0.4: 64 lines, 1e-10..1e-2, every
        level fitted).
    prune : bool, default True
        As in :func:`stairbounce.plane.scan` (same answer; False iterates
        the pixels above the Corollary 2.1 curve too).

    The paper reports 1.324 (Fig. 6) and 1.403 (Fig. 7) with r > 0.99.
    """
    e, n_e = _check_window("e", e)
    u, n_u = _check_window("u", u)
    if which not in _WHICH:
        raise ValueError(f"which must be one of {_WHICH}, got {which!r}")
    default_picture = resolution is None and n_e is None and n_u is None
    if method is None and (n_points is not None or eps is not None):
        method = "uncertainty"  # its own parameters select it, as before issue 37
    method, boxes = _method_and_boxes(method, (n_e, n_u), dict(
        resolution=resolution, connectivity=connectivity, sizes=sizes, offsets=offsets, reduce=reduce,
        tol=tol, min_boxes=min_boxes))
    best = MODEL_DEFAULTS[method]
    max_iter = check_count("max_iter", best["max_iter"] if max_iter is None else max_iter, 1)
    if method == "boxes" and default_picture and fit_range is None and sizes is None:
        fit_range = best["fit_range"]
    if method == "slicing":
        if scales is None and fit_range is None:
            fit_range = best["fit_range"]
        scales = best["scales"] if scales is None else scales
        n_lines = best["n_lines"] if n_lines is None else n_lines
    if method == "uncertainty":
        n_points = best["n_points"] if n_points is None else n_points
        eps = np.asarray(best["eps"]) if eps is None else eps
    resolution, connectivity, sizes, offsets, reduce, tol, min_boxes = (
        boxes[k] for k in ("resolution", "connectivity", "sizes", "offsets", "reduce", "tol", "min_boxes"))
    what = "sliding region" if which == "sliding" else "word-length regions"
    if method == "slicing":
        from .slicing import slicing_dimension

        try:
            lo, hi = (float(v) for v in scales)
        except (TypeError, ValueError):
            raise ValueError(f"scales must be a pair (scale_min, scale_max), got {scales!r}") from None
        return slicing_dimension(
            sliding_classifier(max_iter=max_iter, which=which, y0=y0, v0=v0, prune=prune), (e, u),
            n_lines=n_lines, scale_min=lo, scale_max=hi, seed=seed, fit_range=fit_range,
            progress=progress, label=f"border of the {what}, max_iter {max_iter}",
        )
    if method == "uncertainty":
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
        min_boxes=min_boxes, pixel_size=((e[1] - e[0]) / resolution, (u[1] - u[0]) / resolution),
    )
    return PerimeterDimension(
        **{f: getattr(est, f) for f in BoxDimension.__dataclass_fields__ if f != "max_iter"},
        border=border,
        e=e,
        u=u,
        resolution=resolution,
        max_iter=max_iter,
        which=which,
        region_fraction=float(region.mean()),
    )
