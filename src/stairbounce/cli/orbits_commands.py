"""``stairbounce orbit-diagram``: the bifurcation diagrams of Section 4 (Figs. 8, 9)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import typer

from .._io import atomic_path, write_shielded
from ..model import check_count
from ..units import with_speed
from . import _staircase as st
from ._app import (
    CLIError,
    Dpi,
    Force,
    app,
    check_dpi,
    check_outputs,
    parse_overlays,
    parse_range,
    plural,
    progress_bar,
    save_figure,
)

# Above this many map steps (about a second of work) the sweep runs in slices
# behind a progress bar.
_PROGRESS_STEPS = 200_000_000
_SLICES = 40

_FIGURE_SUFFIXES = {".png", ".pdf", ".svg"}
_DATA_SUFFIXES = {".nc", ".csv", ".zarr"}


def _parameter(name: str, text: str, n: int):
    """``"0.1"`` -> (0.1, False); ``"0:0.5"`` -> (the centres of n equal cells
    of [0, 0.5], True): a range is a window's edges, as in every command."""
    if ":" in text:
        from ..plane import pixel_centres

        lo, hi = parse_range(name, text)
        return pixel_centres(lo, hi, n), True
    try:
        return float(text), False
    except ValueError:
        raise CLIError(f"--{name} must be a number or a range MIN:MAX, got {text!r}") from None


def _sweep(e, u, varied, y0, v0, transient, keep, warm_start):
    """:func:`orbit_diagram`, in slices of the swept values behind a progress
    bar when the work is long; with ``warm_start`` each slice starts from the
    last state of the previous one, so the result is the same as one call."""
    import xarray as xr

    from ..orbits import orbit_diagram

    from .._validate import check_memory

    values = e if varied == "e" else u
    # the whole sweep, before any slice: the slices (20 bytes an iterate) and
    # their concatenation (report D3: each slice fitted, the list did not)
    check_memory(f"keep = {keep} iterates of {values.size} parameter values", 2 * 20 * values.size * keep)
    if values.size * (transient + keep) < _PROGRESS_STEPS or values.size < 2 * _SLICES:
        return orbit_diagram(e, u, y0, v0, transient, keep, warm_start)

    from rich.console import Console

    parts = []
    with progress_bar(Console(stderr=True), f"orbit diagram over {varied}", values.size) as (
        progress, task
    ):
        for chunk in np.array_split(values, _SLICES):
            args = (chunk, u) if varied == "e" else (e, chunk)
            ds = orbit_diagram(*args, y0, v0, transient, keep, warm_start)
            parts.append(ds)
            if warm_start:
                y0, v0 = float(ds.y.values[-1, -1]), float(ds.v.values[-1, -1])
            progress.advance(task, chunk.size)
    # the first slice's attributes carry the user's (y0, v0)
    return xr.concat(parts, dim=varied, combine_attrs="override")


def _write_data(ds, path: Path, overwrite=False) -> None:
    suffix = path.suffix.lower()
    with atomic_path(path, overwrite=overwrite) as tmp:
        if suffix == ".nc":
            write_shielded(lambda: ds.to_netcdf(tmp), tmp)
        elif suffix == ".zarr":
            write_shielded(lambda: ds.to_zarr(tmp), tmp)
        else:
            ds.to_dataframe().to_csv(tmp)


