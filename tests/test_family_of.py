"""sb.family_of: a word's family by its form (issue 39, item 6).

The patterns below are written out by hand from the rule in the docstring
(the run of a primitive block covering the most letters; ties to the shorter
block, then the earlier run), the first two are the issue's own examples;
the round trip asks :func:`stairbounce.cascade`, which locates the members
of a pattern on a line independently of this function, for member k.
"""

from __future__ import annotations

import pytest

import stairbounce as sb


@pytest.mark.parametrize("word, pattern, k", [
    ((1, 1, 1), "(1^k, 0^inf)", 3),
    ((1, 0, 1, 0, 1, 1), "((1, 0)^k, 1, 1, 0^inf)", 2),  # ((1, 0), (1, 0), 1, 1, 0^inf)
    ("(1, 1, 1, 2, 0^inf)", "(1^k, 2, 0^inf)", 3),
    ((3, 0, 0, 1, 1), "(3, 0, 0, 1^k, 0^inf)", 2),  # a block of zeros does not count
    ((2, 1, 2, 1, 2), "((2, 1)^k, 2, 0^inf)", 2),  # (2, 1)^2 from the first letter, not (1, 2)^2
    ((1, 1, 2, 1, 1, 2, 1, 1), "((1, 1, 2)^k, 1, 1, 0^inf)", 2),  # six letters beat 1^2's two
    ((2, 2, 3, 3), "(2^k, 3, 3, 0^inf)", 2),  # equal runs: the earlier one
    ((1, 2, 1, 2, 1, 1, 1, 1), "(1, 2, 1, 2, 1^k, 0^inf)", 4),  # 1^4 (4 letters) ties (1, 2)^2: shorter block
])
def test_known_patterns(word, pattern, k):
    fam = sb.family_of(word)
    assert fam == (pattern, k) and fam.pattern == pattern and fam.k == k
    # the pattern's member k is the word (read back by the cascade's parser)
    from stairbounce.cascades.patterns import _parse_pattern

    member = sb.Word(_parse_pattern(pattern).letters(k))
    assert member == (sb.Word(word) if isinstance(word, tuple) else sb.parse_word(word))


@pytest.mark.parametrize("word", [(2,), (1, 2), (3, 1, 2, 0, 1), "(2, 0^inf)", (2, 1, 3), (3, 0, 0, 1)])
def test_no_repeated_block_is_none(word):
    assert sb.family_of(word) is None


@pytest.mark.parametrize("bad", [None, b"(1, 1)", "(1, 1", 3.5, (0, 1)])
def test_bad_words_are_value_errors_naming_the_word(bad):
    with pytest.raises(ValueError, match="word"):
        sb.family_of(bad)


def test_round_trip_through_cascade():
    """At a point of member k of (1^k, 0^inf) on e = 0.02 (the issue's line), the
    word there names the family, and the family's member k is that word."""
    e = 0.02
    c = sb.cascade("(1^k, 0^inf)", e=e, u=(0.6, 0.75), k_max=4, max_iter=300)
    rows = c.members[c.members["k"] >= 2]
    assert len(rows) >= 2
    for _, r in rows.iterrows():
        u = 0.5 * (r["lo"] + r["hi"])  # a tapped point inside the member
        w = sb.sliding_word(e, u, 300)
        fam = sb.family_of(w)
        assert fam == ("(1^k, 0^inf)", int(r["k"]))
        again = sb.cascade(fam.pattern, e=e, u=(0.6, 0.75), k_max=fam.k, max_iter=300).members
        assert again.set_index("k").loc[fam.k, "word"] == w.format(ascii=True)
