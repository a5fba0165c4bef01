"""Borders as curves (stairbounce.structure, issue 22): continuation, corners,
regions as polygons.

Known answers: Theorem 3.1's tongues (their two curves u^2 = (n-1)/2 and
u^2 = n/2 ((1-e)/(1+e))^2, their tips e_n = (sqrt(n) - sqrt(n-1))^2 on the
Corollary 2.1 curve, their areas as integrals of the two curves); the map
itself (``model._step`` through ``structure.itinerary._margin`` and ``model.iterate``) for
every traced point; pixel counts of a scan for the areas; i21's border points
for the continuation.
"""

import json
import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import stairbounce as sb
from stairbounce import model, structure
from stairbounce.structure import regions
from stairbounce._io import OutputExistsError
from stairbounce.symbolic import word_from_impacts

EPS = np.finfo(float).eps
FIG5E = ((0.04, 0.065), (0.92, 0.945))
TONGUE_WINDOW = ((0.0, 0.5), (0.05, 2.1))


def _tongue_area(n, e_hi=0.5, u_lo=0.05):
    """The integral of sqrt(n/2)(1-e)/(1+e) - sqrt((n-1)/2) over e in [0, tip]
    (clipped to the window for n = 1): the area of Theorem 3.1's tongue."""
    def prim(x, lower):
        return math.sqrt(n / 2.0) * (2.0 * math.log1p(x) - x) - lower * x
    if n == 1:
        return prim(e_hi, u_lo) - prim(0.0, u_lo)
    tip = (math.sqrt(n) - math.sqrt(n - 1)) ** 2
    return prim(tip, math.sqrt((n - 1) / 2.0)) - prim(0.0, math.sqrt((n - 1) / 2.0))


@pytest.fixture(scope="module")
def tongues():
    return {n: sb.word_region((n,), *TONGUE_WINDOW, resolution=64) for n in range(1, 9)}


@pytest.mark.parametrize("n", range(1, 9))
def test_traced_tongues_are_theorem_3_1(tongues, n):
    r = tongues[n]
    assert r.complete and len(r.components) == 1
    comp = r.components[0]
    for arc in comp.boundary:
        if arc.kind == "graze":
            # u^2 = (n-1)/2, the first contact at the edge of step n-1
            assert arc.step == n - 1
            np.testing.assert_allclose(arc.u, math.sqrt((n - 1) / 2.0), rtol=1e-14, atol=0)
        elif arc.kind == "chatter":
            assert arc.step == n
            ref = math.sqrt(n / 2.0) * (1.0 - arc.e) / (1.0 + arc.e)
            np.testing.assert_allclose(arc.u, ref, rtol=1e-14, atol=0)
        else:
            assert arc.kind == "window"
    kinds = comp.kinds
    assert kinds["chatter"] == 1 and kinds.get("graze", 0) == (0 if n == 1 else 1)
    tips = [c for c in comp.corners if {ev[0] for ev in c.events} == {"graze", "chatter"}]
    if n == 1:
        assert not tips  # tongue 1 reaches e = 1: it leaves the window on its right side
    else:
        (tip,) = tips
        assert tip.e == pytest.approx((math.sqrt(n) - math.sqrt(n - 1)) ** 2, rel=1e-14, abs=0)
        # on the Corollary 2.1 curve u = (1 - e)/(2 sqrt(2e))
        assert tip.u == pytest.approx((1 - tip.e) / (2 * math.sqrt(2 * tip.e)), rel=1e-14, abs=0)
    for c in comp.corners:
        if "window" in {ev[0] for ev in c.events}:
            assert c.e in TONGUE_WINDOW[0] or c.u in TONGUE_WINDOW[1]
    assert abs(r.area - _tongue_area(n)) < 1e-12
    assert r.area_error < 1e-12


