"""Pruning of the scan kernels (issue 11): pixels above the Corollary 2.1 curve
get status 1 without iterating, and every array stays bit for bit the one
obtained by iterating every pixel (``prune=False``)."""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest
import xarray as xr

from stairbounce import plane as sc
from stairbounce.figures import BLOWUPS, DIMENSION_WINDOWS
from stairbounce.model import _constants, _step, no_sliding_bound
from stairbounce.plane import (
    no_sliding_curve,
    pixel_centres,
    prunable,
    scan,
    scan_coords,
    scan_points,
)

FIELDS = ("status", "word_length", "jumps", "period", "impacts")


def _assert_same(a, b):
    for k in FIELDS:
        assert a[k].dtype == b[k].dtype, k
        assert np.array_equal(a[k].values, b[k].values), k


def _grid_mask(ds, y0=1.0, v0=0.0):
    E, U = np.meshgrid(ds.e.values, ds.u.values)
    return prunable(E, U, y0, v0)


def _count(es, us, max_iter=20, y0=1.0, v0=0.0, grid=True):
    """Pixels the kernel pruned (its own count).  Writeable copies: a coordinate's
    ``.values`` is read-only, another signature of the kernel, compiled again (~15 s)."""
    es, us = np.array(es, float), np.array(us, float)
    return sc._run(es, us, grid, max_iter, y0, v0, True)[1]


def _check_window(e, u, n_e, n_u, max_iter, y0=1.0, v0=0.0):
    """Pruned and unpruned scans of a window agree (data and attributes);
    the kernel prunes as many pixels as prunable() says, every one of them is
    status 1 when iterated; returns the pruned scan and its count."""
    pruned = scan(e=(*e, n_e), u=(*u, n_u), max_iter=max_iter, y0=y0, v0=v0)
    full = scan(e=(*e, n_e), u=(*u, n_u), max_iter=max_iter, y0=y0, v0=v0, prune=False)
    xr.testing.assert_identical(pruned, full)
    _assert_same(pruned, full)
    mask = _grid_mask(pruned, y0, v0)
    n = _count(pruned.e.values, pruned.u.values, max_iter, y0, v0)
    assert n == mask.sum()
    assert sc._run(np.array(pruned.e.values), np.array(pruned.u.values), True, max_iter, y0, v0, False)[1] == 0
    assert (full.status.values[mask] == 1).all()
    return pruned, n


# --------------------------------------------------------------------------- #
# The bound itself                                                            #
# --------------------------------------------------------------------------- #


def test_threshold_is_the_minimum_of_the_sliding_test_over_v():
    # Corollary 2.1's proof: the parabola (2.3) has its vertex at
    # y* = (1-e)^2 / (8 e u^2); equivalently min_v v + r sqrt(v^2 + 2) =
    # sqrt(2 (r^2 - 1)) = 1/bound.  Checked here by brute force over v.
    for e in (0.01, 0.2, 0.5, 0.9):
        r = (1 + e) / (1 - e)
        v = np.linspace(-50.0, 1.0, 5_000_001)
        lhs = v + r * np.sqrt(v * v + 2.0)
        assert lhs.min() == pytest.approx(math.sqrt(2 * (r * r - 1)), rel=1e-9)
        assert lhs.min() == pytest.approx(1.0 / no_sliding_bound(e), rel=1e-9)
        assert v[lhs.argmin()] == pytest.approx(-(1 / no_sliding_bound(e)) / (r * r - 1), abs=1e-4)


def test_equality_on_the_curve_is_not_pruned():
    # at u = (1-e)/(2 sqrt(2e)) the state (1, v*) meets (2.4) with equality,
    # which counts as sliding (docs/design.md): the curve is iterated
    e = np.linspace(0.001, 0.999, 999)
    u = no_sliding_curve(e)
    assert not prunable(e, u).any()
    T = 1.0 / u
    r = (1 + e) / (1 - e)
    vstar = -T / (r * r - 1)
    lhs = vstar + r * np.sqrt(vstar * vstar + 2.0)
    # the test at (1, v*) is an equality up to rounding
    assert np.allclose(lhs, T, rtol=1e-13, atol=0)
    # and far enough above, everything is pruned
    assert prunable(e, u * (1 + 1e-5)).all()


def test_e_zero_and_out_of_range_are_never_pruned():
    assert not prunable(0.0, np.array([1e-3, 1.0, 1e6, 1e150])).any()
    # speeds where 1/T^2 or T^2 would overflow are outside the valid numeric
    # range (docs/guide/numerics.md): refused by name rather than pruned or iterated
    for u in (1e-300, 1e305):
        with pytest.raises(ValueError, match=r"u \(horizontal speed\) values must be in \[1e-150, 1e\+150\]"):
            prunable(0.5, [u])
    # the e = 0 column is iterated: the ball flies over about 2 u^2 = 50 steps,
    # lands and sticks (a periodic sliding solution); e = 0.5 is pruned
    ds = scan_coords([0.0, 0.5], [5.0], max_iter=500)
    assert _count([0.0, 0.5], [5.0]) == 1
    assert ds.status.values.tolist() == [[0, 1]]


