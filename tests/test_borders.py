"""Borders of the (e, u) plane located to rounding (stairbounce.structure.borders, issue 21).

Independent references: the map of ``model._step`` (``model.iterate``), the
impact-by-impact loop of ``tests/naive.py`` and the analytic curves of
Theorem 3.1 and Corollary 2.1.
"""

import math

import numpy as np
import pytest

import stairbounce as sb
from stairbounce import model, structure
from stairbounce.structure import borders

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
            assert structure.itinerary._margin(e, u, j, structure.itinerary.EDGE, k, 1.0, 0.0, empty) >= 0.0
            assert structure.itinerary._margin(e, u, j, structure.itinerary.EDGE, k + 1, 1.0, 0.0, empty) == nx
        assert structure.itinerary._margin(e, u, j, structure.itinerary.GRAZE, 1, 1.0, 0.0, empty) == c
        assert structure.itinerary._margin(e, u, j, structure.itinerary.CHATTER, 0, 1.0, 0.0, empty) == a


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
    assert not math.isnan(structure.itinerary._margin(e, u, n, structure.itinerary.CHATTER, 0, 1.0, 0.0, prefix))
    assert structure.itinerary._margin(e, u, n, structure.itinerary.CHATTER, 0, 1.0, 0.0, prefix) >= 0.0
    assert math.isnan(structure.itinerary._margin(e, u, n + 1, structure.itinerary.CHATTER, 0, 1.0, 0.0, prefix))
    if n > 1:
        wrong = prefix.copy()
        wrong[0] = wrong[0] + 1
        assert math.isnan(structure.itinerary._margin(e, u, n, structure.itinerary.CHATTER, 0, 1.0, 0.0, wrong))


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


# --------------------------------------------------------------------------- #
# border_points                                                               #
# --------------------------------------------------------------------------- #

SMALL = {"e": (0.0, 1.0, 60), "u": (0.0, 1.5, 50)}
# a window with many words (the paper's Fig. 5a) and one across the tongues n = 1..8
FIG5A = {"e": (0.0, 0.3, 40), "u": (0.3, 0.7, 40)}
TONGUES = {"e": (0.0, 0.25, 50), "u": (0.05, 2.05, 200)}


@pytest.fixture(scope="module")
def small():
    return sb.border_points(**SMALL)


@pytest.fixture(scope="module")
def fig5a():
    return sb.border_points(**FIG5A)


@pytest.fixture(scope="module")
def tongues():
    return sb.border_points(**TONGUES, max_iter=200)


def _word(e, u, max_iter=1000):
    w = sb.sliding_word(e, u, max_iter)
    return w.format(ascii=True) if w else structure.words.NONE_WORD


def test_pairs_are_exactly_those_with_different_words(small):
    # brute force: the word of every pixel centre by sliding_word, pairs compared whole
    es = sb.pixel_centres(*SMALL["e"])
    us = sb.pixel_centres(*SMALL["u"])
    W = [[sb.sliding_word(e, u) for e in es] for u in us]
    expect = set()
    for i in range(us.size):
        for j in range(es.size):
            if j + 1 < es.size and W[i][j] != W[i][j + 1]:
                expect.add((i, j, "e"))
            if i + 1 < us.size and W[i][j] != W[i + 1][j]:
                expect.add((i, j, "u"))
    got = set(zip(small.i_u.values.tolist(), small.i_e.values.tolist(), small.axis.values.tolist()))
    assert got == expect and len(expect) > 100


def _sides(pt):
    """(e, u) of the bracket's low and high ends."""
    e, u, w = float(pt.e), float(pt.u), float(pt.width)
    if pt.axis.item() == "e":
        return (e, u), (e + w, u)
    return (e, u), (e, u + w)


