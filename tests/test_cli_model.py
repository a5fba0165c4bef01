"""`stairbounce word`, `map` and `trajectory`: output, files and bad input."""

from __future__ import annotations

import csv
import io
import subprocess
import sys

import pytest
from PIL import Image

import stairbounce as sb
from stairbounce.cli import main

from ._cli import run_cli as run


def test_word_prints_word_period_impacts(capsys):
    code, out, _ = run(["word", "--e", "0.05", "--u", "0.93"], capsys)
    w = sb.sliding_word(0.05, 0.93)
    assert code == 0
    assert f"period:  {w.period} steps" in out and w.period > 1
    assert f"impacts: {w.impacts}" in out
    assert w.format(ascii=True)[:-6] in out  # the letters, whatever the tail's glyph


def test_word_says_when_nothing_slides(capsys):
    code, out, _ = run(["word", "--e", "0.4", "--u", "0.33", "--max-iter", "50"], capsys)
    assert code == 0
    assert "no periodic sliding solution found within 50 steps" in out
    # above the Corollary 2.1 curve (1.006 at e = 0.1) it is proven, not searched
    code, out, _ = run(["word", "--e", "0.1", "--u", "1.2", "--max-iter", "50"], capsys)
    assert code == 0
    assert "impossible (Corollary 2.1: u >= 1.00623 at e = 0.1)" in out


def test_map_csv_is_the_iterates(capsys):
    code, out, _ = run(["map", "--e", "0.1", "--u", "0.9", "--steps", "25", "--csv"], capsys)
    assert code == 0
    rows = list(csv.DictReader(io.StringIO(out)))
    ys, vs, ks = sb.iterate(1.0, 0.0, 0.1, 0.9, 25)
    assert len(rows) == 26
    for n, row in enumerate(rows):
        assert float(row["y"]) == ys[n] and float(row["v"]) == vs[n]
        if n:
            assert int(row["impacts"]) == ks[n]


def test_map_table_marks_sliding(capsys):
    code, out, _ = run(["map", "--e", "0.1", "--u", "0.5", "--steps", "2"], capsys)
    assert code == 0 and out.count("sliding") == 2


def test_trajectory_writes_figure_and_animation(tmp_path, capsys):
    png, gif = tmp_path / "t.png", tmp_path / "t.gif"
    code, out, _ = run(
        ["trajectory", "--e", "0.2", "--u", "0.45", "--steps", "3", "--out", str(png),
         "--animate", str(gif)],
        capsys,
    )
    assert code == 0
    with Image.open(png) as im:
        assert im.size[0] > 500
    with Image.open(gif) as im:
        assert im.n_frames > 10
    assert "3 accumulation points" in out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.gif", "t.png"]  # no leftovers


@pytest.mark.parametrize(
    "args,needle",
    [
        (["word", "--e", "1.5", "--u", "0.5"], "e (restitution coefficient) must be in [0, 1)"),
        (["word", "--e", "0.1", "--u", "-1"], "u (horizontal speed) must be > 0"),
        (["word", "--e", "nan", "--u", "0.5"], "e must be finite"),
        (["word", "--e", "x", "--u", "0.5"], "--e"),
        (["word", "--u", "0.5"], "--e"),
        (["word", "--e", "0.1", "--u", "0.5", "--max-iter", "0"], "max_iter must be an integer >= 1"),
        (["map", "--e", "0.1", "--u", "0.5", "--y0", "-2"], "must be >= 0"),
        (["map", "--e", "0.1", "--u", "0.5", "--steps", "-1"], "steps must be an integer >= 0"),
        (["trajectory", "--e", "0.1", "--u", "0.5", "--steps", "0"], "--steps must be an integer >= 1"),
        (["trajectory", "--e", "0.1", "--u", "0.5", "--out", "x.jpg2"], "--out must end in"),
        (["trajectory", "--e", "0.1", "--u", "0.5", "--out", "/nonexistent/dir/x.png"], "does not exist"),
        (["nosuchcommand"], "No such command"),
    ],
)
def test_bad_input_is_one_line_and_status_2(args, needle, capsys):
    code, out, err = run(args, capsys)
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("stairbounce: error:")
    assert needle in lines[0]
    assert "Traceback" not in err + out


@pytest.mark.parametrize("command", ["word", "map", "trajectory"])
def test_help_on_every_command(command, capsys):
    code, out, _ = run([command, "--help"], capsys)
    assert code == 0 and "--e" in out and "--u" in out


def test_console_script_runs():
    """The installed entry point, as a newcomer types it."""
    exe = [sys.executable, "-c", "from stairbounce.cli import main; main()"]
    ok = subprocess.run([*exe, "word", "--e", "0.1", "--u", "0.5"], capture_output=True, text=True)
    assert ok.returncode == 0 and "(1, 0^" in ok.stdout
    bad = subprocess.run([*exe, "word", "--e", "2", "--u", "0.5"], capture_output=True, text=True)
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "Traceback" not in bad.stderr
