"""Orbit (bifurcation) diagrams, Section 4 of the paper (issue 5)."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from stairbounce import SLIDING, pixel_centres, poincare_map, tongue
from stairbounce.cli import main
from stairbounce.orbits import orbit_density, orbit_diagram

E_SMALL = 0.001  # the paper's Fig. 8


def naive_row(e, u, y0, v0, transient, keep):
    """Kept iterates by calling the public one-step map in a Python loop."""
    y, v = y0, v0
    for _ in range(transient):
        y, v, _k = poincare_map(y, v, e, u)
    ys, vs, ks = [], [], []
    for _ in range(keep):
        y, v, k = poincare_map(y, v, e, u)
        ys.append(y)
        vs.append(v)
        ks.append(k)
    return np.array(ys), np.array(vs), np.array(ks)


def distinct(values, decimals=9):
    """Distinct values up to rounding at 1e-9: far below the spacing of the
    branches (checked separately) and far above float64 noise near y ~ 1..3."""
    return np.unique(np.round(np.asarray(values, dtype=float), decimals))


def branches(n, u):
    """Heights at the step edges of the sliding solution (n, 0^inf): it leaves
    an edge at (1, 0) and flies, so at the j-th edge its height above the floor
    being entered is 1 + j - j^2 / (2 u^2), j = 0..n-1 (j = 0: the slide)."""
    j = np.arange(n)
    return np.sort(1.0 + j - j * j / (2.0 * u * u))


# --------------------------------------------------------------------------- #
# Theorem 3.1 in the diagram (Fig. 8)                                          #
# --------------------------------------------------------------------------- #


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5])
@pytest.mark.parametrize("where", [0.05, 0.5, 0.95])
def test_n_branches_inside_the_nth_tongue(n, where):
    """Replicates Fig. 8 (e = 0.001): inside the n-th tongue of Theorem 3.1
    the kept iterates are the n points of the sliding solution (n, 0^inf)."""
    lo, hi = tongue(n, E_SMALL)
    u = lo + where * (hi - lo)
    ds = orbit_diagram(E_SMALL, [u])
    y = ds.y.values[0]
    # after a slide the state is exactly (1, 0), so the orbit repeats bit for bit
    assert np.unique(y).size == n
    assert distinct(y).size == n
    # the branches are well separated at this rounding, so 1e-9 neither merges
    # nor splits them
    if n > 1:
        assert np.diff(np.unique(y)).min() > 1e-6
    np.testing.assert_allclose(np.unique(y), branches(n, u), rtol=0, atol=1e-12)
    ks = ds.impacts.values[0]
    # one slide per period, flights over the other n - 1 edges
    assert set(np.unique(ks)) <= {SLIDING, 0}
    assert abs(int((ks == SLIDING).sum()) - ds.sizes["iterate"] / n) <= 1


@pytest.mark.parametrize("n", [2, 3, 4, 5])
def test_new_branch_appears_as_u_crosses_sqrt_n_minus_1_over_2(n):
    """Grazing bifurcation (Section 4): just below sqrt((n-1)/2) (inside the
    (n-1)-th tongue, whose top is only ~2e below) there are n - 1 branches,
    just above n; the new branch leaves y = 1 (the ball grazes the corner)."""
    u_c = math.sqrt((n - 1) / 2.0)
    below = tongue(n - 1, E_SMALL)[1] - 1e-4
    above = u_c + 1e-4
    assert u_c - below < 0.003  # both sides are close to the bifurcation
    ds = orbit_diagram(E_SMALL, [below, above])
    assert distinct(ds.y.values[0]).size == n - 1
    assert distinct(ds.y.values[1]).size == n
    new = np.setdiff1d(distinct(ds.y.values[1]), [1.0])
    assert new.min() - 1.0 < 1e-3  # born at y = 1


def test_sweep_across_tongues_counts_branches():
    """A sweep over tongues 1..5 has, at every value strictly inside tongue n
    (away from the narrow gaps between tongues), exactly n branches."""
    us = np.linspace(0.3, 1.55, 400)
    ds = orbit_diagram(E_SMALL, us)
    checked = 0
    for i, u in enumerate(us):
        n = math.ceil(2.0 * u * u)
        lo, hi = tongue(n, E_SMALL)
        if lo + 1e-4 < u < hi - 1e-4:
            assert distinct(ds.y.values[i]).size == n, u
            checked += 1
    assert checked > 350


# --------------------------------------------------------------------------- #
# The kernel against the map                                                  #
# --------------------------------------------------------------------------- #


@pytest.mark.parametrize("e", [0.0, 0.001, 0.1, 0.3, 0.7])
def test_rows_equal_iterating_poincare_map(e):
    rng = np.random.default_rng(int(e * 1000) + 1)
    us = np.sort(rng.uniform(0.2, 2.5, 12))
    ds = orbit_diagram(e, us, y0=0.1, v0=0.0, transient=300, keep=40)
    for i, u in enumerate(us):
        ys, vs, ks = naive_row(e, u, 0.1, 0.0, 300, 40)
        np.testing.assert_array_equal(ds.y.values[i], ys)
        np.testing.assert_array_equal(ds.v.values[i], vs)
        np.testing.assert_array_equal(ds.impacts.values[i], ks)


def test_rows_equal_poincare_map_when_e_is_swept():
    rng = np.random.default_rng(7)
    es = rng.uniform(0.0, 0.6, 10)
    ds = orbit_diagram(es, 0.93, y0=2.0, v0=-0.5, transient=100, keep=30)
    assert ds.y.dims == ("e", "iterate")
    for i, e in enumerate(es):
        ys, vs, ks = naive_row(e, 0.93, 2.0, -0.5, 100, 30)
        np.testing.assert_array_equal(ds.y.values[i], ys)
        np.testing.assert_array_equal(ds.v.values[i], vs)
        np.testing.assert_array_equal(ds.impacts.values[i], ks)


def test_rows_do_not_depend_on_order_or_neighbours():
    us = np.linspace(0.5, 1.0, 37)
    perm = np.random.default_rng(3).permutation(us.size)
    a = orbit_diagram(0.1, us, transient=200, keep=20)
    b = orbit_diagram(0.1, us[perm], transient=200, keep=20)
    np.testing.assert_array_equal(a.y.values[perm], b.y.values)
    one = orbit_diagram(0.1, us[5:6], transient=200, keep=20)
    np.testing.assert_array_equal(one.y.values[0], a.y.values[5])


def test_iterate_numbering_and_transient_zero():
    ds = orbit_diagram(0.2, [0.8], y0=1.5, v0=0.3, transient=0, keep=5)
    np.testing.assert_array_equal(ds.iterate.values, np.arange(1, 6))
    ys, vs, _ = naive_row(0.2, 0.8, 1.5, 0.3, 0, 5)
    np.testing.assert_array_equal(ds.y.values[0], ys)
    ds = orbit_diagram(0.2, [0.8], transient=2000, keep=200)
    assert ds.iterate.values[0] == 2001 and ds.iterate.values[-1] == 2200


def test_warm_start_continues_from_previous_last_state():
    us = np.linspace(0.6, 0.95, 9)
    ds = orbit_diagram(0.1, us, y0=0.1, v0=0.0, transient=50, keep=10, warm_start=True)
    assert ds.attrs["warm_start"] == 1
    y, v = 0.1, 0.0
    for i, u in enumerate(us):
        ys, vs, ks = naive_row(0.1, u, y, v, 50, 10)
        np.testing.assert_array_equal(ds.y.values[i], ys)
        np.testing.assert_array_equal(ds.impacts.values[i], ks)
        y, v = ys[-1], vs[-1]
    cold = orbit_diagram(0.1, us, y0=0.1, v0=0.0, transient=50, keep=10)
    np.testing.assert_array_equal(cold.y.values[0], ds.y.values[0])  # same start
    assert not np.array_equal(cold.y.values, ds.y.values)  # later rows differ


def test_dataset_layout_and_attributes():
    import stairbounce

    ds = orbit_diagram(0.1, np.linspace(0.3, 1.0, 11), y0=0.2, v0=-0.1, transient=7, keep=3)
    assert set(ds.data_vars) == {"y", "v", "impacts"}
    for name in ds.data_vars:
        assert ds[name].dims == ("u", "iterate")
    assert ds.impacts.dtype == np.int32
    assert float(ds.e) == 0.1
    assert ds.attrs["varied"] == "u"
    assert ds.attrs["e"] == 0.1
    assert (ds.attrs["y0"], ds.attrs["v0"]) == (0.2, -0.1)
    assert (ds.attrs["transient"], ds.attrs["keep"], ds.attrs["warm_start"]) == (7, 3, 0)
    assert ds.attrs["stairbounce_version"] == stairbounce.__version__
    np.testing.assert_array_equal(ds.u.values, np.linspace(0.3, 1.0, 11))


def test_netcdf_round_trip(tmp_path):
    ds = orbit_diagram(np.linspace(0.0, 0.5, 6), 0.7, transient=10, keep=4, warm_start=True)
    ds.to_netcdf(tmp_path / "o.nc")
    with xr.open_dataset(tmp_path / "o.nc") as back:
        xr.testing.assert_identical(back.load(), ds)


# --------------------------------------------------------------------------- #
# Validation                                                                  #
# --------------------------------------------------------------------------- #


@pytest.mark.parametrize(
    "kwargs, words",
    [
        (dict(e=1.0, u=[0.5]), "e (restitution"),
        (dict(e=[0.1, 1.2], u=0.5), "index 1"),
        (dict(e=-0.1, u=[0.5]), "[0, 1)"),
        (dict(e=[0.1, np.nan], u=0.5), "e (restitution"),
        (dict(e=0.1, u=[0.5, 0.0]), "u (horizontal speed) must be finite and > 0"),
        (dict(e=0.1, u=[0.5, np.inf]), "u (horizontal"),
        (dict(e=0.1, u=-1.0), "u (horizontal"),
        (dict(e=0.1, u=[[0.5, 0.6]]), "1-D"),
        (dict(e=0.1, u=[]), "non-empty"),
        (dict(e=0.1, u="fast"), "u must be a real number"),
        (dict(e=0.1, u=0.5), "exactly one of e, u"),
        (dict(e=[0.1], u=[0.5]), "exactly one of e, u"),
        (dict(e=0.1, u=[0.5], y0=-0.1), "y0"),
        (dict(e=0.1, u=[0.5], v0=np.nan), "v0"),
        (dict(e=0.1, u=[0.5], transient=-1), "transient must be an integer >= 0"),
        (dict(e=0.1, u=[0.5], transient=1.5), "transient"),
        (dict(e=0.1, u=[0.5], keep=0), "keep must be an integer >= 1"),
        (dict(e=0.1, u=[0.5], warm_start="yes"), "warm_start"),
    ],
)
def test_bad_input_raises_value_error_naming_the_parameter(kwargs, words):
    with pytest.raises(ValueError) as info:
        orbit_diagram(**kwargs)
    assert words in str(info.value)


# --------------------------------------------------------------------------- #
# Density                                                                     #
# --------------------------------------------------------------------------- #


def test_density_counts_every_point_once():
    ds = orbit_diagram(0.1, np.linspace(0.5, 1.0, 300), transient=500, keep=60)
    d = orbit_density(ds, bins=80)
    assert d.dims == ("u", "y")
    assert d.shape == (300, 80)
    assert int(d.sum()) == ds.y.size == d.attrs["points"] == d.attrs["points_in_range"]
    # one column per (evenly spaced) parameter value: each holds its keep points
    np.testing.assert_array_equal(d.sum("y").values, np.full(300, 60))
    np.testing.assert_allclose(d.u.values, ds.u.values, rtol=0, atol=1e-12)


def test_density_range_drops_points_outside():
    ds = orbit_diagram(0.1, np.linspace(0.5, 1.0, 200), transient=500, keep=50)
    lo, hi = 1.0005, 1.3
    d = orbit_density(ds, bins=33, component="y", range=(lo, hi), param_bins=17)
    y = ds.y.values
    inside = int(((y >= lo) & (y <= hi)).sum())
    assert 0 < inside < y.size
    assert int(d.sum()) == inside == d.attrs["points_in_range"]
    assert d.shape == (17, 33)
    np.testing.assert_allclose(d.attrs["range"], (lo, hi))


def test_density_cell_matches_a_manual_count():
    ds = orbit_diagram(np.linspace(0.0, 0.4, 50), 0.9, transient=200, keep=40)
    d = orbit_density(ds, bins=10, component="v", param_bins=5)
    v, e = ds.v.values, ds.e.values
    p_edges = np.linspace(*d.attrs["param_range"], 6)
    v_edges = np.linspace(*d.attrs["range"], 11)
    rows = (e >= p_edges[1]) & (e < p_edges[2])
    cell = (v[rows] >= v_edges[3]) & (v[rows] < v_edges[4])
    assert int(d.values[1, 3]) == int(cell.sum())


def test_density_of_a_single_branch():
    ds = orbit_diagram(E_SMALL, np.linspace(0.3, 0.6, 20), transient=50, keep=10)
    d = orbit_density(ds, bins=5)  # every point is y = 1 (tongue 1)
    assert int(d.sum()) == 200
    assert int(d.sel(y=1.0, method="nearest").sum()) == 200


@pytest.mark.parametrize(
    "kwargs, words",
    [
        (dict(component="x"), "component"),
        (dict(bins=0), "bins"),
        (dict(param_bins=0), "param_bins"),
        (dict(range=(2.0, 1.0)), "range"),
        (dict(range=(0.0, np.inf)), "range"),
    ],
)
def test_density_bad_input(kwargs, words):
    ds = orbit_diagram(0.1, [0.5, 0.6], transient=5, keep=5)
    with pytest.raises(ValueError) as info:
        orbit_density(ds, **kwargs)
    assert words in str(info.value)
    with pytest.raises(ValueError, match="orbit_diagram"):
        orbit_density(xr.Dataset())


# --------------------------------------------------------------------------- #
# Plot                                                                        #
# --------------------------------------------------------------------------- #


def test_plot_density_points_and_tongue_overlay():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from stairbounce.plot import plot_orbit_diagram

    ds = orbit_diagram(E_SMALL, np.linspace(0.3, 1.6, 200), transient=100, keep=20)
    fig, (a, b) = plt.subplots(1, 2)
    plot_orbit_diagram(ds, ax=a, overlay=("tongues",))
    assert len(a.images) == 1
    xs = {round(line.get_xdata()[0], 9) for line in a.lines if len(line.get_xdata())}
    for n in (2, 3, 4, 5):  # u_low = sqrt((n-1)/2) and u_high of Theorem 3.1
        lo, hi = tongue(n, E_SMALL)
        assert round(lo, 9) in xs
    assert round(tongue(1, E_SMALL)[1], 9) in xs
    assert all(0.3 <= x <= 1.6 for x in xs)
    plot_orbit_diagram(ds, ax=b, density=False, component="v")
    assert len(b.images) == 0 and b.get_ylabel().startswith("vertical velocity")
    with pytest.raises(ValueError, match="overlay"):
        plot_orbit_diagram(ds, overlay=("words",))
    plt.close("all")


def test_plot_tongue_overlay_when_e_is_swept():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from stairbounce.plot import plot_orbit_diagram

    u = 0.8  # tongue 2 (1/2 < u^2 <= 1): it ends where (1-e)/(1+e) = u
    ds = orbit_diagram(np.linspace(0.0, 0.5, 50), u, transient=100, keep=10)
    ax = plot_orbit_diagram(ds, overlay="tongues")
    xs = [line.get_xdata()[0] for line in ax.lines if len(line.get_xdata())]
    assert len(xs) == 1
    e_high = xs[0]
    assert math.isclose(tongue(2, e_high)[1], u, rel_tol=1e-12)
    plt.close("all")


def test_family_and_bound_overlay_at_the_jumps_of_e_0_3():
    """The one-impact families u_n(e) = sqrt(n (1-e) / (2 (1+e))) (formula
    written out here) and Corollary 2.1's (1-e)/(2 sqrt(2e)): at e = 0.3 the
    report's jumps 0.734, 0.899, 1.038, 1.160 and the sliding edge 0.452."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from stairbounce.plot import plot_orbit_diagram
    from stairbounce.plot.orbits import _family_lines

    families, bound = _family_lines("u", 0.3, 0.2, 1.2)
    assert [n for _, n in families] == [1, 2, 3, 4, 5]
    for pos, n in families:
        assert pos == pytest.approx(math.sqrt(n * 0.7 / (2 * 1.3)), rel=1e-14)
    assert [round(p, 3) for p, _ in families[1:]] == [0.734, 0.899, 1.038, 1.16]
    assert bound == pytest.approx(0.7 / (2 * math.sqrt(0.6)), rel=1e-14) and round(bound, 3) == 0.452
    ds = orbit_diagram(0.3, np.linspace(0.2, 1.2, 100), transient=100, keep=10)
    ax = plot_orbit_diagram(ds, overlay=("families", "bound"))
    xs = sorted(line.get_xdata()[0] for line in ax.lines if len(line.get_xdata()))
    np.testing.assert_allclose(xs, sorted([bound] + [p for p, _ in families]), rtol=1e-14)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any("one impact every n steps" in t for t in labels)
    assert any("Corollary 2.1" in t for t in labels)
    # the diagram jumps at u_2: the highest kept iterate just above it is far
    # above the highest just below (a new, longer jump opens)
    fine = orbit_diagram(0.3, np.array([families[1][0] - 0.01, families[1][0] + 0.01]),
                         transient=2000, keep=400)
    below, above = fine.y.values.max(axis=1)
    assert above > below + 0.1
    plt.close("all")


