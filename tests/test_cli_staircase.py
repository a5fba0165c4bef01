"""A real staircase on the command line: ``--speed U --step-height a
--step-length b [--g]`` in SI units instead of ``--u``.

The conversion is the paper's rescaling (Section 1; docs/design.md): lengths
by ``a`` (vertical) and ``b`` (horizontal), time by ``sqrt(a/g)``, so
``u = U sqrt(a/g) / b`` and vertical velocities scale by ``sqrt(a g)``.  The
expected values below are computed from that formula directly, not through
the package's units module.
"""

from __future__ import annotations

import csv
import io
import math

import numpy as np
import pytest
import xarray as xr

import stairbounce as sb

from ._cli import run_cli as run

# a household staircase: 17 cm risers, 29 cm treads
A, B, G = 0.17, 0.29, 9.81


def u_of(speed, a=A, b=B, g=G):
    return speed * math.sqrt(a / g) / b


def test_word_of_a_physical_staircase_is_the_word_at_its_u(capsys):
    speed = 1.2
    code, out, _ = run(["word", "--e", "0.05", "--speed", str(speed), "--step-height", str(A),
                        "--step-length", str(B)], capsys)
    assert code == 0
    w = sb.sliding_word(0.05, u_of(speed))
    assert w is not None and w.period == 1 and "period:  1 step = " in out  # not "1 steps"
    # both descriptions are printed: the speed in m/s and the normalised u
    assert "U = 1.2 m/s" in out and f"u = U sqrt(a/g) / b = {u_of(speed):.6g}" in out
    # a period of n steps lasts n b / U seconds
    assert f"= {w.period * B / speed:.6g} s" in out


def test_motion_of_a_physical_staircase_is_the_motion_at_its_u(capsys):
    # 2.5 m/s on 17 cm x 29 cm steps: u = 1.13, above the Corollary 2.1 bound
    # at e = 0.5, so the orbit never slides and <k> is printed
    speed, e = 2.5, 0.5
    code, out, err = run(["motion", "--e", str(e), "--speed", str(speed), "--step-height", str(A),
                          "--step-length", str(B), "--steps", "200", "--transient", "200"], capsys)
    assert code == 0, err
    code2, ref, _ = run(["motion", "--e", str(e), "--u", repr(u_of(speed)), "--steps", "200",
                         "--transient", "200"], capsys)
    assert code2 == 0
    assert f"u = U sqrt(a/g) / b = {u_of(speed):.6g}" in out
    k_line = [ln for ln in ref.splitlines() if ln.startswith("<k>:")]
    assert k_line and k_line[0] in out
    code3, _, err3 = run(["motion", "--e", "0.5", "--u", "1.0", "--speed", "2.5", "--step-height", str(A),
                          "--step-length", str(B)], capsys)
    assert code3 == 2 and err3.strip().count("\n") == 0


def test_gravity_option_changes_u_as_the_formula_says(capsys):
    # on a staircase with a = g (in its units) the time unit is 1 s and u = U / b;
    # U = 0.5 b lies in the first tongue of Thm 3.1 for e = 0.1 (u^2 <= (1/2)(0.9/1.1)^2)
    code, out, _ = run(["word", "--e", "0.1", "--speed", "0.25", "--step-height", "2",
                        "--step-length", "0.5", "--g", "2"], capsys)
    assert code == 0
    assert "u = U sqrt(a/g) / b = 0.5 " in out
    assert "word:    (1, 0" in out


def test_map_prints_si_columns(capsys):
    speed = 1.0
    code, out, _ = run(["map", "--e", "0.3", "--speed", str(speed), "--step-height", str(A),
                        "--step-length", str(B), "--steps", "6", "--csv"], capsys)
    assert code == 0
    rows = list(csv.DictReader(io.StringIO(out)))
    ys, vs, _ = sb.iterate(1.0, 0.0, 0.3, u_of(speed), 6)
    np.testing.assert_allclose([float(r["y"]) for r in rows], ys, rtol=1e-15)
    np.testing.assert_allclose([float(r["y_m"]) for r in rows], ys * A, rtol=1e-12)
    np.testing.assert_allclose([float(r["v_m_per_s"]) for r in rows], vs * math.sqrt(A * G), rtol=1e-12)


