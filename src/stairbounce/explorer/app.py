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
import html
import io
import math
import threading
import time
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
    FixedTicker,
    HoverTool,
    Legend,
    LegendItem,
    LinearColorMapper,
    Range1d,
    Span,
    TapTool,
)
from bokeh.plotting import figure
from panel.io.state import set_curdoc

from .._colours import KIND_COLOURS, kinds_legend
from .export import export_name, view_netcdf, view_png
from .preview import REMOVE_JS
from .proven import MIN_BOX_PX, STYLES, TAP_CERTIFICATE_STEPS, proven_at, proven_depth, proven_image, proven_slices, proven_summary
from .scheduler import Scheduler
from .view import (
    DEFAULT_VIEW,
    FIELDS,
    MAX_ITER_LIMIT,
    MOTION_COLOR_VARS,
    NO_SLIDING_COLOR,
    NO_SLIDING_LABEL,
    NOT_COMPUTED_COLOR,
    OVERLAYS,
    SLIDES_COLOR,
    TRACE_SIDE,
    U_LIMIT,
    View,
    BORDER_SIDE,
    border_grid,
    border_overlay,
    check_view,
    color_key,
    format_number,
    format_window,
    has_color,
    orbit_along_u,
    overlay_curves,
    parse_query,
    parse_window,
    pixel_of,
    point_details,
    border_point_slices,
    word_row_slices,
    preview_rgba,
    render_slices,
    shade,
    tidy,
    trace_slices,
    trace_window,
    traced_overlay_slices,
    view_url_query,
    window_digits,
)

__all__ = ["Explorer", "create_app", "warm_up", "SCHEDULER"]

SCHEDULER = Scheduler()
"""The one scheduler every session of this process shares."""

# downloads (matplotlib, netCDF) run here, off the event loop and off the
# scheduler (they use no numba kernel)
_EXPORTS = ThreadPoolExecutor(max_workers=1, thread_name_prefix="stairbounce-export")

# set once the compiled kernels are loaded (warm_up)
_WARM = threading.Event()

# least time between two preview pictures of one render sent to the browser,
# and their largest side in pixels (a preview is subsampled to it: a 1000 x
# 1000 preview would be 4 MB on the websocket, shared by every session)
_PREVIEW_EVERY = 1.0
_PREVIEW_SIDE = 300
# no preview for a render that is done sooner than this after its first slice
# (s): the picture itself is about to come, and each picture costs every
# browser showing it a repaint
_PREVIEW_AFTER = 0.25

_COLOR_OPTIONS = {menu: var for var, (menu, _, _) in FIELDS.items()}
_OVERLAY_OPTIONS = {"tongues (n, 0^\u221e), Thm 3.1": "tongues", "no-sliding bound, Cor. 2.1": "no_sliding",
                    "exact borders (graze, edge, chatter)": "borders",
                    "exact borders as traced arcs (seconds)": "traced",
                    "proven: certified atlas (interval arithmetic)": "proven"}
_OVERLAY_LEGEND = {"tongues": "tongues (n, 0^\u221e), Thm 3.1", "no_sliding": "u = (1-e)/(2\u221a(2e)), Cor. 2.1",
                   "borders": f"exact border points: {kinds_legend()}",
                   "traced": f"traced borders between words: {kinds_legend(('graze', 'edge', 'chatter', 'window'))}",
                   "proven": "certified atlas: proven boxes solid, undecided hatched (key below the map)"}

# width (px) of the invisible copy of the traced arcs that carries their hover: the pointer
# within half of it from an arc reports the arc
ARC_HOVER_PX = 14

# what the traced arcs are, under the map while they are drawn (the legend names their colours)
_ARCS_NOTE = ('<span style="font-size:12px">Traced arcs: the exact borders between two words (the edges of '
              "sb.border_graph of the view's traced regions), coloured by the event that changes the word "
              f"({kinds_legend(('graze', 'edge', 'chatter'))}; the window's sides grey). Hover near an arc "
              "for its kind, its step and the words on its two sides.</span>")

# the traced arcs' colour on the window's sides (the other kinds: plot.borders.KIND_COLORS)
_WINDOW_ARC_COLOR = KIND_COLOURS["window"]
# least time between two "tracing borders: N of M words" lines sent to the page (s)
_TRACE_PROGRESS_EVERY = 0.25

# milliseconds without wheel events after which a wheel zoom is taken as done
ZOOM_SETTLE_MS = 150
# range changes (wheel, pan, box zoom) that follow one another within this
# many seconds are one gesture: one history entry, so Back returns to the view
# before it (a wheel turned in notches, on a loaded machine, reports a
# RangesUpdate every few notches)
GESTURE_MERGE_S = 1.0

# the proven overlay's picture before an atlas is drawn (nothing), and its hover: the box's label
_NO_PROVEN_IMAGE = dict(image=[], code=[], x=[], y=[], dw=[], dh=[])
_PROVEN_HOVER_JS = "return value >= 0 && value < names.length ? names[value] : 'none';"

# the longest trajectory drawn for a tap, in steps (one full period when shorter)
MAX_TRAJECTORY_STEPS = 2000

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

_HOVER_VALUE_JS = """
if (value == null || Number.isNaN(value) || value < -1) return 'computing';
return value < 0 ? 'none within max_iter' : String(value);
"""

# a motion field: NaN not computed yet, infinite where the orbit slides
_HOVER_MOTION_JS = """
if (value == null || Number.isNaN(value)) return 'computing';
if (!Number.isFinite(value)) return 'slides';
return value.toPrecision(5);
"""


def _plural(n, word):
    return f"{n} {word}" if n == 1 else f"{n} {word}s"


def _bar_key(var):
    """The colour bar's key: the variable's classes, then white for pixels
    without a periodic sliding solution within max_iter (a motion field's
    key has no white: its first class, grey, is "the orbit slides")."""
    key = color_key(var)
    if var in MOTION_COLOR_VARS or NO_SLIDING_COLOR in key.colors:  # "status" has white already
        return key
    return replace(key, colors=key.colors + (NO_SLIDING_COLOR,), labels=key.labels + (NO_SLIDING_LABEL,))


def _bar_settings(var):
    """Palette, range, ticks and labels of the colour bar of ``var``."""
    key = _bar_key(var)
    n = len(key.colors)
    return (dict(palette=list(key.colors), low=-0.5, high=n - 0.5),
            dict(title=key.title, ticker=FixedTicker(ticks=key.ticks),
                 major_label_overrides={i: s for i, s in enumerate(key.labels)}))


def _key_note(var):
    """The line under the map saying what white and grey mean."""
    if var in MOTION_COLOR_VARS:
        what = (f"grey ({SLIDES_COLOR}): the orbit of (1, 0) slides within 2 max_iter steps "
                "(no non-sliding motion)")
    else:
        what = "white: no periodic sliding solution within max_iter"
    return (f'<span style="font-size:12px">{what}; '
            f'grey ({NOT_COMPUTED_COLOR}): not computed yet</span>')


