"""What the browser app shows, without the browser: views, URL queries, renders.

Everything here is pure Python on top of the library (no Panel, no Bokeh), so
the server side of the app can be tested by calling these functions directly:

- :class:`View`: one window of the (e, u) plane with its pixel size, the
  iteration cap, the variable that colours it and the overlays;
- :func:`parse_query` / :func:`view_query`: the view <-> the page's URL query
  (``?e=0:1&u=0:1.5&size=600x600&max_iter=1000&color=word_length``), with every
  malformed or out-of-range value replaced by its default and reported;
- :func:`check_view`: the limits of one render (the pixel and work budgets,
  float64 resolution), raising :class:`ValueError` with the reason;
- :func:`compute_view`: the scan of a view (:func:`stairbounce.plane.scan_coords`
  on the view's :func:`~stairbounce.plane.pixel_centres`, in bands of rows so a
  newer request can cancel it between bands; with the fields of
  :func:`stairbounce.nonsliding.motion_coords` when a motion field colours it);
- :func:`shade`, :func:`color_key`: the colours of the map (datashader's split:
  compute the labelled grid first, shade it as a separate step);
- :func:`overlay_curves`, :func:`point_details`, :func:`orbit_along_u`: the
  tongues of Theorem 3.1, the curve of Corollary 2.1, and what a tap shows.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from urllib.parse import urlencode

import numpy as np
import xarray as xr

from .. import orbits, plane
from ..cascades import family_of
from ..model import check_e, check_u, tongue
from ..symbolic import sliding_answer
from ..plot.plane import _CLASS_STARTS, _LEAST, NO_SLIDING_COLOR, ColorKey
from ..plot.plane import color_key as _sliding_color_key
from ..trajectory import trajectory

__all__ = [
    "View",
    "DEFAULT_VIEW",
    "COLOR_VARS",
    "OVERLAYS",
    "PIXEL_BUDGET",
    "WORK_BUDGET",
    "MAX_ITER_LIMIT",
    "U_LIMIT",
    "Cancelled",
    "ColorKey",
    "parse_query",
    "parse_window",
    "format_window",
    "view_query",
    "view_url_query",
    "check_view",
    "compute_view",
    "render_slices",
    "preview_rgba",
    "Partial",
    "window_digits",
    "format_number",
    "tidy",
    "FIELDS",
    "MOTION_COLOR_VARS",
    "has_color",
    "color_key",
    "shade",
    "overlay_curves",
    "point_details",
    "orbit_along_u",
    "pixel_of",
    "TRACE_SIDE",
    "trace_window",
    "trace_slices",
    "traced_overlay",
    "traced_overlay_slices",
    "grid_scan_slices",
    "border_point_slices",
    "word_row_slices",
]

MOTION_COLOR_VARS = ("k_mean", "lyap1")
"""Fields of :func:`stairbounce.nonsliding.motion_coords` that can colour the map
(issue 13): computed with ``max_iter`` transient and ``max_iter`` kept steps."""

FIELDS = {
    # variable: (menu entry, colour-key title, least value on a sliding pixel or None)
    "word_length": ("word length", "word length", _LEAST["word_length"]),
    "period": ("period (steps)", "period (steps)", _LEAST["period"]),
    "impacts": ("impacts per period", "impacts per period", _LEAST["impacts"]),
    "jumps": ("non-zero letters (jumps)", "non-zero letters", _LEAST["jumps"]),
    "status": ("status (slides or not)", "periodic sliding solution", None),
    "k_mean": ("<k>, impacts per step (non-sliding motion)", "<k>, impacts per step", None),
    "lyap1": ("lambda_1 (non-sliding motion)", "lambda_1 (N = max_iter kept steps)", None),
}
"""The variables that can colour the map: data variables of
:func:`stairbounce.plane.scan`, then :data:`MOTION_COLOR_VARS`.  A count is
coloured on the figures' discrete scale (:func:`stairbounce.plot.plane.color_key`,
classes counted from its least value, ``_LEAST`` there); ``None``: two
classes (found or not) for ``status``, a continuous key for a motion field."""

COLOR_VARS = tuple(FIELDS)
"""Variables that can colour the map (the keys of :data:`FIELDS`)."""

NO_SLIDING_LABEL = "none within max_iter"
"""Key entry of white pixels: no periodic sliding solution within max_iter steps."""

OVERLAYS = ("tongues", "no_sliding", "borders", "traced", "proven")
"""What can be drawn over the map: the (n, 0^inf) tongues of Theorem 3.1, the
no-sliding bound of Corollary 2.1, the exact borders of the view
(:func:`border_overlay`), ``"traced"``, those borders as traced arcs
(:func:`trace_slices`, :func:`traced_overlay`; the border points are shown
until the arcs come and where there are none) and, ``"proven"``, the
certified atlas of the view (:mod:`stairbounce.explorer.proven`)."""

DEFAULT_OVERLAYS = ("tongues", "no_sliding")
"""The overlays a new view shows (the exact borders cost a computation: off)."""

BORDER_SIDE = 160
"""Pixels per side, at most, of the grid whose borders the overlay locates."""

TRACE_SIDE = 48
"""Seed pixels per side of the traced borders (:func:`trace_slices`): every
word with a pixel centre on a ``TRACE_SIDE`` x ``TRACE_SIDE`` grid of the view
has its region traced.  48 keeps a zoomed view to a few seconds: the Fig. 5e
window, 280 words, 1.5 to 4.4 s on the shared 2-core machine (64 seeds: 409
words, 6.1 s in the same run; 32: 163 words, 2.8 s); benchmarks/README.md,
"The explorer's traced borders".  A region narrower than a seed pixel
everywhere is not traced, and its border points stay on the map.  The whole
Fig. 4 window takes about 8 s, most of it in walks that give up (6 of its 48
words, marked incomplete; one such word is one slice of up to 5 s)."""

PIXEL_BUDGET = 1_000_000
"""Largest view, in pixels, that is computed (1000 x 1000)."""

WORK_BUDGET = 5_000_000_000
"""Largest ``pixels * max_iter`` computed: the worst case (nothing slides, every
pixel runs ``max_iter`` steps) takes of the order of 10 s on two cores."""

MAX_ITER_LIMIT = 1_000_000
"""Largest ``max_iter`` accepted (the work budget usually binds first)."""

U_LIMIT = 50.0
"""Largest u shown; the (n, 0^inf) tongues reach u = sqrt(n/2) only as e -> 0."""

MIN_SIDE = 16
"""Smallest side of a view in pixels."""

# A window is refused when neighbouring pixel centres are closer than this many
# float64 spacings: deeper than that the picture would be rounding noise.
_MIN_ULPS_PER_PIXEL = 4

# A render is cut into slices of at most this many potential map steps
# (pixels * max_iter, the worst case where nothing slides): the server's
# scheduler runs one slice at a time, so a cheap request of another session
# waits at most one slice (under 0.1 s on two idle cores at the 1.2-1.4 G
# steps/s of a window where nothing slides, benchmarks/README.md; a few
# tenths under load), and a cancelled render stops within one.  Smaller
# slices cost more: each parallel call ends on its slowest thread.
SLICE_WORK = 100_000_000

# The coarse preview samples every COARSE-th pixel in each direction (1/64 of
# the pixels); views cheaper than PREVIEW_WORK map steps (the Fig. 4 view at
# 600 x 600 and max_iter 1000 is 3.6e8) skip it.
COARSE = 8
PREVIEW_WORK = 4 * SLICE_WORK

# the slice_work of the one-call versions of the sliced jobs (word_row, traced_overlay)
_UNBOUNDED = 2**62


@dataclass(frozen=True)
class View:
    """One view of the (e, u) plane: window, pixel size, iteration cap, colouring.

    ``e_lo < e_hi`` within [0, 1], ``u_lo < u_hi`` within [0, U_LIMIT];
    ``width`` pixels along e and ``height`` along u; ``point`` is the tapped
    ``(e, u)`` or ``None``.
    """

    e_lo: float = 0.0
    e_hi: float = 1.0
    u_lo: float = 0.0
    u_hi: float = 1.5
    width: int = 600
    height: int = 600
    max_iter: int = 1000
    color: str = "word_length"
    overlays: tuple[str, ...] = field(default=DEFAULT_OVERLAYS)
    point: tuple[float, float] | None = None

    @property
    def pixels(self) -> int:
        return self.width * self.height

    @property
    def work(self) -> int:
        """Most map steps the scan can take: every pixel runs ``max_iter`` steps."""
        return self.pixels * self.max_iter

    def with_window(self, e_lo, e_hi, u_lo, u_hi) -> View:
        return replace(self, e_lo=float(e_lo), e_hi=float(e_hi), u_lo=float(u_lo), u_hi=float(u_hi))


DEFAULT_VIEW = View()
"""The paper's Figure 4 window, e in [0, 1], u in [0, 1.5], 600 x 600 pixels."""


