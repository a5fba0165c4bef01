"""Progress of long work, in a terminal or not: the one helper behind every
command's progress bar and :func:`stairbounce.progress_bar`.

In a terminal (or a Jupyter cell) a rich progress bar is drawn; anywhere else
(a log, ``nohup``, CI, a subprocess) one line is written every
``STAIRBOUNCE_PROGRESS_INTERVAL`` seconds (default 10) while the work runs, so
that a long command is never silent.  rich is imported only when a bar is
made: the core imports no display code (tests/test_architecture.py).
"""

from __future__ import annotations

import os
import threading
import time
from contextlib import contextmanager
from typing import Any

# seconds between two lines when the output is not a terminal
DEFAULT_INTERVAL = 10.0
INTERVAL_VARIABLE = "STAIRBOUNCE_PROGRESS_INTERVAL"


def log_interval() -> float:
    """Seconds between progress lines off a terminal: ``$STAIRBOUNCE_PROGRESS_INTERVAL``
    (a positive number) or 10."""
    text = os.environ.get(INTERVAL_VARIABLE, "")
    try:
        value = float(text)
    except ValueError:
        return DEFAULT_INTERVAL
    return value if value > 0 else DEFAULT_INTERVAL


def _duration(seconds: float) -> str:
    seconds = max(0.0, seconds)
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.1f} min"
    return f"{seconds / 3600:.1f} h"


class LineProgress:
    """The part of ``rich.progress.Progress`` the commands use (``add_task``,
    ``update``, ``advance``), written as one line every ``interval`` seconds
    to ``stream`` by a background thread: ``PREFIX DESCRIPTION: DONE/TOTAL
    UNIT (P%), T elapsed, about R left``.  Nothing is written by work shorter
    than one interval."""

    def __init__(self, stream, interval: float, unit: str = "", prefix: str = "stairbounce: "):
        self.stream, self.interval, self.unit, self.prefix = stream, interval, unit, prefix
        self.tasks: dict[int, dict[str, Any]] = {}
        self.lines = 0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._t0 = time.monotonic()

    def add_task(self, description, total=None, completed=0, **_):
        key = len(self.tasks)
        self.tasks[key] = dict(description=description, total=total, completed=completed)
        return key

    def update(self, task, *, completed=None, total=None, description=None, advance=None, **_):
        t = self.tasks[task]
        if total is not None:
            t["total"] = total
        if completed is not None:
            t["completed"] = completed
        if advance is not None:
            t["completed"] += advance
        if description is not None:
            t["description"] = description

    def advance(self, task, advance=1):
        self.tasks[task]["completed"] += advance

    def line(self) -> str:
        """The line for the latest task's state now."""
        t: dict[str, Any] = (self.tasks[max(self.tasks)] if self.tasks
                             else dict(description="working", total=None, completed=0))
        elapsed = time.monotonic() - self._t0
        done, total = t["completed"], t["total"]
        unit = f" {self.unit}" if self.unit else ""
        if total:
            frac = min(max(done / total, 0.0), 1.0)
            text = f"{done:g}/{total:g}{unit} ({100 * frac:.0f}%), {_duration(elapsed)} elapsed"
            if 0 < frac < 1:
                text += f", about {_duration(elapsed * (1 - frac) / frac)} left"
        else:
            text = f"{done:g}{unit} done, {_duration(elapsed)} elapsed"
        return f"{self.prefix}{t['description']}: {text}"

    def _run(self):
        while not self._stop.wait(self.interval):
            try:
                print(self.line(), file=self.stream, flush=True)
                self.lines += 1
            except (OSError, ValueError):  # the stream was closed: stop quietly
                return

    def start(self):
        self._t0 = time.monotonic()
        self._thread = threading.Thread(target=self._run, name="stairbounce-progress", daemon=True)
        self._thread.start()

    def stop(self):
        self._stop.set()
        if self._thread is not None:
            self._thread.join()

    def __enter__(self):
        self.start()
        return self

    def __exit__(self, *exc):
        self.stop()
        return False


def _has_widgets() -> bool:
    """rich draws a bar in a notebook only with ipywidgets; without it, lines."""
    import importlib.util

    return importlib.util.find_spec("ipywidgets") is not None


def make_display(description, total=None, unit="", console=None):
    """``(bar, task)``, not started (``bar.start()``, ``bar.stop()``): a
    transient rich bar on ``console`` (default stderr) when it is a terminal
    or a Jupyter cell with ipywidgets, else a :class:`LineProgress` on its stream (one line
    every :func:`log_interval` seconds)."""
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    console = console or Console(stderr=True)
    if console.is_terminal or (console.is_jupyter and _has_widgets()):
        bar = Progress(
            TextColumn("[bold]{task.description}"), BarColumn(),
            TextColumn("{task.completed}/{task.total}" + (f" {unit}" if unit else "")),
            TimeElapsedColumn(), TimeRemainingColumn(), console=console, transient=True,
        )
    else:
        bar = LineProgress(console.file, log_interval(), unit)
    return bar, bar.add_task(description, total=total)


@contextmanager
def progress_display(description, total=None, unit="", console=None):
    """:func:`make_display`, started for the ``with`` block: ``(bar, task)``."""
    bar, task = make_display(description, total, unit, console)
    with bar:
        yield bar, task


@contextmanager
def progress_bar(description="working", unit=""):
    """progress_bar(description="working", unit="") -> context manager giving progress(done, total)

    A ready-made ``progress=`` callback for the long functions (:func:`scan`,
    :func:`border_points`, :func:`word_table`, :func:`window_regions`,
    :func:`perimeter_dimension`, :func:`motion_scan`, :func:`scan_to_zarr`,
    ...): a progress bar with the time left in a terminal or a Jupyter
    notebook with ipywidgets (rich, as the command line draws it), and one
    line every 10 s on stderr anywhere else (a log, ``nohup``; the interval is
    ``$STAIRBOUNCE_PROGRESS_INTERVAL`` seconds).  The callback takes the
    function's ``(done, total)``; a total of 0 shows as 0/1.

    >>> import stairbounce as sb
    >>> with sb.progress_bar("scan rows") as progress:
    ...     ds = sb.scan(e=(0.04, 0.065, 64), u=(0.92, 0.945, 64), progress=progress)
    >>> ds.sizes["u"]
    64

    Any other display takes the same two numbers; with tqdm, for instance:
    ``bar = tqdm(); progress = lambda done, total: (setattr(bar, "total", total),
    bar.update(done - bar.n))``.
    """
    with progress_display(description, None, unit) as (bar, task):
        def progress(done, total):
            bar.update(task, completed=done, total=max(total, 1))

        yield progress

