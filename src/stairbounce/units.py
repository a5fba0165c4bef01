"""Physical units <-> the paper's normalised units.

The paper rescales a staircase of step height ``a``, step length ``b`` and
gravity ``g`` to ``a = b = g = 1`` (Section 1): lengths vertically by ``a``,
horizontally by ``b``, time by ``sqrt(a/g)``.  A horizontal speed ``U`` becomes
``u = U sqrt(a/g) / b``; vertical velocities scale by ``sqrt(a g)``.  The
restitution coefficient is dimensionless and unchanged.
"""

from __future__ import annotations

import math

from . import _validate as _v
from .model import check_u

__all__ = ["normalized_speed", "physical_speed", "time_scale"]

# Physical inputs are bounded so that products and quotients of three of them
# stay far inside the float range (report D5: 5e-324 gave inf or ZeroDivisionError)
_PHYS_MIN = 1e-100
_PHYS_MAX = 1e100


def _positive(name, x):
    x = _v.real(name, x)
    if not x > 0.0:
        raise ValueError(f"{name} must be > 0, got {x}")
    if not _PHYS_MIN <= x <= _PHYS_MAX:
        raise ValueError(f"{name} must be in [{_PHYS_MIN:g}, {_PHYS_MAX:g}], got {x}")
    return x


def time_scale(step_height, g=9.81):
    """time_scale(step_height, g=9.81) -> float

    Seconds per normalised time unit, ``sqrt(a / g)``.

    Parameters ``step_height`` (m) and ``g`` (m/s^2) in [1e-100, 1e100].
    """
    return math.sqrt(_positive("step_height", step_height) / _positive("g", g))


def normalized_speed(speed, step_height, step_length, g=9.81):
    """normalized_speed(speed, step_height, step_length, g=9.81) -> float

    The paper's ``u`` for a ball moving at ``speed`` (m/s) over steps of height
    ``a`` and length ``b`` (m): ``u = U sqrt(a/g) / b``.  Every input in
    [1e-100, 1e100]; a result outside the map's range [1e-150, 1e150] is refused.
    """
    speed = _positive("speed", speed)
    u = speed * time_scale(step_height, g) / _positive("step_length", step_length)
    if not _v.U_MIN <= u <= _v.U_MAX:
        raise ValueError(
            f"speed, step_height, step_length and g give u = {u:g}, outside the valid "
            f"range [{_v.U_MIN:g}, {_v.U_MAX:g}] of the horizontal speed"
        )
    return u


def physical_speed(u, step_height, step_length, g=9.81):
    """physical_speed(u, step_height, step_length, g=9.81) -> float

    Inverse of :func:`normalized_speed`: ``U = u b / sqrt(a/g)`` in m/s, for
    ``u`` in [1e-150, 1e150] and the physical inputs in [1e-100, 1e100]; a
    speed outside [1e-300, 1e300] is refused.
    """
    u = check_u(u)
    # u b and sqrt(a/g) are each within 1e-250..1e250: the quotient may not be
    speed = u * _positive("step_length", step_length) / time_scale(step_height, g)
    if not 1e-300 <= speed <= 1e300:
        raise ValueError(
            "u, step_length, step_height and g give a speed of about 1e"
            f"{math.log10(u) + math.log10(step_length) - math.log10(time_scale(step_height, g)):.0f}"
            " m/s, outside the float range [1e-300, 1e300]"
        )
    return speed
