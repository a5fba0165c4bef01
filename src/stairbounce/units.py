"""Physical units <-> the paper's normalised units.

The paper rescales a staircase of step height ``a``, step length ``b`` and
gravity ``g`` to ``a = b = g = 1`` (Section 1): lengths vertically by ``a``,
horizontally by ``b``, time by ``sqrt(a/g)``.  A horizontal speed ``U`` becomes
``u = U sqrt(a/g) / b``; vertical velocities scale by ``sqrt(a g)``.  The
restitution coefficient is dimensionless and unchanged.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import _validate as _v
from .model import check_u

__all__ = ["Speed", "SpeedWindow", "Speeds", "Staircase", "normalized_speed", "physical_speed", "time_scale"]

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


# --------------------------------------------------------------------------- #
# A real staircase, as one object                                             #
# --------------------------------------------------------------------------- #


@dataclass(frozen=True, repr=False)
class Staircase:
    """Staircase(step_height, step_length, g=9.81): a real staircase in SI units.

    Converts speeds both ways (:meth:`to_u`, :meth:`to_speed`) and makes
    speeds in m/s that every function of the package takes where it takes a
    horizontal speed ``u`` (:meth:`speed`): a number (``sliding_word``,
    ``trajectory``, ``motion``, ``poincare_map``, ...), an array
    (``orbit_diagram``, ``scan_coords``, ``motion_coords``) or a window
    ``(lo, hi, n)`` (``scan``, ``motion_scan``).  Datasets computed over such
    speeds keep ``u`` as their dimension and add the coordinate ``speed`` in
    m/s and the attributes ``step_height``, ``step_length`` and ``g``; the
    plots then draw that axis in m/s (and heights in metres).

    >>> import stairbounce as sb
    >>> stairs = sb.Staircase(0.17, 0.28)
    >>> stairs
    Staircase(step_height=0.17 m, step_length=0.28 m, g=9.81 m/s^2)
    >>> round(stairs.to_u(1.5), 4), round(stairs.to_speed(0.7052), 3)
    (0.7052, 1.5)
    """

    step_height: float
    step_length: float
    g: float = 9.81

    def __post_init__(self):
        for name in ("step_height", "step_length", "g"):
            object.__setattr__(self, name, _positive(name, getattr(self, name)))

    def __repr__(self) -> str:
        return (f"Staircase(step_height={self.step_height:g} m, step_length={self.step_length:g} m, "
                f"g={self.g:g} m/s^2)")

    @property
    def time_unit(self) -> float:
        """Seconds per normalised time unit, ``sqrt(a/g)``."""
        return time_scale(self.step_height, self.g)

    @property
    def velocity_unit(self) -> float:
        """m/s per normalised vertical velocity, ``sqrt(a g)``."""
        return math.sqrt(self.step_height * self.g)

    @property
    def speed_unit(self) -> float:
        """m/s per normalised horizontal speed, ``b / sqrt(a/g)`` (``U = u`` times this)."""
        return self.step_length / self.time_unit

    def to_u(self, speed):
        """Normalised ``u`` of a speed in m/s (a number, or an array of them)
        (:func:`normalized_speed`)."""
        if np.ndim(speed) == 0:
            return normalized_speed(speed, self.step_height, self.step_length, self.g)
        return np.array([self.to_u(s) for s in _v.real_array("speed", speed).ravel()]).reshape(np.shape(speed))

    def to_speed(self, u):
        """Speed in m/s of a normalised ``u`` (a number, or an array of them)
        (:func:`physical_speed`)."""
        if np.ndim(u) == 0:
            return physical_speed(u, self.step_height, self.step_length, self.g)
        return np.array([self.to_speed(x) for x in _v.real_array("u", u).ravel()]).reshape(np.shape(u))

    def speed(self, lo, hi=None, n=None):
        """speed(U) -> Speed, speed(array) -> Speeds, speed(lo, hi, n) -> SpeedWindow

        A horizontal speed in m/s to pass wherever the package takes ``u``:
        one speed, an array of speeds, or a scan window whose image edges are
        ``lo`` and ``hi`` m/s with ``n`` pixels (the window's pixel centres
        are the same speeds either way: the conversion is linear).
        """
        if hi is None and n is None:
            if np.ndim(lo) == 0:
                return Speed(self, lo)
            return Speeds(self, lo)
        if hi is None or n is None:
            raise ValueError("speed window must be speed(lo, hi, n): edges in m/s and a pixel count")
        return SpeedWindow(self, lo, hi, n)

    def describe(self) -> str:
        """``steps a = 0.17 m high, b = 0.28 m long, g = 9.81 m/s^2``."""
        return f"steps a = {self.step_height:g} m high, b = {self.step_length:g} m long, g = {self.g:g} m/s^2"

    def attrs(self) -> dict:
        """The staircase as dataset attributes."""
        return {"step_height": self.step_height, "step_length": self.step_length, "g": self.g}

    @classmethod
    def from_attrs(cls, attrs):
        """The staircase a dataset's attributes record, or None."""
        if not all(k in attrs for k in ("step_height", "step_length", "g")):
            return None
        return cls(float(attrs["step_height"]), float(attrs["step_length"]), float(attrs["g"]))


