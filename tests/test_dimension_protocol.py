"""One answer per window (issues 24 and 37): the API's default, the CLI's
default and the dimension study's shipped best estimate of the border's
dimension in the paper's Fig. 6 and Fig. 7 windows.

The CLI's default is the API's default, slicing at fine scales (the same
call, the same number; issue 37 made it the default for its smallest bias on
sets of known dimension, benchmarks/dimension_bias.py); box counting of a
2048 px scan (``method="boxes"``) is a different protocol and says so (its
scales in pixels and in window units).  All state intervals that cover the
drift of the local slope across their scales and, widened by the estimator's
measured bias (``bias_interval``), those intervals must overlap: the same
set, one answer.  The CLI also prints the study's number, labelled as such,
with the command that recomputes it.
"""

from __future__ import annotations

import re

import pytest

import stairbounce as sb
from stairbounce.cli import main
from stairbounce.figures import DIMENSION_WINDOWS, load_border_dimension


def overlap(a, b):
    return a[0] <= b[1] and b[0] <= a[1]


@pytest.mark.slow
@pytest.mark.parametrize("name", ["fig6", "fig7"])
def test_api_cli_and_study_give_one_answer(name, capsys):
    (e, u), _ = DIMENSION_WINDOWS[name]
    study = load_border_dimension()[name]
    # the defaults but 16 lines (a test's budget: the default 128 only narrow the interval)
    slicing = sb.perimeter_dimension(e=e, u=u, n_lines=16)     # the default method
    boxes = sb.perimeter_dimension(e=e, u=u, method="boxes")
    with pytest.raises(SystemExit) as exc:
        main(["dimension", "--e", f"{e[0]}:{e[1]}", "--u", f"{u[0]}:{u[1]}", "--lines", "16"])
    out = capsys.readouterr().out
    assert exc.value.code == 0
    # the CLI's default is the API's slicing protocol, number for number
    assert isinstance(slicing, sb.SlicingDimension)
    assert float(re.search(r"D = ([\d.]+)", out).group(1)) == pytest.approx(slicing.dimension, abs=5e-5)
    assert f"max_iter {slicing.max_iter}" in out and slicing.max_iter == 4000
    # fine scales: the default fit range 1e-8..1e-4 of the window
    assert slicing.scales[0] < 2e-8 and slicing.scales[1] < 2e-4
    # the printed interval widened for the bias, what it leaves out, and the study's number
    lo, hi = slicing.bias_interval
    assert f"with the estimator's bias: [{lo:.4f}, {hi:.4f}]" in out
    assert "left out: the effect of max_iter" in out
    assert f"the dimension study's number for this window ({name}, shipped" in out
    assert "recomputed by: python benchmarks/dimension_study.py" in out
    # each states its scales and max_iter
    assert "of the window" in slicing.summary() and "max_iter 4000" in slicing.summary()
    assert "of the window" in boxes.summary() and "max_iter 1000" in boxes.summary()
    assert boxes.fit_range == (4, 64) and boxes.resolution == 2048
    # the intervals, each covering its drift and its estimator's bias, hold one answer
    for est in (slicing, boxes):
        assert overlap(est.bias_interval, study["interval"]), (est.summary(), study)


def test_disagree_warns_only_when_the_intervals_do_not_overlap():
    from types import SimpleNamespace

    a = SimpleNamespace(dimension=1.50, interval=(1.48, 1.52))
    b = SimpleNamespace(dimension=1.60, interval=(1.55, 1.65))
    c = SimpleNamespace(dimension=1.53, interval=(1.51, 1.56))
    assert sb.dimension.disagree(a, b).startswith("warning: two methods disagree")
    assert sb.dimension.disagree(a, c) == "" and sb.dimension.disagree(b, c) == ""


def test_non_square_pixels_warn():
    import warnings

    import numpy as np

    ds = sb.scan(e=(0.0, 1.0, 100), u=(0.0, 1.5, 70), max_iter=100)  # pixels 0.01 x 0.0214
    region = ds.status.transpose("u", "e") == 0
    border = region.copy(data=sb.boundary(region.values))
    with pytest.warns(RuntimeWarning, match="non-square pixels"):
        sb.box_dimension(border)  # a DataArray gives its own pixel size
    with pytest.warns(RuntimeWarning, match="non-square pixels"):
        sb.box_dimension(border.values, pixel_size=(0.01, 0.0214))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sb.box_dimension(border.values, pixel_size=(0.01, 0.0101))  # square to 1%: silent
        sb.box_dimension(border.values)  # a plain array says nothing of its pixels
    with pytest.raises(ValueError, match="pixel_size"):
        sb.box_dimension(border.values, pixel_size=(0.01, -1))
    assert np.asarray(border).shape == (70, 100)
