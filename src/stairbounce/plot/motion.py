"""The non-sliding motion over the (e, u) plane: <k> and lambda_1 from a
:func:`stairbounce.nonsliding.motion_scan` dataset (issue 13)."""

from __future__ import annotations

import numpy as np

from . import _units
from .. import _validate as _v

__all__ = ["plot_motion", "plot_motion_cut", "MOTION_PLOT_FIELDS"]

MOTION_PLOT_FIELDS = {
    "k_mean": "<k>, impacts per step",
    "speed_spread": "Var|v_-| / <|v_-|>^2",
    "lyap1": "lambda_1 (per step)",
    "jump_mean": "mean jump (steps per landing)",
}
OVERLAYS = ("families", "bound")


def _greys():
    """Fig. 4's word lengths in greys (dark: short words), kept clear of the
    black and white ends so that the colour maps of the motion stay apart."""
    import matplotlib.colors as mcolors
    from matplotlib import colormaps

    return mcolors.ListedColormap(colormaps["Greys_r"](np.linspace(0.2, 0.8, 256)), name="greys_mid")


def _families(ax, e_lo, e_hi, u_lo, u_hi, color):
    """One-impact-per-n-steps curves u_n(e) crossing the view (labels at their right end)."""
    from ..nonsliding import one_impact_family

    e = np.linspace(max(e_lo, 1e-6), min(e_hi, 1 - 1e-6), 600)
    n_top = int(np.ceil(2.0 * u_hi**2 * (1 + e[0]) / (1 - e[0]))) + 1
    first = True
    for n in range(1, min(n_top, 60) + 1):
        u = one_impact_family(n, e)
        inside = (u >= u_lo) & (u <= u_hi)
        if not inside.any():
            continue
        ax.plot(e[inside], u[inside], color=color, lw=0.8, ls=":",
                label="one impact every n steps, <k> = 1/n" if first else None)
        if n <= 6:
            j = np.flatnonzero(inside)[0]
            ax.annotate(f"n={n}", (e[j], u[j]), fontsize=7, color=color,
                        xytext=(3, -9), textcoords="offset points")
        first = False


UNCONVERGED_COLOUR = "#d6249f"


