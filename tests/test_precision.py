"""The Poincare map against a 60-digit reference, near e = 1 above all.

The reference is ``tests.naive.precise_step``: the physics of one step in
mpmath arithmetic (bounces counted one by one, or the geometric series of
their durations summed in closed form past a limit, with 60 digits so that its
cancellation costs nothing).  The reliability report (issue 17, D4) found the
float closed form of eq. (2.2) wrong by up to 100 % at 1 - e = 2^-53; these
tests pin the fix over 1 - e from 1e-3 down to 2^-53 and up to 1e17 impacts.

What "right" means.  The map is ill-conditioned where the bounces are short:
rounding ``T = 1/u`` alone moves the edge by eps T, which can be more than a
whole bounce.  So the answer must be the exact map of the inputs with ``T``
moved by at most ``C eps T``: the impact number between the reference's at
``T (1 - C eps)`` and at ``T (1 + C eps)``, the state on that bounce (its energy
``y - 1 + v^2/2 = v_k^2/2``), and where the reference's bounce is longer than
that uncertainty, the reference's k and state to ``C eps (T + |v| + s)``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import stairbounce as sb
from stairbounce import model
from tests import naive

mpmath = pytest.importorskip("mpmath")

C = 64  # ulps of slack, as in the reliability campaign


def check_against_reference(y, v, e, u, count_limit=50):
    """Assert the float map is right at (y, v, e, u) in the sense of the module
    docstring (tests.naive.classify); return True when the reference's k and
    state were matched exactly, False when within the conditioning."""
    verdict, err = naive.classify(y, v, e, u, sb.poincare_map(y, v, e, u), slack=C, count_limit=count_limit)
    assert verdict in ("ok", "ok-conditioned"), (verdict, err, (y, v, e, u))
    return verdict == "ok"


def test_the_two_cases_of_the_report():
    """Report D4: e = 1 - 2^-53 (the float 1 - 1e-16), from rest at the edge."""
    e = 1 - 1e-16
    assert e == 1 - 2.0**-53
    # 20 impacts, each bounce about 2.8 long: every digit is resolvable
    y, v, k = sb.poincare_map(1.0, 0.0, e, 0.01768)
    assert k == 20  # the 60-digit reference: (1.99997220013928, 0.00745652207306, 20)
    assert y == pytest.approx(1.99997220013928, abs=1e-13)
    assert v == pytest.approx(0.00745652207306, abs=1e-13)
    # about 4.49e15 impacts at T = 1e16: the exact k (1/u to 60 digits) is
    # 4489558784827552 with d = 1.60 into a 1.72-long bounce; T = 1/u rounded to
    # float64 already moves the edge by 0.2, and t_k near 1e16 is known to an
    # ulp (2): the answer is k = ...552 or ...553, on its bounce, never the
    # capped 1e15 of before
    check_against_reference(1.0, 0.0, e, 1e-16)
    k = sb.impact_number(1.0, 0.0, e, 1e-16)
    assert abs(k - 4489558784827552) <= 1
    ref = naive.precise_step(1.0, 0.0, e, 1e-16)
    assert ref[2] == 4489558784827552


def _cases(rng):
    """(y, v, e, u) with the edge in the middle of the bounce after about k
    impacts, for 1 - e from 1e-3 to 2^-53 and k from 5 to 1e17."""
    deltas = [1e-3, 1e-6, 1e-9, 1e-11, 1e-12, 1e-13, 1e-14, 1e-15, 2.0**-53]
    ks = [5, 8, 20, 100, 10**4, 10**6, 10**9, 10**12, 10**15, 10**17]
    with mpmath.workdps(60):
        for delta in deltas:
            e = 1.0 - delta
            for kk in ks:
                # past k |log e| ~ 37, e^k s is below 2^-53 s: the impacts
                # accumulate before any float edge can fall between them
                if kk * delta > 30:
                    continue
                for _ in range(2):
                    y = float(10.0 ** rng.uniform(-3, 2))
                    v = float(rng.uniform(-5, 5))
                    me, s = mpmath.mpf(e), mpmath.sqrt(mpmath.mpf(v) ** 2 + 2 * mpmath.mpf(y))
                    t1 = mpmath.mpf(v) + s
                    tk = t1 + 2 * me * s * (1 - me ** (kk - 1)) / (1 - me)
                    T = tk + 2 * me**kk * s * mpmath.mpf(rng.uniform(0.1, 0.9))
                    yield y, v, e, float(1 / T), kk


def test_map_matches_the_60_digit_reference_near_e_1():
    rng = np.random.default_rng(2026)
    exact = total = 0
    for y, v, e, u, kk in _cases(rng):
        if not 1e-150 <= u:
            continue
        exact += check_against_reference(y, v, e, u)
        total += 1
    # the grid reaches 1e17 impacts; most points are resolvable and must be exact
    assert total > 120
    assert exact > 0.6 * total, (exact, total)


def test_fast_and_closed_forms_are_one_map_near_e_1():
    """_step counts the first impacts and hands over to _step_closed: both give
    the reference's impact number on resolvable points (k < 8 counted, more closed)."""
    rng = np.random.default_rng(5)
    for y, v, e, u, kk in _cases(rng):
        if kk > 10**4:
            continue
        T, ratio = model._constants(e, u)
        a = model._step(y, v, e, T, ratio)
        b = model._step_closed(y, v, e, T, ratio)
        assert a[2] == b[2]
        scale = 64 * naive.EPS * (T + abs(v) + 3)
        assert abs(a[0] - b[0]) <= scale * (1 + abs(a[1])) and abs(a[1] - b[1]) <= scale


def test_reference_counts_and_sums_agree():
    """The reference's two ways (one bounce at a time / the closed sum) agree."""
    for y, v, e, u in [(1.0, 0.0, 1 - 1e-16, 0.01768), (0.3, -1.2, 0.999, 0.02), (2.0, 1.5, 1 - 1e-9, 0.05)]:
        a = naive.precise_step(y, v, e, u, count_limit=10**6)
        b = naive.precise_step(y, v, e, u, count_limit=3)
        assert a[2] == b[2]
        assert abs(a[0] - b[0]) < 1e-35 and abs(a[1] - b[1]) < 1e-35


def test_impact_number_has_no_cap():
    """k up to 3e17 (the principled bound 36.8/|log e|) is returned as computed."""
    e = 1.0 - 2.0**-53
    # T a little below the accumulation time 2 s e/(1-e) ~ 2.5e16 x sqrt(2)
    s = math.sqrt(2.0)
    u = 1.0 / (2 * s * e / (1 - e) * (1 - 1e-6))
    k = sb.impact_number(1.0, 0.0, e, u)
    # e^k = 1e-6 + O(eps): k = log(1e-6)/log(e) = 13.8 / 1.11e-16
    assert k == pytest.approx(math.log(1e-6) / math.log1p(-(2.0**-53)), rel=1e-9)
    assert k > 1e17
