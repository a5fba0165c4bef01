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


def _image(app):
    """The proven overlay's picture as the page has it: (rgba, code, names)."""
    d = app.proven.src.data
    return d["image"][0], d["code"][0], app.proven.names.args["names"]


def test_overlay_draws_the_atlas_in_the_scan_s_colours_with_its_key():
    app, sched = _explorer()
    sched.run_all()
    atlas = app.proven.done[1]
    rgba, code, names = _image(app)
    assert rgba.shape == code.shape == (VIEW.height, VIEW.width)
    assert atlas.boxes.sizes["box"] > 100 and (code >= 0).all()  # the atlas covers the view
    assert "proven overlay:" in app.status.object and "undecided (numerical)" in app.status.object
    note = app.proven.note.object
    assert app.proven.note.visible and "Undecided areas are numerical" in note
    assert f"depth {P.proven_depth(VIEW)}" in note and f"at least {P.MIN_BOX_PX} pixels" in note
    # every pixel of a proven word box has the scan's colour of that pixel, in every colouring the
    # overlay follows (the picture is at the view's pixels: pixel (i, j) is the scan's pixel (i, j))
    for var in ("word_length", "period", "status"):
        app.color.value = var
        rgba, code, names = _image(app)
        word = np.isin(code, [k for k, w in enumerate(names) if w.startswith("proven word")])
        assert word.sum() > 200
        assert np.array_equal(rgba[word], V.shade(app.ds, var)[word]), var
    # the proven word at each word pixel is the float map's word at its centre, on a sample
    es, us = app.ds.e.values, app.ds.u.values
    rows, cols = np.nonzero(word)
    for k in np.linspace(0, rows.size - 1, 12).astype(int):
        i, j = rows[k], cols[k]
        assert names[code[i, j]] == "proven word " + sb.sliding_word(es[j], us[i], VIEW.max_iter).format(ascii=True)
    # undecided boxes: translucent white with their reason's hatch on top (the map shows through);
    # every label's pixels carry their style
    labels = {w: (w.split(": ")[-1] if w.startswith("undecided") else "word" if w.startswith("proven word")
                  else w.split()[1]) for w in names}
    assert {k for k in labels.values() if k in ("graze", "edge", "chatter", "nonsliding")}
    for k, w in enumerate(names):
        fill, alpha, hatch, hcol, _ = P.STYLES[labels[w]]
        px = rgba[code == k]
        hatched = px == V._rgba32((hcol,))[0]
        if hatch != " ":
            assert hatched.any() and (~hatched).any(), w
            assert np.all(px[~hatched] >> 24 == round(255 * alpha)), w
        if fill is not None:
            assert np.all(px[~hatched] & 0xFFFFFF == V._rgba32((fill,))[0] & 0xFFFFFF), w
    # off: nothing drawn, no key, no job left
    app.overlays.value = []
    assert app.proven.src.data["image"] == [] and not app.proven.note.visible
    assert "proven overlay" not in app.status.object


def test_the_picture_s_boxes_meet_without_gaps_and_hatching_runs_on():
    """proven_image: each box paints exactly the pixels whose centres it
    contains, a box of any size (the boxes of a quadtree meet on shared
    edges), and a hatch is the same lattice in every box (it runs on across
    neighbouring boxes of one reason)."""
    app, sched = _explorer()
    sched.run_all()
    atlas = app.proven.done[1]
    pic = P.proven_image(atlas, 50, 37)
    ds = atlas.boxes
    (e0, e1), (u0, u1) = atlas.window
    ce = e0 + (np.arange(50) + 0.5) * (e1 - e0) / 50
    cu = u0 + (np.arange(37) + 0.5) * (u1 - u0) / 37
    quads = P.proven_overlay(atlas)
    for b in range(0, ds.sizes["box"], 7):
        inside = np.outer((cu > ds["u0"].values[b]) & (cu < ds["u1"].values[b]),
                          (ce > ds["e0"].values[b]) & (ce < ds["e1"].values[b]))
        assert np.all(np.asarray(pic["names"])[pic["code"][inside]] == quads["what"][b])
    masks = P._hatch_masks(37, 50)
    assert masks["/"][0, 0] and masks["/"][1, 1] and not masks["/"][1, 0]  # rises to the right, row 0 at the bottom
    with pytest.raises(ValueError, match="width and height"):
        P.proven_image(atlas, 0, 10)


def test_tap_shows_the_certificate_of_the_box_or_why_it_is_undecided():
    app, sched = _explorer()
    app._on_tap(SimpleNamespace(x=0.18, y=0.62))  # tapped before the atlas is computed: shown when it is
    sched.run_all()
    e, u = app.view.point
    text = app.point_pane.object
    c = P.proven_at(app.proven.done[1], e, u)
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
    boxes = app.proven.done[1].boxes
    b = int(np.flatnonzero((boxes["reason"].values == "graze"))[0])
    pe, pu = (float(boxes[a].values[b] + boxes[c_].values[b]) / 2 for a, c_ in (("e0", "e1"), ("u0", "u1")))
    app._on_tap(SimpleNamespace(x=pe, y=pu))
    sched.run_all()
    text = app.point_pane.object
    assert "<b>undecided</b> (numerical), reason <b>graze</b>" in text and "re-verified" not in text


