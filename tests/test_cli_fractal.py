"""``stairbounce dimension``: output, pictures, and one-line errors with exit status 2."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from stairbounce.dimension import boundary, box_dimension, perimeter_dimension

from ._cli import run_cli
from ._stores import StopAfter, stop_after

FIG7 = ["--e", "0.155:0.2138", "--u", "0.6:0.658"]


def run(argv, capsys):
    """``stairbounce dimension ARGV`` in this process."""
    return run_cli(["dimension", *argv], capsys)


def number(pattern, text):
    return float(re.search(pattern, text).group(1))


def write_picture(path, black):
    """A black-on-white picture: ``black`` True is drawn black."""
    Image.fromarray(np.where(black, 0, 255).astype(np.uint8)).save(path)


def disk(n, radius=0.35):
    y, x = np.mgrid[:n, :n] + 0.5
    return (x - n / 2) ** 2 + (y - n / 2) ** 2 <= (radius * n) ** 2


def test_scan_prints_the_api_result(capsys):
    code, out, err = run([*FIG7, "--method", "boxes", "--resolution", "128", "--max-iter", "300", "--fit-range", "1:32"], capsys)
    assert code == 0, err
    ref = perimeter_dimension(e=(0.155, 0.2138), u=(0.6, 0.658), method="boxes", resolution=128, max_iter=300, fit_range=(1, 32))
    assert number(r"D = ([\d.]+)", out) == pytest.approx(ref.dimension, abs=5e-5)
    lo, hi = re.search(r"95% CI = \[([\d.]+), ([\d.]+)\]", out).groups()
    assert (float(lo), float(hi)) == pytest.approx(ref.ci, abs=5e-5)
    assert number(r"r = ([\d.]+)", out) == pytest.approx(ref.r, abs=5e-6)
    assert "boxes of 1..32 px" in out and "128 x 128 px" in out


def test_png_draws_border_and_loglog_plot(tmp_path, capsys):
    png = tmp_path / "fig7.png"
    code, out, err = run([*FIG7, "--method", "boxes", "--resolution", "96", "--max-iter", "200", "--png", str(png),
                          "--proven-depth", "0"], capsys)
    assert code == 0, err
    with Image.open(png) as im:
        assert im.format == "PNG" and im.width > im.height > 200
    assert not list(tmp_path.glob(".*part*"))  # written atomically, nothing left behind


def test_image_measures_the_border_of_the_black_region(tmp_path, capsys):
    path = tmp_path / "disk.png"
    black = disk(512)
    write_picture(path, black)
    code, out, err = run(["--image", str(path)], capsys)
    assert code == 0, err
    ref = box_dimension(boundary(black))
    assert number(r"D = ([\d.]+)", out) == pytest.approx(ref.dimension, abs=5e-5)
    assert abs(ref.dimension - 1.0) < 0.06  # a circle
    assert "border of the black region, 512 x 512 px" in out
    # the white region: the pixels just outside the circle
    code, out, _ = run(["--image", str(path), "--region", "white"], capsys)
    white = box_dimension(boundary(~black))
    assert code == 0 and number(r"D = ([\d.]+)", out) == pytest.approx(white.dimension, abs=5e-5)
    assert white.dimension != ref.dimension
    # --pixels measures the black pixels themselves: a filled disk is an area
    code, out, _ = run(["--image", str(path), "--pixels"], capsys)
    area = box_dimension(black)
    assert code == 0 and number(r"D = ([\d.]+)", out) == pytest.approx(area.dimension, abs=5e-5)
    assert abs(area.dimension - 2.0) < 0.1


def test_image_threshold_is_mid_grey(tmp_path, capsys):
    black = disk(256)
    grey = np.where(black, 127, 128).astype(np.uint8)  # just either side of mid grey
    Image.fromarray(grey).save(tmp_path / "grey.png")
    write_picture(tmp_path / "bw.png", black)
    code1, out1, _ = run(["--image", str(tmp_path / "grey.png")], capsys)
    code2, out2, _ = run(["--image", str(tmp_path / "bw.png")], capsys)
    assert code1 == code2 == 0
    assert out1.split("\n", 1)[1] == out2.split("\n", 1)[1]


@pytest.mark.parametrize(
    "picture, message",
    [
        (np.zeros((64, 64), bool), "no black pixel"),
        (np.ones((64, 64), bool), "has no border"),
        (np.eye(3, dtype=bool), "fewer than 3 usable box sizes"),
    ],
    ids=["all white", "all black", "too small"],
)
def test_bad_pictures_exit_2_with_one_line(tmp_path, capsys, picture, message):
    path = tmp_path / "p.png"
    write_picture(path, picture)
    code, out, err = run(["--image", str(path)], capsys)
    assert code == 2
    assert err.startswith("stairbounce: error: ") and message in err
    assert err.count("\n") == 1


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--image", "{tmp}/missing.png"], "no such file"),
        (["--image", "{tmp}/text.png"], "cannot read"),
        (["--method", "boxes", "--e", "0.5:0.6", "--u", "1.0:1.2", "--resolution", "16", "--max-iter", "20"], "region is empty"),
        (["--e", "0.3:0.2"], "MIN < MAX"),
        (["--method", "boxes", "--resolution", "4"], "--resolution"),
        (["--method", "boxes", "--fit-range", "0:8"], "--fit-range"),
        (["--method", "boxes", "--fit-range", "64:128", *FIG7, "--resolution", "64", "--max-iter", "50"], "fit_range"),
        (["--which", "both"], "--which"),
        (["--connectivity", "6"], "--connectivity"),
        (["--region", "red", "--image", "x.png"], "--region"),
        (["--png", "{tmp}/out.jpg"], "--png"),
    ],
)
def test_bad_input_exits_2_with_one_line(tmp_path, capsys, argv, message):
    (tmp_path / "text.png").write_text("not a picture")
    argv = [a.format(tmp=tmp_path) for a in argv]
    code, out, err = run(argv, capsys)
    assert code == 2, out
    assert err.startswith("stairbounce: error: ") and message in err
    assert err.count("\n") == 1


def test_console_script(tmp_path):
    path = tmp_path / "square.png"
    black = np.zeros((128, 128), bool)
    black[20:100, 30:90] = True
    write_picture(path, black)
    script = Path(sys.executable).with_name("stairbounce")
    proc = subprocess.run(
        [str(script), "dimension", "--image", str(path)], capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 0, proc.stderr
    assert abs(number(r"D = ([\d.]+)", proc.stdout) - 1.0) < 0.1  # the outline of a rectangle


# --------------------------------------------------------------------------- #
# --method uncertainty (the default for a window) and --store (issue 12)      #
# --------------------------------------------------------------------------- #


def test_uncertainty_is_the_default_for_a_window_and_prints_the_api_result(tmp_path, capsys):
    from stairbounce.dimension import sliding_classifier, uncertainty_dimension

    png = tmp_path / "u.png"
    code, out, err = run([*FIG7, "--max-iter", "200", "--points", "2000", "--eps", "1e-3:0.1:5",
                          "--seed", "3", "--png", str(png), "--proven-depth", "0"], capsys)
    assert code == 0, err
    ref = uncertainty_dimension(sliding_classifier(200), ((0.155, 0.2138), (0.6, 0.658)),
                                eps=np.logspace(-3, -1, 5), n_points=2000, seed=3)
    assert number(r"D = ([\d.]+)", out) == pytest.approx(ref.dimension, abs=5e-5)
    assert "uncertainty exponent of 2000 random points (seed 3" in out
    assert "uncertain" in out and png.exists()


@pytest.fixture(scope="module")
def small_store(tmp_path_factory):
    from stairbounce.atlas import scan_to_zarr

    path = tmp_path_factory.mktemp("store") / "s.zarr"
    scan_to_zarr(path, e=(0.155, 0.2138, 96), u=(0.6, 0.658, 96), max_iter=200, tile=32)
    return path


def test_store_is_box_counted_tile_by_tile(small_store, capsys):
    from stairbounce.atlas_boxes import store_box_dimension

    code, out, err = run(["--store", str(small_store), "--fit-range", "2:16"], capsys)
    assert code == 0, err
    ref = store_box_dimension(small_store, fit_range=(2, 16))
    assert number(r"D = ([\d.]+)", out) == pytest.approx(ref.dimension, abs=5e-5)
    assert "96 x 96 px" in out and "tile by tile" in out


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--method", "mass"], "--method must be boxes, uncertainty or slicing"),
        (["--method", "uncertainty", "--store", "{tmp}/x.zarr"], "--method uncertainty classifies points"),
        (["--points", "99"], "--points must be an integer >= 100"),
        (["--eps", "0:0.1:5"], "--eps must have 0 < MIN < MAX < 1"),
        (["--eps", "1e-3:1.5:5"], "--eps must have 0 < MIN < MAX < 1"),
        (["--eps", "1e-3"], "--eps must be MIN:MAX:N"),
        (["--e", "0.2:0.2"], "MIN < MAX"),
        (["--method", "uncertainty", "--fit-range", "0.5:2"], "--fit-range with --method uncertainty"),
        (["--fit-range", "0.5:2"], "--fit-range with --method slicing"),  # the default method
        (["--store", "{tmp}/missing.zarr"], "no such store"),
        (["--store", "{tmp}/text.png"], "not a tiled scan store"),
        (["--store", "{store}", "--png", "{tmp}/a.png"], "--png draws a picture in memory"),
        (["--scheduler", "tcp://127.0.0.1:1"], "--scheduler counts the tiles of a --store"),
        (["--image", "{tmp}/a.png", "--store", "{tmp}/x.zarr"], "give one of them"),
    ],
)
def test_uncertainty_and_store_bad_input_exit_2(tmp_path, capsys, small_store, argv, message):
    (tmp_path / "text.png").write_text("not a store")
    argv = [a.format(tmp=tmp_path, store=small_store) for a in argv]
    code, out, err = run(argv, capsys)
    assert code == 2, out
    assert err.startswith("stairbounce: error: ") and message in err
    assert err.count("\n") == 1


def test_incomplete_store_exits_2(tmp_path, capsys):
    from stairbounce.atlas import scan_to_zarr

    path = tmp_path / "part.zarr"
    with pytest.raises(StopAfter):
        scan_to_zarr(path, e=(0.155, 0.2138, 64), u=(0.6, 0.658, 64), max_iter=50, tile=16, progress=stop_after(1),
                     numba_threads=2)
    code, out, err = run(["--store", str(path)], capsys)
    assert code == 2 and "is not complete" in err and err.count("\n") == 1


# --------------------------------------------------------------------------- #
# issue 24: the scale-resolved view, the drift-covering interval, max_iter    #
# --------------------------------------------------------------------------- #


def test_every_method_prints_scales_max_iter_and_an_interval_covering_the_drift(capsys):
    from stairbounce.dimension import sliding_classifier, slicing_dimension

    code, out, err = run([*FIG7, "--method", "slicing", "--max-iter", "200", "--lines", "8",
                          "--scales", "1e-5:1e-2", "--seed", "2", "--proven-depth", "0"], capsys)
    assert code == 0, err
    ref = slicing_dimension(sliding_classifier(200), ((0.155, 0.2138), (0.6, 0.658)), n_lines=8,
                            scale_min=1e-5, scale_max=1e-2, seed=2)
    assert number(r"D = ([\d.]+)", out) == pytest.approx(ref.dimension, abs=5e-5)
    lo, hi = (float(x) for x in re.search(r"interval = \[([\d.]+), ([\d.]+)\]", out).groups())
    assert lo <= ref.ci[0] and ref.ci[1] <= hi  # the drift widens the statistical interval
    assert lo == pytest.approx(ref.interval[0], abs=5e-5) and hi == pytest.approx(ref.interval[1], abs=5e-5)
    # the local dimension at every scale, first, drawn as a curve on 1 .. 2
    assert out.index("local dimension against scale") < out.index("D = ")
    strips = re.findall(r"\[([ *|-]{41})\]", out)
    assert len(strips) == len(ref.local[1]) and all("*" in t for t in strips)
    assert "max_iter 200" in out and "scales: " in out and "systematic +-" in out
    code, out, err = run([*FIG7, "--max-iter", "200", "--points", "2000", "--eps", "1e-3:0.1:5"], capsys)
    assert code == 0 and "interval = [" in out and "eps" in out and "max_iter 200" in out


def test_check_max_iter_shows_the_local_dimension_at_four_times_max_iter(capsys):
    code, out, err = run([*FIG7, "--max-iter", "50", "--points", "2000", "--eps", "1e-3:0.1:5",
                          "--check-max-iter", "--proven-depth", "0"], capsys)
    assert code == 0, err
    assert "local dimension at max_iter 50 and 200" in out
    assert ("converged at every scale" in out) != ("is not converged at scales" in out)
    code, out, err = run([*FIG7, "--method", "boxes", "--resolution", "64", "--max-iter", "50",
                          "--check-max-iter", "--proven-depth", "0"], capsys)
    assert code == 0, err
    assert "local dimension at max_iter 50 and 200" in out and "+- 0.0300" in out


def test_a_small_store_says_which_range_it_fits(small_store, capsys):
    # 96 px: too small for 16 px .. 1/32; the command says so rather than fall back silently
    code, out, err = run(["--store", str(small_store)], capsys)
    assert code == 0, err
    assert "too small for a fit clear of the pixel scale" in out


# --------------------------------------------------------------------------- #
# issue 44 item 4: proven box counts of the perimeter beside the numerical D   #
# --------------------------------------------------------------------------- #


def test_the_proven_box_counts_are_printed_with_their_basis(capsys):
    import stairbounce as sb

    code, out, err = run([*FIG7, "--lines", "8", "--max-iter", "200", "--proven-depth", "8"], capsys)
    assert code == 0, err
    head = "proven box counts of the sliding border (basis: proven, certify depth 8, max_iter 200)"
    assert head in out and out.index("D = ") < out.index(head)
    r = sb.certify(e=(0.155, 0.2138), u=(0.6, 0.658), depth=8, max_iter=200, classes=True,
                   trap="fine").perimeter_bracket()
    for k, lo, up in zip(r["k"], r["lower"], r["upper"]):
        assert re.search(rf"k = +{k}  window/{1 << k} +lower +{lo:,}  upper +{up:,}\n", out), (k, out)
    assert f"slope {r['slope_text']}" in out and r["finite_text"] in out
    assert "re-verified by the independent checker sb.verify" in out
    assert "not proven: the border of the region sliding at all (the limit max_iter -> infinity)" in out
    # beside the numerical D: the verdict of slope_verdict, said
    d = number(r"\nD = ([\d.]+)", out)
    assert re.search(r"beside the numerical D = [\d.]+: (agrees|differs|not comparable) \(", out)
    from stairbounce.structure.certify import slope_verdict
    assert f": {slope_verdict(d, r['across'])[0]} (" in out


def test_proven_depth_0_leaves_the_counts_out_and_wrong_uses_are_one_line(capsys, tmp_path):
    code, out, err = run([*FIG7, "--lines", "8", "--max-iter", "200", "--proven-depth", "0"], capsys)
    assert code == 0 and "proven box counts" not in out
    path = tmp_path / "disk.png"
    write_picture(path, disk(64))
    # a picture: no default counts, and the option refused by name
    code, out, err = run(["--image", str(path)], capsys)
    assert code == 0 and "proven box counts" not in out
    for argv, message in ((["--image", str(path), "--proven-depth", "6"], "not with --image or --store"),
                          ([*FIG7, "--which", "words", "--proven-depth", "6"], "not with --which words"),
                          ([*FIG7, "--proven-depth", "-1"], "--proven-depth must be an integer in [0, 16]"),
                          ([*FIG7, "--proven-depth", "17"], "--proven-depth must be an integer in [0, 16]")):
        code, out, err = run(argv, capsys)
        assert code == 2 and message in err and len(err.strip().splitlines()) == 1, (argv, err)


def test_the_counts_are_numerical_when_the_checker_rejects(capsys, monkeypatch):
    import sys as _sys

    from stairbounce.structure.verdict import Verdict

    monkeypatch.setattr(_sys.modules["stairbounce.structure.verdict"], "verify",
                        lambda obj: Verdict(False, "word", None, "tampered", checked=9, rejected=1, atlas=True))
    code, out, err = run([*FIG7, "--lines", "8", "--max-iter", "200", "--proven-depth", "5"], capsys)
    assert code == 0, err
    assert "proven box counts of the sliding border (basis: numerical, certify depth 5" in out
    assert "NOT proven: sb.verify did not pass the atlas (tampered)" in out
