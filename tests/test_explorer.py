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
from stairbounce.explorer import render as R
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
    point=st.none() | st.tuples(st.just(0.0) | st.floats(2.0**-53, 0.999999), st.floats(1e-6, 50)),
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
        old = R.SLICE_WORK  # compute_view's module reads it (view re-exports it)
        R.SLICE_WORK = band_work
        try:
            ds = V.compute_view(view)
        finally:
            R.SLICE_WORK = old
        xr.testing.assert_identical(ds.drop_attrs(), ref.drop_attrs())
        for k in ("e_min", "e_max", "n_e", "u_min", "u_max", "n_u", "max_iter", "convention"):
            assert ds.attrs[k] == ref.attrs[k]


def test_compute_view_cancels_between_bands_and_reports_progress(monkeypatch):
    monkeypatch.setattr(R, "SLICE_WORK", 50 * 100 * 10)  # 10 rows per band
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
    view = V.View(0.0, 1.0, 0.0, 1.5, 83, 67, max_iter=400)
    ref = plane.scan(e=(0.0, 1.0, 83), u=(0.0, 1.5, 67), max_iter=400)
    gen = V.render_slices(view, slice_work=83 * 400 * 16, preview_work=0)
    parts = []
    while True:
        try:
            parts.append(next(gen))
        except StopIteration as stop:
            ds = stop.value
            break
    # the preview (11 x 8 samples, in bands of 16 * 83 / 11 = 120 rows: one), then bands of 16 rows
    assert [p.rows_done for p in parts] == [0, 16, 32, 48, 64]
    coarse = xr.concat(parts[0].coarse, dim="u")
    sub = ref.isel(e=slice(4, None, 8), u=slice(4, None, 8))
    np.testing.assert_array_equal(coarse["word_length"].values, sub["word_length"].values)
    xr.testing.assert_identical(ds.drop_attrs(), ref.drop_attrs())
    full = V.shade(ref, "period")
    grey = V._rgba32([V.NOT_COMPUTED_COLOR])[0]
    for p in parts:
        img = V.preview_rgba(p, "period")
        assert img.shape == (67, 83) and not (img == grey).any()
        np.testing.assert_array_equal(img[: p.rows_done], full[: p.rows_done])
        # the coarse sample's own pixel always shows its exact colour
        np.testing.assert_array_equal(img[4::8, 4::8], full[4::8, 4::8])
    # the coarse pass is itself cut into bands: half its rows done, the rest grey
    gen = V.render_slices(view, slice_work=11 * 400 * 4, preview_work=0)
    first = next(gen)
    assert [b.sizes["u"] for b in first.coarse] == [4]
    img = V.preview_rgba(first, "period")
    assert (img[32:] == grey).all() and not (img[:32] == grey).any()
    # a small view skips the preview
    small = list(V.render_slices(V.View(0, 1, 0, 1.5, 40, 40, max_iter=10), slice_work=40 * 10 * 8))
    assert [p.rows_done for p in small] == [8, 16, 24, 32] and all(p.coarse == [] for p in small)


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
        w = sliding_word(e, u, max_iter=300)
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
    # a new page has no tap panels (most of its models): the first tap puts them in
    assert app.tap_panels.objects == []
    app._on_tap(SimpleNamespace(x=0.1, y=0.75))
    assert [p.object for p in app.tap_panels.objects[:1]] == [app.traj_fig]
    assert [p.object for p in app.tap_panels.objects[1].objects] == [app.orbit_fig, app.section_fig]
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
    # above the Corollary 2.1 curve (0.0018 at e = 0.99) the tap says it is proven
    assert "proven: Corollary 2.1 excludes sliding" in app.point_pane.object
    app._on_tap(SimpleNamespace(x=0.4, y=0.33))  # below the curve, no slide within 300 steps
    assert "does not slide within max_iter = 300 steps" in app.point_pane.object
    assert "Corollary 2.1 does not exclude it" in app.point_pane.object


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
    # (the motion fields colour the non-sliding pixels: test_explorer_motion.py)
    for var in [v for v in V.COLOR_VARS if v not in V.MOTION_COLOR_VARS]:
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
    from stairbounce.explorer.controls import _COLOR_OPTIONS, _OVERLAY_OPTIONS

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


def _explore_on_a_busy_port():
    """``stairbounce explore`` on a port another socket listens on: (exit code, port)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        port = s.getsockname()[1]
        with pytest.raises(SystemExit) as exc:
            main(["explore", "--no-browser", "--port", str(port)])
    return exc.value.code, port


def test_cli_port_in_use_is_one_line(capsys):
    code, port = _explore_on_a_busy_port()
    assert code == 2
    err = capsys.readouterr().err
    assert f"cannot serve on 127.0.0.1:{port}" in err and err.count("\n") == 1


def test_cli_help_lists_the_options(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["explore", "--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    assert "--port" in out and "--host" in out and "--no-browser" in out


def test_cli_port_in_use_is_reported_before_loading_kernels(capsys, monkeypatch):
    """Defect 5: the port is checked first, not after the kernels' warm-up."""
    from stairbounce.explorer import app as A

    calls = []
    monkeypatch.setattr(A, "warm_up", lambda *a: calls.append(1))
    code, _ = _explore_on_a_busy_port()
    assert code == 2 and calls == []