def test_a_view_from_e_0_taps_a_proven_box_on_e_0():
    # the boxes touching e = 0 are certified (the corners form on [0, e1]): a tap there
    # shows the certificate, re-verified; (1, 0^inf) is the word of the impact-by-impact
    # loop at e = 0 for u < 1/sqrt(2) (a plastic ball slides on its first landing)
    from . import naive

    app, sched = _explorer(V.View(0.0, 0.333, 0.4, 0.733, 64, 48, max_iter=300, overlays=("proven",)))
    sched.run_all()
    boxes = app.proven.done[1].boxes
    at_zero = boxes["e0"].values == 0.0
    assert at_zero.any() and "range" not in set(boxes["reason"].values.tolist())
    app._on_tap(SimpleNamespace(x=1e-4, y=0.5))
    sched.run_all()
    c = P.proven_at(app.proven.done[1], *app.view.point)
    assert c["box"][0][0] == 0.0 and c["status"] == "word" and c["verdict"].ok
    assert c["word"] == "(1, 0^inf)" and naive.word(0.0, 0.5) == (1,)
    assert "proven by interval arithmetic, re-verified by sb.verify" in app.point_pane.object


def test_a_window_the_certifier_refuses_is_a_message_not_a_traceback():
    # e between 0 and 2^-53 is refused by name (the certifier's contract)
    app, sched = _explorer(V.View(1e-300, 1e-3, 0.5, 0.6, 16, 16, max_iter=50, overlays=("proven",)))
    sched.run_all()
    assert "certifying the view failed" in app.status.object and "2^-53" in app.status.object


def test_a_long_certificate_is_deferred_with_a_message_and_the_worker_stays_free(monkeypatch):
    """Issue 43 item 3: a tap on a box proven not to slide within a max_iter
    above TAP_CERTIFICATE_STEPS does not walk its certificate on the shared
    worker (certify_box and sb.verify are Python loops: 57-133 s at max_iter
    1e6); the tap says so and gives the Python line that computes it, which
    does.  A second page on the same scheduler gets its picture, and no
    certify_box call of the explorer walks more than the bound."""
    walked = []
    real = C.certify_box

    def counting(*args, **kw):
        walked.append(kw.get("max_iter", args[2] if len(args) > 2 else 1000))
        return real(*args, **kw)

    monkeypatch.setattr(C, "certify_box", counting)
    max_iter = 4 * P.TAP_CERTIFICATE_STEPS
    deep = V.View(0.2995, 0.29950000000002, 0.4135, 0.41350000000002, 16, 16, max_iter=max_iter,
                  overlays=("proven",), point=(0.299500000000006, 0.413500000000006))
    app, sched = _explorer(deep)
    from stairbounce.explorer.app import Explorer

    victim = Explorer(V.View(0.0, 1.0, 0.0, 1.5, 32, 32, max_iter=200), scheduler=sched)
    victim.start()
    sched.run_all()
    assert "computed in" in victim.status.object
    atlas = app.proven.done[1]
    c = P.proven_at(atlas, *deep.point, max_steps=P.TAP_CERTIFICATE_STEPS)
    assert c["status"] == "no_slide_within" and c["deferred"] == max_iter and c["certificate"] is None
    text = app.point_pane.object
    assert "not computed here" in text and f"{max_iter:,} steps" in text and "re-verified" not in text
    assert max(walked, default=0) <= P.TAP_CERTIFICATE_STEPS
    # the line the page gives computes the certificate of exactly that box, and it verifies
    import html
    import re

    code = html.unescape(re.search(r'<code class="sb-cert-code">(.*?)</code>', text).group(1))
    assert code.startswith("sb.verify(sb.certify_box(") and code.endswith(f"max_iter={max_iter}))")
    cert = eval(code[len("sb.verify("):-1], {"sb": sb})
    assert (cert.e, cert.u) == c["box"] and cert.status == "no_slide_within" and sb.verify(cert).ok


def test_proven_at_defers_exactly_the_certificates_longer_than_the_bound():
    app, sched = _explorer()
    sched.run_all()
    atlas = app.proven.done[1]
    ds = atlas.boxes
    b = int(np.flatnonzero(ds["status"].values == 0)[0])  # a proven word
    n = P.certificate_steps(atlas, b)
    assert n == len(sb.certify_box(e=(float(ds["e0"][b]), float(ds["e1"][b])), u=(float(ds["u0"][b]), float(ds["u1"][b])),
                                   max_iter=atlas.max_iter).itinerary) > 0
    e, u = float(ds["e0"][b] + ds["e1"][b]) / 2, float(ds["u0"][b] + ds["u1"][b]) / 2
    assert P.proven_at(atlas, e, u, max_steps=n)["certificate"].status == "word"
    late = P.proven_at(atlas, e, u, max_steps=n - 1)
    assert late["deferred"] == n and late["certificate"] is None and late["word"]
    with pytest.raises(ValueError, match="max_steps"):
        P.proven_at(atlas, e, u, max_steps=-1)
