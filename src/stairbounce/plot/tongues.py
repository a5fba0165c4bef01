"""The (n, 0^inf) sliding tongues of Theorem 3.1 and the Corollary 2.1 curve
(the paper's Fig. 3), drawn from their formulas."""

from __future__ import annotations

import numpy as np


def tongue_boundaries(n, e):
    """``(u_low, u_high)`` of the n-th tongue on an array of ``e`` (Theorem 3.1),
    ``u_high`` set to NaN where the tongue is empty."""
    e = np.asarray(e, dtype=float)
    lo = np.full_like(e, np.sqrt((n - 1) / 2.0))
    hi = np.sqrt(n / 2.0) * (1.0 - e) / (1.0 + e)
    return lo, np.where(hi > lo, hi, np.nan)


def plot_tongues(n_max=12, e=(0.0, 1.0), u=(0.0, 1.5), ax=None, samples=2000, bound=True):
    """plot_tongues(n_max=12, e=(0.0, 1.0), u=(0.0, 1.5), ax=None, samples=2000, bound=True) -> Axes

    Fill the (n, 0^inf) tongues ``sqrt((n-1)/2) < u <= sqrt(n/2) (1-e)/(1+e)``,
    n = 1..n_max (Theorem 3.1), and draw the Corollary 2.1 curve
    ``u = (1-e)/(2 sqrt(2e))`` on the window (the paper's Fig. 3).

    Each tongue is labelled in dark text just right of its tip, which lies
    on the Corollary 2.1 curve at ``e = (1-c)/(1+c)``, ``c = sqrt((n-1)/n)``:
    the label sits on the white no-sliding region, never across a tongue.
    n = 1, whose tip is at (1, 0), is labelled inside, in white.
    """
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(7, 5.5))
    es = np.linspace(e[0], e[1], samples)
    for n in range(1, n_max + 1):
        lo, hi = tongue_boundaries(n, es)
        ok = ~np.isnan(hi)
        if ok.any():
            ax.fill_between(es[ok], lo[ok], hi[ok], color="k", lw=0,
                            label=r"$(n, 0^\infty)$ tongues, Theorem 3.1" if n == 1 else None)
    # labels inside the window only, so none is cut by the frame
    if e[0] < 0.35 < e[1] and u[0] < 0.2 < u[1]:
        ax.text(0.35, 0.2, "n = 1", color="w", fontsize=8, ha="center", va="center")
    for n in range(2, n_max + 1):
        c = np.sqrt((n - 1) / n)
        e_tip, u_tip = (1 - c) / (1 + c), np.sqrt((n - 1) / 2.0)
        if e[0] <= e_tip < e[1] - 0.08 * (e[1] - e[0]) and u[0] + 0.03 < u_tip < u[1] - 0.03:
            ax.annotate(f"n = {n}", (e_tip, u_tip), xytext=(6, 0), textcoords="offset points",
                        color="k", fontsize=8, ha="left", va="center")
    if bound:
        from ..plane import no_sliding_curve

        curve = no_sliding_curve(es)
        ax.plot(es, curve, color="C3", lw=1.5,
                label=r"Corollary 2.1: $u = (1-e)/(2\sqrt{2e})$")
    ax.set_xlim(*e)
    ax.set_ylim(*u)
    ax.set_xlabel("e (restitution coefficient)")
    ax.set_ylabel("u (horizontal speed)")
    ax.legend(loc="upper right", fontsize="small")
    return ax
