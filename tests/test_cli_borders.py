"""``stairbounce borders`` and ``stairbounce words`` (issue 21): the files hold
what the library returns, bad input is one line and exit status 2."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
import xarray as xr

import stairbounce as sb

from ._cli import run_cli as run

WINDOW = ["--e", "0:0.3", "--u", "0.3:0.7", "--size", "30x30", "--max-iter", "500"]


def test_borders_writes_the_library_points(tmp_path, capsys):
    code, out, err = run(["borders", *WINDOW, "--out", str(tmp_path / "b.nc"), "--png",
                          str(tmp_path / "b.png"), "--dpi", "40"], capsys)
    assert code == 0, err
    ref = sb.border_points(e=(0.0, 0.3, 30), u=(0.3, 0.7, 30), max_iter=500)
    got = xr.open_dataset(tmp_path / "b.nc").load()
    for name in ("e", "u", "width", "step", "index"):
        np.testing.assert_array_equal(got[name].values, ref[name].values)
    for name in ("kind", "word_low", "word_high", "axis"):
        assert got[name].values.astype(str).tolist() == ref[name].values.astype(str).tolist()
    assert (tmp_path / "b.png").stat().st_size > 1000
    n = ref.sizes["point"]
    assert f"{n} border points" in out
    code, _, err = run(["borders", *WINDOW, "--out", str(tmp_path / "b.csv")], capsys)
    assert code == 0, err
    csv = pd.read_csv(tmp_path / "b.csv")
    assert len(csv) == n and csv["kind"].tolist() == ref.kind.values.tolist()
    np.testing.assert_array_equal(csv["e"].values, ref.e.values)


def test_words_writes_the_table(tmp_path, capsys):
    code, out, err = run(["words", *WINDOW, "--out", str(tmp_path / "w.csv"), "--png",
                          str(tmp_path / "w.png"), "--dpi", "40", "--top", "2"], capsys)
    assert code == 0, err
    ref = sb.word_table(e=(0.0, 0.3, 30), u=(0.3, 0.7, 30), max_iter=500)
    csv = pd.read_csv(tmp_path / "w.csv")
    assert csv["text"].tolist() == ref.text.values.tolist()
    assert csv["pixels"].tolist() == ref.pixels.values.tolist()
    assert f"{ref.sizes['word']} distinct words" in out and ref.text.values[0] in out
    code, _, err = run(["words", *WINDOW, "--out", str(tmp_path / "w.nc")], capsys)
    assert code == 0, err
    got = xr.open_dataset(tmp_path / "w.nc").load()
    np.testing.assert_array_equal(got.distinct_words.values, ref.distinct_words.values)


def test_a_physical_staircase_gives_the_window_of_its_u(tmp_path, capsys):
    a, b, g = 0.17, 0.29, 9.81
    code, out, err = run(["borders", "--e", "0:0.3", "--speed", "1:2", "--step-height", str(a),
                          "--step-length", str(b), "--size", "20x20", "--out",
                          str(tmp_path / "b.nc")], capsys)
    assert code == 0, err
    lo, hi = (s * math.sqrt(a / g) / b for s in (1.0, 2.0))
    got = xr.open_dataset(tmp_path / "b.nc").load()
    assert got.attrs["u_min"] == pytest.approx(lo, rel=1e-15)
    assert got.attrs["u_max"] == pytest.approx(hi, rel=1e-15)
    assert "m/s" in out


@pytest.mark.parametrize("command", ["borders", "words"])
@pytest.mark.parametrize("args,message", [
    (["--e", "0:2", "--out", "x.nc"], "e window"),
    (["--out", "x.txt"], "--out must end in .nc or .csv"),
    (["--png", "x.gif"], "--png must end in"),
    ([], "nothing to write"),
    (["--size", "0x10", "--out", "x.nc"], "--size"),
    (["--max-iter", "0", "--out", "x.nc"], "--max-iter"),
    (["--u", "0:1", "--speed", "1:2", "--out", "x.nc"], "not both"),
    (["--speed", "1:2", "--out", "x.nc"], "--step-height"),
    (["--dpi", "5", "--out", "x.nc"], "--dpi"),
])
def test_bad_input_is_one_line_and_status_2(command, args, message, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, _, err = run([command, *args], capsys)
    assert code == 2 and message in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def test_an_existing_file_is_kept_without_force(tmp_path, capsys):
    target = tmp_path / "b.csv"
    target.write_text("mine")
    code, _, err = run(["borders", *WINDOW, "--out", str(target)], capsys)
    assert code == 2 and target.read_text() == "mine"
    code, _, err = run(["borders", *WINDOW, "--out", str(target), "--force"], capsys)
    assert code == 0 and target.read_text() != "mine"


def test_borders_outcome_sliding(tmp_path, capsys):
    code, out, err = run(["borders", *WINDOW, "--outcome", "sliding", "--out", str(tmp_path / "s.nc")],
                         capsys)
    assert code == 0, err
    ref = sb.border_points(e=(0.0, 0.3, 30), u=(0.3, 0.7, 30), max_iter=500, outcome="sliding")
    got = xr.open_dataset(tmp_path / "s.nc").load()
    np.testing.assert_array_equal(got.e.values, ref.e.values)
    assert got.sliding_border.values.all() and f"{ref.sizes['point']} on the border" in out


def test_borders_bad_outcome(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, _, err = run(["borders", "--outcome", "status", "--out", "x.nc"], capsys)
    assert code == 2 and "--outcome must be word or sliding" in err and len(err.strip().splitlines()) == 1


def test_itinerary_prints_the_library_margins(capsys):
    import csv
    import io

    code, out, err = run(["itinerary", "--e", "0.02", "--u", "0.7", "--csv"], capsys)
    assert code == 0, err
    ref = sb.itinerary(0.02, 0.7)
    rows = list(csv.DictReader(io.StringIO(out)))
    assert [int(r["impacts"]) for r in rows] == ref.impacts.values.tolist()
    for name in ("contact", "next_impact", "accumulation"):
        got = np.array([float(r[name]) for r in rows])
        np.testing.assert_array_equal(got, ref[name].values)
    code, out, err = run(["itinerary", "--e", "0.02", "--u", "0.7"], capsys)
    assert code == 0 and "slides on step 4" in out


def test_itinerary_of_a_physical_staircase(capsys):
    a, b, g, speed = 0.17, 0.29, 9.81, 1.5
    code, out, err = run(["itinerary", "--e", "0.1", "--speed", str(speed), "--step-height", str(a),
                          "--step-length", str(b), "--csv"], capsys)
    assert code == 0, err
    ref = sb.itinerary(0.1, speed * math.sqrt(a / g) / b)
    assert len(out.strip().splitlines()) == ref.sizes["step"] + 1
    for args, message in [(["--e", "1.5", "--u", "1"], "e (restitution"),
                          (["--e", "0.1"], "give the horizontal speed"),
                          (["--e", "0.1", "--u", "1", "--max-iter", "0"], "max_iter")]:
        code, _, err = run(["itinerary", *args], capsys)
        assert code == 2 and message in err and len(err.strip().splitlines()) == 1