@app.command("orbit-diagram", short_help="Orbit diagram over e or u (Section 4, Figs 8, 9).")
def orbit_diagram_(
    e: str = typer.Option(..., "--e", help="Restitution coefficient in [0, 1): a number, or a range MIN:MAX to sweep "
                          "(edges, within [0, 1]: --n values at the centres of equal cells, as every window)."),
    u: str = typer.Option(None, "--u", help="Horizontal speed u > 0: a number, or a range MIN:MAX to sweep (edges, "
                          "MIN >= 0: --n values at the centres of equal cells, so u = 0 is never used)."),
    speed: str = st.speed_option("Horizontal speed in m/s, a number or a range MIN:MAX (edges; instead of --u)."),
    step_height: st.StepHeight = None, step_length: st.StepLength = None, g: st.G = None,
    n: int = typer.Option(3000, "--n", help="Number of values of the swept parameter (>= 2): the centres of "
                          "--n equal cells of its range."),
    transient: int = typer.Option(2000, "--transient", help="Iterates discarded at each value (>= 0)."),
    keep: int = typer.Option(200, "--keep", help="Iterates kept at each value (>= 1)."),
    y0: float = typer.Option(0.1, "--y0", help="Initial height above the step's floor (>= 0)."),
    v0: float = typer.Option(0.0, "--v0", help="Initial vertical velocity."),
    warm_start: bool = typer.Option(False, "--warm-start", help="Start each value from the previous value's last state."),
    component: str = typer.Option("y", "--component", help="Component to plot: y or v."),
    points: bool = typer.Option(False, "--points", help="Draw every point instead of a density image."),
    overlay: list[str] = typer.Option([], "--overlay", help="Lines to draw, comma-separated or repeated: tongues (Theorem 3.1), families (one impact every n steps, where the diagram jumps), bound (Corollary 2.1)."),
    bins: int = typer.Option(400, "--bins", help="Density image rows along the component (>= 1)."),
    value_range: str = typer.Option(None, "--range", help="Plotted range MIN:MAX of the component (a zoom)."),
    png: Path = typer.Option(None, "--png", help="Figure file (.png, .pdf or .svg)."),
    out: Path = typer.Option(None, "--out", help="Data file: .nc (netCDF), .zarr or .csv (one row per point)."),
    dpi: Dpi = 150, force: Force = False,
):
    """Orbit (bifurcation) diagram: iterate the Poincare map at each value of the swept parameter
    and plot the kept iterates (Section 4, Figs. 8 and 9). Exactly one of --e, --u is a range."""
    n = check_count("--n", n, 2)
    u, stairs = st.resolve_u_text(u, speed, step_height, step_length, g)
    if stairs is not None:
        typer.echo(f"speed {speed} m/s on {stairs.describe()}: u = {u}")
    if component not in ("y", "v"):
        raise CLIError(f"--component must be y or v, got {component!r}")
    overlays = parse_overlays(overlay, ("tongues", "families", "bound"))
    check_count("--bins", bins, 1)
    check_dpi(dpi)
    if png is None and out is None:
        raise CLIError("give --png FILE and/or --out FILE: there is nothing to write")
    if png is not None and png.suffix.lower() not in _FIGURE_SUFFIXES:
        raise CLIError(f"--png must end in .png, .pdf or .svg, got {str(png)!r}")
    if out is not None and out.suffix.lower() not in _DATA_SUFFIXES:
        raise CLIError(f"--out must end in .nc, .zarr or .csv, got {str(out)!r}")
    check_outputs(force, png=png, out=out)
    shown = None if value_range is None else parse_range("range", value_range)
    ev, e_swept = _parameter("e", e, n)
    uv, u_swept = _parameter("u", u, n)
    if e_swept == u_swept:
        raise CLIError(
            "exactly one of --e, --u must be a range MIN:MAX (the swept parameter), got "
            + ("two ranges" if e_swept else "no range")
        )
    varied = "e" if e_swept else "u"

    ds = _sweep(ev, uv, varied, y0, v0, transient, keep, warm_start)
    # on a real staircase: the coordinate (or attribute) speed in m/s, and the
    # figure's axes in m/s and metres
    ds = with_speed(ds, stairs, "u")
    fixed = "u" if e_swept else "e"
    summary = (f"{ds.sizes[varied]} values of {varied} x {plural(ds.sizes['iterate'], 'iterate')} "
               f"({ds.sizes[varied] * ds.sizes['iterate']} points), {fixed} = {ds.attrs[fixed]:g}")

    if out is not None:
        _write_data(ds, out, overwrite=force)
        typer.echo(f"wrote {out}: {summary}")
    if png is not None:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        from ..plot import plot_orbit_diagram

        fig, ax = plt.subplots(figsize=(10, 5.5))
        plot_orbit_diagram(ds, component=component, density=not points, ax=ax,
                           overlay=overlays, bins=bins, range=shown)
        fig.tight_layout()
        save_figure(fig, png, dpi, force)
        typer.echo(f"wrote {png}: {summary}")
