"""The explorer's "proven" overlay (issue 36, item 8; ``explorer/proven.py``).

The atlas it draws is :func:`stairbounce.certify`'s box for box (computed in
slices whose work is counted at the certifier's kernels, as the slices of the
other jobs are in tests/test_faults_round3.py), a proven word is drawn in the
scan's colour of that word (checked against the scan's own pixels, which are
an independent float computation), and a tap shows the certificate of the
box under the point, re-verified by the independent checker, or why it is
undecided.
"""

from __future__ import annotations

import importlib
from types import SimpleNamespace

import numpy as np
import pytest

import stairbounce as sb
from stairbounce.explorer import proven as P
from stairbounce.explorer import view as V

C = importlib.import_module("stairbounce.structure.certify")
K = importlib.import_module("stairbounce.structure._kernel")

# the Fig. 7 window (words, graze, chatter and Corollary 2.1 boxes), small and cheap
VIEW = V.View(0.155, 0.2138, 0.6, 0.658, 64, 48, max_iter=300, overlays=("proven",))


def test_depth_keeps_boxes_at_least_two_pixels():
    for w, h, depth in ((600, 600, 8), (64, 48, 4), (16, 16, 3), (1000, 1000, 8), (1000, 20, 3)):
        v = V.View(width=w, height=h)
        assert P.proven_depth(v) == depth
        assert min(w, h) / 2**depth >= P.MIN_BOX_PX and min(w, h) / 2**(depth + 1) < P.MIN_BOX_PX


def _meter(monkeypatch):
    """Potential map steps per call of the certifier's kernels, from their
    arguments: a box of a level BOX_WORK * max_iter, an itinerary computed
    again two corner steps per step."""
    calls = []

    def wrap(name, cost):
        orig = getattr(K, name)

        def wrapped(*a):
            calls.append(cost(*a))
            return orig(*a)

        monkeypatch.setattr(K, name, wrapped)

    wrap("_certify_level", lambda win, level, ii, jj, max_iter, *r: ii.size * P.BOX_WORK * max_iter)
    wrap("_itineraries", lambda win, level, ii, jj, max_iter, cap, form, offsets, out, *r: 2 * int(offsets[-1]))
    return calls


@pytest.mark.parametrize("max_iter, boxes", [(300, 40), (20, 2)])
def test_the_sliced_atlas_is_certify_s_box_for_box_in_bounded_slices(monkeypatch, max_iter, boxes):
    view = V.View(VIEW.e_lo, VIEW.e_hi, VIEW.u_lo, VIEW.u_hi, VIEW.width, VIEW.height, max_iter=max_iter)
    ref = sb.certify(e=(view.e_lo, view.e_hi), u=(view.u_lo, view.u_hi), depth=P.proven_depth(view),
                     max_iter=max_iter)
    # every itinerary is computed again at the end (certify keeps 32 steps per box): the batches of
    # that stage are exercised, and certify's own answer must not change
    monkeypatch.setattr(C, "_KEPT", 0)
    calls = _meter(monkeypatch)
    bound = boxes * P.BOX_WORK * max_iter
    gen = P.proven_slices(view, slice_work=bound)
    per_slice, stages = [], set()
    while True:
        n = len(calls)
        try:
            stage = next(gen)
        except StopIteration as stop:
            atlas = stop.value
            per_slice.append(sum(calls[n:]))
            break
        stages.add(stage[0])
        per_slice.append(sum(calls[n:]))
    # with max_iter 20 the itineraries (the no_slide_within boxes' 20 steps each) need batches of their own
    assert stages == ({"level", "itineraries"} if max_iter == 20 else {"level"})
    assert max(per_slice) <= bound and sum(per_slice) > 5 * bound  # bounded, and many slices of real work
    assert atlas.boxes.equals(ref.boxes)
    assert sb.verify(atlas).ok


def _explorer(view=VIEW):
    pytest.importorskip("panel", reason="panel is in the web extra")
    from stairbounce.explorer.app import Explorer
    from stairbounce.explorer.scheduler import Scheduler

    sched = Scheduler(thread=False)
    app = Explorer(view, scheduler=sched)
    app.start()
    return app, sched