def test_family_and_bound_overlay_when_e_is_swept():
    from stairbounce.nonsliding import one_impact_family
    from stairbounce.plot.orbits import _family_lines

    u = 0.5
    families, bound = _family_lines("e", u, 0.0, 0.99)
    assert [n for _, n in families][:4] == [1, 2, 3, 4]
    for e_n, n in families:
        assert one_impact_family(n, e_n) == pytest.approx(u, rel=1e-12)
    assert (1 - bound) / (2 * math.sqrt(2 * bound)) == pytest.approx(u, rel=1e-12)
    assert _family_lines("e", u, 0.0, 0.2) == ([], None)


# --------------------------------------------------------------------------- #
# Command line                                                                #
# --------------------------------------------------------------------------- #


def run_cli(capsys, *args):
    with pytest.raises(SystemExit) as info:
        main(list(args))
    out, err = capsys.readouterr()
    return info.value.code, out, err


def test_cli_u_swept_writes_png_and_netcdf(tmp_path, capsys):
    png, nc = tmp_path / "fig8.png", tmp_path / "fig8.nc"
    code, out, err = run_cli(capsys, "orbit-diagram", "--e", "0.001", "--u", "0.3:1.6", "--n", "120",
                             "--transient", "300", "--keep", "30", "--overlay", "tongues,families",
                             "--overlay", "bound", "--png", str(png), "--out", str(nc))
    assert code == 0, err
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"
    assert "120 values of u x 30 iterates" in out
    with xr.open_dataset(nc) as ds:
        ref = orbit_diagram(0.001, pixel_centres(0.3, 1.6, 120), transient=300, keep=30)
        xr.testing.assert_identical(ds.load(), ref)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fig8.nc", "fig8.png"]  # no temp files