def _check_point(pt, max_iter):
    (el, ul), (eh, uh) = _sides(pt)
    j = int(pt.step)
    kind = pt.kind.item()
    # located to rounding: no float strictly inside the bracket
    x = el if pt.axis.item() == "e" else ul
    assert 0.0 < float(pt.width) and np.nextafter(x, np.inf) == x + float(pt.width)
    # the pair of sides by model._step (model.iterate), not by the bisection kernel
    ys_l, vs_l, k_l = model.iterate(1.0, 0.0, el, ul, j)
    ys_h, vs_h, k_h = model.iterate(1.0, 0.0, eh, uh, j)
    assert np.array_equal(k_l[1:j], k_h[1:j]) and model.SLIDING not in k_l[1:j]
    assert (k_l[j], k_h[j]) == (int(pt.impacts_low), int(pt.impacts_high))
    pair = sorted((int(k_l[j]), int(k_h[j])))
    if kind == "graze":
        assert pair == [0, 1] and int(pt.index) == 1
    elif kind == "edge":
        assert pair == [int(pt.index) - 1, int(pt.index)] and pair[0] >= 1
    else:
        assert kind == "chatter" and pair[0] == model.SLIDING and pair[1] >= 0
    # the words on each side, by sliding_word
    assert _word(el, ul, max_iter) == pt.word_low.item()
    assert _word(eh, uh, max_iter) == pt.word_high.item()
    assert bool(pt.sliding_border) == (structure.words.NONE_WORD in (pt.word_low.item(), pt.word_high.item()))
    assert pt.word_low.item() != pt.word_high.item()
    # the impact-by-impact loop of tests/naive.py: same impact numbers before
    # step j, and at step j the labelled event's time equals T = 1/u to rounding
    y, v = 1.0, 0.0
    for i in range(1, j):
        y, v, k = naive.step(y, v, el, ul)
        if k == model.SLIDING and k_l[i] > 0 and el ** (k_l[i] - 1) <= 10 * naive.REST:
            return  # bounces below naive.REST: the loop cannot follow this orbit on
        assert k == k_l[i]
    T = 1.0 / ul
    speed = math.sqrt(v * v + 2.0 * y)
    if kind == "graze":
        t = v + speed
    elif kind == "edge":
        t, w = v + speed, el * speed
        for _ in range(int(pt.index) - 1):
            t, w = t + 2.0 * w, el * w
    else:
        t = naive.accumulation_time(y, v, el)
    assert abs(t - T) <= 1e-9 * T
    kn = {naive.step(y, v, el, ul)[2], naive.step(y, v, eh, uh)[2]}
    if kind == "graze":
        assert kn <= {0, 1}
    elif kind == "edge":
        # naive.step calls bounces below naive.REST times the impact speed a slide
        if el ** (int(pt.index) - 1) <= 10 * naive.REST:
            kn.discard(model.SLIDING)
        assert kn <= {int(pt.index) - 1, int(pt.index)}


@pytest.mark.parametrize("which", ["small", "fig5a", "tongues"])
def test_every_label_checked_independently(which, request):
    pts = request.getfixturevalue(which)
    max_iter = int(pts.attrs["max_iter"])
    assert pts.sizes["point"] > 50
    for i in range(pts.sizes["point"]):
        _check_point(pts.isel(point=i), max_iter)
    # every kind occurs
    assert set(pts.kind.values) == {"graze", "edge", "chatter"} or which == "tongues"


def test_theorem_3_1_tongue_borders(tongues):
    # Theorem 3.1: word (n) iff (n-1)/2 < u^2 <= n/2 ((1-e)/(1+e))^2; its border is the
    # graze curve (lower, step n-1) and the chatter curve (upper, step n)
    seen = set()
    for n in range(1, 9):
        word = f"({n}, 0^inf)"
        sel = (tongues.word_low.values == word) | (tongues.word_high.values == word)
        assert sel.sum() > 0, n
        for i in np.flatnonzero(sel):
            pt = tongues.isel(point=int(i))
            e, u = float(pt.e), float(pt.u)
            if pt.kind.item() == "graze":
                assert int(pt.step) == n - 1 and pt.axis.item() == "u"
                assert abs(u * u - (n - 1) / 2) <= 1e-14 * (n - 1) / 2
                # the graze side is below: the low side lands on step n - 1
                assert pt.word_high.item() == word
            else:
                assert pt.kind.item() == "chatter" and int(pt.step) == n
                c = n / 2 * ((1 - e) / (1 + e)) ** 2
                # the bracket's low end; on the u axis the high end is above the curve
                if pt.axis.item() == "u":
                    assert abs(u * u - c) <= 1e-14 * c
                    assert pt.word_low.item() == word
                else:
                    eh = e + float(pt.width)
                    ch = n / 2 * ((1 - eh) / (1 + eh)) ** 2
                    assert min(abs(u * u - c), abs(u * u - ch)) <= 1e-14 * c
                # left of the tip e_n where the two curves meet (Corollary 2.1)
                tip = (math.sqrt(n) - math.sqrt(n - 1)) ** 2
                assert e <= tip
            seen.add((n, pt.kind.item()))
    assert {(n, "chatter") for n in range(1, 9)} <= seen
    assert {(n, "graze") for n in range(2, 9)} <= seen


