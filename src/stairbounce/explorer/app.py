"""The Panel (Bokeh) page of ``stairbounce explore``.

One :class:`Explorer` per browser session.  The map is a Bokeh ``image_rgba``
recomputed at the view's pixel size after every pan or zoom (Bokeh's
``RangesUpdate`` event, one per gesture); a tap shows the word, trajectory and
orbit diagram of the tapped pixel.  All dynamics runs on a worker thread (the
numba kernels release the GIL, so the server's event loop keeps serving the
page), and results come back to the document with ``add_next_tick_callback``,
the Bokeh server's thread-safe way in.  A newer request cancels an older
render between bands of rows (:func:`~stairbounce.explorer.view.compute_view`).
"""

from __future__ import annotations

import html
import io
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace
from functools import partial

import numpy as np
import panel as pn
from bokeh.events import RangesUpdate, Tap
from bokeh.models import (
    ColorBar,
    ColumnDataSource,
    FixedTicker,
    HoverTool,
    Legend,
    LegendItem,
    LinearColorMapper,
    Range1d,
    Span,
)
from bokeh.plotting import figure
from panel.io.state import set_curdoc

from .export import export_name, view_netcdf, view_png
from .view import (
    DEFAULT_VIEW,
    MAX_ITER_LIMIT,
    U_LIMIT,
    Cancelled,
    View,
    check_view,
    color_key,
    compute_view,
    format_window,
    has_color,
    orbit_along_u,
    overlay_curves,
    parse_query,
    parse_window,
    pixel_of,
    point_details,
    shade,
    view_url_query,
)

__all__ = ["Explorer", "create_app", "warm_up"]

# One worker for every session: each numba kernel already uses all cores, and
# numba's fallback threading layer (workqueue) must not be entered from two
# threads at once.
_EXECUTOR = ThreadPoolExecutor(max_workers=1, thread_name_prefix="stairbounce-explorer")

_COLOR_OPTIONS = {
    "word length": "word_length",
    "period (steps)": "period",
    "impacts per period": "impacts",
    "non-zero letters (jumps)": "jumps",
    "status (slides or not)": "status",
    "<k>, impacts per step (non-sliding motion)": "k_mean",
    "lambda_1 (non-sliding motion)": "lyap1",
}
_OVERLAY_OPTIONS = {"tongues (n, 0^\u221e), Thm 3.1": "tongues", "no-sliding bound, Cor. 2.1": "no_sliding"}

_CSS = """
.sb-status { font-family: monospace; font-size: 13px; }
.sb-point table td { padding: 1px 8px 1px 0; vertical-align: top; }
.sb-word { font-family: monospace; font-size: 15px; font-weight: bold; }
"""


