"""``sb.sliding_answer`` and ``stairbounce word``: "impossible" only where the
paper proves it (Corollary 2.1: no solution slides for ``u >= (1-e)/(2
sqrt(2e))``), "not found" below the curve, the word where there is one
(issue 25).  The reference is tests/naive.py's impact-by-impact loop, which
knows nothing of the corollary: above the curve it must find no slide either.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests import naive
import stairbounce as sb

from ._cli import run_cli as run


def cor21(e):
    return (1.0 - e) / (2.0 * math.sqrt(2.0 * e))


@pytest.mark.parametrize("e", [0.1, 0.3, 0.5, 0.7, 0.9])
@pytest.mark.parametrize("factor", [1.001, 1.3, 3.0])
def test_above_the_curve_is_impossible_and_nothing_slides(e, factor):
    u = factor * cor21(e)
    a = sb.sliding_answer(e, u, max_iter=400)
    assert a.verdict == "impossible" and a.word is None and not a.found
    assert a.bound == pytest.approx(cor21(e), rel=1e-15)
    assert f"impossible (Corollary 2.1: u >= {cor21(e):.6g}" in a.text()
    # the impact-by-impact orbit of (1, 0) does not slide either
    assert naive.word(e, u, 400) is None


def test_below_the_curve_found_or_not_found():
    # inside tongue 2 at e = 0.1 (Theorem 3.1): found, the same word as the reference
    lo, hi = sb.tongue(2, 0.1)
    a = sb.sliding_answer(0.1, (lo + hi) / 2)
    assert a.verdict == "found" and a.word.letters == naive.word(0.1, (lo + hi) / 2) == (2,)
    assert "word (2, 0^inf)" in a.text(ascii=True)
    # e = 0.4, u = 0.33: above tongue 1 (0.303), below the curve (0.335); the
    # orbit does not slide within 100 steps (reference too): not found, not "impossible"
    assert sb.tongue(1, 0.4)[1] < 0.33 < cor21(0.4)
    a = sb.sliding_answer(0.4, 0.33, max_iter=100)
    assert naive.word(0.4, 0.33, 100) is None
    assert a.verdict == "not found" and "no periodic sliding solution found within 100 steps" in a.text()
    assert "Corollary 2.1 does not exclude it" in a.text()
    # on the curve itself (equality may slide): never called impossible
    assert sb.sliding_answer(0.5, cor21(0.5), max_iter=10).verdict != "impossible"
    # e = 0: plastic, every speed slides, the bound is infinite
    a = sb.sliding_answer(0.0, 5.0)
    assert a.verdict == "found" and a.bound == math.inf


def test_speed_bound_in_metres_per_second_and_short_repr():
    A, B, G = 0.17, 0.28, 9.81
    stairs = sb.Staircase(A, B, G)
    a = sb.sliding_answer(0.7, stairs.speed(1.5))
    # U = u b / sqrt(a/g) at the bound: the report's 0.270 m/s
    expected = cor21(0.7) * B / math.sqrt(A / G)
    assert a.speed_bound == pytest.approx(expected, rel=1e-14)
    assert round(expected, 3) == 0.270
    assert f"sliding needs U < {expected:.4g} m/s" in a.text()
    assert sb.sliding_answer(0.7, 1.5).speed_bound is None
    long = sb.sliding_answer(0.0806666, 0.6533333, 500)
    assert len(long.word) > 10 and "\n" not in repr(long) and len(repr(long)) < 120
    with pytest.raises(ValueError, match="max_iter"):
        sb.sliding_answer(0.5, 0.5, max_iter=0)


def test_word_command_says_impossible_with_the_speed(capsys):
    code, out, _ = run(["word", "--e", "0.7", "--speed", "1.5", "--step-height", "0.17",
                        "--step-length", "0.28"], capsys)
    assert code == 0
    assert "impossible (Corollary 2.1: u >= 0.126773 at e = 0.7); sliding needs U < 0.2696 m/s" in out
    assert "found within" not in out
    code, out, _ = run(["word", "--e", "0.4", "--u", "0.33", "--max-iter", "100"], capsys)
    assert code == 0 and "no periodic sliding solution found within 100 steps" in out and "needs u < 0.33541" in out
    code, out, _ = run(["word", "--e", "0.3", "--u", "0.2"], capsys)
    assert "period:  1 step\n" in out


def test_explorer_tap_says_proven_above_the_curve():
    pytest.importorskip("panel")
    from stairbounce.explorer import view as V

    d = V.point_details(0.05, 5.0, 200)
    assert d["word"] is None and d["answer"].verdict == "impossible"
    d = V.point_details(0.4, 0.33, 100)
    assert d["answer"].verdict == "not found"