def test_no_border_above_corollary_2_1():
    pts = sb.border_points(e=(0.0, 1.0, 120), u=(0.0, 1.5, 100))
    e, u = pts.e.values, pts.u.values
    with np.errstate(divide="ignore"):
        bound = (1.0 - e) / (2.0 * np.sqrt(2.0 * e))
    assert pts.sliding_border.values.sum() > 100
    assert not np.any(u > bound)


def test_threads_and_tiles_change_nothing(fig5a):
    import numba

    threads = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = sb.border_points(**FIG5A)
    finally:
        numba.set_num_threads(threads)
    assert one.identical(fig5a)
    # from the scan Dataset, and from tiles cut out of it (overlapping by one
    # row or column so that every pair lies inside some tile)
    ds = sb.scan(**FIG5A)
    assert sb.border_points(ds).identical(fig5a)
    rows = []
    for us, es in [(slice(0, 21), slice(0, 16)), (slice(20, None), slice(0, 16)),
                   (slice(0, 21), slice(15, None)), (slice(20, None), slice(15, None))]:
        t = sb.border_points(ds.isel(u=us, e=es)).to_dataframe()
        rows.append(t.drop(columns=["i_e", "i_u"]))
    import pandas as pd

    tiles = pd.concat(rows).drop_duplicates().sort_values(["u", "e", "axis"]).reset_index(drop=True)
    whole = fig5a.to_dataframe().drop(columns=["i_e", "i_u"]).sort_values(["u", "e", "axis"])
    pd.testing.assert_frame_equal(tiles, whole.reset_index(drop=True), check_dtype=False)


def test_word_text_is_the_symbolic_convention():
    from stairbounce.symbolic import word_from_impacts

    for ks in ([-1], [0, 0, -1], [2, 0, 1, 3, -1], [0, 1, 0, 4, 0, -1]):
        a = np.array(ks, np.int64)
        assert structure.words._word_text(a) == word_from_impacts(a).format(ascii=True)


def test_progress_is_called_and_changes_nothing(small):
    calls = []
    got = sb.border_points(**SMALL, progress=lambda d, t: calls.append((d, t)))
    assert got.identical(small)
    assert calls[0] == (0, SMALL["u"][2]) and calls[-1][0] == calls[-1][1] and len(calls) > 10


@pytest.mark.parametrize("kw,name", [
    ({"e": (0.0, 1.1, 10)}, "e window"), ({"u": (-1.0, 1.0, 10)}, "u window"),
    ({"e": (0.0, 1.0, 0)}, "n_e"), ({"max_iter": 0}, "max_iter"), ({"e": "x"}, "e must"),
    ({"progress": 3}, "progress"),
])
def test_border_points_bad_input(kw, name):
    with pytest.raises(ValueError, match=name):
        sb.border_points(**{**SMALL, **kw})


def test_border_points_refuses_a_scan_it_cannot_use():
    ds = sb.scan(e=(0.0, 1.0, 10), u=(0.0, 1.5, 10), y0=2.0)
    with pytest.raises(ValueError, match="y0, v0"):
        sb.border_points(ds)
    ds = sb.scan(e=(0.0, 1.0, 10), u=(0.0, 1.5, 10))
    ds["status"][0, 0] = 255
    with pytest.raises(ValueError, match="status"):
        sb.border_points(ds)
    with pytest.raises(ValueError, match="status"):
        sb.border_points(ds.drop_vars("status"))


def test_a_set_halt_flag_stops_the_kernel_before_any_pair():
    ds = sb.scan(**SMALL)
    es, us, period, max_iter = borders._grid_input(ds)
    a, b, axis = borders._pairs(period, us.size, es.size)
    found = np.zeros(a.size, np.bool_)
    out = np.full((a.size, borders._OUT), 7.0)
    borders._border_kernel(es, us, period, a, b, axis, max_iter, int(period.max()),
                           borders._WORD_BISECT, found, out, np.ones(1, np.int64))
    assert not found.any() and (out == 7.0).all()
    borders._border_kernel(es, us, period, a, b, axis, max_iter, int(period.max()),
                           borders._WORD_BISECT, found, out, np.zeros(1, np.int64))
    assert found.sum() == sb.border_points(ds).sizes["point"]