def test_map_table_with_a_staircase(capsys):
    code, out, _ = run(["map", "--e", "0.3", "--speed", "1", "--step-height", str(A),
                        "--step-length", str(B), "--steps", "2"], capsys)
    assert code == 0
    assert "y (m)" in out and "v (m/s)" in out and "U = 1 m/s" in out


def test_orbit_diagram_speed_range_is_the_u_range(tmp_path, capsys):
    common = ["orbit-diagram", "--e", "0.1", "--n", "30", "--transient", "40", "--keep", "10"]
    code, _, _ = run(common + ["--speed", "0.5:2.5", "--step-height", str(A), "--step-length", str(B),
                               "--out", str(tmp_path / "si.nc")], capsys)
    assert code == 0
    code, _, _ = run(common + ["--u", f"{u_of(0.5)!r}:{u_of(2.5)!r}", "--out", str(tmp_path / "u.nc")],
                     capsys)
    assert code == 0
    with xr.open_dataset(tmp_path / "si.nc") as a, xr.open_dataset(tmp_path / "u.nc") as b:
        np.testing.assert_allclose(a.u.values, b.u.values, rtol=1e-15)
        np.testing.assert_array_equal(a.y.values, b.y.values)


def test_trajectory_axes_in_metres_and_seconds(tmp_path, capsys):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    speed = 1.2
    traj = sb.trajectory(0.5, sb.Staircase(A, B, G).speed(speed), steps=4)
    assert traj.u == u_of(speed)
    fig, (a1, a2) = plt.subplots(1, 2)
    sb.plot.plot_trajectory(traj, ax=a1)
    sb.plot.plot_poincare_section(traj.edge_y, traj.edge_v, traj.edge_impacts, ax=a2, staircase=traj)
    fig.canvas.draw()
    assert a1.get_xlabel() == "x (m)" and a1.get_ylabel() == "height (m)"
    assert a2.get_ylabel().endswith("(m/s)")
    # ticks sit at round physical values: x b, y a, v sqrt(a g) on a 1-2-2.5-5 grid
    for ticks, factor in ((a1.get_xticks(), B), (a1.get_yticks(), A), (a2.get_yticks(), math.sqrt(A * G))):
        values = np.asarray(ticks) * factor
        step = np.min(np.diff(values))
        np.testing.assert_allclose(values / step, np.round(values / step), atol=1e-9)
        mantissa = step / 10 ** math.floor(math.log10(step) + 1e-12)
        assert min(abs(mantissa - m) for m in (1, 2, 2.5, 5, 10)) < 1e-9
    # the top axis is a clock: one step length b is crossed in b / U seconds
    top = [c for c in a1.child_axes if c.get_xlabel() == "t (s)"]
    assert len(top) == 1
    forward, _ = top[0]._functions
    assert forward(1.0) == pytest.approx(B / speed, rel=1e-12)
    # the dashed edge of the map's domain, y = 1, is the step height in metres
    labels = a2.get_legend_handles_labels()[1]
    assert f"y = {A:g} m: edge of the domain of P" in labels
    assert not any(text.startswith("y = 1:") for text in labels)
    plt.close(fig)
    code, out, _ = run(["trajectory", "--e", "0.5", "--speed", "1.2", "--step-height", str(A),
                        "--step-length", str(B), "--steps", "3", "--out", str(tmp_path / "t.png")], capsys)
    assert code == 0 and (tmp_path / "t.png").stat().st_size > 0 and "U = 1.2 m/s" in out


def _round_grid(values):
    """The values are multiples of one step of mantissa 1, 2, 2.5 or 5 (a MaxNLocator grid)."""
    step = np.min(np.diff(values))
    np.testing.assert_allclose(values / step, np.round(values / step), atol=1e-9)
    mantissa = step / 10 ** math.floor(math.log10(step) + 1e-12)
    assert min(abs(mantissa - m) for m in (1, 2, 2.5, 5, 10)) < 1e-9, values
    return step


