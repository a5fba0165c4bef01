"""The closed forms of Section 2 against an impact-by-impact loop and against
the paper's own statements (Prop. 2.1-2.3, Corollary 2.1, Theorem 3.1)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

import stairbounce as sb
from stairbounce import model
from tests import naive


def random_states(rng, n):
    """States over the whole domain: e near 0 and near 1, y from 0 to 1e4
    (log-uniform), v of both signs and large, u from 0.01 to 20."""
    e = np.concatenate(
        [
            rng.uniform(0.0, 1.0, n // 2),
            10.0 ** rng.uniform(-9, -1, n // 8),
            1.0 - 10.0 ** rng.uniform(-3, -1, n // 8),
            np.zeros(n // 16),
        ]
    )
    m = len(e)
    y = np.where(rng.random(m) < 0.15, rng.uniform(0.0, 1.0, m), 10.0 ** rng.uniform(0, 4, m))
    v = rng.choice([-1.0, 1.0], m) * 10.0 ** rng.uniform(-3, 2, m)
    u = 10.0 ** rng.uniform(-2, 1.3, m)
    return e, u, y, v


def near_sliding_boundary(y, v, e, u):
    """Within float64 rounding of (2.4) or of some impact time t_k = T, where
    the two computations may legitimately disagree on k."""
    T = 1.0 / u
    s = math.sqrt(v * v + 2 * y)
    scale = abs(v) + s + T
    if abs(naive.accumulation_time(y, v, e) - T) < 1e-9 * scale:
        return True
    t, w = v + s, e * s
    for _ in range(200):
        if abs(t - T) < 1e-9 * scale:
            return True
        if t > T or w < 1e-17 * s:
            break
        t += 2 * w
        w *= e
    return False


@pytest.mark.parametrize("kernel", ["fast", "closed"])
def test_map_agrees_with_impact_by_impact_loop(kernel):
    """Hypothesis: Prop. 2.3 (with Prop. 2.2 for k) is the map the impacts
    define: same impact count and, off sliding, the same state to 1e-9."""
    rng = np.random.default_rng(20261121)
    e, u, y, v = random_states(rng, 4000)
    step = model._step if kernel == "fast" else model._step_closed
    compared = worst = 0
    for ei, ui, yi, vi in zip(e, u, y, v):
        T, ratio = model._constants(ei, ui)
        yn, vn, k = step(yi, vi, ei, T, ratio)
        assert math.isfinite(yn) and math.isfinite(vn)
        if near_sliding_boundary(yi, vi, ei, ui):
            continue
        ry, rv, rk = naive.step(yi, vi, ei, ui)
        assert k == rk, (ei, ui, yi, vi)
        scale = 1.0 + abs(ry) + abs(rv)
        err = max(abs(yn - ry), abs(vn - rv)) / scale
        worst = max(worst, err)
        compared += 1
    print(f"{kernel}: {compared} of {len(e)} states compared, worst relative error {worst:.2e}")
    assert compared > 0.97 * len(e)
    assert worst < 1e-9


def test_both_kernels_agree_on_the_whole_domain():
    """The fast counting form and the closed form are the same map."""
    rng = np.random.default_rng(7)
    e, u, y, v = random_states(rng, 20000)
    differ = 0
    for ei, ui, yi, vi in zip(e, u, y, v):
        T, ratio = model._constants(ei, ui)
        a = model._step(yi, vi, ei, T, ratio)
        b = model._step_closed(yi, vi, ei, T, ratio)
        if a[2] != b[2]:
            differ += 1
            assert near_sliding_boundary(yi, vi, ei, ui)
            continue
        assert a[0] == pytest.approx(b[0], rel=1e-10, abs=1e-10)
        assert a[1] == pytest.approx(b[1], rel=1e-10, abs=1e-10)
    assert differ <= 5


def parabola_2_3(e, u, v):
    """Right-hand side of (2.3) as derived from (2.5).

    The paper prints the constant term as (1+e)^2 / (2 u^2 (1-e)^2); squaring
    (2.4) gives (1-e)^2 / (2 u^2 (1+e)^2), and only the latter reproduces the
    vertex y* = (1-e)^2 / (8 e u^2) of Corollary 2.1 (test below), so the
    printed fraction is inverted.
    """
    return (
        -2 * e / (1 + e) ** 2 * v**2
        - (1 - e) ** 2 / ((1 + e) ** 2 * u) * v
        + (1 - e) ** 2 / (2 * u**2 * (1 + e) ** 2)
    )


def test_parabola_vertex_is_corollary_2_1():
    for e, u in [(0.1, 0.5), (0.3, 0.2), (0.7, 1.3)]:
        v_star = -((1 - e) ** 2) / (4 * e * u)
        y_star = (1 - e) ** 2 / (8 * e * u * u)
        assert parabola_2_3(e, u, v_star) == pytest.approx(y_star, rel=1e-12)
        assert parabola_2_3(e, u, v_star * 1.01) < y_star
        assert parabola_2_3(e, u, v_star * 0.99) < y_star


def test_sliding_criterion_is_the_parabola_of_prop_2_1():
    """(2.4) as implemented is equivalent to the parabola (2.3)."""
    rng = np.random.default_rng(3)
    e, u, y, v = random_states(rng, 5000)
    checked = sliding = 0
    for ei, ui, yi, vi in zip(e, u, y, v):
        rhs = parabola_2_3(ei, ui, vi)
        if abs(yi - rhs) < 1e-9 * (abs(yi) + abs(rhs) + vi * vi):
            continue
        # the parabola (2.3) is (2.5); (2.4) also needs 1/u - v > 0 (proof of Prop. 2.1)
        slid = sb.slides(yi, vi, ei, ui)
        assert slid == (yi <= rhs and 1 / ui - vi > 0)
        checked += 1
        sliding += slid
    assert checked > 0.97 * len(e)
    assert 0.1 * checked < sliding < 0.9 * checked  # both sides are exercised


def test_sliding_returns_the_edge_state():
    # e = 0.1, u = 0.5 from (1, 0): lands on the first step and slides (Thm 3.1, n = 1)
    assert sb.poincare_map(1.0, 0.0, 0.1, 0.5) == (1.0, 0.0, sb.SLIDING)
    assert sb.slides(1.0, 0.0, 0.1, 0.5)


def test_equality_in_2_4_counts_as_sliding():
    # e = 0: sliding iff the first impact t1 = v + sqrt(v^2 + 2y) <= T; choose t1 = T = 2
    y, v = 2.0, 0.0  # t1 = 2
    assert sb.slides(y, v, 0.0, 0.5)
    assert sb.poincare_map(y, v, 0.0, 0.5)[2] == sb.SLIDING
    assert not sb.slides(y, v, 0.0, 0.5 * (1 + 1e-12))


def test_plastic_impact_sticks_at_first_contact():
    """e = 0: the ball never bounces; either it flies over or it slides."""
    rng = np.random.default_rng(11)
    for _ in range(500):
        y, v, u = rng.uniform(0, 5), rng.uniform(-3, 3), rng.uniform(0.05, 3)
        k = sb.poincare_map(y, v, 0.0, u)[2]
        assert k in (0, sb.SLIDING)
        assert (k == sb.SLIDING) == (v + math.sqrt(v * v + 2 * y) <= 1 / u)


def test_impact_number_matches_loop_and_refuses_sliding():
    rng = np.random.default_rng(5)
    e, u, y, v = random_states(rng, 3000)
    for ei, ui, yi, vi in zip(e, u, y, v):
        if near_sliding_boundary(yi, vi, ei, ui):
            continue
        rk = naive.step(yi, vi, ei, ui)[2]
        if rk == naive.SLIDING:
            with pytest.raises(ValueError, match="slides"):
                sb.impact_number(yi, vi, ei, ui)
        else:
            assert sb.impact_number(yi, vi, ei, ui) == rk


def test_impact_number_closed_form_on_many_impacts():
    """Prop. 2.2 where it matters: up to hundreds of impacts on one step (e near 1)."""
    rng = np.random.default_rng(17)
    for _ in range(300):
        e = rng.uniform(0.8, 0.995)
        y, v = rng.uniform(0, 3), rng.uniform(-2, 2)
        # keep e^k above 1e-8: below it, float64 cannot tell the bounce from rest
        want = min(int(rng.integers(8, 400)), int(math.log(1e-8) / math.log(e)))
        t = naive.accumulation_time(y, v, 0.0)  # first impact
        s = math.sqrt(v * v + 2 * y)
        w = e * s
        for _ in range(want - 1):
            t += 2 * w
            w *= e
        u = 1.0 / (t + w * rng.uniform(0.1, 1.9))  # edge between impacts want and want + 1
        rk = naive.step(y, v, e, u)[2]
        assert rk == want
        assert model._impact_number_closed(y, v, e, 1 / u) == want
        assert sb.impact_number(y, v, e, u) == want
        assert sb.poincare_map(y, v, e, u)[2] == want


def test_impact_times_eq_2_2():
    """Eq. (2.2) equals the times and speeds of consecutive bounces."""
    y, v, e = 1.7, -0.4, 0.6
    times, vel = sb.impact_times(y, v, e, 6)
    s = math.sqrt(v * v + 2 * y)
    t, w = v + s, e * s
    for k in range(6):
        assert times[k] == pytest.approx(t, rel=1e-13)
        assert vel[k] == pytest.approx(w, rel=1e-13)
        t += 2 * w
        w *= e
    assert len(sb.impact_times(y, v, e, 0)[0]) == 0


def test_corollary_2_1_no_sliding_above_the_bound():
    """Above (1-e)/(2 sqrt(2e)) no state of the domain y >= 1 slides."""
    rng = np.random.default_rng(2)
    for e in [0.01, 0.05, 0.1, 0.3, 0.6, 0.9]:
        u = sb.no_sliding_bound(e) * (1 + 1e-9)
        y = 1.0 + 10.0 ** rng.uniform(-6, 3, 2000)
        v = rng.uniform(-20, 20, 2000)
        v = np.concatenate([v, [-(1 - e) ** 2 / (4 * e * u)]])  # the vertex of the parabola
        y = np.concatenate([y, [1.0]])
        assert not any(sb.slides(a, b, e, u) for a, b in zip(y, v))


def test_corollary_2_1_is_sharp_at_the_vertex():
    """Just below the bound, the vertex (1, v*) of the parabola slides."""
    for e in [0.01, 0.1, 0.3, 0.6, 0.9]:
        u = sb.no_sliding_bound(e) * (1 - 1e-6)
        v_star = -((1 - e) ** 2) / (4 * e * u)
        assert sb.slides(1.0, v_star, e, u)
        assert not sb.slides(1.0, v_star, e, sb.no_sliding_bound(e) * (1 + 1e-6))
    assert sb.no_sliding_bound(0.0) == math.inf
    assert sb.no_sliding_bound(0.125) == pytest.approx(0.875 / 1.0)


def tongue_cases():
    """(n, e) with a non-empty tongue: (1-e)/(1+e) > sqrt((n-1)/n)."""
    for n in range(1, 7):
        c = math.sqrt((n - 1) / n)
        e_max = (1 - c) / (1 + c)
        for frac in (0.05, 0.4, 0.8):
            yield n, (0.3 if n == 1 else e_max) * frac


@pytest.mark.parametrize("n,e", list(tongue_cases()))
def test_theorem_3_1_inside_the_tongue(n, e):
    """Inside (n-1)/2 < u^2 <= n/2 ((1-e)/(1+e))^2 the solution is (n, 0^inf)."""
    lo, hi = sb.tongue(n, e)
    assert lo < hi
    for u in [lo + (hi - lo) * f for f in (1e-6, 0.25, 0.5, 0.75)] + [hi * (1 - 1e-12)]:
        if u <= 0:
            continue
        w = sb.sliding_word(e, u, max_iter=50)
        assert w is not None and len(w) == 1 and w.period == n, (n, e, u, w)
        assert w.letters == (n,)


@pytest.mark.parametrize("n,e", list(tongue_cases()))
def test_theorem_3_1_just_outside_the_tongue(n, e):
    lo, hi = sb.tongue(n, e)
    outside = [hi * (1 + 1e-6)] + ([lo * (1 - 1e-6)] if lo > 0 else [])
    for u in outside:
        w = sb.sliding_word(e, u, max_iter=200)
        assert w is None or w.letters != (n,), (n, e, u, w)


def test_tongue_formula():
    assert sb.tongue(1, 0.0) == (0.0, pytest.approx(math.sqrt(0.5)))
    lo, hi = sb.tongue(3, 0.1)
    assert lo == pytest.approx(1.0)
    assert hi == pytest.approx(math.sqrt(1.5) * 0.9 / 1.1)
    # the tongues end on the Corollary 2.1 curve: at the tip u_low = u_high <= the bound
    for n in range(2, 8):
        c = math.sqrt((n - 1) / n)
        e_tip = (1 - c) / (1 + c)
        lo, hi = sb.tongue(n, e_tip)
        assert lo == pytest.approx(hi)
        assert hi <= sb.no_sliding_bound(e_tip) * (1 + 1e-12)


def test_iterate_matches_repeated_map():
    ys, vs, ks = sb.iterate(0.1, 0.0, 0.1, 0.83, 300)
    y, v = 0.1, 0.0
    for n in range(1, 301):
        y, v, k = sb.poincare_map(y, v, 0.1, 0.83)
        assert (ys[n], vs[n], ks[n]) == (y, v, k)
    assert len(ys) == 301 and ys[0] == 0.1 and ks[0] == 0


finite = st.floats(allow_nan=False, allow_infinity=False)


@settings(max_examples=400, deadline=None)
@given(
    y=st.floats(0.0, 1e6),
    v=st.floats(-1e3, 1e3),
    e=st.just(0.0) | st.floats(2.0**-53, 1.0, exclude_max=True),  # the valid range (docs/design.md)
    u=st.floats(1e-3, 1e3),
)
# found by hypothesis: e one ulp below 1, about 1e6 impacts on the step; the
# closed form's cap on k and the cancellation in eq. (2.2) put the ball below the edge
@example(y=0.0, v=6.103515625e-05, e=0.9999999999999999, u=0.0078125)
def test_map_is_finite_and_lands_above_the_edge(y, v, e, u):
    """Property: P never returns NaN and always returns y >= 1 (the ball is
    above the floor when it passes the edge, which is 1 above the next floor)."""
    yn, vn, k = sb.poincare_map(y, v, e, u)
    assert math.isfinite(yn) and math.isfinite(vn)
    assert yn >= 1.0 - 1e-12 * (1 + abs(y) + v * v)
    assert k >= sb.SLIDING


@pytest.mark.parametrize(
    "call,match",
    [
        (lambda: sb.poincare_map(1, 0, 1.0, 0.5), r"e \(restitution coefficient\) must be in \[0, 1\)"),
        (lambda: sb.poincare_map(1, 0, -0.1, 0.5), r"e .*\[0, 1\)"),
        (lambda: sb.poincare_map(1, 0, float("nan"), 0.5), "e must be finite"),
        (lambda: sb.poincare_map(1, 0, 0.1, 0.0), r"u \(horizontal speed\) must be > 0"),
        (lambda: sb.poincare_map(1, 0, 0.1, float("inf")), "u must be finite"),
        (lambda: sb.poincare_map(-1, 0, 0.1, 0.5), "y .* must be >= 0"),
        (lambda: sb.poincare_map(1, float("nan"), 0.1, 0.5), "v must be finite"),
        (lambda: sb.slides(1, 0, 0.1, -2), "u .* must be > 0"),
        (lambda: sb.tongue(0, 0.1), "n must be an integer >= 1"),
        (lambda: sb.tongue(1.5, 0.1), "n must be an integer >= 1"),
        (lambda: sb.iterate(1, 0, 0.1, 0.5, -1), "steps must be an integer >= 0"),
        (lambda: sb.impact_times(1, 0, 0.1, -1), "k must be an integer >= 0"),
        (lambda: sb.sliding_word(0.1, 0.5, max_iter=0), "max_iter must be an integer >= 1"),
        (lambda: sb.no_sliding_bound(2.0), r"e .*\[0, 1\)"),
        (lambda: sb.poincare_map("a", 0, 0.1, 0.5), "y must be a real number"),
    ],
)
def test_bad_input_names_the_parameter(call, match):
    with pytest.raises(ValueError, match=match):
        call()