def test_secant_placement_finds_the_same_events_as_plain_bisection():
    # the secant only places the trial points; every trial is decided by the
    # exact outcome test, so both end on the same event curve, to rounding
    ds = sb.scan(**FIG5A)
    es, us, period, max_iter = borders._grid_input(ds)
    a, b, axis = borders._pairs(period, us.size, es.size)
    f1, o1 = borders._run_pairs(es, us, period, a, b, axis, max_iter, None, secant=True)
    f2, o2 = borders._run_pairs(es, us, period, a, b, axis, max_iter, None, secant=False)
    assert np.array_equal(f1, f2) and f1.sum() > 100
    o1, o2 = o1[f1], o2[f1]
    np.testing.assert_array_equal(o1[:, 2:6], o2[:, 2:6])  # step, kind, index, low impacts
    np.testing.assert_allclose(o1[:, 0], o2[:, 0], rtol=1e-14, atol=0)
    plain = borders._table(es, us, a[f1], axis[f1], o2, max_iter, {})
    for i in range(0, plain.sizes["point"], 7):
        _check_point(plain.isel(point=i), max_iter)


# --------------------------------------------------------------------------- #
# word_table                                                                  #
# --------------------------------------------------------------------------- #


def test_word_table_against_sliding_word(fig5a):
    tab = sb.word_table(**FIG5A, points=fig5a)
    es = sb.pixel_centres(*FIG5A["e"])
    us = sb.pixel_centres(*FIG5A["u"])
    pixels = {}
    for u in us:
        for e in es:
            w = sb.sliding_word(e, u)
            if w is not None:
                pixels.setdefault(w.format(ascii=True), []).append((e, u))
    assert sorted(tab.text.values.tolist()) == sorted(pixels)
    assert tab.attrs["pixels"] == es.size * us.size
    assert tab.attrs["sliding_pixels"] == sum(len(v) for v in pixels.values())
    # most pixels first
    assert np.all(np.diff(tab.pixels.values) <= 0)
    for i in range(tab.sizes["word"]):
        row = tab.isel(word=i)
        text = row.text.item()
        pts = np.array(pixels[text])
        w = sb.parse_word(text)
        assert (int(row.letters), int(row.period), int(row.impacts)) == (len(w), w.period, w.impacts)
        assert int(row.pixels) == len(pts)
        assert float(row.area_fraction) == len(pts) / (es.size * us.size)
        assert (float(row.e_min), float(row.e_max)) == (pts[:, 0].min(), pts[:, 0].max())
        assert (float(row.u_min), float(row.u_max)) == (pts[:, 1].min(), pts[:, 1].max())
        assert sb.sliding_word(float(row.e_rep), float(row.u_rep)).format(ascii=True) == text
        for kind in structure.itinerary.KINDS:
            on = (fig5a.kind.values == kind)
            n = np.sum(on & (fig5a.word_low.values == text)) + np.sum(on & (fig5a.word_high.values == text))
            assert int(row[kind]) == n
    # N(p): distinct words by period
    periods = [sb.parse_word(t).period for t in pixels]
    for p, n in zip(tab.p.values, tab.distinct_words.values):
        assert periods.count(int(p)) == int(n)
    assert sum(tab.distinct_words.values) == len(pixels)


def test_word_table_computes_its_points_and_takes_a_scan():
    tab = sb.word_table(**SMALL)
    again = sb.word_table(sb.scan(**SMALL), points=sb.border_points(**SMALL))
    assert tab.identical(again)
    # Theorem 3.1: the tongue words are there
    assert {"(1, 0^inf)", "(2, 0^inf)", "(3, 0^inf)"} <= set(tab.text.values)
    with pytest.raises(ValueError, match="points"):
        sb.word_table(**SMALL, points=sb.scan(**SMALL))
    with pytest.raises(ValueError, match="n_u"):
        sb.word_table(e=(0.0, 1.0, 5), u=(0.0, 1.0, -1))


