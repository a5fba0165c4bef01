"""The dimension of a border, by three estimators that share no method.

The paper measures "the fractal dimension of the perimeter" of the region of
parameters with periodic sliding solutions by box counting on its pictures and
reports 1.324 for the window ``[0, 0.333] x [0.4, 0.733]`` (Fig. 6) and 1.403
for ``[0.155, 0.2138] x [0.6, 0.658]`` (Fig. 7), with a correlation
coefficient above 0.99.  One module per idea, so that a reader finds an
estimator where its name says:

``borders``
    the border pixels of a region (:func:`boundary`) or between the labels of
    an image (:func:`label_boundary`);
``boxes``
    box counting of a picture (:func:`box_counts`, :func:`box_dimension`);
``uncertainty``
    the uncertainty exponent of random points (:func:`uncertainty_dimension`;
    no picture);
``slicing``
    the crossings of the border along random lines, refined to 1e-10 of the
    window (:func:`slicing_dimension`; Marstrand: a line meets a border of
    dimension D in a set of dimension D - 1);
``fit``
    the slope fit they share (:func:`slope_fit`, :func:`linear_region`) and the
    drift of the local slope across the fitted scales;
``result``
    what every estimate states: its scales, ``max_iter``, the local dimension
    against scale and an interval covering the drift (systematic) beside the
    statistical one;
``convergence``
    whether ``max_iter`` moves an estimate, scale by scale, against the same
    measurement at a larger one (:func:`max_iter_check`);
``classifier``
    the model's classification of ``(e, u)`` points (:func:`sliding_classifier`);
``perimeter``
    a window of the model's plane measured by any of the three
    (:func:`perimeter_dimension`);
``study``
    the dimension study's shipped result (:func:`border_dimension_estimates`).

``stairbounce.fractal`` is the old name of this package, kept as an alias that
warns (DeprecationWarning) and will be removed in 0.6.0.
"""

from .borders import boundary, label_boundary
from .boxes import BoxDimension, box_counts, box_dimension, box_dimension_from_counts
from .classifier import SlidingClassifier, sliding_classifier
from .convergence import MaxIterCheck, max_iter_check
from .fit import SlopeFit, linear_region, slope_fit
from .perimeter import PerimeterDimension, perimeter_dimension
from .result import disagree
from .slicing import SlicingDimension, slicing_dimension
from .study import border_dimension_estimates
from .uncertainty import (
    DEFAULT_EPS,
    UncertainFraction,
    UncertaintyDimension,
    random_points,
    uncertain_fraction,
    uncertainty_dimension,
    uncertainty_dimension_from_counts,
)

__all__ = [
    "BoxDimension",
    "MaxIterCheck",
    "DEFAULT_EPS",
    "PerimeterDimension",
    "SlicingDimension",
    "SlidingClassifier",
    "SlopeFit",
    "UncertainFraction",
    "UncertaintyDimension",
    "border_dimension_estimates",
    "boundary",
    "box_counts",
    "box_dimension",
    "box_dimension_from_counts",
    "disagree",
    "label_boundary",
    "linear_region",
    "max_iter_check",
    "perimeter_dimension",
    "random_points",
    "sliding_classifier",
    "slicing_dimension",
    "slope_fit",
    "uncertain_fraction",
    "uncertainty_dimension",
    "uncertainty_dimension_from_counts",
]
