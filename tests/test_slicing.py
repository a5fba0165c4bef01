"""Slicing (stairbounce.dimension.slicing): the border's dimension from its
crossings along random lines, validated on borders of known dimension.

Sources of the exact answers:

- a circle: a smooth curve, dimension 1; a line meets it in at most 2 points,
  so every occupied box has exactly one occupied child at every scale;
- the graph of the Weierstrass function ``W(x) = sum_n a^n cos(2 pi b^n x)``
  (``0 < a < 1 < b``, ``a b > 1``): box-counting dimension ``2 + ln a / ln b``
  (Kaplan, Mallet-Paret and Yorke, Ergodic Theory Dyn. Syst. 4 (1984) 261;
  Falconer, Fractal Geometry, 3rd ed., Example 11.3).  The sum is cut at
  ``b^-n < 1e-12``, far below the finest scale measured (1e-9), so the finite
  sum is the fractal at every scale measured.  The region is ``y > W(x)``;
  its border is the graph.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from stairbounce.dimension import sliding_classifier, slicing_dimension

UNIT = ((0.0, 1.0), (0.0, 1.0))


def disk(x, y):
    return (x - 0.5) ** 2 + (y - 0.5) ** 2 < 0.3**2


def weierstrass(a, b):
    n = np.arange(int(math.log(1e12) / math.log(b)) + 1)
    amp = 1.0 / (1.0 - a) + 0.1

    def above(x, y):
        x = np.asarray(x)
        w = (a ** n[:, None] * np.cos(2.0 * np.pi * (float(b) ** n[:, None]) * x[None, :])).sum(axis=0)
        return np.asarray(y) > w

    return above, ((0.0, 1.0), (-amp, amp)), 2.0 + math.log(a) / math.log(b)


def test_circle_has_dimension_one_at_every_scale():
    r = slicing_dimension(disk, UNIT, n_lines=32, scale_min=1e-10, seed=3)
    assert r.scales_measured[-1] <= 1e-10  # refined to 1e-10 of the window and below
    np.testing.assert_allclose(r.local[1], 1.0, atol=1e-12)
    assert r.interval[0] <= 1.0 <= r.interval[1]
    assert r.children.min() == 1.0


@pytest.mark.parametrize("a, b", [(3**-0.5, 3), (3**-0.7, 3)])
def test_weierstrass_graph(a, b):
    # D = 1.5 and 1.3; the hidden-crossing bias is low and at most 0.03 at 32 samples
    above, window, exact = weierstrass(a, b)
    r = slicing_dimension(above, window, n_lines=64, scale_min=1e-9, seed=0)
    assert exact - 0.035 <= r.dimension <= exact + 0.01, (r.dimension, exact)
    assert r.interval[0] - 0.03 <= exact <= r.interval[1] + 0.01
    # scale-resolved: no level strays far from the answer
    assert np.all(np.abs(r.local[1] - exact) < 0.1)


def test_more_samples_per_box_reduce_the_hidden_crossing_bias():
    above, window, exact = weierstrass(3**-0.5, 3)
    coarse = slicing_dimension(above, window, n_lines=64, scale_min=1e-7, samples=4, seed=0)
    fine = slicing_dimension(above, window, n_lines=64, scale_min=1e-7, samples=32, seed=0)
    assert coarse.dimension < fine.dimension <= exact + 0.01
    assert exact - coarse.dimension > 0.07  # the bias is real at 4 samples


def test_same_seed_same_answer_and_max_iter_recorded():
    classify = sliding_classifier(max_iter=200)
    window = ((0.155, 0.2138), (0.6, 0.658))
    a = slicing_dimension(classify, window, n_lines=8, scale_min=1e-5, max_boxes=50, seed=1)
    b = slicing_dimension(classify, window, n_lines=8, scale_min=1e-5, max_boxes=50, seed=1)
    assert a.dimension == b.dimension and a.evaluations == b.evaluations
    assert a.max_iter == 200 and "max_iter 200" in a.summary()
    assert 1.0 < a.dimension < 2.0


@pytest.mark.parametrize("kwargs, name", [
    (dict(n_lines=0), "n_lines"),
    (dict(ratio=1), "ratio"),
    (dict(samples=1), "samples"),
    (dict(max_boxes=5), "max_boxes"),
    (dict(scale_min=1e-15), "scale_min"),
    (dict(scale_min=1e-3, scale_max=2e-3), "scale_min"),
    (dict(seed=-1), "seed"),
    (dict(fit_range=(1e-20, 1e-19)), "fit range"),
])
def test_bad_parameters_name_themselves(kwargs, name):
    with pytest.raises(ValueError, match=name):
        slicing_dimension(disk, UNIT, **{"n_lines": 4, **kwargs})


def test_a_border_the_lines_miss_is_refused():
    with pytest.raises(ValueError, match="no crossing"):
        slicing_dimension(lambda x, y: np.zeros(x.shape, bool), UNIT, n_lines=4)


def test_the_classifier_takes_points_next_to_the_edge_e_0():
    """A line refined next to a window's edge e = 0 lands in (0, 2^-53), outside the
    valid numeric range (model.check_e refuses it by name); the estimators' classifier
    evaluates such points at e = 0 (the rebound of e < 2^-53 accumulates at once), so
    the Fig. 6 window's slicing run at the gallery's size no longer stops there."""
    import numpy as np
    import pytest

    import stairbounce as sb

    with pytest.raises(ValueError, match="2\\^-53"):
        sb.scan_points(np.array([4.6e-18]), np.array([0.5]), max_iter=50)
    c = sb.sliding_classifier(max_iter=300)
    u = np.array([0.3, 0.5, 0.7, 1.2])
    tiny = c(np.full(4, 4.6e-18), u)
    assert (tiny == c(np.zeros(4), u)).all()
    assert (c(np.full(4, 0.1), u) == sb.scan_points(np.full(4, 0.1), u, max_iter=300).status.values).all()


class _TruncatedWeierstrass:
    """``y > W_n(x)``, the Weierstrass sum cut after ``terms`` terms: a stand-in
    for a classifier truncated by ``max_iter`` with a known answer.  The cut
    sum is smooth (dimension 1) below its last wavelength ``b^-(terms-1)`` and
    the fractal above it, so against more terms its local dimension moves
    exactly at the fine scales."""

    def __init__(self, a, b, terms):
        self.a, self.b, self.max_iter = a, b, terms

    def __call__(self, x, y):
        n = np.arange(self.max_iter)
        x = np.asarray(x)
        w = (self.a ** n[:, None] * np.cos(2.0 * np.pi * (float(self.b) ** n[:, None]) * x[None, :])).sum(axis=0)
        return np.asarray(y) > w


def _truncated(terms, a=3**-0.5, b=3, n_lines=16):
    _, window, exact = weierstrass(a, b)
    return slicing_dimension(_TruncatedWeierstrass(a, b, terms), window, n_lines=n_lines,
                             scale_min=1e-6, scale_max=1e-2, seed=0), exact


def test_max_iter_check_cuts_the_range_where_the_local_dimension_moves():
    from stairbounce.dimension import max_iter_check

    # 12 terms: smooth below the last wavelength 3^-11 = 5.6e-6 (local
    # dimension -> 1 at the finest scales); 26 terms: the fractal (D = 1.5) at
    # every scale measured (test_weierstrass_graph)
    short, exact = _truncated(12)
    full, _ = _truncated(26)
    check = max_iter_check(short, full)
    assert check.max_iter == (12, 26)
    assert not check.converged
    assert check.local_a[-1] < 1.1 and check.moved[-1]  # smooth and moved at the finest scale
    assert np.all(np.abs(check.local_b - exact) < 0.1)
    lo, hi = check.not_converged
    assert lo == check.scales.min() and hi < check.scales.max()  # the coarsest did not move
    good = check.converged_range
    assert good is not None and good[0] > hi and good[1] == check.scales.max()
    assert np.all(~check.moved[check.scales >= good[0]])
    cut = check.cut(short.scales)
    assert cut == good
    assert "not converged at scales" in check.text()
    refit = short.refit(cut)  # the fit over the converged scales only: back near the answer
    assert refit.scales[0] >= hi and abs(refit.dimension - exact) < abs(short.dimension - exact)
    # fewer terms, fewer converged levels: then the cut fit is refused
    shorter, _ = _truncated(10)
    few = max_iter_check(shorter, full)
    with pytest.raises(ValueError, match="fewer than 3"):
        shorter.refit(few.cut(shorter.scales))


def test_max_iter_check_passes_where_more_terms_change_nothing_measured():
    from stairbounce.dimension import max_iter_check

    # 26 and 30 terms: both the fractal at every scale measured (the terms
    # added have wavelengths below 3^-25 ~ 1e-12); the check must not flag them
    a, _ = _truncated(26)
    b, _ = _truncated(30)
    check = max_iter_check(a, b)
    assert check.converged, check.text()
    assert check.converged_range == (check.scales.min(), check.scales.max())
    assert check.cut(a.scales) == check.converged_range
    assert check.text().startswith("max_iter 26 -> 30: converged at scales")
    assert np.all(np.abs(check.difference) <= check.band)


def test_refit_equals_a_fit_over_the_same_range():
    r, _ = _truncated(26, n_lines=8)
    mid = r.local[0]
    rng = (mid[3], mid[0])
    again = r.refit(rng)
    direct = slicing_dimension(_TruncatedWeierstrass(3**-0.5, 3, 26), weierstrass(3**-0.5, 3)[1], n_lines=8,
                               scale_min=1e-6, scale_max=1e-2, seed=0, fit_range=rng)
    assert again.dimension == direct.dimension and again.ci == direct.ci
    assert again.fit_range == direct.fit_range and again.systematic == direct.systematic
    assert again.evaluations == r.evaluations  # nothing classified again
    assert r.refit((mid.min(), mid.max())).dimension == r.dimension


def test_max_iter_check_on_the_model_finds_max_iter_50_unconverged():
    from stairbounce.dimension import max_iter_check

    # Fig. 7's window: max_iter 50 truncates the border below about 1e-3 of
    # the window (against 200, the local dimension moves by 0.06-0.18 there)
    window = ((0.155, 0.2138), (0.6, 0.658))
    a, b = (slicing_dimension(sliding_classifier(max_iter=m), window, n_lines=8, scale_min=1e-5,
                              scale_max=1e-2, seed=0) for m in (50, 200))
    check = max_iter_check(a, b)
    assert check.max_iter == (50, 200)
    assert not check.converged and check.not_converged[0] == check.scales.min()
    assert np.all(check.difference[check.scales < 1e-3] > 0)  # truncation reads low


def test_max_iter_check_refuses_two_methods():
    from stairbounce.dimension import max_iter_check, uncertainty_dimension

    r, _ = _truncated(26, n_lines=8)
    u = uncertainty_dimension(disk, UNIT, n_points=2000, seed=0)
    with pytest.raises(ValueError, match="one method"):
        max_iter_check(r, u)


def test_max_iter_check_on_constructed_estimates():
    from types import SimpleNamespace

    from stairbounce.dimension import max_iter_check
    from stairbounce.dimension.convergence import NO_NOISE_MODEL_BAND

    def est(mid, d, half, max_iter):
        return SimpleNamespace(scale_unit="px", max_iter=max_iter,
                               local_band=lambda: (np.asarray(mid), np.asarray(d), np.asarray(half)))

    # b measured one scale fewer (16 px): scales are matched by value, not position;
    # no noise model (NaN bands): held to NO_NOISE_MODEL_BAND
    a = est([64, 32, 16, 8, 4], [1.50, 1.52, 1.51, 1.40, 1.30], [np.nan] * 5, 100)
    b = est([64, 32, 8, 4], [1.51, 1.50, 1.49, 1.50], [np.nan] * 4, 400)
    c = max_iter_check(a, b)
    np.testing.assert_array_equal(c.scales, [64, 32, 8, 4])
    np.testing.assert_allclose(c.difference, [0.01, -0.02, 0.09, 0.20])
    assert np.all(c.band == NO_NOISE_MODEL_BAND)
    assert c.moved.tolist() == [False, False, True, True]
    assert c.not_converged == (4.0, 8.0) and c.converged_range == (32.0, 64.0)
    assert c.cut((4, 40)) == (32.0, 32.0) and c.cut((1, 16)) is None
    assert c.text() == "max_iter 100 -> 400: not converged at scales 4..8 px: converged at 32..64"
    # with bands: the two combined, hypot(0.06, 0.08) = 0.1, widened for 4 comparisons
    # (Bonferroni: z(1 - 0.025/4) / z(0.975) = 1.2744), so 0.09 at 8 px passes
    a = est([64, 32, 8, 4], [1.50, 1.52, 1.40, 1.30], [0.06] * 4, 100)
    b = est([64, 32, 8, 4], [1.51, 1.50, 1.49, 1.50], [0.08] * 4, 400)
    c = max_iter_check(a, b)
    np.testing.assert_allclose(c.band, 0.1 * 1.2743629, rtol=1e-6)
    assert c.moved.tolist() == [False, False, False, True]
    # a scale that moved while every finer one agrees is a chance flag, not truncation:
    # reported, not cut (finer scales need longer orbits, so truncation reaches the finest)
    b2 = est([64, 32, 8, 4], [1.51, 1.80, 1.41, 1.31], [0.08] * 4, 400)
    c2 = max_iter_check(a, b2)
    assert c2.moved.tolist() == [False, True, False, False] and not c2.truncated.any()
    assert c2.converged and c2.converged_range == (4.0, 64.0)
    assert "a chance flag, not truncation" in c2.text() and "at 32 " in c2.text()
    # a local dimension measured at one max_iter and not at the other moved
    b = est([64, 32, 8, 4], [1.51, 1.50, 1.49, np.nan], [0.08] * 4, 400)
    assert max_iter_check(a, b).moved.tolist() == [False, False, False, True]