@pytest.mark.parametrize("given", ["staircase", "speed", "trajectory"])
def test_poincare_section_in_metres_given_a_staircase(given):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    stairs = sb.Staircase(A, B, G)
    staircase = {"staircase": stairs, "speed": stairs.speed(1.2),
                 "trajectory": sb.trajectory(0.5, stairs.speed(1.2), steps=2)}[given]
    ys, vs = np.array([1.0, 2.0, 3.0]), np.array([-2.0, 0.0, 2.0])
    ax = sb.plot.plot_poincare_section(ys, vs, staircase=staircase, colorbar=False)
    ax.set_xlim(1.0, 3.0)  # heights 0.17..0.51 m
    ax.set_ylim(-2.0, 2.0)  # velocities -+2 sqrt(a g) = -+2.583 m/s
    ax.figure.canvas.draw()
    assert ax.get_xlabel() == "height at the edge (m)"
    assert ax.get_ylabel() == "vertical velocity at the edge (m/s)"
    assert "a = 0.17 m, b = 0.29 m" in ax.get_title()
    # the data stay normalised; the ticks sit at round metres and m/s, labelled with them
    assert ax.collections[0].get_offsets()[:, 0].tolist() == [1.0, 2.0, 3.0]
    for axis, factor, (lo, hi) in ((ax.xaxis, A, (0.17, 0.51)),
                                   (ax.yaxis, math.sqrt(A * G), (-2.0 * math.sqrt(A * G), 2.0 * math.sqrt(A * G)))):
        view = sorted(axis.get_view_interval())
        shown = [(t, label.get_text()) for t, label in zip(axis.get_ticklocs(), axis.get_ticklabels())
                 if view[0] - 1e-12 <= t <= view[1] + 1e-12]
        values = np.array([t for t, _ in shown]) * factor
        step = _round_grid(values)
        # the ticks span the view: the first within a step of its low end, the last of its high end
        assert lo - 1e-12 <= values[0] < lo + step and hi - step < values[-1] <= hi + 1e-12, (values, lo, hi)
        texts = [float(text.replace("\N{MINUS SIGN}", "-")) for _, text in shown]
        np.testing.assert_allclose(texts, values, atol=1e-9)
    # the dashed edge y = 1 is the step height
    assert "y = 0.17 m: edge of the domain of P" in ax.get_legend_handles_labels()[1]
    plt.close(ax.figure)


def test_poincare_section_normalised_without_a_staircase():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    traj = sb.trajectory(0.5, u_of(1.2), steps=2)  # a plain u: the trajectory carries no staircase
    for staircase in (None, traj):
        ax = sb.plot.plot_poincare_section([1.0, 2.0, 3.0], [-2.0, 0.0, 2.0], colorbar=False,
                                           staircase=staircase)
        ax.set_xlim(1.0, 3.0)
        ax.figure.canvas.draw()
        assert ax.get_xlabel() == "y (height at the edge)"
        assert ax.get_ylabel() == "v (vertical velocity at the edge)"
        assert ax.get_title() == "Poincare section"
        ticks = np.array([t for t in ax.get_xticks() if 1.0 <= t <= 3.0])
        _round_grid(ticks)
        assert ticks[0] == 1.0 and ticks[-1] == 3.0
        assert "y = 1: edge of the domain of P" in ax.get_legend_handles_labels()[1]
        plt.close(ax.figure)
    with pytest.raises(ValueError, match="staircase must be a stairbounce.Staircase"):
        sb.plot.plot_poincare_section([1.0], [0.0], staircase=0.17)


