"""Proven labels and proven tubes (issue 36, items 5 and 6).

Labels: a proven label agrees with a 300-bit mpmath evaluation (the exact
itinerary at the widened ends is the label's, and at the bracket's own ends
the prefix is the label's); a label the exact arithmetic contradicts is never
flagged proven, and such labels exist in the chatter-rich window near e = 0.3.
Tubes: on the Theorem 3.1 tongues (analytic borders u = sqrt(n/2)(1-e)/(1+e))
the tube contains the analytic border, its width is what it states, and a
tampered tube is rejected.
"""

import mpmath as mp
import numpy as np
import pytest

import stairbounce as sb

PREC = 300


def exact_itinerary(e, u, steps, margins=False):
    """The impact numbers of the orbit of (1, 0) at (e, u), 300-bit mpmath,
    impact by impact (eq. (2.2), (2.4), Prop. 2.3 on (v, s)), up to ``steps``
    steps or the slide (-1); with ``margins`` also the least |margin| of the
    decisions taken (slide test, T - t_k, T - t_{k+1})."""
    with mp.workprec(PREC):
        e, T = mp.mpf(e), 1 / mp.mpf(u)
        ratio = (1 + e) / (1 - e)
        v, s = mp.mpf(0), mp.sqrt(2)
        out, least = [], mp.inf
        for _ in range(steps):
            least = min(least, abs(T - (v + ratio * s)))
            if v + ratio * s <= T:
                out.append(-1)
                break
            t, w, k = v + s, s, 0
            while t <= T:  # impact k+1 happens
                least = min(least, abs(T - t))
                k += 1
                w = w * e  # e^k s
                t = t + 2 * w
            least = min(least, abs(T - t))
            # after k impacts: v' = v_k - (T - t_k), s'^2 = v_k^2 + 2 (s^2 + 2 after a fly-over)
            if k == 0:
                v, s = v - T, mp.sqrt(s * s + 2)
            else:
                t_k = t - 2 * w
                v, s = w - (T - t_k), mp.sqrt(w * w + 2)
            out.append(k)
        return (out, float(least)) if margins else out


def _ends(pts, d):
    e, u, w = pts.e.values, pts.u.values, pts.width.values
    along_e = pts.axis.values.astype(str) == "e"
    lo = (np.where(along_e, e - d, e), np.where(along_e, u, u - d))
    hi = (np.where(along_e, e + w + d, e), np.where(along_e, u, u + w + d))
    return lo, hi


@pytest.fixture(scope="module")
def chatter_points():
    # the referee's chatter-rich window (issue 36, item 6), a coarse grid
    return sb.prove_labels(sb.border_points(e=(0.30, 0.36, 20), u=(0.32, 0.38, 20), outcome="sliding"))


def test_prove_labels_columns(chatter_points):
    pts = chatter_points
    assert pts.attrs["proven_fraction"] == pytest.approx(pts.proven.values.mean())
    assert ((pts.reason.values == "") == pts.proven.values).all()
    assert np.isnan(pts.proof_distance.values[~pts.proven.values]).all()
    assert (pts.proof_distance.values[pts.proven.values] > 0).all()
    assert (pts.tried_distance.values >= pts.width.values).all()
    # the border_points option is the same function
    small = sb.border_points(e=(0.0, 0.333, 12), u=(0.4, 0.733, 12), prove=True)
    again = sb.prove_labels(small.drop_vars(["proven", "proof_distance", "tried_distance", "reason",
                                             "unproven_step"]))
    assert (again.proven.values == small.proven.values).all()
    assert small.proven.values.mean() > 0.5


