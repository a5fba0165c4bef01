"""The frozen baseline kernel of the speed ratios (benchmarks/baseline_kernel.py, issue 26)
answers as the production scan does: a yardstick that measures the same work."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from tests._benchmarks import import_benchmark
from stairbounce.plane import pixel_centres, scan_coords

_PATH = Path(__file__).resolve().parent.parent / "benchmarks" / "baseline_kernel.py"


@pytest.fixture(scope="module")
def baseline():
    return import_benchmark("baseline_kernel")


def test_frozen_header_and_no_stairbounce_import():
    # the baseline must not move when the package changes: it imports none of it
    text = _PATH.read_text()
    assert "FROZEN: never edit this file" in text
    imports = [ln for ln in text.splitlines() if ln.lstrip().startswith(("import ", "from "))]
    assert imports and not any("stairbounce" in ln for ln in imports)


@pytest.mark.parametrize("window, size, max_iter", [
    (((0.0, 1.0), (0.0, 1.5)), (50, 35), 1000),       # the paper's plane, coarse
    (((0.04, 0.065), (0.92, 0.945)), (40, 40), 1000),  # Fig. 5e, nothing prunable
    (((0.5, 0.99), (0.01, 0.3)), (30, 30), 300),       # many impacts per step
])
def test_baseline_agrees_with_the_production_scan(baseline, window, size, max_iter):
    (e, u), (n_e, n_u) = window, size
    es, us = pixel_centres(*e, n_e), pixel_centres(*u, n_u)
    ds = scan_coords(es, us, max_iter=max_iter)
    out = baseline.baseline_scan(es, us, max_iter)
    for k in ("status", "word_length", "period", "jumps", "impacts"):
        assert out[k].dtype == ds[k].dtype, k
        assert np.array_equal(out[k], ds[k].values), k
    # not a trivial window: periodic sliding solutions are found, and pixels without
    assert 0 < (out["status"] == 0).sum() < out["status"].size


def test_baseline_transient_from_another_start(baseline):
    es, us = pixel_centres(0.0, 1.0, 30), pixel_centres(0.0, 1.5, 20)
    ds = scan_coords(es, us, max_iter=300, y0=2.5, v0=-0.7)
    out = baseline.baseline_scan(es, us, 300, 2.5, -0.7)
    for k in ("status", "word_length"):
        assert np.array_equal(out[k], ds[k].values), k
