"""One convention for windows and limits, and commands that name what happened
(issue 37): every window is (lo, hi) or (lo, hi, n) image edges, in Python and
on the command line; the step limit is max_iter everywhere; one default
estimator of the dimension; words given as text; old spellings still work, with
a DeprecationWarning, and give the same results."""

from __future__ import annotations

import re
import time
import warnings

import numpy as np
import pytest
import xarray as xr

import stairbounce as sb
from stairbounce import plane

from ._cli import run_cli as run

FIG5E = ((0.04, 0.065), (0.92, 0.945))


def no_warning(call):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return call()


# --------------------------------------------------------------------------- #
# Windows: (lo, hi) or (lo, hi, n) in every function                          #
# --------------------------------------------------------------------------- #


def test_square_counts_make_square_pixels_and_keep_given_counts():
    assert plane.square_counts((0.0, 1.0), (0.0, 1.5)) == (333, 500)
    assert plane.square_counts((0.04, 0.065), (0.92, 0.945)) == (500, 500)
    assert plane.square_counts((0.0, 1.0, 100), (0.0, 0.5)) == (100, 50)   # the given pixel size
    assert plane.square_counts((0.0, 1.0), (0.0, 0.5, 10)) == (20, 10)
    assert plane.square_counts((0.0, 1.0, 7), (0.0, 0.5, 9)) == (7, 9)     # both given: kept
    assert plane.square_counts((0.0, 1.0), (0.0, 1e-6)) == (500, 1)        # at least one pixel


def test_scan_takes_pairs_as_square_pixels_and_gives_the_triples_result():
    e, u = (0.04, 0.065), (0.92, 0.945, 40)
    ds = no_warning(lambda: sb.scan(e=e, u=u, max_iter=300))
    assert dict(ds.sizes) == {"u": 40, "e": 40}
    ref = sb.scan(e=(0.04, 0.065, 40), u=u, max_iter=300)
    assert ds.word_length.equals(ref.word_length) and ds.attrs["n_e"] == 40
    # pixels square in the window's units
    de, du = float(ds.e[1] - ds.e[0]), float(ds.u[1] - ds.u[0])
    assert de == pytest.approx(du, rel=1e-9)


@pytest.mark.parametrize("bad", [(0.1,), (0.1, 0.2, 3, 4), "0.1:0.2", 0.5])
def test_a_window_of_another_form_is_refused_naming_both_forms(bad):
    for call in (lambda: sb.scan(e=bad, u=(0.5, 1.0, 4)),
                 lambda: sb.border_points(e=bad, u=(0.5, 1.0, 4)),
                 lambda: sb.word_region((2,), e=bad),
                 lambda: sb.perimeter_dimension(e=bad)):
        with pytest.raises(ValueError, match=r"e must be a .*\(e_min, e_max\) or \(e_min, e_max, n_e\)|"
                                             r"e must be a window \(min, max\) or \(min, max, n\)"):
            call()


def test_border_points_word_table_and_motion_scan_take_pairs():
    e, u = (0.04, 0.065, 24), (0.92, 0.945)
    pts = no_warning(lambda: sb.border_points(e=e, u=u, max_iter=300))
    ref = sb.border_points(e=e, u=(0.92, 0.945, 24), max_iter=300)
    assert pts.attrs["n_u"] == 24 and pts.sizes["point"] == ref.sizes["point"] > 0
    np.testing.assert_array_equal(pts.e.values, ref.e.values)
    tab = sb.word_table(e=e, u=u, max_iter=300)
    assert tab.attrs["pixels"] == 24 * 24
    m = sb.motion_scan(e=(0.3, 0.5), u=(0.6, 0.8, 6), steps=20, transient=20)
    assert dict(m.sizes) == {"u": 6, "e": 6}