def test_cli_e_swept_writes_csv(tmp_path, capsys):
    csv = tmp_path / "d.csv"
    code, out, err = run_cli(capsys, "orbit-diagram", "--u", "0.6", "--e", "0:0.5", "--n", "25",
                             "--transient", "40", "--keep", "8", "--component", "v", "--points",
                             "--out", str(csv), "--png", str(tmp_path / "d.png"))
    assert code == 0, err
    import pandas as pd

    table = pd.read_csv(csv)
    assert list(table.columns[:2]) == ["e", "iterate"]
    assert len(table) == 25 * 8
    ref = orbit_diagram(pixel_centres(0, 0.5, 25), 0.6, transient=40, keep=8)
    np.testing.assert_array_equal(table["y"].values, ref.y.values.ravel())
    np.testing.assert_array_equal(table["impacts"].values, ref.impacts.values.ravel())


def test_cli_slices_behind_a_progress_bar_give_the_same_result(monkeypatch):
    from stairbounce.cli import orbits_commands

    monkeypatch.setattr(orbits_commands, "_PROGRESS_STEPS", 0)
    us = np.linspace(0.5, 1.0, 200)
    for warm in (False, True):
        sliced = orbits_commands._sweep(0.1, us, "u", 0.1, 0.0, 30, 5, warm)
        whole = orbit_diagram(0.1, us, 0.1, 0.0, 30, 5, warm)
        xr.testing.assert_identical(sliced, whole)