def test_margins_decide_like_the_map_and_their_derivatives_are_exact():
    rng = np.random.default_rng(22)
    buf = np.empty(1000, np.int64)
    checked = 0
    for e, u in zip(rng.uniform(0.0, 0.6, 400), rng.uniform(0.3, 1.5, 400)):
        n = structure.itinerary._itinerary_of(e, u, 1.0, 0.0, 1000, buf)
        if n <= 0:
            continue
        F = structure.continuation._Margins(buf[:n].copy(), (0.0, 0.9, 0.1, 2.0))
        g, ge, gu = F((e, u))
        assert F.inside(g)
        # derivatives against central differences of the margins themselves
        for k, d in ((0, ge), (1, gu)):
            h = 1e-7
            xp, xm = [e, u], [e, u]
            xp[k] += h
            xm[k] -= h
            with np.errstate(invalid="ignore"):  # inf - inf where a margin is infinite, masked by ok
                fd = (F(xp)[0] - F(xm)[0]) / (2 * h)
            ok = np.isfinite(g) & np.isfinite(fd)
            np.testing.assert_allclose(d[ok], fd[ok], rtol=1e-5, atol=1e-5 * (1 + np.abs(d[ok]).max()))
        checked += 1
    assert checked > 100


def test_word_and_itinerary_are_inverse():
    rng = np.random.default_rng(3)
    buf = np.empty(1000, np.int64)
    for e, u in zip(rng.uniform(0.0, 0.5, 300), rng.uniform(0.5, 1.5, 300)):
        n = structure.itinerary._itinerary_of(e, u, 1.0, 0.0, 1000, buf)
        if n > 0:
            ks = buf[:n]
            assert np.array_equal(regions.itinerary_of_word(word_from_impacts(ks)), ks)
    assert list(regions.itinerary_of_word((2, 0, 3, 1))) == [0, 2, 0, 0, 1, -1]
    assert regions.itinerary_of_word("(2, 0, 3, 1, 0^inf)").tolist() == [0, 2, 0, 0, 1, -1]


def _k_at(e, u, j):
    """Impact number of step j from (1, 0) with model.iterate (model._step)."""
    return int(model.iterate(1.0, 0.0, e, u, j)[2][j])


def _rebisect(x, normal, j, k_ref):
    """Bisect across the curve at x along its normal on the map's decision at
    step j (model._step); returns the crossing's offset from x."""
    lo, hi = -1e-9, 1e-9
    side = lambda lam: _k_at(x[0] + lam * normal[0], x[1] + lam * normal[1], j) == k_ref  # noqa: E731
    assert side(lo) != side(hi)
    s_lo = side(lo)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid in (lo, hi):
            break
        if side(mid) == s_lo:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _starts(count, seed):
    """Border points of i21's bisection in the Fig. 5e window (one per kind first)."""
    bp = sb.border_points((*FIG5E[0], 32), (*FIG5E[1], 32), max_iter=1000)
    rng = np.random.default_rng(seed)
    picks = [int(np.nonzero(bp.kind.values == k)[0][0]) for k in ("graze", "edge", "chatter")
             if (bp.kind.values == k).any()]
    picks += [int(i) for i in rng.choice(bp.sizes["point"], count - len(picks), replace=False)]
    return [(float(bp.e[i]), float(bp.u[i])) for i in picks]


@pytest.mark.parametrize("start", _starts(6, 1))
def test_traced_points_lie_on_the_map_s_border_within_ulps(start):
    arc = sb.trace_border(*start, window=FIG5E)
    assert arc.e.size >= 3
    j = arc.step
    prefix = model.iterate(1.0, 0.0, arc.e[0], arc.u[0], j - 1)[2][1:].astype(np.int64)
    idx = np.unique(np.linspace(0, arc.e.size - 1, 12).astype(int))
    for i in idx:
        x = (float(arc.e[i]), float(arc.u[i]))
        ks = model.iterate(1.0, 0.0, x[0], x[1], j)[2][1:]
        assert np.array_equal(ks[:j - 1], prefix)  # the prefix holds along the arc
        # the normal from the neighbouring points
        a, b = max(i - 1, 0), min(i + 1, arc.e.size - 1)
        t = np.array([arc.e[b] - arc.e[a], arc.u[b] - arc.u[a]])
        normal = np.array([-t[1], t[0]]) / np.hypot(*t)
        k_here = _k_at(x[0] + 1e-9 * normal[0], x[1] + 1e-9 * normal[1], j)
        lam = _rebisect(x, normal, j, k_here)
        assert abs(lam) <= 8 * EPS * max(abs(x[0]), abs(x[1])), (i, lam)


