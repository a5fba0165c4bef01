"""``stairbounce figures``: every figure and number of the paper, with a report."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import typer

from ._app import FORCE_HELP, CLIError, app, check_interrupted, plural, progress_bar


@app.command(short_help="Reproduce the paper's Figures 1-9, with a report.")
def figures(
    out: Path = typer.Option(Path("figures"), "--out", help="Folder for the figures and the report."),
    only: str = typer.Option(None, "--only", help="Comma-separated figures to make, e.g. fig4,fig6 (fig5 = all five blow-ups)."),
    fmt: str = typer.Option("png", "--format", help="Image format: png, pdf or svg."),
    dpi: int = typer.Option(150, "--dpi", help="Resolution of raster output (10-1200)."),
    scale: float = typer.Option(1.0, "--scale", help="Multiply every grid's pixel count by this (0.01-16)."),
    max_iter: int = typer.Option(1000, "--max-iter", help="Steps before a point counts as non-sliding (>= 1)."),
    borders: bool = typer.Option(False, "--borders", help="Draw the exact borders (located to rounding, coloured by kind) over Figs. 4 and 5a-e."),
    no_cache: bool = typer.Option(False, "--no-cache", help="Recompute the scans instead of reading the cache."),
    cache_dir: Path = typer.Option(None, "--cache-dir", help="Where scans are cached (default ~/.cache/stairbounce)."),
    force: bool = typer.Option(
        False, "--force",
        help="Replace existing files in --out that an earlier 'figures' run did not write "
             "(files of an earlier run, listed in its manifest.json, are always replaced).",
    ),
):
    """Reproduce the paper's Figures 1-9 and write report.md, report.html and manifest.json.

    With --only into a folder that holds an earlier run, the report keeps the
    other figures of that run (merged by figure) and says so."""
    from rich.console import Console

    from ..figures import Settings, check_outputs, default_cache_dir, make_figures, select, write_report

    if fmt not in ("png", "pdf", "svg"):
        raise CLIError(f"--format must be png, pdf or svg, got {fmt!r}")
    if not 1 <= max_iter <= 2**31 - 1:
        raise CLIError(f"--max-iter must be an integer >= 1 and <= 2147483647, got {max_iter}")
    if out.exists() and not out.is_dir():
        raise CLIError(f"--out must be a folder, but {out} is a file")
    names = select(only.split(",") if only else None)
    cache = None if no_cache else _usable_cache(cache_dir or default_cache_dir())
    settings = Settings(
        out=out, fmt=fmt, dpi=dpi, scale=scale, max_iter=max_iter, cache_dir=cache, overwrite=force,
        borders=borders,
    )
    check_outputs(settings, names)  # before any figure: nothing replaced unasked
    console = Console(stderr=True)
    t0 = time.perf_counter()
    with progress_bar(console, "figures", len(names)) as (bar, task):

        def start(name):
            check_interrupted()  # a Ctrl-C that Python lost in a finaliser stops here
            bar.update(task, description=f"{name}")

        def note(text):
            bar.update(task, description=text)

        def done(res):
            check_interrupted()
            status = f"[red]failed: {res.error}" if res.error else ", ".join(res.files)
            console.print(f"{res.name:6s} {res.seconds:6.2f} s  {status}", highlight=False)
            bar.advance(task)

        settings.progress = note
        results = make_figures(settings, names, on_start=start, on_done=done)
    check_interrupted()
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
    from ..figures import read_manifest, rows_with_verdict, verdict_tally

    # the figures of the whole report (an earlier run's kept ones included)
    recorded = read_manifest(out)
    typer.echo(f"verdicts: {verdict_tally(recorded)} (report.md states the criterion)")
    differs = rows_with_verdict(recorded, "differs")
    if differs:
        typer.echo(f"the {plural(len(differs), 'row')} that differ{'s' if len(differs) == 1 else ''} "
                   "from the paper:")
        for line in differs:
            typer.echo(f"  {line}")
    if failed:
        raise typer.Exit(1)


def _usable_cache(folder: Path):
    """``folder`` if scans can be cached there, else None with one warning:
    an unwritable cache costs time, never a figure."""
    from .._io import _probe_writable

    try:
        folder.mkdir(parents=True, exist_ok=True)
        reason = _probe_writable(folder)
    except OSError as exc:
        reason = (exc.strerror or str(exc)).lower()
    if reason is None:
        return folder
    print(f"stairbounce: warning: cannot use the cache {folder} ({reason}): computing without it",
          file=sys.stderr)
    return None
