"""The Panel (Bokeh) page of ``stairbounce explore``.

One :class:`Explorer` per browser session.  The map is a Bokeh ``image_rgba``
recomputed at the view's pixel size after every pan or zoom (Bokeh's
``RangesUpdate`` event, one per gesture); a tap shows the word, trajectory and
orbit diagram of the tapped pixel.  All dynamics runs on the shared
:class:`~stairbounce.explorer.scheduler.Scheduler` (one worker thread, slices
of bounded work, the least recently busy session first with a quantum for
the job under way, a session's new request superseding its own pending one),
so the server's event loop keeps serving every page; results come back to
the document with ``add_next_tick_callback``, the Bokeh server's thread-safe
way in, and every callback holds the document until it ends (see
:meth:`Explorer._in_doc`).  A render that takes time shows a coarse preview
first (every 8th pixel), then fills in rows.
Downloads are made on their own thread.  The browser's history is kept by
the page itself (a pan, zoom or new window is a history entry; Back and
Forward restore the view).
"""

from __future__ import annotations

import asyncio
import io
import math
import threading
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace
from functools import partial
from urllib.parse import parse_qs

import numpy as np
import panel as pn
from bokeh.events import RangesUpdate, Tap
from bokeh.models import (
    ColorBar,
    ColumnDataSource,
    CustomJS,
    Div,
    CustomJSHover,
    HoverTool,
    Legend,
    LegendItem,
    LinearColorMapper,
    Range1d,
    TapTool,
)
from bokeh.plotting import figure
from panel.io.state import set_curdoc

from .._colours import kinds_legend
from .export import view_netcdf, view_png
from .preview import REMOVE_JS
from ._common import _border_key, _plural
from .controls import Controls
from .borders_layer import BordersLayer
from .proven_layer import ProvenLayer
from .scan_layer import _HOVER_VALUE_JS, ScanLayer, _bar_settings, _placeholder
from .scheduler import Scheduler
from .tap_panel import TapPanel
from .view import (
    DEFAULT_VIEW,
    NOT_COMPUTED_COLOR,
    OVERLAYS,
    U_LIMIT,
    View,
    check_view,
    orbit_along_u,
    overlay_curves,
    parse_query,
    point_details,
    render_slices,
    view_url_query,
)

__all__ = ["Explorer", "create_app", "warm_up", "SCHEDULER"]

SCHEDULER = Scheduler()
"""The one scheduler every session of this process shares."""

# downloads (matplotlib, netCDF) run here, off the event loop and off the
# scheduler (they use no numba kernel)
_EXPORTS = ThreadPoolExecutor(max_workers=1, thread_name_prefix="stairbounce-export")

# set once the compiled kernels are loaded (warm_up)
_WARM = threading.Event()


_OVERLAY_LEGEND = {"tongues": "tongues (n, 0^\u221e), Thm 3.1", "no_sliding": "u = (1-e)/(2\u221a(2e)), Cor. 2.1",
                   "borders": f"exact border points: {kinds_legend()}",
                   "traced": f"traced borders between words: {kinds_legend(('graze', 'edge', 'chatter', 'window'))}",
                   "proven": ProvenLayer.legend}


# milliseconds without wheel events after which a wheel zoom is taken as done
ZOOM_SETTLE_MS = 150


_CSS = """
.sb-status { font-family: monospace; font-size: 13px; min-height: 2.6em; }
.sb-point { font-size: 13px; }
.sb-word { font-family: monospace; font-size: 15px; font-weight: bold; }
"""

