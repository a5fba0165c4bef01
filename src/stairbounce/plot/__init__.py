"""matplotlib renderers: they take arrays, datasets and trajectories and draw
them; they never compute dynamics.  Kept out of the core's import path
(``import stairbounce`` loads none of this; ``sb.plot`` loads it on first use).

Each ``plot_*`` takes the object a computing function returns and needs no
other argument: the datasets carry their window, ``max_iter`` and the meaning
of each variable in their attributes.

=============================  ==============================================
computed by                    drawn by
=============================  ==============================================
``sb.scan``                    :func:`plot_scan` (Figs. 3-5)
``sb.orbit_diagram``           :func:`plot_orbit_diagram` (Figs. 8, 9)
``sb.bifurcations``            :func:`plot_bifurcations` (marks on them)
``sb.cascade``                 :func:`plot_cascade_members` (marks on them),
                               :func:`plot_cascade_law`
``sb.perimeter_dimension``     :func:`plot_box_dimension` (Figs. 6, 7),
                               :func:`plot_box_counts`, :func:`plot_border`
``sb.uncertainty_dimension``   :func:`plot_uncertainty`
``sb.slicing_dimension``       :func:`plot_local_dimension` (any estimate, scale by scale)
``sb.trajectory``              :func:`plot_trajectory` (Fig. 1),
                               :func:`animate_trajectory`
``sb.iterate``                 :func:`plot_poincare_section`
``sb.motion_scan``             :func:`plot_motion`, :func:`plot_motion_cut`
``sb.border_points``           :func:`plot_borders` (over a scan)
(the tongues, Thm. 3.1)        :func:`plot_tongues` (Fig. 2)
=============================  ==============================================
"""

from .._compat import register_alias as _register_alias
from .borders import plot_borders
from .cascades import plot_cascade_law, plot_cascade_members
from .fractal import plot_border, plot_box_counts, plot_box_dimension, plot_local_dimension, plot_uncertainty
from .motion import plot_motion, plot_motion_cut
from .orbits import plot_bifurcations, plot_orbit_diagram
from .plane import plot_scan
from .tongues import plot_tongues
from .trajectory import animate_trajectory, plot_poincare_section, plot_trajectory

# the renderer module was stairbounce.plot.scan; the name now calls plot_scan
scan = _register_alias(__name__ + ".scan", __name__ + ".plane", plot_scan, "scan")

__all__ = [
    "animate_trajectory",
    "plot_bifurcations",
    "plot_border",
    "plot_borders",
    "plot_cascade_law",
    "plot_cascade_members",
    "plot_box_counts",
    "plot_box_dimension",
    "plot_local_dimension",
    "plot_motion",
    "plot_motion_cut",
    "plot_orbit_diagram",
    "plot_poincare_section",
    "plot_scan",
    "plot_tongues",
    "plot_trajectory",
    "plot_uncertainty",
]