def plot_motion(ds, field="k_mean", ax=None, sliding=None, overlay=OVERLAYS, colorbar=True, title=None,
                unconverged=None):
    """plot_motion(ds, field="k_mean", ax=None, sliding=None, overlay=("families", "bound"), colorbar=True, title=None, unconverged=None) -> Axes

    Draw a motion scan: non-sliding pixels coloured by ``field``.

    ``k_mean`` and ``jump_mean`` on a log scale (viridis, clipped at the
    99.5th percentile), ``lambda_1`` on a diverging scale symmetric about 0
    (RdBu_r).  Pixels whose orbit slides are drawn as in the paper's Fig. 4:
    coloured by the word length of ``sliding`` (a :func:`stairbounce.plane.scan`
    dataset of the same grid) in greys, or plain grey without it.

    Parameters
    ----------
    ds : xarray.Dataset from :func:`stairbounce.nonsliding.motion_scan`.
    field : "k_mean", "lyap1" or "jump_mean".
    sliding : optional scan dataset of the same grid (word lengths).
    overlay : among "families" (:func:`stairbounce.nonsliding.one_impact_family`)
        and "bound" (Corollary 2.1).
    unconverged : optional boolean array of the grid's shape (u, e)
        Pixels whose value has not converged (still transient): drawn in one
        distinct colour (magenta) with a legend entry, not by their value.
    """
    import matplotlib.colors as mcolors
    import matplotlib.pyplot as plt
    from matplotlib import colormaps

    if field not in MOTION_PLOT_FIELDS:
        raise ValueError(f"field must be one of {', '.join(MOTION_PLOT_FIELDS)}, got {field!r}")
    _v.among("overlay", overlay, OVERLAYS)
    from .plane import _extent

    if ax is None:
        _, ax = plt.subplots(figsize=(8, 6))
    e_lo, e_hi, u_lo, u_hi = _extent(ds)
    ext = (e_lo, e_hi, u_lo, u_hi)
    slides = np.asarray(ds["slide_step"].values) > 0
    # sliding pixels first, as in Fig. 4 (greys by word length)
    if sliding is not None and "word_length" in sliding:
        wl = np.asarray(sliding["word_length"].values, dtype=float)
        wl = np.ma.masked_array(wl, mask=~slides | (wl <= 0))
        top = float(np.percentile(wl.compressed(), 99.5)) if wl.count() else 2.0
        ax.imshow(wl, origin="lower", extent=ext, aspect="auto", interpolation="nearest",
                  cmap=_greys().with_extremes(bad=(0, 0, 0, 0)),
                  norm=mcolors.LogNorm(vmin=1.0, vmax=max(top, 2.0)))
    else:
        ax.imshow(np.ma.masked_array(np.ones(slides.shape), mask=~slides), origin="lower",
                  extent=ext, aspect="auto", interpolation="nearest",
                  cmap=mcolors.ListedColormap(["0.55"]).with_extremes(bad=(0, 0, 0, 0)))
    if field == "speed_spread":
        from ..nonsliding import speed_spread

        raw = speed_spread(ds.k_mean.values, ds.impulse.values, ds.dissipation.values,
                           ds.e.values[None, :])
        raw = np.maximum(raw, 1e-6)  # 0 on the families (to rounding): the bottom colour
    else:
        raw = np.asarray(ds[field].values, dtype=float)
    hide = slides
    if unconverged is not None:
        unconverged = np.asarray(unconverged, dtype=bool)
        if unconverged.shape != slides.shape:
            raise ValueError(f"unconverged must have the grid's shape {slides.shape}, got {unconverged.shape}")
        unconverged = unconverged & ~slides
        hide = slides | unconverged
    data = np.ma.masked_invalid(np.where(hide, np.nan, raw))
    vals = data.compressed()
    if field == "speed_spread":
        # >= 0, and 0 on the one-impact families: log scale from 1e-4
        top = float(np.percentile(vals, 99.0)) if vals.size else 1.0
        norm = mcolors.LogNorm(vmin=1e-4, vmax=max(top, 1e-2))
        cm = colormaps["plasma"]
        extend = "both"
    elif field == "lyap1":
        m = float(np.max(np.abs(vals))) if vals.size else 1.0
        norm = mcolors.Normalize(-m, m)
        cm = colormaps["RdBu_r"]
        extend = "neither"
    else:
        pos = vals[vals > 0]
        lo = float(pos.min()) if pos.size else 1e-3
        top = float(np.percentile(pos, 99.5)) if pos.size else 1.0
        norm = mcolors.LogNorm(vmin=lo, vmax=max(top, lo * 2))
        cm = colormaps["viridis"]
        extend = "max" if pos.size and pos.max() > top else "neither"
    im = ax.imshow(data, origin="lower", extent=ext, aspect="auto", interpolation="nearest",
                   cmap=cm.with_extremes(bad=(0, 0, 0, 0)), norm=norm)
    if unconverged is not None and unconverged.any():
        import matplotlib.patches as mpatches

        ax.imshow(np.ma.masked_array(np.ones(slides.shape), mask=~unconverged), origin="lower",
                  extent=ext, aspect="auto", interpolation="nearest",
                  cmap=mcolors.ListedColormap([UNCONVERGED_COLOUR]).with_extremes(bad=(0, 0, 0, 0)))
        ax.add_patch(mpatches.Rectangle((e_lo, u_lo), 0, 0, color=UNCONVERGED_COLOUR,
                                        label=f"unconverged (still transient): "
                                              f"{100 * unconverged.mean():.1f}% of pixels"))
    if "families" in overlay:
        _families(ax, e_lo, e_hi, u_lo, u_hi, "black" if field == "lyap1" else "white")
    if "bound" in overlay:
        e = np.linspace(max(e_lo, 1e-6), e_hi, 600)
        ax.plot(e, (1.0 - e) / (2.0 * np.sqrt(2.0 * e)), color="#e8590c", lw=1.4, ls="--",
                label="Corollary 2.1: no sliding above")
    _units.frame_plane(ax, ds, e_lo, e_hi, u_lo, u_hi)
    if title is None:
        what = {"speed_spread": "spread of the impact speeds = <k>/(its Cauchy-Schwarz bound) - 1",
                "lyap1": "lambda_1 (per step): O(1/N) everywhere, lambda_1 = 0"}.get(
            field, MOTION_PLOT_FIELDS[field])
        title = (f"{what}; {ds.attrs.get('transient', '?')} + "
                 f"{ds.attrs.get('steps', '?')} steps from (1, 0)")
    ax.set_title(title, fontsize="medium")
    if colorbar:
        cb = ax.figure.colorbar(im, ax=ax, extend=extend)
        cb.set_label(MOTION_PLOT_FIELDS[field] + " (greys: the orbit slides, as Fig. 4)")
    if overlay or (unconverged is not None and unconverged.any()):
        ax.legend(loc="upper right", fontsize="small", framealpha=0.8)
    return ax


