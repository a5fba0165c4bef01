"""``stairbounce figures``: every figure and number of the paper, with a report."""

from __future__ import annotations

import time
from pathlib import Path

import typer

from ._app import CLIError, app, plural, progress_bar


@app.command()
def figures(
    out: Path = typer.Option(Path("figures"), "--out", help="Folder for the figures and the report."),
    only: str = typer.Option(None, "--only", help="Comma-separated figures to make, e.g. fig4,fig6 (fig5 = all five blow-ups)."),
    fmt: str = typer.Option("png", "--format", help="Image format: png, pdf or svg."),
    dpi: int = typer.Option(150, "--dpi", help="Resolution of raster output (10-1200)."),
    scale: float = typer.Option(1.0, "--scale", help="Multiply every grid's pixel count by this (0.01-16)."),
    max_iter: int = typer.Option(1000, "--max-iter", help="Steps before a point counts as non-sliding (>= 1)."),
    no_cache: bool = typer.Option(False, "--no-cache", help="Recompute the scans instead of reading the cache."),
    cache_dir: Path = typer.Option(None, "--cache-dir", help="Where scans are cached (default ~/.cache/stairbounce)."),
):
    """Reproduce the paper's Figures 1-9 and write report.md, report.html and manifest.json.

    With --only into a folder that holds an earlier run, the report keeps the
    other figures of that run (merged by figure) and says so."""
    from rich.console import Console

    from ..figures import Settings, default_cache_dir, make_figures, select, write_report

    if fmt not in ("png", "pdf", "svg"):
        raise CLIError(f"--format must be png, pdf or svg, got {fmt!r}")
    if max_iter < 1:
        raise CLIError(f"--max-iter must be an integer >= 1, got {max_iter}")
    if out.exists() and not out.is_dir():
        raise CLIError(f"--out must be a folder, but {out} is a file")
    names = select(only.split(",") if only else None)
    settings = Settings(
        out=out, fmt=fmt, dpi=dpi, scale=scale, max_iter=max_iter,
        cache_dir=None if no_cache else (cache_dir or default_cache_dir()),
    )
    console = Console(stderr=True)
    t0 = time.perf_counter()
    with progress_bar(console, "figures", len(names)) as (bar, task):

        def start(name):
            bar.update(task, description=f"{name}")

        def note(text):
            bar.update(task, description=text)

        def done(res):
            status = f"[red]failed: {res.error}" if res.error else ", ".join(res.files)
            console.print(f"{res.name:6s} {res.seconds:6.2f} s  {status}", highlight=False)
            bar.advance(task)

        settings.progress = note
        results = make_figures(settings, names, on_start=start, on_done=done)
    total = time.perf_counter() - t0
    paths, kept = write_report(results, settings, total_seconds=total)
    failed = [r.name for r in results if r.error]
    made = len(results) - len(failed)
    typer.echo(f"wrote {plural(made, 'figure')} and {', '.join(p.name for p in paths)} "
               f"to {out} in {total:.1f} s")
    if kept:
        typer.echo(f"the report keeps {plural(len(kept), 'figure')} of the earlier run in {out} "
                   f"({', '.join(kept)}), merged by figure")
    if failed:
        typer.echo(f"failed: {', '.join(failed)} (see {out / 'report.md'})", err=True)
        raise typer.Exit(1)
