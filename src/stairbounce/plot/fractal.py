"""The paper's Figures 6 and 7: a border image beside its box-counting plot."""

from __future__ import annotations

import numpy as np


def plot_box_counts(result, ax=None):
    """Draw ``log N(s)`` against ``log(1/s)`` of a box-dimension result.

    Every measured size is a marker (hollow when it was not fitted, grey when
    it has a single box); the fitted line spans the fit range, which is shaded.
    The title gives D, its interval covering the drift of the local slope
    (95% statistical and drift half-widths apart) and r.  Axes are in
    natural logarithms with the box side in pixels on a secondary top axis.

    Parameters
    ----------
    result : :class:`stairbounce.dimension.BoxDimension`
    ax : matplotlib Axes or None
    """
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(5, 4.5))
    sizes = np.asarray(result.sizes, dtype=float)
    counts = np.asarray(result.counts, dtype=float)
    keep = counts > 0
    x = np.log(1.0 / sizes[keep])
    y = np.log(counts[keep])
    fitted = result.fitted[keep]
    usable = result.usable[keep]
    ax.plot(x[fitted], y[fitted], "o", color="C0", label="fitted sizes", zorder=3)
    rest = usable & ~fitted
    if rest.any():
        ax.plot(x[rest], y[rest], "o", mfc="none", color="C0", label="not fitted", zorder=3)
    if (~usable).any():
        ax.plot(x[~usable], y[~usable], "o", mfc="none", color="0.6", label="one box", zorder=3)
    lo, hi = np.log(1.0 / result.fit_range[1]), np.log(1.0 / result.fit_range[0])
    ax.axvspan(lo, hi, color="C0", alpha=0.08, lw=0, label="fit range")
    xs = np.array([x.min(), x.max()])
    ax.plot(xs, result.fit.intercept + result.fit.slope * xs, "-", color="C3", lw=1.2,
            label=f"slope {result.dimension:.3f}", zorder=2)
    ax.set_xlabel("log(1/s)   (s: box side in pixels)")
    ax.set_ylabel("log N(s)")
    iv = result.interval
    ax.set_title(f"D = {result.dimension:.3f}  [{iv[0]:.3f}, {iv[1]:.3f}]\n(95% +-{result.statistical:.3f}, "
                 f"drift +-{result.systematic:.3f})  r = {result.r:.4f}", fontsize="medium")
    top = ax.secondary_xaxis(
        "top", functions=(lambda v: np.exp(-v), lambda s: -np.log(np.maximum(s, 1e-300)))
    )
    top.set_xticks(sizes)
    top.set_xticklabels([f"{int(s)}" for s in sizes], fontsize="x-small")
    top.set_xlabel("s (px)", fontsize="small")
    ax.legend(loc="lower right", fontsize="small")
    ax.grid(True, alpha=0.3)
    return ax