def plot_motion_cut(ds, axes=None, families=True):
    """plot_motion_cut(ds, axes=None, families=True) -> (Axes, Axes, Axes)

    A cut of a motion scan at one ``u``: <k> against e (top), the spread of
    the impact speeds (:func:`stairbounce.nonsliding.speed_spread`, middle) and
    ``N lambda_1`` (bottom; bounded for lambda_1 = 0), sliding pixels left out.
    With ``families`` the points (e_n, 1/n) where the one-impact families
    cross the cut are marked.
    """
    import matplotlib.pyplot as plt

    if ds.sizes["u"] != 1:
        raise ValueError(f"a cut needs a motion scan with one u, got {ds.sizes['u']}")
    from ..nonsliding import speed_spread

    if axes is None:
        _, axes = plt.subplots(3, 1, figsize=(9, 8), sharex=True, height_ratios=(3, 2, 1))
    ax, sx, bx = axes
    u = float(ds.u.values[0])
    e = ds.e.values
    k = ds.k_mean.values[0]
    ok = ds.slide_step.values[0] == 0
    ax.plot(e[ok], k[ok], ",", color="#1f4e79", ms=1, rasterized=True)
    ax.plot(e[ok], k[ok], ".", color="#1f4e79", ms=1.2, alpha=0.5, rasterized=True)
    if families:
        n = np.arange(1, 41)
        en = (n - 2 * u * u) / (n + 2 * u * u)  # u_n(e_n) = u
        keep = (en > e.min()) & (en < e.max())
        ax.plot(en[keep], 1.0 / n[keep], "o", mfc="none", color="#e8590c", ms=5,
                label="one impact every n steps: (e_n, 1/n)")
        ax.legend(loc="upper left", fontsize="small")
    ax.set_yscale("log")
    ax.set_ylabel("<k> (impacts per step)")
    ax.set_title(f"u = {u:g}: {ok.sum()} values of e, {ds.attrs.get('steps')} kept steps each",
                 fontsize="medium")
    sp = speed_spread(k, ds.impulse.values[0], ds.dissipation.values[0], e)
    sx.plot(e[ok], np.maximum(sp[ok], 1e-6), ".", color="#b5540b", ms=1.2, rasterized=True)
    sx.set_yscale("log")
    sx.set_ylabel("Var|v_-| / <|v_-|>^2")
    N = ds.attrs.get("steps", 1)
    bx.plot(e[ok], N * ds.lyap1.values[0][ok], ".", color="#7b2d8b", ms=1.2, rasterized=True)
    bx.axhline(0.0, color="0.3", lw=0.6)
    bx.set_ylabel("N lambda_1")
    bx.set_xlabel("e (restitution coefficient)")
    return ax, sx, bx
