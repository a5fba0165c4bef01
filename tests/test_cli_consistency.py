"""The command line speaks one language (issue 15): the same --overlay form in
every command, flags shown without a value, plurals, progress for long jobs,
tiles for every worker."""

from __future__ import annotations

import pytest

from stairbounce.cli._app import CLIError, parse_overlays, plural, tile_for_workers

from ._cli import run_cli as run


def test_overlay_is_a_comma_list_or_repeated_everywhere():
    allowed = ("tongues", "bound")
    assert parse_overlays(["tongues,bound"], allowed) == ("tongues", "bound")
    assert parse_overlays(["tongues", "bound"], allowed) == ("tongues", "bound")
    assert parse_overlays(["bound", "tongues,bound"], allowed) == ("bound", "tongues")
    assert parse_overlays([], allowed) == ()
    with pytest.raises(CLIError, match="--overlay must be among tongues, bound"):
        parse_overlays(["tongues,grid"], allowed)


@pytest.mark.parametrize("form", [["--overlay", "tongues"], ["--overlay", "tongues,"]])
def test_both_commands_take_the_same_overlay_form(form, tmp_path, capsys):
    code, _, err = run(["scan", "--size", "20x20", "--max-iter", "50", "--png",
                        str(tmp_path / "s.png"), *form], capsys)
    assert code == 0, err
    code, _, err = run(["orbit-diagram", "--e", "0.1", "--u", "0.3:1", "--n", "20", "--transient",
                        "20", "--keep", "5", "--png", str(tmp_path / "o.png"), *form], capsys)
    assert code == 0, err


def test_flags_take_no_value_in_the_help(capsys):
    for command in ("map", "orbit-diagram", "figures", "scan"):
        code, out, _ = run([command, "--help"], capsys)
        assert code == 0 and "<bool>" not in out and "BOOLEAN" not in out, command
    code, out, _ = run(["map", "--help"], capsys)
    assert "--csv " in out


def test_plurals(tmp_path, capsys):
    assert plural(1, "tile") == "1 tile" and plural(2, "tile") == "2 tiles"
    assert plural(0, "slide") == "0 slides"
    # e = 0.1, u = 0.5 slides on its first step: one slide in one step
    code, out, _ = run(["trajectory", "--e", "0.1", "--u", "0.5", "--steps", "1", "--out",
                        str(tmp_path / "t.png"), "--dpi", "30"], capsys)
    assert code == 0 and "1 slide" in out and "1 slides" not in out


def test_every_worker_gets_a_tile():
    # the Fig. 4 view with 2 workers: 1024 px tiles would make one tile
    tile, tiles = tile_for_workers(500, 350, 2)
    assert tiles >= 4 and (tile, tiles) == (256, 4)
    assert tile_for_workers(4096, 4096, 2) == (1024, 16)  # large scans keep the default
    # a tiny scan cannot feed 16 workers with tiles of at least 64 px
    assert tile_for_workers(100, 100, 16) == (64, 4)


def test_animation_reports_every_frame(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    from stairbounce.plot import animate_trajectory
    from stairbounce.trajectory import trajectory

    seen = []
    traj = trajectory(0.1, 0.5, 1.0, 0.0, 1)
    animate_trajectory(traj, tmp_path / "a.gif", fps=10, seconds_per_step=0.5,
                       progress=lambda done, total: seen.append((done, total)))
    assert seen[-1] == (5, 5) and [d for d, _ in seen] == [1, 2, 3, 4, 5]
    assert (tmp_path / "a.gif").stat().st_size > 0


def test_help_summaries_are_whole_sentences(capsys, monkeypatch):
    """Click cuts a docstring's summary at its first period ("(Prop." "(Fig.")
    and at 45 characters ("..."): every command has a short summary of its
    own that fits one line of an 80-column terminal (issue 25)."""
    monkeypatch.setenv("COLUMNS", "80")
    code, out, _ = run(["--help"], capsys)
    assert code == 0
    rows = out.split("Commands:")[1].strip().splitlines()
    commands = ("figures", "dimension", "word", "map", "trajectory", "orbit-diagram", "motion",
                "scan", "explore", "render", "borders", "words", "itinerary", "cache", "cascade",
                "certify")
    assert sorted(r.split()[0] for r in rows) == sorted(commands)  # one line each
    for r in rows:
        assert r.endswith(".") and not r.endswith("...") and not r.endswith(("Prop.", "Fig.")), r


@pytest.mark.parametrize("field, description", [("word_length", "scan rows"), ("k_mean", "motion scan rows")])
def test_in_memory_scans_report_progress_over_rows(field, description, tmp_path, capsys, monkeypatch):
    """Both in-memory scans (the words, and the motion fields) drive a progress
    bar over their rows to the end (drawn on stderr when it is a terminal)."""
    from contextlib import contextmanager

    from stairbounce.cli import _app

    calls = []

    class Bar:
        def update(self, task, completed, total):
            calls[-1][2].append((completed, total))

    @contextmanager
    def fake(console, desc, total, unit=""):
        assert console.stderr
        calls.append((desc, total, []))
        yield Bar(), 0

    monkeypatch.setattr(_app, "progress_bar", fake)
    code, _, err = run(["scan", "--size", "20x60", "--max-iter", "20", "--field", field,
                        "--png", str(tmp_path / "s.png")], capsys)
    assert code == 0, err
    (desc, total, updates), = calls
    assert desc == description and total == 60
    assert updates[0] == (0, 60) and updates[-1] == (60, 60) and len(updates) > 10
