"""The (e, u) parameter-plane scan (Section 3, Figures 3-5): kernels against
references, the paper's theorems, invariances, files, the CLI."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numba
import numpy as np
import pytest
import xarray as xr

import stairbounce
from stairbounce import plane as sc
from stairbounce.model import _constants, _slide_or_steps, iterate, no_sliding_bound, tongue
from stairbounce.plane import (
    no_sliding_curve,
    pixel_centres,
    scan,
    scan_coords,
    scan_points,
    tongue_mask,
)
from stairbounce.symbolic import sliding_word
from tests import naive

from ._cli import run_cli as _run

FIELDS = ("status", "word_length", "jumps", "period", "impacts")
DATA = Path(__file__).parent / "data"


def _plain(es, us, max_iter=1000, y0=1.0, v0=0.0):
    """The closed-form baseline kernel on a grid, as a dict of arrays."""
    out = {k: np.empty((len(us), len(es)), dtype=dt) for k, (dt, _) in sc._FIELDS.items()}
    sc._scan_plain(np.asarray(es, float), np.asarray(us, float), max_iter, y0, v0,
                   out["status"], out["word_length"], out["jumps"], out["period"], out["impacts"])
    return out


_naive_step = numba.njit(naive.step)


@numba.njit
def _naive_pixel(y, v, e, u, max_iter):
    """tests/naive.py's impact-by-impact step, compiled: (steps, impacts, jumps)
    up to the first slide, steps 0 when it does not slide."""
    imp = 0
    jmp = 0
    for n in range(1, max_iter + 1):
        y, v, k = _naive_step(y, v, e, u, 10_000_000)
        if k == -1:
            return n, imp, jmp + 1
        if k > 0:
            imp += k
            jmp += 1
    return 0, imp, jmp


@numba.njit
def _naive_grid(es, us, max_iter, y0, v0, out):
    from_rest = y0 == 1.0 and v0 == 0.0
    for i in range(us.size):
        for j in range(es.size):
            n = 1
            if not from_rest:
                n, _, _ = _naive_pixel(y0, v0, es[j], us[i], max_iter)
            imp = 0
            jmp = 0
            if n != 0:
                n, imp, jmp = _naive_pixel(1.0, 0.0, es[j], us[i], max_iter)
            out[0, i, j] = n
            out[1, i, j] = imp if n else 0
            out[2, i, j] = jmp if n else 0


def _naive(es, us, max_iter=1000, y0=1.0, v0=0.0):
    out = np.zeros((3, len(us), len(es)), np.int64)
    _naive_grid(np.asarray(es, float), np.asarray(us, float), max_iter, y0, v0, out)
    return {"period": out[0], "impacts": out[1], "jumps": out[2]}


def _random_grid(seed, n_e, n_u, u_max=1.5):
    rng = np.random.default_rng(seed)
    return np.sort(rng.uniform(0.0, 1.0, n_e)), np.sort(rng.uniform(1e-3, u_max, n_u))


def _disagreements(ds, ref):
    bad = np.zeros(ds["status"].shape, dtype=bool)
    for k in ref:
        bad |= ds[k].values != ref[k]
    return bad


def _near_boundary(e, u, answer, max_iter, rel=1e-9):
    """Whether the scan's answer changes within a relative distance ``rel`` of
    (e, u): the pixel then sits on a boundary up to rounding."""
    es = np.array([e * (1 - rel), e, min(e * (1 + rel), np.nextafter(1.0, 0.0))])
    us = np.array([u * (1 - rel), u, u * (1 + rel)])
    d = scan_coords(es, us, max_iter)
    vals = {(int(d.period.values[i, j]), int(d.impacts.values[i, j])) for i in range(3) for j in range(3)}
    return len(vals) > 1 or answer not in vals


# --------------------------------------------------------------------------- #
# Dataset layout                                                              #
# --------------------------------------------------------------------------- #


def test_pixel_centres_cover_the_window():
    c = pixel_centres(0.0, 1.5, 350)
    step = 1.5 / 350
    assert c.shape == (350,)
    assert c[0] == pytest.approx(step / 2) and c[-1] == pytest.approx(1.5 - step / 2)
    assert np.allclose(np.diff(c), step)
    assert c.min() > 0.0
    assert np.array_equal(pixel_centres(0.2, 0.4, 1), [0.30000000000000004])


def test_scan_dataset_layout_and_attributes():
    ds = scan(e=(0.1, 0.3, 7), u=(0.4, 0.9, 5), max_iter=50)
    assert ds["status"].dims == ("u", "e")
    assert ds.sizes == {"u": 5, "e": 7}
    assert set(ds.data_vars) == set(FIELDS)
    assert np.array_equal(ds.e.values, pixel_centres(0.1, 0.3, 7))
    assert np.array_equal(ds.u.values, pixel_centres(0.4, 0.9, 5))
    a = ds.attrs
    assert (a["e_min"], a["e_max"], a["n_e"]) == (0.1, 0.3, 7)
    assert (a["u_min"], a["u_max"], a["n_u"]) == (0.4, 0.9, 5)
    assert (a["max_iter"], a["y0"], a["v0"]) == (50, 1.0, 0.0)
    assert a["stairbounce_version"] == stairbounce.__version__
    assert "word_length = impacts + 1" in a["convention"]
    assert a["kernel"] == "stairbounce.plane._scan_fast"


def test_fields_are_consistent():
    ds = scan(e=(0.0, 0.4, 60), u=(0.0, 1.5, 60), max_iter=300)
    s = ds.status.values
    assert set(np.unique(s)) == {0, 1}
    none = s == 1
    for k in ("word_length", "jumps", "period", "impacts"):
        assert (ds[k].values[none] == 0).all()
    found = ~none
    wl, imp, jmp, per = (ds[k].values[found] for k in ("word_length", "impacts", "jumps", "period"))
    assert np.array_equal(wl, imp + 1)
    assert (jmp >= 1).all() and (jmp <= wl).all() and (jmp <= per).all()
    assert (per >= 1).all() and (per <= 300).all()


# --------------------------------------------------------------------------- #
# Kernels against references                                                  #
# --------------------------------------------------------------------------- #


def test_every_pixel_agrees_with_sliding_word():
    es, us = _random_grid(3, 23, 17)
    ds = scan_coords(es, us, max_iter=400)
    for i, u in enumerate(us):
        for j, e in enumerate(es):
            w = sliding_word(e, u, max_iter=400)
            got = {k: int(ds[k].values[i, j]) for k in FIELDS}
            if w is None:
                assert got == dict.fromkeys(FIELDS, 0) | {"status": 1}, (e, u)
            else:
                assert got == {"status": 0, "word_length": len(w), "jumps": w.jumps,
                               "period": w.period, "impacts": w.impacts}, (e, u, str(w))


@pytest.mark.parametrize("seed", [0, 1])
def test_fast_plain_and_naive_agree_on_random_grids(seed):
    es, us = _random_grid(seed, 120, 90)
    ds = scan_coords(es, us, max_iter=1000)
    plain = _plain(es, us)
    ref = _naive(es, us)
    n = ds.status.size
    for name, other in (("plain", plain), ("naive", ref)):
        bad = _disagreements(ds, {k: other[k] for k in ("period", "impacts", "jumps")})
        # measured: no disagreement at all on 600 000 random points (see the report)
        assert bad.sum() <= 1e-3 * n, (name, int(bad.sum()))
        for i, j in np.argwhere(bad):
            answer = (int(ds.period.values[i, j]), int(ds.impacts.values[i, j]))
            assert _near_boundary(es[j], us[i], answer, 1000), (name, es[j], us[i])
    # plain and fast evaluate the same map: their results coincide bit for bit here
    for k in FIELDS:
        assert np.array_equal(ds[k].values, plain[k]), k


def test_fast_kernel_equals_model_step_iteration():
    """Pixel by pixel, the fast kernel is model._slide_or_steps (model._step)."""
    es, us = _random_grid(7, 40, 30)
    ds = scan_coords(es, us, max_iter=700)
    for i, u in enumerate(us):
        for j, e in enumerate(es):
            T, ratio = _constants(e, u)
            n, imp, jmp = _slide_or_steps(1.0, 0.0, e, T, ratio, 700)
            assert int(ds.period.values[i, j]) == n
            if n:
                assert (int(ds.impacts.values[i, j]), int(ds.jumps.values[i, j])) == (imp, jmp)


def test_many_impacts_per_step():
    """At larger e and small u many steps have several impacts: the lanes count
    on past the first impact and fall back to the closed form past
    model._COUNTED_IMPACTS.  Compare with the impact-by-impact loop."""
    es = np.linspace(0.5, 0.99, 60)
    us = np.linspace(0.01, 0.3, 60)
    ds = scan_coords(es, us, max_iter=300)
    ref = _naive(es, us, 300)
    for k in ref:
        assert np.array_equal(ds[k].values, ref[k]), k
    # the window does exercise both paths
    ks = np.concatenate([iterate(1.0, 0.0, e, u, 300)[2] for e in es[::3] for u in us[::3]])
    assert (ks >= 2).sum() > 100 and (ks >= 8).sum() > 10


@pytest.mark.parametrize("y0,v0", [(0.1, 0.0), (2.5, -0.7), (1.0, 0.4)])
def test_transient_then_period_from_rest(y0, v0):
    """From (y0, v0) != (1, 0): a transient up to the first slide, then the
    period is measured from (1, 0); status 0 only if both slide."""
    es, us = _random_grid(11, 50, 40)
    ds = scan_coords(es, us, max_iter=300, y0=y0, v0=v0)
    assert (ds.attrs["y0"], ds.attrs["v0"]) == (y0, v0)
    plain = _plain(es, us, 300, y0, v0)
    ref = _naive(es, us, 300, y0, v0)
    for k in FIELDS:
        assert np.array_equal(ds[k].values, plain[k]), k
    for k in ref:
        assert np.array_equal(ds[k].values, ref[k]), k
    from_rest = scan_coords(es, us, max_iter=300)
    both = (ds.status.values == 0)
    # where the transient slides, the periodic solution is the one from (1, 0)
    for k in ("period", "impacts", "jumps"):
        assert np.array_equal(ds[k].values[both], from_rest[k].values[both])
    # and a transient that does not slide leaves status 1 where (1, 0) would slide
    assert ((from_rest.status.values == 0) | (ds.status.values == 1)).all()


def test_transient_that_never_slides_gives_status_1():
    # e = 0.5, u = 1.2 lies above the Corollary 2.1 curve: nothing slides
    ds = scan_coords([0.5], [1.2], max_iter=200, y0=0.1, v0=0.0)
    assert ds.status.values.item() == 1 and ds.period.values.item() == 0


# --------------------------------------------------------------------------- #
# The paper's theorems                                                        #
# --------------------------------------------------------------------------- #


@pytest.fixture(scope="module")
def paper_grid():
    """The paper's grid: 500 x 350 over (0, 1) x (0, 1.5), max_iter 1000."""
    return scan()


