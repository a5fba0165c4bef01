"""The exact borders of :func:`stairbounce.border_points` drawn over a scan,
coloured by the event that makes them (graze, edge, chatter)."""

from __future__ import annotations

import numpy as np

from .. import _validate as _v

from .._colours import KIND_COLOURS as _KIND_COLOURS

KIND_COLORS = {k: _KIND_COLOURS[k] for k in ("graze", "edge", "chatter")}
"""One colour per kind of border point (stairbounce._colours, the same in the
explorer and the SVG export), outside the word-length key and apart from the
tongues' magenta."""

_KINDS = tuple(KIND_COLORS)

MUTED = 0.3
"""Opacity of the scan drawn under the borders, and of its colour key."""


def plot_borders(points, ax=None, scan=None, kinds=_KINDS, size=None, legend="upper right", title=None):
    """plot_borders(points, ax=None, scan=None, kinds=("graze", "edge", "chatter"), size=None, legend="upper right", title=None) -> Axes

    Draw border points located to rounding, one dot each, coloured by kind.

    Parameters
    ----------
    points : xarray.Dataset from :func:`stairbounce.border_points`.
    ax : matplotlib Axes, default a new figure (or the scan's).
    scan : optional scan Dataset drawn first with :func:`plot_scan` (the
        raster the borders separate), muted (opacity ``MUTED``), with its
        colour key muted alike.
    kinds : the kinds to draw, among "graze", "edge", "chatter".
    size : marker area in points^2, default from the number of points.
    legend : location of the legend (counts per kind, markers of a fixed,
        legible size), or None.
    title : default "exact borders" with the count.
    """
    import matplotlib.pyplot as plt

    kinds = tuple(kinds)
    _v.among("kinds", kinds, _KINDS)
    if not hasattr(points, "data_vars") or "kind" not in points:
        raise ValueError("points must be a Dataset from stairbounce.border_points")
    if scan is not None:
        from .plane import plot_scan

        ax = plot_scan(scan, ax=ax, colorbar=True, legend=None,
                       title=title if title is not None else "")
        for image in ax.images:  # muted, so that the borders stand out, and its key with it
            image.set_alpha(MUTED)
            key = getattr(image, "colorbar", None)
            if key is not None and key.solids is not None:
                key.solids.set_alpha(MUTED)
                label = key.ax.get_ylabel()
                key.set_label(label.replace("  (", " (muted; ", 1) if "  (" in label else label + " (muted)",
                              fontsize="small")
    elif ax is None:
        _, ax = plt.subplots(figsize=(8, 6))
    n = points.sizes.get("point", 0)
    if size is None:
        size = float(np.clip(20000.0 / max(n, 1), 1.0, 8.0))
    kind = points["kind"].values
    for k in kinds:
        sel = kind == k
        ax.scatter(points["e"].values[sel], points["u"].values[sel], s=size, c=KIND_COLORS[k],
                   marker=".", linewidths=0, label=f"{k} ({int(sel.sum())})", zorder=3,
                   rasterized=True)
    if scan is None:
        a = points.attrs
        if all(key in a for key in ("e_min", "e_max", "u_min", "u_max")):
            ax.set_xlim(a["e_min"], a["e_max"])
            ax.set_ylim(a["u_min"], a["u_max"])
        ax.set_xlabel("e")
        ax.set_ylabel("u")
    if title is None:
        ax.set_title(f"exact borders: {n} points located to rounding")
    elif scan is None:
        ax.set_title(title)
    if legend is not None:
        earlier = ax.get_legend()
        if earlier is not None:  # the scan's overlay legend stays
            ax.add_artist(earlier)
        from matplotlib.lines import Line2D

        # legend markers of a legible size, whatever the size of the dots
        handles = [Line2D([], [], linestyle="", marker="o", markersize=7, color=KIND_COLORS[k],
                          label=f"{k} ({int((kind == k).sum())})") for k in kinds]
        ax.legend(handles=handles, loc=legend, fontsize="small",
                  title="event at the step's edge", title_fontsize="small")
    return ax