def test_proven_labels_agree_with_300_bit_arithmetic(chatter_points):
    pts = chatter_points.isel(point=np.flatnonzero(chatter_points.proven.values & (chatter_points.step.values <= 80)))
    assert pts.sizes["point"] >= 10
    pts = pts.isel(point=slice(0, 25))
    (el, ul), (eh, uh) = _ends(pts, pts.proof_distance.values)
    (bl, vl), (bh, vh) = _ends(pts, 0.0)
    for i in range(pts.sizes["point"]):
        j = int(pts.step.values[i])
        lo, hi = exact_itinerary(el[i], ul[i], j), exact_itinerary(eh[i], uh[i], j)
        assert len(lo) == len(hi) == j and lo[:-1] == hi[:-1]
        k_lo, k_hi = int(pts.impacts_low.values[i]), int(pts.impacts_high.values[i])
        kind = str(pts.kind.values[i])
        if kind == "chatter":  # one side slides at step j, the other does not
            assert (lo[-1] == -1) == (k_lo == -1) and (hi[-1] == -1) == (k_hi == -1)
        else:
            assert (lo[-1], hi[-1]) == (k_lo, k_hi)
        # the theorem: the whole widened segment has the prefix, the bracket's ends too
        for x, y in ((bl[i], vl[i]), (bh[i], vh[i])):
            assert exact_itinerary(x, y, j - 1) == lo[:-1]


def test_unproven_labels_exist_and_rounding_decides_them(chatter_points):
    pts = chatter_points
    unproven = np.flatnonzero(~pts.proven.values & (pts.step.values <= 80))
    assert unproven.size >= 3, "the chatter-rich window has labels fixed by rounding"
    (bl, vl), (bh, vh) = _ends(pts, 0.0)
    (wl, xl), (wh, xh) = _ends(pts, pts.tried_distance.values)
    for i in unproven[:20]:
        j = int(pts.step.values[i])
        assert pts.reason.values[i] and 1 <= pts.unproven_step.values[i] <= j
        # the 300-bit evidence that rounding decides it: at the bracket's ends
        # or at the ends last tried, the exact orbit leaves the label before
        # step j, or passes a decision within 1e-10 of its edge
        prefix = None
        evidence = False
        for x, y in ((bl[i], vl[i]), (bh[i], vh[i]), (wl[i], xl[i]), (wh[i], xh[i])):
            ks, least = exact_itinerary(x, y, j, margins=True)
            prefix = ks[:j - 1] if prefix is None else prefix
            evidence |= least < 1e-10 or ks[:j - 1] != prefix or len(ks) < j
        assert evidence, (i, pts.reason.values[i])


def test_proven_words_are_the_words_at_their_points():
    tab = sb.word_table(e=(0.30, 0.36, 24), u=(0.32, 0.38, 24), prove=True)
    proven = tab.proven.values
    assert proven.any()
    assert tab.attrs["proven_distinct_words"] == int(proven.sum())
    assert (tab.proven_words.values <= tab.distinct_words.values).all()
    assert tab.proven_words.values.sum() == proven.sum()
    for i in np.flatnonzero(proven)[:15]:
        e, u = float(tab.e_proven.values[i]), float(tab.u_proven.values[i])
        assert sb.sliding_word(e, u) == sb.parse_word(str(tab.text.values[i]))
        row = exact_itinerary(e, u, int(tab.period.values[i]))
        assert row[-1] == -1 and sum(max(k, 0) for k in row) == int(tab.impacts.values[i])
    assert np.isnan(tab.e_proven.values[~proven]).all()


def u_high(n, e):
    with mp.workprec(PREC):
        e = mp.mpf(e)
        return mp.sqrt(mp.mpf(n) / 2) * (1 - e) / (1 + e)


