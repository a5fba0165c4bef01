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


# --------------------------------------------------------------------------- #
# Issue 45, item 2: cascade work bounded, estimated before it starts           #
# --------------------------------------------------------------------------- #


class _TookTooLong(Exception):
    pass


def _within(seconds, fn):
    """``fn()`` under an alarm: the old code ran these for minutes (round 4, R6);
    the refusals come from an estimate made before any search, in milliseconds."""
    import signal

    def alarm(*_):
        raise _TookTooLong(f"still running after {seconds} s")

    old = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        return fn()
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


@pytest.mark.parametrize("pattern, letters", [
    ("(" + "1^999999, " * 90 + "2^k, 0^inf)", 89999911),  # 900 characters, 9e7 letters (round 4)
    ("(1^600000, 1^600000, 2^k, 0^inf)", 1200001),  # each item under the cap, the pattern over it
    ("((1^600000, 1^600000), 2^k, 0^inf)", 1200000),  # a nested group over it
])
def test_the_letter_cap_is_on_the_whole_pattern(pattern, letters):
    with pytest.raises(ValueError, match=rf"pattern must write at most 1000000 letters in all.*got {letters}"):
        _within(10, lambda: sb.cascade(pattern, e=E, u=U_RANGE))


def test_a_pattern_at_the_letter_cap_is_read():
    pat = _parse_pattern("(1^999999, 1^k, 0^inf)")  # 999999 letters and the block: 10^6
    assert len(pat.prefix) == 999999 and pat.block == (1,)


@pytest.mark.parametrize("call, names", [
    (lambda: sb.cascade("((1^999)^999, 2^k, 0^inf)", e=E, u=U_RANGE), "k_max = 100"),
    (lambda: sb.member_count("((1^999)^999, 2^k, 0^inf)", E, U_RANGE), "k_max = 200"),
    (lambda: sb.member_count("(((1^99)^99)^99, 2^k, 0^inf)", E, U_RANGE), "k_max = 200"),
    (lambda: sb.member_count("(1^k, 0^inf)", (0.01, 0.05), U_RANGE, k_max=100, n=100000), "n = 100000"),
    (lambda: sb.member_count("(1^k, 0^inf)", (0.01, 0.05), U_RANGE, k_max=10**5, n=10**5), "k_max = 100000"),
    (lambda: sb.cascade("(9999999^k, 0^inf)", e=E, u=U_RANGE), "k_max = 100"),  # one letter, 1e7 steps
])
def test_work_above_the_limit_is_refused_before_it_starts(call, names):
    with pytest.raises(ValueError) as exc:
        _within(10, call)
    msg = str(exc.value)
    assert names in msg and "more than the limit 3e+07" in msg


