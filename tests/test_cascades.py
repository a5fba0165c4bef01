"""Cascades of words (issue 39): patterns, members located exactly on a line and
checked against sliding_word, the order the search relies on, the law detector
on maps whose laws are known in closed form, and the command line."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

import stairbounce as sb
from stairbounce.cascades.patterns import _parse_pattern, word_impacts
from stairbounce.model import SLIDING
from stairbounce.symbolic import word_from_impacts

from ._cli import run_cli as _run

E = 0.02
U_RANGE = (0.6, 0.75)


@pytest.fixture(scope="module")
def ones():
    return sb.cascade("(1^k, 0^inf)", e=E, u=U_RANGE, k_max=40)


# --------------------------------------------------------------------------- #
# Patterns                                                                    #
# --------------------------------------------------------------------------- #


@pytest.mark.parametrize("text, k, letters", [
    ("(1^k, 0^inf)", 3, (1, 1, 1)),
    ("((1, 0)^k, 1, 1, 0^inf)", 2, (1, 0, 1, 0, 1, 1)),
    ("((1, 0)^m, 0^inf)", 3, (1, 0, 1, 0, 1)),  # 0, 0^inf is 0^inf
    ("(2, (1, 0^2)^n, 3, 0^\u221e)", 1, (2, 1, 0, 0, 3)),
    ("(1^k, 0^inf)", 0, ()),
])
def test_patterns_expand_as_the_paper_writes_words(text, k, letters):
    assert _parse_pattern(text).letters(k) == letters


@pytest.mark.parametrize("text", ["(1^k, 0)", "(1, 0^inf)", "(1^k, 2^m, 0^inf)", "((1^k, 0)^2, 0^inf)",
                                  "(1^k, 0^inf", "1^k, 0^inf", "(1^inf, 0^inf)", "(()^k, 0^inf)", 7])
def test_bad_patterns_are_refused_by_name(text):
    with pytest.raises(ValueError, match="pattern"):
        sb.cascade(text, e=E, u=U_RANGE)


@pytest.mark.parametrize("letters", [(1,), (2, 0, 3, 1), (1, 0, 1, 0, 1, 1), (3, 0, 0, 1)])
def test_word_impacts_inverts_word_from_impacts(letters):
    w = sb.Word(letters)
    ks = word_impacts(w)
    assert ks.shape[0] == w.period and ks[-1] == SLIDING
    assert word_from_impacts(ks) == w


# --------------------------------------------------------------------------- #
# The order the search relies on                                              #
# --------------------------------------------------------------------------- #


def _rank(ks):
    return [math.inf if k == SLIDING else int(k) for k in ks]


@pytest.mark.parametrize("axis", ["u", "e"])
def test_itineraries_are_lexicographically_non_increasing_along_a_line(axis):
    # the module's theorem (margins decrease with e and u along a fixed itinerary),
    # checked on 400 points of a line through the cascades, 80 steps each
    xs = np.linspace(0.675, 0.7, 400) if axis == "u" else np.linspace(0.0, 0.1, 400)
    seqs = []
    for x in xs:
        e, u = (E, x) if axis == "u" else (x, 0.69)
        seqs.append(_rank(sb.iterate(1.0, 0.0, e, u, 80)[2][1:]))
    assert all(a >= b for a, b in zip(seqs, seqs[1:]))
    assert len({tuple(s) for s in seqs}) > 20  # the line crosses many words


# --------------------------------------------------------------------------- #
# Members                                                                     #
# --------------------------------------------------------------------------- #


def test_members_have_their_word_inside_and_another_just_outside(ones):
    m = ones.members
    assert len(m) >= 20 and m.k.tolist() == list(range(1, len(m) + 1))
    for r in m.itertuples():
        w = sb.parse_word(r.word)
        assert w.letters == (1,) * r.k and r.period == r.k
        for x in np.linspace(r.lo, r.hi, 5):
            assert sb.sliding_word(E, float(x)) == w
        if r.lo_kind != "range":
            assert sb.sliding_word(E, float(np.nextafter(r.lo, 0))) != w
        if r.hi_kind != "range":
            assert sb.sliding_word(E, float(np.nextafter(r.hi, 1))) != w
    # the members follow each other along u, and k = 1 is the Theorem 3.1 tongue
    assert np.all(np.diff(m.lo.values) > 0) and np.all(m.lo.values[1:] > m.hi.values[:-1])
    assert m.lo_kind[0] == "range" and m.hi[0] == pytest.approx(sb.tongue(1, E)[1], abs=1e-15)


def test_widths_are_the_issues_and_the_edges_are_labelled_by_their_event(ones):
    # issue 39's sampled widths at e = 0.02 for k = 2..6
    m = ones.members.set_index("k")
    for k, w in zip(range(2, 7), (6.26e-3, 2.02e-3, 9.71e-4, 5.57e-4, 3.53e-4)):
        assert m.width[k] == pytest.approx(w, rel=5e-3)
    # each label says which step's impact number changes across the edge, and how
    # (checked with sb.iterate, independent of the labelling code)
    for k in range(2, 12):
        r = m.loc[k]
        for side, out in (("lo", np.nextafter(r.lo, 0)), ("hi", np.nextafter(r.hi, 1))):
            j = int(r[f"{side}_step"])
            kin = sb.iterate(1.0, 0.0, E, float(r[side]), j)[2][1:]
            kout = sb.iterate(1.0, 0.0, E, float(out), j)[2][1:]
            assert list(kin[:j - 1]) == list(kout[:j - 1]) and kin[j - 1] != kout[j - 1]
            kind = r[f"{side}_kind"]
            if kind == "chatter":
                assert SLIDING in (kin[j - 1], kout[j - 1])
            elif kind == "edge":
                assert {kin[j - 1], kout[j - 1]} == {r[f"{side}_index"] - 1, r[f"{side}_index"]}
            else:
                assert min(kin[j - 1], kout[j - 1]) == 0
        assert (r.lo_kind, r.lo_step, r.hi_kind, r.hi_step) == ("edge", k - 1, "chatter", k)


def test_the_cascade_ends_where_no_float_has_the_next_word(ones):
    last = ones.last
    assert last is not None and last < 40
    assert f"member k = {last + 1}" in ones.stop and "no float" in ones.stop
    # bisection on the word's side at 2000 points between the last member and
    # u_1 finds no point with the next word (a check, not the proof)
    nxt = sb.Word((1,) * (last + 1))
    u1 = sb.one_impact_family(1, E)
    hi_last = ones.members.hi.iloc[-1]
    assert not any(sb.sliding_word(E, float(u)) == nxt for u in np.linspace(hi_last, u1, 2000))


def test_the_accumulation_point_is_enclosed_and_named(ones):
    u1 = sb.one_impact_family(1, E)  # sqrt((1-e)/(2(1+e)))
    lo, hi, n = ones.limit_enclosure
    assert lo <= u1 <= hi and n >= 200
    assert "u_1" in ones.limit_name and ones.limit_curve == pytest.approx(u1, abs=1e-15)
    # the left edges approach u_1 like C/k (issue 39): k (u_1 - lo_k) nearly constant
    m = ones.members.set_index("k")
    c = [k * (u1 - m.lo[k]) for k in (8, 12, 16)]
    assert max(c) / min(c) < 1.15
    # the positions' own law, though the family ends: algebraic, exponent ~1, limit near u_1
    law = ones.law
    assert law.approach_kind == "algebraic" and 0.95 < law.approach < 1.05
    assert abs(law.limit - u1) < 1e-5 and lo <= law.limit <= hi


def test_the_law_of_an_adjacent_family_is_algebraic_with_its_limit_in_the_enclosure():
    c = sb.cascade("((1, 0)^k, 1, 1, 0^inf)", e=E, u=U_RANGE, k_max=40)
    m = c.members
    assert len(m) == 41 and np.all(np.diff(m.lo.values) < 0)  # k = 0..40, moving down in u
    # neighbours share their border: member k's upper edge is beside member k-1's lower one
    for a, b in zip(m.itertuples(), list(m.itertuples())[1:]):
        assert np.nextafter(b.hi, 1) == a.lo and b.hi_kind == "edge"
    assert c.law.kind == "algebraic" and 1.9 < c.law.exponent_interval[0] <= c.law.exponent_interval[1] < 2.1
    lo, hi, _ = c.limit_enclosure
    assert lo <= c.law.limit <= hi
    assert 0.9 < c.law.approach < 1.1  # positions approach like C/k


def test_a_cascade_along_e_at_fixed_u():
    c = sb.cascade("(1^k, 0^inf)", e=(0.0, 0.1), u=0.69, k_max=30)
    assert c.axis == "e" and len(c.members) >= 10
    for r in c.members.itertuples():
        w = sb.parse_word(r.word)
        assert sb.sliding_word(float(0.5 * (r.lo + r.hi)), 0.69) == w
        if r.hi_kind != "range":
            assert sb.sliding_word(float(np.nextafter(r.hi, 1)), 0.69) != w
    e1 = (1 - 2 * 0.69**2) / (1 + 2 * 0.69**2)  # u_1(e) = 0.69 solved for e
    lo, hi, _ = c.limit_enclosure
    assert lo <= e1 <= hi and "u_1" in c.limit_name


@pytest.mark.parametrize("kwargs, name", [
    (dict(e=0.02, u=0.7), "e and u"),
    (dict(e=(0.1, 0.2), u=(0.6, 0.7)), "e and u"),
    (dict(e=0.02, u=(0.7, 0.6)), "u must be a range"),
    (dict(e=1.2, u=(0.6, 0.7)), "e "),
    (dict(e=0.02, u=(0.6, 0.7), k_max=0), "k_max"),
    (dict(e=0.02, u=(0.6, 0.7), law_k=(3, 4)), "law_k"),
])
def test_bad_lines_are_refused_by_name(kwargs, name):
    with pytest.raises(ValueError, match=name):
        sb.cascade("(1^k, 0^inf)", **kwargs)


# --------------------------------------------------------------------------- #
# The law detector on maps whose laws are known in closed form                #
# --------------------------------------------------------------------------- #


def _escape_members(g, c, ks):
    """Intervals of initial points x > 0 that first reach x >= c after exactly k
    iterations of an increasing map g, each edge found by bisection on the
    escape time (monotone in x): lower edges, widths."""
    def escape(x):
        for n in range(1, 10**6):
            x = g(x)
            if x >= c:
                return n
        return 10**6

    def edge(k):  # the least x that escapes within k iterations
        lo, hi = 0.0, c
        while True:
            m = 0.5 * (lo + hi)
            if m in (lo, hi):
                return hi
            lo, hi = (lo, m) if escape(m) <= k else (m, hi)

    edges = np.array([edge(k) for k in [ks[0] - 1] + list(ks)])
    return edges[1:], edges[:-1] - edges[1:]


def test_the_law_detector_finds_a_geometric_cascade():
    # g(x) = lam x, a hyperbolic fixed point at 0 (multiplier lam): the points that
    # escape [0, 1) after exactly k steps form [lam^-k, lam^-(k-1)), widths lam^-k (lam-1):
    # ratio 1/lam, accumulating on 0 (closed form: g^k(x) = lam^k x)
    lam = 1.7
    ks = np.arange(3, 25)
    lo, w = _escape_members(lambda x: lam * x, 1.0, ks)
    np.testing.assert_allclose(lo, lam ** -ks.astype(float), rtol=1e-12)
    law = sb.cascade_law(ks, w, lo)
    assert law.kind == "geometric"
    assert law.ratio_interval[0] - 1e-9 <= 1 / lam <= law.ratio_interval[1] + 1e-9
    assert abs(law.limit) < 1e-9 and law.approach == pytest.approx(1 / lam, rel=1e-6)
    assert law.approach_kind == "geometric"


def test_the_law_detector_finds_an_algebraic_cascade():
    # g(x) = x / (1 - x), a neutral fixed point at 0 (multiplier 1): g^k(x) = x / (1 - k x)
    # in closed form, so the points that first pass c = 1/2 after k steps form
    # [1/(k+2), 1/(k+1)): widths 1/((k+1)(k+2)) ~ k^-2 (exponent 2), edges ~ 1/k -> 0
    ks = np.arange(20, 60)
    lo, w = _escape_members(lambda x: x / (1.0 - x), 0.5, ks)
    np.testing.assert_allclose(lo, 1.0 / (ks + 2.0), rtol=1e-12)
    law = sb.cascade_law(ks, w, lo)
    assert law.kind == "algebraic"
    assert 1.85 < law.exponent_interval[0] <= law.exponent_interval[1] < 2.05
    assert abs(law.limit) < 1e-3 and law.approach == pytest.approx(1.0, abs=0.1)
    assert law.approach_kind == "algebraic"


def test_the_law_detector_can_say_undecided():
    rng = np.random.default_rng(1)
    ks = np.arange(1, 13)
    noisy = np.exp(rng.normal(0.0, 1.0, ks.size))  # follows no law
    assert sb.cascade_law(ks, noisy).kind == "undecided"
    assert sb.cascade_law(ks[:3], noisy[:3]).kind == "undecided"  # too few members
    # a geometric sequence is not called algebraic, nor the reverse
    assert sb.cascade_law(ks + 30, 0.5 ** (ks + 30.0)).kind == "geometric"
    assert sb.cascade_law(ks + 30, (ks + 30.0) ** -2.5).kind == "algebraic"


@pytest.mark.parametrize("args, name", [
    (([1, 2, 3, 4], [1.0, 0.5, -0.1, 0.1]), "widths"),
    (([1, 2, 3], [1.0, 0.5]), "k and widths"),
    (([1, 3, 2, 4], [1.0, 0.5, 0.2, 0.1]), "k must be increasing"),
])
def test_bad_law_input_is_refused_by_name(args, name):
    with pytest.raises(ValueError, match=name):
        sb.cascade_law(*args)
    with pytest.raises(ValueError, match="threshold"):
        sb.cascade_law([1, 2, 3, 4], [1, 0.5, 0.25, 0.125], threshold=1.0)


# --------------------------------------------------------------------------- #
# Command line                                                                #
# --------------------------------------------------------------------------- #


def test_cli_prints_the_members_and_the_law(tmp_path, capsys, ones):
    code, out, err = _run(["cascade", "(1^k, 0^inf)", "--e", "0.02", "--u", "0.6:0.75", "--k-max", "40",
                           "--out", str(tmp_path / "c.csv")], capsys)
    assert code == 0, err
    assert f"{len(ones.members)} member(s)" in out and "law of the widths" in out and "u_1" in out
    assert "0.68617019528662504" in out  # member k = 2's upper edge, to 17 digits
    csv = pd.read_csv(tmp_path / "c.csv")
    np.testing.assert_array_equal(csv["lo"].values, ones.members.lo.values)
    assert csv["hi_kind"].tolist() == ones.members.hi_kind.tolist()


@pytest.mark.parametrize("args", [
    ["(1^k, 0)"],
    ["(1^k, 0^inf)", "--e", "1.5"],
    ["(1^k, 0^inf)", "--u", "0.6"],
    ["(1^k, 0^inf)", "--e", "0.1:0.2", "--u", "0.6:0.7"],
    ["(1^k, 0^inf)", "--law-k", "a:b"],
    ["(1^k, 0^inf)", "--out", "x.txt"],
])
def test_cli_bad_input_is_one_line_and_status_2(args, capsys):
    code, out, err = _run(["cascade", *args], capsys)
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err


# --------------------------------------------------------------------------- #
# Families found, and the member count against e                              #
# --------------------------------------------------------------------------- #


def test_cascades_finds_the_families_by_block_attachment():
    df = sb.cascades(e=E, u=(0.6795, 0.6925), samples=400, k_max=30)
    found = dict(zip(df.pattern, df.members))
    seen = dict(zip(df.pattern, df.seen))
    # every member on this piece of the line (k = 2..23), though 400 samples see fewer
    ones = sb.cascade("(1^k, 0^inf)", e=E, u=(0.6795, 0.6925), k_max=30).members
    assert ones.k.tolist() == list(range(2, 24))
    assert found.get("(1^k, 0^inf)") == 22 and seen["(1^k, 0^inf)"] < 22
    assert found.get("((1, 0)^k, 1, 1, 0^inf)") == 31  # k = 0..30: stops at k_max
    assert df.seen.le(df.members).all() and df.members.ge(4).all()
    row = df.set_index("pattern").loc["((1, 0)^k, 1, 1, 0^inf)"]
    assert row.law == "algebraic" and row.limit_lo < row.limit_hi
    # given words instead of samples: a family needs members among them
    assert sb.cascades(e=E, u=U_RANGE, words=["(1, 0^inf)", "(2, 0^inf)"]).empty
    with pytest.raises(ValueError, match="samples"):
        sb.cascades(e=E, u=U_RANGE, samples=1)


@pytest.mark.parametrize("e, n", [(0.0101, 49), (0.01004, 50), (0.0501, 10), (0.125, 4)])
def test_member_count_follows_the_measured_law_where_it_differs_from_one_over_2e(e, n):
    # measured (docs/guide/cascades.md): member k of (1^k, 0^inf) exists up to
    # e_k ~ 1/(2k - 1/2), so about floor(1/(2e) + 1/4) members; at these e that law
    # and floor(1/(2e)) disagree (except at 0.125, where e_4 = 0.1333 > 1/8)
    c = sb.cascade("(1^k, 0^inf)", e=e, u=(0.3, 0.7071), k_max=200)
    assert c.last == n == math.floor(1 / (2 * e) + 0.25)


# --------------------------------------------------------------------------- #
# Issue 39, items 3-5: windows, the Farey test, counts against e, centres      #
# --------------------------------------------------------------------------- #

from stairbounce.cascades.families import _level2  # noqa: E402
from stairbounce.cascades.farey import _increment  # noqa: E402


def test_families_of_families_are_grouped_by_one_free_count():
    # ((1^n, 0)^k, 1^(n+1), 0^inf) for n = 1..4, written out, and a stranger
    fams = [((), (1,) * n + (0,), (1,) * (n + 1)) for n in range(1, 5)] + [((), (1, 0), (2,))]
    out = _level2(fams)
    assert [(t, [n for n, _ in m]) for t, m, _ in out] == [("((1^n, 0)^k, 1^(n+1), 0^inf)", [1, 2, 3, 4])]
    # and makes the member family of any n, seen or not
    make = out[0][2]
    assert make(6) == ((), (1,) * 6 + (0,), (1,) * 7) and make(0) is None
    # two members are not a family of families
    assert _level2(fams[:2]) == []


def test_increment_recognises_one_more_block():
    assert _increment((1, 0, 1, 1), (1, 0, 1, 0, 1, 1))
    assert _increment((1, 1, 1), (1, 1))
    assert not _increment((1, 1), (1, 1, 0, 0, 1, 1))
    assert not _increment((1, 2), (2, 1))


def test_member_count_at_one_e_is_the_cascades_count():
    assert sb.member_count("(1^k, 0^inf)", 0.125, (0.3, 0.7071)) == 4 == \
        sb.cascade("(1^k, 0^inf)", e=0.125, u=(0.3, 0.7071), k_max=20).last


def test_member_count_over_e_bisects_each_change_to_adjacent_floats():
    df = sb.member_count("(1^k, 0^inf)", (0.12, 0.2), (0.3, 0.7071), n=4)
    assert df.k.tolist() == [4, 3] and not df.appears.any()
    assert (df.count_below - df.count_above).tolist() == [1, 1]
    for r in df.itertuples():
        assert r.e_above == np.nextafter(r.e_below, 1.0)
        # the cascade (its own bracketed search) agrees on both sides
        assert sb.cascade("(1^k, 0^inf)", e=r.e_below, u=(0.3, 0.7071), k_max=20).last == r.k
        assert sb.cascade("(1^k, 0^inf)", e=r.e_above, u=(0.3, 0.7071), k_max=20).last == r.k - 1
        # the measured law (docs/guide/cascades.md): 1/e_k = 2k - 1/2 + delta_k, 0 < delta_k < 0.01
        assert 0 < 1 / r.e_below - (2 * r.k - 0.5) < 0.01
    with pytest.raises(ValueError, match="u must be a range"):
        sb.member_count("(1^k, 0^inf)", 0.1, 0.6)


def test_farey_test_on_a_line_counts_pairs_with_exact_adjacency():
    ft = sb.farey_test(0.02, (0.686, 0.6875), samples=120, gap_samples=16)
    c, pairs = ft.counts, ft.pairs
    assert c["pairs"] == len(pairs) == c["mediant"] + c["other"] + c["adjacent"] > 5
    for r in pairs.itertuples():
        assert r.det == abs(r.p_a * r.q_b - r.p_b * r.q_a)
        if r.relation == "mediant":
            w = sb.parse_word(r.between)
            assert (len(w.letters), w.period) == (r.p_a + r.p_b, r.q_a + r.q_b)
        if r.relation == "adjacent":  # independent: nothing else on a grid between the two samples
            words = {str(sb.sliding_word(0.02, x)) for x in np.linspace(r.u_a, r.u_b, 32)}
            assert words <= {str(sb.parse_word(r.word_a)), str(sb.parse_word(r.word_b))}
    assert ("period adding" in ft.verdict) == (2 * c["mediant"] > c["pairs"])
    imp = sb.farey_test(0.02, (0.686, 0.6875), samples=120, gap_samples=0, label="impacts")
    assert (imp.pairs.p_a == pairs.p_a - 1).all()
    with pytest.raises(ValueError, match="label"):
        sb.farey_test(0.02, (0.686, 0.6875), label="steps")


def test_cli_counts_members_at_one_e_and_over_a_range(capsys):
    code, out, err = _run(["cascade", "(1^k, 0^inf)", "--count", "--e", "0.125", "--u", "0.3:0.7071"], capsys)
    assert code == 0, err
    assert out.startswith("4 member(s)") and "numerical" in out  # the count states its basis
    code, out, err = _run(["cascade", "(1^k, 0^inf)", "--count", "--e", "0.12:0.14", "--u", "0.3:0.7071",
                           "--n", "3"], capsys)
    assert code == 0, err
    assert "disappears  4 -> 3" in out and "1 change(s)" in out and "numerical" in out
    code, out, err = _run(["cascade", "(1^k, 0^inf)", "--count", "--e", "0.1", "--u", "0.6"], capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1


def test_a_windows_families_at_two_levels():
    # between the tongues 1 and 2 (docs/guide/cascades.md): ((1^n, 0)^k, 1^(n+1), 0^inf)
    # for n = 1, 2, ... is a family of families
    df = sb.cascades(e=(0.018, 0.022), u=(0.6790, 0.6905), resolution=32, lines=1, k_max=8)
    rows = df.set_index("pattern")
    one = rows.loc["((1, 0)^k, 1, 1, 0^inf)"]
    assert one.level == 1 and one.members == 9 and one.limit_lo < one.limit_hi  # k = 0..8 (k_max)
    two = rows.loc["((1^n, 0)^k, 1^(n+1), 0^inf)"]
    assert two.level == 2 and set(two.n_values) >= {1, 2}
    # its n = 1 member's accumulation is that family's
    assert one.limit_lo in [c[1] for c in two.limit_curve]
    assert (df.level.diff().fillna(0) >= 0).all()  # level 1 first
    with pytest.raises(ValueError, match="words"):
        sb.cascades(e=(0.018, 0.022), u=(0.679, 0.69), words=["(1, 0^inf)"])
    with pytest.raises(ValueError, match="resolution"):
        sb.cascades(e=(0.018, 0.022), u=(0.679, 0.69), resolution=2)


def test_a_members_tip_is_a_corner_of_its_region():
    # member 4 of (1^k, 0^inf) ends where its edge (step 3) and chatter (step 4) borders
    # cross; the line search (member_count, bisection on e) and the region's walk
    # (pseudo-arclength continuation, word_region) are independent ways to that point
    ch = sb.member_count("(1^k, 0^inf)", (0.12, 0.14), (0.3, 0.7071), n=2)
    e4 = float(ch.set_index("k").loc[4, "e_below"])
    m = sb.cascade("(1^k, 0^inf)", e=e4, u=(0.3, 0.7071), k_max=4).members.set_index("k").loc[4]
    region = sb.word_region("(1, 1, 1, 1, 0^inf)", e=(0.11, 0.14), u=(0.585, 0.61), resolution=48)
    oc = sb.organising_centres((0.11, 0.14), (0.585, 0.61), regions=[region], top=3)
    assert oc.attrs["corners"] == 1 and oc.events[0] == "edge 3; chatter 4"
    assert math.hypot(oc.e[0] - e4, oc.u[0] - m.lo) < 1e-9
    with pytest.raises(ValueError, match="top"):
        sb.organising_centres((0.11, 0.14), (0.585, 0.61), regions=[region], top=0)


# --------------------------------------------------------------------------- #
# Issue 46, item 4: the cascades as a package, its modules in layers           #
# --------------------------------------------------------------------------- #

CASCADE_LAYERS = ["patterns", "search", "laws", "members", "families", "farey"]


def test_the_cascade_modules_import_only_those_above_them():
    """Every relative import inside stairbounce/cascades/ (at any depth, late imports in
    functions included) names a module of an earlier layer: no circle, and the old
    cascades.py <-> cascade_families.py circle cannot come back."""
    import ast
    from pathlib import Path

    root = Path(sb.__file__).parent / "cascades"
    assert sorted(p.stem for p in root.glob("*.py")) == sorted(CASCADE_LAYERS + ["__init__"])
    for i, stem in enumerate(CASCADE_LAYERS):
        for node in ast.walk(ast.parse((root / f"{stem}.py").read_text())):
            if isinstance(node, ast.ImportFrom) and node.level == 1:
                assert node.module in CASCADE_LAYERS[:i], f"cascades/{stem}.py imports .{node.module}"
    assert not (root.parent / "cascade_families.py").exists() and not (root.parent / "cascades.py").exists()
