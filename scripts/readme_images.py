"""Regenerate the README's small pictures in docs/ (a few seconds with the cache).

    python scripts/readme_images.py [--out docs]

They are the figures of ``stairbounce figures`` drawn at a low dpi (the
renderers keep one-pixel borders connected at any dpi), ``model.png``: a
periodic sliding solution beside a Poincare section, and ``borders.png``: the
exact borders of the window e in [0, 0.2], u in [0.55, 0.75] by kind, the same
picture as ``stairbounce borders --e 0:0.2 --u 0.55:0.75 --size 250x250 --png
borders.png --dpi 80``.  Kept small (well under
100 kB each) so that the repository stays light.
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
from pathlib import Path

# figure -> dpi of its small copy (about 600-900 px wide)
SMALL = {"fig4": 72, "fig5a": 70, "fig7": 66, "fig9": 48}


def main(argv=None):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from stairbounce import figures as F
    from stairbounce.structure.borders import border_points
    from stairbounce.model import iterate
    from stairbounce.plane import scan
    from stairbounce.plot import plot_borders, plot_poincare_section, plot_trajectory
    from stairbounce.symbolic import sliding_word
    from stairbounce.trajectory import trajectory

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path(__file__).parent.parent / "docs")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        for name, dpi in SMALL.items():
            settings = F.Settings(out=Path(tmp), dpi=dpi, cache_dir=F.default_cache_dir())
            (res,) = F.make_figures(settings, only=[name])
            if res.error:
                raise SystemExit(f"{name}: {res.error}")
            shutil.copyfile(Path(tmp) / f"{name}.png", args.out / f"{name}.png")
            print(f"wrote {args.out / name}.png")

    e, u = 0.05, 0.93
    word = sliding_word(e, u)
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.6), dpi=66,
                                 gridspec_kw={"width_ratios": [1.1, 1]})
    plot_trajectory(trajectory(e, u, 1.0, 0.0, word.period), ax=a1)
    a1.set_title(f"e = {e}, u = {u}: word $" + F._math_word(word) + "$")
    ys, vs, ks = iterate(1.0, 0.0, 0.1, 0.9, 3000)
    plot_poincare_section(ys, vs, ks, ax=a2)
    a2.set_title("Poincare section, e = 0.1, u = 0.9, 3000 steps from (1, 0)")
    fig.tight_layout()
    fig.savefig(args.out / "model.png")
    print(f"wrote {args.out / 'model.png'}")

    ds = scan(e=(0.0, 0.2, 250), u=(0.55, 0.75, 250))
    fig, ax = plt.subplots(figsize=(8, 6.5), dpi=80)  # as the borders command draws it
    plot_borders(border_points(ds), ax=ax, scan=ds)
    fig.tight_layout()
    fig.savefig(args.out / "borders.png")
    print(f"wrote {args.out / 'borders.png'}")


if __name__ == "__main__":
    main()