# The address bar is written by the page itself: Panel's Location pushes a
# history entry on every change and ignores Back/Forward.  Two models that are
# never shown carry it: ``out.text`` is "push ?query" or "replace ?query"
# (server -> browser); a Back/Forward sets ``back.text`` to "<time> ?query"
# (browser -> server), which the server turns back into the view.
_HISTORY_JS = """
if (!window.__sb_popstate) {
  window.__sb_popstate = true;
  window.addEventListener('popstate', () => {
    back.text = String(Date.now()) + ' ' + window.location.search;
  });
}
const sp = out.text.indexOf(' ');
const mode = out.text.slice(0, sp), query = out.text.slice(sp + 1);
if (window.location.search !== query) {
  const url = window.location.pathname + query + window.location.hash;
  if (mode === 'push') window.history.pushState({}, '', url);
  else window.history.replaceState({}, '', url);
}
"""


class Explorer(Controls, ScanLayer, TapPanel):
    """The widgets, figures and render pipeline of one browser session."""

    def __init__(self, view: View = DEFAULT_VIEW, messages=(), scheduler: Scheduler | None = None):
        self.view = view  # what is asked for
        self.shown: View | None = None  # what the image shows
        self.ds = None
        self._sched = SCHEDULER if scheduler is None else scheduler
        self._doc = pn.state.curdoc
        self._gen = 0
        self._tap_gen = 0
        self._point_text = ""  # the tap's word line, the word table row appended below it
        # the word table of the last tap's view: ((grid, max_iter), Dataset), reused by the next tap there
        self._word_table = None
        # the certified atlas last computed: (proven key, CertifiedAtlas, seconds); the one wanted; its line
        # the tap's pane: word lines, the certificate's line, the non-sliding motion's table
        self._cert_html, self._motion_html = "", ""
        self._cert_gen = -1  # the tap whose certificate is shown
        self._syncing = False
        self._closed = False
        self._connected = False
        self._status_text, self._status_level, self._error_text = "", "info", ""
        self._refused_side = None  # (size widget, value) of the last refused size edit
        self._last_ranges = -math.inf  # time.monotonic() of the last range change

        # the layers composed (layer.Layer): each its glyphs, job, key and tap
        self.borders = BordersLayer(self)
        self.proven = ProvenLayer(self)
        self.layers = [self.borders, self.proven]  # drawn in this order, their status lines too
        self._build_map()
        self._build_point_figures()
        self._build_widgets(messages)
        self.history_out, self.history_back = Div(text="", visible=False), Div(text="", visible=False)
        self.history_out.js_on_change(
            "text", CustomJS(args=dict(out=self.history_out, back=self.history_back), code=_HISTORY_JS))
        self.history_back.on_change("text", self._locked_bokeh(self._on_popstate))
        # referenced from the map, the two models are in the page's document
        self.map_fig.tags = [self.history_out, self.history_back]
        # the tap's panels: a row of their own below the map, the page's full
        # width; put in the page by the first tap (they are more than half of
        # the page's models: a new page's document is half the size without them)
        self._tap_panes = [
            pn.pane.Bokeh(self.traj_fig, sizing_mode="stretch_width"),
            pn.Row(pn.pane.Bokeh(self.orbit_fig, sizing_mode="stretch_width"),
                   pn.pane.Bokeh(self.section_fig, sizing_mode="stretch_width"),
                   sizing_mode="stretch_width"),
        ]
        self.tap_panels = pn.Column(sizing_mode="stretch_width", styles={"flex": "1 1 100%"},
                                    css_classes=["sb-tap-panels"])
        # the status and the tap's word sit above the map, so a laptop screen
        # (1280 x 720) shows them without scrolling; a flex box wraps the
        # trajectory and orbit diagram below the map when the window is narrow
        self.layout = pn.FlexBox(
            pn.Column(
                # HTML, not Markdown: Markdown headings get a stray anchor link
                pn.pane.HTML(
                    "<h2>stairbounce explorer</h2><p>Periodic sliding solutions of a ball bouncing "
                    "down a staircase. Scroll to zoom, drag to pan, tap a point for its orbit; "
                    "Back undoes a zoom.</p>",
                    width=290, margin=(0, 10), css_classes=["sb-title"],
                ),
                self.color, self.max_iter, pn.Row(self.width_in, self.height_in),
                self.e_window, self.u_window, pn.Row(self.go_button, self.fig4_button),
                self.overlays,
                pn.Row(self.png_button, self.nc_button),
                self.url_messages,
                width=310,
            ),
            pn.Column(self.status, self.point_pane, pn.pane.Bokeh(self.map_fig), self.key_note, self.borders.note,
                      self.proven.note),
            self.tap_panels,
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
            tools="pan,wheel_zoom,box_zoom,reset",
            active_drag="pan",
            active_scroll="wheel_zoom",
            toolbar_location="above",
            x_axis_label="e (restitution coefficient)",
            y_axis_label="u (horizontal speed)",
            title="periodic sliding solutions in the (e, u) plane",
            min_border_left=70,
            # a wheel zoom reports its new ranges (RangesUpdate) once the wheel
            # has been still this long: Bokeh's default 500 ms is most of the
            # wait for the next picture; a trackpad's wheel events come every
            # ~16 ms, so a gesture in progress still sends one request
            lod_timeout=ZOOM_SETTLE_MS,
        )
        fig.toolbar.logo = None
        # not yet computed: grey, so it is not mistaken for white (no sliding)
        fig.background_fill_color = NOT_COMPUTED_COLOR
        fig.xgrid.visible = fig.ygrid.visible = False
        self.img_src = ColumnDataSource(
            dict(image=[np.zeros((1, 1), np.uint32)], val=[_placeholder(v.color)],
                 x=[v.e_lo], y=[v.u_lo], dw=[v.e_hi - v.e_lo], dh=[v.u_hi - v.u_lo])
        )
        img = fig.image_rgba(image="image", x="x", y="y", dw="dw", dh="dh", source=self.img_src)
        proven, = self.proven.build(fig)
        # the picture sent with the page's HTML (.preview) goes when the session's first pixels come
        self.img_src.js_on_change("data", CustomJS(code=REMOVE_JS))
        self.hover = HoverTool(renderers=[img], formatters={
            "$x": "printf", "$y": "printf", "@val": CustomJSHover(code=_HOVER_VALUE_JS)})
        fig.add_tools(self.hover)
        self._set_hover(v)
        self.tongue_src = ColumnDataSource(dict(xs=[], ys=[]))
        self.bound_src = ColumnDataSource(dict(xs=[], ys=[]))
        # grey outlines show on the black tongues and on the white no-sliding region alike
        tongues = fig.multi_line("xs", "ys", source=self.tongue_src, line_color="#7a7a7a", line_width=1)
        bound = fig.multi_line("xs", "ys", source=self.bound_src, line_color="#d62728", line_width=2,
                               line_dash="dashed")
        borders, arcs = self.borders.build(fig)
        self._overlay_items = {
            "tongues": LegendItem(label=_OVERLAY_LEGEND["tongues"], renderers=[tongues]),
            "no_sliding": LegendItem(label=_OVERLAY_LEGEND["no_sliding"], renderers=[bound]),
            "borders": LegendItem(label=_OVERLAY_LEGEND["borders"], renderers=[borders]),
            "traced": LegendItem(label=_OVERLAY_LEGEND["traced"], renderers=[arcs]),
            "proven": LegendItem(label=_OVERLAY_LEGEND["proven"], renderers=[proven]),
        }
        self.legend = Legend(items=[], orientation="horizontal", label_text_font_size="9pt",
                             border_line_alpha=0)
        fig.add_layout(self.legend, "below")
        self.point_src = ColumnDataSource(dict(x=[], y=[]))
        fig.scatter("x", "y", source=self.point_src, marker="circle_cross", size=14,
                    fill_alpha=0.0, line_color="#ff00ff", line_width=2)
        mapper, bar = _bar_settings(v.color)
        self.mapper = LinearColorMapper(**mapper)
        self.colorbar = ColorBar(color_mapper=self.mapper, width=14, bar_line_color="black", **bar)
        fig.add_layout(self.colorbar, "right")
        # a tap selects nothing (Bokeh would fade the other glyphs): it is the Tap event's point
        fig.add_tools(TapTool(renderers=[]))
        fig.on_event(RangesUpdate, self._locked_event(self._on_ranges))
        fig.on_event(Tap, self._locked_event(self._on_tap))
        self.map_fig = fig


    # ------------------------------------------------------------ interaction

    def start(self):
        """First render (and the URL's point) once the page is connected."""
        self._connected = True
        self._set_url("replace")
        self._draw_overlays(self.view, borders=False)  # the borders after the render (_request)
        self._request(self.view, history=None)
        if self.view.point is not None:
            self._request_point(*self.view.point)


    def _draw_overlays(self, view, borders=True):
        curves = overlay_curves(view)
        for name, src in (("tongues", self.tongue_src), ("no_sliding", self.bound_src)):
            xs, ys = curves[name] if name in view.overlays else ([], [])
            src.data = dict(xs=list(xs), ys=list(ys))
        if borders:
            for layer in self.layers:
                layer.draw(view)
        self.legend.items = [self._overlay_items[n] for n in OVERLAYS if n in view.overlays]
        self.borders.note.visible = "traced" in view.overlays
        self.legend.visible = bool(view.overlays)

    # ----------------------------------------------------------- proven boxes


    # ---------------------------------------------------------- exact borders


    def _set_url(self, mode):
        """Address bar := the view's query; ``push`` makes a history entry."""
        self.history_out.text = f"{mode} {view_url_query(self.view)}"

    def _on_popstate(self, popped):
        """Back or Forward: show the view of the address bar's query."""
        query = popped.partition(" ")[2]
        view, _messages = parse_query({k: v[-1] for k, v in parse_qs(query.lstrip("?")).items()})
        self._syncing = True
        try:
            self.color.value = view.color
            self.overlays.value = list(view.overlays)
        finally:
            self._syncing = False
        if view.color != self.view.color:
            self._apply_color(view.color)
        if view.overlays != self.view.overlays:
            self.view = replace(self.view, overlays=view.overlays)
            self._draw_overlays(self.view)
        if view.point is not None and view.point != self.view.point:
            self.view = replace(self.view, point=view.point)
            self._request_point(*view.point)
        self._goto(replace(view, point=self.view.point), history=None)
        self._set_url("replace")  # the address bar already shows it: a no-op in the browser


    # --------------------------------------------------------------- renders

    def _request(self, view: View, history="push"):
        """Ask for a render of ``view``: refused at once when over budget, else
        handed to the scheduler (superseding this session's pending render)."""
        try:
            check_view(view)
        except ValueError as exc:
            self._refuse(exc)
            return
        self.view = view
        self._error_text = ""
        self._sync_widgets(view)
        if history is not None:
            self._set_url(history)
        self._draw_overlays(view, borders=False)
        if (view.width, view.height) != (self.map_fig.frame_width, self.map_fig.frame_height):
            self.map_fig.update(frame_width=view.width, frame_height=view.height)
        self._gen += 1
        gen = self._gen
        job = self._sched.submit(
            self, "render", self._render_work(view),
            on_slice=lambda value: self._next_tick(self._show_partial, gen, view, value),
            on_done=lambda result, error, job: self._next_tick(self._finish, gen, view, result, error, job),
            alive=self._alive,
        )
        if gen == self._gen and job.started is False:
            self._message(self._waiting_text(view, job), "busy")
        for layer in self.layers:  # queued after the render: the picture comes first
            layer.draw(view)

    def _waiting_text(self, view, job):
        what = f"{view.width} x {view.height} pixels, max_iter {view.max_iter}"
        if not _WARM.is_set() and self._sched is SCHEDULER:
            return (f"queued ({what}): the server is loading its compiled kernels (the first start "
                    "after an install compiles them, up to a minute)")
        n = self._sched.ahead_of(job)
        if n:
            return (f"queued ({what}): taking turns with {_plural(n, 'request')} of other "
                    "sessions, cheap ones first")
        return f"computing {what} ..."


    def _alive(self):
        """False once the page is gone: its queued work is dropped at once,
        without waiting for Bokeh to destroy the session (15 s or more)."""
        if self._closed:
            return False
        ctx = self._doc.session_context if self._doc is not None else None
        session = getattr(ctx, "_session", None)
        if session is None or not self._connected:
            return True
        return session.connection_count > 0

    def _next_tick(self, fn, *args):
        """Run ``fn`` on the page's document at the server's next tick (any
        thread may ask); without a server (tests), here and now."""
        if self._doc is None or self._doc.session_context is None:
            fn(*args)
            return
        try:
            self._doc.add_next_tick_callback(partial(self._in_doc, fn, *args))
        except Exception:  # the page was closed meanwhile: nobody to show it to
            pass

    def close(self):
        """The session ended: cancel what is queued or running for it."""
        self._closed = True
        self._gen += 1
        self._tap_gen += 1
        self._sched.cancel(self)

    def _in_doc(self, fn, *args):
        """Run ``fn`` on the page's document (under its lock), holding the
        document's change events until it returns.

        Held, the changes reach the browser through Bokeh's own ordered
        writes when ``fn`` ends.  Not held, Panel 1.9 sends a pane's or
        widget's change itself and, when the websocket is busy writing (a
        picture), queues it; two such queues can race and the last change
        is never sent (the page kept "computing ... 83%" over a finished
        picture while other visitors loaded the page).  Without a document
        (tests) ``fn`` just runs.
        """
        doc = self._doc
        if doc is None:
            fn(*args)
            return
        with set_curdoc(doc):
            if doc.callbacks.hold_value is not None:  # someone holds it already: they release it
                fn(*args)
                return
            doc.hold("combine")
            try:
                fn(*args)
            finally:
                doc.unhold()


    # ------------------------------------------------------------------- tap


    # --------------------------------------------------------------- exports

    async def _png(self):
        """The PNG of the view shown, made on the export thread, with the exact
        borders (points and traced arcs) as drawn when they are the shown view's."""
        ds, shown = self.ds, self.shown
        drawn = None
        if shown is not None and self.borders.want[0] is not None and self.borders.want[0] == _border_key(shown):
            drawn = {"points": {k: list(self.borders.border_src.data[k]) for k in ("e", "u", "kind")},
                     "arcs": {k: list(self.borders.arc_src.data[k]) for k in ("xs", "ys", "kind")}}
        data = await asyncio.wrap_future(_EXPORTS.submit(view_png, ds, shown, borders=drawn))
        return io.BytesIO(data)

    async def _netcdf(self):
        ds = self.ds
        data = await asyncio.wrap_future(_EXPORTS.submit(view_netcdf, ds))
        return io.BytesIO(data)


def warm_up(scheduler: Scheduler | None = None):
    """Load (or, on the first start after an install, compile) the kernels on
    the scheduler's thread before any page needs them; returns a
    :class:`threading.Event` set when done."""
    sched = SCHEDULER if scheduler is None else scheduler
    tiny = replace(DEFAULT_VIEW, width=16, height=16, max_iter=10)

    def work():
        for _ in render_slices(tiny):
            pass
        point_details(0.1, 0.75, 10)
        orbit_along_u(0.1, 0.5, 1.0, n=4, transient=2, keep=2)
        yield
        return None

    _WARM.clear()
    sched.submit("warm-up", "warm-up", work(), on_done=lambda result, error, _job: _WARM.set())
    return _WARM


def create_app():
    """The page of one session: the view from the URL query, validated
    (:func:`~stairbounce.explorer.view.parse_query`)."""
    view, messages = parse_query(pn.state.session_args if pn.state.curdoc else {})
    explorer = Explorer(view, messages)
    pn.state.onload(partial(explorer._in_doc, explorer.start))
    pn.state.on_session_destroyed(lambda _ctx: explorer.close())
    return explorer.layout
