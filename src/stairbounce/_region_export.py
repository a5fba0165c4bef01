"""``stairbounce._region_export``: the old path of
:mod:`stairbounce.structure.export` (issue 36, item 9), whose every name is
re-exported here, the very object.  An assignment through this module reaches
nothing: patch :mod:`stairbounce.structure.export`.
"""

import warnings


from .structure.export import (  # noqa: F401
    _EPS,
    _MAX_ROUNDS,
    _S,
    _SAME,
    FACE_COLOUR,
    TOLERANCE,
    _Edge,
    Partition,
    _cells,
    _crossings,
    _deviation,
    _find_crossings,
    _loops,
    _meet,
    _on_segment,
    _orient,
    _polygons,
    _project,
    _reason,
    _same_curve,
    _segments,
    _signed_area,
    _ticks,
    _untangle,
    _untraced_reason,
    build,
    coverage,
    geojson,
    svg,
    untraced,
    write,
)

warnings.warn("stairbounce._region_export is deprecated since 0.5.0 and will be removed in 0.6.0: "
              "import from stairbounce.structure.export"
              ", or use the flat stairbounce API",
              DeprecationWarning, stacklevel=2)
