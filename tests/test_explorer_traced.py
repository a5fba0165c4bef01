"""The explorer's "traced" overlay (issue 22 item 4): the exact borders drawn as
traced arcs (stairbounce.structure.regions) instead of pixel-bound points where they exist.

The overlay's data (view.trace_slices, view.traced_overlay) is checked against
the library (window_regions, border_graph) and the map itself (sliding_word,
itinerary just off each arc); the page logic (app.Explorer) is driven without a
browser on a scheduler whose slices the test runs one by one.  The browser test
is in test_explorer_browser.py.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

import stairbounce as sb
from stairbounce.structure.words import NONE_WORD
from stairbounce.explorer import view as V
from stairbounce.model import SLIDING

pn = pytest.importorskip("panel", reason="panel is in the web extra")

# a window of 23 words (seeds 48 x 48, max_iter 300) with graze, edge and chatter arcs
SMALL = V.View(0.2, 0.3, 0.6, 0.7, 60, 50, max_iter=300, overlays=("traced",))
# Theorem 3.1's tongue n = 1 and the no-sliding region above it: one word, (1, 0^inf),
# whose upper side is the chatter curve u = sqrt(1/2) (1 - e) / (1 + e)
TONGUE1 = (0.6, 0.8, 0.05, 0.2)


def _run(gen):
    """Run a generator to its end; its return value and what it yielded."""
    seen = []
    while True:
        try:
            seen.append(next(gen))
        except StopIteration as stop:
            return stop.value, seen


def _text(e, u, max_iter):
    w = sb.sliding_word(e, u, max_iter)
    return NONE_WORD if w is None else w.format(ascii=True)


def _off(arc_e, arc_u, i, view, d=1e-9):
    """Two points just off a traced arc at its point i, along the normal the test
    computes itself (in the window's scaled units), the lower one (in u, or in e
    where the arc is nearer vertical) first."""
    (e0, e1), (u0, u1) = V.trace_window(view)
    x, y = (np.asarray(arc_e) - e0) / (e1 - e0), (np.asarray(arc_u) - u0) / (u1 - u0)
    a, b = max(i - 1, 0), min(i + 1, x.size - 1)
    tx, ty = x[b] - x[a], y[b] - y[a]
    n = np.array([-ty, tx]) / math.hypot(tx, ty)
    axis = 1 if abs(n[1]) >= abs(n[0]) else 0
    if n[axis] > 0:
        n = -n  # towards the smaller coordinate
    p = np.array([x[i], y[i]])
    lo, hi = p + d * n, p - d * n
    return [(e0 + q[0] * (e1 - e0), u0 + q[1] * (u1 - u0)) for q in (lo, hi)]


def _impacts(e, u, max_iter):
    return sb.itinerary(e, u, max_iter)["impacts"].values


def test_traced_overlay_arcs_kinds_and_the_words_on_both_sides():
    """(a) The overlay's arcs are border_graph's edges of the regions traced from
    the view's seeds (the same regions as stairbounce.window_regions, one word per
    slice); each non-window arc's kind and step are the event where the itineraries
    just off it first differ (graze 0 <-> 1 impacts, edge k <-> k+1, chatter finite
    <-> sliding), its low and high words are sliding_word's just off its middle on
    the lower and upper side, and the word of the region it bounds is on one side
    of it all along."""
    regions, seen = _run(V.trace_slices(SMALL, 48))
    seeds = [s for s in seen if s[1] is None]  # the seed scan's slices come first
    assert seeds and seen[:len(seeds)] == seeds == [(0, None)] * len(seeds)
    seen = seen[len(seeds):]
    assert seen[0] == (0, len(regions)) and seen[-1] == (len(regions), len(regions)) and len(seen) == len(regions) + 1
    ref = sb.window_regions(*V.trace_window(SMALL), resolution=48, max_iter=300)
    assert [r.word for r in regions] == [r.word for r in ref]
    assert [r.area for r in regions] == [r.area for r in ref]  # bit for bit: the same method
    assert 10 <= len(regions) <= 40
    pts = V.view_border_points(SMALL)
    ov = V.traced_overlay(SMALL, regions, pts)
    arcs = ov["arcs"]
    edges = sb.border_graph(regions).edges
    assert len(arcs["xs"]) == len(edges) == sum(ov["counts"].values())
    assert set(arcs["kind"]) == {"graze", "edge", "chatter", "window"}
    assert ov["words"] == len(regions) and ov["incomplete"] == []
    checked = 0
    for i, (_, _, arc) in enumerate(edges):
        xs, ys = np.asarray(arcs["xs"][i]), np.asarray(arcs["ys"][i])
        assert np.array_equal(xs, arc.e) and np.array_equal(ys, arc.u)
        assert (arcs["kind"][i], arcs["step"][i]) == (arc.kind, arc.step)
        if arc.kind == "window":
            assert V.OUTSIDE_WORD in (arcs["word_low"][i], arcs["word_high"][i])
            continue
        if xs.size < 3:
            continue  # corner to corner: no traced point in between to stand on
        m = xs.size // 2
        lo, hi = _off(xs, ys, m, SMALL)
        assert (arcs["word_low"][i], arcs["word_high"][i]) == (_text(*lo, 300), _text(*hi, 300)), i
        # the first step where the two sides' itineraries differ is the arc's, by its event
        ka, kb = _impacts(*lo, 300), _impacts(*hi, 300)
        n = min(ka.size, kb.size)
        j = int(np.flatnonzero(ka[:n] != kb[:n])[0]) + 1
        assert j == arc.step, i
        pair = sorted((int(ka[j - 1]), int(kb[j - 1])))
        if arc.kind == "chatter":
            assert SLIDING in pair
        elif arc.kind == "graze":
            assert pair == [0, 1]
        else:
            assert pair[0] >= 1 and pair[1] == pair[0] + 1 and SLIDING not in pair
        # the region's own word is on one side of the arc at its other traced points too
        for q in range(1, xs.size - 1, max(1, xs.size // 5)):
            assert arc.inside in {_text(*x, 300) for x in _off(xs, ys, q, SMALL)}, (i, q)
        checked += 1
    assert checked >= 20
    # the border points: most lie on an arc of their kind and step and are replaced
    assert len(ov["covered"]) == pts.sizes["point"] and sum(ov["covered"]) > 0.6 * pts.sizes["point"]


def test_traced_overlay_of_the_first_tongue_is_theorem_3_1():
    """The one word of the window, (1, 0^inf), is bounded by the chatter curve of
    Theorem 3.1 (to rounding) and the window; every chatter border point of the
    view lies on that arc and is replaced."""
    view = V.View(*TONGUE1, 60, 50, max_iter=300, overlays=("traced",))
    regions, _ = _run(V.trace_slices(view))
    assert [r.word.format(ascii=True) for r in regions] == ["(1, 0^inf)"]
    pts = V.view_border_points(view)
    ov = V.traced_overlay(view, regions, pts)
    arcs = ov["arcs"]
    chatter = [i for i, k in enumerate(arcs["kind"]) if k == "chatter"]
    assert len(chatter) == 1 and set(arcs["kind"]) == {"chatter", "window"}
    e, u = np.asarray(arcs["xs"][chatter[0]]), np.asarray(arcs["ys"][chatter[0]])
    assert e.min() == pytest.approx(0.6) and e.max() == pytest.approx(0.8) and e.size > 5
    np.testing.assert_allclose(u, math.sqrt(0.5) * (1 - e) / (1 + e), rtol=1e-13)
    i = chatter[0]
    assert (arcs["word_low"][i], arcs["word_high"][i], arcs["step"][i]) == ("(1, 0^inf)", NONE_WORD, 1)
    kinds = pts["kind"].values.astype(str)
    assert (kinds == "chatter").sum() > 20
    assert np.array_equal(np.asarray(ov["covered"]), kinds == "chatter")


def _app(view):
    from stairbounce.explorer.app import Explorer
    from stairbounce.explorer.scheduler import Scheduler

    sched = Scheduler(thread=False)  # nothing runs until the test runs slices
    app = Explorer(view, scheduler=sched)
    app.start()
    sched.run_all()
    return app, sched


def _borders_jobs(sched):
    return [j for j in sched._jobs if j.kind == "borders"]


def test_traced_mode_schedules_a_trace_a_new_view_cancels_it_and_arcs_replace_points():
    """(b) Turning the mode on queues one "borders" job (nothing is computed on the
    page's thread); its slices show the points, then "tracing borders: N of M
    words"; a new view cancels it and traces the new view, whose arcs replace
    the points they pass through; off clears the arcs, on again redraws them
    without a new job."""
    app, sched = _app(V.View(0.2, 0.3, 0.3, 0.4, 60, 50, max_iter=300))
    assert app.borders.arc_src.data["xs"] == [] and app.borders.border_src.data["e"] == []
    app.overlays.value = ["traced"]
    jobs = _borders_jobs(sched)
    assert len(jobs) == 1 and not jobs[0].started
    assert app.borders.arc_src.data["xs"] == [] and app.borders.border_src.data["e"] == []  # not computed yet
    assert "locating the border points" in app.status.object
    old = jobs[0]
    while not app.borders.border_src.data["e"]:  # the border points: their grid's scan, the pairs (bounded slices)
        assert "locating the border points" in app.status.object
        sched.run_next()
    n_points = len(app.borders.border_src.data["e"])
    assert n_points == V.view_border_points(app.view).sizes["point"] > 50
    assert "finding the words" in app.status.object
    while "finding the words" in app.status.object:  # the seed scan (bounded slices)
        sched.run_next()
    assert "tracing borders: 0 of " in app.status.object and " words (48 x 48 seeds)" in app.status.object
    sched.run_next()  # one word
    assert app.borders.arc_src.data["xs"] == [] and len(app.borders.border_src.data["e"]) == n_points
    # a new view (a pan to tongue 1's tip region) cancels the trace under way
    app._on_ranges(SimpleNamespace(x0=TONGUE1[0], x1=TONGUE1[1], y0=TONGUE1[2], y1=TONGUE1[3]))
    assert old.cancelled and old not in sched._jobs
    new = _borders_jobs(sched)
    assert len(new) == 1 and new[0] is not old
    render = [j for j in sched._jobs if j.kind == "render"]
    assert render and render[0].seq < new[0].seq  # the picture first
    sched.run_all()
    assert old.attained > 0 and sched.busy() is False
    arcs = app.borders.arc_src.data
    assert set(arcs["kind"]) == {"chatter", "window"}
    for xs, ys in zip(arcs["xs"], arcs["ys"]):  # only the new view's arcs
        assert TONGUE1[0] <= min(xs) and max(xs) <= TONGUE1[1] and TONGUE1[2] <= min(ys) and max(ys) <= TONGUE1[3]
    from stairbounce._colours import KIND_COLOURS

    assert arcs["color"] == [KIND_COLOURS[k] for k in arcs["kind"]]   # the one set of border colours
    pts = V.view_border_points(app.view)
    kinds = pts["kind"].values.astype(str)
    assert (kinds == "chatter").sum() > 20
    # the result replaces the points: the chatter points are on the arc, the others stay
    assert sorted(app.borders.border_src.data["kind"]) == sorted(kinds[kinds != "chatter"].tolist())
    status = app.status.object
    assert "traced borders: 1 word (48 x 48 seeds)" in status and "chatter 1" in status
    assert f"{(kinds == 'chatter').sum()} of {kinds.size} border points replaced by arcs" in status
    assert "overlays=traced" in app.history_out.text
    assert [i.label.value for i in app.legend.items] == [
        "traced borders between words: graze violet, edge pink, chatter dark green, window grey"]
    assert app.borders.note.visible and "Hover near an arc" in app.borders.note.object
    # off: no arcs, no points, no job; on again: drawn from what was traced, no new job
    app.overlays.value = []
    assert app.borders.arc_src.data["xs"] == [] and app.borders.border_src.data["e"] == [] and not _borders_jobs(sched)
    assert "traced borders" not in app.status.object
    app.overlays.value = ["traced"]
    assert not _borders_jobs(sched) and app.borders.arc_src.data["kind"] == arcs["kind"]
    assert "traced borders: 1 word" in app.status.object
    # the points alone: every point, no arcs
    app.overlays.value = ["borders"]
    assert app.borders.arc_src.data["xs"] == [] and len(app.borders.border_src.data["e"]) == kinds.size


def test_traced_mode_keeps_the_points_of_incomplete_words_and_says_when_it_fails(monkeypatch):
    """A word whose walk gave up keeps its border points and the status names it;
    a trace that fails leaves every point drawn and says so."""
    from stairbounce.explorer import app as A
    from stairbounce.explorer import borders_layer

    real = V.trace_slices

    def incomplete(view, side=V.TRACE_SIDE):
        regions, seen = _run(real(view, side))
        yield from seen
        regions[0].complete = False  # as if a walk around it had given up
        return regions

    monkeypatch.setattr(borders_layer, "trace_slices", incomplete)
    app, sched = _app(V.View(*TONGUE1, 60, 50, max_iter=300))
    app.overlays.value = ["traced"]
    sched.run_all()
    assert len(app.borders.border_src.data["e"]) == V.view_border_points(app.view).sizes["point"]
    assert "chatter" in app.borders.arc_src.data["kind"]
    assert "Incomplete (a walk gave up; their border points are kept): 1 word, (1, 0^inf)" in app.status.object

    def failing(view, side=V.TRACE_SIDE):
        yield 0, 3
        raise RuntimeError("the walk ran out of the domain")

    monkeypatch.setattr(borders_layer, "trace_slices", failing)
    app, sched = _app(V.View(*TONGUE1, 60, 50, max_iter=300))
    app.overlays.value = ["traced"]
    sched.run_all()
    assert app.borders.arc_src.data["xs"] == []
    assert len(app.borders.border_src.data["e"]) == V.view_border_points(app.view).sizes["point"]
    assert ("tracing borders failed: the walk ran out of the domain; the border points are shown"
            in app.status.object)


def test_png_export_draws_the_traced_arcs():
    """The PNG of a view with the traced arcs drawn differs from the one with the points only."""
    from PIL import Image
    import io

    from stairbounce.explorer.export import view_png

    view = V.View(*TONGUE1, 60, 50, max_iter=300, overlays=("traced",))
    ds = V.compute_view(view)
    regions, _ = _run(V.trace_slices(view))
    pts = V.view_border_points(view)
    ov = V.traced_overlay(view, regions, pts)
    keep = ~np.asarray(ov["covered"])
    points = {k: pts[k].values[keep].tolist() for k in ("e", "u", "kind")}
    with_arcs = view_png(ds, view, borders={"points": points, "arcs": ov["arcs"]})
    without = view_png(ds, view, borders={"points": points, "arcs": {"xs": [], "ys": [], "kind": []}})
    assert Image.open(io.BytesIO(with_arcs)).format == "PNG" and with_arcs != without
    # an arc drawn is pixels of the chatter colour in the image: more of them with the arcs
    from stairbounce._colours import KIND_COLOURS

    chatter = tuple(int(KIND_COLOURS["chatter"][i:i + 2], 16) for i in (1, 3, 5))
    red = [np.sum(np.all(np.asarray(Image.open(io.BytesIO(b)).convert("RGB"))[..., :3] == chatter, axis=-1))
           for b in (with_arcs, without)]
    assert red[0] > red[1] + 50


def test_hovering_near_a_traced_arc_reports_its_kind_step_and_both_words():
    """Issue 37: the arcs' hover answered only with the pointer exactly on a
    2 px line.  An invisible copy of the arcs, ARC_HOVER_PX wide (Bokeh
    hit-tests a line within half its width), carries a hover naming the
    arc's kind and step and the words on its two sides, from the same data
    as the drawn arcs; the legend says what the arcs are."""
    pytest.importorskip("panel", reason="panel is in the web extra")
    from bokeh.models import HoverTool, MultiLine

    from stairbounce.explorer import app as A
    from stairbounce.explorer import borders_layer

    from stairbounce.explorer.scheduler import Scheduler

    app = A.Explorer(V.View(0.0, 0.4, 0.3, 1.1, 60, 50, max_iter=300), scheduler=Scheduler(thread=False))
    hovers = [t for t in app.map_fig.tools if isinstance(t, HoverTool)
              and any(r.data_source is app.borders.arc_src for r in (t.renderers or []) if hasattr(r, "data_source"))]
    assert len(hovers) == 1
    [r] = hovers[0].renderers
    glyph = r.glyph
    assert isinstance(glyph, MultiLine) and glyph.line_alpha == 0.0 and glyph.line_width == borders_layer.ARC_HOVER_PX >= 10
    drawn = [x.glyph for x in app.map_fig.renderers if getattr(x, "data_source", None) is app.borders.arc_src
             and x.glyph.line_alpha != 0.0 and x.glyph.line_color == "color"]
    assert drawn and all(borders_layer.ARC_HOVER_PX >= 5 * g.line_width for g in drawn)  # the pointer may be off the line
    fields = " ".join(v for _, v in hovers[0].tooltips)
    for col in ("@kind", "@step", "@word_low", "@word_high"):
        assert col in fields
    assert A._OVERLAY_LEGEND["traced"].startswith("traced borders between words:")
    assert not app.borders.note.visible  # said under the map while the arcs are on
    app.overlays.value = ["traced"]
    assert app.borders.note.visible and "the exact borders between two words" in app.borders.note.object
    assert "the words on its two sides" in app.borders.note.object
