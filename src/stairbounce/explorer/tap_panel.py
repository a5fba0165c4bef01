"""The tap panel of the explorer: a tapped point's word, its row of the word table, the
certificate of its proven box, its trajectory, orbit diagram and Poincare section (issue 46 item 1)."""

from __future__ import annotations

import html
from dataclasses import replace

import numpy as np
from bokeh.models import ColumnDataSource, Range1d, Span
from bokeh.plotting import figure

from ._common import _border_key, _plural
from .proven_layer import _certificate, _certificate_text
from .view import U_LIMIT, BORDER_SIDE, border_grid, orbit_along_u, pixel_of, point_details, word_row_slices


# the longest trajectory drawn for a tap, in steps (one full period when shorter)
MAX_TRAJECTORY_STEPS = 2000


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


class TapPanel:
    """A part of :class:`~stairbounce.explorer.app.Explorer`, mixed in (its methods share the
    page's state; see the module's docstring)."""

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
        borders = self.borders.points
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
            yield _certificate(atlas, e, u)
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
        return self.proven.atlas_of(view)

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
