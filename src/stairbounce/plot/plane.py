"""The (e, u) parameter plane (the paper's Figures 3, 4 and 5) from a scan dataset."""

from __future__ import annotations

import numpy as np

__all__ = ["plot_scan", "FIELDS"]

FIELDS = {
    "word_length": "word length",
    "period": "period (steps)",
    "impacts": "finite impacts per period",
    "jumps": "non-zero letters (landings per period)",
    "status": "periodic sliding solution",
}
OVERLAYS = ("tongues", "bound")


def _colormap():
    """inferno without its palest tenth: perceptually uniform, black at the
    bottom (word length 1 is black, as in the paper's Figure 4) and no colour
    that could be mistaken for the white of "no periodic sliding solution"."""
    import matplotlib.colors as mcolors
    from matplotlib import colormaps

    base = colormaps["inferno"]
    cmap = mcolors.ListedColormap(base(np.linspace(0.0, 0.88, 256)), name="inferno_no_white")
    return cmap.with_extremes(bad="white")


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


def _draw_tongues(ax, e_lo, e_hi, u_lo, u_hi, color):
    """Boundaries of the (n, 0^inf) tongues of Theorem 3.1 crossing the view."""
    e = np.linspace(e_lo, e_hi, 600)
    n_top = int(2.0 * u_hi**2) + 2
    first = True
    for n in range(1, n_top + 1):
        # Theorem 3.1, as stairbounce.tongue(n, e) evaluates it, vectorised
        lows = np.full_like(e, np.sqrt((n - 1) / 2.0))
        highs = np.sqrt(n / 2.0) * (1.0 - e) / (1.0 + e)
        inside = highs > lows  # the tongue is open at these e
        if not inside.any():
            continue
        kw = dict(color=color, lw=0.9, ls="-")
        ax.plot(e[inside], highs[inside], label="Theorem 3.1 tongues" if first else None, **kw)
        if n > 1:
            ax.plot(e[inside], lows[inside], **kw)
        first = False


def plot_scan(ds, field="word_length", ax=None, overlay=(), cmap=None, colorbar=True, title=None):
    """plot_scan(ds, field="word_length", ax=None, overlay=(), cmap=None, colorbar=True, title=None) -> Axes

    Draw a scan of the (e, u) plane: the paper's Figure 4 and its blow-ups.

    Each pixel of ``ds`` (from :func:`stairbounce.plane.scan`) is coloured by
    ``field`` on a perceptually uniform colour map, on a log scale for word
    length, period and jumps (impacts: symmetric log, it is 0 in the
    tongues), clipped at the 99.5th percentile; white where there is no
    periodic sliding solution (``status == 1``).  ``field="status"`` draws the sliding set in black.

    Parameters
    ----------
    ds : xarray.Dataset with dims ("u", "e") and the variables of a scan.
    field : one of "word_length", "period", "impacts", "jumps", "status".
    ax : matplotlib Axes, default a new figure.
    overlay : iterable of "tongues" (boundaries of the (n, 0^inf) tongues,
        Theorem 3.1) and "bound" (the no-sliding bound of Corollary 2.1).
    cmap : colour map, default inferno without its palest tenth.
    colorbar : draw a colour bar (a legend for ``status``).
    title : default names the window and max_iter.

    The extent is the scan's window: axes labelled e and u, origin lower left.
    """
    import matplotlib.colors as mcolors
    import matplotlib.pyplot as plt

    if field not in FIELDS:
        raise ValueError(f"field must be one of {', '.join(FIELDS)}, got {field!r}")
    overlay = tuple(overlay)
    for o in overlay:
        if o not in OVERLAYS:
            raise ValueError(f"overlay must be among {', '.join(OVERLAYS)}, got {o!r}")
    if ax is None:
        _, ax = plt.subplots(figsize=(8, 6))
    e_lo, e_hi, u_lo, u_hi = _extent(ds)
    none = _no_solution(ds, field)
    if field == "status":
        data = np.ma.masked_array(np.ones(none.shape), mask=none)
        cm = mcolors.ListedColormap(["black"]).with_extremes(bad="white")
        norm = mcolors.Normalize(0, 1)
    else:
        data = np.ma.masked_array(np.asarray(ds[field].values, dtype=float), mask=none)
        cm = cmap if cmap is not None else _colormap()
        if isinstance(cm, str):
            from matplotlib import colormaps

            cm = colormaps[cm]
        cm = cm.with_extremes(bad="white")
        # the longest words are rare: clip the colour scale at the 99.5th
        # percentile (the colour bar shows the clipping) so the bulk gets colours
        found = data.compressed()
        top = float(np.percentile(found, 99.5)) if found.size else 1.0
        extend = "max" if found.size and found.max() > top else "neither"
        if field == "impacts":
            norm = mcolors.SymLogNorm(linthresh=1.0, vmin=0.0, vmax=max(top, 1.0), base=10)
        else:
            norm = mcolors.LogNorm(vmin=1.0, vmax=max(top, 2.0))
    im = ax.imshow(
        data, origin="lower", extent=(e_lo, e_hi, u_lo, u_hi), aspect="auto",
        interpolation="nearest", cmap=cm, norm=norm,
    )
    if "tongues" in overlay:
        _draw_tongues(ax, e_lo, e_hi, u_lo, u_hi, "#22c8e5")
    if "bound" in overlay:
        e = np.linspace(max(e_lo, 1e-6), e_hi, 600)
        ax.plot(e, (1.0 - e) / (2.0 * np.sqrt(2.0 * e)), color="#2a9d3a", lw=1.4, ls="--",
                label="Corollary 2.1: no sliding above")
    ax.set_xlim(e_lo, e_hi)
    ax.set_ylim(u_lo, u_hi)
    ax.set_xlabel("e (restitution coefficient)")
    ax.set_ylabel("u (horizontal speed)")
    if title is None:
        mi = ds.attrs.get("max_iter")
        title = f"e in [{e_lo:g}, {e_hi:g}], u in [{u_lo:g}, {u_hi:g}]" + (
            f", max_iter {mi}" if mi is not None else ""
        )
    ax.set_title(title)
    if colorbar:
        if field == "status":
            from matplotlib.patches import Patch

            handles = [Patch(color="black", label="periodic sliding solution"),
                       Patch(facecolor="white", edgecolor="0.5", label="none within max_iter")]
            handles += ax.get_legend_handles_labels()[0]
            ax.legend(handles=handles, loc="upper right", fontsize="small")
        else:
            cb = ax.figure.colorbar(im, ax=ax, extend=extend)
            cb.set_label(FIELDS[field] + " (white: no periodic sliding solution)")
            if overlay:
                ax.legend(loc="upper right", fontsize="small")
    elif overlay:
        ax.legend(loc="upper right", fontsize="small")
    return ax
