"""What the explorer's page and its layers share: plurals, the progress pace, the borders' key."""

from __future__ import annotations

from .view import border_grid


def _plural(n, word):
    return f"{n} {word}" if n == 1 else f"{n} {word}s"


# least time between two "tracing borders: N of M words" lines sent to the page (s)
_TRACE_PROGRESS_EVERY = 0.25


def _border_key(view):
    """What the exact borders of a view depend on: their grid and max_iter."""
    return border_grid(view), view.max_iter