def test_prunable_validation():
    with pytest.raises(ValueError, match=r"e \(restitution coefficient\) values must be in \[0, 1\)"):
        prunable([1.0], [0.5])
    with pytest.raises(ValueError, match=r"u \(horizontal speed\) values must be > 0"):
        prunable([0.5], [-1.0])
    with pytest.raises(ValueError, match="y0 must be finite"):
        prunable(0.5, 1.0, y0=math.inf)
    assert prunable([], []).shape == (0,)


@numba.njit
def _orbit_sizes(es, us, y0, v0, steps):
    """Largest ``(y + |v| T + T^2/2 + 1) / size`` along the orbits of
    ``(y0, v0)``, ``size`` as in plane._never_slides, and the smallest
    computed ``y`` after a step."""
    worst = 0.0
    ymin = np.inf
    for i in range(es.size):
        T, r = _constants(es[i], us[i])
        size = T * T + (1.0 / (T * T) + 1.0 + y0 + v0 * v0) * (r + r / (r - 1.0))
        y, v = y0, v0
        for _ in range(steps):
            worst = max(worst, (y + abs(v) * T + 0.5 * T * T + 1.0) / size)
            y, v, k = _step(y, v, es[i], T, r)
            if k == -1:
                y, v = 1.0, 0.0
            ymin = min(ymin, y)
    return worst, ymin


@pytest.mark.parametrize("y0, v0", [(1.0, 0.0), (50.0, -3.0), (0.0, 10.0), (1e4, 0.0)])
def test_rounding_assumption_of_the_margin(y0, v0):
    # _never_slides' margin covers a computed height below the edge of a few
    # eps times the terms of a step, assuming those stay below a small
    # multiple of `size`; measured here over the prunable part of the plane,
    # from e near 0 (long flights) to e near 1 (slow energy loss), just above
    # the curve and far above it.  _never_slides assumes < 16, with a factor
    # 16 to spare on top.
    rng = np.random.default_rng(5)
    e = np.concatenate([rng.uniform(0, 1, 600), 1 - 10 ** rng.uniform(-8, -1, 300),
                        10 ** rng.uniform(-12, -1, 300)])
    factor = np.concatenate([1 + 10 ** rng.uniform(-8, 0, 600), 10 ** rng.uniform(0, 4, 600)])
    u = no_sliding_curve(e) * factor
    keep = prunable(e, u, y0, v0)
    assert keep.sum() > 900
    worst, ymin = _orbit_sizes(e[keep], u[keep], y0, v0, 4000)
    assert worst < 16.0
    assert ymin > 1.0 - 1e-9


# --------------------------------------------------------------------------- #
# Pruned == iterated, bit for bit                                             #
# --------------------------------------------------------------------------- #


@pytest.mark.slow
def test_paper_grid_at_max_iter_1000():
    ds, n = _check_window((0.0, 1.0), (0.0, 1.5), 500, 350, 1000)
    # the pruned share of the pixels is the share of the window's area above
    # the curve (less the thin margin), integrated here with a fine midpoint rule
    e = (np.arange(1_000_000) + 0.5) / 1_000_000
    above = np.clip(1.5 - no_sliding_curve(e), 0.0, 1.5).mean() / 1.5
    assert n / ds.status.size == pytest.approx(above, abs=3e-3)


@pytest.mark.parametrize("name", sorted(BLOWUPS))
def test_figure_5_windows(name):
    e, u = BLOWUPS[name]
    _check_window(e, u, 90, 90, 400)


@pytest.mark.parametrize("name", sorted(DIMENSION_WINDOWS))
def test_figure_6_and_7_windows(name):
    (e, u), _ = DIMENSION_WINDOWS[name]
    _, n = _check_window(e, u, 120, 120, 600)
    assert n > 0  # both windows reach above the curve


@pytest.mark.parametrize("seed", range(6))
def test_random_windows_straddling_the_curve(seed):
    rng = np.random.default_rng(seed)
    e_mid = rng.uniform(0.02, 0.98)
    half = 10 ** rng.uniform(-9, -1) * min(e_mid, 1 - e_mid)
    e = (e_mid - half, e_mid + half)
    u_mid = no_sliding_bound(e_mid)
    du = 10 ** rng.uniform(-9, -0.5) * u_mid
    u = (u_mid - du, u_mid + du)
    _, n = _check_window(e, u, 40, 40, 500)
    assert 0 < n < 40 * 40