class Cancelled(Exception):
    """A render was abandoned because a newer one was requested."""


# --------------------------------------------------------------------------- #
# URL query <-> view                                                          #
# --------------------------------------------------------------------------- #


def _fmt(x: float) -> str:
    """Shortest text that reads back as the same float64 (deep zooms survive)."""
    s = repr(float(x))
    return s[:-2] if s.endswith(".0") else s


def format_window(lo: float, hi: float) -> str:
    """``"0:1.5"``: a window as the URL and the page show it (exact float64 text)."""
    return f"{_fmt(lo)}:{_fmt(hi)}"


def _text(value) -> str:
    """One query value: Panel gives lists of bytes, tests give plain strings."""
    if isinstance(value, (list, tuple)):
        if not value:
            return ""
        value = value[-1]  # a repeated parameter: the last one wins, as in browsers' forms
    if isinstance(value, bytes):
        value = value.decode("utf-8", errors="replace")
    return str(value).strip()


def _number(name, text):
    try:
        x = float(text)
    except ValueError:
        raise ValueError(f"{name} must be a number, got {text!r}") from None
    if not math.isfinite(x):
        raise ValueError(f"{name} must be finite, got {text!r}")
    return x


def parse_window(name: str, text: str, limit: float) -> tuple[float, float]:
    """``"0:1.5"`` -> ``(0.0, 1.5)`` with ``0 <= lo < hi <= limit``."""
    parts = text.split(":")
    if len(parts) != 2:
        raise ValueError(f"{name} must be a range LO:HI, got {text!r}")
    lo, hi = (_number(name, p) for p in parts)
    if not 0.0 <= lo < hi <= limit:
        raise ValueError(f"{name} must satisfy 0 <= LO < HI <= {_fmt(limit)}, got {text!r}")
    return lo, hi


def parse_size(text: str) -> tuple[int, int]:
    """``"600x400"`` -> ``(600, 400)``: width along e, height along u, within the budget."""
    parts = text.lower().split("x")
    try:
        w, h = (int(p) for p in parts)
    except ValueError:
        raise ValueError(f"size must be WIDTHxHEIGHT in pixels, e.g. 600x600, got {text!r}") from None
    if w < MIN_SIDE or h < MIN_SIDE:
        raise ValueError(f"size must be at least {MIN_SIDE}x{MIN_SIDE} pixels, got {text!r}")
    if w * h > PIXEL_BUDGET:
        raise ValueError(
            f"size {w}x{h} is {w * h} pixels, over the pixel budget of {PIXEL_BUDGET}"
        )
    return w, h