def test_window_regions_takes_the_seed_counts_from_the_windows_never_ignoring_them():
    e, u = FIG5E
    by_counts = sb.window_regions((*e, 8), (*u, 8), max_iter=300)
    by_resolution = sb.window_regions(e, u, resolution=8, max_iter=300)
    assert [(r.word, r.area) for r in by_counts] == [(r.word, r.area) for r in by_resolution]
    assert 5 < len(by_counts) < 100     # a seed scan of 8 x 8, not the default 256 x 256
    with pytest.raises(ValueError, match="give the seed pixels once"):
        sb.window_regions((*e, 8), (*u, 8), resolution=8)
    with pytest.raises(ValueError, match="n_e must be an integer in \\[2, 8192\\]"):
        sb.word_region((2,), e=(0.1, 0.2, 1))


def test_functions_without_pixels_refuse_a_count_instead_of_ignoring_it():
    from stairbounce import dimension

    classify = dimension.sliding_classifier(max_iter=50)
    for call in (lambda: sb.trace_border(0.05, 0.93, window=((0.04, 0.065, 5), (0.92, 0.945))),
                 lambda: dimension.uncertainty_dimension(classify, ((0.15, 0.2, 5), (0.6, 0.65)), n_points=200),
                 lambda: dimension.slicing_dimension(classify, ((0.15, 0.2), (0.6, 0.65, 5)), n_lines=2)):
        with pytest.raises(ValueError, match="window must be"):
            call()


def test_the_inline_explorer_takes_counts_in_the_window_but_not_twice():
    from stairbounce.explorer import inline

    with pytest.raises(ValueError, match="width = 300 and the window's pixel count 50: give the pixels once"):
        inline(e=(0.0, 1.0, 50), width=300)
    with pytest.raises(ValueError, match=r"u must be a tuple \(u_min, u_max\) or \(u_min, u_max, n_u\)"):
        inline(u=(0.0,))


def test_regions_take_the_image_edges_of_a_scan_window():
    # e = 1 and u = 0 are image edges, as in scan: the margins are traced just inside
    r = no_warning(lambda: sb.word_region((1,), e=(0.5, 1.0), u=(0.0, 0.2), resolution=16))
    assert r.found and r.complete and r.e[1] < 1.0 and r.u[0] > 0.0
    # Theorem 3.1: the (1, 0^inf) tongue is u <= sqrt(1/2) (1-e)/(1+e), so its area in the
    # window is the integral of min(0.2, that) over e in [0.5, 1]
    es = np.linspace(0.5, 1.0, 200001)
    exact = np.trapezoid(np.minimum(0.2, np.sqrt(0.5) * (1 - es) / (1 + es)), es)
    assert r.area == pytest.approx(exact, rel=1e-6)
    # a seed pixel centre the traced window would leave out is refused, not traced wrongly
    with pytest.raises(ValueError, match="seed pixel centres beyond"):
        sb.word_region((1,), e=(0.5, 1.0), u=(0.0, 1e-8), resolution=8)


def test_a_word_given_as_text_is_the_word_and_an_absent_word_says_so():
    e, u = FIG5E
    a = sb.word_region("(2, 2, 2)", e, u, resolution=32)
    b = sb.word_region((2, 2, 2), e, u, resolution=32)
    c = sb.word_region("(2, 2, 2, 0^inf)", e, u, resolution=32)
    assert a.word == b.word == c.word and a.area == b.area == c.area > 0 and a.found
    with pytest.warns(UserWarning, match=r"word \(7, 7, 0\^inf\) not found in the window"):
        absent = sb.word_region("(7, 7)", e, u, resolution=16)
    assert not absent.found and absent.area == 0 and "not found in the window" in repr(absent)


# --------------------------------------------------------------------------- #
# The step limit: max_iter everywhere                                         #
# --------------------------------------------------------------------------- #