@pytest.mark.parametrize(
    "args, needle",
    [
        (["word", "--e", "0.1", "--u", "0.5", "--speed", "1"], "either --u or --speed"),
        (["word", "--e", "0.1", "--u", "0.5", "--step-height", "0.2"], "not both"),
        (["word", "--e", "0.1"], "give the horizontal speed"),
        (["word", "--e", "0.1", "--speed", "1", "--step-height", "0.2"], "--speed needs --step-length"),
        (["word", "--e", "0.1", "--speed", "1"], "--step-height and --step-length"),
        (["word", "--e", "0.1", "--g", "9.8"], "--g needs --speed"),
        (["map", "--e", "0.1", "--speed", "-1", "--step-height", "0.2", "--step-length", "0.3"],
         "--speed must be a finite number > 0"),
        (["map", "--e", "0.1", "--speed", "1", "--step-height", "0", "--step-length", "0.3"],
         "--step-height must be a finite number > 0"),
        (["trajectory", "--e", "0.1", "--speed", "1", "--step-height", "0.2", "--step-length", "nan"],
         "--step-length must be a finite number > 0"),
        (["orbit-diagram", "--e", "0.1", "--speed", "2:1", "--step-height", "0.2", "--step-length", "0.3",
          "--out", "x.nc"], "--speed must have MIN < MAX"),
        (["orbit-diagram", "--e", "0.1", "--speed", "fast", "--step-height", "0.2", "--step-length", "0.3",
          "--out", "x.nc"], "--speed must be a number or a range"),
    ],
)
def test_bad_or_mixed_input_is_one_line_and_status_2(args, needle, capsys):
    code, _, err = run(args, capsys)
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("stairbounce: error:")
    assert needle in err


# --------------------------------------------------------------------------- #
# scans and orbit diagrams over a window of speeds in m/s (issue 25)          #
# --------------------------------------------------------------------------- #


def test_scan_speed_window_in_metres_per_second(tmp_path, capsys):
    out = tmp_path / "s.nc"
    code, text, err = run(["scan", "--e", "0.5:0.9", "--speed", "0.1:1.2", "--step-height", str(A),
                           "--step-length", str(B), "--size", "24x18", "--out", str(out)], capsys)
    assert code == 0, err
    ds = xr.load_dataset(out)
    # the picture's window is the same scan in u (u of each edge by the formula)
    ref = sb.scan(e=(0.5, 0.9, 24), u=(u_of(0.1), u_of(1.2), 18))
    np.testing.assert_allclose(ds.u.values, ref.u.values, rtol=1e-14)
    for name in ("status", "word_length", "period"):
        np.testing.assert_array_equal(ds[name].values, ref[name].values)
    # the coordinate speed is U = u b / sqrt(a/g), pixel centres of 0.1..1.2 m/s
    np.testing.assert_allclose(ds.speed.values, 0.1 + (np.arange(18) + 0.5) * 1.1 / 18, rtol=1e-12)
    assert ds.speed.attrs["units"] == "m/s" and ds.attrs["step_length"] == B
    assert "(U in [0.1, 1.2] m/s)" in text


@pytest.mark.parametrize("field", ["word_length", "k_mean"])
def test_scan_speed_figure_axis_in_metres_per_second(field, tmp_path, capsys, monkeypatch):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    saved = []
    original = plt.Figure.savefig
    monkeypatch.setattr(plt.Figure, "savefig", lambda fig, *a, **k: (saved.append(fig), original(fig, *a, **k)))
    code, _, err = run(["scan", "--e", "0.5:0.9", "--speed", "0.1:1.2", "--step-height", str(A),
                        "--step-length", str(B), "--size", "12x10", "--max-iter", "20", "--field", field,
                        "--png", str(tmp_path / "s.png")], capsys)
    assert code == 0, err
    ax = saved[0].axes[0]
    saved[0].canvas.draw()
    assert ax.get_ylabel() == "U (horizontal speed, m/s)"
    # the data stay in u: the axis limits are the u edges, the tick labels m/s
    assert ax.get_ylim() == pytest.approx((u_of(0.1), u_of(1.2)), rel=1e-12)
    labels = [float(t.get_text()) for t in ax.get_yticklabels() if t.get_text()]
    np.testing.assert_allclose(labels, np.asarray(ax.get_yticks())[: len(labels)] * B / math.sqrt(A / G),
                               rtol=1e-3)