@pytest.mark.parametrize("n, e0", [(1, 0.2), (3, 0.05), (8, 0.015)])
def test_tube_holds_the_analytic_tongue_border(n, e0):
    uh = float(u_high(n, e0))
    window = ((0.97 * e0, 1.03 * e0), (0.97 * uh, 1.03 * uh))
    arc = sb.trace_border(e0, uh * (1 - 1e-6), window=window)
    assert (arc.kind, arc.step) == ("chatter", n)
    tube = sb.border_tube(arc, width=1e-10, window=window)
    size = max(window[0][1] - window[0][0], window[1][1] - window[1][0])
    assert tube.proven.all() and tube.proven_fraction == 1.0
    assert tube.max_width <= 1e-10
    assert tube.max_width == pytest.approx(2 * tube.delta.max() / size)
    assert tube.contains(arc.e, arc.u).all()  # the traced points lie inside
    es = np.linspace(tube.e_a.min(), tube.e_b.max(), 41)[1:-1]
    ua = np.array([float(u_high(n, x)) for x in es])
    assert tube.contains(es, ua).all()
    # a float's worth of e: the per-float bounds, a few ulps wide
    lo, hi = tube.bounds(es)
    assert ((lo <= ua) & (ua <= hi)).all()
    assert ((hi - lo) / size).max() < 1e-13
    # the stated width is the proven one: shifted by a few widths, a tube is rejected
    assert tube.verify().all()
    for shift in (3.0, -3.0):
        bad = sb.BorderTube(**{**tube.__dict__, "u_a": tube.u_a + shift * tube.delta,
                               "u_b": tube.u_b + shift * tube.delta})
        assert not bad.verify().any()
        assert not bad.contains(es, ua).all()
    thin = sb.BorderTube(**{**tube.__dict__, "delta": tube.delta / 4})
    assert not thin.verify().all()


def test_tube_of_an_edge_arc_inside_a_window():
    # an arc at a later step, along a longer itinerary (traced in the Fig. 6 window)
    window = ((0.0, 0.333), (0.4, 0.733))
    pts = sb.border_points(e=(0.0, 0.333, 24), u=(0.4, 0.733, 24), prove=True)
    pick = np.flatnonzero((pts.kind.values == "edge") & (pts.step.values >= 3) & pts.proven.values)[0]
    e, u = float(pts.e.values[pick]), float(pts.u.values[pick])
    arc = sb.trace_border(e, u, window=window)
    tube = sb.border_tube(arc, width=1e-6, window=window, max_pieces=20000)
    assert tube.index >= 2 and len(tube.prefix) == arc.step - 1
    assert tube.proven_fraction > 0.9
    assert tube.max_width <= 1e-6
    inside = tube.contains(arc.e, arc.u)
    assert inside.mean() > 0.9
    # every traced point over a proven piece lies in its band
    i = np.clip(np.searchsorted(tube.e_a, arc.e, side="right") - 1, 0, tube.e_a.size - 1)
    over_proven = tube.proven[i] & (arc.e >= tube.e_a[i]) & (arc.e <= tube.e_b[i])
    assert (inside | ~over_proven).all()
    assert tube.verify()[tube.proven].all()
    # the per-float bounds hold the traced points to a few ulps of the arc's drop
    lo, hi = tube.bounds(arc.e[over_proven])
    ok = np.isfinite(lo)
    assert ok.mean() > 0.9
    slack = 64 * np.spacing(arc.u[over_proven][ok])
    assert ((lo[ok] - slack <= arc.u[over_proven][ok]) & (arc.u[over_proven][ok] <= hi[ok] + slack)).all()


def test_bad_input():
    with pytest.raises(ValueError, match="points"):
        sb.prove_labels("not a table")
    arc = sb.trace_border(0.2, float(u_high(1, 0.2)) * (1 - 1e-6))
    with pytest.raises(ValueError, match="width"):
        sb.border_tube(arc, width=0.0)
    with pytest.raises(ValueError, match="max_pieces"):
        sb.border_tube(arc, max_pieces=0)


def test_words_command_reports_the_proven_words_first(tmp_path, capsys):
    from stairbounce.cli import main

    with pytest.raises(SystemExit) as exc:
        main(["words", "--e", "0.30:0.36", "--u", "0.32:0.38", "--size", "24x24", "--top", "0", "--prove",
              "--out", str(tmp_path / "w.csv")])
    out = capsys.readouterr().out
    assert exc.value.code == 0
    lines = [line for line in out.strip().splitlines() if not line.startswith("wrote")]
    tab = sb.word_table(e=(0.30, 0.36, 24), u=(0.32, 0.38, 24), prove=True)
    assert lines[0].startswith(f"{tab.attrs['proven_distinct_words']} proven distinct words")
    assert lines[1].startswith(f"{tab.sizes['word']} distinct words")
