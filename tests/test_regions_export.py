"""The export of traced regions as a planar partition (issue 37): valid polygons,
no overlap, shared vertices along common arcs, the stated tolerance, complete
and untraced words, the window's coverage, and one set of border colours."""

import dataclasses
import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import stairbounce as sb
from stairbounce import _colours, structure

import shapely  # noqa: E402  (the [test] extra)
from shapely.geometry import shape  # noqa: E402

pytestmark = pytest.mark.slow

# the Fig. 5e window and a chatter-rich window near e = 0.3 (the report's windows),
# seeded coarsely enough to keep the module near a minute
WINDOWS = {"fig5e": ((0.04, 0.065), (0.92, 0.945), 48), "chatter": ((0.30, 0.36), (0.32, 0.38), 48)}


@pytest.fixture(scope="module", params=sorted(WINDOWS))
def exported(request):
    e, u, res = WINDOWS[request.param]
    regs = sb.window_regions(e, u, resolution=res)
    gj = sb.regions_geojson(regs, resolution=res)
    feats = [f for f in gj["features"] if f["geometry"] is not None]
    return regs, gj, feats, [shape(f["geometry"]) for f in feats]


def _area(e, u):
    return (e[1] - e[0]) * (u[1] - u[0])


def test_every_polygon_is_valid_and_no_two_overlap(exported):
    regs, gj, feats, geoms = exported
    e, u = regs[0].e, regs[0].u
    assert len(geoms) == sum(len(r.components) for r in regs) > 50
    bad = [(f["properties"]["word"], shapely.is_valid_reason(g)) for f, g in zip(feats, geoms) if not g.is_valid]
    assert bad == []
    assert gj["metadata"]["crossings"] == 0
    tree = shapely.STRtree(geoms)
    a, b = tree.query(geoms, predicate="intersects")
    pairs = [(i, j) for i, j in zip(a, b) if i < j]
    assert len(pairs) > 20   # neighbours touch ...
    worst = max(geoms[i].intersection(geoms[j]).area for i, j in pairs)
    assert worst <= 1e-15 * _area(e, u)   # ... and overlap nowhere


def test_neighbours_share_their_common_arcs_and_the_faces_partition_the_traced_area(exported):
    regs, gj, feats, geoms = exported
    e, u = regs[0].e, regs[0].u
    W = _area(e, u)
    # the union of the faces is their sum: no overlap; and it is the traced area, to the
    # tolerance times the perimeter (the rings are chords of the traced curves)
    union = shapely.union_all(geoms).area
    total = sum(g.area for g in geoms)
    assert abs(union - total) <= 1e-12 * W
    meta = gj["metadata"]
    perimeter = sum(g.length for g in geoms)
    assert meta["max_deviation"] <= meta["tolerance"]
    assert abs(total - meta["traced_area"]) <= meta["tolerance"] * perimeter + sum(r.area_error for r in regs)
    assert math.isclose(meta["polygon_area"], total, rel_tol=1e-9)
    assert math.isclose(meta["traced_area"], sum(r.area for r in regs), rel_tol=1e-12)
    # every piece of border between two traced words is on both faces' boundaries along
    # its whole length (a gap or a second chord polygon would leave a shorter common line)
    graph = sb.border_graph(regs)
    index = {}
    for k, f in enumerate(feats):
        index.setdefault(f["properties"]["word"], []).append(k)
    shared = 0
    for _, _, arc in graph.edges:
        if not arc.outside or arc.outside == arc.inside or arc.kind == "window":
            continue
        A = shapely.union_all([geoms[k] for k in index[arc.inside]])
        B = shapely.union_all([geoms[k] for k in index[arc.outside]])
        common = A.boundary.intersection(B.boundary).length
        chord = float(np.hypot(np.diff(arc.e), np.diff(arc.u)).sum())
        assert common >= chord * (1 - 1e-9), (arc, common, chord)
        shared += 1
    assert shared == meta["shared_edges"] > 10


