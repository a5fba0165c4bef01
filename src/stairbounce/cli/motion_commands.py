"""``stairbounce motion``: impacts per step and Lyapunov exponents of one non-sliding orbit
(issue 13), and the motion fields of ``stairbounce scan --field``."""

from __future__ import annotations

import typer

from . import _staircase as st
from ._app import CLIError, app, save_figure, with_row_progress

MOTION_FIELD_NAMES = ("k_mean", "lyap1", "jump_mean", "speed_spread")


@app.command(short_help="Non-sliding motion: <k>, mean jump, Lyapunov exponents.")
def motion(
    e: st.E, u: st.U = None,
    speed: st.Speed = None, step_height: st.StepHeight = None, step_length: st.StepLength = None, g: st.G = None,
    steps: int = typer.Option(1000, "--steps", help="Kept steps (>= 2)."),
    transient: int = typer.Option(1000, "--transient", help="Steps discarded first (>= 0)."),
    y0: st.Y0 = 1.0, v0: st.V0 = 0.0,
):
    """Whether the orbit slides; if not, <k> (impacts per step), the mean jump and the Lyapunov exponents."""
    from ..nonsliding import motion as run

    u, stairs = st.resolve_u(u, speed, step_height, step_length, g)
    if stairs is not None:
        typer.echo(st.describe(u, stairs))
    r = run(e, u, steps=steps, transient=transient, y0=y0, v0=v0)
    typer.echo(f"e = {e:g}, u = {u:g}, from (y, v) = ({y0:g}, {v0:g}): "
               f"{transient} transient + {steps} kept steps")
    if r["slides"]:
        typer.echo(f"slides on step {r['slide_step']} (Prop. 2.1): then the periodic sliding "
                   "solution through (1, 0); Jacobian 0, exponents -inf")
        return
    typer.echo(f"<k>:         {r['k_mean']:.6g} impacts per step (halves differ by {r['k_err']:.2g})")
    typer.echo(f"mean jump:   {r['jump_mean']:.6g} steps per landing")
    typer.echo(f"lambda_1:    {r['lyap1']:+.3e} per step (halves differ by {r['lyap1_err']:.1e}; "
               f"N lambda_1 = {steps * r['lyap1']:+.2f}: 0 is exact, see stairbounce.nonsliding)")
    typer.echo(f"lambda_2:    {r['lyap2']:+.6e} per step (QR); 2 <k> log e = "
               f"{r['lyap2_identity'] + r['lyap1']:+.6e}")
    typer.echo(f"dissipation: {r['dissipation']:.6f} per step (-> 1, the height descended)")
    typer.echo(f"impulse:     {r['impulse']:.6f} per step (-> 1/u = {1 / u:.6f})")
    typer.echo(f"speed spread Var|v_-|/<|v_-|>^2: {r['speed_spread']:.3e} (0 on a one-impact family)")


def motion_scan_figure(e, u, max_iter, y0, v0, field, png, dpi, out=None, overlays=(), force=False):
    """``stairbounce scan --field k_mean|lyap1|...``: a motion scan with max_iter
    transient and max_iter kept steps, saved and drawn; returns the summary line."""
    from .. import plane as sc
    from ..nonsliding import motion_scan

    if max_iter < 2:
        raise CLIError(f"--max-iter must be >= 2 for a motion field, got {max_iter}")
    ds = with_row_progress(
        lambda progress: motion_scan(e, u, steps=max_iter, transient=max_iter, y0=y0, v0=v0,
                                     progress=progress),
        "motion scan rows", u[2])
    if out is not None:
        sc.save(ds, out, overwrite=force)
        typer.echo(f"wrote {out}")
    if png is not None:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        from ..plot.motion import plot_motion

        fig, ax = plt.subplots(figsize=(9, 6.5))
        ov = tuple(o for o in overlays if o == "bound") + ("families",)
        plot_motion(ds, field=field, ax=ax, overlay=ov)
        fig.tight_layout()
        save_figure(fig, png, dpi, force)
        typer.echo(f"wrote {png}")
    ok = ds.slide_step.values == 0
    l1 = ds.lyap1.values[ok]
    return (f"{e[2]} x {u[2]} pixels, {max_iter} + {max_iter} steps: the orbit does not slide at "
            f"{100 * ok.mean():.1f}% of the pixels"
            + (f"; there <k> in [{ds.k_mean.values[ok].min():.3g}, {ds.k_mean.values[ok].max():.3g}], "
               f"largest lambda_1 {l1.max():.2e}" if ok.any() else ""))
