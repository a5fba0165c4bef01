"""The proven layer of the explorer's map: the view's certified atlas (explorer/proven.py) as one
"proven" job of the scheduler, drawn as one picture, its key, and the certificate line of a tap
(issue 46 item 1).  A :class:`~stairbounce.explorer.layer.Layer`."""

from __future__ import annotations

import html
import time

import panel as pn
from bokeh.models import ColumnDataSource, CustomJSHover, HoverTool

from ._common import _TRACE_PROGRESS_EVERY, _answer_stands
from .layer import Layer
from .proven import (MIN_BOX_PX, STYLES, TAP_CERTIFICATE_STEPS, proven_at, proven_depth, proven_image, proven_slices,
                     proven_summary)


# the proven overlay's picture before an atlas is drawn (nothing), and its hover: the box's label
_NO_PROVEN_IMAGE: dict[str, list] = dict(image=[], code=[], x=[], y=[], dw=[], dh=[])


_PROVEN_HOVER_JS = "return value >= 0 && value < names.length ? names[value] : 'none';"


def _proven_key(view):
    """What the certified atlas of a view depends on: its window, depth and max_iter."""
    return view.e_lo, view.e_hi, view.u_lo, view.u_hi, proven_depth(view), view.max_iter


def _certificate(atlas, e, u):
    """What a tap shows of the atlas at (e, u): the certificate of its box
    (proven.proven_at, deferred beyond TAP_CERTIFICATE_STEPS) and the depth."""
    return {"certificate": proven_at(atlas, e, u, max_steps=TAP_CERTIFICATE_STEPS), "depth": atlas.depth}


def _certificate_work(atlas, e, u):
    """The certificate of the atlas's box at (e, u), as one scheduler slice."""
    return _certificate(atlas, e, u)
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


class ProvenLayer(Layer):
    """The "proven" overlay: ``done`` is the certified atlas last computed
    ``(key, CertifiedAtlas, seconds)``, ``src`` its picture on the map,
    ``names`` the hover's labels, ``note`` its key under the map."""

    name = "proven"
    css = "sb-proven"
    legend = "certified atlas: proven boxes solid, undecided hatched (key below the map)"

    def __init__(self, page):
        super().__init__(page)
        self.done = None  # (proven key, CertifiedAtlas, seconds)
        self.want = None  # the key drawn or being computed (None: off)
        self.gen = 0
        self.note = pn.pane.HTML("", css_classes=["sb-proven-note"], width=700, visible=False)

    def build(self, fig):
        # the certified atlas (overlay "proven", explorer/proven.py): one RGBA picture of its boxes with
        # their hatching (proven.proven_image; a glyph per box froze the browser), over the map and
        # under the curves; named for the browser tests
        self.src = ColumnDataSource(_NO_PROVEN_IMAGE, name="sb-proven-image")
        proven = fig.image_rgba(image="image", x="x", y="y", dw="dw", dh="dh", source=self.src)
        self.names = CustomJSHover(args=dict(names=[]), code=_PROVEN_HOVER_JS)
        fig.add_tools(HoverTool(renderers=[proven], tooltips=[("certified box", "@code{custom}")],
                                formatters={"@code": self.names}))
        return [proven]

    def draw(self, view):
        """The certified atlas of the view when the "proven" overlay is on
        (proven.proven_slices: sb.certify of the view's window, boxes at
        least MIN_BOX_PX pixels a side, the view's max_iter), one "proven"
        job on the scheduler in bounded slices; a view with another atlas
        supersedes the job under way, one already computed is drawn at once."""
        page = self.page
        key = _proven_key(view) if "proven" in view.overlays else None
        if key == self.want:
            return  # drawn, or being computed
        self.want = key
        self.gen += 1
        gen = self.gen
        done = self.done if key is not None and self.done is not None and self.done[0] == key else None
        self._show(None if done is None else done[1:])
        if key is None or done is not None:
            page._sched.cancel(page, "proven")
            self.message("" if done is None else _proven_line(*done[1:]), "info")
            return
        depth = proven_depth(view)
        self.message(f"certifying the view: quadtree to depth {depth} ...", "busy")
        last = [0.0]  # when progress was last sent (worker thread)

        def on_slice(value):
            now = time.monotonic()
            if now - last[0] >= _TRACE_PROGRESS_EVERY:
                last[0] = now
                page._next_tick(self._progress, gen, value)

        page._sched.submit(
            page, "proven", proven_slices(view), on_slice=on_slice,
            on_done=lambda result, error, job: page._next_tick(self._done, gen, key, result, error, job),
            alive=page._alive,
        )

    def _progress(self, gen, value):
        if gen != self.gen:
            return
        stage, done, total = value
        self.message(f"certifying the view: level {done} of {total} of the quadtree ..." if stage == "level"
                     else f"certifying the view: the itineraries of {done} of {total} boxes ...")

    def _done(self, gen, key, atlas, error, job):
        if not _answer_stands(gen, self.gen, error, self.message, "certifying the view"):
            return
        page = self.page
        self.done = (key, atlas, job.attained)
        self._show((atlas, job.attained))
        self.message(_proven_line(atlas, job.attained), "info")
        point = page.view.point
        if point is not None and "proven" in page.view.overlays:
            # the tap waiting for the atlas: its certificate now
            gen_tap, view = page._tap_gen, page.view
            page._sched.submit(
                page, "certificate", _certificate_work(atlas, *point),
                on_done=lambda d, err, _job: None if err is not None else page._next_tick(
                    page._show_certificate, gen_tap, view, d),
                alive=page._alive)

    def _show(self, done):
        """Draw the atlas (``(atlas, seconds)``, or None: nothing) and its key."""
        if done is None:
            self.src.data = dict(_NO_PROVEN_IMAGE)
            self.note.visible = False
            return
        atlas, seconds = done
        view = self.page.view
        # one picture at the view's pixel size (the atlas's boxes are at least MIN_BOX_PX pixels a side)
        pic = proven_image(atlas, view.width, view.height, view.color)
        self.names.args = dict(names=pic.pop("names"))
        self.src.data = {k: [v] for k, v in pic.items()}
        self.note.object = _proven_key_html(atlas, seconds)
        self.note.visible = True

    def recolour(self):
        if self.done is not None and self.done[0] == self.want:  # the atlas's words recoloured
            self._show(self.done[1:])

    def atlas_of(self, view):
        """The certified atlas of ``view`` when computed and the overlay is on, else None."""
        p = self.done
        return p[1] if "proven" in view.overlays and p is not None and p[0] == _proven_key(view) else None

    def at(self, view, e, u):
        """The certificate of the atlas's box at the point (deferred beyond
        TAP_CERTIFICATE_STEPS), or None without an atlas of the view."""
        atlas = self.atlas_of(view)
        return None if atlas is None else _certificate(atlas, e, u)
