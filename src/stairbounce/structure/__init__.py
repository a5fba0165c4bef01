"""The exact structure of the (e, u) plane: borders, regions and their certification.

One module per concept (issue 36, item 9; docs/design.md lists what each holds):
``itinerary`` (itineraries, margins, the event kernels), ``words`` (the words
of points), ``borders`` (border points and word tables), ``bifurcations``,
``continuation`` (arcs followed), ``regions`` (word_region, window_regions),
``trace`` (trace_border), ``graph`` (border_graph), ``export`` (GeoJSON, SVG),
``checks`` (against the paper's theorems), and the certifier: ``certificate``,
``_kernel``, ``certify``, ``verify``, ``reference``, ``labels``, ``tubes``.
``stairbounce.borders``, ``stairbounce.regions`` and
``stairbounce._region_export`` are the old paths, kept as re-exports that
warn (DeprecationWarning) and will be removed in 0.6.0.

Importing the package loads the certifier's entry points only; the other
modules load when imported (``stairbounce`` itself imports them all).
"""

from .certificate import Certificate
from .certify import CertifiedAtlas, certify, certify_box

__all__ = ["Certificate", "CertifiedAtlas", "certify", "certify_box"]