def test_the_work_limit_of_a_cascade_is_the_k_max_it_names():
    """The refusal names the largest k_max within the limit; that k_max is accepted
    (the cascade ends long before, at k = 25), one more is not."""
    with pytest.raises(ValueError, match=r"lower k_max \(at most (\d+) here\)") as exc:
        sb.cascade("(1^k, 0^inf)", e=E, u=U_RANGE, k_max=10**6)
    k = int(exc.value.args[0].split("at most ")[1].split(" ")[0])
    # the estimate: 3 searches of every member (k steps for member k) and of 4 k_max limit steps
    assert 3 * (k * (k + 1) // 2 + 4 * k) <= 3 * 10**7 < 3 * ((k + 1) * (k + 2) // 2 + 4 * (k + 1))
    assert sb.cascade("(1^k, 0^inf)", e=E, u=U_RANGE, k_max=k).last == 25
    with pytest.raises(ValueError, match=f"k_max = {k + 1}"):
        sb.cascade("(1^k, 0^inf)", e=E, u=U_RANGE, k_max=k + 1)


def test_cli_refuses_a_count_over_the_limit_in_one_line(capsys):
    code, out, err = _within(10, lambda: _run(["cascade", "(1^k, 0^inf)", "--count", "--e", "0.01:0.05",
                                                "--u", "0.6:0.75", "--n", "100000"], capsys))
    assert code == 2 and len(err.strip().splitlines()) == 1 and "n = 100000" in err and "limit" in err


@pytest.mark.parametrize("pattern", ["(\u0661^k, 0^inf)", "(\uff11^k, 0^inf)", "(1^\u0663, 2^k, 0^inf)",
                                     "(1^k, \u0660^inf)"])
def test_digits_other_than_ascii_are_refused(pattern):
    with pytest.raises(ValueError, match="cannot read"):
        sb.cascade(pattern, e=E, u=U_RANGE)


def test_families_of_a_long_word_are_split_in_linear_time():
    """A word of 10^5 letters (round 4: past 120 s, the runs were counted before the
    block was tested) is split at once; one word is no family (min_members 4)."""
    df = _within(20, lambda: sb.cascades(E, U_RANGE, words=["(" + "1, " * 100000 + "0^inf)"]))
    assert len(df) == 0


def test_words_whose_decompositions_would_copy_too_much_are_refused():
    # 5000 runs 1, 1 in a word of 15000 letters: 5001 decompositions of 15000 letters each
    word = "(" + "1, 1, 0, " * 5000 + "1, 0^inf)"
    with pytest.raises(ValueError, match=r"words: .* more than the limit 5e\+07"):
        _within(10, lambda: sb.cascades(E, U_RANGE, words=[word]))


def test_candidate_families_over_the_work_limit_are_refused_before_any_search():
    # four members of (P, 1^k, 0^inf) with a prefix of 60000 letters (150000 steps): 3 searches of
    # 100 members, 4.5e7 steps
    prefix = "2, 3, " * 30000
    words = [f"({prefix}" + "1, " * m + "0^inf)" for m in (2, 3, 4, 5)]
    with pytest.raises(ValueError, match=r"candidate families with k_max = 100.*more than the limit"):
        _within(10, lambda: sb.cascades(E, U_RANGE, words=words))


# --------------------------------------------------------------------------- #
# Issue 43, item 4: asymptotic laws, intervals that cover the known truths     #
# --------------------------------------------------------------------------- #


@pytest.mark.parametrize("k_lo, k_hi", [(5, 12), (20, 59), (53, 60), (93, 100)])
def test_the_asymptotic_exponent_of_a_parabolic_accumulation_covers_2(k_lo, k_hi):
    """g(x) = x / (1 - x): widths 1/((k+1)(k+2)) exactly (closed form, the escape
    members located by bisection); the local exponents are 2 - 1/k + ..., every one
    below 2 (the old interval was their range: 1.983 [1.982, 1.984] on 53..60)."""
    ks = np.arange(k_lo, k_hi + 1)
    lo, w = _escape_members(lambda x: x / (1.0 - x), 0.5, ks)
    law = sb.cascade_law(ks, w, lo, tail=ks.size)
    assert law.kind == "algebraic"
    assert law.exponent_local[1] < 2  # the finite-k values exclude the truth ...
    assert law.exponent_interval[0] <= 2 <= law.exponent_interval[1]  # ... the extrapolation covers it
    assert law.exponent_interval[1] - law.exponent_interval[0] < (0.1 if k_lo < 20 else 0.01)
    # the positions 1/(k+2) accumulate on 0
    assert law.limit_interval[0] <= 0 <= law.limit_interval[1]


@pytest.mark.parametrize("r, a", [(0.6, 0.5), (0.3, -2.0), (0.9, 1.0)])
def test_the_asymptotic_ratio_of_a_geometric_law_with_corrections_covers_it(r, a):
    # w_k = r^k (1 + a/k): local ratios r (1 + a/(k+1)) / (1 + a/k) -> r like 1/k^2
    ks = np.arange(5, 13).astype(float)
    w = r**ks * (1 + a / ks)
    law = sb.cascade_law(ks, w, 1 - np.cumsum(w), tail=ks.size)
    assert law.kind == "geometric"
    assert not law.ratio_local[0] <= r <= law.ratio_local[1]
    assert law.ratio_interval[0] <= r <= law.ratio_interval[1]
    # the positions 1 - sum w accumulate on 1 - sum over all k (closed form: a geometric tail
    # and a / k r^k summed, -log(1 - r) a)
    tail = r**5 / (1 - r) + a * (-math.log(1 - r) - sum(r**j / j for j in range(1, 5)))
    assert law.limit_interval[0] <= 1 - tail <= law.limit_interval[1]


def test_the_geometric_map_ratio_is_covered():
    lam = 1.7
    ks = np.arange(3, 25)
    lo, w = _escape_members(lambda x: lam * x, 1.0, ks)
    law = sb.cascade_law(ks, w, lo)
    assert law.ratio_interval[0] <= 1 / lam <= law.ratio_interval[1]
    assert law.ratio_interval[1] - law.ratio_interval[0] < 1e-6


@pytest.mark.parametrize("law_k", [None, (5, 12), (10, 20)])
def test_the_extrapolated_limit_of_ones_contains_u1(law_k):
    """(1^k, 0^inf) at e = 0.02 accumulates on the neutral one-impact family
    u_1 = sqrt((1 - e) / (2 (1 + e))) (sb.one_impact_family: the orbit landing once per
    step forever, the limit itinerary 1, 1, 1, ...; the enclosure, exact to rounding,
    contains it, and cascade names it).  The old interval [0.69310377, 0.69310426]
    (default law_k) excluded it."""
    c = sb.cascade("(1^k, 0^inf)", e=E, u=U_RANGE, law_k=law_k)
    u1 = sb.one_impact_family(1, E)
    assert u1 == pytest.approx(math.sqrt((1 - E) / (2 * (1 + E))), rel=1e-15)
    lo, hi, _ = c.limit_enclosure
    assert lo <= u1 <= hi and c.limit_name.startswith("neutral one-impact family u_1")
    a, b = c.law.limit_interval
    assert a <= u1 <= b and b - a < 2e-7
    assert not (min(c.law.limit_local, a) <= u1 <= max(c.law.limit_local, a) and c.law.limit_local == a)


def test_the_text_names_the_extrapolation_and_the_enclosure():
    c = sb.cascade("(1^k, 0^inf)", e=E, u=U_RANGE)
    text = c.text()
    assert "accumulation (extrapolation, numerical, not an enclosure" in text
    assert "accumulation (enclosure to rounding, numerical" in text
    law = sb.cascade_law(np.arange(53, 61), 1.0 / (np.arange(53, 61) * np.arange(54, 62.0)))
    lo, hi = law.exponent_interval
    assert lo <= 2 <= hi
    assert f"exponent -> {law.exponent:.6g} in [{lo:.6g}, {hi:.6g}] (extrapolated to k -> inf, numerical)" in law.text()
    assert "local exponents [1.98" in law.text()


# --------------------------------------------------------------------------- #
# Issue 43, item 4: the members proven (cascade --prove, Cascade.prove)        #
# --------------------------------------------------------------------------- #


def test_prove_proves_each_member_on_a_segment_inside_its_float_interval():
    c = sb.cascade("(1^k, 0^inf)", e=E, u=U_RANGE, k_max=8)
    proofs = c.prove()
    assert proofs.k.tolist() == c.members.k.tolist() and proofs.proven.all()
    for p, m in zip(proofs.itertuples(), c.members.itertuples()):
        assert m.lo <= p.lo < p.hi <= m.hi and 0.8 <= p.share <= 1.0
        assert p.share == pytest.approx((p.hi - p.lo) / m.width)
        # the proven segment's own certificate, and the float map inside it, give the word
        cert = sb.certify_box(e=(E, E), u=(p.lo, p.hi), max_iter=m.period + 1)
        assert cert.status == "word" and cert.word == sb.parse_word(m.word)
        assert sb.sliding_word(E, 0.5 * (p.lo + p.hi)) == sb.parse_word(m.word)


def test_prove_says_when_a_member_is_not_proven():
    c = sb.cascade("(1^k, 0^inf)", e=E, u=U_RANGE, k_max=6)
    proofs = c.prove(ks=[5, 6], max_iter=2)  # periods 5 and 6: two steps decide nothing
    assert proofs.k.tolist() == [5, 6] and not proofs.proven.any()
    assert (proofs.status == "no_slide_within").all() and proofs.lo.isna().all() and (proofs.share == 0).all()


def test_cli_prove_lists_the_proven_members(tmp_path, capsys):
    code, out, err = _run(["cascade", "(1^k, 0^inf)", "--e", "0.02", "--u", "0.6:0.75", "--k-max", "6",
                           "--prove", "--out", str(tmp_path / "c.csv")], capsys)
    assert code == 0, err
    assert "basis: numerical, to rounding" in out
    assert "proven members (basis: proven, sb.certify_box" in out
    assert "6 of 6 member(s) proven" in out
    csv = pd.read_csv(tmp_path / "c.csv")
    assert csv.proven.all() and (csv.proven_lo >= csv.lo).all() and (csv.proven_hi <= csv.hi).all()


@pytest.mark.parametrize("k_max", [100, 200])
def test_an_infinite_family_accumulating_on_u1_has_both_truths_covered(k_max):
    """(1^k, 2, 0^inf) at e = 0.02 continues up to k_max; its widths are C/k^2 to leading
    order and it accumulates on u_1 (the limit itinerary 1, 1, 1, ...; named by cascade
    from the enclosure).  Eight members at k ~ 200 alone span too little of 1/k: their
    extrapolation excluded 2 and u_1 before it used the members from k_max/2 on."""
    c = sb.cascade("(1^k, 2, 0^inf)", e=E, u=U_RANGE, k_max=k_max)
    assert c.last == k_max and c.law.kind == "algebraic"
    lo, hi = c.law.exponent_interval
    assert lo <= 2 <= hi and hi - lo < 1e-3
    u1 = sb.one_impact_family(1, E)
    a, b = c.law.limit_interval
    assert a <= u1 <= b and c.limit_enclosure[0] <= a <= b <= c.limit_enclosure[1]
    assert "u_1" in c.limit_name
