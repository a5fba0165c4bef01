"""The app's downloads: the current view as a PNG figure and as netCDF data.

Both take the dataset the page shows (they never recompute it), so what is
downloaded is what was on screen.
"""

from __future__ import annotations

import io
import math
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from .. import plane
from .view import MOTION_COLOR_VARS, View, border_overlay, classes, color_key, overlay_curves

__all__ = ["view_png", "view_netcdf", "export_name"]


def export_name(view: View, suffix: str) -> str:
    """``stairbounce_e0-1_u0-1.5.png``: a file name that says which window it holds."""
    def f(x):
        return f"{x:.10g}"

    return f"stairbounce_e{f(view.e_lo)}-{f(view.e_hi)}_u{f(view.u_lo)}-{f(view.u_hi)}{suffix}"


def view_png(ds, view: View, dpi: int = 100, borders: dict | None = None) -> bytes:
    """view_png(ds, view, dpi=100, borders=None) -> bytes

    A PNG of the map as shown: one image pixel per scan pixel (nearest
    neighbour), axes in e and u, the colour key, the overlays of the view,
    the window and max_iter in the title.  ``borders``: the exact borders as
    the page draws them, ``{"points": {"e", "u", "kind"}, "arcs": {"xs",
    "ys", "kind"}}`` (the traced arcs and the border points they leave);
    without it the "borders" and "traced" overlays draw the view's border
    points (:func:`~stairbounce.explorer.view.border_overlay`).
    """
    # the Figure API without pyplot: no global state, so the server can make
    # PNGs on a thread of its own
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.figure import Figure

    key = color_key(view.color)
    idx = classes(ds, view.color).astype(float)
    idx[idx < 0] = np.nan
    cmap = ListedColormap(list(key.colors)).with_extremes(bad="white")
    n = len(key.colors)
    norm = BoundaryNorm(np.arange(n + 1) - 0.5, n)
    # small views are drawn k image pixels per scan pixel, so the axes and
    # the key stay legible and every scan pixel is still a crisp square
    k = max(1, math.ceil(450 / min(view.width, view.height)))
    w, h = view.width * k / dpi, view.height * k / dpi  # image size, inches
    fw, fh = w + 2.9, h + 1.4
    fig = Figure(figsize=(fw, fh), dpi=dpi)
    ax = fig.add_axes((1.0 / fw, 0.75 / fh, w / fw, h / fh))
    im = ax.imshow(idx, origin="lower", extent=(view.e_lo, view.e_hi, view.u_lo, view.u_hi),
                   aspect="auto", interpolation="nearest", cmap=cmap, norm=norm)
    curves = overlay_curves(view)
    styles: dict[str, dict[str, Any]] = {"tongues": dict(color="0.6", lw=0.7),
                                        "no_sliding": dict(color="C3", lw=1.2, ls="--")}
    drew_borders = False
    for name in view.overlays:
        if name in ("borders", "traced"):  # the exact borders, coloured by kind
            if not drew_borders:
                _draw_borders(ax, view, borders)
            drew_borders = True
            continue
        if name == "proven":  # the certified atlas is drawn on the page only
            continue
        for xs, ys in zip(*curves[name]):
            ax.plot(xs, ys, **styles[name])
    ax.set_xlim(view.e_lo, view.e_hi)
    ax.set_ylim(view.u_lo, view.u_hi)
    ax.set_xlabel("e (restitution coefficient)")
    ax.set_ylabel("u (horizontal speed)")
    ax.set_title(
        f"e in [{view.e_lo:.10g}, {view.e_hi:.10g}], u in [{view.u_lo:.10g}, {view.u_hi:.10g}]\n"
        f"{key.title}, max_iter {view.max_iter} "
        + ("(grey: the orbit slides)" if view.color in MOTION_COLOR_VARS
           else "(white: no periodic sliding solution within max_iter)"),
        fontsize="small",
    )
    cax = fig.add_axes(((w + 1.2) / fw, 0.75 / fh, 0.2 / fw, h / fh))
    cb = fig.colorbar(im, cax=cax, ticks=key.ticks)
    cb.ax.set_yticklabels([key.labels[i] for i in key.ticks], fontsize="small")
    cb.set_label(key.title, fontsize="small")
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()


def _draw_borders(ax, view, borders):
    """The border points (and traced arcs) of ``borders``, else the view's border points."""
    from matplotlib.collections import LineCollection

    from .._colours import KIND_COLOURS as KIND_COLORS

    b = border_overlay(view) if borders is None else borders["points"]
    ax.scatter(b["e"], b["u"], s=2, c=[KIND_COLORS[k] for k in b["kind"]], linewidths=0)
    arcs = {} if borders is None else borders.get("arcs", {})
    if arcs.get("xs"):
        lines = [np.column_stack([x, y]) for x, y in zip(arcs["xs"], arcs["ys"])]
        ax.add_collection(LineCollection(lines, colors=[KIND_COLORS[k] for k in arcs["kind"]],
                                         linewidths=1.2))


def view_netcdf(ds) -> bytes:
    """view_netcdf(ds) -> bytes

    The scan of the view as a netCDF4 file, written by
    :func:`stairbounce.plane.save` (same variables and attributes as
    ``stairbounce scan --out view.nc``).
    """
    with tempfile.TemporaryDirectory(prefix="stairbounce-") as tmp:
        path = Path(tmp) / "view.nc"
        plane.save(ds, path)
        return path.read_bytes()
