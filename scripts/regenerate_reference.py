"""Rewrite the regression pin of the parameter-plane scan: tests/data/fig5e.npz
(the arrays) and tests/data/fig5e.png (a picture of them, for people).

The window is the paper's Figure 5e, [0.04, 0.065] x [0.92, 0.945], at
100 x 100 pixels and max_iter 1000.  tests/test_scan.py compares a fresh scan
with the arrays bit for bit; run this only after a deliberate change of the
answers, and say why in the commit.

    python scripts/regenerate_reference.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from stairbounce._io import atomic_path
from stairbounce.plane import scan

DATA = Path(__file__).resolve().parent.parent / "tests" / "data"
WINDOW = {"e": (0.04, 0.065, 100), "u": (0.92, 0.945, 100), "max_iter": 1000}
FIELDS = ("status", "word_length", "jumps", "period", "impacts")


def reference():
    """The scan the pin holds."""
    return scan(**WINDOW)


def main():
    ds = reference()
    arrays = {k: ds[k].values for k in FIELDS}
    arrays.update(e=ds.e.values, u=ds.u.values, max_iter=np.int64(WINDOW["max_iter"]))
    with atomic_path(DATA / "fig5e.npz") as tmp:
        np.savez_compressed(tmp, **arrays)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from stairbounce.plot import plot_scan

    fig, ax = plt.subplots(figsize=(6.5, 5))
    plot_scan(ds, ax=ax, title="regression pin: Fig. 5e window, 100 x 100, max_iter 1000")
    fig.tight_layout()
    with atomic_path(DATA / "fig5e.png") as tmp:
        fig.savefig(tmp, dpi=100)
    plt.close(fig)
    print(f"wrote {DATA / 'fig5e.npz'} and {DATA / 'fig5e.png'}")


if __name__ == "__main__":
    main()
