"""A real staircase on the command line: ``--speed U --step-height a
--step-length b [--g 9.81]`` (SI units) instead of the paper's ``--u``.

The paper's normalised units (Section 1) set ``a = b = g = 1``; a staircase
in metres maps to ``u = U sqrt(a/g) / b`` (:func:`stairbounce.normalized_speed`),
heights scale by ``a``, horizontal lengths by ``b``, time by ``sqrt(a/g)`` and
vertical velocities by ``sqrt(a g)``.  Commands take exactly one of ``--u``
and the physical set; they print both descriptions of the staircase.
"""

from __future__ import annotations

import math
from typing import Annotated, Optional

import typer

from ..units import Staircase
from ._app import CLIError, parse_range

SPEED_HELP = "Horizontal speed of the ball in m/s (with --step-height and --step-length; instead of --u)."
HEIGHT_HELP = "Step height a in metres (with --speed)."
LENGTH_HELP = "Step length b in metres (with --speed)."
G_HELP = "Gravity in m/s^2 (with --speed; default 9.81)."


E_HELP = "Restitution coefficient, in [0, 1)."
U_HELP = "Horizontal speed in normalised units (u > 0). Or --speed with --step-height, --step-length."

# The options the model's commands share, defined once as parameter types
# (``speed: st.Speed = None``; Typer reads the option from the annotation,
# the default from the parameter).
E = Annotated[Optional[float], typer.Option("--e", help=E_HELP)]
U = Annotated[Optional[float], typer.Option("--u", help=U_HELP)]
Speed = Annotated[Optional[float], typer.Option("--speed", help=SPEED_HELP)]
StepHeight = Annotated[Optional[float], typer.Option("--step-height", help=HEIGHT_HELP)]
StepLength = Annotated[Optional[float], typer.Option("--step-length", help=LENGTH_HELP)]
G = Annotated[Optional[float], typer.Option("--g", help=G_HELP)]
Y0 = Annotated[float, typer.Option("--y0", help="Initial height above the step's floor (>= 0).")]
V0 = Annotated[float, typer.Option("--v0", help="Initial vertical velocity.")]


def speed_option(help=SPEED_HELP):
    """--speed with its own help: a window or a number or range (a string)."""
    return typer.Option(None, "--speed", help=help)


def _number(name: str, value) -> float | None:
    if value is None:
        return None
    x = float(value)
    if not math.isfinite(x) or x <= 0.0:
        raise CLIError(f"--{name} must be a finite number > 0, got {value!r}")
    return x


def _staircase(speed, step_height, step_length, g, u):
    """Check the combination; the :class:`Staircase` or None when ``--u`` is used."""
    physical = {"--speed": speed, "--step-height": step_height, "--step-length": step_length, "--g": g}
    given = [name for name, value in physical.items() if value is not None]
    if u is not None and given:
        raise CLIError(
            f"give either --u or --speed with --step-height and --step-length, not both "
            f"(got --u and {', '.join(given)})"
        )
    if u is None and speed is None:
        if given:
            raise CLIError(f"{', '.join(given)} needs --speed (the ball's horizontal speed in m/s)")
        raise CLIError("give the horizontal speed: --u (normalised) or --speed with --step-height "
                       "and --step-length (m/s, m)")
    if u is not None:
        return None
    missing = [name for name in ("--step-height", "--step-length") if physical[name] is None]
    if missing:
        raise CLIError(f"--speed needs {' and '.join(missing)} (in metres)")
    return Staircase(_number("step-height", step_height), _number("step-length", step_length),
                     9.81 if g is None else _number("g", g))


def resolve_u(u, speed, step_height, step_length, g):
    """``(u, staircase)`` from exactly one of ``--u`` or the physical set.

    ``staircase`` is None when ``--u`` was given.  Raises :class:`CLIError`
    (one line, exit status 2) on a missing, mixed or non-positive value.
    """
    stairs = _staircase(speed, step_height, step_length, g, u)
    if stairs is None:
        return u, None
    return stairs.to_u(_number("speed", speed)), stairs


def resolve_u_text(u, speed, step_height, step_length, g):
    """As :func:`resolve_u` for options that take a number or a range ``MIN:MAX``:
    returns the ``--u`` text (normalised; a range maps to a range, the
    conversion being linear) and the staircase or None."""
    stairs = _staircase(speed, step_height, step_length, g, u)
    if stairs is None:
        return u, None
    if ":" in speed:
        lo, hi = parse_range("speed", speed)
        return f"{stairs.to_u(_number('speed', lo))!r}:{stairs.to_u(_number('speed', hi))!r}", stairs
    try:
        value = float(speed)
    except ValueError:
        raise CLIError(f"--speed must be a number or a range MIN:MAX in m/s, got {speed!r}") from None
    return repr(stairs.to_u(_number("speed", value))), stairs


def describe(u: float, stairs: Staircase | None) -> str:
    """One line: the speed in both units (only ``u`` without a staircase)."""
    if stairs is None:
        return f"u = {u:g}"
    return (f"speed U = {stairs.to_speed(u):g} m/s on {stairs.describe()}: u = U sqrt(a/g) / b = {u:.6g} "
            f"(one step takes {stairs.step_length / stairs.to_speed(u):.4g} s)")