def test_overlay_draws_the_atlas_in_the_scan_s_colours_with_its_key():
    app, sched = _explorer()
    sched.run_all()
    atlas = app._proven[1]
    d = app.proven_src.data
    assert len(d["left"]) == atlas.boxes.sizes["box"] > 100
    assert "proven overlay:" in app.status.object and "undecided (numerical)" in app.status.object
    note = app.proven_note.object
    assert app.proven_note.visible and "Undecided areas are numerical" in note
    assert f"depth {P.proven_depth(VIEW)}" in note and f"at least {P.MIN_BOX_PX} pixels" in note
    # every pixel centre inside a proven word box has the scan's colour of the box's fill, in every
    # colouring the overlay follows
    es, us = app.ds.e.values, app.ds.u.values
    labels = np.array(d["what"])
    for var in ("word_length", "period", "status"):
        app.color.value = var
        d = app.proven_src.data
        rgba = V.shade(app.ds, var)
        checked = 0
        for b in np.flatnonzero(np.char.startswith(labels.astype(str), "proven word")):
            cols = np.flatnonzero((es > d["left"][b]) & (es < d["right"][b]))
            rows = np.flatnonzero((us > d["bottom"][b]) & (us < d["top"][b]))
            if cols.size and rows.size:
                want = V._rgba32((d["fill"][b],))[0]
                assert np.all(rgba[np.ix_(rows, cols)] == want), (var, labels[b])
                checked += rows.size * cols.size
        assert checked > 200
    # undecided boxes hatched by reason; the proven non-sliding ones marked
    kinds = {w.split(": ")[-1] for w in labels if w.startswith("undecided")}
    assert kinds and kinds <= set(P.STYLES)
    for w, h in zip(labels, d["hatch"]):
        key = w.split(": ")[-1] if w.startswith("undecided") else w.split()[1] if w.startswith("proven ") else w
        key = "word" if w.startswith("proven word") else key
        assert h == P.STYLES[key][2]
    # off: nothing drawn, no key, no job left
    app.overlays.value = []
    assert app.proven_src.data["left"] == [] and not app.proven_note.visible
    assert "proven overlay" not in app.status.object


def test_tap_shows_the_certificate_of_the_box_or_why_it_is_undecided():
    app, sched = _explorer()
    app._on_tap(SimpleNamespace(x=0.18, y=0.62))  # tapped before the atlas is computed: shown when it is
    sched.run_all()
    e, u = app.view.point
    text = app.point_pane.object
    c = P.proven_at(app._proven[1], e, u)
    assert c["status"] == "word" and c["verdict"].ok
    (e0, e1), (u0, u1) = c["box"]
    assert e0 <= e <= e1 and u0 <= u <= u1
    w = sb.sliding_word(e, u, VIEW.max_iter)
    assert c["word"] == w.format(ascii=True)  # the float map agrees with the proven word at the point
    assert f"<b>{c['word']}</b>" in text and "proven by interval arithmetic, re-verified by sb.verify" in text
    assert f"box e [{e0:.10g}, {e1:.10g}]" in text and "max_iter 300" in text
    # the word's family by its form: (1, 1, 1, 2) is member 3 of (1^k, 2, 0^inf)
    assert "family (1^k, 2, 0^inf), member k = 3" in text
    # an undecided box: its reason, and no claim of proof
    boxes = app._proven[1].boxes
    b = int(np.flatnonzero((boxes["reason"].values == "graze"))[0])
    pe, pu = (float(boxes[a].values[b] + boxes[c_].values[b]) / 2 for a, c_ in (("e0", "e1"), ("u0", "u1")))
    app._on_tap(SimpleNamespace(x=pe, y=pu))
    sched.run_all()
    text = app.point_pane.object
    assert "<b>undecided</b> (numerical), reason <b>graze</b>" in text and "re-verified" not in text


def test_a_window_the_certifier_refuses_is_a_message_not_a_traceback():
    # e between 0 and 2^-53 is refused by name (the certifier's contract)
    app, sched = _explorer(V.View(1e-300, 1e-3, 0.5, 0.6, 16, 16, max_iter=50, overlays=("proven",)))
    sched.run_all()
    assert "certifying the view failed" in app.status.object and "2^-53" in app.status.object
