"""``stairbounce word``, ``map`` and ``trajectory``: the model of Sections 2-3."""

from __future__ import annotations

import csv
import sys
from pathlib import Path
from typing import Annotated, Optional, cast

import typer

from .._io import atomic_path
from ..model import SLIDING, iterate
from ..symbolic import sliding_answer, terminal_can_print_infinity
from ..trajectory import trajectory
from . import _staircase as st
from ._app import (CLIError, Dpi, Force, app, check_dpi, check_outputs, plural, progress_bar, renamed_option,
                   save_figure)

# --u as st.U, and how long one step takes
U = Annotated[Optional[float], typer.Option("--u", help="Horizontal speed in normalised units (u > 0); one step takes 1/u. "
                                  "Or --speed with --step-height, --step-length.")]


@app.command(short_help="Word of the sliding solution through (1, 0), or why none.")
def word(
    e: st.E, u: U = None,
    speed: st.Speed = None, step_height: st.StepHeight = None, step_length: st.StepLength = None, g: st.G = None,
    max_iter: int = typer.Option(1000, "--max-iter", help="Steps to iterate before giving up (>= 1)."),
    max_steps: int = typer.Option(None, "--max-steps", hidden=True,
                                  help="The old name of --max-iter (deprecated)."),
    unicode: bool = typer.Option(False, "--unicode", help="Write the tail 0^∞ (where the terminal can "
                                 "print it) instead of 0^inf, the spelling of every command."),
):
    """Print the word of the periodic sliding solution through (1, 0), its period and impacts."""
    max_iter = renamed_option("--max-steps", max_steps, "--max-iter", max_iter, 1000)
    u, stairs = st.resolve_u(u, speed, step_height, step_length, g)
    if stairs is not None:
        typer.echo(st.describe(u, stairs))
    answer = sliding_answer(e, u if stairs is None else stairs.speed(float(cast(float, speed))),
                            max_iter=max_iter)
    w = answer.word
    if w is None:
        # proven impossible above the Corollary 2.1 curve, else only not found
        typer.echo(f"e = {e:g}, u = {u:g}: {answer.text()}")
        typer.echo(_basis(answer))
        return
    text = w.format(ascii=not (unicode and terminal_can_print_infinity()))
    typer.echo(f"e = {e:g}, u = {u:g}")
    typer.echo(f"word:    {text}")
    typer.echo(f"length:  {len(w)}")
    typer.echo(f"period:  {plural(w.period, 'step')}"
               + ("" if stairs is None else f" = {w.period * stairs.step_length / stairs.to_speed(u):.6g} s"))
    typer.echo(f"impacts: {w.impacts} per period (plus the accumulation)")
    typer.echo(_basis(answer))


def _basis(answer):
    """The answer's basis, one line: proven (Corollary 2.1, or sb.certify_box at the
    point: interval arithmetic over the binary floats of e and u) or numerical."""
    from ..structure.certify import certify_box

    if answer.verdict == "impossible":
        return "basis:   proven (Corollary 2.1, a closed-form bound; nothing iterated)"
    e, u = answer.e, answer.u
    cert = certify_box(e=(e, e), u=(u, u), max_iter=answer.max_iter)
    what = "the binary floats of e and u; sb.certify_box, outward-rounded interval arithmetic"
    if answer.word is not None and cert.status == "word" and cert.word == answer.word:
        return f"basis:   proven at this point ({what}: every decision of the orbit of (1, 0))"
    if answer.word is None and cert.status == "no_slide_within":
        return (f"basis:   proven at this point ({what}): no slide within the first {answer.max_iter} "
                "steps (whether it slides later is open)")
    why = f"{cert.status}" + (f": {cert.reason} at step {cert.step}" if cert.reason else "")
    return (f"basis:   numerical (the float64 orbit of (1, 0); sb.certify_box leaves this point {why}, "
            "within rounding of a border)")


