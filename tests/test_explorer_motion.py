"""The explorer's non-sliding motion (issue 13): colouring by <k> and lambda_1,
and the tap panel's <k>, exponents and Poincare section."""

from __future__ import annotations

from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from stairbounce import model
from stairbounce.explorer import view as V
from stairbounce.nonsliding import motion, motion_coords
from stairbounce.plane import pixel_centres

VIEW = V.View(0.0, 1.0, 0.0, 1.5, 40, 30, max_iter=200)


@pytest.mark.parametrize("var", V.MOTION_COLOR_VARS)
def test_motion_colours_come_from_motion_coords(var):
    view = replace(VIEW, color=var)
    ds = V.compute_view(view)
    ref = motion_coords(pixel_centres(0, 1, 40), pixel_centres(0, 1.5, 30), steps=200, transient=200)
    np.testing.assert_array_equal(ds[var].values, ref[var].values)
    assert V.has_color(ds, var) and not V.has_color(V.compute_view(VIEW), var)
    cls = V.classes(ds, var)
    key = V.color_key(var)
    slid = ref.slide_step.values > 0
    assert np.all(cls[slid] == 0) and key.labels[0] == "slides"  # grey
    assert np.all((cls[~slid] >= 1) & (cls[~slid] < len(key.colors)))
    if var == "k_mean":
        # a larger <k> never gets a lower colour: the key is monotone
        k = ref.k_mean.values[~slid]
        order = np.argsort(k)
        assert np.all(np.diff(cls[~slid][order]) >= 0)
    assert V.shade(ds, var).shape == (30, 40)


def test_point_details_of_a_non_sliding_point_has_k_exponents_and_section():
    d = V.point_details(0.5, 0.8, 300)
    assert d["word"] is None
    r = motion(0.5, 0.8, steps=300, transient=300)
    assert d["motion"]["k_mean"] == r["k_mean"] and d["motion"]["lyap1"] == r["lyap1"]
    ys, vs, _ = model.iterate(1.0, 0.0, 0.5, 0.8, 600)
    np.testing.assert_array_equal(d["section"][0], ys[-300:])
    np.testing.assert_array_equal(d["section"][1], vs[-300:])
    assert V.point_details(0.1, 0.2, 300)["motion"] is None  # slides: the word is shown


def test_explorer_colours_by_k_and_shows_the_motion_on_tap():
    from stairbounce.explorer.app import Explorer

    from .test_explorer import InlineScheduler

    ex = InlineScheduler()
    app = Explorer(VIEW, scheduler=ex)
    app.start()
    app.color.value = "k_mean"  # needs the motion fields: recomputed
    assert ex.calls == ["render", "render"]
    np.testing.assert_array_equal(app.img_src.data["image"][0], V.shade(app.ds, "k_mean"))
    assert app.colorbar.major_label_overrides[0] == "slides"
    # the labelled colours only, on the ticker the page draws (it ignores a new one)
    assert list(app.colorbar.ticker.ticks) == V.color_key("k_mean").ticks == [0, 9, 25, 41, 57]
    assert "the orbit of (1, 0) slides" in app.key_note.object
    app.color.value = "lyap1"  # already there: reshaded only
    assert ex.calls == ["render", "render"]
    np.testing.assert_array_equal(app.img_src.data["image"][0], V.shade(app.ds, "lyap1"))
    app._on_tap(SimpleNamespace(x=0.6, y=1.0))
    e, u = app.view.point
    r = motion(e, u, steps=200, transient=200)
    assert f'{r["k_mean"]:.6g}</span> impacts per step' in app.point_pane.object
    assert "&lambda;<sub>1</sub>" in app.point_pane.object
    assert len(app.section_src.data["x"]) == 200