@pytest.mark.parametrize("origin", ["", "a b", "host/path"])
def test_cli_rejects_a_bad_websocket_origin(capsys, origin):
    with pytest.raises(SystemExit) as exc:
        main(["explore", "--no-browser", "--allow-websocket-origin", origin])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "--allow-websocket-origin" in err and err.count("\n") == 1


def test_websocket_origins_match_what_browsers_send():
    """Defect 4: Bokeh compares the Origin header's host[:port] with the
    allowlist (bokeh.server.util.check_allowlist); browsers write IPv6 hosts in
    brackets and omit default ports."""
    import socket as so

    from bokeh.server.util import check_allowlist

    from stairbounce.explorer import browse_url, normalize_host, websocket_origins

    def ok(host, origin_host, extra=()):
        return check_allowlist(origin_host, websocket_origins(host, 5006, extra))

    for host in ("127.0.0.1", "localhost", "::1", "[::1]"):
        for seen in ("127.0.0.1:5006", "localhost:5006", "[::1]:5006"):
            assert ok(host, seen), (host, seen)
        assert not ok(host, "evil.example.com:5006") and not ok(host, "127.0.0.1:5007")
    name = so.gethostname()
    assert ok("0.0.0.0", f"{name.lower()}:5006") and ok("0.0.0.0", "127.0.0.1:5006")
    assert ok("::", "[::1]:5006") and not ok("0.0.0.0", "evil.example.com:5006")
    assert ok("192.0.2.7", "192.0.2.7:5006") and not ok("192.0.2.7", "127.0.0.1:5006")
    # a reverse proxy's public name: browsers omit :443 and :80, Bokeh reads it as :80
    assert ok("127.0.0.1", "explore.example.org", ["explore.example.org"])
    assert ok("127.0.0.1", "explore.example.org:8443", ["https://explore.example.org:8443/"])
    assert ok("127.0.0.1", "[2001:db8::1]:8080", ["[2001:db8::1]:8080"])
    assert normalize_host("[::1]") == "::1"
    assert browse_url("::1", 5006) == "http://[::1]:5006/"
    assert browse_url("0.0.0.0", 5006) == f"http://{name}:5006/"


def test_make_server_port_zero_binds_a_free_port():
    """Issue 17 item 10: port 0 was refused ("Invalid port in host value: 127.0.0.1:*")."""
    from stairbounce.explorer import make_server

    server = make_server(port=0)
    try:
        assert server.port > 0
        with pytest.raises(OSError):  # it holds the port
            with socket.socket() as s:
                s.bind(("127.0.0.1", server.port))
        assert f"127.0.0.1:{server.port}" in server._tornado.websocket_origins
    finally:
        server.stop()


