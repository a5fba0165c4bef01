"""``sb.Staircase``: a real staircase as one object whose speeds in m/s go
wherever the package takes a horizontal speed ``u`` (issue 25).

Expected values come from the paper's rescaling (Section 1), written out
here: ``u = U sqrt(a/g) / b``.  Every function given a speed in m/s must
return exactly what it returns for that ``u`` (bit for bit: the speed object
*is* that float, array or window), plus the coordinate ``speed`` in m/s.
"""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest

import stairbounce as sb

A, B, G = 0.17, 0.28, 9.81
STAIRS = sb.Staircase(A, B)


def u_of(speed):
    return speed * math.sqrt(A / G) / B


def test_conversions_both_ways_and_repr():
    assert STAIRS.g == 9.81
    assert STAIRS.to_u(1.5) == pytest.approx(u_of(1.5), rel=1e-15)
    assert STAIRS.to_speed(u_of(1.5)) == pytest.approx(1.5, rel=1e-15)
    np.testing.assert_allclose(STAIRS.to_u(np.array([1.0, 2.0])), [u_of(1.0), u_of(2.0)], rtol=1e-15)
    assert STAIRS.to_u(1.5) == sb.normalized_speed(1.5, A, B, G)
    assert STAIRS.to_speed(0.3) == sb.physical_speed(0.3, A, B, G)
    text = repr(STAIRS)
    assert "\n" not in text and text == "Staircase(step_height=0.17 m, step_length=0.28 m, g=9.81 m/s^2)"
    assert "\n" not in repr(STAIRS.speed(1.5)) and "1.5 m/s" in repr(STAIRS.speed(1.5))


@pytest.mark.parametrize("args, name", [((0.0, 0.28), "step_height"), ((0.17, -1.0), "step_length"),
                                        ((0.17, 0.28, float("nan")), "g"), (("0.17", 0.28), "step_height")])
def test_bad_staircase_names_the_parameter(args, name):
    with pytest.raises(ValueError, match=name):
        sb.Staircase(*args)


def test_bad_speeds_name_the_parameter():
    with pytest.raises(ValueError, match="speed"):
        STAIRS.speed(-1.0)
    with pytest.raises(ValueError, match="speed_min < speed_max"):
        STAIRS.speed(2.0, 1.0, 10)
    with pytest.raises(ValueError, match="n_speed"):
        STAIRS.speed(1.0, 2.0, 0)
    with pytest.raises(ValueError, match="speed window"):
        STAIRS.speed(1.0, 2.0)


def test_a_speed_is_its_u_everywhere():
    s = STAIRS.speed(0.25)
    u = u_of(0.25)
    assert float(s) == pytest.approx(u, rel=1e-15) and s.metres_per_second == 0.25
    assert sb.sliding_word(0.7, s) == sb.sliding_word(0.7, float(s)) is not None
    assert sb.poincare_map(1.0, 0.0, 0.5, s) == sb.poincare_map(1.0, 0.0, 0.5, float(s))
    t = sb.trajectory(0.5, STAIRS.speed(1.5), steps=3)
    assert t.u == float(STAIRS.speed(1.5)) and t.staircase == STAIRS
    assert "U = 1.5 m/s" in repr(t)
    assert sb.motion(0.5, STAIRS.speed(1.5), steps=50, transient=50)["k_mean"] == \
        sb.motion(0.5, float(STAIRS.speed(1.5)), steps=50, transient=50)["k_mean"]
    for obj in (s, STAIRS.speed(np.array([1.0, 2.0])), STAIRS.speed(1.0, 2.0, 5)):
        back = pickle.loads(pickle.dumps(obj))
        assert sb.units.staircase_of(back) == STAIRS
        np.testing.assert_array_equal(np.asarray(back, dtype=object).astype(float) if isinstance(back, tuple)
                                      else np.asarray(back), np.asarray(obj, dtype=float))


