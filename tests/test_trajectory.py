"""The exact continuous-time solution against scipy's event-driven integrator
and against the Poincare map at every edge."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

import stairbounce as sb


def impacts_by_integration(e, u, y0, v0, steps):
    """Impact times of (1.3)-(1.4) found by solve_ivp with a terminal event at
    the floor of the current step (no closed form involved)."""

    def rhs(t, z):
        return [z[1], -1.0]

    T = 1.0 / u
    times = []
    t, y, v = 0.0, y0, v0  # y: height above the current step's floor
    for j in range(steps):
        t_end = (j + 1) * T
        while True:

            def floor(t, z):
                return z[0]

            floor.terminal = True
            floor.direction = -1
            sol = solve_ivp(rhs, (t, t_end), [y, v], events=floor, rtol=1e-12, atol=1e-13)
            if sol.t_events[0].size:
                t = float(sol.t_events[0][0])
                v_hit = float(sol.y_events[0][0][1])
                times.append(t)
                y, v = 0.0, -e * v_hit
                if v < 1e-9:  # would accumulate: not used on these orbits
                    raise AssertionError("sliding orbit given to the integrator check")
            else:
                y, v = float(sol.y[0, -1]) + 1.0, float(sol.y[1, -1])
                t = t_end
                break
    return np.array(times)


@pytest.mark.parametrize(
    "e,u,y0,v0",
    [
        (0.7, 0.3, 1.0, 0.0),  # above Cor. 2.1: never slides, several impacts a step
        (0.5, 0.8, 1.0, 0.0),
        (0.9, 0.2, 2.5, 1.0),
        (0.3, 1.1, 1.2, -0.5),
        (0.1, 0.9, 1.0, 0.0),  # between tongues, below Cor. 2.1: quasi-periodic
    ],
)
def test_impact_times_agree_with_solve_ivp(e, u, y0, v0):
    """Hypothesis: the impact times of eq. (2.2), chained by the map, are the
    impacts of the differential equation; checked to 1e-8."""
    steps = 20
    traj = sb.trajectory(e, u, y0, v0, steps)
    assert not traj.accumulations
    ref = impacts_by_integration(e, u, y0, v0, steps)
    got = np.array([i.time for i in traj.impacts])
    assert len(got) == len(ref) >= 4
    np.testing.assert_allclose(got, ref, atol=1e-8, rtol=0)


def test_trajectory_is_the_map_at_every_edge():
    for e, u in [(0.1, 0.83), (0.2, 0.45), (0.05, 0.93), (0.6, 0.15), (0.0, 0.5)]:
        traj = sb.trajectory(e, u, 0.3, 0.2, steps=30)
        y, v = 0.3, 0.2
        for j in range(1, 31):
            y, v, k = sb.poincare_map(y, v, e, u)
            assert (traj.edge_y[j], traj.edge_v[j], traj.edge_impacts[j]) == (y, v, k)
            ye, ve = traj.edge_state(j)  # from the continuous solution of step j - 1
            assert ye == pytest.approx(y, abs=1e-10)
            assert ve == pytest.approx(v, abs=1e-10)


def test_position_is_continuous_and_on_the_floor_at_impacts():
    traj = sb.trajectory(0.3, 0.35, 1.0, 0.0, steps=6)
    T = traj.T
    edges = np.arange(1, 6) * T
    _, left = traj.position(edges - 1e-10)
    _, right = traj.position(edges + 1e-10)
    np.testing.assert_allclose(left, right, atol=1e-8)
    for imp in traj.impacts:
        x, y = traj.position([imp.time])
        assert y[0] == pytest.approx(-imp.step, abs=1e-9)
        assert x[0] == pytest.approx(imp.x)
        assert imp.v_after == pytest.approx(-traj.e * imp.v_before)
    t = np.linspace(0, traj.duration, 20001)
    x, y = traj.position(t)
    floor = -np.floor(x)
    assert np.all(y >= np.minimum(floor, -np.floor(x - 1e-9)) - 1e-9)  # never below the floor


def test_accumulation_time_is_the_geometric_series():
    """The accumulation point is the limit of the listed impacts (sum of the
    series), the ball rests after it and slides off the edge with (1, 0)."""
    e, u = 0.2, 0.45  # inside the n = 1 tongue: slides on every step
    traj = sb.trajectory(e, u, 1.0, 0.0, steps=3, max_listed=60)
    assert len(traj.accumulations) == 3 == len(traj.slides)
    acc = traj.accumulations[0]
    listed = [i for i in traj.impacts if i.step == 0]
    assert len(listed) == acc.listed == 60
    s = math.sqrt(2.0)
    assert acc.time == pytest.approx((1 + e) / (1 - e) * s, rel=1e-14)
    assert listed[-1].time == pytest.approx(acc.time, abs=1e-12)
    sl = traj.slides[0]
    assert (sl.t_start, sl.t_end, sl.x_end) == (acc.time, pytest.approx(traj.T), 1.0)
    _, y = traj.position(np.linspace(sl.t_start, sl.t_end, 50))
    assert np.all(y == 0.0)
    assert traj.edge_state(1) == (1.0, 0.0)


def test_flights_are_parabolas_of_the_solution():
    traj = sb.trajectory(0.4, 0.5, 1.3, 0.7, steps=5)
    for f in traj.flights:
        t = np.linspace(f.t_start, f.t_end, 7)[1:-1]
        _, y = traj.position(t)
        dt = t - f.t_start
        np.testing.assert_allclose(y, f.y_start + f.v_start * dt - 0.5 * dt * dt, atol=1e-10)


@settings(max_examples=200, deadline=None)
@given(
    y=st.floats(0.0, 50.0),
    v=st.floats(-10.0, 10.0),
    e=st.just(0.0) | st.floats(2.0**-53, 0.98),  # the valid range (docs/design.md)
    u=st.floats(0.05, 5.0),
)
def test_map_equals_trajectory_at_the_edge(y, v, e, u):
    """Property: poincare_map equals the state of the continuous solution at the edge."""
    yn, vn, k = sb.poincare_map(y, v, e, u)
    ye, ve = sb.trajectory(e, u, y, v, steps=1).edge_state(1)
    scale = 1 + abs(v) + math.sqrt(v * v + 2 * y)
    assert abs(ye - yn) <= 1e-9 * scale
    assert abs(ve - vn) <= 1e-9 * scale


def test_trajectory_bad_input():
    with pytest.raises(ValueError, match="steps must be an integer >= 0"):
        sb.trajectory(0.1, 0.5, steps=-1)
    with pytest.raises(ValueError, match=r"y0 .* must be >= 0"):
        sb.trajectory(0.1, 0.5, y0=-1)
    traj = sb.trajectory(0.1, 0.5, steps=2)
    with pytest.raises(ValueError, match="t must be in"):
        traj.position([-1.0])


def test_scalar_time_after_the_first_impact_of_a_step():
    """Report D6: position(2.0) raised TypeError where position([2.0]) worked;
    scalars give 0-d results equal to the 1-element arrays, at every kind of time."""
    traj = sb.trajectory(0.05, 0.93, steps=6)
    for t in [0.5, 2.0, 2.05, 4.2, traj.duration]:
        x, y = traj.position(t)
        xa, ya = traj.position([t])
        assert np.shape(y) == () and float(y) == ya[0] and float(x) == xa[0]
        vx, vy = traj.velocity(t)
        assert np.shape(vy) == () and float(vy) == traj.velocity([t])[1][0]


def test_times_must_be_numbers():
    traj = sb.trajectory(0.05, 0.93, steps=2)
    for bad in ["abc", None, True, 0.5 + 0j, {}, [0.5, "a"], 10**400]:
        with pytest.raises(ValueError, match="^t must"):
            traj.position(bad)


def test_many_impacts_on_one_step_are_not_all_listed():
    """Report D3: trajectory(1-1e-9, 1e-9, steps=1) listed ~4e8 impacts (24 GB).
    At most max_listed are listed per step, the rest is one Unlisted record,
    and position() still resolves them: it agrees with the map at the edge."""
    e, u = 1 - 1e-9, 1e-9
    traj = sb.trajectory(e, u, steps=1)
    k = int(traj.edge_impacts[1])
    assert k > 10**8  # the step really has that many impacts
    assert len(traj.impacts) == 30
    (rest,) = traj.unlisted
    assert (rest.first, rest.count) == (31, k - 30)
    y, v = traj.edge_state(1)
    assert (y, v) == pytest.approx((traj.edge_y[1], traj.edge_v[1]), rel=1e-9, abs=1e-9)


_MEASURE = """
import tracemalloc, stairbounce as sb
sb.trajectory(0.9, 0.05, steps=3)  # compiled or loaded before tracing
tracemalloc.start()
base = tracemalloc.get_traced_memory()[0]
traj = sb.trajectory(0.9, 0.05, steps=400, max_listed=50)
used = tracemalloc.get_traced_memory()[0] - base
n = sum(len(x) for x in (traj.flights, traj.impacts, traj.accumulations, traj.slides, traj.unlisted))
print(n, used / n)
"""


def test_listed_records_are_estimated_before_they_are_made():
    """The refusal uses the real size of a record, measured with tracemalloc
    in a fresh interpreter (pytest's own tracing would blur it)."""
    import importlib
    import subprocess
    import sys

    tmod = importlib.import_module("stairbounce.trajectory")
    out = subprocess.run([sys.executable, "-c", _MEASURE], capture_output=True, text=True, check=True)
    records, per_record = out.stdout.split()
    assert int(records) > 5000
    assert 0.7 * tmod._RECORD_BYTES < float(per_record) <= 1.1 * tmod._RECORD_BYTES
    # a sliding orbit lists max_listed impacts per step: refused before listing
    with pytest.raises(ValueError, match=r"steps = 1000000 with max_listed = 1000000000 needs about"):
        sb.trajectory(0.05, 0.93, steps=10**6, max_listed=10**9)
    with pytest.raises(ValueError, match=r"^steps = 1000000000000 needs about .* TiB"):
        sb.trajectory(0.9, 0.05, steps=10**12)