def test_page_requests_share_one_kept_session():
    """Load: a page request answers with the page's HTML rendered from one
    kept session; it no longer builds a session's document on the event loop
    (0.3 s each, which every open page waited for).  Five requests with
    different queries leave one session on the server (they left five)."""
    import subprocess
    import sys

    code = (
        "import threading, urllib.request\n"
        "from stairbounce.explorer import make_server\n"
        "server = make_server(port=0)\n"
        "ctx = server._tornado.applications['/']\n"
        "url = f'http://127.0.0.1:{server.port}/'\n"
        "pages = []\n"
        "def hit():\n"
        "    try:\n"
        "        for q in ['', '?e=0:0.5', '?size=100x100', '?e=0.1:0.2&u=0.5:0.6', '']:\n"
        "            with urllib.request.urlopen(url + q, timeout=60) as r:\n"
        "                pages.append((r.status, b'<title>stairbounce explorer</title>' in r.read()))\n"
        "    finally:\n"
        "        server.io_loop.add_callback(server.io_loop.stop)\n"
        "threading.Thread(target=hit).start()\n"
        "server.start()\n"
        "server.io_loop.start()\n"
        "print('SESSIONS', len(list(ctx.sessions)), pages)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=180)
    assert out.returncode == 0, out.stderr
    line = [x for x in out.stdout.splitlines() if x.startswith("SESSIONS")][0]
    assert line == "SESSIONS 1 " + repr([(200, True)] * 5), line


def test_page_changes_are_held_until_a_callback_ends():
    """Every callback into a page runs with its document held, so its changes
    go out through Bokeh's own ordered writes when it ends (Panel's direct
    sending, used otherwise, lost the last status line under load); a hold
    taken by someone else is left to them."""
    from bokeh.document import Document
    from panel.io.state import set_curdoc

    from stairbounce.explorer import app as A

    doc = Document()
    with set_curdoc(doc):
        page = A.Explorer(V.View(width=40, height=40, max_iter=10), scheduler=InlineScheduler())
    assert page._doc is doc
    seen = []
    page._in_doc(lambda: seen.append(doc.callbacks.hold_value))
    assert seen == ["combine"] and doc.callbacks.hold_value is None
    doc.hold("collect")
    page._in_doc(lambda: seen.append(doc.callbacks.hold_value))
    assert seen[-1] == "collect" and doc.callbacks.hold_value == "collect"
    doc.unhold()
    # the map's pan/zoom and tap events take the same way
    event_seen = []
    monkey = page._locked_event(lambda ev: event_seen.append((ev, doc.callbacks.hold_value)))
    monkey("ev")
    assert event_seen == [("ev", "combine")]


def test_render_sends_a_preview_only_when_the_render_takes_time(monkeypatch):
    """Progressive rendering: a render done within _PREVIEW_AFTER (0.25 s) of
    its first slice sends no preview picture (each costs every browser a
    repaint); a longer one sends the coarse pass first.  The final picture is
    the same either way."""
    from stairbounce.explorer import app as A
    from stairbounce.explorer import scan_layer

    view = V.View(0.3, 0.4, 0.3, 0.45, 200, 200, max_iter=3000)  # 1.2e8 steps: over one slice

    def run():
        gen = A.Explorer._render_work(None, view)
        previews = []
        while True:
            try:
                fraction, rgba = next(gen)
            except StopIteration as stop:
                return previews, stop.value
            previews.append((fraction, None if rgba is None else rgba.shape))

    monkeypatch.setattr(scan_layer, "_PREVIEW_AFTER", 1e9)
    never, (ds1, rgba1, _) = run()
    monkeypatch.setattr(scan_layer, "_PREVIEW_AFTER", 0.0)
    at_once, (ds2, rgba2, _) = run()
    assert len(never) >= 1 and all(shape is None for _, shape in never)
    assert at_once[0][1] is not None and at_once[0][0] < 1  # the coarse pass, shown first
    assert np.array_equal(rgba1, rgba2) and ds1.identical(ds2)


def test_server_log_lines_are_written_once():
    """Defect 13 (doubled log lines): in a server process, a record of the
    server's loggers is written once (one handler on its way)."""
    import subprocess
    import sys

    names = ("bokeh.server.views.ws", "bokeh.server.tornado", "panel", "tornado.application")
    code = (
        "import logging\n"
        "from stairbounce.cli import main\n"
        "from stairbounce.explorer import make_server\n"
        "server = make_server(port=0)\n"
        f"for name in {names!r}:\n"
        "    logging.getLogger(name).warning('probe %s', name)\n"
        "server.stop()\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    for name in names:
        assert (out.stdout + out.stderr).count(f"probe {name}") == 1, (name, out.stdout, out.stderr)


@pytest.mark.slow
def test_console_script_serves_the_page_and_stops_on_ctrl_c():
    """``--port 0``: the URL printed has the real port; kernels load after it."""
    import os
    import re
    import shutil
    import signal
    import subprocess
    import sys
    import urllib.request

    exe = shutil.which("stairbounce", path=os.path.dirname(sys.executable))
    cmd = [exe] if exe else [sys.executable, "-c", "from stairbounce.cli import main; main()"]
    proc = subprocess.Popen(cmd + ["explore", "--port", "0", "--no-browser"],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        first = proc.stdout.readline()
        m = re.search(r"stairbounce explorer at http://127\.0\.0\.1:(\d+)/", first)
        assert m, first
        port = int(m.group(1))
        assert port > 0
        assert "loading the compiled kernels" in proc.stdout.readline()
        assert "kernels ready in" in proc.stdout.readline()
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/?size=abc", timeout=60) as r:
            page = r.read().decode()
        assert "<title>stairbounce explorer</title>" in page
        # a query value Panel would refuse (over 4300 digits) is the app's message, not HTTP 500
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/?e={'1' * 20000}", timeout=60) as r:
            assert r.status == 200
        proc.send_signal(signal.SIGINT)
        out, _ = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0
    assert "stopped" in out and "Traceback" not in out


# --------------------------------------------------------------------------- #
# The scheduler (issue 14, defect 2)                                          #
# --------------------------------------------------------------------------- #


def _timed_slices(log, name, n, seconds):
    """A job of ``n`` slices of ``seconds`` each that records its name in ``log``."""
    import time

    for i in range(n):
        time.sleep(seconds)
        log.append(name)
        yield i


def _slices(log, name, n, result=None):
    """A job of ``n`` slices that records each one in ``log``."""
    for i in range(n):
        log.append((name, i))
        yield i
    log.append((name, "done"))
    return result


def test_scheduler_runs_a_cheap_request_before_a_heavy_one_continues():
    """Least recent usage first: a heavy job that has had its slices waits
    while another session's one-slice job runs; it never runs to the end first
    (no quantum: the rule alone)."""
    from stairbounce.explorer.scheduler import Scheduler

    s = Scheduler(thread=False, quantum=0.0)
    log = []
    a, b = object(), object()
    heavy = s.submit(a, "render", _slices(log, "A", 10))
    for _ in range(3):  # A has run three slices
        s.run_slice(heavy)
    s.submit(b, "render", _slices(log, "B", 1))
    s.run_all()
    order = [name for name, _ in log]
    assert order.index("B") == 3  # B's slice runs next, before A's fourth
    assert log[-1] == ("A", "done")


def test_scheduler_shares_turns_between_two_heavy_sessions():
    from stairbounce.explorer.scheduler import Scheduler

    log = []
    # equal-cost slices: attained service grows alike, so the two alternate
    def slow(name):
        for i in range(6):
            time.sleep(0.005)  # slices of equal cost
            log.append((name, i))
            yield i

    import time

    s = Scheduler(thread=False, quantum=0.0)
    s.submit("a", "render", slow("A"))
    s.submit("b", "render", slow("B"))
    s.run_all()
    first_half = [name for name, _ in log[:8]]
    assert first_half.count("A") >= 3 and first_half.count("B") >= 3


def test_scheduler_does_not_starve_a_long_render():
    """Session A's long render keeps getting slices while B keeps sending
    new small requests (each superseding the last): B's usage counts, not
    only its newest job's (ranking jobs by their own time starved A)."""
    from stairbounce.explorer.scheduler import Scheduler

    s = Scheduler(thread=False, quantum=0.0)
    log = []
    s.submit("a", "render", _timed_slices(log, "A", 1000, 0.004))
    for _ in range(40):
        s.submit("b", "render", _timed_slices(log, "B", 3, 0.004))
        for _ in range(3):
            assert s.run_next()
    # A had about a fair half of the 120 slices, not none
    assert 40 <= log.count("A") <= 80
    s.cancel("a")


def test_scheduler_finishes_equal_requests_one_after_another():
    """With the quantum, three sessions' equal small renders run first come,
    first served (the first done after one render, not all at the end);
    without it they share the worker slice by slice (processor sharing)."""
    from stairbounce.explorer.scheduler import Scheduler

    def order(quantum):
        s = Scheduler(thread=False, quantum=quantum)
        log = []
        for name in "ABC":  # slices of no measurable cost: far below the quantum
            s.submit(name, "render", _slices(log, name, 4))
        s.run_all()
        return "".join(name for name, i in log if i != "done")

    assert order(0.25) == "AAAABBBBCCCC"
    assert sorted(order(0.0)[:3]) == ["A", "B", "C"]  # each session's first slice first


def test_scheduler_quantum_bounds_the_wait_of_a_new_request():
    """A request from an idle session waits for at most the quantum (0.25 s)
    of another session's render under way, plus the slice in progress."""
    from stairbounce.explorer.scheduler import Scheduler

    s = Scheduler(thread=False, quantum=0.25)
    log = []
    heavy = s.submit("a", "render", _timed_slices(log, "A", 20, 0.05))
    s.run_slice(heavy)
    s.submit("b", "render", _timed_slices(log, "B", 1, 0.05))
    while "B" not in log:
        assert s.run_next()
    # A's usage (at least 0.05 s a slice, decayed by at most 6 %) passes 0.25 s after
    # its 6th slice at the latest, so B comes by then (sooner if sleeps overshoot);
    # with no quantum it would come right after A's 1st
    assert 2 <= log.index("B") <= 6
    s.cancel("a")


def test_scheduler_new_request_supersedes_the_sessions_pending_one():
    from stairbounce.explorer.scheduler import Scheduler

    s = Scheduler(thread=False)
    log, done = [], []
    s.submit("a", "render", _slices(log, "old", 5), on_done=lambda r, e, j: done.append("old"))
    s.submit("a", "point", _slices(log, "tap", 1), on_done=lambda r, e, j: done.append("tap"))
    s.submit("a", "render", _slices(log, "new", 2), on_done=lambda r, e, j: done.append("new"))
    s.run_all()
    assert not any(name == "old" for name, _ in log)  # never started, never finished
    assert sorted(done) == ["new", "tap"]  # another kind of the same session is kept


def test_scheduler_drops_a_closed_sessions_work_at_once():
    from stairbounce.explorer.scheduler import Scheduler

    s = Scheduler(thread=False)
    log, done = [], []
    alive = [True]
    job = s.submit("a", "render", _slices(log, "A", 100), alive=lambda: alive[0],
                   on_done=lambda r, e, j: done.append(r))
    s.run_slice(job)
    alive[0] = False  # the page's websocket closed
    s.run_all()
    assert log == [("A", 0)] and done == []
    # and cancel() for a session ended by Bokeh
    job = s.submit("b", "render", _slices(log, "B", 100))
    s.run_slice(job)
    s.cancel("b")
    s.run_all()
    assert log[-1] == ("B", 0)
    assert not s.busy()


def test_scheduler_thread_keeps_serving_after_a_failing_job():
    import threading

    from stairbounce.explorer.scheduler import Scheduler

    def bad():
        yield
        raise RuntimeError("boom")

    s = Scheduler()
    errors, ok = [], threading.Event()
    s.submit("a", "render", bad(), on_done=lambda r, e, j: errors.append(e))
    s.submit("b", "render", _slices([], "B", 2, result=7), on_done=lambda r, e, j: ok.set())
    assert ok.wait(30)
    assert len(errors) == 1 and str(errors[0]) == "boom"


def test_render_work_is_sliced_within_the_budget():
    """A render is cut into slices of at most SLICE_WORK potential map steps,
    so the wait of another session's request is bounded by one slice."""
    view = V.View(0.5, 1.0, 5.0, 6.0, 1000, 1000, max_iter=5000)  # nothing slides: worst case
    rows = max(1, V.SLICE_WORK // (view.width * view.max_iter))
    assert rows * view.width * view.max_iter <= V.SLICE_WORK
    # so is every slice, coarse preview included (max_iter 1 keeps the test fast)
    budget = V.SLICE_WORK // 5000
    work = []
    for p in V.render_slices(replace(view, max_iter=1), slice_work=budget, preview_work=0):
        last = p.parts[-1] if p.parts else p.coarse[-1]
        work.append(last.sizes["u"] * last.sizes["e"])
    assert len(work) > 40 and max(work) <= budget


def test_page_says_when_it_is_queued():
    from stairbounce.explorer import app as A
    from stairbounce.explorer.scheduler import Scheduler

    s = Scheduler(thread=False)
    other = A.Explorer(V.View(width=40, height=40, max_iter=10), scheduler=s)
    other._request(V.View(0, 1, 0, 1.5, 40, 40, max_iter=20))
    mine = A.Explorer(V.View(width=40, height=40, max_iter=10), scheduler=s)
    mine._request(V.View(0, 1, 0, 1.5, 40, 40, max_iter=30))
    assert "queued" in mine.status.object and "1 request of other sessions" in mine.status.object
    s.run_all()
    assert "computed in" in mine.status.object and "computed in" in other.status.object


def test_page_says_the_kernels_are_loading(monkeypatch):
    from stairbounce.explorer import app as A
    from stairbounce.explorer.scheduler import Scheduler

    s = Scheduler(thread=False)
    monkeypatch.setattr(A, "SCHEDULER", s)
    warm = A.warm_up()
    assert not warm.is_set()
    page = A.Explorer(V.View(width=40, height=40, max_iter=10))
    page.start()
    assert "loading its compiled kernels" in page.status.object
    s.run_all()
    assert warm.is_set() and "computed in" in page.status.object


# --------------------------------------------------------------------------- #
# The page's other defects (issue 14)                                         #
# --------------------------------------------------------------------------- #


def test_downloads_run_off_the_event_loop(explorer, monkeypatch):
    """Defect 3: the callbacks are coroutines; the export runs on another thread."""
    import asyncio
    import inspect
    import threading

    from stairbounce.explorer import app as A

    app, _ = explorer
    seen = []
    real = A.view_png

    def spy(ds, view, **kw):
        seen.append(threading.current_thread())
        return real(ds, view, **kw)

    monkeypatch.setattr(A, "view_png", spy)
    assert inspect.iscoroutinefunction(app.png_button.callback)
    assert inspect.iscoroutinefunction(app.nc_button.callback)
    loop_thread = []

    async def download():
        loop_thread.append(threading.current_thread())
        return await app._png()

    assert asyncio.run(download()).getvalue()[:4] == b"\x89PNG"
    assert seen and seen[0] is not loop_thread[0]


def test_download_buttons_wait_for_a_view():
    """Defect 6: disabled until the first picture."""
    from stairbounce.explorer.app import Explorer

    s = InlineScheduler()
    app = Explorer(V.View(0.0, 0.4, 0.3, 1.1, 40, 30, max_iter=100), scheduler=s)
    assert app.png_button.disabled and app.nc_button.disabled
    app.start()
    assert not app.png_button.disabled and not app.nc_button.disabled


def test_deep_zoom_status_and_hover_tell_the_ends_apart():
    """Defect 8: enough digits for the window's ends and one pixel; the hover
    shows the colouring variable's value."""
    from stairbounce.explorer.app import Explorer

    lo = 0.0525
    view = V.View(lo, lo + 2e-9, 0.93, 0.93 + 2e-9, 40, 40, max_iter=100)
    app = Explorer(view, scheduler=InlineScheduler())
    app.start()
    import re

    a, b = re.search(r">e (\S+) to (\S+),", app.status.object).groups()
    assert a != b and float(a) == lo and abs(float(b) - (lo + 2e-9)) < 1e-12
    tips = dict(app.hover.tooltips)
    digits = int(tips["e"].split("%.")[1].split("g")[0])
    step = 2e-9 / 40
    assert f"{lo + 0.5 * step:.{digits}g}" != f"{lo + 1.5 * step:.{digits}g}"
    assert tips["word length"] == "@val{custom}"
    val = app.img_src.data["val"][0]
    sl = app.ds["status"].values == 0
    np.testing.assert_array_equal(val[sl], app.ds["word_length"].values[sl])
    assert (val[~sl] == -1).all()


def test_refused_zoom_snaps_back_to_the_last_view(explorer):
    """Defect 8: a zoom deeper than float64 resolves is refused and the plot's
    ranges go back to the view shown."""
    app, ex = explorer
    n = len(ex.calls)
    app._on_ranges(SimpleNamespace(x0=0.1, x1=0.1 + 1e-16, y0=0.5, y1=0.6))
    assert len(ex.calls) == n and "too narrow" in app.status.object
    assert (app.map_fig.x_range.start, app.map_fig.x_range.end) == (app.shown.e_lo, app.shown.e_hi)
    assert (app.map_fig.y_range.start, app.map_fig.y_range.end) == (app.shown.u_lo, app.shown.u_hi)


def test_error_is_cleared_when_the_input_is_put_back(explorer):
    """Defect 9: a refused value is put back in its widget; the message goes
    when the input is back at the view shown, or after Reset."""
    app, ex = explorer
    app.width_in.value = 1000
    app.height_in.value = 1001  # refused
    assert "pixel budget" in app.status.object
    assert app.height_in.value == app.view.height == 50  # the widget shows the view again
    _type_window(app, e="0:0.4")  # the window shown, typed again: nothing to do, message gone
    assert "sb-error" not in app.status.object
    _type_window(app, e="abc")
    assert "sb-error" in app.status.object and app.e_window.value == "0:0.4"
    v = app.view  # Reset: Bokeh's reset tool moves the ranges back to the view
    app._on_ranges(SimpleNamespace(x0=v.e_lo, x1=v.e_hi, y0=v.u_lo, y1=v.u_hi))
    assert "sb-error" not in app.status.object


def test_one_apply_for_both_windows(explorer):
    """Defect 12: typing e and u, then Enter (or Apply) in either box, renders once."""
    app, ex = explorer
    n = len(ex.calls)
    app.e_window.value_input = "0.1:0.2"  # typed, no Enter yet: nothing happens
    app.e_window.value = "0.1:0.2"  # a blur commits the text box: still nothing
    assert len(ex.calls) == n
    app.u_window.value_input = "0.5:0.6"
    app.u_window.param.trigger("enter_pressed")
    assert ex.calls[n:] == ["render"]
    assert (app.shown.e_lo, app.shown.e_hi, app.shown.u_lo, app.shown.u_hi) == (0.1, 0.2, 0.5, 0.6)


def test_zoom_url_has_no_float_noise(explorer):
    """Defect 13: Bokeh's 0.9200000000000002 is written 0.92."""
    app, _ = explorer
    app._on_ranges(SimpleNamespace(x0=0.04000000000000001, x1=0.065, y0=0.9200000000000002,
                                   y1=0.9450000000000001))
    assert (app.view.e_lo, app.view.u_lo, app.view.u_hi) == (0.04, 0.92, 0.945)
    assert "u=0.92:0.945&" in app.history_out.text


def test_overlay_legend_follows_the_overlays(explorer):
    app, _ = explorer
    assert app.legend.visible and len(app.legend.items) == 2
    app.overlays.value = ["no_sliding"]
    assert [i.label.value for i in app.legend.items] == [_OVERLAY_LEGEND()["no_sliding"]]
    app.overlays.value = []
    assert not app.legend.visible and app.legend.items == []


def _OVERLAY_LEGEND():
    from stairbounce.explorer.app import _OVERLAY_LEGEND

    return _OVERLAY_LEGEND


def test_tap_trajectory_shows_a_full_period_and_singular_words(explorer):
    """Defect 13: a period-31 orbit shows at least 31 steps; 'period 1 step'."""
    app, _ = explorer
    # the report's period-31 point (2 x14, 3, 0^inf), checked with sliding_word
    e, u = 0.0621875, 0.9436874999999999
    w = sliding_word(e, u, 1000)
    assert w is not None and w.period == 31
    app.view = replace(app.view, max_iter=1000)
    app._request_point(e, u)
    assert app.path_src.data["x"].max() >= 31  # the ball went down 31 steps or more
    assert "period 31 steps" in app.point_pane.object
    assert "one full period" in app.traj_fig.title.text
    # a point inside the n = 1 tongue: word (1, 0^inf), period 1
    app._request_point(0.05, 0.5)
    assert sliding_word(0.05, 0.5, 1000).period == 1
    assert "period 1 step," in app.point_pane.object and "1 steps" not in app.point_pane.object


def test_back_and_forward_restore_the_view(explorer):
    """Defect 1 (server side): a zoom pushes a history entry; the browser's
    popstate with an older query brings that view back without a new entry."""
    app, ex = explorer
    first = app.history_out.text
    assert first.startswith("replace ?")
    app._on_ranges(SimpleNamespace(x0=0.05, x1=0.15, y0=0.6, y1=0.7))
    assert app.history_out.text.startswith("push ?e=0.05:0.15&u=0.6:0.7&")
    app.color.value = "period"  # recolouring replaces the entry
    assert app.history_out.text.startswith("replace ?") and "color=period" in app.history_out.text
    app.history_back.text = "123 " + first.split(" ", 1)[1]  # Back
    assert (app.shown.e_lo, app.shown.e_hi, app.shown.u_lo, app.shown.u_hi) == (0.0, 0.4, 0.3, 1.1)
    assert app.e_window.value == "0:0.4" and app.color.value == "word_length"
    assert app.map_fig.x_range.start == 0.0 and app.map_fig.y_range.end == 1.1
    assert app.history_out.text.startswith("replace ?e=0:0.4&")


def test_exact_borders_overlay_shows_the_views_border_points(explorer):
    """Issue 21: the "exact borders" overlay draws stairbounce.border_points of the
    view (hover: kind, step, the two words), coloured by kind; off by default."""
    from stairbounce.plot.borders import KIND_COLORS

    app, _ = explorer
    assert "borders" not in app.view.overlays and app.borders.border_src.data["e"] == []
    app.overlays.value = ["borders"]
    data = app.borders.border_src.data
    ref = V.border_overlay(app.view)
    assert len(data["e"]) > 10 and data["e"] == ref["e"] and data["word_high"] == ref["word_high"]
    assert data["color"] == [KIND_COLORS[k] for k in ref["kind"]]
    assert [i.label.value for i in app.legend.items] == [_OVERLAY_LEGEND()["borders"]]
    assert "overlays=borders" in app.history_out.text
    app.overlays.value = []
    assert app.borders.border_src.data["e"] == []


def _row_of(tab, text):
    """The row of ``text`` in a word_table, as {column: value}."""
    hit = np.flatnonzero(tab["text"].values == text)
    assert hit.size == 1
    r = tab.isel(word=int(hit[0]))
    return {k: r[k].item() for k in V.WORD_ROW_FIELDS}


def test_tap_reports_the_words_row_of_the_views_word_table(explorer, monkeypatch):
    """Issue 21 item 6: a tap reports its word's row of stairbounce.word_table of
    the view (on the border grid, here the view's own 60 x 50 pixels), computed
    in the tap's scheduler job; a point that does not slide has no row."""
    import stairbounce as sb

    app, ex = explorer
    n = len(ex.calls)
    scans = []  # the view is at most BORDER_SIDE per side: the tap uses its own scan, computes none
    real_scan = plane.scan
    monkeypatch.setattr(plane, "scan", lambda *a, **k: scans.append(1) or real_scan(*a, **k))
    # inside the n = 2 tongue of Theorem 3.1 at e = 0.05: sqrt(1/2) < u <= sqrt(1) (0.95 / 1.05)
    app._on_tap(SimpleNamespace(x=0.05, y=0.8))
    assert ex.calls[n:] == ["point"]  # the row came with the tap's own job
    assert scans == []
    e, u = app.view.point
    w = sliding_word(e, u, 300)
    assert w.format(ascii=True) == "(2, 0^inf)"
    assert V.border_grid(app.view) == ((0.0, 0.4, 60), (0.3, 1.1, 50))
    tab = sb.word_table(e=(0.0, 0.4, 60), u=(0.3, 1.1, 50), max_iter=300)
    ref = _row_of(tab, "(2, 0^inf)")
    found = V.word_row(app.view, "(2, 0^inf)")
    assert found["row"] == ref and found["grid"] == (60, 50) and found["words"] == tab.sizes["word"]
    assert app._word_table[0] == (V.border_grid(app.view), 300)
    assert app._word_table[1].identical(tab)  # kept for the next tap in this view
    # computed from the view's own scan (its pixels are the grid): the same table
    assert sb.word_table(app.ds).equals(tab) and V.word_row(app.view, "(2, 0^inf)", scan=app.ds)["row"] == ref
    assert ref["pixels"] > 100 and ref["graze"] + ref["chatter"] > 0  # a row that could be wrong
    text = app.point_pane.object
    assert "computing" not in text
    assert f"word table of this view (60 x 50 pixels, {tab.sizes['word']} words)" in text
    # the row's letters, period and impacts are the tapped Word's
    assert (ref["letters"], ref["period"], ref["impacts"]) == (len(w), w.period, w.impacts) == (1, 2, 0)
    for part in ("(2, 0^inf)", "1 letter,", "period 2,", "0 finite impacts per period",
                 f"{ref['pixels']} pixels", f"{100 * ref['area_fraction']:.3g} % of the view",
                 f"({ref['e_rep']:.6g}, {ref['u_rep']:.6g})", f"e {ref['e_min']:.6g} .. {ref['e_max']:.6g}",
                 f"u {ref['u_min']:.6g} .. {ref['u_max']:.6g}",
                 f"graze {ref['graze']}, edge {ref['edge']}, chatter {ref['chatter']}"):
        assert part in text, part
    # a second tap in the view reuses the table; with the exact borders drawn, the
    # tap reuses their points: the same row either way
    kept = app._word_table[1]
    app._on_tap(SimpleNamespace(x=0.05, y=0.8))
    assert app._word_table[1] is kept
    assert f"graze {ref['graze']}, edge {ref['edge']}, chatter {ref['chatter']}" in app.point_pane.object
    app._word_table = None
    app.overlays.value = ["borders"]
    assert app.borders.points[0] == (V.border_grid(app.view), 300)
    app._on_tap(SimpleNamespace(x=0.05, y=0.8))
    assert f"graze {ref['graze']}, edge {ref['edge']}, chatter {ref['chatter']}" in app.point_pane.object
    # a point that does not slide within max_iter: no row
    app._on_tap(SimpleNamespace(x=0.4, y=0.33))
    assert sliding_word(*app.view.point, 300) is None
    text = app.point_pane.object
    assert "none within max_iter (no row)" in text and "word table of this view" not in text


def test_tap_word_row_grid_is_at_most_border_side_and_says_when_the_word_is_off_it():
    big = V.View(0.0, 0.4, 0.3, 1.1, 600, 400, max_iter=300)
    assert V.border_grid(big) == ((0.0, 0.4, V.BORDER_SIDE), (0.3, 1.1, V.BORDER_SIDE))
    small = V.View(0.0, 0.4, 0.3, 1.1, 12, 10, max_iter=300)
    found = V.word_row(small, "(7, 0, 3, 0^inf)")  # no such word in this window
    assert found["row"] is None and found["grid"] == (12, 10) and found["words"] >= 2


def test_png_export_draws_the_exact_borders_overlay():
    from PIL import Image

    from stairbounce.explorer.export import view_png

    view = V.View(0.0, 0.3, 0.3, 0.7, 60, 50, max_iter=200, overlays=("tongues", "borders"))
    ds = V.compute_view(view)
    plain = view_png(ds, V.View(0.0, 0.3, 0.3, 0.7, 60, 50, max_iter=200, overlays=("tongues",)))
    png = view_png(ds, view)
    assert Image.open(io.BytesIO(png)).format == "PNG" and png != plain
def test_a_size_asked_for_in_one_edit_is_refused_whole(explorer):
    """Issue 25: 5000 typed as width, then 5000 as height, is one request for
    5000 x 5000 (refused with both numbers), not 600 x 5000: the refused width
    is put back in its widget but asked for again with the height."""
    app, ex = explorer
    app.height_in.value = 500  # 60 x 500: computed
    n = len(ex.calls)
    app.width_in.value = 5000  # 5000 x 500: over the budget
    assert "view of 5000x500 " in app.status.object and app.width_in.value == app.view.width == 60
    app.height_in.value = 5000
    assert "view of 5000x5000 = 25000000 pixels refused" in app.status.object
    assert (app.width_in.value, app.height_in.value) == (60, 500) and len(ex.calls) == n
    # another setting next is not combined with the refused side
    app.max_iter.value = 200
    assert app.view.max_iter == 200 and (app.view.width, app.view.height) == (60, 500)
    # a refused height, then a width: asked for together
    app.height_in.value = 50000
    app.width_in.value = 100
    assert "view of 100x50000" in app.status.object


def test_a_quick_run_of_zooms_is_one_history_entry(explorer, monkeypatch):
    """Issue 25: a six-notch wheel zoom reports several RangesUpdates on a
    loaded machine; those within GESTURE_MERGE_S of each other are one
    gesture, one history entry, so Back returns to the start view."""
    import stairbounce.explorer.app as A
    from stairbounce.explorer import controls

    app, ex = explorer
    clock = [100.0]
    monkeypatch.setattr(controls.time, "monotonic", lambda: clock[0])
    modes = []
    for k in range(6):  # notches 0.2 s apart
        clock[0] += 0.2
        app._on_ranges(SimpleNamespace(x0=0.02 * (k + 1), x1=0.4 - 0.02 * (k + 1), y0=0.3, y1=1.1))
        modes.append(app.history_out.text.split(" ")[0])
    assert modes == ["push"] + ["replace"] * 5
    assert app.history_out.text.startswith("replace ?e=0.12:0.28&")
    clock[0] += controls.GESTURE_MERGE_S + 0.01  # a later zoom is a gesture of its own
    app._on_ranges(SimpleNamespace(x0=0.15, x1=0.25, y0=0.3, y1=1.1))
    assert app.history_out.text.startswith("push ?e=0.15:0.25&")
