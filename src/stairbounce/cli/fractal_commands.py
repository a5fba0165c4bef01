"""``stairbounce dimension``: box-counting dimension of a border (Figs. 6 and 7)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import typer

from .._io import atomic_path
from ._app import FORCE_HELP, CLIError, app, check_dpi, check_outputs, parse_range

# Scans with more pixel-steps than this show a progress bar.
_PROGRESS_WORK = 2e8


def _parse_fit_range(text):
    if text is None:
        return None
    lo, hi = parse_range("fit-range", text)
    if lo < 1:
        raise CLIError(f"--fit-range must be box sides in pixels MIN:MAX with MIN >= 1, got {text!r}")
    return lo, hi


def _read_region(path: Path, region: str) -> np.ndarray:
    """The region of a black-and-white picture: pixels darker than mid grey
    (``region="black"``) or not (``"white"``), rows from the top."""
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(path) as im:
            grey = np.asarray(im.convert("L"), dtype=np.uint8)
    except FileNotFoundError:
        raise CLIError(f"--image: no such file: {path}") from None
    except (UnidentifiedImageError, OSError, ValueError, Image.DecompressionBombError) as exc:
        raise CLIError(f"--image: cannot read {path} as an image ({exc})") from None
    dark = grey < 128
    return dark if region == "black" else ~dark


def _scan_with_progress(kwargs):
    from ..fractal import perimeter_dimension

    n = kwargs["resolution"]
    if n * n * kwargs["max_iter"] < _PROGRESS_WORK:
        return perimeter_dimension(**kwargs)
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    with Progress(
        TextColumn("scanning"), BarColumn(), TextColumn("{task.completed}/{task.total} rows"),
        TimeElapsedColumn(), console=Console(stderr=True), transient=True,
    ) as bar:
        task = bar.add_task("scan", total=n)
        return perimeter_dimension(**kwargs, progress=lambda done, total: bar.update(task, completed=done))


@app.command()
def dimension(
    e: str = typer.Option("0:0.333", "--e", help="Window along e, MIN:MAX (default: the paper's Fig. 6)."),
    u: str = typer.Option("0.4:0.733", "--u", help="Window along u, MIN:MAX (default: the paper's Fig. 6)."),
    resolution: int = typer.Option(512, "--resolution", help="Pixels along each axis of the scan (>= 8)."),
    max_iter: int = typer.Option(1000, "--max-iter", help="Steps before a point counts as non-sliding (>= 1)."),
    image: Path = typer.Option(None, "--image", help="Measure the border of the region of this black-and-white picture instead of scanning."),
    region: str = typer.Option("black", "--region", help="With --image: which colour is the region, black (darker than mid grey) or white."),
    pixels: bool = typer.Option(False, "--pixels", help="With --image: measure the region's pixels as they are (a line drawing), not its border."),
    which: str = typer.Option("sliding", "--which", help="Scan: 'sliding' (border of the sliding region) or 'words' (borders between word lengths)."),
    fit_range: str = typer.Option(None, "--fit-range", help="Box sides to fit, MIN:MAX pixels (default: largest linear region, a heuristic). The paper's numbers: 1:64 at 500 px."),
    offsets: int = typer.Option(1, "--offsets", help="Grid shifts per axis, counts averaged over them (>= 1)."),
    connectivity: int = typer.Option(4, "--connectivity", help="Neighbours that define the border: 4 or 8."),
    png: Path = typer.Option(None, "--png", help="Draw the border beside the log-log plot (Figs. 6/7) to this file (.png, .pdf, .svg)."),
    dpi: int = typer.Option(120, "--dpi", help="Resolution of raster output (10-1200)."),
    force: bool = typer.Option(False, "--force", help=FORCE_HELP),
):
    """Box-counting dimension of the border of the sliding region (Figs. 6 and 7), or of a picture."""
    from ..fractal import boundary, box_dimension

    if png is not None and png.suffix.lower() not in {".png", ".pdf", ".svg"}:
        raise CLIError(f"--png must end in .png, .pdf or .svg, got {str(png)!r}")
    if region not in ("black", "white"):
        raise CLIError(f"--region must be black or white, got {region!r}")
    if which not in ("sliding", "words"):
        raise CLIError(f"--which must be sliding or words, got {which!r}")
    if connectivity not in (4, 8):
        raise CLIError(f"--connectivity must be 4 or 8, got {connectivity}")
    if offsets < 1:
        raise CLIError(f"--offsets must be an integer >= 1, got {offsets}")
    fr = _parse_fit_range(fit_range)
    check_dpi(dpi)
    check_outputs(force, png=png)

    if image is not None:
        mask = _read_region(image, region)
        if not mask.any():
            raise CLIError(f"--image: {image} has no {region} pixel (threshold at mid grey): the region is empty")
        if mask.all() and not pixels:
            raise CLIError(f"--image: {image} is all {region} (threshold at mid grey): the region has no border")
        measured = mask if pixels else boundary(mask, connectivity=connectivity)
        try:
            result = box_dimension(measured, offsets=offsets, fit_range=fr)
        except ValueError as exc:
            raise CLIError(f"--image: {image}: {exc}") from None
        what = f"{region} pixels" if pixels else f"border of the {region} region"
        typer.echo(f"{image}: {what}, {mask.shape[1]} x {mask.shape[0]} px")
        plot_image = measured[::-1]  # drawn with rows upwards: flip to look like the file
    else:
        if resolution < 8:
            raise CLIError(f"--resolution must be an integer >= 8, got {resolution}")
        if max_iter < 1:
            raise CLIError(f"--max-iter must be an integer >= 1, got {max_iter}")
        ew, uw = parse_range("e", e), parse_range("u", u)
        result = _scan_with_progress(dict(
            e=ew, u=uw, resolution=resolution, max_iter=max_iter, which=which,
            connectivity=connectivity, offsets=offsets, fit_range=fr,
        ))
        what = "sliding region" if which == "sliding" else "word-length regions"
        typer.echo(
            f"border of the {what} in [{ew[0]:g}, {ew[1]:g}] x [{uw[0]:g}, {uw[1]:g}], "
            f"{resolution} x {resolution} px, max_iter {max_iter} "
            f"(sliding region: {100 * result.region_fraction:.1f}% of the window)"
        )
        plot_image = None

    lo, hi = result.ci
    typer.echo(f"D = {result.dimension:.4f}")
    typer.echo(f"95% CI = [{lo:.4f}, {hi:.4f}]  (stderr {result.stderr:.4f})")
    typer.echo(f"r = {result.r:.5f}")
    auto = " (automatic: largest linear region, a heuristic)" if fr is None else ""
    typer.echo(f"fit: boxes of {result.fit_range[0]}..{result.fit_range[1]} px, {result.fit.n} sizes{auto}")
    typer.echo("sizes:  " + " ".join(f"{int(s)}" for s in result.sizes))
    typer.echo("counts: " + " ".join(f"{c:g}" for c in np.asarray(result.counts, dtype=float)))

    if png is not None:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        from ..plot import plot_box_dimension

        fig = plot_box_dimension(result, image=plot_image, title=str(image) if image is not None else None)
        with atomic_path(png, overwrite=force) as tmp:
            fig.savefig(tmp, dpi=dpi)
        plt.close(fig)
        typer.echo(f"wrote {png}")