def parse_max_iter(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        raise ValueError(f"max_iter must be an integer in [1, {MAX_ITER_LIMIT}], got {text!r}") from None
    if not 1 <= n <= MAX_ITER_LIMIT:
        raise ValueError(f"max_iter must be an integer in [1, {MAX_ITER_LIMIT}], got {text!r}")
    return n


def parse_color(text: str) -> str:
    if text not in COLOR_VARS:
        raise ValueError(f"color must be one of {', '.join(COLOR_VARS)}, got {text!r}")
    return text


def parse_overlays(text: str) -> tuple[str, ...]:
    if text in ("", "none"):
        return ()
    names = tuple(dict.fromkeys(t.strip() for t in text.split(",")))
    bad = [n for n in names if n not in OVERLAYS]
    if bad:
        raise ValueError(
            f"overlays must be 'none' or a comma-separated list of {', '.join(OVERLAYS)}, got {text!r}"
        )
    return tuple(n for n in OVERLAYS if n in names)


def parse_point(text: str) -> tuple[float, float]:
    """``"0.1,0.75"`` -> ``(0.1, 0.75)``, a valid ``(e, u)``."""
    parts = text.split(",")
    if len(parts) != 2:
        raise ValueError(f"point must be E,U, got {text!r}")
    e, u = (_number("point", p) for p in parts)
    try:
        e, u = check_e(e), check_u(u)
    except ValueError as exc:
        raise ValueError(f"point: {exc}") from None
    if u > U_LIMIT:
        raise ValueError(f"point: u must be <= {_fmt(U_LIMIT)}, got {u}")
    return e, u


def parse_query(args) -> tuple[View, list[str]]:
    """parse_query(args) -> (View, messages)

    The view a page URL asks for, and what was wrong with it.

    ``args`` maps query names to a string, bytes, or a list of them (Panel's
    ``pn.state.session_args`` gives lists of bytes).  Recognised names:
    ``e=LO:HI`` (0 <= LO < HI <= 1), ``u=LO:HI`` (0 <= LO < HI <= U_LIMIT),
    ``size=WxH`` (W*H <= PIXEL_BUDGET), ``max_iter=N``, ``color=NAME``
    (one of :data:`COLOR_VARS`), ``overlays=tongues,no_sliding`` or ``none``,
    ``point=E,U``.  Each malformed or out-of-range value is replaced by the
    default of :data:`DEFAULT_VIEW` and reported in one message; so is a view
    that fails :func:`check_view` as a whole.  Never raises on user input.
    """
    view = DEFAULT_VIEW
    messages: list[str] = []
    parsers: dict[str, Callable[[str], dict]] = {
        "e": lambda t: dict(zip(("e_lo", "e_hi"), parse_window("e", t, 1.0))),
        "u": lambda t: dict(zip(("u_lo", "u_hi"), parse_window("u", t, U_LIMIT))),
        "size": lambda t: dict(zip(("width", "height"), parse_size(t))),
        "max_iter": lambda t: {"max_iter": parse_max_iter(t)},
        "color": lambda t: {"color": parse_color(t)},
        "overlays": lambda t: {"overlays": parse_overlays(t)},
        "point": lambda t: {"point": parse_point(t)},
    }
    defaults = view_query(DEFAULT_VIEW)
    for name, value in dict(args or {}).items():
        if name not in parsers:
            messages.append(f"ignored unknown URL parameter {name!r}")
            continue
        text = _text(value)
        try:
            view = replace(view, **parsers[name](text))
        except ValueError as exc:
            fallback = defaults.get(name, "none")
            messages.append(f"ignored {name}={text!r} from the URL: {exc}; using {fallback}")
    if view.work > WORK_BUDGET:
        messages.append(
            f"ignored max_iter={view.max_iter} from the URL: {view.pixels} pixels x max_iter is "
            f"over the work budget of {WORK_BUDGET:.3g} map steps; using {DEFAULT_VIEW.max_iter}"
        )
        view = replace(view, max_iter=DEFAULT_VIEW.max_iter)  # <= 1e9 steps at any allowed size
    try:
        check_view(view)
    except ValueError as exc:  # only the window can still be wrong: float64 resolution
        messages.append(f"ignored the URL's window: {exc}; using the Figure 4 window")
        view = view.with_window(DEFAULT_VIEW.e_lo, DEFAULT_VIEW.e_hi, DEFAULT_VIEW.u_lo, DEFAULT_VIEW.u_hi)
    return view, messages


def view_query(view: View) -> dict[str, str]:
    """view_query(view) -> dict

    The URL query of a view; :func:`parse_query` reads it back exactly.
    """
    q = {
        "e": format_window(view.e_lo, view.e_hi),
        "u": format_window(view.u_lo, view.u_hi),
        "size": f"{view.width}x{view.height}",
        "max_iter": str(view.max_iter),
        "color": view.color,
        "overlays": ",".join(view.overlays) or "none",
    }
    if view.point is not None:
        q["point"] = f"{_fmt(view.point[0])},{_fmt(view.point[1])}"
    return q


def view_url_query(view: View) -> str:
    """``?e=0:1&u=0:1.5&...``: the query string of a shareable link."""
    return "?" + urlencode(view_query(view), safe=":,")


# --------------------------------------------------------------------------- #
# Limits and computation                                                      #
# --------------------------------------------------------------------------- #


def _check_resolution(name, lo, hi, n):
    step = (hi - lo) / n
    ulp = float(np.spacing(max(abs(lo), abs(hi))))
    if not step >= _MIN_ULPS_PER_PIXEL * ulp:
        raise ValueError(
            f"the {name} window [{_fmt(lo)}, {_fmt(hi)}] is too narrow for {n} pixels in float64 "
            f"(pixel width {step:.3g}, float64 spacing {ulp:.3g}): zoom out"
        )


def check_view(view: View) -> View:
    """check_view(view) -> View

    Raise :class:`ValueError` (naming the limit) when a view must not be computed.

    Limits: the window within e in [0, 1] and u in [0, U_LIMIT] with
    ``lo < hi``; each side >= MIN_SIDE pixels; ``width * height <=
    PIXEL_BUDGET``; ``1 <= max_iter <= MAX_ITER_LIMIT`` and ``width * height *
    max_iter <= WORK_BUDGET``; neighbouring pixel centres at least a few
    float64 spacings apart (deeper zooms are rounding noise).
    """
    for name, lo, hi, limit in (("e", view.e_lo, view.e_hi, 1.0), ("u", view.u_lo, view.u_hi, U_LIMIT)):
        if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 <= lo < hi <= limit):
            raise ValueError(f"{name} window must satisfy 0 <= lo < hi <= {_fmt(limit)}, got [{lo}, {hi}]")
    if view.width < MIN_SIDE or view.height < MIN_SIDE:
        raise ValueError(f"view size must be at least {MIN_SIDE}x{MIN_SIDE} pixels, got {view.width}x{view.height}")
    if view.pixels > PIXEL_BUDGET:
        raise ValueError(
            f"view of {view.width}x{view.height} = {view.pixels} pixels refused: over the pixel "
            f"budget of {PIXEL_BUDGET}"
        )
    if not 1 <= view.max_iter <= MAX_ITER_LIMIT:
        raise ValueError(f"max_iter must be in [1, {MAX_ITER_LIMIT}], got {view.max_iter}")
    if view.work > WORK_BUDGET:
        raise ValueError(
            f"view refused: {view.pixels} pixels x max_iter {view.max_iter} = {view.work:.3g} map "
            f"steps in the worst case, over the work budget of {WORK_BUDGET:.3g}; lower max_iter "
            "or the size"
        )
    if view.color not in COLOR_VARS:
        raise ValueError(f"color must be one of {', '.join(COLOR_VARS)}, got {view.color!r}")
    _check_resolution("e", view.e_lo, view.e_hi, view.width)
    _check_resolution("u", view.u_lo, view.u_hi, view.height)
    return view


@dataclass
class Partial:
    """A render in progress, yielded by :func:`render_slices` after each slice.

    ``coarse``: scans of bands of the coarse grid, every ``step``-th pixel
    centre of both axes from offset ``step // 2`` (empty when the view skips
    the preview); ``parts``: the scans of the first ``rows_done`` rows, in order.
    """

    view: View
    coarse: list
    parts: list
    rows_done: int
    step: int = COARSE

    @property
    def fraction(self) -> float:
        return self.rows_done / self.view.height


