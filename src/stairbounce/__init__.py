"""stairbounce: a ball bouncing down a staircase, exactly and fast.

The model of Campos, Romero-Valles and Torres, "A fractal structure in a
bouncing ball model" (and its reference [1], Chaos, Solitons & Fractals 32
(2007) 415-426), in normalised units (step height = step length = g = 1).

Every public function is a name of this package (``sb.scan``,
``sb.box_dimension``, ...; the list is ``__all__`` and the API reference in
the documentation).  Three submodules are loaded only when first used,
because they bring heavy dependencies: ``sb.plot`` (matplotlib renderers),
``sb.figures`` (the paper's figures as recipes) and ``sb.explorer`` (the
Panel app, the ``web`` extra).
"""

from importlib import import_module as _import_module

from .atlas import downsample, scan_to_zarr, tiles_done
from .dimension import (
    BoxDimension,
    PerimeterDimension,
    SlicingDimension,
    SlopeFit,
    UncertainFraction,
    UncertaintyDimension,
    border_dimension_estimates,
    boundary,
    box_counts,
    box_dimension,
    box_dimension_from_counts,
    label_boundary,
    linear_region,
    perimeter_dimension,
    random_points,
    slicing_dimension,
    sliding_classifier,
    slope_fit,
    uncertain_fraction,
    uncertainty_dimension,
    uncertainty_dimension_from_counts,
)
from .atlas_boxes import store_box_counts, store_box_dimension, store_info
from .model import (
    SLIDING,
    impact_number,
    impact_times,
    iterate,
    no_sliding_bound,
    poincare_map,
    slides,
    tongue,
)
from .nonsliding import (
    Motion,
    k_mean_bound,
    lyapunov_exponents,
    motion,
    motion_coords,
    motion_scan,
    one_impact_family,
    one_impact_state,
    speed_spread,
    step_jacobian,
)
from .orbits import orbit_density, orbit_diagram
from .plane import (
    estimate_bytes,
    estimate_points_bytes,
    load,
    no_sliding_curve,
    pixel_centres,
    prunable,
    save,
    scan_coords,
    scan_points,
    tongue_mask,
)
from .plane import scan as _scan_function
from .cascades import (Cascade, CascadeLaw, FareyTest, cascade, cascade_law, cascades, family_of, farey_test,
                       member_count, organising_centres)
from .structure.bifurcations import bifurcations
from .structure.borders import border_points, word_table
from .structure.checks import band_similarity
from .structure.export import regions_geojson, regions_svg, write_regions
from .structure.graph import BorderGraph, border_graph
from .structure.itinerary import itinerary
from .structure.regions import BorderArc, Corner, Region, RegionComponent, window_regions, word_region
from .structure.trace import trace_border
from ._progress import progress_bar
from .structure import Certificate, CertifiedAtlas, certify, certify_box
from .structure.certify_store import CertifiedStore, certify_to_zarr
from .structure.labels import prove_labels
from .structure.trapping import TrappingRegion, trapping_region
from .structure.tubes import BorderTube, border_tube
from .structure.verdict import Verdict, verify
from .symbolic import SlidingAnswer, Word, parse_word, sliding_answer, sliding_word
from .trajectory import Accumulation, Flight, Impact, Slide, Trajectory, trajectory
from .units import Speed, SpeedWindow, Speeds, Staircase, normalized_speed, physical_speed, time_scale
from ._compat import register_alias as _register_alias
from ._version import __version__


# ``sb.scan`` is the function; it doubles as the old module ``stairbounce.scan``
# (now ``stairbounce.plane``) so that old imports keep working, with a warning.
scan = _register_alias(__name__ + ".scan", __name__ + ".plane", _scan_function, "scan")

__all__ = [
    "BorderArc",
    "BorderGraph",
    "Corner",
    "Region",
    "RegionComponent",
    "band_similarity",
    "border_graph",
    "regions_geojson",
    "regions_svg",
    "trace_border",
    "window_regions",
    "word_region",
    "write_regions",
    "Accumulation",
    "Certificate",
    "CertifiedAtlas",
    "certify",
    "certify_box",
    "certify_to_zarr",
    "CertifiedStore",
    "BoxDimension",
    "Flight",
    "Impact",
    "Motion",
    "PerimeterDimension",
    "SLIDING",
    "SlicingDimension",
    "Slide",
    "SlidingAnswer",
    "SlopeFit",
    "Speed",
    "SpeedWindow",
    "Speeds",
    "Staircase",
    "Trajectory",
    "UncertainFraction",
    "UncertaintyDimension",
    "Word",
    "__version__",
    "bifurcations",
    "border_dimension_estimates",
    "border_points",
    "boundary",
    "box_counts",
    "box_dimension",
    "box_dimension_from_counts",
    "downsample",
    "estimate_bytes",
    "estimate_points_bytes",
    "impact_number",
    "impact_times",
    "iterate",
    "itinerary",
    "k_mean_bound",
    "label_boundary",
    "linear_region",
    "load",
    "lyapunov_exponents",
    "motion",
    "motion_coords",
    "motion_scan",
    "no_sliding_bound",
    "no_sliding_curve",
    "normalized_speed",
    "one_impact_family",
    "one_impact_state",
    "orbit_density",
    "orbit_diagram",
    "parse_word",
    "perimeter_dimension",
    "physical_speed",
    "pixel_centres",
    "poincare_map",
    "progress_bar",
    "prunable",
    "random_points",
    "save",
    "scan",
    "scan_coords",
    "scan_points",
    "scan_to_zarr",
    "slicing_dimension",
    "slides",
    "sliding_answer",
    "sliding_classifier",
    "sliding_word",
    "slope_fit",
    "speed_spread",
    "step_jacobian",
    "store_box_counts",
    "store_box_dimension",
    "store_info",
    "tiles_done",
    "time_scale",
    "tongue",
    "tongue_mask",
    "trajectory",
    "uncertain_fraction",
    "uncertainty_dimension",
    "uncertainty_dimension_from_counts",
    "word_table",
    "Cascade",
    "CascadeLaw",
    "cascade",
    "cascade_law",
    "cascades",
    "family_of",
    "FareyTest",
    "farey_test",
    "member_count",
    "organising_centres",
    "prove_labels",
    "BorderTube",
    "border_tube",
    "TrappingRegion",
    "trapping_region",
    "Verdict",
    "verify",
]

# heavy submodules, imported on first use (PEP 562)
_LAZY_SUBMODULES = ("plot", "figures", "explorer", "cli")
# the old paths of moved modules, imported (with their DeprecationWarning) only
# when asked for: stairbounce.fractal (now stairbounce.dimension) and
# stairbounce.borders, regions, _region_export (now stairbounce.structure's)
_DEPRECATED_SUBMODULES = ("fractal", "borders", "regions", "_region_export")


def __getattr__(name):
    if name in _LAZY_SUBMODULES or name in _DEPRECATED_SUBMODULES:
        return _import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY_SUBMODULES))
