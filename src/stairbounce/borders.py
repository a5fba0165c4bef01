"""``stairbounce.borders``: the old path of the border points, word tables and
bifurcations, now in the package :mod:`stairbounce.structure` (issue 36, item
9): :mod:`~stairbounce.structure.itinerary`, :mod:`~stairbounce.structure.words`,
:mod:`~stairbounce.structure.borders`, :mod:`~stairbounce.structure.bifurcations`
and :mod:`~stairbounce.structure.checks`.

Every name the module defined is re-exported here, the very object of its new
module, so ``from stairbounce.borders import X`` keeps working.  An assignment
through this module (``monkeypatch.setattr``) reaches nothing: patch the module
that looks the name up (docs/design.md, "Architecture and data flow").
"""

import warnings


from .structure.bifurcations import (  # noqa: F401
    _MAX_ROUNDS,
    _bifurcation_kernel,
    _long_run,
    _long_run_kernel,
    _run_text,
    _same_run,
    bifurcations,
)
from .structure.borders import (  # noqa: F401
    _CONVENTION,
    _OUT,
    _ROUND_LANES_MIN,
    _ROUND_UNIT_MIN,
    _SLIDING,
    _WORD,
    _WORD_BISECT,
    PAIR_TRIALS,
    _at,
    _bisect_pair,
    _bisect_sliding_pair,
    _border_kernel,
    _event_of,
    _finish_sliding,
    _first_difference,
    _grid_input,
    _pairs,
    _run_pairs,
    _scan_input,
    _shrink_secant,
    _slide_period,
    _slide_periods,
    _sliding_rounds,
    _table,
    _trial,
    _word_table_rows,
    _work_blocks,
    _write_point,
    _write_sliding_point,
    border_point_slices,
    border_points,
    grid_blocks,
    pair_work,
    staged,
    word_group_slices,
    word_table,
    word_table_slices,
)
from .structure.checks import (  # noqa: F401
    TONGUE_WINDOW,
    above_no_sliding_curve,
    side_agreement,
    tongue_distances,
)
from .structure.itinerary import (  # noqa: F401
    _BLOCK,
    _ITINERARY_BYTES,
    _ITINERARY_NAMES,
    CHATTER,
    EDGE,
    GRAZE,
    KINDS,
    _check_max_iter,
    _event_margin,
    _follows,
    _impact_time_at,
    _impacts_from_rest,
    _itinerary_args,
    _itinerary_block,
    _itinerary_blocks,
    _margin,
    _next_margin,
    itinerary,
)
from .structure.words import (  # noqa: F401
    NONE_WORD,
    _fill_impacts,
    _hash_rows,
    _rows_equal,
    _word_groups,
    _word_text,
    _words,
)

__all__ = ["itinerary", "border_points", "word_table", "bifurcations"]

warnings.warn("stairbounce.borders is deprecated since 0.5.0 and will be removed in 0.6.0: "
              "import from stairbounce.structure.borders (and .itinerary, .words, .bifurcations, .checks)"
              ", or use the flat stairbounce API",
              DeprecationWarning, stacklevel=2)