def render_slices(view: View, slice_work: int | None = None, coarse: int = COARSE,
                  preview_work: int | None = None):
    """render_slices(view, slice_work=SLICE_WORK, coarse=COARSE, preview_work=PREVIEW_WORK) -> generator

    The scan of a view computed one bounded slice at a time.

    A generator: each ``next()`` computes one slice and yields the
    :class:`Partial` so far; the generator's return value (``StopIteration.value``)
    is the finished dataset, equal bit for bit to :func:`stairbounce.plane.scan`
    on the view's window (pixels are independent, so scanning rows of
    :func:`~stairbounce.plane.pixel_centres` in bands changes nothing).

    First, when the view costs more than ``preview_work`` map steps, the
    coarse preview: every ``coarse``-th pixel centre of both axes (exact
    values of those pixels, 1/coarse^2 of the work); then the full grid.
    Both in bands of rows of at most ``slice_work`` potential map steps
    (``max_iter`` per pixel), a row over it in pieces of at most that
    (:func:`_bands`; one pixel at least).  A view coloured by a motion
    field (:data:`MOTION_COLOR_VARS`) also has the fields of
    :func:`stairbounce.nonsliding.motion_coords` in every band (``max_iter``
    transient and ``max_iter`` kept steps, 3 ``max_iter`` per pixel in all),
    so it is cut into slices and cancelled like any render.

    Raises :class:`ValueError` from :func:`check_view` for a view over budget.
    """
    check_view(view)
    slice_work = SLICE_WORK if slice_work is None else slice_work
    preview_work = PREVIEW_WORK if preview_work is None else preview_work
    es = plane.pixel_centres(view.e_lo, view.e_hi, view.width)
    us = plane.pixel_centres(view.u_lo, view.u_hi, view.height)

    motion = view.color in MOTION_COLOR_VARS
    # a motion field costs max_iter transient + max_iter kept steps per pixel
    per_pixel = view.max_iter * (3 if motion else 1)

    def compute(e, u):
        band = plane.scan_coords(e, u, max_iter=view.max_iter)
        return _with_motion(band, view, e, u) if motion else band

    pre = []
    if coarse > 1 and view.work > preview_work and min(view.width, view.height) >= 2 * coarse:
        off = coarse // 2
        for _, band in _bands(es[off::coarse], us[off::coarse], per_pixel, slice_work, compute):
            if band is not None:
                pre.append(band)
            yield Partial(view, pre, [], 0, coarse)
    parts, rows = [], 0
    for done, band in _bands(es, us, per_pixel, slice_work, compute):
        if band is not None:
            parts.append(band)
            rows = done
        if done < view.height or band is None:
            yield Partial(view, pre, parts, rows, coarse)
    ds = parts[0] if len(parts) == 1 else xr.concat(parts, dim="u", combine_attrs="override")
    ds.attrs.update(
        e_min=view.e_lo, e_max=view.e_hi, n_e=view.width,
        u_min=view.u_lo, u_max=view.u_hi, n_u=view.height,
    )
    return ds


def _bands(es, us, per_pixel, slice_work, compute):
    """The grid ``us x es`` computed by ``compute(e, u) -> Dataset`` in blocks of
    at most ``slice_work`` potential map steps (``per_pixel`` each;
    :func:`stairbounce.structure.borders.grid_blocks`): yields ``(rows done, band)``
    after each block, ``band`` the Dataset of the rows just completed, or
    ``None`` after a piece of a row (pixels are independent: the pieces
    joined along ``e`` are the row bit for bit)."""
    from ..structure.borders import grid_blocks

    pieces = []
    for r, c in grid_blocks(es.size, us.size, per_pixel, slice_work):
        pieces.append(compute(es[c], us[r]))
        if c.stop < es.size:
            yield r.start, None
            continue
        band = pieces[0] if len(pieces) == 1 else xr.concat(pieces, dim="e", combine_attrs="override")
        pieces = []
        yield r.stop, band


def grid_scan_slices(e, u, max_iter, slice_work=None):
    """grid_scan_slices(e=(lo, hi, n), u=(lo, hi, n), max_iter, slice_work=SLICE_WORK) -> generator, returning xarray.Dataset

    :func:`stairbounce.plane.scan_coords` of the window's pixel centres in
    blocks of at most ``slice_work`` potential map steps (:func:`_bands`),
    yielding ``(rows done, rows)`` after each; returns the scan with the
    window's attributes (as :func:`stairbounce.scan`'s), which the border
    points and the word table read.
    """
    slice_work = SLICE_WORK if slice_work is None else slice_work
    es, us = plane.pixel_centres(*e), plane.pixel_centres(*u)
    parts = []
    for done, band in _bands(es, us, max_iter, slice_work,
                             lambda a, b: plane.scan_coords(a, b, max_iter=max_iter)):
        if band is not None:
            parts.append(band)
        yield done, us.size
    ds = parts[0] if len(parts) == 1 else xr.concat(parts, dim="u", combine_attrs="override")
    ds.attrs.update(e_min=float(e[0]), e_max=float(e[1]), n_e=int(e[2]),
                    u_min=float(u[0]), u_max=float(u[1]), n_u=int(u[2]))
    return ds


def compute_view(view: View, cancelled=None, progress=None) -> xr.Dataset:
    """compute_view(view, cancelled=None, progress=None) -> xarray.Dataset

    The scan of a view: :func:`stairbounce.plane.scan` on its window and pixels.

    Runs :func:`render_slices` to the end (same values bit for bit as one
    call of ``scan``; the dataset carries the same attributes).  Between
    slices ``cancelled()`` is asked whether a newer request superseded this
    one (then :class:`Cancelled` is raised) and ``progress(done, total)`` is
    told how many rows are done.

    Raises :class:`ValueError` from :func:`check_view` for a view over budget.
    """
    gen = render_slices(view)
    while True:
        if cancelled is not None and cancelled():
            gen.close()
            raise Cancelled
        try:
            part = next(gen)
        except StopIteration as stop:
            ds = stop.value
            if progress is not None:
                progress(view.height, view.height)
            return ds
        if progress is not None:
            progress(part.rows_done, view.height)