def test_word_groups_fall_back_to_whole_rows_on_a_hash_collision(monkeypatch):
    E, U = np.meshgrid(sb.pixel_centres(*FIG5A["e"]), sb.pixel_centres(*FIG5A["u"]))
    ds = sb.scan(**FIG5A)
    period = np.where(ds.status.values == 0, ds.period.values, 0).ravel()
    ids, rows = structure.words._word_groups(E.ravel(), U.ravel(), period)
    monkeypatch.setattr(structure.words, "_rows_equal", lambda *a: False)
    ids2, rows2 = structure.words._word_groups(E.ravel(), U.ravel(), period)
    texts = np.array([structure.words._word_text(r) for r in rows] + [structure.words.NONE_WORD], dtype=object)
    texts2 = np.array([structure.words._word_text(r) for r in rows2] + [structure.words.NONE_WORD], dtype=object)
    assert np.array_equal(texts[ids], texts2[ids2]) and len(rows) == len(rows2) > 20


def test_outcome_sliding_bisects_the_crossings_of_the_sliding_region():
    ds = sb.scan(**FIG5A)
    pts = sb.border_points(ds, outcome="sliding")
    s = ds.status.values
    crossings = int((s[:, 1:] != s[:, :-1]).sum() + (s[1:, :] != s[:-1, :]).sum())
    assert pts.sizes["point"] == crossings > 50
    assert pts.sliding_border.values.all() and pts.sliding_pair.values.all()
    assert pts.attrs["outcome"] == "sliding"
    for i in range(pts.sizes["point"]):
        _check_point(pts.isel(point=i), 1000)
    # with the word as the outcome the same pairs are flagged, but may end on another word's border
    words = sb.border_points(ds)
    assert words.sliding_pair.values.sum() == crossings
    assert words.sliding_border.values.sum() <= crossings
    with pytest.raises(ValueError, match="outcome"):
        sb.border_points(ds, outcome="status")


@pytest.mark.parametrize("lanes_min", [0, 200, 10**9])
def test_sliding_rounds_on_the_scan_kernel_give_the_per_pair_rows(monkeypatch, lanes_min):
    # outcome="sliding" halves every bracket in a round and decides the
    # midpoints with the scan's kernel (lanes in lockstep, pruning; a round
    # with fewer than _ROUND_LANES_MIN midpoints one orbit per point); the
    # per-pair kernel decides each by _slide_period (model._step from (1, 0)):
    # the same brackets, trial and step counts, bit for bit (lanes_min 200:
    # lanes while 200 or more brackets are open, of FIG5A's 209)
    monkeypatch.setattr(borders, "_ROUND_LANES_MIN", lanes_min)
    monkeypatch.setattr(borders, "_ROUND_UNIT_MIN", 64)  # several units, both threads
    for win in (SMALL, FIG5A, {"e": (0.04, 0.065, 24), "u": (0.92, 0.945, 24)}):
        ds = sb.scan(**win)
        es, us, period, max_iter = borders._grid_input(ds)
        a, b, axis = borders._pairs(period, us.size, es.size, sliding=True)
        f1, o1 = borders._run_pairs(es, us, period, a, b, axis, max_iter, None, sliding=True,
                                    lanes=False)
        calls = []
        f2, o2 = borders._sliding_rounds(es, us, period, a, b, axis, max_iter,
                                         lambda d, t: calls.append((d, t)))
        assert f1.sum() > 20 and np.array_equal(f1, f2) and np.array_equal(o1, o2)
        done = [d for d, _ in calls]
        assert done[0] == 0 and done == sorted(done) and done[-1] == calls[-1][1] > 40
        assert len({t for _, t in calls}) == 1
    # border_points takes the rounds from _ROUND_LANES_MIN crossings (80 here)
    got = sb.border_points(ds, outcome="sliding")
    monkeypatch.setattr(borders, "_ROUND_LANES_MIN", 10**9)
    assert got.identical(sb.border_points(ds, outcome="sliding")) and got.sizes["point"] == f1.sum()
    # the last stage reads the halt flag: set, it writes no row
    out = np.full((a.size, borders._OUT), 7.0)
    z = np.zeros(a.size, np.int64)
    x = np.full(a.size, 0.5)
    borders._finish_sliding(x, x, x, z, z + 1, z, z, f1, out, np.ones(1, np.int64))
    assert (out == 7.0).all()


def test_no_border_of_the_sliding_region_above_corollary_2_1():
    # Corollary 2.1: above u = (1-e)/(2 sqrt(2e)) nothing slides, so the sliding region's
    # border (its crossings, bisected to rounding) lies on or below the curve
    pts = sb.border_points(e=(0.0, 1.0, 120), u=(0.0, 1.5, 100), outcome="sliding")
    e, u = pts.e.values, pts.u.values + np.where(pts.axis.values == "u", pts.width.values, 0.0)
    with np.errstate(divide="ignore"):
        bound = (1.0 - e) / (2.0 * np.sqrt(2.0 * e))
    assert pts.sizes["point"] > 100
    assert not np.any(pts.u.values > bound)
    # and the sliding side of every point is at or below it too
    assert not np.any(np.minimum(u, pts.u.values) > bound)