def test_pinched_slivers_at_the_tongue_tips_give_a_valid_partition():
    # the Fig. 4 window seeded at 32 x 32: near the tongue tips at u = 1/sqrt(2), e -> 0,
    # borders of different words (a chatter border of one, edge borders of another) come
    # within rounding of each other, where halving cannot separate their chords; before
    # those chords were noded (both faces through the same points, the pinched sliver's
    # inverted loops dropped), 2 of the 35 polygons self-intersected
    from stairbounce.structure import export as rx

    e, u, res = (0.0, 0.999), (0.001, 1.5), 32
    regs = sb.window_regions(e, u, resolution=res)
    part, faces, _, meta = rx.build(regs, resolution=res)
    gj = sb.regions_geojson(regs, resolution=res)
    feats = [f for f in gj["features"] if f["geometry"] is not None]
    geoms = [shape(f["geometry"]) for f in feats]
    assert len(geoms) >= 30
    bad = [(f["properties"]["word"], shapely.is_valid_reason(g)) for f, g in zip(feats, geoms) if not g.is_valid]
    assert bad == []
    W = _area(e, u)
    tree = shapely.STRtree(geoms)
    a, b = tree.query(geoms, predicate="intersects")
    pairs = [(i, j) for i, j in zip(a, b) if i < j]
    assert len(pairs) > 10
    # overlaps of rounding size only (a pinched sliver's sides cross by about an ulp)
    assert max(geoms[i].intersection(geoms[j]).area for i, j in pairs) <= 1e-15 * W
    assert abs(shapely.union_all(geoms).area - sum(g.area for g in geoms)) <= 1e-13 * W
    # every edge between two traced words: its vertices are vertices of both faces (but
    # those of a sliver's inverted loops, pinched off where its sides cross to rounding)
    words = {}
    for (ri, ci), polys in faces.items():
        words.setdefault(part.regions[ri].word.format(ascii=True), set()).update(
            map(tuple, np.concatenate([R for rings in polys for R in rings])))
    shared = total = missing = 0
    for ed, (_, _, arc) in zip(part.edges, part.graph.edges):
        if arc.outside and arc.outside != arc.inside and arc.kind != "window":
            pts = set(map(tuple, ed.P))
            total += len(pts)
            missing += len(pts - words[arc.inside]) + len(pts - words[arc.outside])
            shared += 1
    assert shared >= 5 and total >= 100
    assert missing <= 0.01 * total


def test_properties_state_both_areas_and_completeness(exported):
    regs, gj, feats, geoms = exported
    tol = gj["metadata"]["tolerance"]
    W = _area(regs[0].e, regs[0].u)
    for f, g in zip(feats, geoms):
        p = f["properties"]
        assert p["complete"] is True and p["reason"] is None
        # (shapely's shoelace on the raw coordinates rounds to about 1e-16 of the window)
        assert math.isclose(p["polygon_area"], g.area, rel_tol=1e-9, abs_tol=1e-12 * W)
        # the polygon differs from the exact area by at most the tolerance along its boundary
        assert abs(p["polygon_area"] - p["area"]) <= tol * g.length + p["area_error"] + 1e-18
        # RFC 7946: outer rings counter-clockwise
        outer = g.geoms[0].exterior if g.geom_type == "MultiPolygon" else g.exterior
        assert outer.is_ccw


def test_coverage_is_the_traced_share_of_the_seed_scans_sliding_area(exported):
    regs, gj, feats, geoms = exported
    meta = gj["metadata"]
    e, u = regs[0].e, regs[0].u
    res = meta["seed_resolution"]
    # the seed scan's pixel centres are those of sb.scan over the same window
    ds = sb.scan(e=(e[0], e[1], res), u=(u[0], u[1], res), max_iter=meta["max_iter"])
    sliding = int((ds.status.values == 0).sum())
    assert meta["sliding_pixels"] == sliding
    assert math.isclose(meta["sliding_area"], sliding * _area(e, u) / res ** 2, rel_tol=1e-12)
    assert math.isclose(meta["coverage"], meta["traced_area"] / meta["sliding_area"], rel_tol=1e-12)
    assert 0.5 < meta["coverage"] < 1.05


