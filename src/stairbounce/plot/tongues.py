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
    """Fill the tongues ``sqrt((n-1)/2) < u <= sqrt(n/2) (1-e)/(1+e)``, n = 1..n_max,
    and draw the Corollary 2.1 curve ``u = (1-e)/(2 sqrt(2e))`` on the window."""
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(7, 5.5))
    es = np.linspace(e[0], e[1], samples)
    for n in range(1, n_max + 1):
        lo, hi = tongue_boundaries(n, es)
        ok = ~np.isnan(hi)
        if ok.any():
            ax.fill_between(es[ok], lo[ok], hi[ok], color="k", lw=0,
                            label="(n, 0^\u221e) tongues" if n == 1 else None)
            mid = 0.5 * (lo[ok][0] + hi[ok][0])  # label at the wide end of the tongue
            if u[0] < mid < u[1] and n <= 10:
                ax.annotate(f"n = {n}", (es[ok][0], mid), xytext=(3, -3),
                            textcoords="offset points", color="w", fontsize=7, va="center")
    if bound:
        from ..plane import no_sliding_curve

        curve = no_sliding_curve(es)
        ax.plot(es, curve, color="C3", lw=1.5, label="Corollary 2.1: u = (1-e)/(2\u221a(2e))")
    ax.set_xlim(*e)
    ax.set_ylim(*u)
    ax.set_xlabel("e")
    ax.set_ylabel("u")
    ax.legend(loc="upper right", fontsize="small")
    return ax
