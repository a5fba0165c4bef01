"""The exact continuous-time solution: flights, impacts, accumulation, sliding.

Coordinates: the ball starts at time 0 at the edge ``x = 0`` with height ``y0``
above the floor of step 0.  Step ``j`` covers ``j <= x < j + 1`` and its floor
is at height ``-j``; the horizontal motion is uniform, ``x = u t``.  Every step
is solved in closed form from its entry state (the Poincare iterates of
Prop. 2.3): a parabolic flight to the first impact, the impact times and
velocities of eq. (2.2), and, when they accumulate (Prop. 2.1), the exact
accumulation time ``t_inf = v + (1+e)/(1-e) sqrt(v^2 + 2y)`` followed by a slide
along the floor to the edge.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from numba import njit

from . import _validate as _v
from .model import (
    SLIDING,
    _constants,
    _finite,
    _impact_time,
    _state_in_step,
    check_count,
    check_e,
    check_state,
    check_u,
    iterate,
)
from .units import Staircase, staircase_of

__all__ = ["Trajectory", "Flight", "Impact", "Accumulation", "Slide", "Unlisted", "trajectory"]

# Bytes one listed record (a Flight or an Impact with its floats) takes, measured
# with tracemalloc (tests/test_trajectory.py keeps the estimate honest)
_RECORD_BYTES = 240


@dataclass(frozen=True)
class Flight:
    """A parabolic arc: ``y(t) = y_start + v_start (t - t_start) - (t - t_start)^2 / 2``."""

    t_start: float
    t_end: float
    y_start: float
    v_start: float
    step: int


@dataclass(frozen=True)
class Impact:
    """An impact on the floor of ``step`` (at height ``y = -step``)."""

    time: float
    x: float
    y: float
    v_before: float
    v_after: float
    step: int


@dataclass(frozen=True)
class Accumulation:
    """The limit of infinitely many impacts on ``step`` at the exact time of the
    geometric series; ``listed`` impacts before it are in ``Trajectory.impacts``."""

    time: float
    x: float
    y: float
    step: int
    listed: int


@dataclass(frozen=True)
class Unlisted:
    """Impacts ``first .. first + count - 1`` of a step with more impacts than
    ``max_listed``, between ``t_start`` and ``t_end``: not listed, but
    resolved exactly by ``Trajectory.position``."""

    t_start: float
    t_end: float
    step: int
    first: int
    count: int


@dataclass(frozen=True)
class Slide:
    """The ball slides along the floor of ``step`` (height ``y``) to its edge."""

    t_start: float
    t_end: float
    x_start: float
    x_end: float
    y: float
    step: int


@dataclass(repr=False)
class Trajectory:
    """The solution over ``steps`` steps; see :func:`trajectory`.

    Its repr is one line (the parameters and how many of each record);
    the records themselves are the lists ``flights``, ``impacts``,
    ``accumulations``, ``slides`` and ``unlisted``.  ``staircase`` is the
    :class:`stairbounce.Staircase` when ``u`` was given as a speed in m/s.
    """

    e: float
    u: float
    steps: int
    edge_y: np.ndarray  # Poincare iterates: state at each edge, length steps + 1
    edge_v: np.ndarray
    edge_impacts: np.ndarray  # impact number of step j at index j + 1
    flights: list[Flight] = field(default_factory=list)
    impacts: list[Impact] = field(default_factory=list)
    accumulations: list[Accumulation] = field(default_factory=list)
    slides: list[Slide] = field(default_factory=list)
    unlisted: list[Unlisted] = field(default_factory=list)
    staircase: Staircase | None = None

    def __repr__(self) -> str:
        speed = "" if self.staircase is None else f" (U = {self.staircase.to_speed(self.u):.4g} m/s)"
        counts = [(len(self.impacts), "impact"), (len(self.accumulations), "accumulation"),
                  (len(self.slides), "slide")]
        more = sum(r.count for r in self.unlisted)
        text = ", ".join(f"{n} {word}{'' if n == 1 else 's'}" for n, word in counts)
        return (f"Trajectory(e={self.e:g}, u={self.u:g}{speed}, y0={float(self.edge_y[0]):g}, "
                f"v0={float(self.edge_v[0]):g}, steps={self.steps}: {text}"
                + (f", {more} more impacts unlisted" if more else "") + ")")

    @property
    def T(self) -> float:
        """Time to cross one step, ``1/u``."""
        return 1.0 / self.u

    @property
    def duration(self) -> float:
        return self.steps / self.u

    def _local(self, t):
        """Step index, local time and local (height, velocity) for times ``t``
        (a scalar gives 0-d arrays)."""
        t = _times(t)
        if np.any(~np.isfinite(t)) or np.any(t < 0) or np.any(t > self.duration * (1 + 1e-12)):
            raise ValueError(f"t must be in [0, {self.duration}] (the trajectory's duration)")
        j = np.clip(np.floor(t / self.T).astype(np.int64), 0, max(self.steps - 1, 0))
        tau = t - j * self.T
        y, v = self._solve_local(j, tau)
        return j, tau, y, v

    def _solve_local(self, j, tau):
        """Height above the floor of step ``j`` and vertical velocity at local
        time ``tau`` (0 <= tau <= T) after entering it, in closed form
        (:func:`stairbounce.model._state_in_step`, the map's own functions)."""
        j = np.asarray(j, dtype=np.int64)
        tau = np.asarray(tau, dtype=float)
        j, tau = np.broadcast_arrays(j, tau)
        y = np.empty(tau.shape)
        v = np.empty(tau.shape)
        _states(self.edge_y, self.edge_v, self.e, (1.0 + self.e) / (1.0 - self.e),
                j.ravel(), tau.ravel(), y.reshape(-1), v.reshape(-1))
        return y, v

    def edge_state(self, j):
        """edge_state(j) -> (y, v): the state at edge ``j`` (1 <= j <= steps)
        from the continuous solution of step ``j - 1`` evaluated at its end.

        It equals the Poincare iterate ``P^j(y0, v0)``, computed independently.
        """
        j = check_count("j", j, 1)
        if j > self.steps:
            raise ValueError(f"j must be an integer in [1, {self.steps}], got {j}")
        y, v = self._solve_local(np.array([j - 1]), np.array([self.T]))
        return float(y[0]) + 1.0, float(v[0])

    def position(self, t):
        """position(t) -> (x, y): exact position at times ``t`` (a number or an
        array of them; a number gives 0-d arrays)."""
        j, _, y, _ = self._local(t)
        return self.u * _times(t), y - j

    def velocity(self, t):
        """velocity(t) -> (vx, vy): horizontal and vertical velocity at ``t``
        (right limits at impact times; a number gives 0-d arrays)."""
        _, _, _, v = self._local(t)
        return np.full_like(v, self.u), v


def _times(t):
    """Times as a float array: numbers or arrays of real numbers only."""
    if isinstance(t, np.ndarray):
        if t.dtype.kind not in "iuf":
            raise ValueError(f"t must be a number or an array of real numbers, got an array of {t.dtype}")
        return t.astype(float)
    if isinstance(t, (list, tuple)):
        a = np.array(t, dtype=object)
        for x in a.ravel():
            _finite("t", x)
        return a.astype(float)
    return np.asarray(_finite("t", t))


@njit(cache=True)
def _states(edge_y, edge_v, e, ratio, j, tau, y, v):
    for i in range(tau.size):
        y[i], v[i] = _state_in_step(edge_y[j[i]], edge_v[j[i]], e, tau[i], ratio)


def trajectory(e, u, y0=1.0, v0=0.0, steps=10, max_listed=30):
    """trajectory(e, u, y0=1.0, v0=0.0, steps=10, max_listed=30) -> Trajectory

    The exact continuous-time solution of (1.3)-(1.4) over ``steps`` steps.

    Each step is solved from its entry state (the Poincare iterates, Prop. 2.3):
    a flight to ``t_1 = v + sqrt(v^2 + 2y)``, impacts at the times of eq. (2.2),
    and when the impacts accumulate (Prop. 2.1) the accumulation at
    ``t_inf = v + (1+e)/(1-e) sqrt(v^2+2y)`` (the sum of the geometric series)
    and a slide to the edge.  The result lists flight arcs, impacts (time,
    position, velocity before and after, step), accumulation points and slides,
    and evaluates the exact position at any time with ``position(t)``.

    Parameters
    ----------
    e : float in [0, 1)
    u : float > 0
    y0 : float >= 0, default 1.0
        Initial height above the floor of step 0, at the edge x = 0.
    v0 : float, default 0.0
        Initial vertical velocity.
    steps : int >= 0, default 10
    max_listed : int >= 1, default 30
        Impacts listed per step: before an accumulation point, and on a step
        with more impacts than that (the rest, recorded as one
        :class:`Unlisted`, is still resolved exactly by ``position``).

    The listed records are counted before they are made and refused with a
    ValueError when they would not fit in the memory available.
    """
    e = check_e(e)
    speed, u = u, check_u(u)
    y0, v0 = check_state(y0, v0, "y0", "v0")
    steps = check_count("steps", steps, 0)
    max_listed = check_count("max_listed", max_listed, 1)
    T, ratio = _constants(e, u)
    ys, vs, ks = iterate(y0, v0, e, u, steps)
    # a flight and an impact per listed impact, plus up to three records a step
    records = sum(2 * _listed(int(k), e, max_listed) + 3 if k else 1 for k in ks[1:])
    _v.check_memory(f"steps = {steps} with max_listed = {max_listed}", records * _RECORD_BYTES)
    traj = Trajectory(e=e, u=u, steps=steps, edge_y=ys, edge_v=vs, edge_impacts=ks,
                      staircase=staircase_of(speed))
    for j in range(steps):
        _solve_step(traj, j, ys[j], vs[j], int(ks[j + 1]), e, T, ratio, max_listed)
    return traj


def _listed(k, e, max_listed):
    """Impacts listed for a step with impact number ``k``."""
    if k == SLIDING:
        return 1 if e == 0.0 else max_listed
    return min(k, max_listed)


def _solve_step(traj, j, y, v, k, e, T, ratio, max_listed):
    """Append the flights, impacts, accumulation and slide of step ``j``."""
    t0 = j * T
    s = math.sqrt(v * v + 2.0 * y)
    if k == 0:
        traj.flights.append(Flight(t0, t0 + T, y - j, v, j))
        return
    n = _listed(k, e, max_listed)
    tk = v + s  # eq. (2.1)
    vk = s
    traj.flights.append(Flight(t0, t0 + tk, y - j, v, j))
    for i in range(1, n + 1):
        if i > 1:
            t_next = _impact_time(v, s, e, i)  # eq. (2.2)
            traj.flights.append(Flight(t0 + tk, t0 + t_next, -float(j), vk, j))
            tk = t_next
        traj.impacts.append(Impact(t0 + tk, traj.u * (t0 + tk), -float(j), -vk, e * vk, j))
        vk = e * vk
    if k != SLIDING:
        if k > n:
            traj.unlisted.append(Unlisted(t0 + tk, t0 + T, j, n + 1, k - n))
        else:
            traj.flights.append(Flight(t0 + tk, t0 + T, -float(j), vk, j))
        return
    t_inf = t0 + v + ratio * s
    traj.accumulations.append(Accumulation(t_inf, traj.u * t_inf, -float(j), j, n))
    traj.slides.append(Slide(t_inf, t0 + T, traj.u * t_inf, float(j + 1), -float(j), j))
