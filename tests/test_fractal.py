"""Box counting (stairbounce.dimension) against slow references, against sets of
known dimension, and against the paper's Figures 6 and 7."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from scipy import stats

from stairbounce.dimension import boxes as dimension_boxes
from stairbounce.dimension import (
    box_counts,
    box_dimension,
    boundary,
    label_boundary,
    linear_region,
    perimeter_dimension,
    slope_fit,
)
from tests import naive

# --------------------------------------------------------------------------- #
# Rasterised sets of known dimension                                          #
# --------------------------------------------------------------------------- #


def raster(points, n):
    """Pixels (row = y, column = x) of an n x n image hit by the points."""
    ij = np.floor(points).astype(np.int64)
    ok = (ij[:, 0] >= 0) & (ij[:, 0] < n) & (ij[:, 1] >= 0) & (ij[:, 1] < n)
    img = np.zeros((n, n), dtype=bool)
    img[ij[ok, 1], ij[ok, 0]] = True
    return img


def ifs_points(maps, level, start):
    """The images of ``start`` under all compositions of ``level`` affine maps."""
    pts = np.array([start], dtype=float)
    for _ in range(level):
        pts = np.concatenate([pts @ a.T + b for a, b in maps])
    return pts


def rotation(angle, scale):
    c, s = math.cos(angle), math.sin(angle)
    return scale * np.array([[c, -s], [s, c]])


def koch_curve(n):
    """Koch curve on [0, 1] scaled to n px; points spaced < 0.5 px (level
    ceil(log3(2n))), so the raster is connected."""
    h = math.sqrt(3) / 6
    maps = [
        (rotation(0, 1 / 3), np.array([0.0, 0.0])),
        (rotation(math.pi / 3, 1 / 3), np.array([1 / 3, 0.0])),
        (rotation(-math.pi / 3, 1 / 3), np.array([0.5, h])),
        (rotation(0, 1 / 3), np.array([2 / 3, 0.0])),
    ]
    level = math.ceil(math.log(2 * n) / math.log(3))
    pts = np.concatenate([ifs_points(maps, level, [0, 0]), ifs_points(maps, level, [1, 0])])
    return raster(pts * (n - 1) + np.array([0.5, n / 3]), n)


def sierpinski_triangle(n):
    """Equilateral Sierpinski triangle of side n px; points spaced 0.5 px."""
    maps = [
        (np.eye(2) / 2, np.array([0.0, 0.0])),
        (np.eye(2) / 2, np.array([0.5, 0.0])),
        (np.eye(2) / 2, np.array([0.25, math.sqrt(3) / 4])),
    ]
    level = math.ceil(math.log2(2 * n))
    return raster(ifs_points(maps, level, [0, 0]) * (n - 1) + 0.5, n)


def segment(n):
    """A segment of slope 5/8 across the image, sampled every 0.12 px."""
    t = np.linspace(0.0, 1.0, 8 * n)
    return raster(np.c_[0.1 * n + 0.8 * n * t, 0.2 * n + 0.5 * n * t], n)


def disk(n, radius=0.4):
    y, x = np.mgrid[:n, :n] + 0.5
    return (x - n / 2) ** 2 + (y - n / 2) ** 2 <= (radius * n) ** 2


def filled_square(n):
    img = np.zeros((n, n), dtype=bool)
    img[n // 10 : 9 * n // 10, n // 10 : 9 * n // 10] = True
    return img


# Source of each exact value: a segment and a circle are rectifiable curves
# (D = 1); a filled square has D = 2; the Koch curve is self-similar with 4
# copies at ratio 1/3 (D = log 4 / log 3, Koch 1904, Falconer, "Fractal
# Geometry", Sec. 9.1); the Sierpinski triangle has 3 copies at ratio 1/2
# (D = log 3 / log 2, Falconer Sec. 9.1).
KNOWN_SETS = {
    "segment": (segment, 1.0),
    "circle": (lambda n: boundary(disk(n)), 1.0),
    "filled square (area)": (filled_square, 2.0),
    "Koch curve": (koch_curve, math.log(4) / math.log(3)),
    "Sierpinski triangle": (sierpinski_triangle, math.log(3) / math.log(2)),
}


@pytest.mark.parametrize("name", KNOWN_SETS)
def test_known_sets_at_2048_px_within_0_03(name):
    make, exact = KNOWN_SETS[name]
    est = box_dimension(make(2048))
    assert abs(est.dimension - exact) < 0.03, est.summary()
    assert est.ci[0] < est.dimension < est.ci[1]
    assert est.r > 0.99


@pytest.mark.parametrize("name", KNOWN_SETS)
@pytest.mark.parametrize("n", [512, 1024])
def test_known_sets_at_lower_resolution_within_0_07(name, n):
    # fewer box sizes and a larger pixel-scale bias: a looser bound
    make, exact = KNOWN_SETS[name]
    est = box_dimension(make(n))
    assert abs(est.dimension - exact) < 0.07, est.summary()


def test_sierpinski_counts_are_powers_of_three_on_pascal_triangle_mod_2():
    # Pascal's triangle mod 2 on a 2^k grid: (i & j) == 0; a box of side 2^m
    # aligned with the grid holds a copy of the level-m triangle, and there are
    # exactly 3^(k-m) such boxes (the self-similarity of the Sierpinski gasket).
    k = 10
    i, j = np.indices((2**k, 2**k))
    sizes, counts = box_counts((i & j) == 0)
    assert sizes.tolist() == [2**m for m in range(k + 1)]
    assert counts.tolist() == [3 ** (k - m) for m in range(k + 1)]
    assert box_dimension((i & j) == 0, min_boxes=2).dimension == pytest.approx(math.log2(3), abs=1e-9)


# --------------------------------------------------------------------------- #
# Box counts against the one-box-at-a-time loop of tests/naive.py             #
# --------------------------------------------------------------------------- #


def test_box_counts_match_naive_loop_on_random_images():
    rng = np.random.default_rng(20240607)
    for _ in range(25):
        h, w = rng.integers(1, 70, 2)
        img = rng.random((h, w)) < rng.choice([0.002, 0.02, 0.2, 0.7])
        sizes = np.unique(np.r_[rng.integers(1, 80, 3), 1, 2, 4, 8, 16, 32, 64])
        offsets = int(rng.integers(1, 4))
        s, c = box_counts(img, sizes=sizes, offsets=offsets, reduce="min")
        s2, c2 = box_counts(img, sizes=sizes, offsets=offsets, reduce="mean")
        lists = img.tolist()
        for size, got_min, got_mean in zip(s, c, c2):
            shifts = dimension_boxes._offsets_for(size, offsets)
            ref = [naive.box_count(lists, int(size), oy, ox) for oy in shifts for ox in shifts]
            assert got_min == min(ref)
            assert got_mean == pytest.approx(np.mean(ref))
        assert s.tolist() == s2.tolist() == sorted(set(sizes.tolist()))


@settings(max_examples=40, deadline=None)
@given(
    hnp.arrays(np.bool_, hnp.array_shapes(min_dims=2, max_dims=2, min_side=1, max_side=40)),
)
def test_pyramid_counts_match_naive_loop(img):
    # default sizes: the OR-pyramid path (odd sides pool their last row/column alone)
    s, c = box_counts(img)
    lists = img.tolist()
    assert c.tolist() == [naive.box_count(lists, int(size)) for size in s]
    assert s.tolist() == [2**m for m in range(int(math.log2(min(img.shape))) + 1)]


def test_pyramid_and_direct_kernel_agree_on_a_large_image():
    rng = np.random.default_rng(7)
    img = rng.random((1000, 1331)) < 0.003
    s, c = box_counts(img)
    for size, count in zip(s, c):
        assert dimension_boxes._count_boxes(img.view(np.uint8), int(size), 0, 0) == count


def test_box_counts_accept_any_nonzero_image():
    rng = np.random.default_rng(3)
    img = rng.random((64, 48)) < 0.1
    ref = box_counts(img)[1]
    for other in (img.astype(np.uint8) * 255, img.astype(float) * 0.5, img.astype(np.int32)):
        assert box_counts(other)[1].tolist() == ref.tolist()


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"sizes": [0, 2]}, "sizes"),
        ({"sizes": [1.5]}, "sizes"),
        ({"sizes": []}, "sizes"),
        ({"offsets": 0}, "offsets"),
        ({"reduce": "max"}, "reduce"),
    ],
)
def test_box_counts_reject_bad_arguments(kwargs, message):
    with pytest.raises(ValueError, match=message):
        box_counts(np.ones((8, 8), bool), **kwargs)


def test_box_counts_reject_non_2d_images():
    with pytest.raises(ValueError, match="image must be a 2-D array"):
        box_counts(np.ones((4, 4, 3), bool))


# --------------------------------------------------------------------------- #
# Borders                                                                     #
# --------------------------------------------------------------------------- #


@settings(max_examples=60, deadline=None)
@given(hnp.arrays(np.bool_, hnp.array_shapes(min_dims=2, max_dims=2, min_side=1, max_side=25)))
def test_boundary_matches_naive_neighbour_loop(mask):
    assert boundary(mask).tolist() == naive.border_pixels(mask.tolist())


def test_boundary_image_edge_and_connectivity():
    m = np.zeros((7, 9), bool)
    m[:, :4] = True  # a region touching three image edges, cut by a vertical line
    inner = boundary(m)
    assert inner[:, 3].all() and inner.sum() == 7  # only the cut inside the image
    framed = boundary(m, image_edge="border")
    assert framed[0, :4].all() and framed[-1, :4].all() and framed[:, 0].all()
    assert not framed[1:-1, 1:3].any()
    # 8-neighbourhood: a superset, adding pixels that touch the outside by a corner
    d = disk(40)
    b4, b8 = boundary(d), boundary(d, connectivity=8)
    assert (b4 <= b8).all() and b8.sum() > b4.sum()
    assert not (boundary(d) & ~d).any()


def test_label_boundary_of_two_labels_marks_both_sides():
    m = disk(50)
    both = label_boundary(m.astype(np.int64))
    assert both.tolist() == (boundary(m) | boundary(~m)).tolist()
    labels = np.zeros((6, 6), np.int64)
    labels[:, 2:4] = 1
    labels[:, 4:] = 2
    assert label_boundary(labels).sum(axis=0).tolist() == [0, 6, 6, 6, 6, 0]


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: boundary(np.ones(5, bool)), "mask must be a 2-D array"),
        (lambda: boundary(np.ones((3, 3), bool), connectivity=6), "connectivity"),
        (lambda: boundary(np.ones((3, 3), bool), image_edge="wrap"), "image_edge"),
        (lambda: label_boundary(np.ones((3, 3))), "integer"),
    ],
)
def test_border_functions_reject_bad_input(call, message):
    with pytest.raises(ValueError, match=message):
        call()


# --------------------------------------------------------------------------- #
# Slope fit                                                                   #
# --------------------------------------------------------------------------- #


def test_slope_fit_matches_scipy_linregress():
    rng = np.random.default_rng(11)
    x = np.sort(rng.uniform(0, 5, 12))
    y = 1.3 * x + 0.4 + rng.normal(0, 0.05, 12)
    fit = slope_fit(x, y, range=(0, 12))
    ref = stats.linregress(x, y)
    assert fit.slope == pytest.approx(ref.slope)
    assert fit.intercept == pytest.approx(ref.intercept)
    assert fit.stderr == pytest.approx(ref.stderr)
    assert fit.r == pytest.approx(ref.rvalue)
    t = stats.t.ppf(0.975, 10)
    assert fit.ci == pytest.approx((ref.slope - t * ref.stderr, ref.slope + t * ref.stderr))
    assert fit.range == (0, 12) and fit.n == 12


def test_slope_fit_ci_covers_true_slope_about_95_percent_of_the_time():
    rng = np.random.default_rng(5)
    x = np.arange(6, dtype=float)
    hits = 0
    for _ in range(2000):
        fit = slope_fit(x, 2.0 * x + rng.normal(0, 0.3, 6), range=(0, 6))
        hits += fit.ci[0] <= 2.0 <= fit.ci[1]
    assert 0.93 < hits / 2000 < 0.97  # binomial sd 0.005


def test_linear_region_finds_the_straight_part_between_bends():
    x = np.arange(12, dtype=float)
    y = 1.5 * x
    y[:3] = y[3] - 0.5 * (3 - x[:3])  # shallow start (a pixel-scale bend)
    y[9:] = y[8] + 3.0 * (x[9:] - 8)  # steep end (saturation)
    assert linear_region(x, y) == (3, 9)
    fit = slope_fit(x, y)
    assert fit.range == (3, 9) and fit.slope == pytest.approx(1.5)
    assert fit.stderr == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: slope_fit([1, 2], [1, 2]), "at least 3"),
        (lambda: slope_fit([1, 2, 3], [1, 2]), "same length"),
        (lambda: slope_fit([1, 2, np.nan], [1, 2, 3]), "finite"),
        (lambda: slope_fit([1, 2, 3, 4], [1, 2, 3, 4], range=(0, 2)), "at least 3"),
        (lambda: slope_fit([1, 1, 1], [1, 2, 3], range=(0, 3)), "constant"),
        (lambda: linear_region([1, 2, 3], [1, 2, 3], tol=0), "tol"),
    ],
)
def test_slope_fit_rejects_bad_input(call, message):
    with pytest.raises(ValueError, match=message):
        call()


# --------------------------------------------------------------------------- #
# box_dimension                                                               #
# --------------------------------------------------------------------------- #


def test_box_dimension_fit_range_in_pixels():
    est = box_dimension(koch_curve(1024), fit_range=(2, 64))
    assert est.fit_range == (2, 64)
    assert est.fitted.tolist() == [s in (2, 4, 8, 16, 32, 64) for s in est.sizes]
    x = np.log(1.0 / est.sizes[est.fitted])
    y = np.log(est.counts[est.fitted])
    assert est.dimension == pytest.approx(stats.linregress(x, y).slope)


def test_box_dimension_errors_name_the_problem():
    with pytest.raises(ValueError, match="no nonzero pixel"):
        box_dimension(np.zeros((64, 64), bool))
    one = np.zeros((64, 64), bool)
    one[10, 10] = True
    with pytest.raises(ValueError, match="fewer than 3 usable box sizes"):
        box_dimension(one)
    with pytest.raises(ValueError, match="fit_range"):
        box_dimension(segment(256), fit_range=(64, 128))
    with pytest.raises(ValueError, match="min_boxes"):
        box_dimension(segment(256), min_boxes=1)


def test_box_dimension_of_small_image_falls_back_to_all_usable_sizes():
    est = box_dimension(segment(64))  # at most 28 boxes at 2 px: under min_boxes
    assert est.fit.n >= 3 and abs(est.dimension - 1.0) < 0.1


# --------------------------------------------------------------------------- #
# The paper's Figures 6 and 7                                                 #
# --------------------------------------------------------------------------- #

FIG6 = dict(e=(0.0, 0.333), u=(0.4, 0.733))
FIG7 = dict(e=(0.155, 0.2138), u=(0.6, 0.658))


@pytest.mark.parametrize("window, paper", [(FIG6, 1.324), (FIG7, 1.403)], ids=["Fig6", "Fig7"])
def test_replicates_figs_6_and_7_of_campos_et_al(window, paper):
    # Replicates Figs. 6 and 7 of Campos, Romero-Valles and Torres: the border
    # of the sliding region on a 500 px picture of the window, boxes of 1 to
    # 64 px (the powers of two up to an eighth of the picture; the paper does
    # not give its range): D within 0.08 of the paper's value, r > 0.99.
    est = perimeter_dimension(**window, method="boxes", resolution=500, max_iter=1000, fit_range=(1, 64))
    assert abs(est.dimension - paper) < 0.08, est.summary()
    assert est.r > 0.99
    # the report's criterion (issue 24): the paper's number inside our interval,
    # which here is wide because the local slope drifts across 1..64 px
    assert est.interval[0] <= paper <= est.interval[1] and est.systematic > est.statistical
    assert est.border.shape == (500, 500)
    assert 0.0 < est.region_fraction < 1.0


def test_perimeter_dimension_measures_the_border_of_the_scanned_region():
    from stairbounce.plane import scan

    est = perimeter_dimension(**FIG7, method="boxes", resolution=96, max_iter=300, fit_range=(1, 16))
    ds = scan(e=(*FIG7["e"], 96), u=(*FIG7["u"], 96), max_iter=300)
    region = ds["status"].transpose("u", "e").values == 0
    assert est.border.tolist() == boundary(region).tolist()
    assert est.region_fraction == pytest.approx(region.mean())
    words = perimeter_dimension(**FIG7, method="boxes", resolution=96, max_iter=300, which="words", fit_range=(1, 16))
    # every border of the sliding region is also a border between word lengths
    assert (est.border <= words.border).all()


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(e=(0.5, 0.6), u=(1.0, 1.2)), "region is empty"),  # above Cor. 2.1
        (dict(e=(0.0, 0.01), u=(0.1, 0.2)), "fills the window"),  # inside the (1, 0^inf) tongue
        (dict(e=(0.3, 0.2)), "min < max"),
        (dict(resolution=4), "resolution"),
        (dict(which="both"), "which"),
    ],
)
def test_perimeter_dimension_rejects_bad_windows(kwargs, message):
    kwargs = {"method": "boxes", "resolution": 32, "max_iter": 50, **kwargs}
    with pytest.raises(ValueError, match=message):
        perimeter_dimension(**kwargs)


def test_plot_box_dimension_draws_border_and_fitted_line():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from stairbounce.plot import plot_box_dimension

    est = perimeter_dimension(**FIG7, method="boxes", resolution=64, max_iter=200, fit_range=(1, 16))
    fig = plot_box_dimension(est)
    img_ax, log_ax = fig.axes[:2]
    assert img_ax.images[0].get_array().shape == (64, 64)
    assert img_ax.images[0].get_extent() == [*FIG7["e"], *FIG7["u"]]
    # D with its interval covering the drift, both terms apart (issue 24)
    iv = f"[{est.interval[0]:.3f}, {est.interval[1]:.3f}]"
    assert f"D = {est.dimension:.3f}" in log_ax.get_title() and iv in log_ax.get_title()
    assert "drift +-" in log_ax.get_title()
    # the third panel: the local slope against box size
    assert fig.axes[2].get_ylabel() == "local dimension"
    line = [ln for ln in log_ax.lines if ln.get_label().startswith("slope")][0]
    x, y = line.get_data()
    assert np.allclose(y, est.fit.intercept + est.dimension * x)
    # a plain box-dimension result needs the image it measured
    with pytest.raises(ValueError, match="image"):
        plot_box_dimension(box_dimension(segment(128)))
    plt.close("all")


def _linear_region_cubic(x, y, tol, min_points):
    """The plain search linear_region used before its O(n^2) form: every
    window refitted from scratch, lengths from the longest down."""
    from stairbounce.dimension.fit import _fit

    n = len(x)
    with np.errstate(divide="ignore", invalid="ignore"):
        local = np.diff(y) / np.diff(x)
    best = fallback = None
    for length in range(n, min_points - 1, -1):
        for start in range(0, n - length + 1):
            stop = start + length
            seg = local[start : stop - 1]
            if not np.all(np.isfinite(seg)):
                continue
            slope, _, stderr, _ = _fit(x[start:stop], y[start:stop])
            dev = np.max(np.abs(seg - slope))
            if dev <= tol * abs(slope):
                if best is None or (length, -stderr) > best[0]:
                    best = ((length, -stderr), start, stop)
            elif length == min_points:
                spread = dev / max(abs(slope), 1e-300)
                if fallback is None or spread < fallback[0]:
                    fallback = (spread, start, stop)
        if best is not None:
            return best[1], best[2]
    return (0, n) if fallback is None else fallback[1:]


def test_linear_region_quadratic_form_equals_the_plain_search():
    """Report D12: the search was O(n^3).  The O(n^2) form picks the same
    window as the plain one on log-log curves with bends, noise and kinks."""
    from stairbounce.dimension import linear_region

    rng = np.random.default_rng(12)
    for trial in range(60):
        n = int(rng.integers(3, 40))
        x = np.sort(rng.uniform(-8, 0, n)) if trial % 3 else np.arange(n, dtype=float)
        kink = rng.uniform(x.min(), x.max())
        y = 1.3 * x + np.where(x > kink, 0.7 * (x - kink), 0.0) + rng.normal(0, 10.0 ** rng.uniform(-4, -1), n)
        tol, mp = float(rng.choice([0.02, 0.1, 0.3])), int(rng.integers(3, max(4, n // 2 + 1)))
        mp = min(mp, n)
        assert linear_region(x, y, tol=tol, min_points=mp) == _linear_region_cubic(x, y, tol, mp), trial


def test_linear_region_is_fast_on_many_points():
    """2000 points (the plain search took more than 30 s) in well under a second
    or two; and a constant x is refused instead of answering (0, n)."""
    from stairbounce.dimension import linear_region, slope_fit

    x = np.log(np.arange(1, 2001, dtype=float))
    y = 1.5 * x + 0.01 * np.sin(7 * x)
    start, stop = linear_region(x, y)
    assert stop - start == 2000
    assert slope_fit(x, y).slope == pytest.approx(1.5, abs=0.01)
    with pytest.raises(ValueError, match="x must not be constant"):
        linear_region(np.ones(5), np.arange(5.0))


def test_box_counts_offsets_are_bounded():
    """Report D12: offsets=10**9 looped for ever; offsets beyond the box side add
    nothing (every shift is already used) and beyond 64 are refused."""
    from stairbounce.dimension import box_counts
    from stairbounce.dimension.boxes import _offsets_for

    assert _offsets_for(4, 64) == [0, 1, 2, 3] == _offsets_for(4, 4)
    assert _offsets_for(8, 3) == [0, 2, 5]
    img = np.zeros((16, 16), bool)
    img[3:9, 5] = True
    with pytest.raises(ValueError, match=r"offsets must be an integer in \[1, 64\]"):
        box_counts(img, offsets=10**9)
    s, c = box_counts(img, sizes=[2, 4], offsets=64, reduce="min")
    assert list(c) == [3, 2]  # the 6-pixel segment: 3 boxes of 2, and 2 of 4 at best


def test_box_sides_beyond_int64_arithmetic_are_refused():
    """Report D5: sizes=[2**63 - 1] counted 0 boxes (int64 overflow), [2**64]
    raised TypeError.  Sides up to 2**31 are counted: one box holds the set."""
    from stairbounce.dimension import box_counts

    img = np.eye(8, dtype=bool)
    for bad in ([2**63 - 1], [2**64], [1.5], [0], ["a"], [True]):
        with pytest.raises(ValueError, match=r"sizes must be an integer in \[1, 2147483648\]"):
            box_counts(img, sizes=bad)
    assert box_counts(img, sizes=[2**31])[1].tolist() == [1]