def test_untraced_neighbours_and_incomplete_words_are_listed():
    e, u = WINDOWS["fig5e"][:2]
    regs = sb.window_regions(e, u, resolution=24)
    gone = regs[1]   # a large word left out: its neighbours' arcs have no other side now
    broken = dataclasses.replace(regs[2], complete=False, failures=2)
    empty = dataclasses.replace(regs[3], components=[], complete=False, failures=1)
    kept = [regs[0], broken, empty] + regs[4:]
    gj = sb.regions_geojson(kept)
    by_word = {}
    for f in gj["features"]:
        by_word.setdefault(f["properties"]["word"], []).append(f)
    text = gone.word.format(ascii=True)
    assert text in gj["metadata"]["untraced"]
    (f,) = by_word[text]
    p = f["properties"]
    assert f["geometry"] is None and p["complete"] is False and "not traced" in p["reason"]
    # the point beside it does have that word
    assert sb.sliding_word(*p["seen_at"]) == gone.word
    for f in by_word[broken.word.format(ascii=True)]:
        assert f["geometry"] is not None and f["properties"]["complete"] is False
        assert f["properties"]["reason"].startswith("2 of the word's walks")
    (f,) = by_word[empty.word.format(ascii=True)]
    assert f["geometry"] is None and f["properties"]["complete"] is False
    assert "no component traced" in f["properties"]["reason"]
    assert set(gj["metadata"]["incomplete"]) == {broken.word.format(ascii=True), empty.word.format(ascii=True)}
    # the complete run lists none of them
    full = sb.regions_geojson(regs)
    assert full["metadata"]["incomplete"] == [] and text not in full["metadata"]["untraced"]


def test_tolerance_bounds_the_chords_deviation():
    regs = sb.window_regions(*WINDOWS["fig5e"][:2], resolution=16)
    coarse = sb.regions_geojson(regs)["metadata"]
    fine = sb.regions_geojson(regs, tolerance=1e-9)["metadata"]
    assert coarse["tolerance"] == pytest.approx(1e-6 * 0.025)
    assert fine["max_deviation"] <= 1e-9 < coarse["max_deviation"]
    assert fine["vertices"] > coarse["vertices"]
    # closer to the exact area with the finer tolerance
    assert abs(fine["polygon_area"] - fine["traced_area"]) < abs(coarse["polygon_area"] - coarse["traced_area"])
    for bad in (0, -1e-9, float("nan"), "x"):
        with pytest.raises(ValueError, match="tolerance"):
            sb.regions_geojson(regs, tolerance=bad)
    with pytest.raises(ValueError, match="resolution"):
        sb.regions_geojson(regs, resolution=1)


def _lab(hexcolour):
    c = np.array([int(hexcolour[i:i + 2], 16) / 255 for i in (1, 3, 5)])
    c = np.where(c > 0.04045, ((c + 0.055) / 1.055) ** 2.4, c / 12.92)
    m = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]])
    x = m @ c / np.array([0.95047, 1.0, 1.08883])
    f = np.where(x > 0.008856, np.cbrt(x), 7.787 * x + 16 / 116)
    return np.array([116 * f[1] - 16, 500 * (f[0] - f[1]), 200 * (f[1] - f[2])])


def test_border_colours_are_one_set_outside_the_word_length_palette():
    from stairbounce.explorer import app, borders_layer
    from stairbounce.plot.borders import KIND_COLORS
    from stairbounce.plot.plane import TONGUE_COLOR, color_key

    kinds = ("graze", "edge", "chatter")
    assert KIND_COLORS == {k: _colours.KIND_COLOURS[k] for k in kinds}
    assert structure.export.KIND_COLOURS is _colours.KIND_COLOURS
    assert borders_layer._WINDOW_ARC_COLOR == _colours.KIND_COLOURS["window"]
    for k in kinds:
        assert _colours.KIND_COLOUR_NAMES[k] in app._OVERLAY_LEGEND["traced"]
        assert _colours.KIND_COLOUR_NAMES[k] in app._OVERLAY_LEGEND["borders"]
    palette = list(color_key("word_length").colors) + ["#ffffff", TONGUE_COLOR]
    for k in kinds:
        d = min(np.linalg.norm(_lab(_colours.KIND_COLOURS[k]) - _lab(p)) for p in palette)
        assert d >= 40, (k, d)   # CIELAB units: clearly another colour
    for a in kinds:
        for b in kinds:
            if a < b:
                assert np.linalg.norm(_lab(_colours.KIND_COLOURS[a]) - _lab(_colours.KIND_COLOURS[b])) >= 40