@pytest.mark.parametrize(
    "args, words",
    [
        (["--e", "0:0.2", "--u", "0.3:1"], "exactly one of --e, --u"),
        (["--e", "0.1", "--u", "0.5"], "exactly one of --e, --u"),
        (["--e", "0.1", "--u", "1:0.3"], "MIN < MAX"),
        (["--e", "0.1", "--u", "a:b"], "--u must be a range"),
        (["--e", "x", "--u", "0.3:1"], "--e must be a number"),
        (["--e", "0.5:1.5", "--u", "0.7"], "e (restitution coefficient) must be in [0, 1)"),
        (["--e", "0.1", "--u", "-1:1"], "u (horizontal speed)"),
        (["--e", "0.1", "--u", "0.3:1", "--n", "1"], "--n must be an integer >= 2"),
        (["--e", "0.1", "--u", "0.3:1", "--keep", "0"], "keep"),
        (["--e", "0.1", "--u", "0.3:1", "--transient", "-5"], "transient"),
        (["--e", "0.1", "--u", "0.3:1", "--y0", "-1"], "y0"),
        (["--e", "0.1", "--u", "0.3:1", "--component", "x"], "--component"),
        (["--e", "0.1", "--u", "0.3:1", "--overlay", "words"], "--overlay"),
        (["--e", "0.1", "--u", "0.3:1", "--range", "2:1"], "--range"),
        (["--e", "0.1", "--u", "0.3:1", "--png", "x.jpg"], "--png must end"),
        (["--e", "0.1", "--u", "0.3:1", "--out", "x.txt"], "--out must end"),
        (["--e", "0.1", "--u", "0.3:1", "--png", "no/such/dir/x.png"], "does not exist"),
        (["--e", "0.1", "--u", "0.3:1"], "nothing to write"),
        (["--e", "0.1"], "--u"),
    ],
)
def test_cli_bad_input_one_line_exit_2(tmp_path, capsys, monkeypatch, args, words):
    monkeypatch.chdir(tmp_path)
    if "--png" not in args and "--out" not in args and "nothing" not in words:
        args = [*args, "--png", "o.png"]
    code, out, err = run_cli(capsys, "orbit-diagram", *args)
    assert code == 2
    assert err.startswith("stairbounce: error:") and err.count("\n") == 1
    assert words in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow  # two interpreter start-ups that import numba
def test_console_script(tmp_path):
    script = Path(sys.executable).with_name("stairbounce")
    assert script.exists()
    png = tmp_path / "o.png"
    proc = subprocess.run(
        [str(script), "orbit-diagram",
         "--e", "0.1", "--u", "0.3:1.0", "--n", "50", "--transient", "100", "--keep", "10",
         "--png", str(png)],
        capture_output=True, text=True, timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert png.exists()
    bad = subprocess.run(
        [str(script), "orbit-diagram",
         "--e", "0.1", "--u", "0.3:1.0", "--n", "0", "--png", str(png)],
        capture_output=True, text=True, timeout=300,
    )
    assert bad.returncode == 2 and bad.stderr.startswith("stairbounce: error:")
