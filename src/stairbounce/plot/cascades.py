"""Cascades of words (issue 39): members marked on an orbit diagram (Figs. 8
and 9), and the law of a cascade's widths."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["plot_cascade_members", "plot_cascade_law"]


def _math_pattern(text):
    """A pattern as mathtext: ``$(1^k, 0^{\\infty})$``."""
    return "$" + text.replace("0^inf", r"0^{\infty}") + "$"


def _selected(c, k):
    m = c.members
    if k is not None and len(k):
        m = m[(m.k >= k[0]) & (m.k <= k[1])]
    return m


def plot_cascade_members(cascades, ax=None, heights=None, k=None, first=4, colors=None,
                         legend="upper right", band=True):
    """plot_cascade_members(cascades, ax=None, heights=None, k=None, first=4, colors=None, legend="upper right", band=True) -> Axes

    Mark the members of one or more cascades (:func:`stairbounce.cascade`)
    on an axes whose horizontal axis is the cascade's line (an orbit diagram
    of Figs. 8 and 9): a shaded band over each member's interval ``[lo, hi]``
    (edges located to rounding), a tick ``|`` at its centre on each of its
    branches, and ``k = ...`` under the first ``first`` members that are far
    enough apart to be read; one legend entry per cascade.

    Parameters
    ----------
    cascades : Cascade or sequence of Cascade
    ax : matplotlib Axes or None
    heights : sequence (one per cascade) of {k: array of heights}, or None
        The heights of each member's periodic orbit in the axes' vertical
        units (the branches; computed by the caller: a renderer computes no
        dynamics).  None, or a member missing from the mapping: the tick is
        drawn at the top of the axes.
    k : (k_lo, k_hi), a sequence of them (one per cascade), or None
        The members drawn (all by default).
    first : int or sequence of int (one per cascade), default 4
        How many members get their ``k`` written (under the axes' top
        tongue labels: just above the bottom).
    colors : sequence of matplotlib colours, default C3, C1, C4, ...
    legend : matplotlib location (a name, or the lower left corner in axes fraction) or None, default "upper right"
        Drawn as its own legend, beside any legend the axes already has.
    band : bool, default True
        Shade each member's interval (a member narrower than a pixel shows
        only its ticks).
    """
    import matplotlib.pyplot as plt
    from matplotlib.legend import Legend

    if not isinstance(cascades, (list, tuple)):
        cascades = [cascades]
    for c in cascades:
        if not hasattr(c, "members") or not hasattr(c, "pattern"):
            raise ValueError("cascades must be Cascade objects from stairbounce.cascade")
    if heights is not None and len(heights) != len(cascades):
        raise ValueError(f"heights must give one mapping per cascade ({len(cascades)}), got {len(heights)}")
    if ax is None:
        _, ax = plt.subplots(figsize=(9, 5.5))
    colors = list(colors) if colors is not None else ["C3", "C9", "C8", "C5", "C6"]
    firsts = list(first) if isinstance(first, (list, tuple)) else [first] * len(cascades)
    if len(firsts) != len(cascades):
        raise ValueError(f"first must be one count or one per cascade ({len(cascades)}), got {first!r}")
    xlim, ylim = ax.get_xlim(), ax.get_ylim()  # the marks never move the view
    lo_x, hi_x = sorted(xlim)
    span = hi_x - lo_x
    top = ax.get_xaxis_transform()  # x in data, y in axes fraction
    if k is not None and len(k) and not isinstance(k[0], (int, np.integer)):
        if len(k) != len(cascades):
            raise ValueError(f"k must be one (k_lo, k_hi) or one per cascade ({len(cascades)}), got {k!r}")
        ranges = list(k)
    else:
        ranges = [k] * len(cascades)
    handles = []
    for i, c in enumerate(cascades):
        color = colors[i % len(colors)]
        m = _selected(c, ranges[i])
        m = m[(m.hi >= lo_x) & (m.lo <= hi_x)]
        if not len(m):
            continue
        h = heights[i] if heights is not None else {}
        mids = 0.5 * (m.lo.values + m.hi.values)
        if band:  # one collection for all the bands: the full height of the axes
            ax.broken_barh(list(zip(m.lo.values, m.hi.values - m.lo.values)), (0, 1),
                           transform=top, facecolors=color, alpha=0.13, lw=0, zorder=1)
        # the ticks: one line of markers per cascade, on the branches where known
        on = [(x, y) for x, kk in zip(mids, m.k.values) for y in h.get(int(kk), ())]
        if on:
            xs, ys = zip(*on)
            ax.plot(xs, ys, ls="none", marker="|", ms=9, mew=1.3, color=color, zorder=5)
        off = [x for x, kk in zip(mids, m.k.values) if not len(h.get(int(kk), ()))]
        if off:
            ax.plot(off, [0.97] * len(off), ls="none", marker="|", ms=9, mew=1.3, color=color,
                    transform=top, zorder=5)
        last_label = -math.inf
        labelled = 0
        for kk, mid in zip(m.k.values, mids):
            if labelled < firsts[i] and mid - last_label > 0.04 * span:
                ax.annotate(f"k={kk}", (mid, 0.065), xycoords=("data", "axes fraction"),
                            ha="center", va="bottom", fontsize="x-small", color=color,
                            bbox={"boxstyle": "round,pad=0.1", "fc": "white", "ec": "none",
                                  "alpha": 0.8}, zorder=6)
                last_label = mid
                labelled += 1
        ks = m.k.values
        handles.append(plt.Line2D([], [], ls="none", marker="|", ms=9, mew=1.3, color=color,
                                  label=f"{_math_pattern(c.pattern)}, k = {ks[0]}..{ks[-1]}"
                                        f" ({len(ks)} members, exact)"))
    ax.set_xlim(xlim)
    ax.set_ylim(ylim)
    if legend is not None and handles:
        ax.add_artist(Legend(ax, handles, [h.get_label() for h in handles], loc=legend,
                             fontsize="x-small", framealpha=0.85,
                             title="cascade members (sb.cascade)", title_fontsize="x-small"))
    return ax


def plot_cascade_law(c, ax=None, k=None):
    """plot_cascade_law(c, ax=None, k=None) -> Axes

    The widths of a cascade's members against k on logarithmic axes, with the
    two laws :func:`stairbounce.cascade_law` weighs on the members it used
    (``c.law.ks_used``): algebraic ``w = C k^-gamma`` and geometric
    ``w = C r^k``, each through the geometric mean of those widths, and the
    decision in the title.

    Parameters
    ----------
    c : Cascade
        From :func:`stairbounce.cascade`.
    ax : matplotlib Axes or None
    k : (k_lo, k_hi) or None
        The members drawn (all with a width > 0 by default).
    """
    import matplotlib.pyplot as plt

    if not hasattr(c, "members") or not hasattr(c, "law"):
        raise ValueError("c must be a Cascade from stairbounce.cascade")
    if ax is None:
        _, ax = plt.subplots(figsize=(5, 4))
    m = _selected(c, k)
    m = m[(m.width > 0) & (m.k >= 1) & (m.lo_kind != "range") & (m.hi_kind != "range")]
    ax.loglog(m.k.values, m.width.values, "o", ms=3.5, color="k", label="members (exact widths)")
    law = c.law
    used = m[m.k.isin(law.ks_used)]
    # the straight lines whose residuals decide the law (the fitted slopes, not the asymptotic values)
    if len(used) >= 2 and math.isfinite(law.exponent_fit):
        kk = used.k.values.astype(float)
        lw = np.log(used.width.values)
        grid = np.linspace(kk[0], kk[-1], 50)
        a_alg = np.mean(lw + law.exponent_fit * np.log(kk))
        ax.loglog(grid, np.exp(a_alg - law.exponent_fit * np.log(grid)), "-", color="C3", lw=1.5,
                  label=rf"algebraic: $k^{{-{law.exponent_fit:.3g}}}$ (residual {law.residual_algebraic:.2g})")
        a_geo = np.mean(lw - kk * math.log(law.ratio_fit))
        ax.loglog(grid, np.exp(a_geo + grid * math.log(law.ratio_fit)), "--", color="C0", lw=1.2,
                  label=f"geometric: ${law.ratio_fit:.3g}^k$ (residual {law.residual_geometric:.2g})")
    # plain numbers on the k axis (no 3x10^0 labels crowding the decade)
    from matplotlib.ticker import NullFormatter, ScalarFormatter

    ks = m.k.values
    if len(ks):
        ax.set_xticks([t for t in (1, 2, 3, 5, 10, 20, 50, 100, 200, 500, 1000)
                       if ks.min() <= t <= ks.max()])
    ax.xaxis.set_major_formatter(ScalarFormatter())
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("k")
    ax.set_ylabel(f"width of member k (in {c.axis})")
    span = f"k = {law.ks_used[0]}..{law.ks_used[-1]}" if law.ks_used else "no members"
    ax.set_title(f"{_math_pattern(c.pattern)}: {law.kind} on {span}", fontsize="medium")
    ax.legend(fontsize="x-small", loc="lower left")
    return ax