@pytest.mark.parametrize("start", _starts(4, 2))
def test_traced_points_satisfy_F_evaluated_with_model_step(start):
    arc = sb.trace_border(*start, window=FIG5E)
    j = arc.step
    prefix = model.iterate(1.0, 0.0, arc.e[0], arc.u[0], j - 1)[2][1:].astype(np.int64)
    side_k = model.iterate(1.0, 0.0, arc.e[0], arc.u[0], j)[2][j]
    it = structure.itinerary
    kind = {"graze": it.GRAZE, "edge": it.EDGE, "chatter": it.CHATTER}[arc.kind]
    for x in zip(arc.e, arc.u):
        if arc.kind == "edge":
            # the border between k and k+1 impacts: t_(k+1) = T, k the smaller side
            k = min(side_k, _k_at(x[0], x[1], j)) if side_k >= 1 else 1
            ks = [_k_at(x[0] + d, x[1] + d2, j) for d in (-1e-9, 1e-9) for d2 in (-1e-9, 1e-9)]
            index = min(k for k in ks if k >= 1) + 1
        else:
            index = 1 if arc.kind == "graze" else 0
        def F(a, b):
            return structure.itinerary._margin(a, b, j, kind, index, 1.0, 0.0, prefix)
        h = 1e-8
        grad = math.hypot((F(x[0] + h, x[1]) - F(x[0] - h, x[1])) / (2 * h),
                          (F(x[0], x[1] + h) - F(x[0], x[1] - h)) / (2 * h))
        # F = 0 to rounding: the distance |F| / |grad F| to the level set is a few ulps
        assert abs(F(*x)) / grad <= 8 * EPS * max(abs(x[0]), abs(x[1])), (x, F(*x), grad)


def test_continuation_reaches_the_neighbouring_border_points():
    n = 48
    bp = sb.border_points((*FIG5E[0], n), (*FIG5E[1], n), max_iter=1000)
    spacing = (FIG5E[0][1] - FIG5E[0][0]) / n
    rng = np.random.default_rng(5)
    starts = rng.choice(bp.sizes["point"], 12, replace=False)
    reached = 0
    for p in starts:
        pt = bp.isel(point=int(p))
        arc = sb.trace_border(float(pt.e), float(pt.u), window=FIG5E)
        assert (arc.kind, arc.step) == (str(pt.kind.values), int(pt.step))
        words = {str(pt.word_low.values), str(pt.word_high.values)}
        same = (bp.kind == arc.kind) & (bp.step == arc.step)
        near = np.hypot(bp.e - pt.e, bp.u - pt.u) <= 1.5 * spacing
        cand = bp.where(same & near, drop=True)
        P = np.stack([arc.e, arc.u], 1)
        for q in range(cand.sizes["point"]):
            c = cand.isel(point=q)
            if {str(c.word_low.values), str(c.word_high.values)} != words:
                continue
            d = np.hypot(P[:, 0] - float(c.e), P[:, 1] - float(c.u)).min()
            # the arc passes through it (its points are closer than the grid spacing
            # and the chord through the nearest two within the chords' sagitta)
            assert d <= spacing
            A, B = P[:-1], P[1:]
            AB = B - A
            tau = np.clip(((np.array([float(c.e), float(c.u)]) - A) * AB).sum(1) / (AB ** 2).sum(1), 0, 1)
            C = A + tau[:, None] * AB
            assert np.hypot(C[:, 0] - float(c.e), C[:, 1] - float(c.u)).min() <= 1e-7
            reached += 1
    assert reached >= 10