def test_word_length_one_is_the_union_of_theorem_3_1_tongues(paper_grid):
    """Figure 3 = the word-length-1 part of Figure 4, away from a one-pixel band
    at the tongue boundaries."""
    ds = paper_grid
    E, U = np.meshgrid(ds.e.values, ds.u.values)
    mask = tongue_mask(E, U, n_max=100)
    one = (ds.status.values == 0) & (ds.word_length.values == 1)
    # pixels whose 3 x 3 neighbourhood straddles a tongue boundary
    pad = np.pad(mask, 1, mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(pad, (3, 3))
    band = windows.any(axis=(2, 3)) != windows.all(axis=(2, 3))
    assert mask.sum() > 0.15 * mask.size  # the tongues: a fifth of Figure 4's plane
    assert np.array_equal(one[~band], mask[~band])
    # the band is thin: a one-pixel outline of the tongues
    assert band.sum() < 0.05 * band.size
    # inside the band only pixels within rounding of (3.1) may differ (measured: none)
    assert (one[band] != mask[band]).sum() <= 0.01 * band.sum()


def test_no_sliding_above_corollary_2_1(paper_grid):
    ds = paper_grid
    E, U = np.meshgrid(ds.e.values, ds.u.values)
    above = U >= no_sliding_curve(E)
    assert above.sum() > 0.5 * above.size
    assert (ds.status.values[above] == 1).all()
    # and the sliding set reaches up to the curve (the bound is sharp, Section 3)
    sliding = ds.status.values == 0
    rows_top = np.array([U[sliding[:, j], j].max() for j in range(0, 500, 50)])
    curve = no_sliding_curve(ds.e.values[::50])
    assert np.all(rows_top > 0.85 * np.minimum(curve, 1.5))


def test_paper_grid_has_the_fractal_between_tongues(paper_grid):
    ds = paper_grid
    found = ds.status.values == 0
    assert 0.2 < found.mean() < 0.3
    # words longer than 1 live between the tongues
    assert (ds.word_length.values > 1).sum() > 1000
    assert ds.word_length.values.max() > 100


def test_tongue_mask_matches_model_tongue():
    rng = np.random.default_rng(5)
    e = rng.uniform(0, 1, 500)
    u = rng.uniform(1e-3, 2.0, 500)
    got = tongue_mask(e, u, n_max=4)
    for x, y, g in zip(e, u, got):
        want = any(lo < y <= hi for lo, hi in (tongue(n, x) for n in range(1, 5)))
        assert g == want
    # broadcasting
    assert tongue_mask(np.array([0.1, 0.2]), np.array([[0.3], [0.75], [5.0]]), 3).shape == (3, 2)
    assert tongue_mask(0.1, 0.3, 1).item() is True
    # the boundaries: u_low excluded, u_high included
    lo, hi = tongue(3, 0.01)
    assert not tongue_mask(0.01, lo, 3) and tongue_mask(0.01, hi, 3)
    with pytest.raises(ValueError, match="n_max"):
        tongue_mask(0.1, 0.3, 0)


def test_no_sliding_curve_matches_corollary():
    e = np.array([0.0, 0.01, 0.3, 0.99])
    c = no_sliding_curve(e)
    assert c[0] == math.inf
    assert np.allclose(c[1:], [no_sliding_bound(x) for x in e[1:]])


# --------------------------------------------------------------------------- #
# Invariances                                                                 #
# --------------------------------------------------------------------------- #


def test_thread_count_invariance():
    before = numba.get_num_threads()
    try:
        results = []
        for n in sorted({1, numba.config.NUMBA_NUM_THREADS}):
            numba.set_num_threads(n)
            results.append(scan(e=(0.0, 0.4, 130), u=(0.3, 1.3, 90), max_iter=600))
    finally:
        numba.set_num_threads(before)
    for k in FIELDS:
        assert np.array_equal(results[0][k].values, results[-1][k].values), k


# --------------------------------------------------------------------------- #
# scan_points: the same kernel on a list of points                            #
# --------------------------------------------------------------------------- #


def _assert_points_equal_grid(pts, grid, rows, cols):
    for k in FIELDS:
        assert pts[k].dtype == grid[k].dtype, k
        assert np.array_equal(pts[k].values, grid[k].values[rows, cols]), k


def test_scan_points_equals_scan_on_a_flattened_grid():
    # straddles the Corollary 2.1 curve and the first tongues: pruned,
    # sliding and non-sliding pixels, transients from a start y0 < 1
    for y0, v0 in ((1.0, 0.0), (0.3, -0.7)):
        grid = scan(e=(0.0, 0.6, 53), u=(0.0, 1.5, 47), max_iter=400, y0=y0, v0=v0)
        E, U = np.meshgrid(grid.e.values, grid.u.values)
        pts = scan_points(E.ravel(), U.ravel(), max_iter=400, y0=y0, v0=v0)
        assert pts.sizes == {"point": E.size}
        assert np.array_equal(pts.e.values, E.ravel()) and np.array_equal(pts.u.values, U.ravel())
        rows, cols = np.divmod(np.arange(E.size), E.shape[1])
        _assert_points_equal_grid(pts, grid, rows, cols)
        same = {k: v for k, v in grid.attrs.items() if not k.startswith(("e_", "u_", "n_"))}
        assert pts.attrs == same


def test_scan_points_random_points_equal_scan_coords():
    # shuffled points of a random (unevenly spaced) grid: each point's answer
    # is scan_coords' at its (e, u), whatever its neighbours in the list
    es, us = _random_grid(7, 61, 43)
    grid = scan_coords(es, us, max_iter=700)
    rng = np.random.default_rng(8)
    rows = rng.integers(0, us.size, 5000)
    cols = rng.integers(0, es.size, 5000)
    pts = scan_points(es[cols], us[rows], max_iter=700)
    _assert_points_equal_grid(pts, grid, rows, cols)
    # and against the closed-form baseline, point by point (a 1 x 1 grid each)
    ref = _plain(es[cols[:200]], us[rows[:200]], max_iter=700)
    for k in ("status", "period", "impacts"):
        assert np.array_equal(np.diag(ref[k]), pts[k].values[:200]), k


def test_scan_points_thread_count_invariance():
    rng = np.random.default_rng(3)
    e = rng.uniform(0.0, 0.5, 6000)
    u = rng.uniform(0.05, 1.3, 6000)
    before = numba.get_num_threads()
    try:
        results = []
        for n in sorted({1, numba.config.NUMBA_NUM_THREADS}):
            numba.set_num_threads(n)
            results.append(scan_points(e, u, max_iter=500))
    finally:
        numba.set_num_threads(before)
    for k in FIELDS:
        assert np.array_equal(results[0][k].values, results[-1][k].values), k


def test_scan_points_empty_and_scalar_like_inputs():
    ds = scan_points([], [], max_iter=10)
    assert ds.sizes == {"point": 0} and set(ds.data_vars) == set(FIELDS)
    one = scan_points([0.2], (0.5,), max_iter=300)
    ref = scan_coords([0.2], [0.5], max_iter=300)
    for k in FIELDS:
        assert one[k].values[0] == ref[k].values[0, 0], k


@pytest.mark.parametrize(
    "e, u, kwargs, match",
    [
        ([0.1, 0.2], [0.5], {}, "e and u must have the same length, got 2 and 1"),
        ([[0.1]], [0.5], {}, r"e must be a 1-D array, got shape \(1, 1\)"),
        (0.1, [0.5], {}, r"e must be a 1-D array, got shape \(\)"),
        ([0.1], [[0.5]], {}, r"u must be a 1-D array"),
        (["a"], [0.5], {}, "e must be a 1-D array of real numbers"),
        ([1.0], [0.5], {}, r"e \(restitution coefficient\) values must be in \[0, 1\)"),
        ([0.1], [0.0], {}, r"u \(horizontal speed\) values must be > 0"),
        ([np.nan], [0.5], {}, "e values must be finite"),
        ([0.1], [0.5], {"max_iter": 0}, "max_iter must be an integer >= 1"),
        ([0.1], [0.5], {"y0": -0.5}, r"y0 \(height above the step.s floor\) must be >= 0"),
        ([0.1], [0.5], {"v0": math.inf}, "v0 must be finite"),
    ],
)
def test_scan_points_validation(e, u, kwargs, match):
    with pytest.raises(ValueError, match=match):
        scan_points(e, u, **kwargs)


def test_scan_points_memory_refusal(monkeypatch):
    monkeypatch.setattr(sc, "_available_memory", lambda: 10_000)
    with pytest.raises(ValueError, match=r"a scan of 1000 points needs about 40\.0 KiB"):
        scan_points(np.full(1000, 0.2), np.full(1000, 0.5), max_iter=5)
    assert sc.estimate_points_bytes(1000) == 1000 * (25 + 16)
    assert scan_points(np.full(10, 0.2), np.full(10, 0.5), max_iter=5).sizes == {"point": 10}


def test_tiles_equal_the_whole_scan():
    whole = scan(e=(0.0, 0.3, 97), u=(0.3, 0.7, 61), max_iter=500)
    es, us = whole.e.values, whole.u.values
    cuts_e, cuts_u = [0, 13, 50, 97], [0, 1, 30, 61]
    for a, b in zip(cuts_u[:-1], cuts_u[1:]):
        for c, d in zip(cuts_e[:-1], cuts_e[1:]):
            tile = scan_coords(es[c:d], us[a:b], max_iter=500)
            for k in FIELDS:
                assert np.array_equal(tile[k].values, whole[k].values[a:b, c:d]), (k, a, c)


def test_progress_blocks_give_the_same_scan():
    calls = []
    plain = scan(e=(0.0, 0.3, 40), u=(0.3, 0.7, 120), max_iter=300)
    blocks = scan(e=(0.0, 0.3, 40), u=(0.3, 0.7, 120), max_iter=300,
                  progress=lambda done, total: calls.append((done, total)))
    assert plain.identical(blocks)
    assert calls[0] == (0, 120) and calls[-1] == (120, 120) and len(calls) > 10
    assert [c[0] for c in calls] == sorted(c[0] for c in calls)


def test_regression_pin_figure_5e():
    """A committed 100 x 100 scan of the Figure 5e window (tests/data/fig5e.npz,
    picture beside it); scripts/regenerate_reference.py rewrites both."""
    ref = np.load(DATA / "fig5e.npz")
    ds = scan(e=(0.04, 0.065, 100), u=(0.92, 0.945, 100), max_iter=int(ref["max_iter"]))
    assert np.array_equal(ds.e.values, ref["e"]) and np.array_equal(ds.u.values, ref["u"])
    for k in FIELDS:
        assert np.array_equal(ds[k].values, ref[k]), k
    assert (DATA / "fig5e.png").exists()


# --------------------------------------------------------------------------- #
# Files                                                                       #
# --------------------------------------------------------------------------- #


@pytest.mark.parametrize("suffix", [".zarr", ".nc"])
def test_save_load_round_trip(tmp_path, suffix):
    ds = scan(e=(0.0, 0.5, 30), u=(0.2, 1.0, 20), max_iter=200, y0=1.5, v0=-0.25)
    path = tmp_path / f"scan{suffix}"
    sc.save(ds, path)
    back = sc.load(path)
    assert back.identical(ds)
    for k in FIELDS:
        assert back[k].dtype == ds[k].dtype
    assert back.attrs == ds.attrs
    # nothing left beside it but the file itself
    assert [p.name for p in tmp_path.iterdir()] == [path.name]
    # replacing an existing file needs overwrite=True, and is atomic too
    with pytest.raises(ValueError, match="exists: not replaced"):
        sc.save(ds.isel(e=slice(0, 5)), path)
    sc.save(ds.isel(e=slice(0, 5)), path, overwrite=True)
    assert sc.load(path).sizes["e"] == 5


def test_zarr_is_chunked(tmp_path):
    import zarr

    ds = scan(e=(0.0, 0.5, 40), u=(0.2, 1.0, 30), max_iter=50)
    sc.save(ds, tmp_path / "s.zarr", chunks=16)
    z = zarr.open_group(str(tmp_path / "s.zarr"), mode="r")
    assert z["word_length"].chunks == (16, 16)


def test_save_refuses_bad_paths(tmp_path):
    ds = scan(e=(0.0, 0.5, 4), u=(0.2, 1.0, 3), max_iter=10)
    with pytest.raises(ValueError, match=r"\.zarr or \.nc"):
        sc.save(ds, tmp_path / "scan.csv")
    with pytest.raises(ValueError, match="does not exist"):
        sc.save(ds, tmp_path / "missing" / "scan.nc")
    with pytest.raises(ValueError, match="no such file"):
        sc.load(tmp_path / "nothing.nc")


# --------------------------------------------------------------------------- #
# Validation and memory                                                       #
# --------------------------------------------------------------------------- #


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"e": (-0.1, 0.5, 10)}, r"e window must lie in \[0, 1\]"),
        ({"e": (0.5, 1.2, 10)}, r"e window must lie in \[0, 1\]"),
        ({"e": (0.5, 0.5, 10)}, "e_min must be < e_max"),
        ({"e": (0.0, 0.5, 0)}, "n_e must be an integer >= 1"),
        ({"e": (0.0, 0.5, 2.5)}, "n_e must be an integer"),
        ({"e": (0.0,)}, r"e must be a tuple \(e_min, e_max\) or \(e_min, e_max, n_e\)"),
        ({"e": (0.0, 0.5, 3, 4)}, r"e must be a tuple \(e_min, e_max\) or \(e_min, e_max, n_e\)"),
        ({"e": ("a", 0.5, 3)}, "e_min must be a real number"),
        ({"u": (-1.0, 1.0, 10)}, r"u window must lie in \[0, inf\)"),
        ({"u": (1.0, 0.5, 10)}, "u_min must be < u_max"),
        ({"u": (0.0, math.inf, 10)}, "u_max must be finite"),
        ({"u": (0.0, 1.0, -3)}, "n_u must be an integer >= 1"),
        ({"max_iter": 0}, "max_iter must be an integer >= 1"),
        ({"y0": -1.0}, "y0"),
        ({"v0": math.nan}, "v0 must be finite"),
    ],
)
def test_scan_validation(kwargs, match):
    args = {"e": (0.0, 0.5, 4), "u": (0.1, 1.0, 3), "max_iter": 10} | kwargs
    with pytest.raises(ValueError, match=match):
        scan(**args)