class Explorer:
    """The widgets, figures and render pipeline of one browser session."""

    def __init__(self, view: View = DEFAULT_VIEW, messages=(), executor=_EXECUTOR):
        self.view = view  # what is asked for
        self.shown: View | None = None  # what the image shows
        self.ds = None
        self._executor = executor
        self._doc = pn.state.curdoc
        self._gen = 0
        self._running = False
        self._pending: View | None = None
        self._tap_gen = 0
        self._syncing = False
        self._status_text, self._status_level, self._error_text = "", "info", ""

        self._build_map()
        self._build_point_figures()
        self._build_widgets(messages)
        # a flex box wraps the tap panel below the map when the window is narrow
        self.layout = pn.FlexBox(
            pn.Column(
                pn.pane.Markdown(
                    "## stairbounce explorer\nPeriodic sliding solutions of a ball bouncing down "
                    "a staircase (Campos, Romero-Valles, Torres). Scroll to zoom, drag to pan, "
                    "tap a point for its word, trajectory and orbit diagram.",
                    width=300,
                ),
                self.color, self.max_iter, pn.Row(self.width_in, self.height_in),
                self.e_window, self.u_window, self.overlays, self.fig4_button,
                pn.Row(self.png_button, self.nc_button),
                self.url_messages,
                width=320,
            ),
            pn.Column(pn.pane.Bokeh(self.map_fig), self.status),
            pn.Column(self.point_pane, pn.pane.Bokeh(self.traj_fig), pn.pane.Bokeh(self.orbit_fig),
                      pn.pane.Bokeh(self.section_fig)),
            flex_wrap="wrap",
            align_items="flex-start",
            gap="12px",
            stylesheets=[_CSS],
        )

    # ------------------------------------------------------------------ build

    def _build_map(self):
        v = self.view
        fig = figure(
            x_range=Range1d(v.e_lo, v.e_hi, bounds=(0.0, 1.0)),
            y_range=Range1d(v.u_lo, v.u_hi, bounds=(0.0, U_LIMIT)),
            frame_width=v.width,
            frame_height=v.height,
            tools="pan,wheel_zoom,box_zoom,tap,reset",
            active_drag="pan",
            active_scroll="wheel_zoom",
            toolbar_location="above",
            x_axis_label="e (restitution coefficient)",
            y_axis_label="u (horizontal speed)",
            title="periodic sliding solutions in the (e, u) plane",
        )
        fig.toolbar.logo = None
        fig.background_fill_color = "#f4f4f4"
        fig.xgrid.visible = fig.ygrid.visible = False
        self.img_src = ColumnDataSource(
            dict(image=[np.zeros((1, 1), np.uint32)], x=[v.e_lo], y=[v.u_lo],
                 dw=[v.e_hi - v.e_lo], dh=[v.u_hi - v.u_lo])
        )
        img = fig.image_rgba(image="image", x="x", y="y", dw="dw", dh="dh", source=self.img_src)
        fig.add_tools(HoverTool(renderers=[img], tooltips=[("e", "$x{0.0000000}"), ("u", "$y{0.0000000}")]))
        self.tongue_src = ColumnDataSource(dict(xs=[], ys=[]))
        self.bound_src = ColumnDataSource(dict(xs=[], ys=[]))
        # grey outlines show on the black tongues and on the white no-sliding region alike
        tongues = fig.multi_line("xs", "ys", source=self.tongue_src, line_color="#9a9a9a", line_width=1)
        bound = fig.multi_line("xs", "ys", source=self.bound_src, line_color="#d62728", line_width=2,
                               line_dash="dashed")
        fig.add_layout(Legend(items=[
            LegendItem(label="tongues (n, 0^\u221e), Thm 3.1", renderers=[tongues]),
            LegendItem(label="u = (1-e)/(2\u221a(2e)), Cor. 2.1", renderers=[bound]),
        ], orientation="horizontal", label_text_font_size="9pt", border_line_alpha=0), "below")
        self.point_src = ColumnDataSource(dict(x=[], y=[]))
        fig.scatter("x", "y", source=self.point_src, marker="circle_cross", size=14,
                    fill_alpha=0.0, line_color="#ff00ff", line_width=2)
        key = color_key(v.color)
        self.mapper = LinearColorMapper(palette=list(key.colors), low=-0.5, high=len(key.colors) - 0.5)
        self.colorbar = ColorBar(
            color_mapper=self.mapper, title=key.title, width=14,
            ticker=FixedTicker(ticks=key.ticks),
            major_label_overrides={i: s for i, s in enumerate(key.labels)},
        )
        fig.add_layout(self.colorbar, "right")
        fig.on_event(RangesUpdate, self._on_ranges)
        fig.on_event(Tap, self._on_tap)
        self.map_fig = fig

    def _build_point_figures(self):
        t = figure(height=340, width=560, match_aspect=True, tools="pan,wheel_zoom,reset",
                   active_scroll="wheel_zoom", title="trajectory from (1, 0): tap the map",
                   x_axis_label="x (steps)", y_axis_label="height")
        t.toolbar.logo = None
        self.stairs_src = ColumnDataSource(dict(x=[], y=[]))
        self.path_src = ColumnDataSource(dict(x=[], y=[]))
        self.impact_src = ColumnDataSource(dict(x=[], y=[]))
        self.accum_src = ColumnDataSource(dict(x=[], y=[]))
        self.slide_src = ColumnDataSource(dict(xs=[], ys=[]))
        t.line("x", "y", source=self.stairs_src, line_color="#444444", line_width=1.5)
        t.line("x", "y", source=self.path_src, line_color="#1f77b4", line_width=1.5, legend_label="ball")
        t.scatter("x", "y", source=self.impact_src, size=5, color="#d62728", legend_label="impacts")
        t.multi_line("xs", "ys", source=self.slide_src, line_color="#2ca02c", line_width=5,
                     legend_label="sliding")
        t.scatter("x", "y", source=self.accum_src, marker="star", size=14, fill_color="#ff7f0e",
                  line_color="black", legend_label="accumulation")
        t.legend.location = "top_right"
        t.legend.label_text_font_size = "8pt"
        self.traj_fig = t

        o = figure(height=300, width=560, x_range=Range1d(0, 1.5), y_range=Range1d(0, 3), tools="pan,wheel_zoom,box_zoom,reset",
                   title="orbit diagram along u: tap the map", output_backend="webgl",
                   x_axis_label="u", y_axis_label="y at the step edges")
        o.toolbar.logo = None
        self.orbit_src = ColumnDataSource(dict(x=[], y=[]))
        o.scatter("x", "y", source=self.orbit_src, size=1.5, color="black", alpha=0.35)
        self.orbit_marker = Span(location=0.0, dimension="height", line_color="#ff00ff",
                                 line_width=2, visible=False)
        o.add_layout(self.orbit_marker)
        self.orbit_fig = o

        p = figure(height=300, width=560, tools="pan,wheel_zoom,box_zoom,reset", output_backend="webgl",
                   title="Poincare section of a non-sliding point: tap the map",
                   x_axis_label="y at the step edges", y_axis_label="v at the step edges")
        p.toolbar.logo = None
        self.section_src = ColumnDataSource(dict(x=[], y=[]))
        p.scatter("x", "y", source=self.section_src, size=2, color="#1f4e79", alpha=0.5)
        self.section_fig = p

    def _build_widgets(self, messages):
        v = self.view
        self.color = pn.widgets.Select(label="Colour by", options=_COLOR_OPTIONS, value=v.color, width=280,
                                       css_classes=["sb-color"])
        self.max_iter = pn.widgets.IntInput(label=f"max_iter (1 to {MAX_ITER_LIMIT})", value=v.max_iter,
                                            width=280, css_classes=["sb-max-iter"])
        self.width_in = pn.widgets.IntInput(label="width (px)", value=v.width, width=135,
                                            css_classes=["sb-width"])
        self.height_in = pn.widgets.IntInput(label="height (px)", value=v.height, width=135,
                                             css_classes=["sb-height"])
        self.e_window = pn.widgets.TextInput(label="e window (LO:HI)", value=format_window(v.e_lo, v.e_hi),
                                             width=280, css_classes=["sb-e-window"])
        self.u_window = pn.widgets.TextInput(label="u window (LO:HI)", value=format_window(v.u_lo, v.u_hi),
                                             width=280, css_classes=["sb-u-window"])
        self.overlays = pn.widgets.CheckBoxGroup(
            options=_OVERLAY_OPTIONS, value=list(v.overlays), inline=False, width=280,
            css_classes=["sb-overlays"])
        self.fig4_button = pn.widgets.Button(label="Figure 4 window (e 0:1, u 0:1.5)", width=280)
        self.png_button = pn.widgets.FileDownload(
            callback=self._png, filename="stairbounce_view.png", label="Download PNG",
            color="primary", width=135, embed=False)
        self.nc_button = pn.widgets.FileDownload(
            callback=self._netcdf, filename="stairbounce_view.nc", label="Download .nc",
            color="primary", width=135, embed=False)
        self.status = pn.pane.HTML("", css_classes=["sb-status"], width=600)
        self.url_messages = pn.pane.Alert(
            '<div class="sb-url-text" style="overflow-wrap: anywhere">' + "<br>".join(html.escape(m) for m in messages) + "</div>",
            alert_type="warning",
            visible=bool(messages), width=290, margin=(10, 10), css_classes=["sb-url-messages"])
        self.point_pane = pn.pane.HTML(
            "<i>Tap a point of the map.</i>", css_classes=["sb-point"], width=560)

        self.color.param.watch(self._locked(self._on_color), "value")
        for w in (self.max_iter, self.width_in, self.height_in):
            w.param.watch(self._locked(self._on_settings), "value")
        for w in (self.e_window, self.u_window):
            w.param.watch(self._locked(self._on_window_text), "value")
        self.overlays.param.watch(self._locked(self._on_overlays), "value")
        self.fig4_button.on_click(self._locked(self._on_fig4))

    def _locked(self, fn):
        """Run a widget callback under the Bokeh document lock.

        Panel calls widget callbacks without the lock, and changing a raw
        Bokeh model (the figure's ranges, its data sources) there raises; the
        next tick callback of a Bokeh server session holds it.  Bokeh's own
        events (pan, zoom, tap) already arrive with the lock.
        """

        def run(*args):
            if self._doc is not None and self._doc.session_context is not None:
                self._doc.add_next_tick_callback(partial(self._in_doc, fn, *args))
            else:  # no server (tests)
                fn(*args)

        return run

    # ------------------------------------------------------------ interaction

    def start(self):
        """First render (and the URL's point) once the page is connected."""
        self._sync_url()
        self._draw_overlays(self.view)
        self._request(self.view)
        if self.view.point is not None:
            self._request_point(*self.view.point)

    def _message(self, text, level="info"):
        """Status line: the render's state (info, busy) and, on a line of its
        own, the last refusal (error), kept until a request is accepted so a
        render finishing meanwhile does not hide it."""
        if level == "error":
            self._error_text = text
        else:
            self._status_text, self._status_level = text, level
        colours = {"info": "#1a5e1a", "busy": "#555555", "error": "#b00020"}
        parts = [(self._status_level, self._status_text), ("error", self._error_text)]
        self.status.object = "<br>".join(
            f'<span class="sb-{lv}" style="color:{colours[lv]}">{html.escape(t)}</span>'
            for lv, t in parts if t
        )

    def _on_ranges(self, event):
        if None in (event.x0, event.x1, event.y0, event.y1):
            return
        new = self.view.with_window(event.x0, event.x1, event.y0, event.y1)
        if new != self.view:
            self._request(new)

    def _on_window_text(self, _event):
        if self._syncing:
            return
        try:
            e_lo, e_hi = parse_window("e window", self.e_window.value, 1.0)
            u_lo, u_hi = parse_window("u window", self.u_window.value, U_LIMIT)
        except ValueError as exc:
            self._message(str(exc), "error")
            return
        self._goto(self.view.with_window(e_lo, e_hi, u_lo, u_hi))

    def _on_fig4(self, _event):
        self._goto(self.view.with_window(DEFAULT_VIEW.e_lo, DEFAULT_VIEW.e_hi,
                                         DEFAULT_VIEW.u_lo, DEFAULT_VIEW.u_hi))

    def _goto(self, view):
        """Move the plot's ranges (the image follows when computed)."""
        try:
            check_view(view)
        except ValueError as exc:
            self._message(str(exc), "error")
            return
        self.map_fig.x_range.update(start=view.e_lo, end=view.e_hi)
        self.map_fig.y_range.update(start=view.u_lo, end=view.u_hi)
        self._request(view)

    def _on_settings(self, _event):
        if self._syncing:
            return
        try:
            new = replace(self.view, max_iter=int(self.max_iter.value), width=int(self.width_in.value),
                          height=int(self.height_in.value))
        except (TypeError, ValueError):
            self._message("max_iter, width and height must be integers", "error")
            return
        if new != self.view:
            self._request(new)

    def _on_color(self, _event):
        new = replace(self.view, color=self.color.value)
        key = color_key(new.color)
        self.mapper.update(palette=list(key.colors), low=-0.5, high=len(key.colors) - 0.5)
        self.colorbar.update(title=key.title, ticker=FixedTicker(ticks=key.ticks),
                             major_label_overrides={i: s for i, s in enumerate(key.labels)})
        self.view = new
        if self.ds is not None and self.shown is not None and has_color(self.ds, new.color):
            self.shown = replace(self.shown, color=new.color)
            self.img_src.patch({"image": [(0, shade(self.ds, new.color))]})
        elif self.ds is not None:
            self._request(new)  # the motion fields are computed on demand
        self._sync_url()

    def _on_overlays(self, _event):
        self.view = replace(self.view, overlays=tuple(o for o in ("tongues", "no_sliding")
                                                      if o in self.overlays.value))
        self._draw_overlays(self.view)
        self._sync_url()

    def _draw_overlays(self, view):
        curves = overlay_curves(view)
        for name, src in (("tongues", self.tongue_src), ("no_sliding", self.bound_src)):
            xs, ys = curves[name] if name in view.overlays else ([], [])
            src.data = dict(xs=list(xs), ys=list(ys))

    def _sync_url(self):
        if pn.state.location is not None:
            pn.state.location.search = view_url_query(self.view)

    def _sync_widgets(self, view):
        self._syncing = True
        try:
            self.e_window.value = format_window(view.e_lo, view.e_hi)
            self.u_window.value = format_window(view.u_lo, view.u_hi)
            self.max_iter.value = view.max_iter
            self.width_in.value = view.width
            self.height_in.value = view.height
        finally:
            self._syncing = False

    # --------------------------------------------------------------- renders

    def _request(self, view: View):
        """Ask for a render of ``view``: refused at once when over budget, else
        queued behind (and cancelling) the one in progress."""
        try:
            check_view(view)
        except ValueError as exc:
            self._message(str(exc), "error")
            return
        self.view = view
        self._error_text = ""
        self._sync_widgets(view)
        self._sync_url()
        self._draw_overlays(view)
        if (view.width, view.height) != (self.map_fig.frame_width, self.map_fig.frame_height):
            self.map_fig.update(frame_width=view.width, frame_height=view.height)
        self._gen += 1
        self._pending = view
        self._message(f"computing {view.width} x {view.height} pixels, max_iter {view.max_iter} ...",
                      "busy")
        if not self._running:
            self._start()

    def _start(self):
        view, self._pending = self._pending, None
        gen = self._gen
        self._running = True
        self._executor.submit(self._work, gen, view)

    def _work(self, gen, view):
        """On the worker thread: compute, then hand the result to the document."""
        t0 = time.perf_counter()

        def progress(done, total):
            if done < total:
                self._next_tick(self._show_progress, gen, view, done, total)

        try:
            ds = compute_view(view, cancelled=lambda: gen != self._gen, progress=progress)
            rgba = shade(ds, view.color)
            result = (ds, rgba, time.perf_counter() - t0)
        except Cancelled:
            result = None
        except Exception as exc:  # shown on the page; the server keeps going
            result = exc
        self._next_tick(self._finish, gen, view, result)

    def _next_tick(self, fn, *args):
        if self._doc is None:  # no server (tests): run here
            fn(*args)
            return
        try:
            self._doc.add_next_tick_callback(partial(self._in_doc, fn, *args))
        except Exception:  # the page was closed meanwhile: nobody to show it to
            pass

    def close(self):
        """The session ended: cancel what is queued or running for it."""
        self._gen += 1
        self._tap_gen += 1
        self._pending = None

    def _in_doc(self, fn, *args):
        with set_curdoc(self._doc):
            fn(*args)

    def _show_progress(self, gen, view, done, total):
        if gen == self._gen:
            self._message(f"computing {view.width} x {view.height} pixels, max_iter "
                          f"{view.max_iter} ... {100 * done // total}%", "busy")

    def _finish(self, gen, view, result):
        self._running = False
        if isinstance(result, Exception):
            self._message(f"render failed: {result}", "error")
        elif result is not None and gen == self._gen:
            ds, rgba, seconds = result
            self.ds, self.shown = ds, view
            self.img_src.data = dict(image=[rgba], x=[view.e_lo], y=[view.u_lo],
                                     dw=[view.e_hi - view.e_lo], dh=[view.u_hi - view.u_lo])
            frac = float((ds["status"].values == 0).mean())
            self._message(
                f"e {view.e_lo:.12g} to {view.e_hi:.12g}, u {view.u_lo:.12g} to {view.u_hi:.12g}: "
                f"{view.width} x {view.height} pixels, max_iter {view.max_iter}, "
                f"{100 * frac:.1f}% with a periodic sliding solution, computed in {seconds:.2f} s",
                "info",
            )
            self.png_button.filename = export_name(view, ".png")
            self.nc_button.filename = export_name(view, ".nc")
        if self._pending is not None:
            self._start()

    # ------------------------------------------------------------------- tap

    def _on_tap(self, event):
        if event.x is None or event.y is None:
            return
        e, u = float(event.x), float(event.y)
        # the tapped pixel's centre: exactly the (e, u) its colour was computed at
        if self.shown is not None and self.ds is not None:
            ij = pixel_of(self.shown, e, u)
            if ij is not None:
                e, u = float(self.ds.e.values[ij[1]]), float(self.ds.u.values[ij[0]])
        if not (0.0 <= e < 1.0 and 0.0 < u <= U_LIMIT):
            self._message(f"no point at e = {e:.6g}, u = {u:.6g}: need 0 <= e < 1, 0 < u <= {U_LIMIT:g}",
                          "error")
            return
        self.view = replace(self.view, point=(e, u))
        self._sync_url()
        self._request_point(e, u)

    def _request_point(self, e, u):
        self._tap_gen += 1
        gen = self._tap_gen
        self.point_src.data = dict(x=[e], y=[u])
        self.point_pane.object = f"<i>computing the orbit at e = {e!r}, u = {u!r} ...</i>"
        self._executor.submit(self._point_work, gen, e, u, self.view)

    def _point_work(self, gen, e, u, view):
        try:
            details = point_details(e, u, view.max_iter)
            orbit = orbit_along_u(e, max(view.u_lo, 0.0), view.u_hi)
            result = (details, orbit)
        except Exception as exc:
            result = exc
        self._next_tick(self._show_point, gen, view, result)

    def _show_point(self, gen, view, result):
        if gen != self._tap_gen:
            return
        if isinstance(result, Exception):
            self.point_pane.object = f"<b>failed:</b> {html.escape(str(result))}"
            return
        d, orbit = result
        e, u, w = d["e"], d["u"], d["word"]
        if w is None:
            rows = [("word", f"none: the orbit of (1, 0) does not slide within max_iter = "
                             f"{view.max_iter} steps")]
            title = f"trajectory from (1, 0), {d['steps']} steps (no sliding found)"
        else:
            rows = [("word", f'<span class="sb-word">{html.escape(w.format())}</span>'),
                    ("length", str(len(w))), ("period", f"{w.period} steps"),
                    ("impacts", f"{w.impacts} per period (plus the accumulation)"),
                    ("non-zero letters", str(w.jumps))]
            title = f"trajectory from (1, 0), {d['steps']} steps (period {w.period})"
        rows = [("e", f'<span class="sb-e">{e!r}</span>'), ("u", f'<span class="sb-u">{u!r}</span>')] + rows
        m = d.get("motion")
        if m is not None and not m["slides"]:
            rows += [("&lt;k&gt;", f'<span class="sb-k">{m["k_mean"]:.6g}</span> impacts per step '
                                   f'(halves differ by {m["k_err"]:.2g})'),
                     ("mean jump", f'{m["jump_mean"]:.6g} steps per landing'),
                     ("&lambda;<sub>1</sub>", f'{m["lyap1"]:+.2e} &plusmn; {m["lyap1_err"]:.1e} (0 exactly)'),
                     ("&lambda;<sub>2</sub>", f'{m["lyap2"]:+.4e} = 2&lt;k&gt; log e')]
        elif m is not None:
            rows += [("motion", f'slides on step {m["slide_step"]} of 2 max_iter')]
        sec = d.get("section")
        self.section_src.data = dict(x=sec[0], y=sec[1]) if sec is not None else dict(x=[], y=[])
        self.section_fig.title.text = (f"Poincare section at e = {e:.6g}, u = {u:.6g}: last "
                                       f"{len(sec[0])} iterates from (1, 0)" if sec is not None else
                                       "Poincare section: none (the orbit slides)")
        self.point_pane.object = "<table>" + "".join(
            f"<tr><td><b>{k}</b></td><td>{v}</td></tr>" for k, v in rows) + "</table>"
        steps = d["steps"]
        sx = np.repeat(np.arange(-1, steps + 1), 2)[1:].astype(float)
        sy = -np.repeat(np.arange(-1, steps + 1), 2)[:-1].astype(float)
        self.stairs_src.data = dict(x=sx, y=sy)
        self.path_src.data = dict(x=d["path"][0], y=d["path"][1])
        self.impact_src.data = dict(x=d["impacts"][0], y=d["impacts"][1])
        self.accum_src.data = dict(x=d["accumulations"][0], y=d["accumulations"][1])
        self.slide_src.data = dict(xs=[[a, b] for a, b, _ in d["slides"]],
                                   ys=[[y, y] for _, _, y in d["slides"]])
        self.traj_fig.title.text = title
        y = orbit["y"].values
        self.orbit_src.data = dict(x=np.repeat(orbit["u"].values, y.shape[1]), y=y.ravel())
        self.orbit_fig.x_range.update(start=float(orbit["u"].values[0]), end=float(orbit["u"].values[-1]))
        finite = y[np.isfinite(y)]
        if finite.size:
            lo, hi = float(finite.min()), float(finite.max())
            pad = 0.05 * (hi - lo) or 0.5
            self.orbit_fig.y_range.update(start=lo - pad, end=hi + pad)
        self.orbit_marker.update(location=u, visible=True)
        self.orbit_fig.title.text = f"orbit diagram at e = {e:.6g}, iterates 2001-2200 from (0.1, 0)"

    # --------------------------------------------------------------- exports

    def _png(self):
        if self.ds is None:
            raise ValueError("nothing computed yet")
        return io.BytesIO(view_png(self.ds, self.shown))

    def _netcdf(self):
        if self.ds is None:
            raise ValueError("nothing computed yet")
        return io.BytesIO(view_netcdf(self.ds))


def warm_up(executor=_EXECUTOR):
    """Load the compiled kernels on the worker thread before the first page
    asks for them (numba's cache still takes a second or two to load)."""
    tiny = replace(DEFAULT_VIEW, width=16, height=16, max_iter=10)

    def run():
        compute_view(tiny)
        point_details(0.1, 0.75, 10)
        orbit_along_u(0.1, 0.5, 1.0, n=4, transient=2, keep=2)

    return executor.submit(run)


def create_app():
    """The page of one session: the view from the URL query, validated
    (:func:`~stairbounce.explorer.view.parse_query`)."""
    view, messages = parse_query(pn.state.session_args if pn.state.curdoc else {})
    explorer = Explorer(view, messages)
    pn.state.onload(explorer.start)
    pn.state.on_session_destroyed(lambda _ctx: explorer.close())
    return explorer.layout
