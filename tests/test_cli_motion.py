"""`stairbounce motion` and `stairbounce scan --field k_mean|lyap1|...` (issue 13)."""

from __future__ import annotations

import pytest
from PIL import Image

from stairbounce.nonsliding import motion

from .test_cli_model import run


def test_motion_prints_k_and_exponents_of_the_library(capsys):
    code, out, _ = run(["motion", "--e", "0.5", "--u", "0.8", "--steps", "400", "--transient", "300"], capsys)
    r = motion(0.5, 0.8, steps=400, transient=300)
    assert code == 0
    assert f"<k>:         {r['k_mean']:.6g} impacts per step" in out
    assert f"lambda_1:    {r['lyap1']:+.3e}" in out
    assert f"lambda_2:    {r['lyap2']:+.6e}" in out


def test_motion_says_when_the_orbit_slides(capsys):
    code, out, _ = run(["motion", "--e", "0.1", "--u", "0.2"], capsys)
    assert code == 0 and "slides on step 1" in out


@pytest.mark.parametrize("args, word", [
    (["--e", "1.5", "--u", "0.5"], "e (restitution coefficient) must be in [0, 1)"),
    (["--e", "0.5", "--u", "-1"], "u (horizontal speed) must be > 0"),
    (["--e", "0.5", "--u", "1", "--steps", "1"], "steps must be an integer >= 2"),
    (["--e", "0.5", "--u", "1", "--transient", "-3"], "transient must be an integer >= 0"),
])
def test_motion_bad_input_is_one_line_and_status_2(args, word, capsys):
    code, out, err = run(["motion", *args], capsys)
    assert code == 2 and word in err and err.count("\n") == 1


@pytest.mark.parametrize("field", ["k_mean", "lyap1", "speed_spread"])
def test_scan_field_accepts_the_motion_fields(field, tmp_path, capsys):
    png = tmp_path / "m.png"
    code, out, _ = run(["scan", "--field", field, "--size", "30x20", "--max-iter", "100",
                        "--png", str(png), "--out", str(tmp_path / "m.nc")], capsys)
    assert code == 0 and "does not slide at" in out
    assert Image.open(png).size[0] > 100 and (tmp_path / "m.nc").exists()


def test_scan_motion_field_refuses_tiles(tmp_path, capsys):
    code, _, err = run(["scan", "--field", "k_mean", "--tile", "8", "--out", str(tmp_path / "a.zarr")], capsys)
    assert code == 2 and "not available for tiled scans" in err
