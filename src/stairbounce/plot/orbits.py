"""Orbit (bifurcation) diagrams: the paper's Figs. 8 and 9."""

from __future__ import annotations

import math

import numpy as np

from .. import _validate as _v
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


def density_cmap():
    """inferno_r without its palest quarter: the rarest visits (one iterate
    in a cell) are orange, not pale yellow lost on the white background."""
    import matplotlib.colors as mcolors
    from matplotlib import colormaps

    base = colormaps["inferno_r"]
    return mcolors.ListedColormap(base(np.linspace(0.25, 1.0, 256)), name="inferno_r_no_pale")


def plot_orbit_diagram(ds, component="y", density=True, ax=None, overlay=(), bins=400,
                       range=None, cmap=None, colorbar=True, vmax=None, legend="best",
                       offset=0.0, unit=1.0, label=None):
    """plot_orbit_diagram(ds, component="y", density=True, ax=None, overlay=(), bins=400, range=None, cmap=None, colorbar=True, vmax=None, legend="best", offset=0.0, unit=1.0, label=None) -> Axes

    Draw an orbit (bifurcation) diagram from :func:`stairbounce.orbit_diagram`.

    By default the kept iterates are binned by
    :func:`stairbounce.orbits.orbit_density` (one column per parameter value,
    ``bins`` rows) and shown as an image with a logarithmic colour scale
    (empty cells white, a single iterate orange); ``density=False`` draws
    every point instead, as the paper's Figs. 8 and 9 do.
    ``overlay=("tongues",)`` draws the boundaries of the sliding tongues of
    Theorem 3.1 as vertical lines: ``u_low = sqrt((n-1)/2)`` dashed and
    ``u_high = sqrt(n/2)(1-e)/(1+e)`` dotted when ``u`` is swept (each tongue
    numbered once, at its middle), ``e_high = (sqrt(n/2)-u)/(sqrt(n/2)+u)``
    when ``e`` is.  The component is drawn as ``(value - offset) / unit`` (a
    zoom far below the unit reads without matplotlib's offset notation).

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
        Range of the component shown, in the component's own units (a
        zoom); None: the data with a margin.
    cmap : colour map or None, default :func:`density_cmap`
    colorbar : bool, default True
    vmax : float or None, default None
        Top of the colour scale (None: the densest cell); give the same
        value to panels that share one colour bar.
    legend : matplotlib location, ``"outside"`` (above the axes) or None, default "best"
    offset, unit : float, default 0.0 and 1.0
        The vertical axis shows ``(value - offset) / unit``.
    label : str or None
        Vertical axis label (default the component's name).

    Returns ``ax``; the density image is ``ax.get_images()[0]``.
    """
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm

    varied = _varied(ds)
    if component not in ("y", "v"):
        raise ValueError(f"component must be 'y' or 'v', got {component!r}")
    overlay = (overlay,) if isinstance(overlay, str) else tuple(overlay)
    _v.among("overlay", overlay, _OVERLAYS)
    if not (math.isfinite(unit) and unit > 0):
        raise ValueError(f"unit must be a finite number > 0, got {unit!r}")
    if ax is None:
        _, ax = plt.subplots(figsize=(9, 5.5))
    cmap = density_cmap() if cmap is None else cmap

    params = np.asarray(ds[varied].values, dtype=float)
    values = (np.asarray(ds[component].values, dtype=float) - offset) / unit
    shown = None if range is None else ((range[0] - offset) / unit, (range[1] - offset) / unit)
    if density:
        if shown is None:
            # a margin keeps the branch y = 1 (the state after sliding) off the frame
            finite = values[np.isfinite(values)]
            lo, hi = (finite.min(), finite.max()) if finite.size else (0.0, 1.0)
            pad = 0.03 * (hi - lo) if hi > lo else 0.5
            shown = (lo - pad, hi + pad)
        scaled = ds.copy()
        scaled[component] = (ds[component].dims, values)
        d = orbit_density(scaled, bins=bins, component=component, range=shown)
        counts = d.values.T.astype(float)
        counts[counts == 0] = np.nan  # empty cells stay white
        (p0, p1), (c0, c1) = d.attrs["param_range"], d.attrs["range"]
        if vmax is None:
            vmax = np.nanmax(counts) if np.isfinite(counts).any() else 1.0
        # antialiased in colour space: thin branches survive when there are
        # more parameter values than pixel columns
        im = ax.imshow(counts, origin="lower", aspect="auto", extent=(p0, p1, c0, c1),
                       interpolation="antialiased", interpolation_stage="rgba", cmap=cmap,
                       norm=LogNorm(vmin=1, vmax=max(vmax, 1.0)))
        if colorbar:
            cb = ax.figure.colorbar(im, ax=ax, pad=0.01)
            cb.set_label("iterates per cell")
    else:
        ps = np.broadcast_to(params[:, None], values.shape)
        ax.plot(ps.ravel(), values.ravel(), ",", color="k", alpha=0.6, rasterized=True)
        if params.min() < params.max():
            ax.set_xlim(params.min(), params.max())
        if shown is not None:
            ax.set_ylim(*shown)

    if "tongues" in overlay:
        _draw_tongue_lines(ax, ds, varied, legend)

    fixed_name = "e" if varied == "u" else "u"
    a = ds.attrs
    ax.set_xlabel(_LONG_NAMES[varied])
    ax.set_ylabel(label if label is not None else _LONG_NAMES[component])
    # never "1e-5+1" above the axis: the offset is in the label instead
    ax.ticklabel_format(axis="y", useOffset=False)
    first, last = int(ds["iterate"].values[0]), int(ds["iterate"].values[-1])
    ax.set_title(f"orbit diagram, {fixed_name} = {float(a[fixed_name]):g}, "
                 f"iterates {first}..{last} from ({float(a['y0']):g}, {float(a['v0']):g})"
                 + (", warm start" if int(a.get("warm_start", 0)) else ""), fontsize="medium")
    return ax


