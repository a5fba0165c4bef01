"""Server side of ``stairbounce explore``: URL validation, renders, budgets, exports.

The page logic (:class:`stairbounce.explorer.app.Explorer`) is driven here
without a browser, its worker replaced by one that runs at once; the real
browser is in ``test_explorer_browser.py``.
"""

from __future__ import annotations

import io
import math
import socket
import tempfile
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st

from stairbounce import no_sliding_bound, plane, sliding_word, tongue
from stairbounce.cli import main
from stairbounce.explorer import view as V
from tests import naive

pn = pytest.importorskip("panel", reason="panel is in the web extra")


# --------------------------------------------------------------------------- #
# URL query                                                                   #
# --------------------------------------------------------------------------- #


def test_empty_query_is_the_figure_4_window():
    view, messages = V.parse_query({})
    assert view == V.DEFAULT_VIEW and messages == []
    assert (view.e_lo, view.e_hi, view.u_lo, view.u_hi) == (0.0, 1.0, 0.0, 1.5)
    assert (view.width, view.height, view.max_iter) == (600, 600, 1000)


def test_query_as_panel_gives_it():
    """Panel's session_args: lists of bytes; a repeated parameter keeps the last."""
    args = {"e": [b"0.04:0.065"], "u": [b"0:1", b"0.92:0.945"], "size": [b"400x300"],
            "max_iter": [b"5000"], "color": [b"period"], "overlays": [b"no_sliding"],
            "point": [b"0.05,0.93"]}
    view, messages = V.parse_query(args)
    assert messages == []
    assert view == V.View(0.04, 0.065, 0.92, 0.945, 400, 300, 5000, "period", ("no_sliding",),
                          (0.05, 0.93))


@pytest.mark.parametrize(
    "name, value, words",
    [
        ("e", "abc", ["e=", "LO:HI"]),
        ("e", "0.5:0.2", ["e=", "LO < HI"]),
        ("e", "-0.1:0.5", ["e=", "0 <= LO"]),
        ("e", "0:1.5", ["e=", "<= 1"]),
        ("e", "0:nan", ["e=", "finite"]),
        ("u", "0:1e9", ["u=", "<= 50"]),
        ("u", "1", ["u=", "LO:HI"]),
        ("size", "600", ["size=", "WIDTHxHEIGHT"]),
        ("size", "8x8", ["size=", "at least"]),
        ("size", "2000x1000", ["size=", "pixel budget", "1000000"]),
        ("max_iter", "0", ["max_iter=", "[1, "]),
        ("max_iter", "1.5", ["max_iter=", "integer"]),
        ("color", "rainbow", ["color=", "word_length"]),
        ("overlays", "tongues,grid", ["overlays=", "no_sliding"]),
        ("point", "1.2,0.5", ["point=", "[0, 1)"]),
        ("point", "0.5", ["point=", "E,U"]),
        ("bogus", "1", ["unknown", "bogus"]),
    ],
)
def test_bad_query_values_give_a_message_and_the_default(name, value, words):
    view, messages = V.parse_query({name: value})
    assert len(messages) == 1
    for w in words:
        assert w in messages[0]
    assert view == V.DEFAULT_VIEW  # the default replaces the bad value, the rest is kept
    V.check_view(view)


def test_bad_values_do_not_spoil_good_ones():
    view, messages = V.parse_query({"e": "0:0.3", "u": "oops", "max_iter": "200", "size": "1x1"})
    assert len(messages) == 2
    assert (view.e_lo, view.e_hi, view.max_iter) == (0.0, 0.3, 200)
    assert (view.u_lo, view.u_hi, view.width) == (0.0, 1.5, 600)


def test_query_over_the_work_budget_falls_back_to_default_max_iter():
    view, messages = V.parse_query({"size": "1000x1000", "max_iter": str(V.MAX_ITER_LIMIT)})
    assert view.max_iter == V.DEFAULT_VIEW.max_iter and (view.width, view.height) == (1000, 1000)
    assert len(messages) == 1 and "work budget" in messages[0]


def test_query_deeper_than_float64_falls_back_to_the_figure_4_window():
    x = 0.5
    view, messages = V.parse_query({"e": f"{x!r}:{np.nextafter(x, 1.0)!r}"})
    assert len(messages) == 1 and "float64" in messages[0]
    assert (view.e_lo, view.e_hi) == (0.0, 1.0)


windows = st.tuples(st.floats(0, 1), st.floats(0, 1)).filter(lambda t: t[1] - t[0] > 1e-6)


