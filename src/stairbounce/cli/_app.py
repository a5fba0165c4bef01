"""The Typer application and the helpers every command shares.

Commands live in sibling modules (one per part of the package) and register
themselves on ``app``; :func:`stairbounce.cli.main` turns bad input into one
line on stderr and exit status 2.
"""

from __future__ import annotations

import math
from contextlib import contextmanager
import threading
from pathlib import Path
from typing import Annotated, Optional

import typer

app = typer.Typer(
    name="stairbounce",
    help="A ball bouncing down a staircase: Poincare map, sliding solutions, "
    "the fractal of periodic sliding solutions in the (e, u) plane.  "
    "A window MIN:MAX of e, u or --speed means the same in every command: the edges "
    "of the interval, cut into equal cells (pixels, or the --n values of orbit-diagram) "
    "sampled at their centres, so MIN and MAX themselves are never used (e = 1 and "
    "u = 0 may be edges).  Without --size, pixels are square: 500 along the longer "
    "side of the window (the default window keeps the paper's 500x350 grid).  The "
    "step limit is --max-iter everywhere.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    # plain click help: Typer's rich help shows every flag with a "<bool>"
    # value it does not take
    rich_markup_mode=None,
)


def _print_version(value: bool) -> None:
    if value:
        from .._version import __version__

        typer.echo(f"stairbounce {__version__}")
        raise typer.Exit()


@app.callback()
def _main_options(
    version: bool = typer.Option(False, "--version", callback=_print_version, is_eager=True,
                                 help="Print the version and exit."),
) -> None:
    """The options of ``stairbounce`` itself (before any command)."""


class CLIError(Exception):
    """Bad input from the command line: printed as one line, exit status 2."""


# Set by the Ctrl-C handler of :func:`stairbounce.cli.main`: long loops check it
# (a KeyboardInterrupt raised inside a finaliser is lost, this record is not).
INTERRUPTED = threading.Event()

FORCE_HELP = "Replace output files that exist (never a folder stairbounce did not write)."

# Options several commands share, defined once as parameter types: the option
# comes from the annotation, the default from the parameter (``dpi: Dpi = 150``).
Dpi = Annotated[int, typer.Option("--dpi", help="Resolution of raster output (10-1200).")]
Force = Annotated[bool, typer.Option("--force", help=FORCE_HELP)]
MaxIter = Annotated[int, typer.Option("--max-iter", help="Steps allowed before giving up (>= 1).")]


def check_interrupted():
    """Raise KeyboardInterrupt if Ctrl-C was pressed since the command started."""
    if INTERRUPTED.is_set():
        raise KeyboardInterrupt


def check_dpi(dpi: int, option: str = "--dpi") -> int:
    """Every command takes a dpi in [10, 1200] (a 100000 dpi figure does not fit in memory)."""
    if not (10 <= dpi <= 1200):
        raise CLIError(f"{option} must be in [10, 1200], got {dpi}")
    return dpi


def check_outputs(force: bool, **paths) -> None:
    """Check every output path before any work: its folder exists and takes a
    new file, and an existing file is replaced only with ``--force`` (a folder
    only when it is one of our stores).  ``paths``: option name (``png``,
    ``out``) -> Path or None."""
    from .._io import check_output

    for option, path in paths.items():
        if path is not None:
            check_output(Path(path), overwrite=force, option="--" + option.replace("_", "-"))


def save_figure(fig, path, dpi: int, overwrite: bool = False) -> None:
    """Write a matplotlib Figure to ``path`` atomically (under a temporary
    name, renamed when complete; the format from the suffix) and close it,
    whether the write succeeds or not."""
    import matplotlib.pyplot as plt

    from .._io import atomic_path

    try:
        with atomic_path(path, overwrite=overwrite) as tmp:
            fig.savefig(tmp, dpi=dpi)
    finally:
        plt.close(fig)


