"""The Typer application and the helpers every command shares.

Commands live in sibling modules (one per part of the package) and register
themselves on ``app``; :func:`stairbounce.cli.main` turns bad input into one
line on stderr and exit status 2.
"""

from __future__ import annotations

import math
import threading
from pathlib import Path

import typer

app = typer.Typer(
    name="stairbounce",
    help="A ball bouncing down a staircase: Poincare map, sliding solutions, "
    "the fractal of periodic sliding solutions in the (e, u) plane.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


class CLIError(Exception):
    """Bad input from the command line: printed as one line, exit status 2."""


# Set by the Ctrl-C handler of :func:`stairbounce.cli.main`: long loops check it
# (a KeyboardInterrupt raised inside a finaliser is lost, this record is not).
INTERRUPTED = threading.Event()

FORCE_HELP = "Replace output files that exist (never a folder stairbounce did not write)."


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
    parts = text.lower().split("x")
    try:
        w, h = (int(p) for p in parts)
    except ValueError:
        raise CLIError(f"--size must be WIDTHxHEIGHT in pixels, e.g. 500x350, got {text!r}") from None
    if w < 1 or h < 1:
        raise CLIError(f"--size must have WIDTH >= 1 and HEIGHT >= 1, got {text!r}")
    return w, h
