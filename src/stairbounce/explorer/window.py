"""One view of the explorer and its text: the window, the pixel size, the
iteration cap, the colouring and the overlays (:class:`View`), the limits of a
render, and the view <-> the page's URL query (:func:`parse_query`,
:func:`view_query`), with the window's numbers as text (:func:`format_window`,
:func:`window_digits`, :func:`tidy`).

Pure Python, no Panel or Bokeh; :mod:`stairbounce.explorer.view` re-exports
everything here.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from urllib.parse import urlencode

import numpy as np

from .._validate import size_text
from ..model import check_e, check_u
from ..plot.plane import _LEAST

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
    wh = size_text(text)
    if wh is None:
        raise ValueError(f"size must be WIDTHxHEIGHT in pixels, e.g. 600x600, got {text!r}")
    w, h = wh
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
