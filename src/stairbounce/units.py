"""Physical units <-> the paper's normalised units.

The paper rescales a staircase of step height ``a``, step length ``b`` and
gravity ``g`` to ``a = b = g = 1`` (Section 1): lengths vertically by ``a``,
horizontally by ``b``, time by ``sqrt(a/g)``.  A horizontal speed ``U`` becomes
``u = U sqrt(a/g) / b``; vertical velocities scale by ``sqrt(a g)``.  The
restitution coefficient is dimensionless and unchanged.
"""

from __future__ import annotations

import math

from .model import _finite

__all__ = ["normalized_speed", "physical_speed", "time_scale"]


def _positive(name, x):
    x = _finite(name, x)
    if not x > 0.0:
        raise ValueError(f"{name} must be > 0, got {x}")
    return x


def time_scale(step_height, g=9.81):
    """time_scale(step_height, g=9.81) -> float

    Seconds per normalised time unit, ``sqrt(a / g)``.
    """
    return math.sqrt(_positive("step_height", step_height) / _positive("g", g))


def normalized_speed(speed, step_height, step_length, g=9.81):
    """normalized_speed(speed, step_height, step_length, g=9.81) -> float

    The paper's ``u`` for a ball moving at ``speed`` (m/s) over steps of height
    ``a`` and length ``b`` (m): ``u = U sqrt(a/g) / b``.
    """
    speed = _positive("speed", speed)
    return speed * time_scale(step_height, g) / _positive("step_length", step_length)


def physical_speed(u, step_height, step_length, g=9.81):
    """physical_speed(u, step_height, step_length, g=9.81) -> float

    Inverse of :func:`normalized_speed`: ``U = u b / sqrt(a/g)`` in m/s.
    """
    u = _positive("u", u)
    return u * _positive("step_length", step_length) / time_scale(step_height, g)
