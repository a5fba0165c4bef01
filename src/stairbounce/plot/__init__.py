"""matplotlib renderers: they take arrays, datasets and trajectories and draw
them; they never compute dynamics.  Kept out of the core's import path."""

from .fractal import plot_border, plot_box_counts, plot_box_dimension, plot_uncertainty
from .orbits import plot_orbit_diagram
from .plane import plot_scan
from .tongues import plot_tongues
from .trajectory import animate_trajectory, plot_poincare_section, plot_trajectory

__all__ = [
    "animate_trajectory",
    "plot_border",
    "plot_box_counts",
    "plot_box_dimension",
    "plot_orbit_diagram",
    "plot_poincare_section",
    "plot_scan",
    "plot_tongues",
    "plot_trajectory",
    "plot_uncertainty",
]