@app.command("map", short_help="Poincare iterates (Prop 2.3): the state at each edge.")
def map_(
    e: st.E, u: U = None,
    speed: st.Speed = None, step_height: st.StepHeight = None, step_length: st.StepLength = None, g: st.G = None,
    y0: st.Y0 = 1.0, v0: st.V0 = 0.0,
    steps: int = typer.Option(10, "--steps", help="Number of steps (>= 0)."),
    as_csv: bool = typer.Option(False, "--csv", help="Write CSV to stdout instead of a table."),
):
    """Print the Poincare iterates (Prop. 2.3): the state at each step edge and the step's impacts.
    With a physical staircase, also the height in m and the velocity in m/s."""
    u, stairs = st.resolve_u(u, speed, step_height, step_length, g)
    ys, vs, ks = iterate(y0, v0, cast(float, e), cast(float, u), steps)
    # (y, v) normalised, then (y a, v sqrt(a g)) in SI units when a staircase was given
    si = () if stairs is None else (stairs.step_height, stairs.velocity_unit)
    if as_csv:
        w = csv.writer(sys.stdout, lineterminator="\n")
        w.writerow(["n", "y", "v", "impacts"] + (["y_m", "v_m_per_s"] if si else []))
        for n, (y, v, k) in enumerate(zip(ys, vs, ks)):
            w.writerow([n, repr(float(y)), repr(float(v)), "" if n == 0 else int(k)]
                       + ([repr(float(y * si[0])), repr(float(v * si[1]))] if si else []))
        return
    if stairs is not None:
        typer.echo(st.describe(u, stairs))
    extra = f"  {'y (m)':>14}  {'v (m/s)':>14}" if si else ""
    typer.echo(f"{'n':>6}  {'y':>22}  {'v':>22}  impacts{extra}")
    for n, (y, v, k) in enumerate(zip(ys, vs, ks)):
        label = "" if n == 0 else ("sliding" if k == SLIDING else str(int(k)))
        extra = f"  {y * si[0]:>14.8g}  {v * si[1]:>14.8g}" if si else ""
        typer.echo(f"{n:>6}  {y:>22.15g}  {v:>22.15g}  {label:7s}{extra}".rstrip())


@app.command("trajectory", short_help="The ball's path (Fig 1) and Poincare section (Fig 2).")
def trajectory_(
    e: st.E, u: U = None,
    speed: st.Speed = None, step_height: st.StepHeight = None, step_length: st.StepLength = None, g: st.G = None,
    y0: st.Y0 = 1.0, v0: st.V0 = 0.0,
    steps: int = typer.Option(8, "--steps", help="Number of steps (>= 1)."),
    out: Path = typer.Option(Path("trajectory.png"), "--out", help="Figure file (.png, .pdf, .svg)."),
    animate: Path = typer.Option(None, "--animate", help="Also write an animation of the ball (.gif)."),
    dpi: Dpi = 150, force: Force = False,
):
    """Draw the ball's path on the staircase (Fig. 1) beside its Poincare section (Fig. 2).
    With a physical staircase the axes are in metres, m/s and seconds."""
    u, stairs = st.resolve_u(u, speed, step_height, step_length, g)
    if steps < 1:
        raise CLIError(f"--steps must be an integer >= 1, got {steps}")
    if out.suffix.lower() not in {".png", ".pdf", ".svg"}:
        raise CLIError(f"--out must end in .png, .pdf or .svg, got {str(out)!r}")
    if animate is not None and animate.suffix.lower() != ".gif":
        raise CLIError(f"--animate must end in .gif, got {str(animate)!r}")
    check_dpi(dpi)
    check_outputs(force, out=out, animate=animate)
    # on a physical staircase the trajectory carries it (the same u), and both
    # panels draw themselves in metres, m/s and seconds
    traj = trajectory(e, u if stairs is None else stairs.speed(speed), y0, v0, steps)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..plot import animate_trajectory, plot_poincare_section, plot_trajectory

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.8), gridspec_kw={"width_ratios": [1.6, 1]})
    plot_trajectory(traj, ax=a1)
    plot_poincare_section(traj.edge_y, traj.edge_v, traj.edge_impacts, ax=a2, staircase=traj)
    if stairs is not None:
        typer.echo(st.describe(u, stairs))
    # the path's title sits above its clock axis, which the layout does not count: room for it
    fig.tight_layout(rect=None if stairs is None else (0.0, 0.0, 1.0, 0.94))
    save_figure(fig, out, dpi, force)
    typer.echo(
        f"wrote {out}: {plural(len(traj.impacts), 'impact')} listed, "
        f"{plural(len(traj.accumulations), 'accumulation point')}, "
        f"{plural(len(traj.slides), 'slide')}"
    )
    if animate is not None:
        from rich.console import Console

        # Pillow encodes a frame at a time: about 12 s for 8 steps
        with progress_bar(Console(stderr=True), "animation frames", None) as (bar, task), \
                atomic_path(animate, overwrite=force) as tmp:
            animate_trajectory(traj, tmp, progress=lambda done, total: bar.update(
                task, completed=done, total=total))
        typer.echo(f"wrote {animate}")