def test_scan_over_a_speed_window():
    window = STAIRS.speed(0.1, 1.2, 9)
    ds = sb.scan(e=(0.5, 0.9, 7), u=window)
    ref = sb.scan(e=(0.5, 0.9, 7), u=(u_of(0.1), u_of(1.2), 9))
    np.testing.assert_allclose(ds.u.values, ref.u.values, rtol=1e-15)
    plain = sb.scan(e=(0.5, 0.9, 7), u=tuple(window))
    for name in ("status", "word_length", "period", "impacts", "jumps"):
        np.testing.assert_array_equal(ds[name].values, plain[name].values)
    # pixel centres of 0.1..1.2 m/s, the dimension stays u
    np.testing.assert_allclose(ds.speed.values, 0.1 + (np.arange(9) + 0.5) * 1.1 / 9, rtol=1e-12)
    assert ds.speed.dims == ("u",) and ds.status.dims == ("u", "e")
    assert (ds.attrs["step_height"], ds.attrs["step_length"], ds.attrs["g"]) == (A, B, G)
    assert sb.Staircase.from_attrs(ds.attrs) == STAIRS
    # with progress, the same dataset
    prog = sb.scan(e=(0.5, 0.9, 7), u=window, progress=lambda d, t: None)
    np.testing.assert_array_equal(prog.speed.values, ds.speed.values)
    # plain u: no speed coordinate, no staircase attributes
    assert "speed" not in plain.coords and "step_height" not in plain.attrs
    cs = sb.scan_coords(ds.e.values, STAIRS.speed(np.array([0.2, 0.4])))
    np.testing.assert_allclose(cs.speed.values, [0.2, 0.4], rtol=1e-14)


def test_motion_scan_over_a_speed_window():
    ds = sb.motion_scan(e=(0.5, 0.9, 4), u=STAIRS.speed(1.0, 2.5, 3), steps=20, transient=20)
    ref = sb.motion_scan(e=(0.5, 0.9, 4), u=(u_of(1.0), u_of(2.5), 3), steps=20, transient=20)
    np.testing.assert_allclose(ds.k_mean.values, ref.k_mean.values, rtol=1e-12)
    np.testing.assert_allclose(ds.speed.values, [1.25, 1.75, 2.25], rtol=1e-12)


def test_orbit_diagram_over_speeds():
    speeds = np.linspace(0.5, 2.0, 6)
    ds = sb.orbit_diagram(0.3, STAIRS.speed(speeds), transient=30, keep=5)
    ref = sb.orbit_diagram(0.3, u_of(speeds), transient=30, keep=5)
    np.testing.assert_allclose(ds.u.values, ref.u.values, rtol=1e-14)
    np.testing.assert_allclose(ds.speed.values, speeds, rtol=1e-12)
    assert type(ds.u.values) is np.ndarray
    fixed = sb.orbit_diagram(np.array([0.1, 0.2]), STAIRS.speed(1.0), transient=30, keep=5)
    assert fixed.attrs["speed"] == pytest.approx(1.0, rel=1e-12)
    with pytest.raises(ValueError, match="scan window"):
        sb.orbit_diagram(0.3, STAIRS.speed(0.5, 2.0, 10))


def test_plots_draw_the_speed_axis_in_metres_per_second():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ds = sb.scan(e=(0.5, 0.9, 7), u=STAIRS.speed(0.1, 1.2, 9))
    ax = sb.plot.plot_scan(ds)
    assert ax.get_ylabel() == "U (horizontal speed, m/s)" and "m/s" in ax.get_title()
    ax.figure.canvas.draw()
    for t, y in zip(ax.get_yticklabels(), ax.get_yticks()):
        if t.get_text():
            assert float(t.get_text()) == pytest.approx(y * B / math.sqrt(A / G), rel=1e-3)
    plt.close("all")
    ax = sb.plot.plot_scan(sb.scan(e=(0.5, 0.9, 7), u=(0.1, 1.2, 9)))
    assert ax.get_ylabel() == "u (horizontal speed)"
    plt.close("all")


def test_plot_trajectory_of_a_speed_is_in_metres_and_seconds():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = sb.trajectory(0.5, STAIRS.speed(1.2), steps=4)
    ax = sb.plot.plot_trajectory(t)
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("x (m)", "height (m)") and "U = 1.2 m/s" in ax.get_title()
    top = [c for c in ax.child_axes if c.get_xlabel() == "t (s)"]
    forward, _ = top[0]._functions
    assert forward(1.0) == pytest.approx(B / 1.2, rel=1e-12)  # one step length in b / U seconds
    plt.close("all")
    ax = sb.plot.plot_trajectory(sb.trajectory(0.5, float(STAIRS.speed(1.2)), steps=4))
    assert ax.get_xlabel() == "x (steps)" and not ax.child_axes
    plt.close("all")