@pytest.mark.parametrize("e, u", [(0.05, 0.93), (0.4, 0.33), (0.1, 1.2)])
def test_max_steps_still_works_with_a_deprecation_warning_and_the_same_answer(e, u):
    new = no_warning(lambda: sb.sliding_word(e, u, max_iter=50))
    with pytest.warns(DeprecationWarning, match="max_steps= is deprecated: use max_iter="):
        old = sb.sliding_word(e, u, max_steps=50)
    assert old == new
    answer = no_warning(lambda: sb.sliding_answer(e, u, max_iter=50))
    with pytest.warns(DeprecationWarning, match="max_steps= is deprecated"):
        old_answer = sb.sliding_answer(e, u, max_steps=50)
    assert old_answer == answer and answer.max_iter == 50
    with pytest.warns(DeprecationWarning, match="max_steps is deprecated: use max_iter"):
        assert answer.max_steps == 50
    assert sb.sliding_word(e, u, 50) == new     # positional, as before


def test_max_steps_and_max_iter_together_are_refused():
    with pytest.warns(DeprecationWarning), pytest.raises(ValueError, match="give max_iter only"):
        sb.sliding_word(0.05, 0.93, max_iter=10, max_steps=20)


def test_cli_word_takes_max_iter_and_still_reads_max_steps(capsys):
    code, new, err = run(["word", "--e", "0.4", "--u", "0.33", "--max-iter", "50"], capsys)
    assert code == 0 and err == ""
    code, old, err = run(["word", "--e", "0.4", "--u", "0.33", "--max-steps", "50"], capsys)
    assert code == 0 and old == new and "within 50 steps" in new
    assert err == "stairbounce: warning: --max-steps is deprecated: use --max-iter\n"
    code, _, err = run(["word", "--e", "0.4", "--u", "0.33", "--max-steps", "50", "--max-iter", "9"], capsys)
    assert code == 2 and "give --max-iter only" in err


# --------------------------------------------------------------------------- #
# The dimension: one default estimator                                         #
# --------------------------------------------------------------------------- #

SMALL = dict(e=(0.155, 0.2138), u=(0.6, 0.658), max_iter=60)


def test_perimeter_dimension_defaults_to_the_uncertainty_exponent_as_the_cli():
    kw = dict(SMALL, n_points=2000, eps=np.logspace(-4, -1, 4))
    default = no_warning(lambda: sb.perimeter_dimension(**kw))
    explicit = sb.perimeter_dimension(**kw, method="uncertainty")
    assert isinstance(default, sb.UncertaintyDimension)
    assert default.dimension == explicit.dimension and default.interval == explicit.interval


def test_box_parameters_without_method_still_count_boxes_with_a_deprecation_warning():
    kw = dict(SMALL, resolution=32, fit_range=(1, 8))
    with pytest.warns(DeprecationWarning, match="pass method='boxes'"):
        old = sb.perimeter_dimension(**kw)
    new = no_warning(lambda: sb.perimeter_dimension(**kw, method="boxes"))
    assert isinstance(old, sb.PerimeterDimension)
    assert old.dimension == new.dimension and np.array_equal(old.border, new.border)
    # the windows' counts are the same as resolution
    counted = sb.perimeter_dimension(e=(*SMALL["e"], 32), u=(*SMALL["u"], 32), max_iter=60,
                                     fit_range=(1, 8), method="boxes")
    assert counted.dimension == new.dimension and counted.resolution == 32


@pytest.mark.parametrize("kw, match", [
    (dict(method="uncertainty", resolution=64), "resolution are parameters of box counting"),
    (dict(method="slicing", connectivity=8), "connectivity are parameters of box counting"),
    (dict(e=(0.155, 0.2138, 64)), "n_e are parameters of box counting"),
    (dict(method="boxes", e=(0.155, 0.2138, 64), u=(0.6, 0.658, 32)), "square grid"),
    (dict(method="boxes", e=(0.155, 0.2138, 64), u=(0.6, 0.658, 64), resolution=64), "give the pixels once"),
])
def test_parameters_a_method_does_not_use_are_refused_not_ignored(kw, match):
    with pytest.raises(ValueError, match=match):
        sb.perimeter_dimension(**{**SMALL, **kw})