def draw_scan(ds, field, overlays, png, dpi, overwrite=False) -> None:
    """Draw ``field`` of a scan dataset (in memory) with
    :func:`stairbounce.plot.plot_scan` and the ``overlays`` into ``png``:
    what ``scan --png`` and ``render`` write."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..plot import plot_scan

    fig, ax = plt.subplots(figsize=(8, 6))
    plot_scan(ds, field=field, ax=ax, overlay=overlays)
    fig.tight_layout()
    save_figure(fig, png, dpi, overwrite)


def parse_range(name: str, text: str) -> tuple[float, float]:
    """``"0:1.5"`` -> ``(0.0, 1.5)``, with ``min < max`` and both finite."""
    parts = text.split(":")
    if len(parts) != 2:
        raise CLIError(f"--{name} must be a range MIN:MAX, got {text!r}")
    try:
        lo, hi = float(parts[0]), float(parts[1])
    except ValueError:
        raise CLIError(f"--{name} must be a range MIN:MAX of numbers, got {text!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise CLIError(f"--{name} must be a finite range, got {text!r}")
    if not lo < hi:
        raise CLIError(f"--{name} must have MIN < MAX, got {text!r}")
    return lo, hi


def parse_size(text: str) -> tuple[int, int]:
    """``"500x350"`` -> ``(500, 350)`` (width along e, height along u), both >= 1."""
    from .._validate import size_text

    wh = size_text(text)
    if wh is None:
        raise CLIError(f"--size must be WIDTHxHEIGHT in pixels, e.g. 500x350, got {text!r}")
    w, h = wh
    if w < 1 or h < 1:
        raise CLIError(f"--size must have WIDTH >= 1 and HEIGHT >= 1, got {text!r}")
    return w, h


def renamed_option(old: str, old_value, new: str, new_value, default):
    """The value of an option renamed from ``old`` to ``new``: ``old_value``
    (None when not given) is still taken, with a one-line warning on stderr;
    both given (the new one not at its default) is an error."""
    if old_value is None:
        return new_value
    typer.echo(f"stairbounce: warning: {old} is deprecated: use {new}", err=True)
    if new_value != default:
        raise CLIError(f"{old} is the deprecated name of {new}: give {new} only")
    return old_value


# the default window of scan, borders and words (the paper's Fig. 4) and its grid
DEFAULT_E, DEFAULT_U, DEFAULT_SIZE = "0:1", "0:1.5", (500, 350)
SIZE_HELP = ("Pixels WIDTHxHEIGHT (along e x along u); default square pixels, 500 along the longer side "
             "of the window (500x350, the paper's Fig. 4 grid, for the default window).")
Size = Annotated[Optional[str], typer.Option("--size", help=SIZE_HELP)]


def window_size(size, e, u, default_window: bool) -> tuple[int, int]:
    """``--size`` or, when not given, the pixel counts of the window
    ``e = (lo, hi)``, ``u = (lo, hi)``: square pixels, 500 along the longer
    side (:func:`stairbounce.plane.square_counts`); the default window
    (``default_window``: neither --e, --u nor --speed given) keeps the paper's
    500 x 350 grid."""
    if size is not None:
        return parse_size(size)
    if default_window:
        return DEFAULT_SIZE
    from ..plane import square_counts

    return square_counts(e, u)


def perimeter_lines(r, extra=()) -> list[str]:
    """The lines printing a perimeter bracket ``r`` (``CertifiedAtlas.perimeter_bracket``'s
    or ``CertifiedStore.perimeter_bracket``'s dict): its counts per scale, the slope
    brackets, ``extra`` lines, then its basis and what it does not prove."""
    refined = "" if r.get("focus") is None else f" refined for k <= {r['focus']}"
    lines = [f"proven box counts of the sliding border (basis: {r['basis']}, certify depth {r['depth']}{refined}, "
             f"max_iter {r['max_iter']}): closed cells of side window/2^k meeting the border of the region "
             "sliding within max_iter"]
    lines += [f"  k = {k:2d}  window/{1 << k:<7d} lower {lo:>9,}  upper {up:>9,}"
              for k, lo, up in zip(r["k"], r["lower"], r["upper"])]
    lines += [f"  slope {r['slope_text']}", f"  narrowest between two scales with lower counts > 0: {r['finite_text']}"]
    if r.get("witnesses"):
        lines.append(f"  lower counts with {r['witnesses']:,} proven points inside undecided boxes "
                     f"({r['witnesses_tried']:,} certified)")
    return lines + list(extra) + [f"  {r['basis']}: {r['proof']}", f"  not proven: {r['not_proven']}"]


def plural(n: int, word: str, many: str | None = None) -> str:
    """``plural(1, "tile")`` -> "1 tile", ``plural(3, "tile")`` -> "3 tiles"."""
    return f"{n} {word if n == 1 else (many or word + 's')}"


@contextmanager
def progress_bar(console, description, total, unit=""):
    """A transient progress bar on ``console`` (stderr): ``(bar, task)``.

    When stderr is not a terminal (a log, ``nohup``, a notebook's ``!``
    command) no bar is drawn; one line is written every 10 s instead
    (``$STAIRBOUNCE_PROGRESS_INTERVAL`` seconds; :mod:`stairbounce._progress`,
    the same for every command).  The calls on ``bar`` work either way."""
    from .._progress import progress_display

    with progress_display(description, total, unit, console) as (bar, task):
        yield bar, task


def with_row_progress(run, description, rows):
    """``run(progress)`` behind a progress bar over ``rows`` on stderr (lines
    every 10 s when stderr is not a terminal): the in-memory scans, which call
    ``progress(done, total)`` after each block of rows."""
    from rich.console import Console

    with progress_bar(Console(stderr=True), description, rows) as (bar, task):
        # a run may report that it has nothing to do (total 0): the bar shows 0/1
        return run(lambda done, total: bar.update(task, completed=done, total=max(total, 1)))


def parse_overlays(values, allowed) -> tuple[str, ...]:
    """``--overlay`` as every command takes it: a comma-separated list, or the
    option repeated, or both (``--overlay tongues,bound`` = ``--overlay
    tongues --overlay bound``); each name one of ``allowed``."""
    if isinstance(values, str):
        values = [values]
    names = []
    for text in values or ():
        for part in str(text).split(","):
            part = part.strip()
            if not part:
                continue
            if part not in allowed:
                raise CLIError(f"--overlay must be among {', '.join(allowed)} (comma-separated "
                               f"or repeated), got {part!r}")
            if part not in names:
                names.append(part)
    return tuple(names)


def tile_for_workers(n_e: int, n_u: int, workers: int, largest: int = 1024, smallest: int = 64):
    """tile_for_workers(n_e, n_u, workers) -> (tile, tiles)

    The largest square tile (a power of two from ``largest`` down to
    ``smallest`` px) that cuts an ``n_e x n_u`` grid into at least
    ``2 * workers`` tiles, so that every worker has work and a slow tile
    (high u runs all max_iter steps) can be balanced by two quick ones.
    Below ``smallest`` px the per-tile overhead would cost more than the
    parallelism gains; then fewer tiles than workers may result."""
    tile = largest
    while True:
        tiles = math.ceil(n_e / tile) * math.ceil(n_u / tile)
        if tiles >= 2 * workers or tile // 2 < smallest:
            return tile, tiles
        tile //= 2
