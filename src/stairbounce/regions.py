"""``stairbounce.regions``: the old path of the traced regions, now in the
package :mod:`stairbounce.structure` (issue 36, item 9):
:mod:`~stairbounce.structure.itinerary` (the margins),
:mod:`~stairbounce.structure.continuation`, :mod:`~stairbounce.structure.regions`,
:mod:`~stairbounce.structure.trace`, :mod:`~stairbounce.structure.graph`,
:mod:`~stairbounce.structure.export` and :mod:`~stairbounce.structure.checks`.

Every name the module defined is re-exported here, the very object of its new
module, so ``from stairbounce.regions import X`` keeps working.  An assignment
through this module (``monkeypatch.setattr``) reaches nothing: patch the module
that looks the name up (docs/design.md, "Architecture and data flow").
"""

import warnings


from .structure.checks import band_similarity  # noqa: F401
from .structure.continuation import (  # noqa: F401
    _EPS,
    _MAX_TURN,
    _NEWTON,
    _ROUND_ULPS,
    _Arc,
    _Margins,
    _corner,
    _corner_on_arc,
    _correct,
    _follow,
    _into_window,
    _locate_corner,
    _noise,
    _outgoing,
    _solve2,
    _tangent,
    _ulps,
    _unit,
    _walk,
)
from .structure.export import (  # noqa: F401
    _export_options,
    regions_geojson,
    regions_svg,
    write_regions,
)
from .structure.graph import (  # noqa: F401
    _GraphMargins,
    BorderGraph,
    _corners_on_arcs,
    _curves,
    _on_arc_curve,
    _region_list,
    _split_arc,
    border_graph,
)
from .structure.itinerary import _hash_itinerary, _itinerary_of, _margins, _words_grid  # noqa: F401
from .structure.regions import (  # noqa: F401
    _CORNER_DIRECTIONS,
    _CORNER_MIN_AREA,
    _CORNER_RADII,
    _CORNER_ROUNDS,
    _CORNER_SEEDS,
    _DEFAULT_RESOLUTION,
    _E_TOP,
    _GAUSS,
    _MAX_STEPS,
    _U_BOTTOM,
    BorderArc,
    Corner,
    Region,
    RegionComponent,
    _arc_area,
    _as_word,
    _below_rounding,
    _bisect_into,
    _check_centres,
    _check_run,
    _check_steps,
    _check_window,
    _chord_position,
    _chord_positions,
    _closed,
    _corner_rings,
    _corner_seeds,
    _crossing,
    _curve_area,
    _fill,
    _grid,
    _hermite_area,
    _image_window,
    _inside_polygon,
    _label_grid,
    _label_grid_slices,
    _new_curve,
    _on_curves,
    _point_seeds,
    _position_rounding,
    _seed_grid,
    _to_arcs,
    _trace_word,
    _words_points,
    iter_window_regions,
    itinerary_of_word,
    traced_columns,
    window_regions,
    word_region,
)
from .structure.trace import (  # noqa: F401
    _event_between,
    _outcome,
    _prescribed_step,
    _same,
    _side_itinerary,
    _word_text,
    trace_border,
)

__all__ = ["BorderArc", "Corner", "Region", "RegionComponent", "BorderGraph", "trace_border",
           "word_region", "window_regions", "border_graph", "regions_geojson", "regions_svg",
           "write_regions", "band_similarity"]

warnings.warn("stairbounce.regions is deprecated since 0.5.0 and will be removed in 0.6.0: "
              "import from stairbounce.structure.regions (and .continuation, .trace, .graph, .export, .checks)"
              ", or use the flat stairbounce API",
              DeprecationWarning, stacklevel=2)