class Speed(float):
    """A horizontal speed in m/s on a :class:`Staircase`; as a number it is the
    normalised ``u``, so it goes wherever ``u`` goes.  ``metres_per_second``
    and ``staircase`` say where it came from."""

    metres_per_second: float
    staircase: Staircase

    def __new__(cls, staircase, speed):
        speed = _positive("speed", speed)
        self = super().__new__(cls, staircase.to_u(speed))
        self.metres_per_second = speed
        self.staircase = staircase
        return self

    def __repr__(self) -> str:
        return f"Speed({self.metres_per_second:g} m/s: u = {float(self):.6g} on {self.staircase!r})"

    def __reduce__(self):
        return (Speed, (self.staircase, self.metres_per_second))


class Speeds(np.ndarray):
    """Horizontal speeds in m/s on a :class:`Staircase`; as an array they are
    the normalised ``u`` values (so they go wherever an array of ``u`` goes);
    ``metres_per_second`` and ``staircase`` say where they came from."""

    def __new__(cls, staircase, speeds):
        a = np.asarray(staircase.to_u(speeds), dtype=np.float64).view(cls)
        a.staircase = staircase
        return a

    def __array_finalize__(self, obj):
        self.staircase = getattr(obj, "staircase", None)

    @property
    def metres_per_second(self):
        return np.asarray(self) * self.staircase.speed_unit

    def __reduce__(self):
        return (Speeds, (self.staircase, self.metres_per_second))


class SpeedWindow(tuple):
    """A scan window ``(u_min, u_max, n)`` given in m/s on a :class:`Staircase`:
    as a tuple it is the normalised window, so :func:`stairbounce.scan` and
    :func:`stairbounce.motion_scan` take it as their ``u``."""

    metres_per_second: tuple[float, float]
    staircase: Staircase

    def __new__(cls, staircase, lo, hi, n):
        lo = _v.real("speed_min", lo)
        hi = _v.real("speed_max", hi)
        if not 0.0 <= lo < hi:
            raise ValueError(f"speed window must have 0 <= speed_min < speed_max (m/s), got [{lo}, {hi}]")
        u_lo = 0.0 if lo == 0.0 else staircase.to_u(lo)
        self = super().__new__(cls, (u_lo, staircase.to_u(hi), _v.count("n_speed", n, 1)))
        self.metres_per_second = (lo, hi)
        self.staircase = staircase
        return self

    def __repr__(self) -> str:
        lo, hi = self.metres_per_second
        return f"SpeedWindow({lo:g}..{hi:g} m/s, {self[2]} pixels: u = {self[0]:.6g}..{self[1]:.6g} on {self.staircase!r})"

    def __reduce__(self):
        return (SpeedWindow, (self.staircase, *self.metres_per_second, self[2]))


def staircase_of(u):
    """The :class:`Staircase` a speed argument was given on, or None for plain ``u``."""
    return u.staircase if isinstance(u, (Speed, Speeds, SpeedWindow)) else None


def with_speed(ds, staircase, dim="u"):
    """``ds`` with the coordinate ``speed`` (m/s) along ``dim`` and the staircase's
    attributes, when ``staircase`` is not None (the normalised ``u`` stays the
    dimension).  A dataset whose ``u`` is one number gets the attribute
    ``speed`` instead."""
    if staircase is None:
        return ds
    ds.attrs.update(staircase.attrs())
    speed_attrs = {"long_name": "horizontal speed U", "units": "m/s"}
    if dim in ds.dims:
        ds = ds.assign_coords(speed=(dim, np.asarray(ds[dim].values) * staircase.speed_unit, speed_attrs))
    elif dim in ds.attrs:
        ds.attrs["speed"] = float(ds.attrs[dim]) * staircase.speed_unit
    return ds