def _placeholder(var):
    """The hover value of a picture not computed yet."""
    return np.full((1, 1), np.nan, np.float32) if var in MOTION_COLOR_VARS else np.full((1, 1), -2, np.int32)


class Explorer:
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
        # the exact borders last drawn: ((grid, max_iter), border_points Dataset), reused by a tap
        self._borders = None
        # the word table of the last tap's view: ((grid, max_iter), Dataset), reused by the next tap there
        self._word_table = None
        # the traced borders last computed: ((trace window, max_iter, points' key), traced_overlay dict)
        self._traced = None
        # what the borders overlay shows or is computing: (points' key or None, trace key or None)
        self._borders_want = (None, None)
        self._borders_gen = 0
        self._trace_text, self._trace_level = "", "busy"
        # the certified atlas last computed: (proven key, CertifiedAtlas, seconds); the one wanted; its line
        self._proven = None
        self._proven_want = None
        self._proven_gen = 0
        self._proven_text, self._proven_level = "", "busy"
        # the tap's pane: word lines, the certificate's line, the non-sliding motion's table
        self._cert_html, self._motion_html = "", ""
        self._cert_gen = -1  # the tap whose certificate is shown
        self._syncing = False
        self._closed = False
        self._connected = False
        self._status_text, self._status_level, self._error_text = "", "info", ""
        self._refused_side = None  # (size widget, value) of the last refused size edit
        self._last_ranges = -math.inf  # time.monotonic() of the last range change

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
            pn.Column(self.status, self.point_pane, pn.pane.Bokeh(self.map_fig), self.key_note, self.arcs_note,
                      self.proven_note),
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
        # the certified atlas (overlay "proven", explorer/proven.py): one RGBA picture of its boxes with
        # their hatching (proven.proven_image; a glyph per box froze the browser), over the map and
        # under the curves; named for the browser tests
        self.proven_src = ColumnDataSource(_NO_PROVEN_IMAGE, name="sb-proven-image")
        proven = fig.image_rgba(image="image", x="x", y="y", dw="dw", dh="dh", source=self.proven_src)
        self._proven_names = CustomJSHover(args=dict(names=[]), code=_PROVEN_HOVER_JS)
        fig.add_tools(HoverTool(renderers=[proven], tooltips=[("certified box", "@code{custom}")],
                                formatters={"@code": self._proven_names}))
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
        self.border_src = ColumnDataSource(dict(e=[], u=[], kind=[], step=[], word_low=[],
                                                word_high=[], color=[]))
        borders = fig.scatter("e", "u", source=self.border_src, size=3, color="color", line_width=0)
        fig.add_tools(HoverTool(renderers=[borders], tooltips=[
            ("border", "@kind at step @step"), ("low side", "@word_low"), ("high side", "@word_high")]))
        # the traced arcs (view.traced_overlay): one polyline per arc; named for the browser tests
        self.arc_src = ColumnDataSource(dict(xs=[], ys=[], kind=[], step=[], word_low=[], word_high=[],
                                             color=[]), name="sb-traced-arcs")
        # a white casing under each arc (same data) sets it off from the map's orange and red classes
        fig.multi_line("xs", "ys", source=self.arc_src, line_color="white", line_width=4, line_alpha=0.8)
        arcs = fig.multi_line("xs", "ys", source=self.arc_src, line_color="color", line_width=2)
        # hovering near an arc reports it: the same arcs, invisible and ARC_HOVER_PX wide (Bokeh hit-tests
        # a line within half its width), carry the hover
        near = fig.multi_line("xs", "ys", source=self.arc_src, line_color="color", line_alpha=0.0,
                              line_width=ARC_HOVER_PX, name="sb-arc-hover")
        fig.add_tools(HoverTool(renderers=[near], line_policy="nearest", tooltips=[
            ("traced border arc", "@kind at step @step"), ("word below / left", "@word_low"),
            ("word above / right", "@word_high")]))
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

    def _build_point_figures(self):
        t = figure(height=340, sizing_mode="stretch_width", min_width=360, match_aspect=True, tools="pan,wheel_zoom,reset",
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
        t.legend.visible = False  # shown with the first tap
        self.traj_fig = t

        o = figure(height=300, sizing_mode="stretch_width", min_width=360, x_range=Range1d(0, 1.5), y_range=Range1d(0, 3),
                   tools="pan,wheel_zoom,box_zoom,reset",
                   title="orbit diagram along u: tap the map", output_backend="webgl",
                   x_axis_label="u", y_axis_label="y at the step edges")
        o.toolbar.logo = None
        self.orbit_src = ColumnDataSource(dict(x=[], y=[]))
        o.scatter("x", "y", source=self.orbit_src, size=1.5, color="black", alpha=0.35)
        self.orbit_marker = Span(location=0.0, dimension="height", line_color="#ff00ff",
                                 line_width=2, visible=False)
        o.add_layout(self.orbit_marker)
        self.orbit_fig = o

        p = figure(height=300, sizing_mode="stretch_width", min_width=360, tools="pan,wheel_zoom,box_zoom,reset", output_backend="webgl",
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
        self.u_window = pn.widgets.TextInput(label="u window (LO:HI), Enter applies both",
                                             value=format_window(v.u_lo, v.u_hi),
                                             width=280, css_classes=["sb-u-window"])
        self.go_button = pn.widgets.Button(label="Apply window", width=110, css_classes=["sb-go"])
        self.overlays = pn.widgets.CheckBoxGroup(
            options=_OVERLAY_OPTIONS, value=list(v.overlays), inline=False, width=280,
            css_classes=["sb-overlays"])
        self.fig4_button = pn.widgets.Button(label="Figure 4 window", width=160, css_classes=["sb-fig4"])
        # disabled until there is a view to download
        self.png_button = pn.widgets.FileDownload(
            callback=self._png, filename="stairbounce_view.png", label="Download PNG",
            color="primary", width=135, embed=False, disabled=True, css_classes=["sb-png"])
        self.nc_button = pn.widgets.FileDownload(
            callback=self._netcdf, filename="stairbounce_view.nc", label="Download .nc",
            color="primary", width=135, embed=False, disabled=True, css_classes=["sb-nc"])
        self.status = pn.pane.HTML("", css_classes=["sb-status"], width=700, margin=(0, 5))
        self.url_messages = pn.pane.Alert(
            '<div class="sb-url-text" style="overflow-wrap: anywhere">' + "<br>".join(html.escape(m) for m in messages) + "</div>",
            alert_type="warning",
            visible=bool(messages), width=290, margin=(10, 10), css_classes=["sb-url-messages"])
        self.point_pane = pn.pane.HTML(
            "<i>Tap a point of the map for its word; its trajectory and orbit diagram follow.</i>",
            css_classes=["sb-point"], width=700, margin=(0, 5))
        self.key_note = pn.pane.HTML(_key_note(v.color), css_classes=["sb-key-note"], width=700)
        self.proven_note = pn.pane.HTML("", css_classes=["sb-proven-note"], width=700, visible=False)
        self.arcs_note = pn.pane.HTML(_ARCS_NOTE, css_classes=["sb-arcs-note"], width=700,
                                      visible="traced" in v.overlays)

        self.color.param.watch(self._locked(self._on_color), "value")
        for w in (self.max_iter, self.width_in, self.height_in):
            w.param.watch(self._locked(self._on_settings), "value")
        # one apply for both windows: Enter in either box, or the button
        for w in (self.e_window, self.u_window):
            w.param.watch(self._locked(self._on_window_text), "enter_pressed")
        self.go_button.on_click(self._locked(self._on_window_text))
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
            if self._syncing:  # the page itself is setting the widgets (watchers fire now)
                return
            self._next_tick(fn, *args)

        return run

    def _locked_bokeh(self, fn):
        """A Bokeh property callback ``(attr, old, new)``; it holds the lock already."""
        return lambda attr, old, new: self._in_doc(fn, new)

    def _locked_event(self, fn):
        """A Bokeh UI event callback (pan, zoom, tap); it holds the lock already."""
        return lambda event: self._in_doc(fn, event)

    # ------------------------------------------------------------ interaction

    def start(self):
        """First render (and the URL's point) once the page is connected."""
        self._connected = True
        self._set_url("replace")
        self._draw_overlays(self.view, borders=False)  # the borders after the render (_request)
        self._request(self.view, history=None)
        if self.view.point is not None:
            self._request_point(*self.view.point)

    def _message(self, text, level="info"):
        """Status line: the render's state (info, busy) and, on a line of its
        own, the last refusal (error), kept until a request is accepted or
        the input is put back to the view shown, so a render finishing
        meanwhile does not hide it."""
        if level == "error":
            self._error_text = text
        else:
            self._status_text, self._status_level = text, level
        self._show_status()

    def _clear_error(self):
        if self._error_text:
            self._error_text = ""
            self._show_status()

    def _show_status(self):
        colours = {"info": "#1a5e1a", "busy": "#555555", "error": "#b00020", "warning": "#8a5a00"}
        parts = [(self._status_level, self._status_text, ""), (self._trace_level, self._trace_text, " sb-trace"),
                 (self._proven_level, self._proven_text, " sb-proven"), ("error", self._error_text, "")]
        self.status.object = "<br>".join(
            f'<span class="sb-{lv}{extra}" style="color:{colours[lv]}">{html.escape(t)}</span>'
            for lv, t, extra in parts if t
        )

    def _trace_message(self, text, level="busy"):
        """The traced borders' line of the status (empty: none)."""
        self._trace_text, self._trace_level = text, level
        self._show_status()

    def _refuse(self, exc):
        """A refused request: say why, and put widgets and plot back to the view."""
        self._message(str(exc), "error")
        self._sync_widgets(self.view)
        self._set_ranges(self.view)

    def _on_ranges(self, event):
        if None in (event.x0, event.x1, event.y0, event.y1):
            return
        # Bokeh's ranges carry float noise in their last bits (0.9200000000000002):
        # the shortest decimals within a thousandth of a pixel
        v = self.view
        tol_e = 1e-3 * abs(event.x1 - event.x0) / v.width
        tol_u = 1e-3 * abs(event.y1 - event.y0) / v.height
        new = v.with_window(tidy(event.x0, tol_e), tidy(event.x1, tol_e),
                            tidy(event.y0, tol_u), tidy(event.y1, tol_u))
        if new == v:
            self._clear_error()  # e.g. Reset back to the view shown
            return
        now = time.monotonic()
        merged = now - self._last_ranges < GESTURE_MERGE_S
        self._last_ranges = now
        self._request(new, history="replace" if merged else "push")

    def _on_window_text(self, _event=None):
        if self._syncing:
            return

        def typed(w):
            return w.value_input if w.value_input not in (None, "") else w.value

        try:
            e_lo, e_hi = parse_window("e window", typed(self.e_window), 1.0)
            u_lo, u_hi = parse_window("u window", typed(self.u_window), U_LIMIT)
        except ValueError as exc:
            self._refuse(exc)
            return
        self._goto(self.view.with_window(e_lo, e_hi, u_lo, u_hi))

    def _on_fig4(self, _event=None):
        self._goto(self.view.with_window(DEFAULT_VIEW.e_lo, DEFAULT_VIEW.e_hi,
                                         DEFAULT_VIEW.u_lo, DEFAULT_VIEW.u_hi))

    def _set_ranges(self, view):
        self.map_fig.x_range.update(start=view.e_lo, end=view.e_hi)
        self.map_fig.y_range.update(start=view.u_lo, end=view.u_hi)

    def _goto(self, view, history="push"):
        """Move the plot's ranges (the image follows when computed)."""
        if view == self.view:
            self._clear_error()
            self._sync_widgets(view)
            return
        try:
            check_view(view)
        except ValueError as exc:
            self._refuse(exc)
            return
        self._set_ranges(view)
        self._request(view, history=history)

    def _on_settings(self, event):
        if self._syncing:
            return
        # a refused side is put back in its widget (the widgets show the view);
        # the other side typed next is asked for with it: 5000, then 5000, is
        # one request for 5000 x 5000, not for 600 x 5000
        refused, self._refused_side = self._refused_side, None
        obj = getattr(event, "obj", None)
        sides = (self.width_in, self.height_in)
        try:
            width, height = int(self.width_in.value), int(self.height_in.value)
            if refused is not None and obj in sides and refused[0] in sides and obj is not refused[0]:
                width, height = (refused[1], height) if refused[0] is self.width_in else (width, refused[1])
            new = replace(self.view, max_iter=int(self.max_iter.value), width=width, height=height)
        except (TypeError, ValueError):
            self._refuse(ValueError("max_iter, width and height must be integers"))
            return
        if new == self.view:
            self._clear_error()
            return
        try:
            check_view(new)
        except ValueError as exc:
            if obj in sides:
                self._refused_side = (obj, int(obj.value))
            self._refuse(exc)
            return
        self._request(new)

    def _apply_color(self, color):
        mapper, bar = _bar_settings(color)
        self.mapper.update(**mapper)
        # the page's colour bar keeps drawing the ticks of the ticker it was
        # built with: a new FixedTicker is ignored there, new ticks on it are not
        self.colorbar.ticker.ticks = bar.pop("ticker").ticks
        self.colorbar.update(**bar)
        self.key_note.object = _key_note(color)
        self.view = replace(self.view, color=color)
        if self.ds is not None and self.shown is not None and has_color(self.ds, color):
            self.shown = replace(self.shown, color=color)
            self.img_src.patch({"image": [(0, shade(self.ds, color))], "val": [(0, _values(self.ds, color))]})
        elif color in MOTION_COLOR_VARS:
            # the motion fields are computed on demand: a render of the same
            # window with them (superseding one in progress without them)
            self._request(self.view, history=None)
        self._set_hover(self.shown or self.view)
        if self._proven is not None and self._proven[0] == self._proven_want:  # the atlas's words recoloured
            self._show_proven(self._proven[1:])

    def _on_color(self, _event):
        if self._syncing or self.color.value == self.view.color:
            return
        self._apply_color(self.color.value)
        self._set_url("replace")

    def _on_overlays(self, _event):
        if self._syncing:
            return
        self.view = replace(self.view, overlays=tuple(o for o in OVERLAYS if o in self.overlays.value))
        self._draw_overlays(self.view)
        self._set_url("replace")

    def _draw_overlays(self, view, borders=True):
        curves = overlay_curves(view)
        for name, src in (("tongues", self.tongue_src), ("no_sliding", self.bound_src)):
            xs, ys = curves[name] if name in view.overlays else ([], [])
            src.data = dict(xs=list(xs), ys=list(ys))
        if borders:
            self._draw_borders(view)
            self._draw_proven(view)
        self.legend.items = [self._overlay_items[n] for n in OVERLAYS if n in view.overlays]
        self.arcs_note.visible = "traced" in view.overlays
        self.legend.visible = bool(view.overlays)

    # ----------------------------------------------------------- proven boxes

    def _draw_proven(self, view):
        """The certified atlas of the view when the "proven" overlay is on
        (proven.proven_slices: sb.certify of the view's window, boxes at
        least MIN_BOX_PX pixels a side, the view's max_iter), one "proven"
        job on the scheduler in bounded slices; a view with another atlas
        supersedes the job under way, one already computed is drawn at once."""
        key = _proven_key(view) if "proven" in view.overlays else None
        if key == self._proven_want:
            return  # drawn, or being computed
        self._proven_want = key
        self._proven_gen += 1
        gen = self._proven_gen
        done = self._proven if key is not None and self._proven is not None and self._proven[0] == key else None
        self._show_proven(None if done is None else done[1:])
        if key is None or done is not None:
            self._sched.cancel(self, "proven")
            self._proven_message("" if done is None else _proven_line(*done[1:]), "info")
            return
        depth = proven_depth(view)
        self._proven_message(f"certifying the view: quadtree to depth {depth} ...", "busy")
        last = [0.0]  # when progress was last sent (worker thread)

        def on_slice(value):
            now = time.monotonic()
            if now - last[0] >= _TRACE_PROGRESS_EVERY:
                last[0] = now
                self._next_tick(self._proven_progress, gen, value)

        self._sched.submit(
            self, "proven", proven_slices(view), on_slice=on_slice,
            on_done=lambda result, error, job: self._next_tick(self._proven_done, gen, key, result, error, job),
            alive=self._alive,
        )

    def _proven_message(self, text, level="busy"):
        self._proven_text, self._proven_level = text, level
        self._show_status()

    def _proven_progress(self, gen, value):
        if gen != self._proven_gen:
            return
        stage, done, total = value
        self._proven_message(f"certifying the view: level {done} of {total} of the quadtree ..." if stage == "level"
                             else f"certifying the view: the itineraries of {done} of {total} boxes ...")

    def _proven_done(self, gen, key, atlas, error, job):
        if gen != self._proven_gen:
            return
        if error is not None:
            self._proven_message(f"certifying the view failed: {error}", "error")
            return
        self._proven = (key, atlas, job.attained)
        self._show_proven((atlas, job.attained))
        self._proven_message(_proven_line(atlas, job.attained), "info")
        point = self.view.point
        if point is not None and "proven" in self.view.overlays:
            # the tap waiting for the atlas: its certificate now
            gen_tap, view = self._tap_gen, self.view
            self._sched.submit(
                self, "certificate", _certificate_work(atlas, *point),
                on_done=lambda d, err, _job: None if err is not None else self._next_tick(
                    self._show_certificate, gen_tap, view, d),
                alive=self._alive)

    def _show_proven(self, done):
        """Draw the atlas (``(atlas, seconds)``, or None: nothing) and its key."""
        if done is None:
            self.proven_src.data = dict(_NO_PROVEN_IMAGE)
            self.proven_note.visible = False
            return
        atlas, seconds = done
        # one picture at the view's pixel size (the atlas's boxes are at least MIN_BOX_PX pixels a side)
        pic = proven_image(atlas, self.view.width, self.view.height, self.view.color)
        self._proven_names.args = dict(names=pic.pop("names"))
        self.proven_src.data = {k: [v] for k, v in pic.items()}
        self.proven_note.object = _proven_key_html(atlas, seconds)
        self.proven_note.visible = True

    # ---------------------------------------------------------- exact borders

    def _draw_borders(self, view):
        """The exact borders of the view, when the "borders" or "traced" overlay
        is on: its border points (view.border_overlay) and, with "traced", the
        traced arcs (view.trace_slices, view.traced_overlay), which replace the
        points they pass through.  Both are computed in one "borders" job on
        the scheduler (points first, then one word's region per slice); a
        view with other borders supersedes (cancels) the job under way, and
        what is already computed for the view is drawn at once."""
        traced = "traced" in view.overlays
        key = _border_key(view) if traced or "borders" in view.overlays else None
        tkey = (trace_window(view), view.max_iter, key) if traced else None
        if (key, tkey) == self._borders_want:
            return  # drawn, or being computed
        self._borders_want = (key, tkey)
        self._borders_gen += 1
        gen = self._borders_gen
        pts = self._borders[1] if key is not None and self._borders is not None and self._borders[0] == key else None
        done = self._traced[1] if tkey is not None and self._traced is not None and self._traced[0] == tkey else None
        self._show_borders(pts, done)
        if key is None or (pts is not None and (tkey is None or done is not None)):
            self._sched.cancel(self, "borders")
            self._trace_message("" if done is None else self._traced_text(done, None),
                                "warning" if done is not None and done["incomplete"] else "info")
            return
        self._trace_message("locating the border points ..." if pts is None else
                            f"tracing borders: finding the words ({TRACE_SIDE} x {TRACE_SIDE} seeds) ...", "busy")
        last = [0.0]  # when progress was last sent (worker thread)

        def on_slice(value):
            now = time.monotonic()
            if value[0] == "points" or value[1] in (0, value[2]) or now - last[0] >= _TRACE_PROGRESS_EVERY:
                last[0] = now
                self._next_tick(self._borders_progress, gen, key, value)

        self._sched.submit(
            self, "borders", self._borders_work(view, pts, traced),
            on_slice=on_slice,
            on_done=lambda result, error, job: self._next_tick(self._borders_done, gen, key, tkey, result, error, job),
            alive=self._alive,
        )

    def _borders_work(self, view, pts, traced):
        """Slices of the "borders" job, each of bounded work (view.SLICE_WORK map
        steps, issue 38 R1; a traced word is one slice): the view's border
        points (unless given: their grid's scan, then the pairs), then, for
        the traced arcs, the seed scan, one word's region per slice, and the
        overlay's data (the words beside the arcs); returns ``(points,
        traced_overlay dict or None)``."""
        if pts is None:
            pts = yield from border_point_slices(view)
            yield "points", pts
        if not traced:
            return pts, None
        work = trace_slices(view)
        while True:
            try:
                done, total = next(work)
            except StopIteration as stop:
                regions = stop.value
                break
            yield "trace", done, total
        overlay = traced_overlay_slices(view, regions, pts)
        while True:
            try:
                done, total = next(overlay)
            except StopIteration as stop:
                return pts, stop.value
            yield "sides", done, total

    def _show_borders(self, pts, traced):
        """Draw border points (a view_border_points Dataset or None) and the
        traced overlay (or None): the points a traced arc passes through are
        left out."""
        from ..plot.borders import KIND_COLORS

        data = dict(e=[], u=[], kind=[], step=[], word_low=[], word_high=[])
        if pts is not None:
            data = border_overlay(None, points=pts)
            if traced is not None and traced["covered"]:
                keep = ~np.asarray(traced["covered"], dtype=bool)
                data = {k: [x for x, y in zip(v, keep) if y] for k, v in data.items()}
        data["color"] = [KIND_COLORS[k] for k in data["kind"]]
        self.border_src.data = data
        arcs = dict(xs=[], ys=[], kind=[], step=[], word_low=[], word_high=[])
        if traced is not None:
            arcs = dict(traced["arcs"])
        arcs["color"] = [KIND_COLORS.get(k, _WINDOW_ARC_COLOR) for k in arcs["kind"]]
        self.arc_src.data = arcs

    def _borders_progress(self, gen, key, value):
        if gen != self._borders_gen:
            return
        if value[0] == "points":
            self._borders = (key, value[1])
            self._show_borders(value[1], None)
            if "traced" in self.view.overlays:
                self._trace_message(f"tracing borders: finding the words ({TRACE_SIDE} x {TRACE_SIDE} seeds) ...")
            return
        stage, done, total = value
        if stage in ("scan", "pairs"):
            what = "the grid's rows" if stage == "scan" else "the pairs of pixels"
            self._trace_message(f"locating the border points: {done} of {total} of {what} ...")
            return
        if stage == "sides":
            self._trace_message(f"tracing borders: the words beside the arcs, {done} of {_plural(total, 'arc')} ...")
            return
        if total is None:
            self._trace_message(f"tracing borders: finding the words ({TRACE_SIDE} x {TRACE_SIDE} seeds) ...")
            return
        self._trace_message(f"tracing borders: {done} of {_plural(total, 'word')} ({TRACE_SIDE} x {TRACE_SIDE} "
                            f"seeds) ..." if done < total else
                            f"tracing borders: {total} of {_plural(total, 'word')}, joining the arcs ...")

    def _borders_done(self, gen, key, tkey, result, error, job):
        if gen != self._borders_gen:
            return
        if error is not None:
            pts = self._borders[1] if self._borders is not None and self._borders[0] == key else None
            what = "tracing borders" if pts is not None else "locating the border points"
            self._trace_message(f"{what} failed: {error}" + ("; the border points are shown" if pts is not None
                                                               else ""), "error")
            return
        pts, traced = result
        self._borders = (key, pts)
        self._show_borders(pts, traced)
        if traced is None:
            self._trace_message("", "info")
            return
        self._traced = (tkey, traced)
        self._trace_message(self._traced_text(traced, job), "warning" if traced["incomplete"] else "info")

    @staticmethod
    def _traced_text(traced, job):
        """The status line of a finished trace."""
        kinds = ", ".join(f"{k} {n}" for k, n in sorted(traced["counts"].items()))
        covered = traced["covered"]
        text = (f"traced borders: {_plural(traced['words'], 'word')} ({TRACE_SIDE} x {TRACE_SIDE} seeds), "
                f"{_plural(sum(traced['counts'].values()), 'arc')} ({kinds or 'none'}); "
                f"{sum(covered)} of {_plural(len(covered), 'border point')} replaced by arcs"
                + (f", traced in {job.attained:.2f} s" if job is not None else ""))
        bad = traced["incomplete"]
        if bad:
            short = [w if len(w) <= 40 else w[:37] + "..." for w in bad[:3]]
            text += (f". Incomplete (a walk gave up; their border points are kept): {_plural(len(bad), 'word')}, "
                     + "; ".join(short) + ("; ..." if len(bad) > 3 else ""))
        return text

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

    def _sync_widgets(self, view):
        self._syncing = True
        try:
            for w, text in ((self.e_window, format_window(view.e_lo, view.e_hi)),
                            (self.u_window, format_window(view.u_lo, view.u_hi))):
                w.value = text
                w.value_input = text
            self.max_iter.value = view.max_iter
            self.width_in.value = view.width
            self.height_in.value = view.height
        finally:
            self._syncing = False

    def _set_hover(self, view):
        """Hover: e and u to a tenth of a pixel, and the colouring variable's value."""
        de = window_digits(view.e_lo, view.e_hi, view.width)
        du = window_digits(view.u_lo, view.u_hi, view.height)
        self.hover.tooltips = [("e", f"$x{{%.{de}g}}"), ("u", f"$y{{%.{du}g}}"),
                               (color_key(view.color).title, "@val{custom}")]
        code = _HOVER_MOTION_JS if view.color in MOTION_COLOR_VARS else _HOVER_VALUE_JS
        if self.hover.formatters["@val"].code != code:
            self.hover.formatters = {**self.hover.formatters, "@val": CustomJSHover(code=code)}

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
        self._draw_borders(view)  # queued after the render: the picture comes first
        self._draw_proven(view)

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

    def _render_work(self, view):
        """The render as scheduler slices: the scan's slices, with a preview
        picture at most every _PREVIEW_EVERY seconds; returns (ds, rgba, values)."""
        slices = render_slices(view)
        first = last = None
        while True:
            try:
                part = next(slices)
            except StopIteration as stop:
                ds = stop.value
                break
            now = time.perf_counter()
            if first is None:
                first = now
            if now - first >= _PREVIEW_AFTER and (last is None or now - last >= _PREVIEW_EVERY):
                last = now
                k = -(-max(view.width, view.height) // _PREVIEW_SIDE)
                yield part.fraction, preview_rgba(part, view.color)[k // 2 :: k, k // 2 :: k]
            else:
                yield part.fraction, None
        return ds, shade(ds, view.color), _values(ds, view.color)

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

    def _show_partial(self, gen, view, value):
        if gen != self._gen:
            return
        fraction, rgba = value
        if rgba is not None:
            self._show_image(view, rgba, _placeholder(view.color))
        self._message(f"computing {view.width} x {view.height} pixels, max_iter {view.max_iter} ... "
                      f"{int(100 * fraction)}%" + (" (coarse preview, refining)" if fraction < 1 else ""),
                      "busy")

    def _show_image(self, view, rgba, values):
        self.img_src.data = dict(image=[rgba], val=[values], x=[view.e_lo], y=[view.u_lo],
                                 dw=[view.e_hi - view.e_lo], dh=[view.u_hi - view.u_lo])

    def _finish(self, gen, view, result, error, job):
        if gen != self._gen:
            return
        if error is not None:
            self._message(f"render failed: {error}", "error")
            return
        ds, rgba, values = result
        if self.view.color != view.color and has_color(ds, self.view.color):  # recoloured meanwhile
            view = replace(view, color=self.view.color)
            rgba, values = shade(ds, view.color), _values(ds, view.color)
        self.ds, self.shown = ds, view
        self._show_image(view, rgba, values)
        self._set_hover(view)
        frac = float((ds["status"].values == 0).mean())
        de = window_digits(view.e_lo, view.e_hi, view.width)
        du = window_digits(view.u_lo, view.u_hi, view.height)
        waited = time.monotonic() - job.submitted - job.attained
        self._message(
            f"e {format_number(view.e_lo, de)} to {format_number(view.e_hi, de)}, "
            f"u {format_number(view.u_lo, du)} to {format_number(view.u_hi, du)}: "
            f"{view.width} x {view.height} pixels, max_iter {view.max_iter}, "
            f"{100 * frac:.1f}% with a periodic sliding solution, computed in {job.attained:.2f} s"
            + (f" (after {waited:.1f} s in the queue)" if waited >= 0.5 else ""),
            "info",
        )
        self.png_button.filename = export_name(view, ".png")
        self.nc_button.filename = export_name(view, ".nc")
        self.png_button.disabled = self.nc_button.disabled = False

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
        self._clear_error()
        self.view = replace(self.view, point=(e, u))
        self._set_url("replace")
        self._request_point(e, u)

    def _request_point(self, e, u):
        self._tap_gen += 1
        gen = self._tap_gen
        view = self.view
        self.point_src.data = dict(x=[e], y=[u])
        self.point_pane.object = f"<i>computing the orbit at e = {e!r}, u = {u!r} ...</i>"
        # the exact borders overlay's points of the same grid, when drawn: the row's border counts
        borders = self._borders
        points = borders[1] if borders is not None and borders[0] == _border_key(view) else None
        cached = self._word_table
        table = cached[1] if cached is not None and cached[0] == _border_key(view) else None
        # the view's own scan when its pixels are the grid (a view of at most BORDER_SIDE per side)
        shown = self.shown
        scan = (self.ds if shown is not None and self.ds is not None and _border_key(shown) == _border_key(view)
                and (shown.width, shown.height) == (view.width, view.height)
                and max(view.width, view.height) <= BORDER_SIDE else None)
        atlas = self._atlas_of(view)
        self._sched.submit(
            self, "point", self._point_work(e, u, view, points, table, scan, atlas),
            on_slice=lambda d: None if isinstance(d, tuple) else self._next_tick(
                self._show_word_row if "word_row" in d else
                self._show_certificate if "certificate" in d else self._show_point, gen, view, d),
            on_done=lambda result, error, _job: self._next_tick(self._show_orbit, gen, view, result, error),
            alive=self._alive,
        )

    def _point_work(self, e, u, view, points=None, table=None, scan=None, atlas=None):
        """Slices: the word and trajectory (shown at once); with the view's
        certified atlas (``atlas``, the "proven" overlay), the certificate of
        its box at the point, re-verified (proven.proven_at); for a sliding point
        its row of the view's word table (view.word_row, on a grid of at most
        BORDER_SIDE x BORDER_SIDE pixels; ``points``: that grid's border points
        when the overlay has them, ``table``: its word table when a previous
        tap computed it, ``scan``: the view's own scan when it is that grid);
        then the orbit diagram."""
        details = point_details(e, u, view.max_iter, max_steps=MAX_TRAJECTORY_STEPS)
        yield details
        if atlas is not None:
            yield {"certificate": proven_at(atlas, e, u, max_steps=TAP_CERTIFICATE_STEPS), "depth": atlas.depth}
        if details["word"] is not None:
            text = details["word"].format(ascii=True)
            # in slices of bounded work (their progress tuples are not shown)
            found = yield from word_row_slices(view, text, points=points, table=table, scan=scan)
            yield {"word_row": found, "text": text}
        return orbit_along_u(e, max(view.u_lo, 0.0), view.u_hi)

    def _show_point(self, gen, view, d):
        if gen != self._tap_gen:
            return
        if not self.tap_panels.objects:
            self.tap_panels.objects = list(self._tap_panes)
        e, u, w = d["e"], d["u"], d["word"]
        head = (f'e = <span class="sb-e">{e!r}</span>, u = <span class="sb-u">{u!r}</span>: ')
        steps = d["steps"]
        answer = d.get("answer")
        if w is None and answer is not None and answer.verdict == "impossible":
            body = (f"no periodic sliding solution, proven: Corollary 2.1 excludes sliding for "
                    f"u &gt;= {answer.bound:.6g} at this e (sliding needs u &lt; {answer.bound:.6g})")
            title = f"trajectory from (1, 0), {_plural(steps, 'step')} (never slides: Corollary 2.1)"
        elif w is None:
            body = (f"no periodic sliding solution: the orbit of (1, 0) does not slide within "
                    f"max_iter = {_plural(view.max_iter, 'step')} (Corollary 2.1 does not exclude it: "
                    f"u &lt; {answer.bound if answer is not None else float('nan'):.6g})")
            title = f"trajectory from (1, 0), {_plural(steps, 'step')} (no sliding found)"
        else:
            body = (f'word <span class="sb-word">{html.escape(w.format())}</span>, length {len(w)}, '
                    f"period {_plural(w.period, 'step')}, {_plural(w.impacts, 'impact')} per period "
                    f"(plus the accumulation), {_plural(w.jumps, 'non-zero letter')}")
            shown = "one full period" if steps >= w.period else f"first {steps} steps of the period"
            title = f"trajectory from (1, 0), {_plural(steps, 'step')}: {shown} (period {w.period})"
        family = d.get("family")
        if family is not None:
            body += (f'<br><span class="sb-family">family {html.escape(family.pattern)}, member k = {family.k}'
                     "</span> (the word's form: its longest run of a repeated block, sb.family_of)")
        if w is None:
            body += '<br><span class="sb-row">its row of the word table: none within max_iter (no row)</span>'
        else:
            (_, _, n_e), (_, _, n_u) = border_grid(view)
            body += (f'<br><span class="sb-row"><i>its row of the word table of this view '
                     f"({n_e} x {n_u} pixels): computing ...</i></span>")
        self._point_text = head + body
        self._motion_html = _motion_table(d.get("motion"))
        if self._cert_gen != gen:  # this tap's certificate is not shown yet
            self._cert_html = ("" if "proven" not in view.overlays else
                               '<br><span class="sb-cert"><i>certificate: computing ...</i></span>'
                               if self._atlas_of(view) is not None else
                               '<br><span class="sb-cert"><i>certificate: the proven overlay is being computed; '
                               "it shows here when done</i></span>")
        self._refresh_point()
        sec = d.get("section")
        self.section_src.data = dict(x=sec[0], y=sec[1]) if sec is not None else dict(x=[], y=[])
        self.section_fig.title.text = (f"Poincare section at e = {e:.6g}, u = {u:.6g}: last "
                                       f"{_plural(len(sec[0]), 'iterate')} from (1, 0)" if sec is not None else
                                       "Poincare section: none (the orbit slides)")
        sx = np.repeat(np.arange(-1, steps + 1), 2)[1:].astype(float)
        sy = -np.repeat(np.arange(-1, steps + 1), 2)[:-1].astype(float)
        self.stairs_src.data = dict(x=sx, y=sy)
        self.path_src.data = dict(x=d["path"][0], y=d["path"][1])
        self.impact_src.data = dict(x=d["impacts"][0], y=d["impacts"][1])
        self.accum_src.data = dict(x=d["accumulations"][0], y=d["accumulations"][1])
        self.slide_src.data = dict(xs=[[a, b] for a, b, _ in d["slides"]],
                                   ys=[[y, y] for _, _, y in d["slides"]])
        self.traj_fig.title.text = title
        self.traj_fig.legend.visible = True

    def _show_word_row(self, gen, view, d):
        """The tapped word's row of the view's word table, under the word line."""
        self._word_table = (_border_key(view), d["word_row"]["table"])
        if gen != self._tap_gen:
            return
        head = self._point_text.split('<br><span class="sb-row">')[0]
        self._point_text = head + '<br><span class="sb-row">' + _row_text(d["word_row"], d["text"]) + "</span>"
        self._refresh_point()

    def _refresh_point(self):
        """The tap's pane: the word lines, the certificate's line, the motion's table."""
        self.point_pane.object = self._point_text + self._cert_html + self._motion_html

    def _show_certificate(self, gen, view, d):
        """The certificate of the atlas's box at the tapped point (proven.proven_at)."""
        if gen != self._tap_gen:
            return
        self._cert_gen = gen
        self._cert_html = '<br><span class="sb-cert">' + _certificate_text(d["certificate"], d["depth"]) + "</span>"
        self._refresh_point()

    def _atlas_of(self, view):
        """The certified atlas of ``view`` when computed and the overlay is on, else None."""
        p = self._proven
        return p[1] if "proven" in view.overlays and p is not None and p[0] == _proven_key(view) else None

    def _show_orbit(self, gen, view, orbit, error):
        if gen != self._tap_gen:
            return
        if error is not None:
            self.point_pane.object = f"<b>failed:</b> {html.escape(str(error))}"
            return
        e, u = self.view.point if self.view.point is not None else (None, None)
        y = orbit["y"].values
        self.orbit_src.data = dict(x=np.repeat(orbit["u"].values, y.shape[1]), y=y.ravel())
        self.orbit_fig.x_range.update(start=float(orbit["u"].values[0]), end=float(orbit["u"].values[-1]))
        finite = y[np.isfinite(y)]
        if finite.size:
            lo, hi = float(finite.min()), float(finite.max())
            pad = 0.05 * (hi - lo) or 0.5
            self.orbit_fig.y_range.update(start=lo - pad, end=hi + pad)
        if u is not None:
            self.orbit_marker.update(location=u, visible=True)
            self.orbit_fig.title.text = f"orbit diagram at e = {e:.6g}, iterates 2001-2200 from (0.1, 0)"

    # --------------------------------------------------------------- exports

    async def _png(self):
        """The PNG of the view shown, made on the export thread, with the exact
        borders (points and traced arcs) as drawn when they are the shown view's."""
        ds, shown = self.ds, self.shown
        drawn = None
        if shown is not None and self._borders_want[0] is not None and self._borders_want[0] == _border_key(shown):
            drawn = {"points": {k: list(self.border_src.data[k]) for k in ("e", "u", "kind")},
                     "arcs": {k: list(self.arc_src.data[k]) for k in ("xs", "ys", "kind")}}
        data = await asyncio.wrap_future(_EXPORTS.submit(view_png, ds, shown, borders=drawn))
        return io.BytesIO(data)

    async def _netcdf(self):
        ds = self.ds
        data = await asyncio.wrap_future(_EXPORTS.submit(view_netcdf, ds))
        return io.BytesIO(data)


def _proven_key(view):
    """What the certified atlas of a view depends on: its window, depth and max_iter."""
    return view.e_lo, view.e_hi, view.u_lo, view.u_hi, proven_depth(view), view.max_iter


def _certificate_work(atlas, e, u):
    """The certificate of the atlas's box at (e, u), as one scheduler slice."""
    return {"certificate": proven_at(atlas, e, u, max_steps=TAP_CERTIFICATE_STEPS), "depth": atlas.depth}
    yield  # a generator: the scheduler's slices


def _proven_line(atlas, seconds):
    """The status line of a finished atlas."""
    shares = proven_summary(atlas)
    proven = sum(v for k, v in shares.items() if k in ("word", "no_sliding", "no_slide_within"))
    return (f"proven overlay: {atlas.boxes.sizes['box']} boxes to depth {atlas.depth}, "
            f"{100 * proven:.1f} % of the view proven ({100 * shares.get('word', 0.0):.1f} % with a proven word), "
            f"{100 * (1 - proven):.1f} % undecided (numerical); certified in {seconds:.2f} s")


# CSS backgrounds of the key's swatches, like the map's hatch patterns
_SWATCH = {" ": "{c}", ".": "radial-gradient({h} 1px, #fff 1.5px) 0 0/4px 4px",
           "o": "radial-gradient(#fff 1.2px, {h} 1.5px, {h} 2px, #fff 2.5px) 0 0/6px 6px",
           "/": "repeating-linear-gradient(-45deg, {h} 0 1.5px, #fff 1.5px 5px)",
           "\\": "repeating-linear-gradient(45deg, {h} 0 1.5px, #fff 1.5px 5px)",
           "x": "repeating-linear-gradient(45deg, {h} 0 1px, transparent 1px 5px), "
                "repeating-linear-gradient(-45deg, {h} 0 1px, #fff 1px 5px)",
           "-": "repeating-linear-gradient(0deg, {h} 0 1.5px, #fff 1.5px 5px)",
           "|": "repeating-linear-gradient(90deg, {h} 0 1.5px, #fff 1.5px 5px)",
           "+": "repeating-linear-gradient(0deg, {h} 0 1px, transparent 1px 5px), "
                "repeating-linear-gradient(90deg, {h} 0 1px, #fff 1px 5px)"}


def _proven_key_html(atlas, seconds):
    """The proven overlay's key under the map: what each mark means, its share
    of the view, and that the undecided areas are numerical."""
    shares = proven_summary(atlas)
    (e0, e1), (u0, u1) = atlas.window
    rows = []
    for name, (fill, _alpha, hatch, hcol, text) in STYLES.items():
        bg = _SWATCH[hatch].format(c="linear-gradient(90deg, #000 0 25%, #3e9bfe 25% 50%, #a2fc3c 50% 75%, "
                                     "#f66b19 75%)" if fill is None else fill, h=hcol)
        rows.append(f'<tr class="sb-proven-{name}"><td><span style="display:inline-block;width:22px;height:12px;'
                    f'border:1px solid #888;background:{bg}"></span></td><td>{html.escape(text)}</td>'
                    f'<td style="text-align:right;white-space:nowrap">{100 * shares.get(name, 0.0):.1f} %</td></tr>')
    depth = atlas.depth
    return (f'<div class="sb-proven-key" style="font-size:12px"><b>Proven overlay</b>: the certified atlas of this view '
            f"(sb.certify, corners form, max_iter {atlas.max_iter}): an adaptive quadtree of boxes down to "
            f"window/2<sup>{depth}</sup> (depth {depth}, chosen from the view's size so that the smallest boxes "
            f"are at least {MIN_BOX_PX} pixels a side), computed in {seconds:.2f} s on the server. "
            f'<table style="font-size:12px">{"".join(rows)}</table>'
            "<b>Undecided areas are numerical</b>: there the picture's colour is a floating-point answer, "
            "which rounding may have chosen (next to a border) or which is only a finite run (non-sliding "
            "motion). Tap a point for the certificate of its box.</div>")


def _certificate_text(c, depth):
    """The tap's line for the atlas's box at the point (proven.proven_at)."""
    if c is None:
        return "<i>certificate: the point is outside the certified atlas</i>"
    (e0, e1), (u0, u1) = c["box"]
    box = f"box e [{e0:.10g}, {e1:.10g}] x u [{u0:.10g}, {u1:.10g}] (level {c['level']} of {depth})"
    if c["status"] == "undecided":
        where = f" at step {c['step']}" if c["step"] else ""
        return (f"certified atlas, {box}: <b>undecided</b> (numerical), reason <b>{html.escape(c['reason'])}</b>"
                f"{where}: {html.escape(STYLES[c['reason']][4].split(': ', 1)[-1])}")
    if c.get("deferred") is not None:
        return (f'certified atlas, {box}, max_iter {c["max_iter"]}: <b class="sb-cert-status">{c["status"]}</b> '
                f"(the atlas's claim); its certificate is <b>not computed here</b>: it walks "
                f"{c['deferred']:,} steps, more than one slice of the shared worker allows "
                f"({TAP_CERTIFICATE_STEPS:,} steps), and would hold every page of this server. "
                f'Compute and check it in Python: <code class="sb-cert-code">{html.escape(_certificate_code(c))}</code>')
    claim = {"word": f"every point has the periodic sliding solution of the word "
                     f"<b>{html.escape(c['word'] or '')}</b>",
             "no_sliding": "no periodic sliding solution anywhere (Corollary 2.1 over the whole box)",
             "no_slide_within": f"the orbit of (1, 0) does not slide within max_iter = {c['max_iter']} steps "
                                "anywhere"}[c["status"]]
    verdict = c["verdict"]
    how = ("proven by interval arithmetic, re-verified by sb.verify" if verdict is not None and verdict.ok else
           "proven by interval arithmetic; sb.verify did NOT re-verify it: "
           + html.escape(verdict.message if verdict is not None else "not run"))
    return (f'certified atlas, {box}, max_iter {c["max_iter"]}: <b class="sb-cert-status">{c["status"]}</b>, '
            f"{claim}; {how}")


def _certificate_code(c):
    """The Python line that computes and checks a box's certificate (its edges
    as hex floats: exactly the box)."""
    (e0, e1), (u0, u1) = c["box"]
    return (f"sb.verify(sb.certify_box(e=(float.fromhex('{e0.hex()}'), float.fromhex('{e1.hex()}')), "
            f"u=(float.fromhex('{u0.hex()}'), float.fromhex('{u1.hex()}')), max_iter={c['max_iter']}))")


def _border_key(view):
    """What the exact borders of a view depend on: their grid and max_iter."""
    return border_grid(view), view.max_iter


def _row_text(found, text):
    """Two short lines: the tapped word's row of the view's word table
    (view.word_row), or why it has none."""
    n_e, n_u = found["grid"]
    r = found["row"]
    where = f"word table of this view ({n_e} x {n_u} pixels, {_plural(found['words'], 'word')})"
    if r is None:
        return f"<i>{html.escape(text)}: no pixel centre of the {where}</i>"
    return (f'{where}: <span class="sb-row-word">{html.escape(r["text"])}</span>, '
            f"{_plural(r['letters'], 'letter')}, period {r['period']}, "
            f"{_plural(r['impacts'], 'finite impact')} per period, {_plural(r['pixels'], 'pixel')} "
            f"({100 * r['area_fraction']:.3g} % of the view)<br>"
            f"representative (e, u) = ({r['e_rep']:.6g}, {r['u_rep']:.6g}), "
            f"box e {r['e_min']:.6g} .. {r['e_max']:.6g}, u {r['u_min']:.6g} .. {r['u_max']:.6g}; "
            f"border points: graze {r['graze']}, edge {r['edge']}, chatter {r['chatter']}")


def _motion_table(m):
    """The rows of a non-sliding point's motion (issue 13) under its word line:
    <k>, the mean jump and the two Lyapunov exponents."""
    if m is None:
        return ""
    if m["slides"]:
        rows = [("motion", f'slides on step {m["slide_step"]} of 2 max_iter')]
    else:
        rows = [("&lt;k&gt;", f'<span class="sb-k">{m["k_mean"]:.6g}</span> impacts per step '
                              f'(halves differ by {m["k_err"]:.2g})'),
                ("mean jump", f'{m["jump_mean"]:.6g} steps per landing'),
                ("&lambda;<sub>1</sub>", f'{m["lyap1"]:+.2e} &plusmn; {m["lyap1_err"]:.1e} (0 exactly)'),
                ("&lambda;<sub>2</sub>", f'{m["lyap2"]:+.4e} = 2&lt;k&gt; log e')]
    return '<table class="sb-motion">' + "".join(
        f"<tr><td><b>{k}</b></td><td>{v}</td></tr>" for k, v in rows) + "</table>"


def _values(ds, var):
    """The colouring variable per pixel for the hover (-1: no sliding solution),
    as int16 when it fits (half the bytes on the websocket); a motion field as
    float32, infinite where the orbit slides."""
    if var in MOTION_COLOR_VARS:
        return np.where(ds["slide_step"].values > 0, np.inf, ds[var].values).astype(np.float32)
    v = np.where(ds["status"].values == 0, ds[var].values, -1)
    return v.astype(np.int16 if v.max(initial=0) < 2**15 else np.int32)


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