@pytest.mark.parametrize(
    "es, us, match",
    [
        ([0.1, 1.0], [0.5], r"e \(restitution coefficient\) values must be in \[0, 1\)"),
        ([-0.1], [0.5], r"e \(restitution coefficient\)"),
        ([0.1], [0.0, 0.5], r"u \(horizontal speed\) values must be > 0"),
        ([0.1], [np.nan], "u values must be finite"),
        ([], [0.5], "e values must be a non-empty 1-D array"),
        ([[0.1]], [0.5], "e values must be a non-empty 1-D array"),
    ],
)
def test_scan_coords_validation(es, us, match):
    with pytest.raises(ValueError, match=match):
        scan_coords(es, us, max_iter=10)


def test_memory_refusal_names_the_estimate(monkeypatch):
    with pytest.raises(ValueError, match=r"needs about .* more than the .* of memory available"):
        scan(e=(0.0, 1.0, 10**7), u=(0.1, 1.5, 10**7))
    monkeypatch.setattr(sc, "_available_memory", lambda: 10_000)
    with pytest.raises(ValueError, match=r"100 x 100 pixels needs about 245\.7 KiB"):
        scan(e=(0.0, 1.0, 100), u=(0.1, 1.5, 100))
    with pytest.raises(ValueError, match="needs about"):
        scan_coords(np.linspace(0.1, 0.5, 100), np.linspace(0.1, 1, 100))
    assert sc.estimate_bytes(100, 100) == 100 * 100 * 25 + 8 * 200
    monkeypatch.setattr(sc, "_available_memory", lambda: None)  # unknown: allowed
    assert scan(e=(0.0, 1.0, 3), u=(0.1, 1.5, 2), max_iter=5).sizes == {"u": 2, "e": 3}


