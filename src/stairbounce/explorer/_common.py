"""What the explorer's page and its layers share: plurals, the progress pace, the borders' key,
the check of a finished job's answer."""

from __future__ import annotations

from .view import border_grid


def _plural(n, word):
    return f"{n} {word}" if n == 1 else f"{n} {word}s"


# least time between two "tracing borders: N of M words" lines sent to the page (s)
_TRACE_PROGRESS_EVERY = 0.25


def _border_key(view):
    """What the exact borders of a view depend on: their grid and max_iter."""
    return border_grid(view), view.max_iter



def _answer_stands(gen, current, error, message, what):
    """Whether a background job's answer is to be shown: not when a later
    request replaced it (``gen`` is not ``current``), nor when it failed, which
    ``message`` says as an error line ``"<what> failed: <error>"``."""
    if gen != current:
        return False
    if error is not None:
        message(f"{what} failed: {error}", "error")
        return False
    return True
