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

The code lives in :mod:`~stairbounce.explorer.window` (the view, its limits
and its URL query), :mod:`~stairbounce.explorer.render` (the scan of a view,
whole or in slices), :mod:`~stairbounce.explorer.colors` (the colours of the
map), :mod:`~stairbounce.explorer.overlays` (what is drawn over it) and
:mod:`~stairbounce.explorer.point` (what a tap shows); this module gathers
their names.
"""

from __future__ import annotations

from .window import (  # noqa: F401
    MOTION_COLOR_VARS,
    FIELDS,
    COLOR_VARS,
    NO_SLIDING_LABEL,
    OVERLAYS,
    DEFAULT_OVERLAYS,
    BORDER_SIDE,
    TRACE_SIDE,
    PIXEL_BUDGET,
    WORK_BUDGET,
    MAX_ITER_LIMIT,
    U_LIMIT,
    MIN_SIDE,
    _MIN_ULPS_PER_PIXEL,
    SLICE_WORK,
    COARSE,
    PREVIEW_WORK,
    _UNBOUNDED,
    View,
    DEFAULT_VIEW,
    Cancelled,
    _fmt,
    format_window,
    _text,
    _number,
    parse_window,
    parse_size,
    parse_max_iter,
    parse_color,
    parse_overlays,
    parse_point,
    parse_query,
    view_query,
    view_url_query,
    _check_resolution,
    check_view,
    window_digits,
    format_number,
    tidy,
)
from .colors import (  # noqa: F401
    NO_SLIDING_COLOR,
    has_color,
    NOT_COMPUTED_COLOR,
    color_key,
    _rgba32,
    _NBINS,
    SLIDES_COLOR,
    _MOTION_RANGE,
    _motion_key,
    classes,
    shade,
    ColorKey,
)
from .render import (  # noqa: F401
    Partial,
    render_slices,
    _bands,
    grid_scan_slices,
    compute_view,
    preview_rgba,
    _with_motion,
)
from .overlays import (  # noqa: F401
    overlay_curves,
    border_grid,
    view_border_points,
    border_point_slices,
    border_overlay,
    trace_window,
    trace_slices,
    _word_at,
    OUTSIDE_WORD,
    _arc_sides,
    _on_arcs,
    ARC_SIDE_WORK,
    traced_overlay,
    traced_overlay_slices,
    WORD_ROW_FIELDS,
    word_row,
    word_row_slices,
)
from .point import (  # noqa: F401
    pixel_of,
    point_details,
    _SECTION_POINTS,
    _point_motion,
    orbit_along_u,
)

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

