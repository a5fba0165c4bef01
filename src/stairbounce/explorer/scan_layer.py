"""The scan layer of the explorer's map: the picture of the view in slices (a coarse preview
first), its colour bar, key note and hover (issue 46 item 1: one module per layer)."""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
from bokeh.models import CustomJSHover, FixedTicker

from ._common import _answer_stands
from .export import export_name
from .view import (
    MOTION_COLOR_VARS,
    NO_SLIDING_COLOR,
    NO_SLIDING_LABEL,
    NOT_COMPUTED_COLOR,
    SLIDES_COLOR,
    color_key,
    format_number,
    has_color,
    preview_rgba,
    render_slices,
    shade,
    window_digits,
)


# least time between two preview pictures of one render sent to the browser,
# and their largest side in pixels (a preview is subsampled to it: a 1000 x
# 1000 preview would be 4 MB on the websocket, shared by every session)
_PREVIEW_EVERY = 1.0


_PREVIEW_SIDE = 300


# no preview for a render that is done sooner than this after its first slice
# (s): the picture itself is about to come, and each picture costs every
# browser showing it a repaint
_PREVIEW_AFTER = 0.25


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


def _values(ds, var):
    """The colouring variable per pixel for the hover (-1: no sliding solution),
    as int16 when it fits (half the bytes on the websocket); a motion field as
    float32, infinite where the orbit slides."""
    if var in MOTION_COLOR_VARS:
        return np.where(ds["slide_step"].values > 0, np.inf, ds[var].values).astype(np.float32)
    v = np.where(ds["status"].values == 0, ds[var].values, -1)
    return v.astype(np.int16 if v.max(initial=0) < 2**15 else np.int32)


class ScanLayer:
    """A part of :class:`~stairbounce.explorer.app.Explorer`, mixed in (its methods share the
    page's state; see the module's docstring)."""

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
        if not _answer_stands(gen, self._gen, error, self._message, "render"):
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
        for layer in self.layers:
            layer.recolour()

    def _set_hover(self, view):
        """Hover: e and u to a tenth of a pixel, and the colouring variable's value."""
        de = window_digits(view.e_lo, view.e_hi, view.width)
        du = window_digits(view.u_lo, view.u_hi, view.height)
        self.hover.tooltips = [("e", f"$x{{%.{de}g}}"), ("u", f"$y{{%.{du}g}}"),
                               (color_key(view.color).title, "@val{custom}")]
        code = _HOVER_MOTION_JS if view.color in MOTION_COLOR_VARS else _HOVER_VALUE_JS
        if self.hover.formatters["@val"].code != code:
            self.hover.formatters = {**self.hover.formatters, "@val": CustomJSHover(code=code)}
