"""The ``stairbounce`` command line (Typer): parse, call the library, print.

Every command turns bad input into one line on stderr and exit status 2, never
a traceback: a ``ValueError`` from the library, an unwritable or full
destination (``OSError``), a request too large for the memory
(``MemoryError``), an image too large to decode.  Ctrl-C stops with status 130
and leaves no half-written file; output closed early (``... | head``) ends
quietly, as Unix tools do.
"""

from __future__ import annotations

import errno
import os
import signal
import sys
import warnings

import typer

from . import figures_commands  # noqa: F401  (registers figures, the main job)
from . import fractal_commands  # noqa: F401  (registers dimension)
from . import model_commands  # noqa: F401  (registers word, map, trajectory)
from . import orbits_commands  # noqa: F401  (registers orbit-diagram)
from . import scan_commands  # noqa: F401  (registers scan)
from . import explore_commands  # noqa: F401  (registers explore)
from . import atlas_commands  # noqa: F401  (registers render; scan --tile calls into it)
from . import motion_commands  # noqa: F401  (registers motion; scan --field k_mean calls into it)
from . import cache_commands  # noqa: F401  (registers cache info|clear)
from . import borders_commands  # noqa: F401  (registers borders, words)
from . import cascade_commands  # noqa: F401  (registers cascade)
from . import certify_commands  # noqa: F401  (registers certify)
from ._app import CLIError, INTERRUPTED, app

__all__ = ["app", "main", "console"]

# exit status of a process whose output pipe was closed (128 + SIGPIPE), as a
# shell reports for `yes | head -1`
EXIT_PIPE = 141


def main(argv: list[str] | None = None) -> None:
    """Entry point of the ``stairbounce`` console script."""
    INTERRUPTED.clear()
    previous = _catch_sigint()
    said = warnings.catch_warnings()
    said.__enter__()
    warnings.showwarning = _one_line_warning
    try:
        code = app(args=argv, prog_name="stairbounce", standalone_mode=False)
        try:
            sys.stdout.flush()  # a full or closed stdout is reported here, not at exit
        except OSError as exc:
            exc.filename = exc.filename or "the standard output"
            raise
    except (KeyboardInterrupt, typer.Abort):
        _interrupted()
    except SystemExit as exc:
        # click ends a command whose stdout pipe closed with status 1 and wraps
        # stdout so that nothing more is written: report it as a closed pipe
        if exc.code == 1 and type(sys.stdout).__name__ == "PacifyFlushWrapper":
            _quiet_stdout()
            raise SystemExit(EXIT_PIPE) from None
        raise
    except BrokenPipeError:
        _quiet_stdout()
        raise SystemExit(EXIT_PIPE) from None
    except (CLIError, ValueError) as exc:
        _fail(str(exc))
    except MemoryError as exc:
        detail = f" ({' '.join(str(exc).split())})" if str(exc).strip() else ""
        _fail(f"not enough memory for this request{detail}: ask for less (a smaller size, dpi or count)")
    except OSError as exc:
        if exc.errno == errno.EPIPE:
            _quiet_stdout()
            raise SystemExit(EXIT_PIPE) from None
        _fail(_os_message(exc))
    except Exception as exc:
        if type(exc).__name__ == "DecompressionBombError":  # PIL: a huge image
            _fail(f"image too large to read safely: {exc}")
        # usage errors of Typer's (vendored or not) click: bad option, missing value
        if hasattr(exc, "format_message") and hasattr(exc, "exit_code"):
            if not exc.format_message():  # bare command: the help was shown
                raise SystemExit(exc.exit_code) from None
            _fail(exc.format_message())
        raise
    finally:
        said.__exit__(None, None, None)
        _restore_sigint(previous)
    if INTERRUPTED.is_set():
        # Ctrl-C landed where Python could not raise it (a finaliser): the
        # command finished, but the user asked it to stop
        _interrupted()
    raise SystemExit(code if isinstance(code, int) else 0)


def console() -> None:
    """The ``stairbounce`` console script: :func:`main`, then the process ends at once.

    Python's own shutdown of a process that has loaded numba, xarray and the
    kernels' thread pool takes about 0.45 s (measured: 0.013 s with
    ``os._exit``), which a Ctrl-C would wait for (issue 45: within 0.5 s).  By
    the time :func:`main` returns or raises, every file the command wrote is
    complete and renamed or removed (``_atomic``, the stores' ``finally``
    blocks) and every cluster it started is closed, so only the standard
    streams are left to flush: they are flushed here, then ``os._exit`` ends
    the process with main's status.  ``main`` itself (called in-process by the
    tests) exits normally.
    """
    try:
        main()
        code = 0
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
        if not isinstance(exc.code, (int, type(None))):
            print(exc.code, file=sys.stderr)
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe: main has reported it already
            pass
    os._exit(code)


def _one_line_warning(message, category, filename, lineno, file=None, line=None):
    """Warnings (a damaged tile recomputed, a cache that cannot be written) as one line."""
    try:
        print(f"stairbounce: warning: {' '.join(str(message).split())}", file=sys.stderr)
    except (OSError, ValueError):  # pragma: no cover - stderr closed
        pass


def _catch_sigint():
    """Record every Ctrl-C (besides raising KeyboardInterrupt): an interrupt
    raised inside a finaliser is swallowed by Python, the record is not."""
    import threading

    if threading.current_thread() is not threading.main_thread():
        return None

    def handler(signum, frame):
        INTERRUPTED.set()
        raise KeyboardInterrupt

    try:
        previous = signal.getsignal(signal.SIGINT)
        if previous is signal.SIG_IGN:
            return None  # started in the background with Ctrl-C ignored: keep it so
        signal.signal(signal.SIGINT, handler)
        return previous
    except (ValueError, OSError):  # pragma: no cover - no signals here
        return None


def _restore_sigint(previous):
    if previous is not None:
        try:
            signal.signal(signal.SIGINT, previous)
        except (ValueError, OSError):  # pragma: no cover
            pass


def _interrupted():
    print("stairbounce: interrupted", file=sys.stderr)
    raise SystemExit(130)


def _quiet_stdout():
    """Point stdout at /dev/null so that the flush at exit does not fail again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):
        pass


def _os_message(exc: OSError) -> str:
    if exc.errno in (errno.ENOSPC, errno.EDQUOT, errno.EFBIG):
        _quiet_stdout()
    what = exc.strerror or str(exc) or type(exc).__name__
    name = exc.filename if exc.filename is not None else None
    if name is None and exc.errno in (errno.ENOSPC, errno.EDQUOT):
        return f"cannot write the output: {what.lower()}"
    return f"cannot write {name}: {what.lower()}" if name is not None else f"{what}"


def _fail(message: str) -> None:
    first = " ".join(str(message).split())
    print(f"stairbounce: error: {first}", file=sys.stderr)
    raise SystemExit(2)