def preview_rgba(part: Partial, var: str) -> np.ndarray:
    """preview_rgba(part, var) -> uint32 array (n_u, n_e)

    The picture of a render in progress: the rows already computed at full
    resolution, the others from the coarse preview (each coarse sample
    painted over the ``step x step`` block of pixels around it), and
    the not-yet-computed colour where there is neither.
    """
    v, c = part.view, part.step
    out = np.full((v.height, v.width), _rgba32((NOT_COMPUTED_COLOR,))[0], dtype=np.uint32)
    row = 0
    for band in part.coarse:
        block = np.repeat(np.repeat(shade(band, var), c, axis=0), c, axis=1)
        rows = min(block.shape[0], v.height - row)
        if rows <= 0:
            break
        # the last block column (row) covers what is left of a side not divisible by step
        block = np.pad(block, ((0, 0), (0, max(0, v.width - block.shape[1]))), mode="edge")
        out[row : row + rows] = block[:rows, : v.width]
        row += rows
    n_coarse = len(range(c // 2, v.height, c))
    if part.coarse and sum(b.sizes["u"] for b in part.coarse) == n_coarse and 0 < row < v.height:
        out[row:] = out[row - 1]  # a side not divisible by step: its last block is taller
    row = 0
    for p in part.parts:
        n = p.sizes["u"]
        out[row : row + n] = shade(p, var)
        row += n
    return out


def window_digits(lo: float, hi: float, n: int) -> int:
    """window_digits(lo, hi, n) -> int

    Significant digits that show the ends of a window of ``n`` pixels apart
    and resolve one pixel: a tenth of a pixel at the larger end, 4 to 17.
    """
    big = max(abs(lo), abs(hi), 1e-300)
    pixel = (hi - lo) / n
    return int(min(17, max(4, math.ceil(math.log10(big / (pixel / 10))))))


def format_number(x: float, digits: int) -> str:
    """``x`` with ``digits`` significant digits, or its exact shortest text if shorter."""
    exact = _fmt(x)
    short = f"{x:.{digits}g}"
    return exact if len(exact) <= len(short) else short


def tidy(x: float, tolerance: float) -> float:
    """tidy(x, tolerance) -> float

    The float with the shortest decimal text within ``tolerance`` of ``x``
    (``0.9200000000000002`` -> ``0.92`` for any tolerance above 2e-16): a
    zoom or pan lands on the range Bokeh computed, whose last bits are noise.
    """
    for p in range(1, 18):
        y = float(f"{x:.{p}g}")
        if abs(y - x) <= tolerance:
            return y
    return float(x)


def _with_motion(ds, view, es, us):
    """``ds`` (a band of rows) with the fields of
    :func:`stairbounce.nonsliding.motion_coords` (``max_iter`` transient +
    ``max_iter`` kept steps) at the same pixel centres."""
    from ..nonsliding import motion_coords

    m = motion_coords(es, us, steps=max(2, view.max_iter), transient=view.max_iter)
    return ds.assign({k: m[k] for k in m.data_vars}).assign_attrs(motion_steps=m.attrs["steps"])


def has_color(ds: xr.Dataset, var: str) -> bool:
    """Whether ``ds`` holds what colouring by ``var`` needs (a motion variable
    needs a view computed with it, :func:`compute_view`)."""
    return var in ds or var == "status"


def pixel_of(view: View, e: float, u: float) -> tuple[int, int] | None:
    """Indices ``(row along u, column along e)`` of the pixel containing ``(e, u)``,
    or ``None`` outside the window."""
    if not (view.e_lo <= e <= view.e_hi and view.u_lo <= u <= view.u_hi):
        return None
    j = min(view.width - 1, int((e - view.e_lo) / (view.e_hi - view.e_lo) * view.width))
    i = min(view.height - 1, int((u - view.u_lo) / (view.u_hi - view.u_lo) * view.height))
    return i, j


# --------------------------------------------------------------------------- #
# Colours                                                                     #
# --------------------------------------------------------------------------- #

# One colour scale for the explorer and the figures (Figs. 4 and 5): the
# classes of the counts (_CLASS_STARTS from their least values _LEAST), their
# colours and white for no sliding live with the matplotlib renderer of the
# plane (stairbounce.plot.plane); the explorer adds the grey of pixels not yet
# computed and the continuous keys of the motion fields.
NOT_COMPUTED_COLOR = "#b8b8b8"


def color_key(var: str) -> ColorKey:
    """color_key(var) -> ColorKey: the classes and colours used for ``var``: the
    figures' discrete scale for the counts (:func:`stairbounce.plot.plane.color_key`),
    found / none within max_iter for ``status``, a continuous key for the
    motion variables."""
    if var not in FIELDS:
        raise ValueError(f"color must be one of {', '.join(COLOR_VARS)}, got {var!r}")
    if var in MOTION_COLOR_VARS:
        return _motion_key(var)
    _, title, b = FIELDS[var]
    if b is None:
        return ColorKey(var, title, ("found", NO_SLIDING_LABEL), ("#000000", NO_SLIDING_COLOR))
    return replace(_sliding_color_key(var), title=title)


def _rgba32(hex_colors):
    """Hex colours -> uint32 RGBA in the little-endian byte order Bokeh's
    ``image_rgba`` and Pillow's ``RGBA`` mode read."""
    out = np.empty(len(hex_colors), dtype=np.uint32)
    for i, h in enumerate(hex_colors):
        r, g, b = (int(h[k : k + 2], 16) for k in (1, 3, 5))
        out[i] = r | (g << 8) | (b << 16) | (255 << 24)
    return out


# Continuous keys of the motion variables: class 0 is "the orbit slides"
# (grey), then _NBINS colours over a fixed range: log10 <k> in [-2.5, 1.5];
# N lambda_1 in [-5, 5] (lambda_1 = 0 exactly, its finite-N estimate is O(1/N)).
_NBINS = 64
SLIDES_COLOR = "#9a9a9a"
_MOTION_RANGE = {"k_mean": (-2.5, 1.5), "lyap1": (-5.0, 5.0)}


def _motion_key(var):
    from matplotlib import colormaps
    from matplotlib.colors import to_hex

    cmap = colormaps["viridis" if var == "k_mean" else "RdBu_r"]
    colors = (SLIDES_COLOR,) + tuple(to_hex(cmap(x)) for x in np.linspace(0, 1, _NBINS))
    lo, hi = _MOTION_RANGE[var]
    labels = ["slides"] + [""] * _NBINS
    marks = {"k_mean": {-2: "0.01", -1: "0.1", 0: "1", 1: "10"},
             "lyap1": {-5: "-5/N", -2.5: "-2.5/N", 0: "0", 2.5: "+2.5/N", 5: "+5/N"}}[var]
    for x, text in marks.items():
        labels[1 + min(_NBINS - 1, int((x - lo) / (hi - lo) * _NBINS))] = text
    return ColorKey(var, FIELDS[var][1], tuple(labels), colors)


def classes(ds: xr.Dataset, var: str) -> np.ndarray:
    """Class index of every pixel under :func:`color_key` (-1: no sliding; a
    motion variable: 0 where the orbit slides, never -1)."""
    if var in MOTION_COLOR_VARS:
        lo, hi = _MOTION_RANGE[var]
        with np.errstate(invalid="ignore", divide="ignore"):
            x = np.log10(ds[var].values) if var == "k_mean" else ds[var].values * ds.attrs["motion_steps"]
        idx = 1 + np.clip(np.floor((x - lo) / (hi - lo) * _NBINS), 0, _NBINS - 1)
        return np.where((ds["slide_step"].values > 0) | ~np.isfinite(x), 0, idx).astype(np.int64)
    sliding = ds["status"].values == 0
    least = FIELDS[var][2]
    if least is None:
        return np.where(sliding, 0, 1)
    v = ds[var].values.astype(np.int64) - least
    idx = np.searchsorted(np.asarray(_CLASS_STARTS), v, side="right") - 1
    return np.where(sliding, idx, -1)


def shade(ds: xr.Dataset, var: str) -> np.ndarray:
    """shade(ds, var) -> uint32 array (n_u, n_e)

    RGBA pixels of a scan coloured by ``var`` (row 0 is the lowest u), the
    colours of :func:`color_key`; no sliding solution is white.
    """
    key = color_key(var)
    lut = _rgba32(key.colors + (NO_SLIDING_COLOR,))
    return lut[classes(ds, var)]  # index -1 picks the no-sliding colour


# --------------------------------------------------------------------------- #
# Overlays and the tapped point                                               #
# --------------------------------------------------------------------------- #


def overlay_curves(view: View, samples: int = 400, max_tongues: int = 400) -> dict:
    """overlay_curves(view, samples=400, max_tongues=400) -> dict

    Curves of the paper over the view's e range, as lists of polylines.

    ``"tongues"``: the outline of every (n, 0^inf) tongue of Theorem 3.1 that
    meets the window, ``sqrt((n-1)/2) < u <= sqrt(n/2) (1-e)/(1+e)`` (bounds
    from :func:`stairbounce.tongue`), closed at the e where the two bounds
    meet; ``"no_sliding"``: Corollary 2.1's ``u = (1-e)/(2 sqrt(2e))``
    (:func:`stairbounce.plane.no_sliding_curve`).  Each value is
    ``(xs, ys)``, two lists of 1-D arrays; at most ``max_tongues`` tongues
    (the ones nearest the window's bottom).
    """
    e = np.linspace(view.e_lo, min(view.e_hi, np.nextafter(1.0, 0.0)), samples)
    txs, tys = [], []
    n_first = max(1, int(2.0 * view.u_lo**2))  # sqrt(n/2) <= u_lo: the tongue lies below
    n_last = min(n_first + max_tongues, int(2.0 * view.u_hi**2) + 1)
    for n in range(n_first, n_last + 1):
        u_low, top0 = tongue(n, 0.0)
        if top0 <= view.u_lo or u_low >= view.u_hi:
            continue
        # the bounds meet where (1-e)/(1+e) = u_low / top0
        r = u_low / top0
        e_tip = (1.0 - r) / (1.0 + r)
        inside = e < e_tip
        if not inside.any():
            continue
        ee = np.concatenate([e[inside], [e_tip]]) if e_tip <= view.e_hi else e[inside]
        top = top0 * (1.0 - ee) / (1.0 + ee)
        xs = np.concatenate([ee, ee[::-1]])
        ys = np.concatenate([top, np.full(ee.size, u_low)[::-1]])
        txs.append(xs)
        tys.append(ys)
    with np.errstate(divide="ignore"):
        ns = plane.no_sliding_curve(e)
    ok = np.isfinite(ns)
    return {"tongues": (txs, tys), "no_sliding": ([e[ok]], [ns[ok]])}


def border_grid(view: View, side: int = BORDER_SIDE) -> tuple:
    """border_grid(view, side=BORDER_SIDE) -> ((e_lo, e_hi, n_e), (u_lo, u_hi, n_u))

    The window arguments of the grid of at most ``side`` x ``side`` pixels of
    the view's window on which the exact borders and the tap's word table row
    are computed (the view's own pixels when it is no larger).
    """
    n_e = max(2, min(side, view.width))
    n_u = max(2, min(side, view.height))
    return (view.e_lo, view.e_hi, n_e), (view.u_lo, view.u_hi, n_u)


def view_border_points(view: View, side: int = BORDER_SIDE) -> xr.Dataset:
    """:func:`stairbounce.border_points` of :func:`border_grid` (the view's max_iter)."""
    from ..structure.borders import border_points

    e, u = border_grid(view, side)
    return border_points(e=e, u=u, max_iter=view.max_iter)


def border_point_slices(view: View, side: int = BORDER_SIDE, slice_work: int | None = None):
    """border_point_slices(view, side=BORDER_SIDE, slice_work=SLICE_WORK) -> generator, returning xarray.Dataset

    :func:`view_border_points` in slices of at most ``slice_work`` map steps
    (the explorer's scheduler; issue 38, R1): the grid's scan
    (:func:`grid_scan_slices`, ``max_iter`` per pixel), then the pairs
    (:func:`stairbounce.structure.borders.border_point_slices`, a bound of
    :func:`stairbounce.structure.borders.pair_work` each).  Yields ``("scan", done,
    total)`` and ``("pairs", done, total)``; returns the same Dataset as
    :func:`view_border_points`.
    """
    from ..structure.borders import _grid_input, staged
    from ..structure.borders import border_point_slices as pair_slices

    slice_work = SLICE_WORK if slice_work is None else slice_work
    e, u = border_grid(view, side)
    ds = yield from staged("scan", grid_scan_slices(e, u, view.max_iter, slice_work))
    es, us, period, max_iter = _grid_input(ds)
    attrs = {k: ds.attrs[k] for k in ("e_min", "e_max", "n_e", "u_min", "u_max", "n_u")}
    return (yield from staged("pairs", pair_slices(es, us, period, max_iter, attrs, slice_work)))


def border_overlay(view: View, side: int = BORDER_SIDE, points: xr.Dataset | None = None) -> dict:
    """border_overlay(view, side=BORDER_SIDE, points=None) -> dict

    The exact borders of the view (:func:`stairbounce.border_points` on a grid
    of at most ``side`` x ``side`` pixels of its window, the view's
    max_iter; ``points`` when already computed: :func:`view_border_points`),
    as columns for a scatter: ``e``, ``u``, ``kind``, ``step``, ``word_low``,
    ``word_high``.
    """
    pts = view_border_points(view, side) if points is None else points
    return {k: pts[k].values.tolist() for k in ("e", "u", "kind", "step", "word_low", "word_high")}


def trace_window(view: View) -> tuple:
    """trace_window(view) -> ((e_lo, e_hi), (u_lo, u_hi))

    The window whose regions :func:`trace_slices` traces: the view's, with e
    below 1 and u above 0 (the margins of :mod:`stairbounce.structure.itinerary` need
    both; as :func:`stairbounce.word_table` with ``regions=True``).
    """
    return (view.e_lo, min(view.e_hi, 1.0 - 1e-12)), (max(view.u_lo, 1e-9), view.u_hi)


def trace_slices(view: View, side: int = TRACE_SIDE, slice_work: int | None = None):
    """trace_slices(view, side=TRACE_SIDE, slice_work=SLICE_WORK) -> generator of (done, total), returning list[Region]

    The regions of every word of the view (:func:`stairbounce.window_regions`'
    method, the words seen by ``side`` x ``side`` seed pixel centres of
    :func:`trace_window`, the view's max_iter), one word per ``next()``: the
    scheduler's slices, so a trace of many words stays cancellable and shares
    the worker.  The seed scan comes first, in slices of at most
    ``slice_work`` map steps, each yielding ``(0, None)``; then ``(0,
    total)`` once the words are known and ``(done, total)`` after each word;
    returns the regions, largest first.
    """
    from ..structure.regions import iter_window_regions

    e, u = trace_window(view)
    return (yield from iter_window_regions(e, u, resolution=side, max_iter=view.max_iter,
                                           slice_work=SLICE_WORK if slice_work is None else slice_work))


def _word_at(e, u, window, max_iter, buf, texts):
    """The word text of the orbit of (1, 0) at (e, u) as the border points write
    it, or "outside the view" outside ``window`` (``texts``: the texts found
    so far, by the itinerary's hashes)."""
    from ..structure.itinerary import _hash_itinerary, _itinerary_of
    from ..structure.words import NONE_WORD, _word_text

    (e0, e1), (u0, u1) = window
    if not (e0 <= e <= e1 and u0 <= u <= u1):
        return OUTSIDE_WORD
    n = _itinerary_of(e, u, 1.0, 0.0, max_iter, buf)
    if n <= 0:
        return NONE_WORD
    key = (n, *(int(h) for h in _hash_itinerary(buf, n)))
    if key not in texts:
        texts[key] = _word_text(buf[:n])
    return texts[key]


OUTSIDE_WORD = "outside the view"
"""The word of the outer side of a traced arc on the window's edge."""


def _arc_sides(arc, window, max_iter, buf, texts):
    """``(word_low, word_high)``: the map's words just off the middle of ``arc``
    on its two sides, the low side being the one of smaller u (smaller e where
    the arc is nearer vertical than horizontal, in the window's scaled units,
    as a border point's bisection axis would be)."""
    (e0, e1), (u0, u1) = window
    x = (np.asarray(arc.e) - e0) / (e1 - e0)
    y = (np.asarray(arc.u) - u0) / (u1 - u0)
    n = x.size
    if n >= 3:  # a traced point: on the curve to rounding
        m = n // 2
        px, py, tx, ty = x[m], y[m], x[m + 1] - x[m - 1], y[m + 1] - y[m - 1]
    else:  # two corners: the chord's middle, off the curve by its sagitta at most
        px, py, tx, ty = 0.5 * (x[0] + x[-1]), 0.5 * (y[0] + y[-1]), x[-1] - x[0], y[-1] - y[0]
    norm = math.hypot(tx, ty) or 1.0
    nx, ny = -ty / norm, tx / norm  # the left normal
    if abs(ny) >= abs(nx):
        low = -1.0 if ny > 0 else 1.0  # the side of smaller u
    else:
        low = -1.0 if nx > 0 else 1.0  # the side of smaller e
    words = None
    for d in (1e-9, 1e-7, 1e-5, 1e-3):  # the nearest offset that sees two words
        words = [_word_at(e0 + (px + s * d * nx) * (e1 - e0), u0 + (py + s * d * ny) * (u1 - u0), window,
                          max_iter, buf, texts)
                 for s in (low, -low)]
        if words[0] != words[1]:
            break
    return words[0], words[1]


def _on_arcs(points, arcs, window):
    """Which border points lie on a traced arc of their own kind and step: in
    the window's scaled units (its sides 1), within 1e-9 of one of the arc's
    points or beside one of its chords within 1.5 % of the chord's length
    (the arcs turn by at most 0.08 rad per chord, so a chord leaves its curve
    by at most 1 % of its length)."""
    (e0, e1), (u0, u1) = window
    pe = (np.asarray(points["e"]) - e0) / (e1 - e0)
    pu = (np.asarray(points["u"]) - u0) / (u1 - u0)
    kinds, steps = np.asarray(points["kind"]).astype(str), np.asarray(points["step"])
    hit = np.zeros(pe.size, dtype=bool)
    groups: dict = {}
    for arc in arcs:
        if arc.kind != "window":
            P = np.stack([(arc.e - e0) / (e1 - e0), (arc.u - u0) / (u1 - u0)], 1)
            groups.setdefault((arc.kind, arc.step), []).append(P)
    tol = 1e-9
    for (kind, step), polys in groups.items():
        A = np.concatenate([P[:-1] for P in polys])
        B = np.concatenate([P[1:] for P in polys])
        AB = B - A
        L2 = (AB**2).sum(1)
        near = np.maximum(tol, 0.015 * np.sqrt(L2))
        idx = np.flatnonzero((kinds == kind) & (steps == step))
        chunk = max(1, 2_000_000 // A.shape[0])
        for lo in range(0, idx.size, chunk):  # points x chords at a time, in bounded blocks
            i = idx[lo:lo + chunk]
            dx, dy = pe[i, None] - A[None, :, 0], pu[i, None] - A[None, :, 1]
            raw = (dx * AB[:, 0] + dy * AB[:, 1]) / np.where(L2 > 0, L2, 1.0)
            tau = np.clip(raw, 0.0, 1.0)
            d = np.hypot(dx - tau * AB[:, 0], dy - tau * AB[:, 1])
            hit[i] = np.any(d <= np.where((raw > 0) & (raw < 1), near, tol), axis=1)
    return hit


ARC_SIDE_WORK = 8
"""Most orbits of ``max_iter`` steps :func:`_arc_sides` follows per arc (two
sides at four offsets at most)."""


def traced_overlay(view: View, regions, points=None) -> dict:
    """traced_overlay(view, regions, points=None) -> dict

    :func:`traced_overlay_slices` run to its end in one call.
    """
    gen = traced_overlay_slices(view, regions, points, slice_work=_UNBOUNDED)
    while True:
        try:
            next(gen)
        except StopIteration as stop:
            return stop.value


def traced_overlay_slices(view: View, regions, points=None, slice_work=None):
    """traced_overlay_slices(view, regions, points=None, slice_work=SLICE_WORK) -> generator, returning dict

    The traced borders of the view as the overlay draws them: the edges of
    :func:`stairbounce.border_graph` of ``regions`` (from :func:`trace_slices`)
    as ``"arcs"``, columns ``xs``, ``ys`` (one polyline per arc), ``kind``
    (graze, edge, chatter, or window for the window's sides), ``step``,
    ``word_low``, ``word_high`` (the map's words just off the arc's middle,
    :func:`_arc_sides`); ``"covered"``, per border point of ``points`` (a
    :func:`view_border_points` Dataset or its :func:`border_overlay`
    columns), whether a traced arc of its kind and step passes through it
    and neither of its words is incomplete (those points are replaced by the
    arcs; the others stay); ``"words"`` (words traced), ``"incomplete"``
    (their texts: a walk gave up, their points are kept) and ``"counts"``
    (arcs by kind).  The words beside the arcs cost up to
    ``ARC_SIDE_WORK * max_iter`` map steps per arc: they are found for as
    many arcs per ``next()`` as ``slice_work`` map steps allow (one at
    least), yielding ``(arcs done, arcs)``.
    """
    from ..structure.graph import border_graph

    slice_work = SLICE_WORK if slice_work is None else slice_work
    per_slice = max(1, slice_work // (ARC_SIDE_WORK * view.max_iter))
    window = trace_window(view)
    graph = border_graph(regions)
    buf, texts = np.empty(view.max_iter, dtype=np.int64), dict[tuple, str]()
    cols: dict = {k: [] for k in ("xs", "ys", "kind", "step", "word_low", "word_high")}
    counts: dict = {}
    edges = list(graph.edges)
    for i, (_, _, arc) in enumerate(edges):
        if i and i % per_slice == 0:
            yield i, len(edges)
        low, high = _arc_sides(arc, window, view.max_iter, buf, texts)
        for k, v in (("xs", arc.e.tolist()), ("ys", arc.u.tolist()), ("kind", arc.kind), ("step", int(arc.step)),
                     ("word_low", low), ("word_high", high)):
            cols[k].append(v)
        counts[arc.kind] = counts.get(arc.kind, 0) + 1
    incomplete = sorted(r.word.format(ascii=True) for r in regions if not r.complete)
    covered = []
    if points is not None and len(points["e"]):
        covered = _on_arcs(points, [a for _, _, a in graph.edges], window)
        bad = set(incomplete)
        covered &= ~np.array([lo in bad or hi in bad for lo, hi in
                              zip(np.asarray(points["word_low"], dtype=object).tolist(),
                                  np.asarray(points["word_high"], dtype=object).tolist())], dtype=bool)
        covered = covered.tolist()
    return {"arcs": cols, "covered": covered, "words": len(regions), "incomplete": incomplete, "counts": counts}


WORD_ROW_FIELDS = ("text", "letters", "period", "impacts", "pixels", "area_fraction", "e_rep", "u_rep",
                   "e_min", "e_max", "u_min", "u_max", "graze", "edge", "chatter")
"""The columns of :func:`stairbounce.word_table` a tap reports (:func:`word_row`)."""


def word_row(view: View, text: str, side: int = BORDER_SIDE, points: xr.Dataset | None = None,
             table: xr.Dataset | None = None, scan: xr.Dataset | None = None) -> dict:
    """word_row(view, text, side=BORDER_SIDE, points=None, table=None, scan=None) -> dict

    :func:`word_row_slices` run to its end in one call.
    """
    gen = word_row_slices(view, text, side, points, table, scan, slice_work=_UNBOUNDED)
    while True:
        try:
            next(gen)
        except StopIteration as stop:
            return stop.value


def word_row_slices(view: View, text: str, side: int = BORDER_SIDE, points: xr.Dataset | None = None,
                    table: xr.Dataset | None = None, scan: xr.Dataset | None = None,
                    slice_work: int | None = None):
    """word_row_slices(view, text, side=BORDER_SIDE, points=None, table=None, scan=None, slice_work=SLICE_WORK) -> generator, returning dict

    The row of the word ``text`` (ASCII, as ``Word.format(ascii=True)``) in
    :func:`stairbounce.word_table` of the view: the grid :func:`border_grid`
    (at most ``side`` x ``side`` pixels of the window, the view's max_iter);
    ``points``: that grid's :func:`view_border_points` when already computed
    (the "exact borders" overlay); ``table``: that grid's word table when
    already computed (a previous tap in the same view); ``scan``: the view's
    own scan when its pixels are that grid (no scan is computed then).  Returns ``{"grid":
    (n_e, n_u), "words": number of distinct words there, "row": {column:
    value} or None, "table": the word table}`` (row None: the word has no
    pixel centre on that grid, e.g. a region smaller than its pixels).
    Computed in slices of at most ``slice_work`` map steps (the scan of
    the grid, its border points unless given, the words of its pixels:
    :func:`stairbounce.structure.borders.word_table_slices`), yielding ``(stage,
    done, total)``.
    """
    from ..structure.borders import staged, word_table_slices

    slice_work = SLICE_WORK if slice_work is None else slice_work
    e, u = border_grid(view, side)
    if table is not None:
        tab = table
    else:
        if scan is None:
            scan = yield from staged("scan", grid_scan_slices(e, u, view.max_iter, slice_work))
        tab = yield from word_table_slices(scan, points, slice_work)
    hit = np.flatnonzero(tab["text"].values == text)
    row = None
    if hit.size:
        r = tab.isel(word=int(hit[0]))
        row = {k: r[k].item() for k in WORD_ROW_FIELDS}
    return {"grid": (e[2], u[2]), "words": int(tab.sizes["word"]), "row": row, "table": tab}


def point_details(e: float, u: float, max_iter: int, steps: int | None = None,
                  max_steps: int = 2000) -> dict:
    """point_details(e, u, max_iter, steps=None, max_steps=2000) -> dict

    What a tap on ``(e, u)`` shows: the word of the periodic sliding solution
    through (1, 0) (:func:`stairbounce.sliding_word`, ``None`` when it does
    not slide within ``max_iter`` steps) and ``"answer"``, the
    :class:`stairbounce.SlidingAnswer` saying whether Corollary 2.1 proves
    that it never slides, for a point that does not slide its
    motion (:func:`stairbounce.nonsliding.motion`, ``max_iter`` transient and kept
    steps: <k>, exponents) and last Poincare iterates (``"motion"``,
    ``"section"``; ``None`` otherwise), and the exact trajectory from (1, 0)
    over ``steps`` steps (default: one full period and two more steps, at
    least 4 and at most ``max_steps``; 12 when it does not slide) sampled for
    drawing (at most about 40 000 points), with its impacts, accumulation
    points and slides; ``"family"``: the word's family by its form
    (:func:`stairbounce.family_of`, ``None`` without a repeated block or a word).
    """
    e, u = check_e(e), check_u(u)
    answer = sliding_answer(e, u, max_iter=max_iter)
    w = answer.word
    mo, section = _point_motion(e, u, max_iter) if w is None else (None, None)
    if steps is None:
        steps = 12 if w is None else int(min(max_steps, max(4, w.period + 2)))
    traj = trajectory(e, u, 1.0, 0.0, steps)
    per_step = max(10, min(200, 40_000 // steps))
    t = np.linspace(0.0, traj.duration, per_step * steps + 1)
    t = np.union1d(t, [i.time for i in traj.impacts if i.time <= traj.duration])
    x, y = traj.position(t)
    return {
        "e": e,
        "u": u,
        "word": w,
        "answer": answer,
        "steps": steps,
        "path": (x, y),
        "impacts": (np.array([i.x for i in traj.impacts]), np.array([i.y for i in traj.impacts])),
        "accumulations": (
            np.array([a.x for a in traj.accumulations]),
            np.array([a.y for a in traj.accumulations]),
        ),
        "slides": [(s.x_start, s.x_end, s.y) for s in traj.slides],
        "motion": mo,
        "section": section,
        "family": None if w is None else family_of(w),
    }


# Points of the Poincare section sent to the page after a tap
_SECTION_POINTS = 2000


def _point_motion(e, u, max_iter):
    """:func:`stairbounce.nonsliding.motion` of a non-sliding point (``max_iter``
    transient and kept steps), and the last kept Poincare iterates ``(y, v)``."""
    from ..model import iterate
    from ..nonsliding import motion

    steps = max(2, max_iter)
    r = motion(e, u, steps=steps, transient=max_iter)
    if r["slides"]:
        return r, None
    ys, vs, _ = iterate(1.0, 0.0, e, u, max_iter + steps)
    keep = min(steps, _SECTION_POINTS)
    return r, (ys[-keep:], vs[-keep:])


def orbit_along_u(e: float, u_lo: float, u_hi: float, n: int = 300, transient: int = 2000,
                  keep: int = 200) -> xr.Dataset:
    """orbit_along_u(e, u_lo, u_hi, n=300, transient=2000, keep=200) -> xarray.Dataset

    The orbit diagram of Section 4 (Figs. 8, 9) at restitution ``e`` over ``n``
    pixel centres of ``[u_lo, u_hi]``: :func:`stairbounce.orbits.orbit_diagram`
    from the paper's ``(y0, v0) = (0.1, 0)``.
    """
    us = plane.pixel_centres(u_lo, u_hi, n)
    return orbits.orbit_diagram(e, us, y0=0.1, v0=0.0, transient=transient, keep=keep)