@pytest.mark.parametrize(
    "args, needle",
    [
        (["scan", "--speed", "0.5:1", "--u", "0:1"], "not both"),
        (["scan", "--speed", "0.5:1", "--step-height", "0.2"], "--speed needs --step-length"),
        (["scan", "--speed", "1", "--step-height", "0.2", "--step-length", "0.3"], "must be a range"),
    ],
)
def test_scan_bad_speed_options_are_one_line_and_status_2(args, needle, capsys):
    code, _, err = run(args, capsys)
    assert code == 2 and err.count("\n") == 1 and needle in err


def test_orbit_diagram_speed_axes_in_metres(tmp_path, capsys, monkeypatch):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    saved = []
    original = plt.Figure.savefig
    monkeypatch.setattr(plt.Figure, "savefig", lambda fig, *a, **k: (saved.append(fig), original(fig, *a, **k)))
    out = tmp_path / "od.nc"
    code, _, err = run(["orbit-diagram", "--e", "0.3", "--speed", "0.5:2", "--step-height", str(A),
                        "--step-length", str(B), "--n", "40", "--transient", "50", "--keep", "10",
                        "--out", str(out), "--png", str(tmp_path / "od.png")], capsys)
    assert code == 0, err
    ds = xr.load_dataset(out)
    np.testing.assert_allclose(ds.speed.values, sb.pixel_centres(0.5, 2.0, 40), rtol=1e-12)
    ax = saved[0].axes[0]
    assert ax.get_xlabel() == "U (horizontal speed, m/s)"
    assert ax.get_ylabel() == "height at the edge (m)"
    saved[0].canvas.draw()
    # heights: tick labels are y a
    labels = [(float(t.get_text()), y) for t, y in zip(ax.get_yticklabels(), ax.get_yticks()) if t.get_text()]
    assert labels and all(abs(lab - y * A) < 1e-3 for lab, y in labels)


def test_tiled_scan_over_speeds_records_the_staircase(tmp_path, capsys):
    """A tiled store over a window of speeds: the same pixels as the in-memory
    scan, the coordinate speed, the staircase in its attributes; resuming it
    with another staircase is refused."""
    store = tmp_path / "t.zarr"
    args = ["scan", "--e", "0.5:0.9", "--speed", "0.1:1.2", "--step-height", str(A), "--step-length",
            str(B), "--size", "40x30", "--tile", "16", "--out", str(store)]
    code, _, err = run(args, capsys)
    assert code == 0, err
    ds = sb.load(store)
    ref = sb.scan(e=(0.5, 0.9, 40), u=sb.Staircase(A, B, G).speed(0.1, 1.2, 30))
    for name in ("status", "word_length", "period"):
        np.testing.assert_array_equal(ds[name].values, ref[name].values)
    np.testing.assert_array_equal(ds.speed.values, ref.speed.values)
    assert (ds.attrs["step_height"], ds.attrs["step_length"], ds.attrs["g"]) == (A, B, G)
    code, _, err = run(args[:8] + [str(B + 0.01)] + args[9:], capsys)
    assert code == 2 and "step_length: store 0.29, asked 0.3" in err


def test_trajectory_figure_keeps_the_path_title_inside(tmp_path, capsys, monkeypatch):
    # the path's title (speed and staircase) sits above the clock axis; it was cut off above
    # the figure (title box up to 486 px in a 480 px figure) before the layout made room
    from stairbounce.cli import model_commands

    seen = []
    real = model_commands.save_figure

    def keep(fig, *args, **kwargs):
        fig.canvas.draw()
        r = fig.canvas.get_renderer()
        seen.append([(ax.get_title(), ax.title.get_window_extent(r), fig.bbox) for ax in fig.axes])
        return real(fig, *args, **kwargs)

    monkeypatch.setattr(model_commands, "save_figure", keep)
    code, _, _ = run(["trajectory", "--e", "0.5", "--speed", "1.2", "--step-height", str(A),
                      "--step-length", str(B), "--steps", "5", "--out", str(tmp_path / "t.png")], capsys)
    assert code == 0 and len(seen) == 1
    titles = [(title, box, fig) for title, box, fig in seen[0] if title]
    assert any("U = 1.2 m/s" in title for title, _, _ in titles)
    for title, box, fig in titles:
        assert box.y1 <= fig.y1 and box.y0 >= fig.y0, title
