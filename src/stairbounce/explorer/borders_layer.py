"""The exact borders layers of the explorer's map: the border points (overlay "borders") and the
traced arcs (overlay "traced"), one "borders" job of the scheduler (issue 46 item 1).  A :class:`~stairbounce.explorer.layer.Layer`."""

from __future__ import annotations

import time

import numpy as np
import panel as pn
from bokeh.models import ColumnDataSource, HoverTool

from .._colours import KIND_COLOURS, kinds_legend
from ._common import _TRACE_PROGRESS_EVERY, _border_key, _plural
from .layer import Layer
from .view import (
    TRACE_SIDE,
    border_overlay,
    border_point_slices,
    trace_slices,
    trace_window,
    traced_overlay_slices,
)


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


class BordersLayer(Layer):
    """The "borders" and "traced" overlays (one layer: one job computes both,
    the arcs replacing the points they pass through): ``points`` the border
    points last computed ``((grid, max_iter), Dataset)`` (a tap's word row
    reuses them), ``traced`` the traced overlay last computed, ``want`` what
    is drawn or being computed, ``border_src`` and ``arc_src`` their data on
    the map, ``note`` the arcs' note under the map."""

    name = "borders"
    css = "sb-trace"

    def __init__(self, page):
        super().__init__(page)
        self.points = None  # ((grid, max_iter), border_points Dataset)
        self.traced = None  # ((trace window, max_iter, points' key), traced_overlay dict)
        self.want = (None, None)  # (points' key or None, trace key or None)
        self.gen = 0
        self.note = pn.pane.HTML(_ARCS_NOTE, css_classes=["sb-arcs-note"], width=700,
                                 visible="traced" in page.view.overlays)

    def build(self, fig):
        """Its glyphs on the map ``fig``: the border points and the traced arcs; returns their
        renderers (for the legend)."""
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
        return [borders, arcs]

    def draw(self, view):
        """The exact borders of the view, when the "borders" or "traced" overlay
        is on: its border points (view.border_overlay) and, with "traced", the
        traced arcs (view.trace_slices, view.traced_overlay), which replace the
        points they pass through.  Both are computed in one "borders" job on
        the scheduler (points first, then one word's region per slice); a
        view with other borders supersedes (cancels) the job under way, and
        what is already computed for the view is drawn at once."""
        page = self.page
        traced = "traced" in view.overlays
        key = _border_key(view) if traced or "borders" in view.overlays else None
        tkey = (trace_window(view), view.max_iter, key) if traced else None
        if (key, tkey) == self.want:
            return  # drawn, or being computed
        self.want = (key, tkey)
        self.gen += 1
        gen = self.gen
        pts = self.points[1] if key is not None and self.points is not None and self.points[0] == key else None
        done = self.traced[1] if tkey is not None and self.traced is not None and self.traced[0] == tkey else None
        self._show(pts, done)
        if key is None or (pts is not None and (tkey is None or done is not None)):
            page._sched.cancel(page, "borders")
            self.message("" if done is None else self._traced_text(done, None),
                         "warning" if done is not None and done["incomplete"] else "info")
            return
        self.message("locating the border points ..." if pts is None else
                     f"tracing borders: finding the words ({TRACE_SIDE} x {TRACE_SIDE} seeds) ...", "busy")
        last = [0.0]  # when progress was last sent (worker thread)

        def on_slice(value):
            now = time.monotonic()
            if value[0] == "points" or value[1] in (0, value[2]) or now - last[0] >= _TRACE_PROGRESS_EVERY:
                last[0] = now
                page._next_tick(self._progress, gen, key, value)

        page._sched.submit(
            page, "borders", self._work(view, pts, traced),
            on_slice=on_slice,
            on_done=lambda result, error, job: page._next_tick(self._done, gen, key, tkey, result, error, job),
            alive=page._alive,
        )

    def _work(self, view, pts, traced):
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

    def _show(self, pts, traced):
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

    def _progress(self, gen, key, value):
        if gen != self.gen:
            return
        if value[0] == "points":
            self.points = (key, value[1])
            self._show(value[1], None)
            if "traced" in self.page.view.overlays:
                self.message(f"tracing borders: finding the words ({TRACE_SIDE} x {TRACE_SIDE} seeds) ...")
            return
        stage, done, total = value
        if stage in ("scan", "pairs"):
            what = "the grid's rows" if stage == "scan" else "the pairs of pixels"
            self.message(f"locating the border points: {done} of {total} of {what} ...")
            return
        if stage == "sides":
            self.message(f"tracing borders: the words beside the arcs, {done} of {_plural(total, 'arc')} ...")
            return
        if total is None:
            self.message(f"tracing borders: finding the words ({TRACE_SIDE} x {TRACE_SIDE} seeds) ...")
            return
        self.message(f"tracing borders: {done} of {_plural(total, 'word')} ({TRACE_SIDE} x {TRACE_SIDE} "
                     f"seeds) ..." if done < total else
                     f"tracing borders: {total} of {_plural(total, 'word')}, joining the arcs ...")

    def _done(self, gen, key, tkey, result, error, job):
        if gen != self.gen:
            return
        if error is not None:
            pts = self.points[1] if self.points is not None and self.points[0] == key else None
            what = "tracing borders" if pts is not None else "locating the border points"
            self.message(f"{what} failed: {error}" + ("; the border points are shown" if pts is not None
                                                       else ""), "error")
            return
        pts, traced = result
        self.points = (key, pts)
        self._show(pts, traced)
        if traced is None:
            self.message("", "info")
            return
        self.traced = (tkey, traced)
        self.message(self._traced_text(traced, job), "warning" if traced["incomplete"] else "info")

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
