"""The ``stairbounce`` command line (Typer): parse, call the library, print.

Every command turns bad input into one line on stderr and exit status 2, never
a traceback; Ctrl-C stops with status 130 and leaves no half-written file.
"""

from __future__ import annotations

import sys

import typer

from . import figures_commands  # noqa: F401  (registers figures, the main job)
from . import fractal_commands  # noqa: F401  (registers dimension)
from . import model_commands  # noqa: F401  (registers word, map, trajectory)
from . import orbits_commands  # noqa: F401  (registers orbit-diagram)
from . import scan_commands  # noqa: F401  (registers scan)
from . import explore_commands  # noqa: F401  (registers explore)
from . import atlas_commands  # noqa: F401  (registers render; scan --tile calls into it)
from . import motion_commands  # noqa: F401  (registers motion; scan --field k_mean calls into it)
from ._app import CLIError, app

__all__ = ["app", "main"]


def main(argv: list[str] | None = None) -> None:
    """Entry point of the ``stairbounce`` console script."""
    try:
        code = app(args=argv, prog_name="stairbounce", standalone_mode=False)
    except (KeyboardInterrupt, typer.Abort):
        print("stairbounce: interrupted", file=sys.stderr)
        raise SystemExit(130) from None
    except (CLIError, ValueError) as exc:
        _fail(str(exc))
    except Exception as exc:
        # usage errors of Typer's (vendored or not) click: bad option, missing value
        if hasattr(exc, "format_message") and hasattr(exc, "exit_code"):
            if not exc.format_message():  # bare command: the help was shown
                raise SystemExit(exc.exit_code) from None
            _fail(exc.format_message())
        raise
    raise SystemExit(code if isinstance(code, int) else 0)


def _fail(message: str) -> None:
    first = " ".join(str(message).split())
    print(f"stairbounce: error: {first}", file=sys.stderr)
    raise SystemExit(2)
