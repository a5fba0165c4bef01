"""The border pixels of a region, or between the labels of an image: the set
whose dimension :mod:`stairbounce.dimension.boxes` measures."""

from __future__ import annotations

import numpy as np

from .. import _validate as _v

__all__ = ["boundary", "label_boundary"]


# --------------------------------------------------------------------------- #
# Borders                                                                     #
# --------------------------------------------------------------------------- #

_IMAGE_EDGES = ("ignore", "border")


def _check_image(name, image, ndim=2):
    # before a zero-copy view is materialised: its padded copy, the output and a
    # comparison's temporary (report round 3, R8)
    item = getattr(getattr(image, "dtype", None), "itemsize", 8)
    _v.check_array_memory(f"{name} of {{n}} pixels", image, item + 3)
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


def boundary(mask, connectivity=4, image_edge="ignore"):
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


def label_boundary(labels, connectivity=4):
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
