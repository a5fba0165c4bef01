"""``stairbounce scan``: the (e, u) parameter plane of Section 3 (Figures 3, 4, 5)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import typer

from ._app import (
    FORCE_HELP,
    CLIError,
    check_dpi,
    check_outputs,
    app,
    draw_scan,
    parse_overlays,
    DEFAULT_E,
    DEFAULT_U,
    MaxIter,
    Size,
    parse_range,
    plural,
    window_size,
    tile_for_workers,
    with_row_progress,
)
from . import _staircase as st
from .motion_commands import MOTION_FIELD_NAMES, motion_scan_figure

FIELD_NAMES = ("word_length", "period", "impacts", "jumps", "status") + MOTION_FIELD_NAMES
OVERLAY_NAMES = ("tongues", "bound")


# Peak resident memory of a non-tiled `stairbounce scan` per pixel: the scan's
# 25 bytes, the figure (matplotlib normalises and colours the whole image) and
# the file; measured 82-132 B/pixel above the interpreter at 1000^2-3000^2
# pixels (report D3 found 4x the 25 B/pixel the check used to assume)
_CLI_BYTES_PER_PIXEL = 140


@app.command("scan", short_help="Scan the (e, u) plane for sliding solutions (Figs 3-5).")
def scan_(
    e: str = typer.Option(
        None, "--e",
        help="Window along e, MIN:MAX: the image edges, within [0, 1] (pixel centres lie inside, < 1); default 0:1, Fig. 4's window.",
    ),
    u: str = typer.Option(
        None, "--u",
        help="Window along u, MIN:MAX: the image edges, MIN >= 0 (pixel centres lie inside, > 0); default 0:1.5, Fig. 4's window.",
    ),
    speed: str = st.speed_option(
        "Window along the ball's speed in m/s, MIN:MAX (with --step-height and --step-length; instead "
        "of --u): the picture's axis and the data's coordinate 'speed' are in m/s."),
    step_height: st.StepHeight = None, step_length: st.StepLength = None, g: st.G = None,
    size: Size = None, max_iter: MaxIter = 1000,
    y0: float = typer.Option(1.0, "--y0", help="Initial height at the edge (>= 0); (1, 0) is the paper's."),
    v0: float = typer.Option(0.0, "--v0", help="Initial vertical velocity."),
    out: Path = typer.Option(None, "--out", help="Save the data: .zarr (chunked) or .nc."),
    png: Path = typer.Option(
        None, "--png",
        help="Figure to write (.png, .pdf or .svg); default scan.png when --out is not given, none with --out.",
    ),
    field: str = typer.Option("word_length", "--field", help="Colour by: " + ", ".join(FIELD_NAMES) + " (the last "
                              "four: non-sliding motion, max_iter transient + max_iter kept steps, stairbounce.nonsliding)."),
    overlay: list[str] = typer.Option([], "--overlay", help="Curves to draw, comma-separated or repeated: tongues (Theorem 3.1), bound (Corollary 2.1)."),
    dpi: int = typer.Option(150, "--dpi", help="Resolution of raster output."),
    tile: int = typer.Option(None, "--tile", help="Tiled, resumable scan into --out (.zarr), TILE x TILE pixels a tile."),
    scheduler: str = typer.Option(None, "--scheduler", help="Tiled scan on a running Dask scheduler (tcp://HOST:PORT)."),
    workers: int = typer.Option(None, "--workers", help="Tiled scan on a local Dask cluster of this many workers."),
    force: bool = typer.Option(False, "--force", help=FORCE_HELP + " A tiled store is resumed, not replaced."),
):
    """Scan the (e, u) plane for periodic sliding solutions and draw it (Figures 3-5).

    With no options: the paper's Figure 4 view, e in [0, 1] x u in [0, 1.5],
    500 x 350 pixels, max_iter 1000, written to scan.png.  The windows are
    image edges; pixels are sampled at their centres, so u = 0 is never used.
    Any other window gets square pixels unless --size is given.
    A picture is written only to --png, or to scan.png when neither --out nor
    --png is given; existing files are replaced only with --force.
    """
    from .. import plane as sc

    default_window = e is None and u is None and speed is None
    e_lo, e_hi = parse_range("e", e or DEFAULT_E)
    stairs = None
    if u is None and (speed, step_height, step_length, g) == (None,) * 4:
        u = DEFAULT_U
    else:
        u, stairs = st.resolve_u_text(u, speed, step_height, step_length, g)
        if stairs is not None and ":" not in speed:
            raise CLIError(f"--speed must be a range MIN:MAX in m/s for a scan, got {speed!r}")
    u_lo, u_hi = parse_range("u", u)
    n_e, n_u = window_size(size, (e_lo, e_hi), (u_lo, u_hi), default_window)
    if max_iter < 1:
        raise CLIError(f"--max-iter must be an integer >= 1, got {max_iter}")
    if field not in FIELD_NAMES:
        raise CLIError(f"--field must be one of {', '.join(FIELD_NAMES)}, got {field!r}")
    overlays = parse_overlays(overlay, OVERLAY_NAMES)
    if png is not None and png.suffix.lower() not in {".png", ".pdf", ".svg"}:
        raise CLIError(f"--png must end in .png, .pdf or .svg, got {str(png)!r}")
    if out is not None and out.suffix not in {".zarr", ".nc"}:
        raise CLIError(f"--out must end in .zarr or .nc, got {str(out)!r}")
    check_dpi(dpi)
    # the library's checks name the bound that is out of range
    sc._window("e", (e_lo, e_hi, n_e), 0.0, 1.0, "[0, 1]")
    sc._window("u", (u_lo, u_hi, n_u), 0.0, float("inf"), "[0, inf)")
    if y0 < 0:
        raise CLIError(f"--y0 must be >= 0, got {y0}")
    tiled = tile is not None or scheduler is not None or workers is not None
    # the u window: in m/s on a real staircase (the Dataset gets the coordinate 'speed')
    u_window: Any = (u_lo, u_hi, n_u) if stairs is None else stairs.speed(*parse_range("speed", speed), n_u)
    if stairs is not None:
        typer.echo(f"speed U in [{u_window.metres_per_second[0]:g}, {u_window.metres_per_second[1]:g}] m/s "
                   f"on {stairs.describe()}: u in [{u_lo:.6g}, {u_hi:.6g}]")
    if png is None and out is None and not tiled:
        png = Path("scan.png")
    if not tiled:
        # before the progress bar draws anything; the figure and the file
        # written from the scan take more than the scan itself
        sc._check_memory(n_e, n_u, _CLI_BYTES_PER_PIXEL)
    # before any work: a tiled store is resumed (its own checks), files are not replaced
    check_outputs(force, png=png, out=None if tiled else out)

    if field in MOTION_FIELD_NAMES:
        if tiled:
            raise CLIError(f"--field {field} is not available for tiled scans; scan tiles with "
                           "stairbounce.nonsliding.motion_coords")
        typer.echo(motion_scan_figure((e_lo, e_hi, n_e), u_window, max_iter, y0, v0,
                                      field, png, dpi, out, overlays, force=force))
        return
    if tiled:
        if out is None:
            raise CLIError("a tiled scan (--tile, --scheduler, --workers) needs --out STORE.zarr")
        from .atlas_commands import draw_store, run_tiled_scan

        if tile is None and workers is not None and workers >= 1 and scheduler is None:
            # the default 1024 px tile makes one tile of the Fig. 4 view: one
            # worker busy, the others idle behind the cluster's start-up
            tile, tiles = tile_for_workers(n_e, n_u, workers)
            typer.echo(f"tiles of {tile} px: {plural(tiles, 'tile')} for "
                       f"{plural(workers, 'worker')}"
                       + ("" if tiles >= workers else
                          f" (tiles under 64 px cost more than they share; "
                          f"{plural(workers - tiles, 'worker')} idle)"), err=True)
        ds = run_tiled_scan(out, (e_lo, e_hi, n_e), u_window, max_iter, y0, v0,
                            tile=tile, scheduler=scheduler, workers=workers)
        if png is not None:
            # never the whole store in memory: reduced by blocks first
            draw_store(ds, field, png, dpi, overlay=overlays, overwrite=force)
            typer.echo(f"wrote {png}")
        return

    ds = _scan_with_progress(sc, (e_lo, e_hi, n_e), u_window, max_iter, y0, v0)
    if out is not None:
        sc.save(ds, out, overwrite=force)
        typer.echo(f"wrote {out}")
    if png is not None:
        draw_scan(ds, field, overlays, png, dpi, overwrite=force)
        typer.echo(f"wrote {png}")
    found = ds["status"].values == 0
    frac = found.mean()
    longest = int(ds["word_length"].values.max())
    typer.echo(
        f"{n_e} x {n_u} pixels, e in [{e_lo:g}, {e_hi:g}], u in [{u_lo:g}, {u_hi:g}]"
        + ("" if stairs is None else " (U in [{:g}, {:g}] m/s)".format(*u_window.metres_per_second))
        + ", "
        f"max_iter {max_iter}: periodic sliding solution at {100 * frac:.1f}% of the pixels"
        + (f", longest word {longest}" if found.any() else "")
    )
    typer.echo("basis: numerical (each pixel centre's float64 orbit of (1, 0) followed up to max_iter steps; "
               "stairbounce certify proves words over boxes)")


def _scan_with_progress(sc, e, u, max_iter, y0, v0):
    return with_row_progress(lambda progress: sc.scan(e, u, max_iter, y0, v0, progress=progress),
                             "scan rows", u[2])