# --------------------------------------------------------------------------- #
# bifurcations                                                                #
# --------------------------------------------------------------------------- #


@pytest.fixture(scope="module")
def fig8_bifurcations():
    # the paper's Fig. 8: e = 0.001, u swept, from (0.1, 0), iterates 2000..2200
    return sb.bifurcations(0.001, np.linspace(0.3, 2.0, 600))


def test_bifurcations_at_the_tongue_borders_of_theorem_3_1(fig8_bifurcations):
    b = fig8_bifurcations
    e = 0.001
    for n in range(1, 6):
        word = f"({n}, 0^inf)"
        upper = math.sqrt(n / 2) * (1 - e) / (1 + e)
        sel = (b.itinerary_low.values == word) & (b.kind.values == "chatter")
        assert sel.sum() == 1, n
        assert abs(float(b.value[sel][0]) - upper) <= 1e-14 * upper
        if n >= 2:
            lower = math.sqrt((n - 1) / 2)
            sel = (b.itinerary_high.values == word) & (b.kind.values == "graze")
            assert sel.sum() == 1, n
            assert abs(float(b.value[sel][0]) - lower) <= 1e-14 * lower


def test_every_bifurcation_label_checked_with_model_step(fig8_bifurcations):
    b = fig8_bifurcations
    assert b.sizes["bifurcation"] > 20
    for i in range(b.sizes["bifurcation"]):
        pt = b.isel(bifurcation=i)
        lo = float(pt.value)
        hi = lo + float(pt.width)
        assert np.nextafter(lo, np.inf) == hi
        j = int(pt.step)
        _, _, kl = model.iterate(0.1, 0.0, 0.001, lo, j)
        _, _, kh = model.iterate(0.1, 0.0, 0.001, hi, j)
        assert np.array_equal(kl[1:j], kh[1:j])
        assert (kl[j], kh[j]) == (int(pt.impacts_low), int(pt.impacts_high))
        pair = sorted((int(kl[j]), int(kh[j])))
        kind = pt.kind.item()
        if kind == "graze":
            assert pair == [0, 1]
        elif kind == "edge":
            # impacts k+1 .. index land within rounding of the edge only where their
            # bounces (e^k times the impact speed) are below the ulp: e = 0.001, k >= 5
            assert pair[1] == int(pt.index) and pair[0] >= 1
            assert pair[1] - pair[0] == 1 or 0.001 ** pair[0] < 1e-14
        else:
            assert pair[0] == model.SLIDING and pair[1] >= 0
        assert pt.itinerary_low.item() != pt.itinerary_high.item()


def test_long_run_itinerary_is_a_pattern_up_to_its_phase():
    buf = np.zeros(40, np.int64)
    halt = np.zeros(1, np.int64)
    # inside tongue 3 the long run is the word (3, 0^inf): two flights and a slide
    lo, hi = sb.tongue(3, 0.001)
    p = structure.bifurcations._long_run(0.001, 0.5 * (lo + hi), 0.1, 0.0, 100, 20, buf, halt)
    assert p == 3 and list(buf[:3]) == [-1, 0, 0]
    assert structure.bifurcations._run_text(p, buf) == "(3, 0^inf)"
    assert structure.bifurcations._run_text(0, buf) == "not periodic within keep"


@pytest.mark.parametrize("kw,name", [
    ({"e": 0.1, "u": 0.5}, "exactly one"), ({"e": [0.1, 0.2], "u": [0.5, 0.6]}, "exactly one"),
    ({"e": 0.1, "u": [0.5, -1.0]}, "u"), ({"e": 1.5, "u": [0.5, 0.6]}, "e"),
    ({"e": 0.1, "u": [0.5, 0.6], "keep": 1}, "keep"), ({"e": 0.1, "u": [0.5, 0.6], "transient": -1}, "transient"),
    ({"e": 0.1, "u": [0.5, 0.6], "y0": -1.0}, "y0"),
])
def test_bifurcations_bad_input(kw, name):
    with pytest.raises(ValueError, match=name):
        sb.bifurcations(**kw)