# --------------------------------------------------------------------------- #
# The command line: LO:HI is one thing, defaults are valid                    #
# --------------------------------------------------------------------------- #


def test_orbit_diagram_range_is_edges_so_u_0_is_never_sampled(tmp_path, capsys):
    out = tmp_path / "fig8.nc"
    code, stdout, err = run(["orbit-diagram", "--e", "0.001", "--u", "0:1.5", "--n", "30",
                             "--transient", "50", "--keep", "5", "--out", str(out)], capsys)
    assert code == 0, err
    ds = xr.load_dataset(out)
    np.testing.assert_array_equal(ds.u.values, sb.pixel_centres(0.0, 1.5, 30))
    ref = sb.orbit_diagram(0.001, sb.pixel_centres(0.0, 1.5, 30), transient=50, keep=5)
    np.testing.assert_array_equal(ds.y.values, ref.y.values)


def test_cli_help_states_the_one_meaning_of_a_window(capsys):
    code, out, _ = run(["--help"], capsys)
    text = " ".join(out.split())
    assert code == 0 and "the edges of the interval" in text and "never used" in text
    code, out, _ = run(["orbit-diagram", "--help"], capsys)
    assert "centres of equal cells" in " ".join(out.split())


def test_words_regions_with_the_default_window_is_not_refused(tmp_path, capsys):
    out = tmp_path / "fig4.geojson"
    code, stdout, err = run(["words", "--regions", "--size", "12x12", "--max-iter", "200", "--out", str(out)],
                            capsys)
    assert code == 0, err
    assert out.exists() and "words" in stdout
    code, _, err = run(["words", "--regions", "--size", "1x12", "--out", str(tmp_path / "x.geojson")], capsys)
    assert code == 2 and "--size with --regions must be 2 to 8192 pixels a side" in err


def _pixels_line(out):
    """The line of a scan's summary that gives its grid ("N x M pixels ..."); the basis
    line ("basis: numerical ...") follows it."""
    return next(line for line in out.splitlines() if " pixels" in line and " x " in line)


def test_a_zoom_without_size_gets_square_pixels_and_the_default_view_its_grid(tmp_path, capsys):
    code, out, err = run(["scan", "--e", "0.04:0.065", "--u", "0.92:0.945", "--max-iter", "100",
                          "--out", str(tmp_path / "z.nc")], capsys)
    assert code == 0, err
    assert _pixels_line(out).startswith("500 x 500 pixels")
    code, out, err = run(["scan", "--e", "0:0.5", "--max-iter", "50", "--out", str(tmp_path / "h.nc")], capsys)
    assert _pixels_line(out).startswith("167 x 500 pixels")   # 0.5 x 1.5: square pixels
    code, out, err = run(["scan", "--max-iter", "50", "--out", str(tmp_path / "d.nc")], capsys)
    assert _pixels_line(out).startswith("500 x 350 pixels")   # the paper's Fig. 4 grid
    code, out, err = run(["scan", "--e", "0.04:0.065", "--u", "0.92:0.945", "--size", "50x20",
                          "--max-iter", "50", "--out", str(tmp_path / "s.nc")], capsys)
    assert _pixels_line(out).startswith("50 x 20 pixels")


# --------------------------------------------------------------------------- #
# Commands that name what happened                                            #
# --------------------------------------------------------------------------- #


