"""Orbit (bifurcation) diagrams: the paper's Figs. 8 and 9."""

from __future__ import annotations

import math

import numpy as np

from ..model import tongue
from ..orbits import _LONG_NAMES, _varied, orbit_density

__all__ = ["plot_orbit_diagram"]

_OVERLAYS = ("tongues",)


def _tongue_lines(varied, fixed, lo, hi):
    """Tongue boundaries of Theorem 3.1 inside [lo, hi] of the swept parameter:
    ``[(position, n, kind)]`` with kind "low" (u_low = sqrt((n-1)/2), excluded
    from the tongue) or "high" (u_high = sqrt(n/2)(1-e)/(1+e), included)."""
    lines = []
    if varied == "u":
        e = fixed
        n = 1
        # u_low grows like sqrt(n/2): stop once it is past the window
        while math.sqrt((n - 1) / 2.0) <= hi:
            u_low, u_high = tongue(n, e)
            if u_high > u_low:  # the tongue is not empty
                if n > 1 and lo <= u_low <= hi:
                    lines.append((u_low, n, "low"))
                if lo <= u_high <= hi:
                    lines.append((u_high, n, "high"))
            n += 1
    else:
        # fixed u: (3.1) holds for the one n with (n-1)/2 < u^2 <= n/2, while
        # (1-e)/(1+e) >= u / sqrt(n/2), i.e. up to e = (sqrt(n/2)-u)/(sqrt(n/2)+u)
        u = fixed
        n = max(1, math.ceil(2.0 * u * u))
        if (n - 1) / 2.0 < u * u <= n / 2.0:
            r = math.sqrt(n / 2.0)
            e_high = (r - u) / (r + u)
            if lo <= e_high <= hi:
                lines.append((e_high, n, "high"))
    return lines


def plot_orbit_diagram(ds, component="y", density=True, ax=None, overlay=(), bins=400,
                       range=None, cmap="inferno_r"):
    """plot_orbit_diagram(ds, component="y", density=True, ax=None, overlay=(), bins=400, range=None, cmap="inferno_r") -> Axes

    Draw an orbit (bifurcation) diagram from :func:`stairbounce.orbit_diagram`.

    By default the kept iterates are binned by
    :func:`stairbounce.orbits.orbit_density` (one column per parameter value,
    ``bins`` rows) and shown as an image with a logarithmic colour scale
    (empty cells white); ``density=False`` draws every point instead, as the
    paper's Figs. 8 and 9 do.  ``overlay=("tongues",)`` draws the boundaries of
    the sliding tongues of Theorem 3.1 as vertical lines: ``u_low =
    sqrt((n-1)/2)`` dashed and ``u_high = sqrt(n/2)(1-e)/(1+e)`` dotted when
    ``u`` is swept, ``e_high = (sqrt(n/2)-u)/(sqrt(n/2)+u)`` when ``e`` is.

    Parameters
    ----------
    ds : xarray.Dataset
        Output of :func:`stairbounce.orbit_diagram`.
    component : "y" or "v", default "y"
    density : bool, default True
    ax : matplotlib Axes or None
    overlay : iterable of str, default ()
        Subset of ``("tongues",)``.
    bins : int, default 400
        Density bins along the component.
    range : (float, float) or None, default None
        Range of the component shown (a zoom); None: the data with a margin.
    cmap : str, default "inferno_r"
        Colour map of the density image.
    """
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    varied = _varied(ds)
    if component not in ("y", "v"):
        raise ValueError(f"component must be 'y' or 'v', got {component!r}")
    overlay = (overlay,) if isinstance(overlay, str) else tuple(overlay)
    for name in overlay:
        if name not in _OVERLAYS:
            raise ValueError(f"overlay must be a subset of {_OVERLAYS}, got {name!r}")
    if ax is None:
        _, ax = plt.subplots(figsize=(9, 5.5))

    params = np.asarray(ds[varied].values, dtype=float)
    if density:
        if range is None:
            # a margin keeps the branch y = 1 (the state after sliding) off the frame
            values = np.asarray(ds[component].values, dtype=float)
            finite = values[np.isfinite(values)]
            lo, hi = (finite.min(), finite.max()) if finite.size else (0.0, 1.0)
            pad = 0.03 * (hi - lo) if hi > lo else 0.5
            range = (lo - pad, hi + pad)
        d = orbit_density(ds, bins=bins, component=component, range=range)
        counts = d.values.T.astype(float)
        counts[counts == 0] = np.nan  # empty cells stay white
        (p0, p1), (c0, c1) = d.attrs["param_range"], d.attrs["range"]
        vmax = np.nanmax(counts) if np.isfinite(counts).any() else 1.0
        # antialiased in colour space: thin branches survive when there are
        # more parameter values than pixel columns
        im = ax.imshow(counts, origin="lower", aspect="auto", extent=(p0, p1, c0, c1),
                       interpolation="antialiased", interpolation_stage="rgba", cmap=cmap,
                       norm=LogNorm(vmin=1, vmax=max(vmax, 1.0)))
        cb = ax.figure.colorbar(im, ax=ax, pad=0.01)
        cb.set_label("iterates per cell")
    else:
        values = np.asarray(ds[component].values, dtype=float)
        ps = np.broadcast_to(params[:, None], values.shape)
        ax.plot(ps.ravel(), values.ravel(), ",", color="k", alpha=0.6, rasterized=True)
        if params.min() < params.max():
            ax.set_xlim(params.min(), params.max())
        if range is not None:
            ax.set_ylim(*range)

    if "tongues" in overlay:
        lo, hi = ax.get_xlim()
        fixed = float(ds.attrs["e" if varied == "u" else "u"])
        for pos, n, kind in _tongue_lines(varied, fixed, min(lo, hi), max(lo, hi)):
            low = kind == "low"
            colour = "C0" if low else "C2"
            ax.axvline(pos, color=colour, lw=0.8, ls="--" if low else ":", zorder=3)
            # tongue number inside the tongue: right of its start, left of its end
            ax.annotate(str(n), (pos, 1.0), xycoords=("data", "axes fraction"),
                        xytext=(2 if low else -2, -2), textcoords="offset points",
                        ha="left" if low else "right", va="top", fontsize="x-small", color=colour)
        if varied == "u":
            ax.plot([], [], color="C0", lw=0.8, ls="--", label="tongue n begins (u_low, Thm 3.1)")
        ax.plot([], [], color="C2", lw=0.8, ls=":", label=f"tongue n ends ({varied}_high, Thm 3.1)")
        ax.legend(loc="best", fontsize="x-small", framealpha=0.85)

    fixed_name = "e" if varied == "u" else "u"
    a = ds.attrs
    ax.set_xlabel(_LONG_NAMES[varied])
    ax.set_ylabel(_LONG_NAMES[component])
    first, last = int(ds["iterate"].values[0]), int(ds["iterate"].values[-1])
    ax.set_title(f"orbit diagram, {fixed_name} = {float(a[fixed_name]):g}, "
                 f"iterates {first}..{last} from ({float(a['y0']):g}, {float(a['v0']):g})"
                 + (", warm start" if int(a.get("warm_start", 0)) else ""), fontsize="medium")
    return ax