@pytest.mark.parametrize("y0, v0", [(0.0, 0.0), (0.2, 0.5), (3.0, -2.0), (1e3, 0.0)])
def test_any_start_is_pruned_safely(y0, v0):
    # y0 < 1: the first step may slide; then the orbit of (1, 0) cannot
    _check_window((0.0, 0.6), (0.0, 1.5), 50, 50, 300, y0, v0)
    _check_window((0.1, 0.3), (0.5, 0.9), 40, 40, 300, y0, v0)


def _band(rel, n, seed):
    rng = np.random.default_rng(seed)
    e = np.concatenate([rng.uniform(0.0, 1.0, n - 200), 10 ** rng.uniform(-9, -1, 100),
                        1 - 10 ** rng.uniform(-9, -1, 100)])
    u = no_sliding_curve(e) * (1 + rng.uniform(-rel, rel, n))
    return e, u


def test_thin_band_within_1e_12_of_the_curve():
    e, u = _band(1e-12, 4000, 11)
    p = scan_points(e, u, max_iter=1000)
    f = scan_points(e, u, max_iter=1000, prune=False)
    xr.testing.assert_identical(p, f)
    # within 1e-12 the margin keeps every pixel iterated
    assert _count(e, u, grid=False) == 0 and not prunable(e, u).any()


def test_band_across_the_margin_and_the_exact_pruned_set():
    # relative distances 1e-11 .. 1e-6 on both sides: the pruning switches on
    # inside the band; pixel by pixel the kernel prunes exactly prunable()
    e, u = _band(1e-6, 4000, 12)
    p = scan_points(e, u, max_iter=1000)
    f = scan_points(e, u, max_iter=1000, prune=False)
    xr.testing.assert_identical(p, f)
    mask = prunable(e, u)
    assert 0 < mask.sum() < mask.size
    assert _count(e, u, grid=False) == mask.sum()
    # one point per call: the count is the kernel's decision for that point
    pick = np.random.default_rng(0).choice(e.size, 300, replace=False)
    for i in pick:
        assert _count(e[i : i + 1], u[i : i + 1], grid=False) == int(mask[i])
    # below the curve nothing is pruned
    assert not mask[u < no_sliding_curve(e)].any()


# --------------------------------------------------------------------------- #
# Invariances and pass-through                                                #
# --------------------------------------------------------------------------- #


def test_thread_and_tile_invariance_with_pruning():
    e, u, mi = (0.0, 0.5), (0.2, 1.5), 400
    whole = scan(e=(*e, 90), u=(*u, 70), max_iter=mi)
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = scan(e=(*e, 90), u=(*u, 70), max_iter=mi)
    finally:
        numba.set_num_threads(before)
    _assert_same(whole, one)
    es, us = pixel_centres(*e, 90), pixel_centres(*u, 70)
    n = 0
    for a, b in ((0, 13), (13, 50), (50, 70)):
        for c, d in ((0, 41), (41, 90)):
            tile = scan_coords(es[c:d], us[a:b], max_iter=mi)
            n += _count(es[c:d], us[a:b])
            for k in FIELDS:
                assert np.array_equal(tile[k].values, whole[k].values[a:b, c:d]), k
    assert n == _count(es, us)


def test_progress_blocks_with_pruning():
    kw = dict(e=(0.0, 1.0, 60), u=(0.0, 1.5, 55), max_iter=200)
    xr.testing.assert_identical(scan(**kw, progress=lambda *a: None), scan(**kw, prune=False))


def test_perimeter_dimension_passes_prune():
    from stairbounce.dimension import perimeter_dimension

    # the window is not square and its pixels are not either: box_dimension says so
    with pytest.warns(RuntimeWarning, match="non-square pixels"):
        a = perimeter_dimension(e=(0.1, 0.333), u=(0.4, 0.733), method="boxes", resolution=64, max_iter=300,
                                fit_range=(1, 8))
    with pytest.warns(RuntimeWarning, match="non-square pixels"):
        b = perimeter_dimension(e=(0.1, 0.333), u=(0.4, 0.733), method="boxes", resolution=64, max_iter=300,
                                fit_range=(1, 8), prune=False)
    assert np.array_equal(a.border, b.border) and a.dimension == b.dimension


def test_scan_to_zarr_passes_prune_and_resumes_either_way(tmp_path):
    from stairbounce.atlas import scan_to_zarr

    kw = dict(e=(0.0, 0.6, 40), u=(0.0, 1.5, 30), max_iter=200, tile=16)
    ref = scan(e=kw["e"], u=kw["u"], max_iter=200, prune=False)
    store = scan_to_zarr(tmp_path / "a.zarr", prune=False, **kw)
    for k in FIELDS:
        assert np.array_equal(store[k].values, ref[k].values), k
    # the same store, asked again with pruning: same scan, nothing to redo
    again = scan_to_zarr(tmp_path / "a.zarr", prune=True, **kw)
    for k in FIELDS:
        assert np.array_equal(again[k].values, ref[k].values), k
