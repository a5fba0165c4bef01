"""stairbounce: a ball bouncing down a staircase, exactly and fast.

The model of Campos, Romero-Valles and Torres, "A fractal structure in a
bouncing ball model" (and its reference [1], Chaos, Solitons & Fractals 32
(2007) 415-426), in normalised units (step height = step length = g = 1).
"""

from importlib.metadata import PackageNotFoundError, version

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
from .motion import k_mean_bound, motion_scan, one_impact_family
from .orbits import orbit_density, orbit_diagram
from .symbolic import Word, parse_word, sliding_word
from .trajectory import Trajectory, trajectory
from .units import normalized_speed, physical_speed, time_scale

try:
    __version__ = version("stairbounce")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0+unknown"

__all__ = [
    "SLIDING",
    "Trajectory",
    "Word",
    "__version__",
    "impact_number",
    "impact_times",
    "iterate",
    "k_mean_bound",
    "motion_scan",
    "no_sliding_bound",
    "normalized_speed",
    "one_impact_family",
    "orbit_density",
    "orbit_diagram",
    "parse_word",
    "physical_speed",
    "poincare_map",
    "sliding_word",
    "slides",
    "time_scale",
    "tongue",
    "trajectory",
]