def test_core_module_imports_no_plotting_or_cli():
    code = ("import sys, stairbounce.plane; "
            "bad = [m for m in ('matplotlib', 'typer', 'bokeh', 'panel') if m in sys.modules]; "
            "print(bad); sys.exit(1 if bad else 0)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr


# --------------------------------------------------------------------------- #
# Plotting                                                                    #
# --------------------------------------------------------------------------- #


def test_plot_scan(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from stairbounce.plot import plot_scan

    ds = scan(e=(0.0, 0.4, 80), u=(0.2, 1.2, 60), max_iter=300)
    for field in ("word_length", "period", "impacts", "jumps", "status"):
        fig, ax = plt.subplots()
        out = plot_scan(ds, field=field, ax=ax, overlay=("tongues", "bound"))
        assert out is ax
        im = ax.get_images()[0]
        assert im.get_extent() == [0.0, 0.4, 0.2, 1.2]
        data = im.get_array()
        # white (masked) exactly where no periodic sliding solution was found
        assert np.array_equal(np.ma.getmaskarray(data), ds.status.values == 1)
        assert ax.get_xlabel().startswith("e") and ax.get_ylabel().startswith("u")
        assert len(ax.get_lines()) >= 2  # tongue boundaries and the bound
        fig.savefig(tmp_path / f"{field}.png")
        plt.close(fig)
    fig, ax = plt.subplots()
    plot_scan(ds, ax=ax)
    # the fixed discrete word-length classes (1, 2, 3, 4, 5, 6-7, ...), not a scale fitted to the data
    assert type(ax.get_images()[0].norm).__name__ == "BoundaryNorm"
    assert list(ax.get_images()[0].norm.boundaries[:7]) == [1, 2, 3, 4, 5, 6, 8]
    assert len(fig.axes) == 2  # the colour bar
    plt.close(fig)
    # a dataset reduced to one variable (as the atlas renderer passes) still plots
    ax = plot_scan(ds[["word_length"]])
    assert np.array_equal(np.ma.getmaskarray(ax.get_images()[0].get_array()), ds.status.values == 1)
    plt.close(ax.figure)
    with pytest.raises(ValueError, match="field must be one of"):
        plot_scan(ds, field="colour")
    with pytest.raises(ValueError, match="overlay must be among tongues, bound, got 'grid'"):
        plot_scan(ds, overlay=("grid",))


def test_every_plot_refuses_an_unknown_overlay_by_name():
    """The three plots with overlays check them the same way (_validate.among)."""
    from stairbounce import nonsliding, orbits
    from stairbounce.plot import plot_motion, plot_orbit_diagram

    motion = nonsliding.motion_scan(e=(0.1, 0.2, 4), u=(0.5, 0.6, 3), steps=10, transient=0)
    with pytest.raises(ValueError, match="overlay must be among families, bound, got 'grid'"):
        plot_motion(motion, overlay=("grid",))
    diagram = orbits.orbit_diagram(e=0.1, u=(0.5, 0.6, 3), transient=2, keep=2)
    with pytest.raises(ValueError, match="overlay must be among tongues, families, bound, got 'grid'"):
        plot_orbit_diagram(diagram, overlay="grid")


# --------------------------------------------------------------------------- #
# Command line                                                                #
# --------------------------------------------------------------------------- #


def test_cli_scan_writes_data_and_figure(tmp_path, capsys):
    out, png = tmp_path / "s.zarr", tmp_path / "s.png"
    code, stdout, err = _run(["scan", "--e", "0:0.3", "--u", "0.3:0.7", "--size", "60x40",
                              "--max-iter", "200", "--out", str(out), "--png", str(png),
                              "--overlay", "tongues,bound", "--field", "period"], capsys)
    assert code == 0, err
    assert f"wrote {out}" in stdout and f"wrote {png}" in stdout
    assert "60 x 40 pixels" in stdout and "periodic sliding solution at" in stdout
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    got = sc.load(out)
    assert got.identical(scan(e=(0.0, 0.3, 60), u=(0.3, 0.7, 40), max_iter=200))


def test_cli_scan_defaults_are_figure_4(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, stdout, err = _run(["scan", "--out", "fig4.nc"], capsys)
    assert code == 0, err
    assert not (tmp_path / "scan.png").exists()  # a picture only where asked (--png)
    ds = sc.load(tmp_path / "fig4.nc")
    a = ds.attrs
    assert (a["e_min"], a["e_max"], a["n_e"], a["u_min"], a["u_max"], a["n_u"], a["max_iter"]) == (
        0.0, 1.0, 500, 0.0, 1.5, 350, 1000)
    assert ds.u.values.min() > 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fig4.nc"]


@pytest.mark.parametrize(
    "args, message",
    [
        (["--e", "0:1.5"], "e window must lie in [0, 1]"),
        (["--e", "-0.5:0.5"], "e window must lie in [0, 1]"),
        (["--u", "-1:1"], "u window must lie in [0, inf)"),
        (["--u", "1:1"], "--u must have MIN < MAX"),
        (["--e", "0.5:0.2"], "--e must have MIN < MAX"),
        (["--size", "0x10"], "--size must have WIDTH >= 1"),
        (["--size", "ax10"], "--size must be WIDTHxHEIGHT"),
        (["--max-iter", "0"], "--max-iter must be an integer >= 1"),
        (["--max-iter", "x"], "max-iter"),
        (["--e", "a:b"], "--e must be a range MIN:MAX of numbers"),
        (["--field", "colour"], "--field must be one of"),
        (["--overlay", "grid"], "--overlay must be among tongues, bound (comma-separated or repeated)"),
        (["--out", "x.csv"], "--out must end in .zarr or .nc"),
        (["--png", "x.jpg"], "--png must end in .png, .pdf or .svg"),
        (["--y0", "-1"], "--y0 must be >= 0"),
        (["--size", "10000000x10000000"], "needs about"),
    ],
)
def test_cli_scan_bad_input_is_one_line_and_exit_2(args, message, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, err = _run(["scan", *args], capsys)
    assert code == 2
    assert err.startswith("stairbounce: error:") and err.count("\n") == 1, err
    assert message in err
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_console_script_exit_status(tmp_path):
    exe = Path(sys.executable).with_name("stairbounce")
    r = subprocess.run([str(exe), "scan", "--e", "0:1.5"], capture_output=True, text=True, cwd=tmp_path)
    assert r.returncode == 2
    assert r.stderr.strip().startswith("stairbounce: error:") and "Traceback" not in r.stderr


def test_tongue_mask_is_one_test_per_point():
    """Report D12: tongue_mask(0.1, 1e10, 10**12) looped over 2e20 tongues.  The
    one-tongue form equals the loop over n of inequalities (3.1)."""
    rng = np.random.default_rng(3)
    e = np.concatenate([rng.uniform(0, 1, 3000), [0.0, 0.5]])
    u = np.concatenate([10.0 ** rng.uniform(-150, 1.5, 3000), [1e-150, 2.0]])
    for n_max in (1, 2, 5, 40, 10**6):
        loop = np.zeros(e.shape, bool)
        for n in range(1, min(n_max, 2 * 32**2 + 2) + 1):
            loop |= (math.sqrt((n - 1) / 2.0) < u) & (u <= math.sqrt(n / 2.0) * (1 - e) / (1 + e))
        assert np.array_equal(tongue_mask(e, u, n_max), loop), n_max
    assert not tongue_mask(0.1, 1e10, 10**12)  # (1-e)/(1+e) < 1: above every tongue


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: tongue_mask(0.1, float("inf"), 5), "^u (values )?must be finite"),
        (lambda: tongue_mask(float("nan"), 0.5, 5), "^e (values )?must be finite"),
        (lambda: tongue_mask(-1, 0.5, 5), r"e \(restitution coefficient\) values must be in \[0, 1\)"),
        (lambda: tongue_mask("abc", 0.5, 5), "e must be a real number"),
        (lambda: no_sliding_curve(None), "e must be a real number"),
        (lambda: no_sliding_curve(2), r"e \(restitution coefficient\) values must be finite and in \[0, 1\]"),
        (lambda: sc.estimate_bytes(-1, 10), r"n_e must be an integer >= 1"),
        (lambda: sc.estimate_bytes(10, 1.5), r"n_u must be an integer >= 1"),
        (lambda: pixel_centres(1, 0, 4), "lo must be < hi"),
        (lambda: pixel_centres(-1.7e308, 1.7e308, 4), "hi - lo finite"),
        (lambda: pixel_centres(0, 1, 10**12), r"n = 1000000000000 pixel centres needs about"),
    ],
)
def test_plane_helpers_validate(call, match):
    with pytest.raises(ValueError, match=match):
        call()


# --------------------------------------------------------------------------- #
# What scan() does around its kernel (issue 26, eighth round)                 #
# --------------------------------------------------------------------------- #


@pytest.mark.parametrize(
    "window",
    [
        {"e": (0.0, 1e-17, 10)},  # centres in (0, 2^-53)
        {"e": (0.0, 2e-16, 1)},
        {"u": (0.0, 5e-324, 2)},  # the first centre underflows to 0
        {"u": (1e149, 1e151, 3)},  # above U_MAX
        {"u": (0.0, 1e-151, 2)},  # below U_MIN
    ],
)
def test_scan_refuses_bad_centres_as_scan_coords_does(window):
    # scan() checks its pixel centres from the least and the largest only
    # (plane._check_centres): the same refusals, word for word, as scan_coords
    # checking every centre
    args = {"e": (0.0, 1.0, 4), "u": (0.1, 1.0, 3)} | window
    es, us = pixel_centres(*args["e"]), pixel_centres(*args["u"])
    with pytest.raises(ValueError) as whole:
        scan_coords(es, us, max_iter=5)
    with pytest.raises(ValueError) as ends:
        scan(**args, max_iter=5)
    assert str(ends.value) == str(whole.value)


def test_the_fast_dataset_is_the_public_constructors():
    # plane._dataset hands the variables and indexes to xarray's private fast
    # path; the result must be what xr.Dataset(...) builds, invariants included
    for ds in (scan((0.1, 0.9, 7), (0.2, 1.4, 5), max_iter=50),
               scan_points([0.3, 0.5, 0.7], [0.4, 0.4, 0.9], max_iter=50)):
        data_vars = {k: (ds[k].dims, ds[k].values, ds[k].attrs) for k in ds.data_vars}
        coords = {k: (ds[k].dims, ds[k].values, ds[k].attrs) for k in ds.coords}
        public = xr.Dataset(data_vars, coords=coords, attrs=ds.attrs)
        xr.testing.assert_identical(ds, public)
        assert list(ds.variables) == list(public.variables)
        assert set(ds.xindexes) == set(public.xindexes)
        xr.testing._assert_internal_invariants(ds, check_default_indexes=True)
    grid = scan((0.1, 0.9, 7), (0.2, 1.4, 5), max_iter=50)
    assert set(grid.xindexes) == {"e", "u"}  # a dimension coordinate selects
    assert grid.sel(e=0.5, method="nearest").sizes == {"u": 5}
    assert not scan_points([0.3], [0.4], max_iter=5).xindexes  # point coordinates are not indexes


def test_output_arrays_are_reused_only_once_nothing_refers_to_them():
    # plane._outputs takes back the arrays of an earlier scan of the same size
    # when their dataset (and every view of it) is gone: never while in use
    window = dict(e=(0.05, 0.95, 31), u=(0.02, 1.3, 23), max_iter=300)
    ref = scan(**window)
    expect = {k: ref[k].values.copy() for k in FIELDS}
    del ref
    kept = [scan(**window) for _ in range(4)]  # all alive: four sets of arrays
    bases = {k: [ds[k].values.base if ds[k].values.base is not None else ds[k].values for ds in kept]
             for k in FIELDS}
    for k in FIELDS:
        for i in range(4):
            for j in range(i):
                assert not np.shares_memory(bases[k][i], bases[k][j])
    view = kept[0]["status"].values  # a view kept: its array stays in use
    older = {k: kept[2][k].values for k in FIELDS}
    del kept
    again = [scan(**window) for _ in range(3)]
    for ds in again:
        for k in FIELDS:
            np.testing.assert_array_equal(ds[k].values, expect[k])
            assert not np.shares_memory(ds[k].values, view if k == "status" else np.empty(0))
    # the view and the arrays still held were not written over
    np.testing.assert_array_equal(view, expect["status"])
    for k in FIELDS:
        np.testing.assert_array_equal(older[k], expect[k])
    # a loop that keeps its last result gets arrays back (the one before)
    ds = scan(**window)
    first = ds["period"].values.__array_interface__["data"][0]  # its address, not a reference
    ds = scan(**window)  # the first still alive while this one is made: other arrays
    assert ds["period"].values.__array_interface__["data"][0] != first
    ds = scan(**window)  # the first is gone now: its arrays are taken back
    assert ds["period"].values.__array_interface__["data"][0] == first
    np.testing.assert_array_equal(ds["period"].values, expect["period"])


def test_concurrent_scans_never_share_output_arrays():
    # several threads scanning windows of one size at once (the explorer's
    # tabs): each result is its own window's, whatever arrays were taken back
    import threading

    windows = [dict(e=(0.05 + 0.1 * i, 0.55 + 0.1 * i, 40), u=(0.02, 1.3, 30), max_iter=200) for i in range(4)]
    expect = [{k: scan(**w)[k].values.copy() for k in FIELDS} for w in windows]
    errors = []

    def worker(i):
        try:
            for _ in range(15):
                ds = scan(**windows[i])
                for k in FIELDS:
                    if not np.array_equal(ds[k].values, expect[i][k]):
                        errors.append((i, k))
        except Exception as exc:  # noqa: BLE001 - reported below
            errors.append(repr(exc))

    threads = [threading.Thread(target=worker, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    assert len({tuple(e["status"].ravel()) for e in expect}) == 4  # the windows differ


def test_outputs_of_big_scans_are_not_kept(monkeypatch):
    monkeypatch.setattr(sc, "_SPARE_BYTES_MAX", 1000)
    monkeypatch.setattr(sc, "_spare", {})
    scan(e=(0.1, 0.9, 10), u=(0.1, 1.0, 10), max_iter=5)  # 2500 bytes of outputs: not kept
    assert all(not v for v in sc._spare.values())
    scan(e=(0.1, 0.9, 5), u=(0.1, 1.0, 5), max_iter=5)  # 625: kept
    assert all(len(v) == 1 and v[0].shape == (25,) for v in sc._spare.values())


def test_read_only_coordinates_reuse_the_compiled_scan_kernel():
    """An xarray coordinate's values are read-only; numba would compile the scan kernel
    again for them (about 15 s in a fresh install). scan_coords and scan_points hand the
    kernel a writeable C-contiguous copy, so every signature it was compiled for takes
    writeable arrays, and the answer is the scan's. In a fresh interpreter: another
    test of this process may call the kernel itself with other arrays."""
    code = """
import numpy as np, stairbounce as sb, stairbounce.plane as P
ds = sb.scan(e=(0.1, 0.5, 6), u=(0.3, 1.2, 5), max_iter=100)
assert not ds.e.values.flags.writeable
c = sb.scan_coords(ds.e.values, ds.u.values, max_iter=100)
assert c.word_length.equals(ds.word_length)
p = sb.scan_points(ds.e.values[::2], np.full(3, 0.7), max_iter=100)  # a strided, read-only view
assert p.sizes["point"] == 3
sigs = P._scan_fast.signatures
print(len(sigs), all(s[0].mutable and s[1].mutable and s[0].layout == "C" for s in sigs))
"""
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-3000:]
    assert r.stdout.split() == ["1", "True"], r.stdout