def test_svg_is_a_figure_with_axes_window_and_legend(tmp_path):
    e, u = WINDOWS["fig5e"][:2]
    regs = sb.window_regions(e, u, resolution=16)
    text = sb.regions_svg(regs, size=400, resolution=16)
    ns = "{http://www.w3.org/2000/svg}"
    root = ET.fromstring(text)
    strokes = {p.get("stroke") for p in root.iter(ns + "polyline")}
    graph = sb.border_graph(regs)
    kinds = {a.kind for _, _, a in graph.edges} - {"window"}
    assert strokes == {_colours.KIND_COLOURS[k] for k in kinds}
    # each piece of border drawn once
    assert len(list(root.iter(ns + "polyline"))) == sum(a.kind != "window" for _, _, a in graph.edges)
    words = " ".join(t.text or "" for t in root.iter(ns + "text"))
    for needed in ("graze", "edge", "chatter", "window", "e (restitution coefficient)",
                   "u (normalised horizontal speed)", "traced region", "0.04", "0.92", "seed scan"):
        assert needed in words, needed
    legend = [ln.get("stroke") for ln in root.iter(ns + "line") if ln.get("stroke-width") == "2.5"]
    assert legend == [_colours.KIND_COLOURS[k] for k in ("graze", "edge", "chatter", "window")]
    assert len(list(root.iter(ns + "path"))) == sum(len(r.components) for r in regs)
    out = sb.write_regions(regs, tmp_path / "r.svg", resolution=16)
    assert ET.fromstring(out.read_text()).tag == ns + "svg"


def test_tangles_at_the_tongue_tips_are_clipped_out_as_incomplete_boxes():
    # the Fig. 4 window seeded at 48 x 48: at the tongue tips (e -> 0, u = 1/sqrt(2) and 1)
    # borders of different words come within rounding of each other over a length of
    # ~0.005, and chord pairs still cross when halving's vertex budget is spent (before
    # they were clipped out, 3 of the 43 polygons self-intersected, shapely.is_valid)
    e, u, res = (0.0, 0.999), (0.001, 1.5), 48
    regs = sb.window_regions(e, u, resolution=res)
    gj = sb.regions_geojson(regs, resolution=res)
    meta = gj["metadata"]
    W = _area(e, u)
    boxes = meta["clipped"]
    assert meta["crossings"] > 0 and len(boxes) >= 2
    tips = [1 / math.sqrt(2), 1.0]
    for b in boxes:
        # each box at the window's edge e = 0, around a tongue tip, small
        assert b[0] == e[0] and any(b[2] <= t <= b[3] for t in tips)
        assert (b[1] - b[0]) * (b[3] - b[2]) < 1e-4 * W
    tangles = [f for f in gj["features"] if f["properties"]["word"] is None]
    assert [f["geometry"]["coordinates"][0][0] for f in tangles] == [[b[0], b[2]] for b in boxes]
    for f in tangles:
        assert f["properties"]["complete"] is False and "accumulation of borders" in f["properties"]["reason"]
    # every traced word still present, its exact area kept, what was clipped stated
    words = {f["properties"]["word"] for f in gj["features"]}
    assert {r.word.format(ascii=True) for r in regs} <= words
    traced = [f["properties"] for f in gj["features"] if f["properties"]["word"]]
    assert all(p["clipped_area"] >= 0 for p in traced)
    assert sum(p["clipped_area"] > 1e-15 * W for p in traced) >= 2
    for p in traced:
        if p["area"] is not None and not p["clipped_area"]:
            assert abs(p["polygon_area"] - p["area"]) <= 1e-4 * W
    feats = [f for f in gj["features"] if f["geometry"] is not None]
    geoms = [shape(f["geometry"]) for f in feats]
    assert [(f["properties"]["word"], shapely.is_valid_reason(g)) for f, g in zip(feats, geoms)
            if not g.is_valid] == []
    for f, g in zip(feats, geoms):
        assert math.isclose(f["properties"]["polygon_area"], g.area, rel_tol=1e-9, abs_tol=1e-12 * W)
        outer = g.geoms[0].exterior if g.geom_type == "MultiPolygon" else g.exterior
        assert outer.is_ccw
    a, b = shapely.STRtree(geoms).query(geoms, predicate="intersects")
    assert max(geoms[i].intersection(geoms[j]).area for i, j in zip(a, b) if i < j) <= 1e-15 * W
    assert abs(shapely.union_all(geoms).area - sum(g.area for g in geoms)) <= 1e-13 * W
    assert math.isclose(meta["polygon_area"], sum(p["polygon_area"] for p in traced), rel_tol=1e-12)