def test_report_measures_on_known_answers():
    # the tongue window at a coarse grid: every (n, 0^inf) border point within 1e-14
    (e0, e1), (u0, u1) = structure.checks.TONGUE_WINDOW
    pts = sb.border_points(e=(e0, e1, 30), u=(u0, u1, 120), max_iter=200)
    t = structure.checks.tongue_distances(pts)
    assert t["points"] > 30 and t["wrong_kind"] == 0 and t["max_relative"] <= 1e-14
    assert t["kinds"][1] == {"chatter"} and t["kinds"][5] == {"graze", "chatter"}
    # a point moved off its curve by 1e-9 is measured as such
    moved = pts.copy(deep=True)
    i = int(np.flatnonzero(moved.word_low.values == "(3, 0^inf)")[0])
    moved["u"].values[i] *= 1 + 1e-9
    assert structure.checks.tongue_distances(moved)["max_relative"] > 5e-10
    assert structure.checks.above_no_sliding_curve(pts) == 0
    moved["u"].values[i] = 10.0
    assert structure.checks.above_no_sliding_curve(moved) == 1
    ds = sb.scan(**FIG5A)
    share, near = structure.checks.side_agreement(sb.border_points(ds), ds)
    assert near > 100 and 0.8 < share <= 1.0


def test_plot_borders_and_bifurcations_draw_one_mark_per_point(fig5a, fig8_bifurcations):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ds = sb.scan(**FIG5A)
    ax = sb.plot.plot_borders(fig5a, scan=ds)
    drawn = {c.get_label(): len(c.get_offsets()) for c in ax.collections}
    for kind in structure.itinerary.KINDS:
        n = int((fig5a.kind.values == kind).sum())
        assert drawn[f"{kind} ({n})"] == n
    assert ax.images[0].get_alpha() == 0.3
    # the muted scan has its key, muted alike, and the legend's markers are legible
    key = ax.images[0].colorbar
    assert key is not None and key.solids.get_alpha() == 0.3 and "muted" in key.ax.get_ylabel()
    legend = ax.get_legend()
    assert [t.get_text() for t in legend.get_texts()] == [f"{k} ({int((fig5a.kind.values == k).sum())})"
                                                          for k in borders.KINDS]
    assert min(h.get_markersize() for h in legend.legend_handles) >= 6
    with pytest.raises(ValueError, match="kinds"):
        sb.plot.plot_borders(fig5a, kinds=("slide",))
    plt.close("all")
    fig, ax = plt.subplots()
    ax.set_xlim(0.3, 2.0)
    sb.plot.plot_bifurcations(fig8_bifurcations, ax=ax)
    marks = sum(len(c.get_segments()) for c in ax.collections)
    assert marks == fig8_bifurcations.sizes["bifurcation"]
    with pytest.raises(ValueError, match="bifurcations"):
        sb.plot.plot_bifurcations(fig5a, ax=ax)
    plt.close("all")


def test_explorer_border_overlay_is_the_library_points():
    from stairbounce.explorer import view as V

    v = V.View(0.0, 0.3, 0.3, 0.7, 60, 50, 500, "word_length", ("borders",), None)
    got = V.border_overlay(v)
    ref = sb.border_points(e=(0.0, 0.3, 60), u=(0.3, 0.7, 50), max_iter=500)
    assert got["e"] == ref.e.values.tolist() and got["kind"] == ref.kind.values.tolist()
    assert got["word_low"] == ref.word_low.values.tolist()
    assert V.parse_overlays("borders,tongues") == ("tongues", "borders")
    assert V.View().overlays == ("tongues", "no_sliding")


def test_figures_borders_option_draws_the_exact_borders(tmp_path, monkeypatch):
    from stairbounce import figures as F

    from ._figures import patch_figures

    figs = {}
    real = F.settings._save

    def keep(fig, settings, name):
        figs[name] = fig
        return real(fig, settings, name)

    patch_figures(monkeypatch, "_save", keep)
    settings = F.Settings(out=tmp_path, scale=0.1, dpi=30, borders=True)
    # fig5a: a blow-up without the certified rows of fig5e, which cost most of the time
    (res,) = F.make_figures(settings, only=["fig5a"])
    assert res.error is None and "located to rounding" in res.caption
    labels = [c.get_label() for c in figs["fig5a"].axes[0].collections]
    assert any(label.startswith("chatter (") for label in labels)
    assert settings.record()["borders"] is True
    assert "borders" not in F.Settings(out=tmp_path).record()
