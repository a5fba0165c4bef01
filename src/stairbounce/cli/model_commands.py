"""``stairbounce word``, ``map`` and ``trajectory``: the model of Sections 2-3."""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import typer

from .._io import atomic_path
from ..model import SLIDING, iterate
from ..symbolic import sliding_word, terminal_can_print_infinity
from ..trajectory import trajectory
from ._app import FORCE_HELP, CLIError, app, check_dpi, check_outputs

E_HELP = "Restitution coefficient, in [0, 1)."
U_HELP = "Horizontal speed in normalised units (u > 0); one step takes 1/u."


@app.command()
def word(
    e: float = typer.Option(..., "--e", help=E_HELP),
    u: float = typer.Option(..., "--u", help=U_HELP),
    max_steps: int = typer.Option(1000, "--max-steps", help="Steps to iterate before giving up (>= 1)."),
):
    """Print the word of the periodic sliding solution through (1, 0), its period and impacts."""
    w = sliding_word(e, u, max_steps=max_steps)
    if w is None:
        typer.echo(
            f"e = {e:g}, u = {u:g}: no periodic sliding solution found within {max_steps} steps "
            "(the orbit of (1, 0) does not slide)"
        )
        return
    text = w.format(ascii=not terminal_can_print_infinity())
    typer.echo(f"e = {e:g}, u = {u:g}")
    typer.echo(f"word:    {text}")
    typer.echo(f"length:  {len(w)}")
    typer.echo(f"period:  {w.period} steps")
    typer.echo(f"impacts: {w.impacts} per period (plus the accumulation)")


@app.command("map")
def map_(
    e: float = typer.Option(..., "--e", help=E_HELP),
    u: float = typer.Option(..., "--u", help=U_HELP),
    y0: float = typer.Option(1.0, "--y0", help="Initial height above the step's floor (>= 0)."),
    v0: float = typer.Option(0.0, "--v0", help="Initial vertical velocity."),
    steps: int = typer.Option(10, "--steps", help="Number of steps (>= 0)."),
    as_csv: bool = typer.Option(False, "--csv", help="Write CSV to stdout instead of a table."),
):
    """Print the Poincare iterates (Prop. 2.3): the state at each step edge and the step's impacts."""
    ys, vs, ks = iterate(y0, v0, e, u, steps)
    if as_csv:
        w = csv.writer(sys.stdout, lineterminator="\n")
        w.writerow(["n", "y", "v", "impacts"])
        for n, (y, v, k) in enumerate(zip(ys, vs, ks)):
            w.writerow([n, repr(float(y)), repr(float(v)), "" if n == 0 else int(k)])
        return
    typer.echo(f"{'n':>6}  {'y':>22}  {'v':>22}  impacts")
    for n, (y, v, k) in enumerate(zip(ys, vs, ks)):
        label = "" if n == 0 else ("sliding" if k == SLIDING else str(int(k)))
        typer.echo(f"{n:>6}  {y:>22.15g}  {v:>22.15g}  {label}")


@app.command("trajectory")
def trajectory_(
    e: float = typer.Option(..., "--e", help=E_HELP),
    u: float = typer.Option(..., "--u", help=U_HELP),
    y0: float = typer.Option(1.0, "--y0", help="Initial height above the step's floor (>= 0)."),
    v0: float = typer.Option(0.0, "--v0", help="Initial vertical velocity."),
    steps: int = typer.Option(8, "--steps", help="Number of steps (>= 1)."),
    out: Path = typer.Option(Path("trajectory.png"), "--out", help="Figure file (.png, .pdf, .svg)."),
    animate: Path = typer.Option(None, "--animate", help="Also write an animation of the ball (.gif)."),
    dpi: int = typer.Option(150, "--dpi", help="Resolution of raster output (10-1200)."),
    force: bool = typer.Option(False, "--force", help=FORCE_HELP),
):
    """Draw the ball's path on the staircase (Fig. 1) beside its Poincare section (Fig. 2)."""
    if steps < 1:
        raise CLIError(f"--steps must be an integer >= 1, got {steps}")
    if out.suffix.lower() not in {".png", ".pdf", ".svg"}:
        raise CLIError(f"--out must end in .png, .pdf or .svg, got {str(out)!r}")
    if animate is not None and animate.suffix.lower() != ".gif":
        raise CLIError(f"--animate must end in .gif, got {str(animate)!r}")
    check_dpi(dpi)
    check_outputs(force, out=out, animate=animate)
    traj = trajectory(e, u, y0, v0, steps)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..plot import animate_trajectory, plot_poincare_section, plot_trajectory

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.8), gridspec_kw={"width_ratios": [1.6, 1]})
    plot_trajectory(traj, ax=a1)
    plot_poincare_section(traj.edge_y, traj.edge_v, traj.edge_impacts, ax=a2)
    fig.tight_layout()
    with atomic_path(out, overwrite=force) as tmp:
        fig.savefig(tmp, dpi=dpi)
    plt.close(fig)
    typer.echo(
        f"wrote {out}: {len(traj.impacts)} impacts listed, "
        f"{len(traj.accumulations)} accumulation points, {len(traj.slides)} slides"
    )
    if animate is not None:
        with atomic_path(animate, overwrite=force) as tmp:
            animate_trajectory(traj, tmp)
        typer.echo(f"wrote {animate}")