@settings(max_examples=200, deadline=None)
@given(
    e=windows,
    u=st.tuples(st.floats(0, 50), st.floats(0, 50)).filter(lambda t: t[1] - t[0] > 1e-4),
    w=st.integers(16, 1000),
    h=st.integers(16, 1000),
    max_iter=st.integers(1, 5000),
    color=st.sampled_from(V.COLOR_VARS),
    overlays=st.sampled_from([(), ("tongues",), ("no_sliding",), ("tongues", "no_sliding")]),
    point=st.none() | st.tuples(st.floats(0, 0.999999), st.floats(1e-6, 50)),
)
def test_view_query_reads_back_exactly(e, u, w, h, max_iter, color, overlays, point):
    view = V.View(e[0], e[1], u[0], u[1], w, h, max_iter, color, overlays, point)
    if view.pixels > V.PIXEL_BUDGET:
        return
    back, messages = V.parse_query(V.view_query(view))
    assert messages == []
    assert back == view  # floats survive bit for bit: deep zooms can be shared


def test_url_query_string():
    q = V.view_url_query(V.View(0.04, 0.065, 0.92, 0.945, 400, 300))
    assert q.startswith("?e=0.04:0.065&u=0.92:0.945&size=400x300&max_iter=1000")


# --------------------------------------------------------------------------- #
# Budgets and computation                                                     #
# --------------------------------------------------------------------------- #


