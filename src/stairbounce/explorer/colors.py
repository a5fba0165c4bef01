"""The colours of the explorer's map: the colour key of each variable
(:func:`color_key`), the classes of a scan (:func:`classes`) and its RGBA
picture (:func:`shade`).

Pure Python, no Panel or Bokeh; :mod:`stairbounce.explorer.view` re-exports
everything here.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import xarray as xr

from ..plot.plane import _CLASS_STARTS, NO_SLIDING_COLOR, ColorKey
from ..plot.plane import color_key as _sliding_color_key
from .window import COLOR_VARS, FIELDS, MOTION_COLOR_VARS, NO_SLIDING_LABEL


def has_color(ds: xr.Dataset, var: str) -> bool:
    """Whether ``ds`` holds what colouring by ``var`` needs (a motion variable
    needs a view computed with it, :func:`compute_view`)."""
    return var in ds or var == "status"


# Colours                                                                     #
# --------------------------------------------------------------------------- #

# One colour scale for the explorer and the figures (Figs. 4 and 5): the
# classes of the counts (_CLASS_STARTS from their least values _LEAST), their
# colours and white for no sliding live with the matplotlib renderer of the
# plane (stairbounce.plot.plane); the explorer adds the grey of pixels not yet
# computed and the continuous keys of the motion fields.
NOT_COMPUTED_COLOR = "#b8b8b8"


def color_key(var: str) -> ColorKey:
    """color_key(var) -> ColorKey: the classes and colours used for ``var``: the
    figures' discrete scale for the counts (:func:`stairbounce.plot.plane.color_key`),
    found / none within max_iter for ``status``, a continuous key for the
    motion variables."""
    if var not in FIELDS:
        raise ValueError(f"color must be one of {', '.join(COLOR_VARS)}, got {var!r}")
    if var in MOTION_COLOR_VARS:
        return _motion_key(var)
    _, title, b = FIELDS[var]
    if b is None:
        return ColorKey(var, title, ("found", NO_SLIDING_LABEL), ("#000000", NO_SLIDING_COLOR))
    return replace(_sliding_color_key(var), title=title)


def _rgba32(hex_colors):
    """Hex colours -> uint32 RGBA in the little-endian byte order Bokeh's
    ``image_rgba`` and Pillow's ``RGBA`` mode read."""
    out = np.empty(len(hex_colors), dtype=np.uint32)
    for i, h in enumerate(hex_colors):
        r, g, b = (int(h[k : k + 2], 16) for k in (1, 3, 5))
        out[i] = r | (g << 8) | (b << 16) | (255 << 24)
    return out


# Continuous keys of the motion variables: class 0 is "the orbit slides"
# (grey), then _NBINS colours over a fixed range: log10 <k> in [-2.5, 1.5];
# N lambda_1 in [-5, 5] (lambda_1 = 0 exactly, its finite-N estimate is O(1/N)).
_NBINS = 64
SLIDES_COLOR = "#9a9a9a"
_MOTION_RANGE = {"k_mean": (-2.5, 1.5), "lyap1": (-5.0, 5.0)}


def _motion_key(var):
    from matplotlib import colormaps
    from matplotlib.colors import to_hex

    cmap = colormaps["viridis" if var == "k_mean" else "RdBu_r"]
    colors = (SLIDES_COLOR,) + tuple(to_hex(cmap(x)) for x in np.linspace(0, 1, _NBINS))
    lo, hi = _MOTION_RANGE[var]
    labels = ["slides"] + [""] * _NBINS
    marks = {"k_mean": {-2: "0.01", -1: "0.1", 0: "1", 1: "10"},
             "lyap1": {-5: "-5/N", -2.5: "-2.5/N", 0: "0", 2.5: "+2.5/N", 5: "+5/N"}}[var]
    for x, text in marks.items():
        labels[1 + min(_NBINS - 1, int((x - lo) / (hi - lo) * _NBINS))] = text
    return ColorKey(var, FIELDS[var][1], tuple(labels), colors)


def classes(ds: xr.Dataset, var: str) -> np.ndarray:
    """Class index of every pixel under :func:`color_key` (-1: no sliding; a
    motion variable: 0 where the orbit slides, never -1)."""
    if var in MOTION_COLOR_VARS:
        lo, hi = _MOTION_RANGE[var]
        with np.errstate(invalid="ignore", divide="ignore"):
            x = np.log10(ds[var].values) if var == "k_mean" else ds[var].values * ds.attrs["motion_steps"]
        idx = 1 + np.clip(np.floor((x - lo) / (hi - lo) * _NBINS), 0, _NBINS - 1)
        return np.where((ds["slide_step"].values > 0) | ~np.isfinite(x), 0, idx).astype(np.int64)
    sliding = ds["status"].values == 0
    least = FIELDS[var][2]
    if least is None:
        return np.where(sliding, 0, 1)
    v = ds[var].values.astype(np.int64) - least
    idx = np.searchsorted(np.asarray(_CLASS_STARTS), v, side="right") - 1
    return np.where(sliding, idx, -1)


def shade(ds: xr.Dataset, var: str) -> np.ndarray:
    """shade(ds, var) -> uint32 array (n_u, n_e)

    RGBA pixels of a scan coloured by ``var`` (row 0 is the lowest u), the
    colours of :func:`color_key`; no sliding solution is white.
    """
    key = color_key(var)
    lut = _rgba32(key.colors + (NO_SLIDING_COLOR,))
    return lut[classes(ds, var)]  # index -1 picks the no-sliding colour