def _pixel_area(mask, cell):
    inner = mask.copy()
    inner[1:] &= mask[:-1]
    inner[:-1] &= mask[1:]
    inner[:, 1:] &= mask[:, :-1]
    inner[:, :-1] &= mask[:, 1:]
    outer = mask.copy()
    outer[1:] |= mask[:-1]
    outer[:-1] |= mask[1:]
    outer[:, 1:] |= mask[:, :-1]
    outer[:, :-1] |= mask[:, 1:]
    return inner.sum() * cell, outer.sum() * cell


@pytest.mark.parametrize("word", [(2, 2), (2, 2, 2), (2, 2, 0, 2, 2, 2)])
def test_region_area_against_pixel_counts(word):
    res = 1024
    r = sb.word_region(word, *FIG5E, resolution=128)
    assert r.complete
    es, us = regions._grid(*FIG5E, res)
    h1, h2, _ = regions._label_grid(es, us, 1000, 1.0, 0.0)
    ks = regions.itinerary_of_word(word)
    a, b = structure.itinerary._hash_itinerary(ks, ks.size)
    mask = (h1 == a) & (h2 == b)
    cell = (0.025 / res) ** 2
    lo, hi = _pixel_area(mask, cell)
    # the pixels surely inside <= the traced area <= the pixels touching the region
    assert lo <= r.area <= hi
    assert abs(r.area - mask.sum() * cell) <= 0.5 * (hi - lo)


def test_regions_of_a_window_sum_to_its_sliding_area():
    # a window near the tongues of Theorem 3.1 and the first words between them
    # seeded by the same pixel centres that are counted: every sliding pixel's word
    # is traced, so the traced total lies between the pixels surely inside and the
    # pixels touching a sliding region (a word narrower than a pixel everywhere is
    # missed by both)
    e, u = (0.02, 0.2), (0.95, 1.05)
    res = 128
    regs = sb.window_regions(e, u, resolution=res)
    es, us = regions._grid(e, u, res)
    _, _, steps = regions._label_grid(es, us, 1000, 1.0, 0.0)
    sliding = steps > 0
    cell = (0.18 / res) * (0.1 / res)
    lo, hi = _pixel_area(sliding, cell)
    # every walk closes (2 of the 438 words stalled before, at corners of margins that
    # cross at a tiny angle)
    assert [r for r in regs if not r.complete] == []
    total = sum(r.area for r in regs)
    assert lo <= total <= hi
    words = {r.word.letters for r in regs}
    assert (2,) in words and (3,) in words


GRAPH_WINDOW = ((0.02, 0.2), (0.95, 1.05))


@pytest.fixture(scope="module")
def graph32():
    return sb.border_graph(sb.window_regions(*GRAPH_WINDOW, resolution=32))


def test_graph_splits_arcs_at_one_sided_junctions(graph32):
    # tongue 3 (word (3)) lies above the graze line u = 1 (Theorem 3.1); below it, the
    # region of (2, 3, 0, 0, 2, 3) reaches the line between two corners, one of them where
    # its edge border of step 5 ends on the line: a T-junction that tongue 3's boundary
    # does not have (its arc along u = 1 runs past it)
    graph = graph32
    regs = {r.word.format(ascii=True): r for r in graph.regions}
    low = regs["(2, 3, 0, 0, 2, 3, 0^inf)"]
    tongue = regs["(3, 0^inf)"]
    (j,) = [c for c in low.corners if sorted(ev[0] for ev in c.events) == ["edge", "graze"]
            and ("graze", 2) in c.events and ("edge", 5) in c.events]
    assert j.u == 1.0  # on the graze line u^2 = (3 - 1)/2
    assert all(math.hypot(c.e - j.e, c.u - j.u) > 1e-6 for c in tongue.corners)
    (arc,) = [a for a in tongue.components[0].boundary if a.kind == "graze"
              and a.e.min() < j.e < a.e.max()]  # tongue 3's own arc runs through it
    node = [n for n, c in enumerate(graph.nodes) if math.hypot(c.e - j.e, c.u - j.u) <= 1e-12]
    assert len(node) == 1
    # in the graph the tongue's arc is cut there: two of its edges end at the junction,
    # one of them the border it shares with the word below
    ends = [(a, b, edge) for a, b, edge in graph.edges if node[0] in (a, b)
            and edge.inside == "(3, 0^inf)" and edge.kind == "graze"]
    assert len(ends) == 2
    assert "(2, 3, 0, 0, 2, 3, 0^inf)" in {edge.outside for _, _, edge in ends}
    assert graph.junctions > 0


