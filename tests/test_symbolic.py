"""Words of periodic sliding solutions (docs/design.md's convention)."""

from __future__ import annotations

import numpy as np
import pytest

import stairbounce as sb
from stairbounce.symbolic import word_from_impacts
from tests import naive


def test_word_properties_and_notation():
    w = sb.Word((2, 0, 3, 1))
    assert len(w) == 4
    assert w.period == 6  # steps: the sum of the jump numbers
    assert w.impacts == 3  # finite impacts: every letter but the last
    assert w.jumps == 3
    assert str(w) == "(2, 0, 3, 1, 0^\u221e)"
    assert w.format(ascii=True) == "(2, 0, 3, 1, 0^inf)"
    assert sb.parse_word(str(w)) == w == sb.parse_word("(2,0,3,1,0^inf)")


@pytest.mark.parametrize("bad", [(), (0, 1), (1, 0), (2, -1, 1)])
def test_word_rejects_impossible_letters(bad):
    with pytest.raises(ValueError, match="letters"):
        sb.Word(bad)


def test_parse_word_reads_the_letters_without_the_tail_and_rejects_other_text():
    # the letters alone, as Word keeps them, are the same word (issue 37)
    assert sb.parse_word("(2, 0, 3)") == sb.parse_word("(2, 0, 3, 0^inf)") == sb.Word((2, 0, 3))
    for bad in ("(2, 0, 3", "2, 0, 3", "(0^inf)", "(2, x)", "()"):
        with pytest.raises(ValueError, match="word must look like"):
            sb.parse_word(bad)


def test_word_from_impacts_follows_the_convention():
    # fly over, land with 2 impacts, land with 1, fly over twice, accumulate
    ks = [0, 2, 1, 0, 0, sb.SLIDING]
    assert word_from_impacts(ks).letters == (2, 0, 1, 3)
    assert word_from_impacts([sb.SLIDING]).letters == (1,)
    assert word_from_impacts([0, 0, sb.SLIDING]).letters == (3,)
    with pytest.raises(ValueError):
        word_from_impacts([0, 1])


def test_sliding_word_agrees_with_impact_by_impact_loop():
    """Hypothesis: the word read off the fast map equals the word of the naive
    simulation on random parameters of the paper's plane."""
    rng = np.random.default_rng(42)
    found = 0
    for _ in range(400):
        e, u = rng.uniform(0, 0.6), rng.uniform(0.05, 1.5)
        w = sb.sliding_word(e, u, max_iter=300)
        ref = naive.word(e, u, max_steps=300)
        assert (w.letters if w else None) == ref, (e, u)
        found += w is not None
    assert 50 < found < 400  # both outcomes occur


def test_known_words_from_the_paper_plane():
    # inside the n = 1 and n = 2 tongues of Theorem 3.1 at e = 0.1
    assert sb.sliding_word(0.1, 0.5).letters == (1,)
    assert sb.sliding_word(0.1, 0.75).letters == (2,)
    # above Corollary 2.1 nothing slides
    assert sb.sliding_word(0.1, 1.01, max_iter=5000) is None
    # e = 0: the ball sticks wherever it lands; from (1, 0) it lands on the first
    # step iff sqrt(2) <= 1/u, i.e. the n = 1 tongue u <= 1/sqrt(2)
    assert sb.sliding_word(0.0, 0.7).letters == (1,)