def test_figures_summary_names_the_rows_that_differ(tmp_path, capsys, monkeypatch):
    from stairbounce import figures

    def fake(settings, names, on_start=None, on_done=None):
        settings.out.mkdir(parents=True, exist_ok=True)
        rows = [figures.Row("box-counting dimension, boxes 1..64 px", "D = 1.324", "D = 1.47 [1.45, 1.49]",
                            verdict="differs", why="+0.146: the paper's 1.324 is outside our interval"),
                figures.Row("slope", "r > 0.99", "r = 0.999", verdict="agrees"),
                figures.Row("study", "D = 1.324", "D = 1.55", verdict="not comparable", why="another set")]
        res = [figures.Result("fig6", "Box-counting dimension", [], rows)]
        for r in res:
            on_done(r)
        return res

    monkeypatch.setattr(figures, "make_figures", fake)
    code, out, err = run(["figures", "--only", "fig6", "--out", str(tmp_path / "f"), "--no-cache"], capsys)
    assert code == 0, err
    assert "verdicts: 1 agrees, 1 differs, 1 not comparable" in out
    assert "the 1 row that differs from the paper:" in out
    assert ("  fig6: box-counting dimension, boxes 1..64 px (paper D = 1.324; here D = 1.47 [1.45, 1.49]): "
            "+0.146: the paper's 1.324 is outside our interval") in out
    assert "slope" not in out and "study" not in out


def test_progress_lines_off_a_terminal(monkeypatch):
    import io

    from stairbounce._progress import LineProgress, log_interval

    monkeypatch.setenv("STAIRBOUNCE_PROGRESS_INTERVAL", "0.02")
    assert log_interval() == 0.02
    stream = io.StringIO()
    with LineProgress(stream, log_interval(), "rows") as bar:
        task = bar.add_task("scan rows", total=10)
        bar.update(task, completed=4)
        time.sleep(0.2)
    lines = stream.getvalue().splitlines()
    assert len(lines) >= 2 and bar.lines == len(lines)
    assert re.fullmatch(r"stairbounce: scan rows: 4/10 rows \(40%\), \d+ s elapsed, about \d+ s left", lines[-1])
    quiet = io.StringIO()
    with LineProgress(quiet, 60.0) as bar:   # work shorter than one interval writes nothing
        bar.add_task("x", total=1)
    assert quiet.getvalue() == ""
    for bad in ("", "nope", "-1", "0"):
        monkeypatch.setenv("STAIRBOUNCE_PROGRESS_INTERVAL", bad)
        assert log_interval() == 10.0


def test_a_command_off_a_terminal_prints_progress_lines(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("STAIRBOUNCE_PROGRESS_INTERVAL", "0.01")
    from stairbounce._progress import LineProgress

    # a scan whose rows are slow enough to be seen: each block waits a little
    original = LineProgress.update

    def slow_update(self, *a, **k):
        original(self, *a, **k)
        time.sleep(0.03)

    monkeypatch.setattr(LineProgress, "update", slow_update)
    code, out, err = run(["scan", "--e", "0.04:0.065", "--u", "0.92:0.945", "--size", "40x40",
                          "--max-iter", "100", "--out", str(tmp_path / "p.nc")], capsys)
    assert code == 0
    lines = [x for x in err.splitlines() if x.startswith("stairbounce: scan rows: ")]
    assert len(lines) >= 3, err
    assert re.match(r"stairbounce: scan rows: \d+/40 \(\d+%\), \d+ s elapsed", lines[-1])


def test_progress_bar_is_a_ready_made_callback(capsys, monkeypatch):
    monkeypatch.setenv("STAIRBOUNCE_PROGRESS_INTERVAL", "0.01")
    seen = []
    with sb.progress_bar("scan rows") as progress:
        def slow(done, total):
            seen.append((done, total))
            progress(done, total)
            time.sleep(0.02)

        ds = sb.scan(e=(0.04, 0.065, 20), u=(0.92, 0.945, 20), max_iter=100, progress=slow)
    assert ds.word_length.equals(sb.scan(e=(0.04, 0.065, 20), u=(0.92, 0.945, 20), max_iter=100).word_length)
    assert seen[0] == (0, 20) and seen[-1] == (20, 20)
    err = capsys.readouterr().err
    assert re.search(r"stairbounce: scan rows: \d+/20 \(\d+%\)", err), err
    assert "progress_bar" in sb.__all__ and "STAIRBOUNCE_PROGRESS_INTERVAL" in sb.progress_bar.__doc__