def test_pixel_budget_refuses_without_computing(monkeypatch):
    calls = []
    monkeypatch.setattr(plane, "scan_coords", lambda *a, **k: calls.append(a))
    big = replace(V.DEFAULT_VIEW, width=1001, height=1000, max_iter=10)
    with pytest.raises(ValueError, match="pixel budget of 1000000"):
        V.compute_view(big)
    over_work = replace(V.DEFAULT_VIEW, width=1000, height=1000, max_iter=V.WORK_BUDGET // 10**6 + 1)
    with pytest.raises(ValueError, match="work budget"):
        V.compute_view(over_work)
    assert calls == []
    V.check_view(replace(V.DEFAULT_VIEW, width=1000, height=1000))  # exactly the budget is fine


def test_check_view_limits():
    with pytest.raises(ValueError, match="e window"):
        V.check_view(V.View(e_lo=0.5, e_hi=0.5))
    with pytest.raises(ValueError, match="u window"):
        V.check_view(V.View(u_lo=0.0, u_hi=51.0))
    with pytest.raises(ValueError, match="too narrow"):
        V.check_view(V.View(u_lo=1.0, u_hi=1.0 + 1e-14))
    with pytest.raises(ValueError, match="color"):
        V.check_view(V.View(color="nope"))
    V.check_view(V.View(u_lo=1.0, u_hi=1.0 + 1e-11))  # 600 pixels of ~2e-14: still resolved


def test_compute_view_is_the_scan_bit_for_bit():
    view = V.View(0.0, 1.0, 0.0, 1.5, 120, 90, max_iter=400)
    ref = plane.scan(e=(0.0, 1.0, 120), u=(0.0, 1.5, 90), max_iter=400)
    for band_work in (10**12, 120 * 400 * 7):  # one band, bands of 7 rows
        old = V.SLICE_WORK
        V.SLICE_WORK = band_work
        try:
            ds = V.compute_view(view)
        finally:
            V.SLICE_WORK = old
        xr.testing.assert_identical(ds.drop_attrs(), ref.drop_attrs())
        for k in ("e_min", "e_max", "n_e", "u_min", "u_max", "n_u", "max_iter", "convention"):
            assert ds.attrs[k] == ref.attrs[k]


def test_compute_view_cancels_between_bands_and_reports_progress(monkeypatch):
    monkeypatch.setattr(V, "SLICE_WORK", 50 * 100 * 10)  # 10 rows per band
    view = V.View(0.0, 1.0, 0.0, 1.5, 50, 40, max_iter=100)
    seen = []
    V.compute_view(view, progress=lambda done, total: seen.append((done, total)))
    assert seen == [(10, 40), (20, 40), (30, 40), (40, 40)]
    asked = []

    def cancelled():
        asked.append(1)
        return len(asked) > 2

    with pytest.raises(V.Cancelled):
        V.compute_view(view, cancelled=cancelled)
    assert len(asked) == 3


def test_progressive_render_previews_then_gives_the_scan_bit_for_bit():
    """The coarse preview holds the exact values of every 8th pixel; each
    preview picture shows the finished rows exactly; the end is the scan."""
    view = V.View(0.0, 1.0, 0.0, 1.5, 83, 61, max_iter=400)
    ref = plane.scan(e=(0.0, 1.0, 83), u=(0.0, 1.5, 61), max_iter=400)
    gen = V.render_slices(view, slice_work=83 * 400 * 16, preview_work=0)
    parts = []
    while True:
        try:
            parts.append(next(gen))
        except StopIteration as stop:
            ds = stop.value
            break
    assert [p.rows_done for p in parts] == [0, 16, 32, 48]  # the preview, then bands of 16 rows
    coarse = parts[0].coarse
    sub = ref.isel(e=slice(4, None, 8), u=slice(4, None, 8))
    np.testing.assert_array_equal(coarse["word_length"].values, sub["word_length"].values)
    xr.testing.assert_identical(ds.drop_attrs(), ref.drop_attrs())
    full = V.shade(ref, "period")
    for p in parts:
        img = V.preview_rgba(p, "period")
        assert img.shape == (61, 83)
        np.testing.assert_array_equal(img[: p.rows_done], full[: p.rows_done])
        # the coarse sample's own pixel always shows its exact colour
        np.testing.assert_array_equal(img[4::8, 4::8], full[4::8, 4::8])
    # a small view skips the preview
    small = list(V.render_slices(V.View(0, 1, 0, 1.5, 40, 40, max_iter=10), slice_work=40 * 10 * 8))
    assert [p.rows_done for p in small] == [8, 16, 24, 32] and all(p.coarse is None for p in small)


def test_window_digits_tell_the_ends_apart():
    for lo, hi, n in ((0.0525, 0.0525 + 1e-9, 600), (0.0, 1.0, 600), (0.3, 0.3 + 4e-14, 100)):
        d = V.window_digits(lo, hi, n)
        a, b = V.format_number(lo, d), V.format_number(hi, d)
        assert a != b
        # one pixel is resolved: the text of the second pixel centre differs from the first
        step = (hi - lo) / n
        assert V.format_number(lo + 0.5 * step, d) != V.format_number(lo + 1.5 * step, d)
    assert V.format_number(0.1, 9) == "0.1"


def test_tidy_removes_float_noise_within_tolerance():
    assert V.tidy(0.9200000000000002, 1e-12) == 0.92
    assert V.tidy(0.19999999999999996, 1e-12) == 0.2
    x = 0.052500001234
    assert V.tidy(x, 0.0) == x and abs(V.tidy(x, 1e-6) - x) <= 1e-6


def test_map_agrees_with_sliding_word_at_pixel_centres():
    view = V.View(0.0, 0.4, 0.3, 1.1, 40, 40, max_iter=300)
    ds = V.compute_view(view)
    rng = np.random.default_rng(7)
    for i, j in rng.integers(0, 40, size=(60, 2)):
        e, u = float(ds.e[j]), float(ds.u[i])
        w = sliding_word(e, u, max_steps=300)
        assert (w is None) == (ds.status.values[i, j] == 1)
        if w is not None:
            assert ds.word_length.values[i, j] == len(w)
            assert ds.period.values[i, j] == w.period


def test_pixel_of_inverts_pixel_centres():
    view = V.View(0.1, 0.3, 0.5, 0.9, 37, 23)
    es = plane.pixel_centres(0.1, 0.3, 37)
    us = plane.pixel_centres(0.5, 0.9, 23)
    for i in range(23):
        for j in range(37):
            assert V.pixel_of(view, es[j], us[i]) == (i, j)
    assert V.pixel_of(view, 0.3, 0.9) == (22, 36)
    assert V.pixel_of(view, 0.05, 0.6) is None


# --------------------------------------------------------------------------- #
# Colours, overlays, the tapped point                                          #
# --------------------------------------------------------------------------- #


def test_colour_classes():
    key = V.color_key("word_length")
    assert key.labels[:7] == ("1", "2", "3", "4", "5", "6-7", "8-10")
    assert key.labels[-1] == ">= 501" and key.colors[0] == "#000000"
    assert len(set(key.colors)) == len(key.colors) and V.NO_SLIDING_COLOR not in key.colors
    assert V.color_key("impacts").labels[:2] == ("0", "1")
    ds = xr.Dataset({
        "status": (("u", "e"), np.array([[0, 0, 0, 0, 1]])),
        "word_length": (("u", "e"), np.array([[1, 6, 7, 8, 0]])),
    })
    assert V.classes(ds, "word_length").tolist() == [[0, 5, 5, 6, -1]]
    rgba = V.shade(ds, "word_length")
    assert rgba.dtype == np.uint32 and rgba.shape == (1, 5)
    assert rgba[0, 0] == 0xFF000000  # opaque black: the tongues, as in Fig. 4
    assert rgba[0, 4] == 0xFFFFFFFF  # white: no sliding solution
    assert rgba[0, 1] == rgba[0, 2] != rgba[0, 3]
    assert V.shade(ds, "status").tolist() == [[0xFF000000] * 4 + [0xFFFFFFFF]]
    with pytest.raises(ValueError, match="color"):
        V.color_key("nope")


def test_tongue_overlay_follows_theorem_3_1():
    view = V.View(0.0, 1.0, 0.0, 1.5)
    curves = V.overlay_curves(view, samples=200)
    xs, ys = curves["tongues"]
    assert len(xs) == 5  # u_low = sqrt((n-1)/2) < 1.5 for n = 1..5
    for n, (x, y) in enumerate(zip(xs, ys), start=1):
        half = x.size // 2
        u_low, _ = tongue(n, 0.0)
        np.testing.assert_allclose(y[half:], u_low)  # the bottom edge
        for e, u in zip(x[:half], y[:half]):  # the top edge: u_high(e)
            if e == 1.0:  # the first tongue's tip, a limit: e < 1
                assert u == 0.0
                continue
            assert math.isclose(u, tongue(n, float(e))[1], rel_tol=1e-12, abs_tol=1e-12)
        # closed at the tip, where the two bounds of (3.1) meet
        assert math.isclose(y[half - 1], u_low, abs_tol=1e-12)
    (ex,), (ey,) = curves["no_sliding"]
    for e, u in zip(ex[::17], ey[::17]):
        assert math.isclose(u, no_sliding_bound(float(e)), rel_tol=1e-12)


def test_overlay_of_a_deep_window_has_only_the_tongues_that_meet_it():
    def tongues(view):
        _, ys = V.overlay_curves(view)["tongues"]
        return sorted(round(2 * float(y[-1]) ** 2) + 1 for y in ys)  # n from u_low

    # Fig. 5 c): only the third tongue, u_low = 1 (the second one ends at u = 1, sqrt(3/2) > 1.22)
    assert tongues(V.View(0.0, 0.1, 1.0, 1.22)) == [3]
    assert tongues(V.View(0.0, 0.1, 1.0, 1.3)) == [3, 4]
    assert tongues(V.View(0.5, 1.0, 1.0, 1.3)) == []  # the tongues end before e = 0.5


def test_point_details_match_the_word_and_the_trajectory():
    # inside the (2, 0^inf) tongue of Theorem 3.1 at e = 0.1
    lo, hi = tongue(2, 0.1)
    d = V.point_details(0.1, (lo + hi) / 2, 1000)
    assert d["word"] == sliding_word(0.1, (lo + hi) / 2, 1000)
    assert d["word"].letters == (2,)
    assert d["steps"] == 4
    x, y = d["path"]
    assert x[0] == 0.0 and y[0] == 1.0  # starts at (1, 0) on the edge of step 0
    assert np.all(np.diff(x) >= 0) and x[-1] == pytest.approx(4.0)
    assert len(d["slides"]) == 2 and len(d["accumulations"][0]) == 2
    # a point with a longer word: the same word as the impact-by-impact reference
    w = naive.word(0.0806666, 0.6533333, 500)
    d = V.point_details(0.0806666, 0.6533333, 500)
    assert d["word"] == sliding_word(0.0806666, 0.6533333, 500)
    assert w is not None and len(w) > 10
    assert d["word"].letters == w
    assert V.point_details(0.05, 5.0, 200)["word"] is None  # above Cor. 2.1: no sliding


def test_orbit_along_u_is_the_orbit_diagram():
    ds = V.orbit_along_u(0.1, 0.5, 1.0, n=20, transient=50, keep=10)
    assert ds.sizes == {"u": 20, "iterate": 10}
    np.testing.assert_array_equal(ds.u.values, plane.pixel_centres(0.5, 1.0, 20))
    assert float(ds.e) == 0.1


# --------------------------------------------------------------------------- #
# Exports                                                                     #
# --------------------------------------------------------------------------- #


def test_exports_png_and_netcdf():
    from PIL import Image

    from stairbounce.explorer.export import export_name, view_netcdf, view_png

    view = V.View(0.0, 1.0, 0.0, 1.5, 120, 80, max_iter=200)
    ds = V.compute_view(view)
    png = view_png(ds, view)
    img = Image.open(io.BytesIO(png))
    assert img.format == "PNG" and img.width > 120 and img.height > 80
    data = view_netcdf(ds)
    assert data[:4] == b"\x89HDF"  # netCDF4 is HDF5
    with tempfile.TemporaryDirectory() as tmp:
        p = Path(tmp) / "v.nc"
        p.write_bytes(data)
        loaded = plane.load(p)
    xr.testing.assert_identical(loaded.drop_attrs(), ds.drop_attrs())
    assert export_name(view, ".nc") == "stairbounce_e0-1_u0-1.5.nc"


# --------------------------------------------------------------------------- #
# The page logic, without a browser                                           #
# --------------------------------------------------------------------------- #


from stairbounce.explorer.scheduler import Scheduler  # noqa: E402


class InlineScheduler(Scheduler):
    """Runs submitted work to its end at once and records its kind."""

    def __init__(self):
        super().__init__(thread=False)
        self.calls = []

    def submit(self, owner, kind, work, **kw):
        self.calls.append(kind)
        job = super().submit(owner, kind, work, **kw)
        self.run_all()
        return job


@pytest.fixture
def explorer():
    from stairbounce.explorer.app import Explorer

    ex = InlineScheduler()
    app = Explorer(V.View(0.0, 0.4, 0.3, 1.1, 60, 50, max_iter=300), scheduler=ex)
    app.start()
    return app, ex


def _type_window(app, e=None, u=None):
    """Type into the window boxes (live text, as the browser syncs it), then Enter."""
    if e is not None:
        app.e_window.value_input = e
    if u is not None:
        app.u_window.value_input = u
    app._on_window_text()


def test_explorer_renders_the_view(explorer):
    app, ex = explorer
    assert ex.calls == ["render"]
    img = app.img_src.data["image"][0]
    assert img.shape == (50, 60) and img.dtype == np.uint32
    np.testing.assert_array_equal(img, V.shade(app.ds, "word_length"))
    assert "computed in" in app.status.object and "60 x 50 pixels" in app.status.object
    assert app.e_window.value == "0:0.4" and app.u_window.value == "0.3:1.1"
    assert len(app.tongue_src.data["xs"]) >= 2 and len(app.bound_src.data["xs"]) == 1


def test_explorer_follows_a_zoom(explorer):
    app, ex = explorer
    app._on_ranges(SimpleNamespace(x0=0.05, x1=0.15, y0=0.6, y1=0.7))
    assert app.shown.e_lo == 0.05 and app.shown.u_hi == 0.7
    assert app.e_window.value == "0.05:0.15" and app.u_window.value == "0.6:0.7"
    assert float(app.ds.e.min()) > 0.05 and float(app.ds.u.max()) < 0.7
    _type_window(app, e="0.2:0.3")  # typed in: the plot's range moves too
    assert app.map_fig.x_range.start == 0.2 and app.shown.e_hi == 0.3


def test_explorer_refuses_a_view_over_budget(explorer):
    app, ex = explorer
    app.width_in.value = 1000  # 1000 x 50: computed
    assert len(ex.calls) == 2 and app.shown.width == 1000
    app.height_in.value = 1001  # 1000 x 1001: refused, not computed
    assert len(ex.calls) == 2
    assert app.view.height == 50 and app.shown.height == 50
    assert "pixel budget" in app.status.object and "sb-error" in app.status.object
    _type_window(app, e="0.3:0.1")
    assert "e window must satisfy" in app.status.object
    assert len(ex.calls) == 2 and app.shown.e_lo == 0.0


def test_explorer_tap_shows_the_word(explorer):
    app, ex = explorer
    app._on_tap(SimpleNamespace(x=0.1, y=0.75))
    e, u = app.view.point
    assert (e, u) != (0.1, 0.75)  # snapped to the tapped pixel's centre
    assert e in app.ds.e.values and u in app.ds.u.values
    w = sliding_word(e, u, 300)
    assert w.format() in app.point_pane.object
    assert f"period {w.period} step" in app.point_pane.object
    assert len(app.path_src.data["x"]) > 100 and app.orbit_marker.location == u
    assert len(app.orbit_src.data["x"]) == 300 * 200
    app._on_tap(SimpleNamespace(x=0.99, y=0.2))  # outside the window: taken as it is
    assert app.view.point == (0.99, 0.2)


def test_explorer_colour_change_reshades_without_recomputing(explorer):
    app, ex = explorer
    n = len(ex.calls)
    app.color.value = "status"
    assert len(ex.calls) == n
    np.testing.assert_array_equal(app.img_src.data["image"][0], V.shade(app.ds, "status"))
    assert app.colorbar.major_label_overrides == {0: "found", 1: "none within max_iter"}
    assert app.mapper.palette == ["#000000", "#ffffff"]


def test_colour_key_says_what_white_means(explorer):
    """Defect 7: white is 'no periodic sliding solution within max_iter', in
    the key of every variable, drawn with a border, and unlike the
    not-yet-computed background."""
    app, _ = explorer
    for var in V.COLOR_VARS:
        app.color.value = var
        labels = app.colorbar.major_label_overrides
        last = max(labels)
        assert labels[last] == "none within max_iter"
        assert app.mapper.palette[last] == V.NO_SLIDING_COLOR == "#ffffff"
        assert len(app.mapper.palette) == len(labels)
        # the no-sliding pixels of the image are that colour
        img = app.img_src.data["image"][0]
        none = app.ds["status"].values != 0
        assert none.any() and (img[none] == V._rgba32(["#ffffff"])[0]).all()
    assert app.colorbar.bar_line_color == "black"
    assert app.map_fig.background_fill_color.lower() != "#ffffff"
    assert "white: no periodic sliding solution within max_iter" in app.key_note.object


def test_every_colour_variable_is_offered():
    from stairbounce.explorer.app import _COLOR_OPTIONS, _OVERLAY_OPTIONS

    assert sorted(_COLOR_OPTIONS.values()) == sorted(V.COLOR_VARS)
    assert sorted(_OVERLAY_OPTIONS.values()) == sorted(V.OVERLAYS)


def test_explorer_downloads(explorer):
    app, _ = explorer
    import asyncio

    assert asyncio.run(app._png()).getvalue()[:8] == b"\x89PNG\r\n\x1a\n"
    assert asyncio.run(app._netcdf()).getvalue()[:4] == b"\x89HDF"


def test_create_app_reports_url_messages(monkeypatch):
    from stairbounce.explorer import app as A

    view, messages = V.parse_query({"size": "5000x5000"})
    ex = A.Explorer(view, messages, scheduler=InlineScheduler())
    assert ex.url_messages.visible and "pixel budget" in ex.url_messages.object


# --------------------------------------------------------------------------- #
# Command line                                                                #
# --------------------------------------------------------------------------- #


@pytest.mark.parametrize("args, words", [
    (["--port", "70000"], ["--port", "65535"]),
    (["--host", " "], ["--host"]),
])
def test_cli_rejects_bad_options(capsys, args, words):
    with pytest.raises(SystemExit) as exc:
        main(["explore", "--no-browser", *args])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("stairbounce: error:") and err.count("\n") == 1
    for w in words:
        assert w in err


def test_cli_port_in_use_is_one_line(capsys):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        with pytest.raises(SystemExit) as exc:
            main(["explore", "--no-browser", "--port", str(port)])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert f"cannot serve on 127.0.0.1:{port}" in err and err.count("\n") == 1


def test_cli_help_lists_the_options(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["explore", "--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    assert "--port" in out and "--host" in out and "--no-browser" in out


@pytest.mark.slow
def test_console_script_serves_the_page_and_stops_on_ctrl_c():
    import os
    import shutil
    import signal
    import subprocess
    import sys
    import time
    import urllib.request

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    exe = shutil.which("stairbounce", path=os.path.dirname(sys.executable))
    cmd = [exe] if exe else [sys.executable, "-c", "from stairbounce.cli import main; main()"]
    proc = subprocess.Popen(cmd + ["explore", "--port", str(port), "--no-browser"],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        deadline = time.monotonic() + 60
        while True:
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/?size=abc", timeout=30) as r:
                    page = r.read().decode()
                break
            except OSError:
                assert proc.poll() is None and time.monotonic() < deadline, "the server did not start"
                time.sleep(0.3)
        assert "<title>stairbounce explorer</title>" in page
        proc.send_signal(signal.SIGINT)
        out, _ = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0
    assert f"stairbounce explorer at http://127.0.0.1:{port}/" in out
    assert "stopped" in out and "Traceback" not in out
