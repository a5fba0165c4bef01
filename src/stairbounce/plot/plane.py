"""The (e, u) parameter plane (the paper's Figures 3, 4 and 5) from a scan dataset."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import _units
from .. import _validate as _v

__all__ = ["plot_scan", "FIELDS", "ColorKey", "color_key", "NO_SLIDING_COLOR", "class_bounds"]

FIELDS = {
    "word_length": "word length",
    "period": "period (steps)",
    "impacts": "finite impacts per period",
    "jumps": "non-zero letters (landings per period)",
    "status": "periodic sliding solution",
}
OVERLAYS = ("tongues", "bound")

# --------------------------------------------------------------------------- #
# The colour classes, shared by the figures and the browser explorer          #
# --------------------------------------------------------------------------- #

# Lower bounds of the colour classes, counted from the least value a variable
# takes on a sliding pixel (1 for word length, period and jumps; 0 for
# impacts): the first class holds the (n, 0^inf) solutions for word length,
# impacts and jumps (black, as the paper's tongues in Fig. 4); classes widen
# because the counts fall off roughly geometrically.
_CLASS_STARTS = (0, 1, 2, 3, 4, 5, 7, 10, 15, 25, 50, 100, 250, 500)
_LEAST = {"word_length": 1, "period": 1, "impacts": 0, "jumps": 1}
NO_SLIDING_COLOR = "#ffffff"
_LABELS = {
    "word_length": "word length",
    "period": "period (steps)",
    "impacts": "impacts per period",
    "jumps": "non-zero letters",
    "status": "periodic sliding solution",
}


@dataclass(frozen=True)
class ColorKey:
    """The colour classes of a variable: ``colors[i]`` paints values in class
    ``i`` (labelled ``labels[i]``); pixels without a sliding solution get
    ``NO_SLIDING_COLOR``."""

    var: str
    title: str
    labels: tuple[str, ...]
    colors: tuple[str, ...]

    @property
    def ticks(self) -> list[int]:
        """Indices of the labelled colours (a continuous key labels a few)."""
        return [i for i, t in enumerate(self.labels) if t]


def _palette(n):
    """Black, then ``n - 1`` well separated colours of the turbo map."""
    from matplotlib import colormaps
    from matplotlib.colors import to_hex

    cmap = colormaps["turbo"]
    return ("#000000",) + tuple(to_hex(cmap(x)) for x in np.linspace(0.1, 0.95, n - 1))


def color_key(var: str) -> ColorKey:
    """color_key(var) -> ColorKey: the classes and colours used for ``var``.

    One fixed, discrete scale per variable (word length: 1, 2, 3, 4, 5, 6-7,
    8-10, 11-15, ..., >= 501), the same in every figure and in the explorer,
    so a word length has the same colour in every window."""
    if var == "status":
        return ColorKey(var, _LABELS[var], ("found", "none"), ("#000000", NO_SLIDING_COLOR))
    if var not in _LEAST:
        raise ValueError(f"color must be one of {', '.join(FIELDS)}, got {var!r}")
    b = _LEAST[var]
    labels = []
    for lo, hi in zip(_CLASS_STARTS, _CLASS_STARTS[1:] + (None,)):
        if hi is None:
            labels.append(f">= {b + lo}")
        elif hi - lo == 1:
            labels.append(str(b + lo))
        else:
            labels.append(f"{b + lo}-{b + hi - 1}")
    return ColorKey(var, _LABELS[var], tuple(labels), _palette(len(labels)))


def class_bounds(var: str) -> np.ndarray:
    """Edges of the colour classes of ``var`` in its own units: class ``i``
    holds ``bounds[i] <= value < bounds[i + 1]`` (the last edge is 2**62,
    beyond any count a scan stores)."""
    if var not in _LEAST:
        raise ValueError(f"var must be one of {', '.join(_LEAST)}, got {var!r}")
    return np.array([_LEAST[var] + s for s in _CLASS_STARTS] + [2**62], dtype=float)


def _extent(ds):
    """Image edges: the window stored by :func:`stairbounce.plane.scan`, else
    half a pixel beyond the outer coordinates."""
    a = ds.attrs
    if all(k in a for k in ("e_min", "e_max", "u_min", "u_max")):
        return float(a["e_min"]), float(a["e_max"]), float(a["u_min"]), float(a["u_max"])
    out = []
    for name in ("e", "u"):
        c = np.asarray(ds[name].values, dtype=float)
        h = 0.5 * (c[-1] - c[0]) / (c.size - 1) if c.size > 1 else 0.5e-3 * max(abs(c[0]), 1.0)
        out += [c[0] - h, c[-1] + h]
    return tuple(out)


def _no_solution(ds, field):
    """Where there is no periodic sliding solution: ``status != 0``; for a
    dataset reduced to one variable, word length, period and jumps are 0
    exactly there (impacts is 0 in the tongues too, so it cannot tell)."""
    if "status" in ds:
        return np.asarray(ds["status"].values) != 0
    for name in ("word_length", "period", "jumps"):
        if name in ds:
            return np.asarray(ds[name].values) == 0
    return np.zeros(ds[field].shape, dtype=bool)


TONGUE_COLOR = "#ff00ff"
"""Colour of the tongue boundaries over the map: magenta is in no colour class."""
BOUND_COLOR = "0.35"


def _draw_tongues(ax, e_lo, e_hi, u_lo, u_hi, color):
    """Boundaries of the (n, 0^inf) tongues of Theorem 3.1 crossing the view;
    returns whether any of them is inside the view."""
    e = np.linspace(e_lo, e_hi, 600)
    n_top = int(2.0 * u_hi**2) + 2
    seen = False
    for n in range(1, n_top + 1):
        # Theorem 3.1, as stairbounce.tongue(n, e) evaluates it, vectorised
        lows = np.full_like(e, np.sqrt((n - 1) / 2.0))
        highs = np.sqrt(n / 2.0) * (1.0 - e) / (1.0 + e)
        inside = highs > lows  # the tongue is open at these e
        if not inside.any():
            continue
        kw = dict(color=color, lw=0.9, ls="-")
        curves = [highs] + ([lows] if n > 1 else [])
        for c in curves:
            ax.plot(e[inside], c[inside], **kw)
            seen |= bool(((c[inside] >= u_lo) & (c[inside] <= u_hi)).any())
    return seen


def _legend(ax, where, handles=None):
    """A legend ``where`` = a matplotlib location, ``"below"`` (outside the
    axes, under the e label: for windows whose data fill every corner) or None."""
    if where is None:
        return
    if handles is None:
        handles = ax.get_legend_handles_labels()[0]
    if not handles:
        return
    if where == "below":
        ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.13),
                  ncol=2, fontsize="small", frameon=False)
    else:
        ax.legend(handles=handles, loc=where, fontsize="small")


def plot_scan(ds, field="word_length", ax=None, overlay=(), cmap=None, colorbar=True, title=None,
              legend="upper right"):
    """plot_scan(ds, field="word_length", ax=None, overlay=(), cmap=None, colorbar=True, title=None, legend="upper right") -> Axes

    Draw a scan of the (e, u) plane: the paper's Figure 4 and its blow-ups.

    Each pixel of ``ds`` (from :func:`stairbounce.plane.scan`) is coloured by
    the class of its ``field`` value on one fixed, discrete scale
    (:func:`color_key`: word length 1, 2, 3, 4, 5, 6-7, 8-10, ..., >= 501,
    black for 1 as in the paper's Fig. 4), the same in every window, so that
    panels drawn separately compare colour for colour; white where there is
    no periodic sliding solution within max_iter (``status == 1``).
    ``field="status"`` draws the sliding set in black.

    Parameters
    ----------
    ds : xarray.Dataset with dims ("u", "e") and the variables of a scan.
    field : one of "word_length", "period", "impacts", "jumps", "status".
    ax : matplotlib Axes, default a new figure.
    overlay : iterable of "tongues" (boundaries of the (n, 0^inf) tongues,
        Theorem 3.1, magenta) and "bound" (the no-sliding bound of
        Corollary 2.1, grey dashed).  A curve outside the window gets no
        legend entry.
    cmap : list of colours, one per class, default :func:`color_key`'s.
    colorbar : draw the colour key (a legend for ``status``).
    title : default names the window and max_iter.
    legend : location of the overlay legend, ``"below"`` the axes, or None.

    The extent is the scan's window: axes labelled e and u, origin lower left.
    """
    import matplotlib.colors as mcolors
    import matplotlib.pyplot as plt

    if field not in FIELDS:
        raise ValueError(f"field must be one of {', '.join(FIELDS)}, got {field!r}")
    overlay = tuple(overlay)
    _v.among("overlay", overlay, OVERLAYS)
    if ax is None:
        _, ax = plt.subplots(figsize=(8, 6))
    e_lo, e_hi, u_lo, u_hi = _extent(ds)
    none = _no_solution(ds, field)
    key = color_key(field)
    if field == "status":
        data = np.ma.masked_array(np.ones(none.shape), mask=none)
        cm = mcolors.ListedColormap(["black"]).with_extremes(bad="white")
        norm = mcolors.Normalize(0, 1)
    else:
        data = np.ma.masked_array(np.asarray(ds[field].values, dtype=float), mask=none)
        colors = key.colors if cmap is None else tuple(cmap)
        if len(colors) != len(key.colors):
            raise ValueError(f"cmap must list {len(key.colors)} colours, one per class, "
                             f"got {len(colors)}")
        cm = mcolors.ListedColormap(colors).with_extremes(bad=NO_SLIDING_COLOR)
        norm = mcolors.BoundaryNorm(class_bounds(field), len(colors))
    im = ax.imshow(
        data, origin="lower", extent=(e_lo, e_hi, u_lo, u_hi), aspect="auto",
        interpolation="nearest", cmap=cm, norm=norm,
    )
    handles = []
    if "tongues" in overlay and _draw_tongues(ax, e_lo, e_hi, u_lo, u_hi, TONGUE_COLOR):
        handles.append(plt.Line2D([], [], color=TONGUE_COLOR, lw=0.9,
                                  label=r"$(n, 0^\infty)$ tongues, Theorem 3.1"))
    if "bound" in overlay:
        e = np.linspace(max(e_lo, 1e-6), e_hi, 600)
        curve = (1.0 - e) / (2.0 * np.sqrt(2.0 * e))
        ax.plot(e, curve, color=BOUND_COLOR, lw=1.4, ls="--")
        if ((curve >= u_lo) & (curve <= u_hi)).any():
            handles.append(plt.Line2D([], [], color=BOUND_COLOR, lw=1.4, ls="--",
                                      label="Corollary 2.1: no sliding above"))
    stairs = _units.frame_plane(ax, ds, e_lo, e_hi, u_lo, u_hi)
    mi = ds.attrs.get("max_iter")
    if title is None:
        speeds = (f"u in [{u_lo:g}, {u_hi:g}]" if stairs is None else
                  f"U in [{u_lo * stairs.speed_unit:.4g}, {u_hi * stairs.speed_unit:.4g}] m/s "
                  f"({_units.describe(stairs)})")
        title = f"e in [{e_lo:g}, {e_hi:g}], {speeds}" + (
            f", max_iter {mi}" if mi is not None else ""
        )
    ax.set_title(title)
    within = f" within max_iter = {mi}" if mi is not None else ""
    if colorbar and field == "status":
        from matplotlib.patches import Patch

        handles = [Patch(color="black", label="periodic sliding solution"),
                   Patch(facecolor="white", edgecolor="0.5", label=f"none{within}")] + handles
    elif colorbar:
        cb = ax.figure.colorbar(im, ax=ax, spacing="uniform", pad=0.02)
        bounds = class_bounds(field)
        # a tick in the middle of each class, labelled with the class
        cb.set_ticks(0.5 * (bounds[:-1] + bounds[1:]), labels=list(key.labels))
        cb.ax.tick_params(labelsize="small", length=0)
        cb.ax.minorticks_off()
        cb.set_label(f"{FIELDS[field]}  (white: no periodic sliding solution{within})",
                     fontsize="small")
    _legend(ax, legend, handles)
    return ax