def _pool_any(img, f):
    """``f x f`` blocks -> one pixel, set when any pixel of the block is set
    (the edge blocks padded with unset pixels)."""
    if f <= 1:
        return img
    h, w = img.shape
    H, W = -(-h // f) * f, -(-w // f) * f
    padded = np.zeros((H, W), dtype=bool)
    padded[:h, :w] = img
    return padded.reshape(H // f, f, W // f, f).any(axis=(1, 3))


def plot_border(border, e=None, u=None, ax=None, title=None):
    """plot_border(border, e=None, u=None, ax=None, title=None) -> Axes

    Draw a border image (black on white), rows upwards, with square pixels:
    a square window is drawn square.

    With ``e = (e_min, e_max)`` and ``u = (u_min, u_max)`` the axes are the
    parameter plane (e across, u up, as in Figs. 6 and 7); without, pixels.
    When the image has more pixels than the axes have on the figure (at the
    figure's dpi, which should be the dpi it is saved at), it is first
    reduced by ``f x f`` blocks, a block black when any of its pixels is:
    a one-pixel border then stays a connected line instead of aliasing into
    dotted fragments, as resampling would make it.
    """
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(5, 5))
    img = np.asarray(border, dtype=bool)
    if e is not None and u is not None:
        extent = (e[0], e[1], u[0], u[1])
        ax.set_xlabel("e (restitution coefficient)")
        ax.set_ylabel("u (horizontal speed)")
    else:
        extent = (0, img.shape[1], 0, img.shape[0])
        ax.set_xlabel("pixels")
    # square pixels: one pixel's height on screen equals its width
    aspect = ((extent[1] - extent[0]) / img.shape[1]) / ((extent[3] - extent[2]) / img.shape[0])
    ax.set_aspect(aspect, adjustable="box")
    ax.apply_aspect()
    box = ax.get_window_extent()
    f = int(np.ceil(max(img.shape[0] / max(box.height, 1.0), img.shape[1] / max(box.width, 1.0))))
    shown = _pool_any(img, f)
    if f > 1:  # the padded blocks reach past the window: extend the image to match
        extent = (extent[0], extent[0] + (extent[1] - extent[0]) * shown.shape[1] * f / img.shape[1],
                  extent[2], extent[2] + (extent[3] - extent[2]) * shown.shape[0] * f / img.shape[0])
    ax.imshow(shown, cmap="gray_r", origin="lower", extent=extent, aspect=aspect,
              interpolation="nearest", vmin=0, vmax=1)
    ax.set_xlim(extent[0], e[1] if e is not None and u is not None else img.shape[1])
    ax.set_ylim(extent[2], u[1] if e is not None and u is not None else img.shape[0])
    if title:
        ax.set_title(title, fontsize="medium")
    return ax


def plot_box_dimension(result, image=None, axes=None, title=None):
    """Draw the paper's Figures 6/7: the border image beside the box-counting plot.

    Parameters
    ----------
    result : :class:`~stairbounce.dimension.BoxDimension` or
        :class:`~stairbounce.dimension.PerimeterDimension`
        A perimeter result carries its border image and window; for a plain
        box-dimension result pass the measured ``image``.
    image : 2-D array or None
    axes : (ax_image, ax_plot) or (ax_image, ax_plot, ax_local) or None
        None: a new figure of three panels, the third the local slope
        against box size (:func:`plot_local_dimension`).
    title : str or None
        Figure title; default names the window, resolution and max_iter of a
        perimeter result.

    Returns the figure.
    """
    import matplotlib.pyplot as plt

    if axes is None:
        fig, axes = plt.subplots(1, 3, figsize=(16, 5), gridspec_kw={"width_ratios": [1, 1.1, 1.1]})
    else:
        fig = axes[0].figure
    border = image if image is not None else getattr(result, "border", None)
    if border is None:
        raise ValueError("image is needed to draw a box-dimension result that has no border image")
    e = getattr(result, "e", None)
    u = getattr(result, "u", None)
    panel = None
    if getattr(result, "border", None) is not None and image is None:
        what = "sliding region" if result.which == "sliding" else "word-length regions"
        panel = f"border of the {what}, {result.resolution} x {result.resolution} px"
    plot_border(border, e, u, ax=axes[0], title=panel)
    plot_box_counts(result, ax=axes[1])
    if len(axes) > 2:
        plot_local_dimension(result, ax=axes[2], label="local slope between box sizes")
    if title is None and e is not None and getattr(result, "border", None) is not None:
        title = (f"perimeter of the periodic sliding region in [{e[0]:g}, {e[1]:g}] x "
                 f"[{u[0]:g}, {u[1]:g}]  (max_iter = {result.max_iter}, boxes of "
                 f"{result.fit_range[0]}..{result.fit_range[1]} px fitted)")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def plot_uncertainty(result, axes=None, title=None):
    """Draw an uncertainty-exponent result: ``f(eps)`` on log-log axes with
    the fitted power law, and the local dimensions ``2 - d log f / d log eps``.

    Parameters
    ----------
    result : :class:`stairbounce.dimension.UncertaintyDimension`
    axes : (ax_fraction, ax_local) or None
        None: a new figure of two panels.
    title : str or None

    Returns the figure.
    """
    import matplotlib.pyplot as plt

    if axes is None:
        fig, axes = plt.subplots(1, 2, figsize=(11, 4.6))
    else:
        fig = axes[0].figure
    ax, ax2 = axes
    ok = result.uncertain > 0
    fitted = result.fitted
    ax.loglog(result.eps[ok & fitted], result.fraction[ok & fitted], "o", color="C0", label="fitted eps")
    rest = ok & ~fitted
    if rest.any():
        ax.loglog(result.eps[rest], result.fraction[rest], "o", mfc="none", color="C0", label="not fitted")
    lo, hi = result.fit_range
    xs = np.array([lo, hi])
    ax.loglog(xs, np.exp(result.fit.intercept) * xs ** result.alpha, "-", color="C3",
              label=f"f ~ eps^{result.alpha:.3f}")
    ax.set_xlabel("eps (fraction of the window)")
    ax.set_ylabel("uncertain fraction f(eps)")
    iv = result.interval
    ax.set_title(f"D = 2 - alpha = {result.dimension:.3f}  [{iv[0]:.3f}, {iv[1]:.3f}] "
                 f"(95% +-{result.statistical:.3f}, drift +-{result.systematic:.3f})", fontsize="medium")
    ax.legend(loc="lower right", fontsize="small")
    ax.grid(True, which="both", alpha=0.3)
    plot_local_dimension(result, ax=ax2, label="local 2 - dlog f/dlog eps")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def plot_local_dimension(result, ax=None, compare=(), label="local dimension", title=None):
    """plot_local_dimension(result, ax=None, compare=(), label="local dimension", title=None) -> Axes

    The scale-resolved view of a dimension estimate, its primary output: the
    local dimension against scale (with its 95% band where the estimator
    has a noise model), the fitted ``D`` over the fitted scales, its
    statistical 95% interval (dark) and the interval that also covers the
    drift of the local slope (light).

    Parameters
    ----------
    result : a dimension estimate (``BoxDimension``, ``UncertaintyDimension``
        or ``SlicingDimension``): anything with ``local_band()``,
        ``dimension``, ``ci``, ``interval`` and ``scales``.
    compare : sequence of (estimate, label)
        Further estimates whose local dimensions are drawn on the same axes
        (for instance the same measurement at a larger ``max_iter``).
    """
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(6, 4.5))
    for k, (res, name) in enumerate([(result, label), *compare]):
        mid, dl, half = res.local_band()
        colour = f"C{k}"
        ax.plot(mid, dl, "o-", color=colour, ms=4, label=name)
        if np.isfinite(half).any():
            ax.fill_between(mid, dl - half, dl + half, color=colour, alpha=0.15, lw=0)
    lo, hi = result.scales
    ci, iv = result.ci, result.interval
    ax.fill_between([lo, hi], iv[0], iv[1], color="C3", alpha=0.1, lw=0,
                    label=f"interval with drift [{iv[0]:.3f}, {iv[1]:.3f}]")
    ax.fill_between([lo, hi], ci[0], ci[1], color="C3", alpha=0.25, lw=0,
                    label=f"95% statistical [{ci[0]:.3f}, {ci[1]:.3f}]")
    ax.plot([lo, hi], [result.dimension] * 2, "-", color="C3", lw=1.2,
            label=f"D = {result.dimension:.3f} over the fitted scales")
    ax.set_xscale("log")
    unit = getattr(result, "scale_unit", "")
    ax.set_xlabel(f"scale ({unit})" if unit else "scale")
    ax.set_ylabel("local dimension")
    mi = getattr(result, "max_iter", None)
    ax.set_title(title or ("local dimension against scale" + (f", max_iter {mi}" if mi else "")),
                 fontsize="medium")
    ax.legend(loc="best", fontsize="x-small")
    ax.grid(True, which="both", alpha=0.3)
    return ax
