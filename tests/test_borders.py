"""Borders of the (e, u) plane located to rounding (stairbounce.borders, issue 21).

Independent references: the map of ``model._step`` (``model.iterate``), the
impact-by-impact loop of ``tests/naive.py`` and the analytic curves of
Theorem 3.1 and Corollary 2.1.
"""

import math

import numpy as np
import pytest

import stairbounce as sb
from stairbounce import borders, model

from . import naive

RNG = np.random.default_rng(21)
# random points of the paper's plane [0, 1) x (0, 1.5], plus points of the tongues
POINTS = [(float(e), float(u)) for e, u in zip(RNG.uniform(0.0, 0.95, 300), RNG.uniform(0.05, 1.5, 300))]


@pytest.mark.parametrize("e,u", POINTS[:100])
def test_itinerary_impacts_are_model_steps(e, u):
    it = sb.itinerary(e, u, max_iter=300)
    ks = it.impacts.values
    _, _, ref = model.iterate(1.0, 0.0, e, u, ks.size)
    assert np.array_equal(ks, ref[1:])
    assert it.attrs["slid"] == int(ks[-1] == model.SLIDING)
    if not it.attrs["slid"]:
        assert ks.size == 300
    assert np.array_equal(it.step.values, np.arange(1, ks.size + 1))


@pytest.mark.parametrize("e,u", POINTS)
def test_margin_signs_reproduce_the_impact_numbers(e, u):
    it = sb.itinerary(e, u, max_iter=200)
    T, ratio = model._constants(e, u)
    empty = np.zeros(0, np.int64)
    for j, (k, c, nx, a) in enumerate(zip(it.impacts.values, it.contact.values,
                                          it.next_impact.values, it.accumulation.values), 1):
        # the sliding test (2.4) and the first contact, as signs
        assert (k == model.SLIDING) == (a >= 0.0)
        if k == model.SLIDING:
            assert math.isnan(nx)
            continue
        assert (k == 0) == (c < 0.0)
        assert nx < 0.0
        if k >= 1:
            # k impacts: t_k <= T < t_(k+1), each margin from the scalar helper
            # that a continuation code calls as a function of (e, u)
            assert borders._margin(e, u, j, borders.EDGE, k, 1.0, 0.0, empty) >= 0.0
            assert borders._margin(e, u, j, borders.EDGE, k + 1, 1.0, 0.0, empty) == nx
        assert borders._margin(e, u, j, borders.GRAZE, 1, 1.0, 0.0, empty) == c
        assert borders._margin(e, u, j, borders.CHATTER, 0, 1.0, 0.0, empty) == a


@pytest.mark.parametrize("e,u", POINTS[:150])
def test_itinerary_agrees_with_the_impact_by_impact_loop(e, u):
    # naive.step bounces one impact at a time (no closed form); it cannot tell
    # an accumulation from rest closer than naive.REST, so the steps compared
    # are those whose margins are far from every event
    it = sb.itinerary(e, u, max_iter=200)
    T = 1.0 / u
    y, v = 1.0, 0.0
    for k, c, nx, a in zip(it.impacts.values, it.contact.values, it.next_impact.values,
                           it.accumulation.values):
        close = min(abs(c), abs(a), abs(nx) if k != model.SLIDING else math.inf) < 1e-9 * T
        yn, vn, kn = naive.step(y, v, e, u)
        if close:
            return
        assert kn == k
        # the signs of the margins, from the naive state and its own times
        speed = math.sqrt(v * v + 2.0 * y)
        assert (T - (v + speed) >= 0.0) == (c >= 0.0)
        assert (T - naive.accumulation_time(y, v, e) >= 0.0) == (a >= 0.0)
        if k == model.SLIDING:
            return
        y, v = yn, vn


def test_margin_is_nan_off_the_prefix_and_after_a_slide():
    e, u = 0.02, 0.7  # word (1, 1, 2, 0^inf): 4 steps, the last slides
    it = sb.itinerary(e, u)
    ks = it.impacts.values
    n = ks.size
    assert it.attrs["slid"] == 1 and n == 4
    prefix = ks.astype(np.int64)
    assert not math.isnan(borders._margin(e, u, n, borders.CHATTER, 0, 1.0, 0.0, prefix))
    assert borders._margin(e, u, n, borders.CHATTER, 0, 1.0, 0.0, prefix) >= 0.0
    assert math.isnan(borders._margin(e, u, n + 1, borders.CHATTER, 0, 1.0, 0.0, prefix))
    if n > 1:
        wrong = prefix.copy()
        wrong[0] = wrong[0] + 1
        assert math.isnan(borders._margin(e, u, n, borders.CHATTER, 0, 1.0, 0.0, wrong))


def test_itinerary_tongue_n_slides_at_step_n():
    # Theorem 3.1: inside tongue n the word is (n, 0^inf): n - 1 flights, then a slide
    for n in range(1, 6):
        lo, hi = sb.tongue(n, 0.01)
        u = 0.5 * (lo + hi)
        ks = sb.itinerary(0.01, u).impacts.values
        assert list(ks) == [0] * (n - 1) + [model.SLIDING]


def test_itinerary_start_state_and_max_iter():
    it = sb.itinerary(0.5, 2.0, max_iter=7, y0=3.0, v0=-0.5)
    assert it.sizes["step"] == 7 and it.attrs["slid"] == 0
    assert it.y.values[0] == 3.0 and it.v.values[0] == -0.5
    ys, vs, ks = model.iterate(3.0, -0.5, 0.5, 2.0, 7)
    assert np.array_equal(it.y.values, ys[:7]) and np.array_equal(it.v.values, vs[:7])
    assert np.array_equal(it.impacts.values, ks[1:])


@pytest.mark.parametrize("kw,name", [
    ({"e": 1.0}, "e"), ({"e": -0.1}, "e"), ({"u": 0.0}, "u"), ({"u": "1"}, "u"),
    ({"max_iter": 0}, "max_iter"), ({"max_iter": 2**31}, "max_iter"), ({"y0": -1.0}, "y0"),
    ({"v0": math.nan}, "v0"),
])
def test_itinerary_bad_input(kw, name):
    args = {"e": 0.3, "u": 0.8, **kw}
    with pytest.raises(ValueError, match=name):
        sb.itinerary(**args)