def _draw_tongue_lines(ax, ds, varied, legend):
    """The tongue boundaries inside the view, each tongue numbered once at
    the middle of its visible part, and a legend of what is drawn only."""
    import matplotlib.pyplot as plt

    lo, hi = sorted(ax.get_xlim())
    fixed = float(ds.attrs["e" if varied == "u" else "u"])
    lines = _tongue_lines(varied, fixed, lo, hi)
    kinds = set()
    for pos, n, kind in lines:
        low = kind == "low"
        kinds.add(kind)
        ax.axvline(pos, color="C0" if low else "C2", lw=0.8, ls="--" if low else ":", zorder=3)
    if varied == "u":
        # the n-th tongue at this e is (u_low, u_high]: its number sits in its middle
        n = 1
        while math.sqrt((n - 1) / 2.0) < hi:
            u_low, u_high = tongue(n, fixed)
            a, b = max(u_low, lo), min(u_high, hi)
            if u_high > u_low and b - a > 0.04 * (hi - lo):
                ax.annotate(f"n={n}", (0.5 * (a + b), 1.0), xycoords=("data", "axes fraction"),
                            xytext=(0, -3), textcoords="offset points", ha="center", va="top",
                            fontsize="x-small", color="C0")
            n += 1
    handles = []
    if "low" in kinds:
        handles.append(plt.Line2D([], [], color="C0", lw=0.8, ls="--",
                                  label=r"tongue $n$ begins: $u = \sqrt{(n-1)/2}$"))
    if "high" in kinds:
        text = (r"tongue $n$ ends: $u = \sqrt{n/2}\,(1-e)/(1+e)$" if varied == "u"
                else r"tongue $n$ ends: $e = (\sqrt{n/2}-u)/(\sqrt{n/2}+u)$")
        handles.append(plt.Line2D([], [], color="C2", lw=0.8, ls=":", label=text))
    if not handles or legend is None:
        return
    if legend == "outside":
        ax.legend(handles=handles, loc="lower center", bbox_to_anchor=(0.5, 1.07), ncol=2,
                  fontsize="x-small", frameon=False)
    else:
        ax.legend(handles=handles, loc=legend, fontsize="x-small", framealpha=0.85)


def plot_bifurcations(points, ax=None, height=0.05, legend="lower right"):
    """plot_bifurcations(points, ax=None, height=0.05, legend="lower right") -> Axes

    Mark the bifurcations of :func:`stairbounce.bifurcations` on an orbit
    diagram: a short tick at the bottom of the axes at each parameter value
    (``height`` in axes fraction), coloured by kind (graze, edge, chatter;
    the colours of :func:`plot_borders`), with a legend of the counts.
    """
    import matplotlib.pyplot as plt

    from .borders import KIND_COLORS

    if not hasattr(points, "data_vars") or "kind" not in points or "value" not in points:
        raise ValueError("points must be a Dataset from stairbounce.bifurcations")
    if ax is None:
        _, ax = plt.subplots(figsize=(10, 5.5))
    kind = points["kind"].values
    value = points["value"].values
    trans = ax.get_xaxis_transform()
    lo, hi = sorted(ax.get_xlim())
    for k, color in KIND_COLORS.items():
        x = value[(kind == k) & (value >= lo) & (value <= hi)]
        if x.size:
            ax.vlines(x, 0.0, height, transform=trans, colors=color, lw=0.7, zorder=4,
                      label=f"{k} bifurcation ({x.size})")
    if legend is not None and value.size:
        handles = [h for h in ax.get_legend_handles_labels()[0]]
        labels = ax.get_legend_handles_labels()[1]
        picked = [(h, lab) for h, lab in zip(handles, labels) if "bifurcation" in lab]
        if picked:
            from matplotlib.legend import Legend

            ax.add_artist(Legend(ax, [h for h, _ in picked], [lab for _, lab in picked],
                                 loc=legend, fontsize="x-small", title="exact, located to rounding",
                                 title_fontsize="x-small"))
    return ax
