"""Regenerate the README's small pictures in docs/ (a few seconds with the cache).

    python scripts/readme_images.py [--out docs]

They are the figures of ``stairbounce figures`` drawn at a low dpi (the
renderers keep one-pixel borders connected at any dpi), ``model.png``: a
periodic sliding solution beside a Poincare section, ``borders.png``: the
exact borders of the window e in [0, 0.2], u in [0.55, 0.75] by kind, the same
picture as ``stairbounce borders --e 0:0.2 --u 0.55:0.75 --size 250x250 --png
borders.png --dpi 80``, and ``cascade.png`` (the guide's page on cascades): the
regions of the first members of (1^k, 0^inf) beside the law of the widths.
Kept small (well under 100 kB each) so that the repository stays light.
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
    cascade_picture(args.out / "cascade.png")


def cascade_picture(path, dpi=66):
    """The members k = 2..6 of (1^k, 0^inf): their regions in (e, u)
    (sb.word_region), the line e = 0.02 with the members' intervals on it
    (sb.cascade), and the widths against k with the two laws weighed
    (plot_cascade_law); the code shown in docs/guide/cascades.md."""
    import matplotlib.pyplot as plt

    import stairbounce as sb
    from stairbounce.plot import plot_cascade_law

    e0 = 0.02
    c = sb.cascade("(1^k, 0^inf)", e=e0, u=(0.6, 0.75), law_k=(5, 12))
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2), dpi=dpi)
    for k in range(2, 6):
        member = c.members[c.members.k == k].iloc[0]
        region = sb.word_region(member.word, e=(0, 0.12), u=(0.64, 0.71), resolution=96)
        for comp in region.components:
            e, u = comp.polygon()
            left.fill(e, u, color=f"C{k - 2}", alpha=0.75, lw=0,
                      label=f"k = {k}: $(" + "1, " * k + r"0^{\infty})$")
        left.plot([e0, e0], [member.lo, member.hi], color="k", lw=2.5, solid_capstyle="butt")
    left.axvline(e0, color="k", lw=0.6, ls=":")
    left.set(xlabel="restitution e", ylabel="horizontal speed u", xlim=(0, 0.12), ylim=(0.64, 0.71))
    left.set_title(r"regions of $(1^k, 0^{\infty})$; black: the members on e = " + f"{e0}",
                   fontsize="medium")
    left.legend(fontsize="x-small", loc="lower left")
    plot_cascade_law(c, ax=right)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