def _edge_boxes(graph):
    return np.array([(a.e.min(), a.e.max(), a.u.min(), a.u.max()) for _, _, a in graph.edges])


def test_graph_edges_meet_only_at_nodes_and_separate_two_words(graph32):
    graph = graph32
    (e0, e1), (u0, u1) = GRAPH_WINDOW
    scale = max(e1 - e0, u1 - u0)
    tol = 1e-11 * scale
    margins = structure.graph._GraphMargins(graph.regions)
    boxes = _edge_boxes(graph)
    buf = np.empty(1000, np.int64)
    shared = 0
    for k, (a, b, edge) in enumerate(graph.edges):
        # every traced point of an edge (its ends aside) lies on no other edge, away
        # from that edge's nodes: edges overlap nowhere but at nodes
        pts = np.stack([edge.e, edge.u], 1)[1:-1]
        if len(pts) == 0:
            pts = margins.middle(edge)[None]
        for x in pts[:: max(1, len(pts) // 4)]:
            near = np.nonzero((boxes[:, 0] - tol <= x[0]) & (x[0] <= boxes[:, 1] + tol)
                              & (boxes[:, 2] - tol <= x[1]) & (x[1] <= boxes[:, 3] + tol))[0]
            for m in near:
                if m == k:
                    continue
                a2, b2, other = graph.edges[m]
                if min(math.hypot(x[0] - graph.nodes[n].e, x[1] - graph.nodes[n].u) for n in (a2, b2)) <= 1e-9 * scale:
                    continue
                assert not (regions._chord_position(np.stack([other.e, other.u], 1), x, tol) is not None and
                            structure.graph._on_arc_curve(margins(other), other._slot, x, 2 * tol)), (edge, other)
        if edge.kind == "window":
            assert edge.outside == ""
            continue
        # the two sides: the map's word just across the middle of the edge is another
        # word than inside, and the one named outside where the other side was traced
        x = margins.middle(edge)
        i = min(edge.e.size // 2, edge.e.size - 2)
        t = np.array([edge.e[i + 1] - edge.e[i], edge.u[i + 1] - edge.u[i]])
        left = np.array([-t[1], t[0]]) / np.hypot(*t)
        words = []
        for side in (1, -1):
            y = x + side * 1e-9 * scale * left
            n = structure.itinerary._itinerary_of(y[0], y[1], 1.0, 0.0, 1000, buf)
            words.append(word_from_impacts(buf[:n]).format(ascii=True) if n > 0 else "")
        assert words[0] == edge.inside and words[1] != edge.inside
        if edge.outside:
            shared += 1
            assert words[1] == edge.outside
    assert shared >= 20


def test_graph_counts_and_exports(tmp_path, graph32):
    graph = graph32
    regs = graph.regions
    counts = graph.counts()
    assert counts["words"] == len(regs)
    assert sum(graph.words_by_period().values()) == len(regs)
    # the tip of tongue 3 is a node where graze meets chatter
    tip3 = (math.sqrt(3) - math.sqrt(2)) ** 2
    assert any(abs(c.e - tip3) < 1e-14 for c in graph.nodes)
    for i, j, arc in graph.edges:
        assert 0 <= i < len(graph.nodes) and 0 <= j < len(graph.nodes)
    gj = sb.regions_geojson(regs)
    # one polygon per component (the untraced words seen beside arcs come after, unlocated)
    feats = [f for f in gj["features"] if f["geometry"] is not None]
    assert len(feats) == counts["components"]
    for f, comp in zip(feats, [c for r in regs for c in r.components]):
        poly = f["geometry"]["coordinates"]
        ring = np.array(poly[0][0] if f["geometry"]["type"] == "MultiPolygon" else poly[0])
        shoelace = 0.5 * np.sum(ring[:-1, 0] * ring[1:, 1] - ring[1:, 0] * ring[:-1, 1])
        assert shoelace > 0  # counter-clockwise
        # the chords alone (no Hermite correction): the same polygon, a little inside
        assert abs(shoelace - comp.area) <= 1e-2 * comp.area
        assert {"word", "period", "impacts", "area", "kinds"} <= set(f["properties"])
    out = sb.write_regions(regs, tmp_path / "x.geojson")
    assert json.loads(out.read_text())["type"] == "FeatureCollection"
    svg = sb.write_regions(regs, tmp_path / "x.svg")
    root = ET.fromstring(svg.read_text())
    assert root.tag.endswith("svg") and len(list(root.iter("{http://www.w3.org/2000/svg}polyline"))) > 0
    with pytest.raises(ValueError, match="out must end in"):
        sb.write_regions(regs, tmp_path / "x.png")
    with pytest.raises(OutputExistsError):
        sb.write_regions(regs, tmp_path / "x.svg")
    assert sb.write_regions(regs, tmp_path / "x.svg", overwrite=True).exists()


def test_band_similarity_numbers():
    s = sb.band_similarity(n=(2, 3, 4), repeats=(2,), resolution=64)
    row = s[2]
    assert row["n"] == [2, 3, 4]
    # each family's tip lies below its tongue's tip (Corollary 2.1 bounds every band)
    for k, te, tu in zip(row["n"], row["tip_e"], row["tip_u"]):
        assert 0 < te < (math.sqrt(k) - math.sqrt(k - 1)) ** 2
        assert tu <= (1 - te) / (2 * math.sqrt(2 * te))
    assert len(row["area_ratio"]) == 2 and all(0 < x < 1 for x in row["area_ratio"])


@pytest.mark.parametrize("call, match", [
    (lambda: sb.word_region("nonsense"), "word must look like"),
    (lambda: sb.word_region((0, 1)), "letters"),
    (lambda: sb.word_region((2,), e=(0.5, 0.2)), "e window"),
    (lambda: sb.word_region((2,), e=(0.0, 1.2)), "e window"),
    (lambda: sb.word_region((2,), u=(-0.1, 1.0)), "u window"),
    (lambda: sb.word_region((2,), resolution=1), "resolution"),
    (lambda: sb.word_region((2,), e=(0.1, 0.2, 8), resolution=8), "give the seed pixels once"),
    (lambda: sb.word_region((2,), e=(0.1, 0.2, 8, 8)), r"e must be a tuple \(e_min, e_max\)"),
    (lambda: sb.trace_border(0.5, 3.0, window=((0.4, 0.6), (2.9, 3.1))), "no border"),
    (lambda: sb.trace_border(0.05, 0.93, search=0), "search"),
    (lambda: sb.trace_border(1.5, 0.93), "e"),
])
def test_bad_input(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_word_table_with_traced_regions():
    window = ((0.02, 0.2, 24), (0.95, 1.05, 24))
    tab = sb.word_table(*window, regions=True)
    assert not np.isnan(tab.traced_area.values).any()
    row = tab.isel(word=list(tab.text.values).index("(3, 0^inf)"))
    # the tongue of Theorem 3.1 clipped to the window: e from 0.02 to its tip, u from 1 to
    # the chatter curve, or to the window's top u = 1.05 until the curve falls below it
    tip = (math.sqrt(3) - math.sqrt(2)) ** 2
    c = 1.05 / math.sqrt(1.5)
    e_star = (1 - c) / (1 + c)

    def prim(x):
        return math.sqrt(1.5) * (2.0 * math.log1p(x) - x) - x
    exact = 0.05 * (e_star - 0.02) + prim(tip) - prim(e_star)
    assert float(row.traced_area) == pytest.approx(exact, rel=1e-12)
    assert int(row.components) == 1 and bool(row.complete)


def test_cli_words_regions(tmp_path, capsys):
    from stairbounce.cli import main

    def run(args):
        with pytest.raises(SystemExit) as exc:
            main(args)
        out, err = capsys.readouterr()
        return exc.value.code, out, err

    out = tmp_path / "w.geojson"
    code, text, err = run(["words", "--e", "0.02:0.2", "--u", "0.95:1.05", "--size", "24x24",
                           "--regions", "--out", str(out)])
    assert code == 0, err
    gj = json.loads(out.read_text())
    ref = sb.window_regions((0.02, 0.2), (0.95, 1.05), resolution=24)
    assert len([f for f in gj["features"] if f["geometry"]]) == sum(len(r.components) for r in ref)
    assert any(f["properties"]["word"] == "(3, 0^inf)" for f in gj["features"])
    assert f"{len(ref)} words in" in text
    # the coverage of the seed scan (24 x 24, the larger side of --size), in the file and the summary
    meta = gj["metadata"]
    assert meta["seed_resolution"] == 24 and f"({100 * meta['coverage']:.2f} %)" in text
    code, _, err = run(["words", "--e", "0.02:0.2", "--u", "0.95:1.05", "--size", "24x24", "--regions",
                        "--out", str(tmp_path / "t.geojson"), "--tolerance", "-1"])
    assert code == 2 and "--tolerance must be" in err and "Traceback" not in err
    code, _, err = run(["words", "--e", "0.02:0.2", "--u", "0.95:1.05", "--size", "24x24",
                        "--regions", "--out", str(tmp_path / "w.svg")])
    assert code == 0 and (tmp_path / "w.svg").read_text().startswith("<svg")
    code, _, err = run(["words", "--regions", "--out", str(tmp_path / "w.csv")])
    assert code == 2 and "--regions needs --out" in err and "Traceback" not in err


def test_fig5c_report_row_on_exact_borders(tmp_path):
    from stairbounce import figures

    row = figures.plane._band_similarity_row(figures.Settings(out=tmp_path, scale=0.25))
    assert row.verdict in figures.VERDICTS
    assert "tip ratios" in row.measured and "no constant scale factor" in row.why


def test_regions_seeded_from_finer_border_points():
    # a coarse seed scan (8 x 8) misses most words; i21's border points of a 32 x 32 scan
    # seed the rest, each traced from the word's end of a bisected bracket
    e, u = (0.08, 0.12), (0.98, 1.02)
    coarse = sb.window_regions(e, u, resolution=8)
    bp = sb.border_points((*e, 32), (*u, 32))
    seeded = sb.window_regions(e, u, resolution=8, points=bp)
    fine = sb.window_regions(e, u, resolution=32)
    words = {r.word.letters for r in seeded if r.complete}
    assert {r.word.letters for r in coarse} < words | {r.word.letters for r in coarse}
    assert len(words) > len({r.word.letters for r in coarse})
    # no component twice, and nothing outside the sliding set: the total lies below the
    # pixels touching a sliding pixel at 512 x 512
    # (per word: slivers along chatter borders, W 0^k W..., have areas below 1e-15)
    for r in seeded:
        areas = np.sort([c.area for c in r.components])
        assert np.all(np.diff(areas) > 1e-9 * areas[1:]), r
    areas = [c.area for r in seeded for c in r.components]
    res = 512
    es, us = regions._grid(e, u, res)
    _, _, steps = regions._label_grid(es, us, 1000, 1.0, 0.0)
    _, hi = _pixel_area(steps > 0, (0.04 / res) ** 2)
    assert sum(areas) <= hi
    # a word traced both ways has the same area
    by_word = {r.word.letters: r.area for r in fine if r.complete}
    for r in seeded:
        if r.complete and r.word.letters in by_word and len(r.components) == 1:
            assert r.area == pytest.approx(by_word[r.word.letters], rel=1e-9)
    with pytest.raises(ValueError, match="points must be"):
        sb.window_regions(e, u, resolution=8, points=42)


FIG7 = ((0.155, 0.2138), (0.6, 0.658))


# Words whose boundary walks failed before (they were marked incomplete), each named by
# a pixel (i, j) of the 128 x 128 seed scan of its window and its number of steps:
# - 78 steps: a long sliver; a pixel centre between a traced curve and its chord (inside
#   the polygon, outside the region) was taken for a missed component, whose search failed;
# - 252 (Fig. 5e) and 126 (Fig. 7) steps: corners where the margins of the same step in
#   consecutive repeats of the word cross at a tiny angle, so 2-D Newton never settled to
#   4 ulps (the corner is fixed along the arc only to the margins' rounding, 1e-14).
@pytest.mark.parametrize("window, pixel, steps", [(FIG5E, (30, 92), 78), (FIG5E, (67, 33), 252),
                                                  (FIG7, (109, 71), 126)])
def test_previously_incomplete_walks_close(window, pixel, steps):
    e, u = window
    es, us = regions._grid(e, u, 128)
    buf = np.empty(1000, np.int64)
    n = structure.itinerary._itinerary_of(es[pixel[1]], us[pixel[0]], 1.0, 0.0, 1000, buf)
    assert n == steps
    ks = buf[:n].copy()
    r = sb.word_region(word_from_impacts(ks), e, u, resolution=128)
    assert r.complete and len(r.components) == 1
    # every traced point lies on its arc's curve and in the closure of the region, to the
    # margins' rounding (32 ulps of the position times the gradient)
    F = structure.continuation._Margins(ks, (*e, *u))
    for arc in r.components[0].boundary:
        for x in zip(arc.e, arc.u):
            g = F(np.array(x))
            tol = structure.continuation._noise(g, x)
            assert abs(g[0][arc._slot]) <= tol[arc._slot]
            assert np.all(g[0] >= -tol)
    # the area between the pixels surely inside and those touching at 1024 x 1024 over the
    # region's bounding box (with a quarter of its size around it)
    pe, pu = r.components[0].polygon()
    de, du = np.ptp(pe), np.ptp(pu)
    ze = (max(e[0], pe.min() - 0.25 * de), min(e[1], pe.max() + 0.25 * de))
    zu = (max(u[0], pu.min() - 0.25 * du), min(u[1], pu.max() + 0.25 * du))
    res = 1024
    zs, ws = regions._grid(ze, zu, res)
    h1, h2, _ = regions._label_grid(zs, ws, 1000, 1.0, 0.0)
    a, b = structure.itinerary._hash_itinerary(ks, ks.size)
    lo, hi = _pixel_area((h1 == a) & (h2 == b), (ze[1] - ze[0]) * (zu[1] - zu[0]) / res ** 2)
    assert hi > 0 and lo <= r.area <= hi


def test_fig5e_regions_no_component_twice():
    # the seeds of one component all land on its traced boundary: each component is
    # walked once (an earlier version walked 7 of the 918 twice here)
    regs = sb.window_regions(*FIG5E, resolution=128)
    assert len(regs) > 800
    for r in regs:
        areas = [round(c.area, 16) for c in r.components]
        assert len(set(areas)) == len(areas), r
    assert sum(r.area for r in regs) < 0.025 ** 2
    # every walk closes (13 of the 920 words stalled before, at corners of margins that
    # cross at a tiny angle and at pixel centres within a chord's sagitta)
    assert [r for r in regs if not r.complete] == []
