"""The explorer's controls and status line: the widgets (colour, max_iter, size, window, overlays),
their events and the pan/zoom ranges, each turned into a request of the page (issue 46 item 1)."""

from __future__ import annotations

import html
import time
from dataclasses import replace

import panel as pn

from .scan_layer import _key_note
from .view import (
    DEFAULT_VIEW,
    FIELDS,
    MAX_ITER_LIMIT,
    OVERLAYS,
    U_LIMIT,
    check_view,
    format_window,
    parse_window,
    tidy,
)


_COLOR_OPTIONS = {menu: var for var, (menu, _, _) in FIELDS.items()}


_OVERLAY_OPTIONS = {"tongues (n, 0^\u221e), Thm 3.1": "tongues", "no-sliding bound, Cor. 2.1": "no_sliding",
                    "exact borders (graze, edge, chatter)": "borders",
                    "exact borders as traced arcs (seconds)": "traced",
                    "proven: certified atlas (interval arithmetic)": "proven"}


# range changes (wheel, pan, box zoom) that follow one another within this
# many seconds are one gesture: one history entry, so Back returns to the view
# before it (a wheel turned in notches, on a loaded machine, reports a
# RangesUpdate every few notches)
GESTURE_MERGE_S = 1.0


class Controls:
    """A part of :class:`~stairbounce.explorer.app.Explorer`, mixed in (its methods share the
    page's state; see the module's docstring)."""

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
        parts = [(self._status_level, self._status_text, ""),
                 *((lay.level, lay.text, f" {lay.css}") for lay in self.layers), ("error", self._error_text, "")]
        self.status.object = "<br>".join(
            f'<span class="sb-{lv}{extra}" style="color:{colours[lv]}">{html.escape(t)}</span>'
            for lv, t, extra in parts if t
        )

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
