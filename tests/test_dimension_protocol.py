"""One answer per window (issue 24): the API's default, the CLI's default and
the dimension study's shipped best estimate of the border's dimension in the
paper's Fig. 6 and Fig. 7 windows.

The CLI's default is the API's default, the uncertainty protocol (the same
call, the same number; issue 37 made them one); box counting of a 512 px
scan (``method="boxes"``) is a different protocol and says so (its scales in
pixels and in window units).
All three state intervals that cover the drift of the local slope across
their scales, and those intervals must overlap: the same set, one answer.
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
    uncertainty = sb.perimeter_dimension(e=e, u=u)     # the default method
    boxes = sb.perimeter_dimension(e=e, u=u, method="boxes")
    with pytest.raises(SystemExit) as exc:
        main(["dimension", "--e", f"{e[0]}:{e[1]}", "--u", f"{u[0]}:{u[1]}"])
    out = capsys.readouterr().out
    assert exc.value.code == 0
    # the CLI's default is the API's uncertainty protocol, number for number
    assert float(re.search(r"D = ([\d.]+)", out).group(1)) == pytest.approx(uncertainty.dimension, abs=5e-5)
    assert f"max_iter {uncertainty.max_iter}" in out
    # each states its scales and max_iter
    assert "of the window" in uncertainty.summary() and "max_iter 1000" in uncertainty.summary()
    assert "of the window" in boxes.summary() and "max_iter 1000" in boxes.summary()
    # the three intervals, each covering its drift, hold one answer
    for est in (uncertainty, boxes):
        assert overlap(est.interval, study["interval"]), (est.summary(), study)


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
