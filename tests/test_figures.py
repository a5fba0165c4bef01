"""`stairbounce figures`: the whole paper at reduced resolution, with its report."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from PIL import Image

from stairbounce import figures as F
from stairbounce.cli import main
from stairbounce.dimension import box_dimension, boundary
from stairbounce.plane import scan, tongue_mask

from ._figures import patch_figures

SCALE = 0.12  # 60 x 42 for Fig. 4, 60 px for Figs. 6/7, 360 orbit columns


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """The full set, made once through the command line."""
    out = tmp_path_factory.mktemp("figures")
    cache = tmp_path_factory.mktemp("cache")
    with pytest.raises(SystemExit) as exc:
        main(["figures", "--out", str(out), "--scale", str(SCALE), "--dpi", "40",
              "--cache-dir", str(cache)])
    assert exc.value.code == 0
    return out, cache, json.loads((out / "manifest.json").read_text())


def test_every_figure_is_a_valid_image(made):
    out, _, manifest = made
    names = [f["name"] for f in manifest["figures"]]
    assert names == list(F.FIGURES)
    for f in manifest["figures"]:
        assert f["error"] is None, f
        for name in f["files"]:
            with Image.open(out / name) as im:
                im.verify()
            with Image.open(out / name) as im:
                assert im.size[0] > 100 and im.size[1] > 100
    assert not [p for p in out.iterdir() if ".part" in p.name]  # nothing half-written


def test_report_rows_are_the_computed_numbers(made):
    """The report's numbers come from the computation, not from literals:
    recompute two of them independently and find them in report.md."""
    out, _, manifest = made
    report = (out / "report.md").read_text()
    html = (out / "report.html").read_text()
    by_name = {f["name"]: f for f in manifest["figures"]}

    # Fig. 4: fraction of word-length-1 pixels inside the analytic tongues
    n_e, n_u = by_name["fig4"]["params"]["size"]
    ds = scan(e=(0, 1, n_e), u=(0, 1.5, n_u))
    E, U = np.meshgrid(ds.e.values, ds.u.values)
    wl1 = ds.word_length.values == 1
    frac = 100 * tongue_mask(E, U, 200)[wl1].mean()
    assert f"{frac:.2f}% of word-length-1 pixels" in report

    # Fig. 6: D of the border at the recorded resolution and fit range
    p = by_name["fig6"]["params"]
    res = p["resolution"]
    region = scan(e=(*p["e"], res), u=(*p["u"], res)).status.values == 0
    est = box_dimension(boundary(region), fit_range=tuple(p["fit_range"]))
    assert p["D"] == pytest.approx(est.dimension, abs=1e-12)
    assert f"D = {est.dimension:.3f}" in report
    assert "D = 1.324, r &gt; 0.99" in html
    for f in manifest["figures"]:
        assert f["seconds"] > 0
        assert f"## {f['name']}:" in report


def test_fig8_rows_count_branches(made):
    _, _, manifest = made
    row = next(f for f in manifest["figures"] if f["name"] == "fig8")["rows"][0]
    counts = [int(c) for c in re.findall(r"n=\d+: (\d+)", row["measured"])]
    assert counts == [1, 2, 3, 4, 5, 6]
    assert row["agrees"] is True and row["verdict"] == "agrees"


def test_rerun_reads_the_cache(made, tmp_path, monkeypatch):
    out, cache, _ = made
    before = sorted(p.name for p in cache.iterdir())
    assert any(n.startswith("scan-") for n in before) and any(n.startswith("orbits-") for n in before)
    real = F.settings._cached
    calls = []

    def spy(settings, kind, inputs, compute):
        calls.append(kind)
        return real(settings, kind, inputs, lambda: pytest.fail("recomputed a cached scan"))

    patch_figures(monkeypatch, "_cached", spy)
    settings = F.Settings(out=tmp_path, scale=SCALE, dpi=40, cache_dir=cache)
    res = F.make_figures(settings, only=["fig4", "fig5e"])
    assert [r.error for r in res] == [None, None] and calls == ["scan", "scan"]
    assert sorted(p.name for p in cache.iterdir()) == before


def test_a_failing_figure_does_not_stop_the_others(tmp_path, monkeypatch, capsys):
    def broken(settings):
        raise RuntimeError("boom")

    monkeypatch.setitem(F.FIGURES, "fig2", broken)
    with pytest.raises(SystemExit) as exc:
        main(["figures", "--out", str(tmp_path), "--only", "fig1,fig2,fig3", "--no-cache",
              "--dpi", "40"])
    assert exc.value.code == 1
    assert (tmp_path / "fig1.png").exists() and (tmp_path / "fig3.png").exists()
    assert "RuntimeError: boom" in (tmp_path / "report.md").read_text()
    assert "failed: fig2" in capsys.readouterr().err


def test_only_selects_and_formats(tmp_path):
    assert F.select(["fig5"]) == ["fig5a", "fig5b", "fig5c", "fig5d", "fig5e"]
    assert F.select(["fig9", "fig1"]) == ["fig1", "fig9"]
    res = F.make_figures(F.Settings(out=tmp_path, fmt="svg", dpi=40), only=["fig3"])
    assert res[0].files == ["fig3.svg"] and (tmp_path / "fig3.svg").read_text().startswith("<?xml")


@pytest.mark.parametrize(
    "args,needle",
    [
        (["--only", "fig10"], "unknown figure 'fig10'"),
        (["--format", "jpg"], "--format must be png, pdf or svg"),
        (["--dpi", "0"], "dpi must be an integer in [10, 1200]"),
        (["--scale", "0"], "scale must be in [0.01, 16]"),
        (["--max-iter", "0"], "--max-iter must be an integer >= 1"),
    ],
)
def test_bad_input(args, needle, tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["figures", "--out", str(tmp_path / "x"), *args])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and needle in err and len(err.strip().splitlines()) == 1


# --------------------------------------------------------------------------- #
# The report: a verdict on every row, captions, partial runs merged            #
# --------------------------------------------------------------------------- #


def test_every_row_has_a_verdict_and_every_figure_a_caption(made):
    """No blank verdict: a blank cell reads as "not checked" (issue 15)."""
    out, _, manifest = made
    report = (out / "report.md").read_text()
    for f in manifest["figures"]:
        assert len(f["caption"]) > 80, f["name"]
        assert f["rows"], f["name"]
        for row in f["rows"]:
            assert row["verdict"] in F.VERDICTS, (f["name"], row)
            if row["verdict"] != "agrees":
                assert row["why"], (f["name"], row)  # by how much, or why not comparable
    assert "no verdict" not in report
    for line in report.splitlines():
        if line.startswith("| ") and not line.startswith("| quantity"):
            assert "|  |" not in line and not line.rstrip().endswith("| |"), line
    # the automatic-range rows: "differs" exactly when the paper's value is
    # outside their drift-covering interval (at the paper's 500 px it is, for
    # both windows: docs/guide/dimension-study.md), "not comparable" when that interval leaves [1, 2]
    # (a failed fit, as at this small scale), and they say which scale they
    # leave out
    by_name = {f["name"]: f for f in manifest["figures"]}
    for name in ("fig6", "fig7"):
        auto = next(r for r in by_name[name]["rows"] if "automatic" in r["quantity"])
        lo, hi = (float(x) for x in re.search(r"interval \[(\S+?), (\S+?)\]", auto["measured"]).groups())
        paper = F.DIMENSION_WINDOWS[name][1]
        expected = ("not comparable" if not (1 <= lo and hi <= 2)
                    else "agrees" if lo <= paper <= hi else "differs")
        assert auto["verdict"] == expected
        assert "pixel scale" in auto["why"]
    assert F.CRITERION[:40] in report
    assert report.rstrip().splitlines()[-1].startswith("Tally: ")


def test_row_verdicts():
    assert F.Row("q", "p", "m", True).verdict == "agrees"
    assert F.Row("q", "p", "m", False).verdict == "differs"
    assert F.Row("q", "p", "m", verdict="differs", why="+0.1").agrees is False
    assert F.Row("q", "p", "m").verdict_text() == "no verdict"
    with pytest.raises(ValueError, match="verdict must be one of"):
        F.Row("q", "p", "m", verdict="maybe")
    # the paper's value inside the interval agrees; outside it differs by the signed gap
    assert F.rows._compare(1.40, 1.324, ci=(1.30, 1.50))[0] == "agrees"
    assert F.rows._compare(1.53, 1.403, ci=(1.52, 1.55)) == (
        "differs", "+0.127: the paper's 1.403 is outside our interval [1.520, 1.550]")


def test_partial_run_keeps_the_full_report(made, tmp_path, capsys):
    """`figures --only fig3` into a folder with a full run merges by figure."""
    import shutil

    out, cache, manifest = made
    folder = tmp_path / "figs"
    shutil.copytree(out, folder)
    with pytest.raises(SystemExit) as exc:
        main(["figures", "--out", str(folder), "--only", "fig3", "--dpi", "40",
              "--cache-dir", str(cache)])
    assert exc.value.code == 0
    said = capsys.readouterr().out
    others = len(F.FIGURES) - 1
    assert f"keeps {others} figures of the earlier run" in said and "merged by figure" in said
    merged = json.loads((folder / "manifest.json").read_text())
    assert [f["name"] for f in merged["figures"]] == list(F.FIGURES)
    assert len(merged["kept_from_earlier_run"]) == others and "fig3" not in merged["kept_from_earlier_run"]
    report = (folder / "report.md").read_text()
    assert "## fig9:" in report and "kept from an earlier run" in report
    # an empty folder: nothing to keep, nothing said
    with pytest.raises(SystemExit):
        main(["figures", "--out", str(tmp_path / "new"), "--only", "fig3", "--dpi", "40"])
    assert "the report keeps" not in capsys.readouterr().out


def test_no_blank_line_on_stderr_when_not_a_terminal(tmp_path):
    import subprocess
    import sys

    exe = [sys.executable, "-c", "from stairbounce.cli import main; main()"]
    run = subprocess.run([*exe, "figures", "--out", str(tmp_path), "--only", "fig3", "--dpi", "40",
                          "--no-cache"], capture_output=True, text=True)
    assert run.returncode == 0
    assert run.stderr.strip() and "" not in run.stderr.splitlines(), repr(run.stderr)
    assert "wrote 1 figure and" in run.stdout  # singular


# --------------------------------------------------------------------------- #
# The figures themselves: the defects a referee saw, where a test can see them #
# --------------------------------------------------------------------------- #


@pytest.fixture(scope="module")
def drawn(made, tmp_path_factory):
    """Every figure, kept as a matplotlib Figure after it is saved at 60 dpi (the
    computed arrays read from ``made``'s cache: only the drawing is done again)."""
    import matplotlib

    matplotlib.use("Agg")
    out = tmp_path_factory.mktemp("drawn")
    study = out / "border_dimension.json"
    # a made-up study result (not a measurement): the figure must show what the file says
    study.write_text(json.dumps({
        "fig6": {"dimension": 1.4567, "ci95": [1.41, 1.50], "method": "test fixture",
                 "details": "-"}}))
    figs = {}
    real = F.settings._save

    def keep(fig, settings, name):
        figs[name] = fig
        return real(fig, settings, name)

    mp = pytest.MonkeyPatch()
    patch_figures(mp, "_save", keep)
    try:
        settings = F.Settings(out=out, scale=SCALE, dpi=60, border_dimension=study, cache_dir=made[1])
        results = F.make_figures(settings)
    finally:
        mp.undo()
    assert [r.error for r in results] == [None] * len(F.FIGURES)
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    for fig in figs.values():
        FigureCanvasAgg(fig)  # closed by pyplot: an Agg canvas to measure the text on
        fig.canvas.draw()
    return figs, {r.name: r for r in results}


def _texts(fig):
    return [t for t in fig.findobj(matplotlib_text()) if t.get_visible() and t.get_text().strip()]


def matplotlib_text():
    from matplotlib.text import Text

    return Text


def test_no_text_outside_the_figure_and_no_offset_notation(drawn):
    figs, _ = drawn
    for name, fig in figs.items():
        r = fig.canvas.get_renderer()
        w, h = fig.get_size_inches()
        tight = fig.get_tightbbox(r)  # everything drawn, in inches
        assert tight.x0 >= -0.01 and tight.y0 >= -0.01, (name, tight)
        assert tight.x1 <= w + 0.01 and tight.y1 <= h + 0.01, (name, tight, (w, h))
        for t in fig.texts:
            ext = t.get_window_extent(r)
            assert fig.bbox.contains(ext.x0, ext.y0) and fig.bbox.contains(ext.x1, ext.y1), name
        for ax in fig.axes:
            # "1e-5+1" above an axis: matplotlib's offset text
            assert not ax.yaxis.get_offset_text().get_text(), (name, ax.get_title())
            assert not ax.xaxis.get_offset_text().get_text(), (name, ax.get_title())


def test_infinity_is_a_real_superscript(drawn):
    """(n, 0^inf) is written with mathtext's raised infinity, never a caret."""
    figs, _ = drawn
    seen = 0
    for name, fig in figs.items():
        for t in _texts(fig):
            s = t.get_text()
            assert "\u221e" not in s and "0^inf" not in s, (name, s)
            if "\\infty" in s:
                assert s.count("$") >= 2 and ("0^\\infty" in s or "0^{\\infty}" in s), (name, s)
                seen += 1
    assert seen >= 3  # Fig. 1's word, Fig. 3's title and legend, the tongue legends


def test_figs_4_and_5_share_one_discrete_colour_scale(drawn):
    """The same word length has the same colour in all six panels, and
    lengths 1..6 are told apart (they were near-identical purples)."""
    figs, _ = drawn
    names = ["fig4", "fig5a", "fig5b", "fig5c", "fig5d", "fig5e"]
    lengths = np.array([1, 2, 3, 4, 5, 6, 7, 8, 11, 40, 600])
    colours = []
    for name in names:
        im = figs[name].axes[0].get_images()[0]
        colours.append(im.to_rgba(lengths.astype(float)))  # through the image's own norm
        bar = figs[name].axes[1]
        assert "white: no periodic sliding solution within max_iter = 1000" in bar.get_ylabel()
    for c in colours[1:]:
        assert np.array_equal(c, colours[0])
    first = [tuple(c) for c in colours[0][:6]]  # 1, 2, 3, 4, 5, 6
    assert len(set(first)) == 6
    assert tuple(colours[0][5]) == tuple(colours[0][6])  # 6 and 7: one class
    assert tuple(colours[0][0][:3]) == (0.0, 0.0, 0.0)  # length 1 black, as in the paper


def test_fig5_titles_and_legend_off_the_data(drawn):
    figs, _ = drawn
    for letter in "abcde":
        fig = figs[f"fig5{letter}"]
        ax = fig.axes[0]
        assert ax.get_title().startswith(f"Fig. 5{letter}: [")
        legend = ax.get_legend()
        if legend is not None:
            r = fig.canvas.get_renderer()
            assert legend.get_window_extent(r).y1 <= ax.get_window_extent(r).y0  # below the axes


def test_fig3_labels_sit_on_white_inside_the_axes(drawn):
    from stairbounce.plane import tongue_mask

    figs, _ = drawn
    fig = figs["fig3"]
    ax = fig.axes[0]
    r = fig.canvas.get_renderer()
    labels = [t for t in ax.texts if t.get_text().startswith("n = ")]
    assert {t.get_text() for t in labels} >= {"n = 1", "n = 2", "n = 3", "n = 4", "n = 5"}
    inv = ax.transData.inverted()
    for t in labels:
        ext = t.get_window_extent(r)
        assert ax.get_window_extent(r).contains(ext.x0, ext.y0)
        assert ax.get_window_extent(r).contains(ext.x1, ext.y1), t.get_text()
        if t.get_text() == "n = 1":
            continue
        # every corner and the centre of the label's box lie outside the tongues
        pts = inv.transform([(ext.x0, ext.y0), (ext.x1, ext.y1), (ext.x0, ext.y1),
                             (ext.x1, ext.y0), ((ext.x0 + ext.x1) / 2, (ext.y0 + ext.y1) / 2)])
        assert not tongue_mask(pts[:, 0], pts[:, 1], 50).any(), t.get_text()
        assert sum(matplotlib_colour(t.get_color())) < 1.0  # dark text on white


def matplotlib_colour(c):
    from matplotlib.colors import to_rgb

    return to_rgb(c)


def test_fig2_colour_bar_legend_and_y1(drawn):
    figs, results = drawn
    fig = figs["fig2"]
    ax = fig.axes[0]
    assert len(fig.axes) == 2 and fig.axes[1].get_ylabel() == "iterate index n"
    labels = ax.get_legend_handles_labels()[1]
    assert any(label.startswith("y = 1") for label in labels)
    handle = ax.get_legend_handles_labels()[0][labels.index("iterates (colour: index n)")]
    assert matplotlib_colour(handle.get_color()) == pytest.approx((0.45, 0.45, 0.45))
    assert "schematics" in results["fig2"].caption and "schematics" in results["fig1"].caption


def test_figs_6_and_7_square_and_unaliased_with_the_study(drawn):
    figs, results = drawn
    for name in ("fig6", "fig7"):
        fig = figs[name]
        ax = fig.axes[0]
        r = fig.canvas.get_renderer()
        box = ax.get_window_extent(r)
        (e0, e1), (u0, u1) = F.DIMENSION_WINDOWS[name][0]
        # drawn with the window's own proportions (both windows are square to 2%)
        assert box.width / box.height == pytest.approx((e1 - e0) / (u1 - u0), rel=0.02)
        shown = ax.get_images()[0].get_array()
        assert shown.shape[0] <= box.height + 1 and shown.shape[1] <= box.width + 1
        text = "\n".join(t.get_text() for t in fig.texts)
        assert "fit range: boxes 1-" in text and "our reading of the paper" in text
        assert f"paper: D = {F.DIMENSION_WINDOWS[name][1]}" in text
    assert "D = 1.457 [1.410, 1.500] with its drift, test fixture" in "\n".join(t.get_text() for t in figs["fig6"].texts)
    assert "no study result" in "\n".join(t.get_text() for t in figs["fig7"].texts)
    row = next(r for r in results["fig6"].rows if r.quantity.startswith("dimension study"))
    assert row.verdict == "differs" and row.why.startswith("+0.133")


def test_plot_border_keeps_a_one_pixel_line_connected():
    """An image with more pixels than the axes is reduced by "any" blocks:
    a one-pixel diagonal stays a connected chain, no gaps."""
    import matplotlib.pyplot as plt

    from stairbounce.plot import plot_border

    img = np.eye(600, dtype=bool)
    fig, ax = plt.subplots(figsize=(2, 2), dpi=100)
    plot_border(img, ax=ax)
    shown = ax.get_images()[0].get_array()
    assert shown.shape[0] < 600 and np.array_equal(np.asarray(shown), np.eye(shown.shape[0], dtype=bool))
    plt.close(fig)


def test_border_dimension_loader(tmp_path):
    assert F.load_border_dimension(tmp_path / "absent.json") is None
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"fig6": {"dimension": 1.4, "ci95": [1.5, 1.3], "method": "m"}}))
    with pytest.raises(ValueError, match="border_dimension: .*bad.json"):
        F.load_border_dimension(bad)
    bad.write_text("{not json")
    with pytest.raises(ValueError, match="is not a dimension study result"):
        F.load_border_dimension(bad)
    # provenance keys beside the windows are not windows
    good = tmp_path / "good.json"
    good.write_text(json.dumps({"fig6": {"dimension": 1.5, "ci95": [1.49, 1.51], "method": "m"},
                                "generated_by": "a script", "date": "2026-11-22"}))
    assert set(F.load_border_dimension(good)) == {"fig6"}
    # the study shipped with the package loads, and its CI holds its estimate
    shipped = F.load_border_dimension()
    assert shipped is not None and {"fig6", "fig7"} <= set(shipped)
    for entry in shipped.values():
        assert entry["ci95"][0] <= entry["dimension"] <= entry["ci95"][1]


def test_fig8_legend_clear_of_the_first_grazing_and_labels_inside(drawn):
    import math

    figs, _ = drawn
    fig = figs["fig8"]
    ax = fig.axes[0]
    r = fig.canvas.get_renderer()
    legend = ax.get_legend().get_window_extent(r)
    x, y = ax.transData.transform((math.sqrt(0.5), 1.0))
    assert not legend.contains(x, y)
    labels = [t for t in ax.texts if t.get_text().startswith("n=")]
    assert [t.get_text() for t in labels][:3] == ["n=1", "n=2", "n=3"]
    axbox = ax.get_window_extent(r)
    for t in labels:
        ext = t.get_window_extent(r)
        assert axbox.x0 <= ext.x0 and ext.x1 <= axbox.x1, t.get_text()  # not under the colour bar
        assert not ext.overlaps(legend), t.get_text()


def test_fig9_one_colour_bar_and_legible_sparse_cells(drawn):
    from matplotlib.colors import to_rgb

    figs, _ = drawn
    fig = figs["fig9"]
    images = [im for ax in fig.axes for im in ax.get_images()]
    assert len(images) == 4 and len(fig.axes) == 5  # four panels, one colour bar
    assert len({(im.norm.vmin, im.norm.vmax) for im in images}) == 1
    rgb = to_rgb(images[0].cmap(images[0].norm(1.0)))
    assert 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2] < 0.75  # not pale yellow on white
    for k, ax in enumerate(fig.axes[1:4], start=1):
        assert ax.get_ylabel() == f"(y - 1) / $10^{{-{2 * k}}}$"


def _cascade_legends(ax):
    return [a for a in ax.artists if hasattr(a, "get_title")
            and a.get_title().get_text() == "cascade members (sb.cascade)"]


def test_figs_8_and_9_mark_the_cascade_members(drawn):
    """Issue 39: every panel names its cascades in a legend of its own, draws a
    tick per member (at its centre, inside the panel) and numbers the first ones."""
    figs, results = drawn
    panels = [(figs["fig8"].axes[0], F.orbits.FIG8_CASCADES)]
    panels += list(zip(figs["fig9"].axes[:4], F.orbits.FIG9_CASCADES))
    for ax, cascades in panels:
        (legend,) = _cascade_legends(ax)
        texts = [t.get_text() for t in legend.get_texts()]
        assert len(texts) == len(cascades)
        for text, (pattern, _) in zip(texts, cascades):
            assert pattern.replace("0^inf", r"0^{\infty}") in text and "exact" in text, text
        lo, hi = sorted(ax.get_xlim())
        ticks = [ln for ln in ax.lines if ln.get_marker() == "|"]
        assert ticks and all(lo <= ln.get_xdata()[0] <= hi for ln in ticks)
    # fig9's first panel: (1^k, 0^inf), k = 2..5 at e = 0.1, numbered under the branches
    ax = figs["fig9"].axes[0]
    assert [t.get_text() for t in ax.texts if t.get_text().startswith("k=")][:1] == ["k=2"]
    assert "k = 2..5 (4 members" in _cascade_legends(ax)[0].get_texts()[0].get_text()
    assert "(stairbounce.cascade" in results["fig9"].caption
    assert "(stairbounce.cascade" in results["fig8"].caption


def test_a_long_figure_says_what_it_is_doing(tmp_path):
    """`figures --only fig4 --scale 2` shows progress inside the figure, not a
    bar stuck at 0/1: the recipe reports its scan rows and its drawing."""
    notes = []
    settings = F.Settings(out=tmp_path, scale=SCALE, dpi=40, progress=notes.append)
    (res,) = F.make_figures(settings, only=["fig4"])
    assert res.error is None
    assert any(n.startswith("fig4: scan 60 x 42, row ") for n in notes)
    assert "fig4: drawing" in notes and notes[-1] == "fig4: writing fig4.png"


def test_no_legend_entry_for_a_curve_outside_the_window():
    """A window above every tongue and right of the Corollary 2.1 curve gets no
    legend; the same renderer names both curves where they cross the window."""
    import matplotlib.pyplot as plt

    from stairbounce.orbits import orbit_diagram
    from stairbounce.plane import scan
    from stairbounce.plot import plot_orbit_diagram, plot_scan

    # u in [1.2, 1.5] at e in [0.5, 1]: tongue n reaches u = 1.2 only below e = 0.03,
    # and the curve (1-e)/(2 sqrt(2e)) is below 0.5 there
    ds = scan(e=(0.5, 1.0, 20), u=(1.2, 1.5, 20), max_iter=50)
    fig, ax = plt.subplots()
    plot_scan(ds, ax=ax, overlay=("tongues", "bound"))
    assert ax.get_legend() is None
    ds = scan(e=(0.0, 0.3, 20), u=(0.3, 0.9, 20), max_iter=50)
    fig, ax = plt.subplots()
    plot_scan(ds, ax=ax, overlay=("tongues", "bound"))
    assert len(ax.get_legend().get_texts()) == 2
    # inside one tongue at e = 0.1, u in [0.75, 0.8]: neither a tongue start nor an end
    od = orbit_diagram(0.1, np.linspace(0.75, 0.8, 20), transient=20, keep=5)
    fig, ax = plt.subplots()
    plot_orbit_diagram(od, ax=ax, overlay=("tongues",))
    assert ax.get_legend() is None
    plt.close("all")


def test_compare_agrees_only_inside_the_interval():
    # the criterion stated in the report's header: the paper's number inside our interval
    assert F.rows._compare(1.40, 1.324, (1.30, 1.50))[0] == "agrees"
    # issue 24: Fig. 6 at --scale 2 gave 1.366 [1.264, 1.468]; an interval that
    # excludes the paper's value differs, whatever its distance
    verdict, why = F.rows._compare(1.366, 1.324, (1.33, 1.40))
    assert verdict == "differs" and "outside" in why and "[1.330, 1.400]" in why
    # an interval reaching below 1 (or above 2) is a failed fit, never agreement
    verdict, why = F.rows._compare(1.014, 1.324, (-0.909, 2.937))
    assert verdict == "not comparable" and "failed fit" in why


def test_ours_rows_quote_no_paper():
    row = F.rows._ours("x", "measured 3", False, "criterion")
    assert row.paper == "-" and row.quantity.startswith("ours: ") and "FAILS" in row.measured
    assert row.verdict == "not comparable"


def _slicing_row_values(row):
    d = float(re.search(r"D = (\S+?),", row.measured).group(1))
    lo, hi = (float(x) for x in re.search(r"interval \[(\S+?), (\S+?)\]", row.measured).groups())
    a, b = (float(x) for x in re.search(r"scales (\S+?)\.\.(\S+?) of the window", row.measured).groups())
    return d, (lo, hi), (a, b)


def test_the_slicing_row_is_checked_at_four_times_max_iter(tmp_path):
    """Issue 24: the slicing row of Figs. 6/7 is measured again at 4 x max_iter
    on the same lines; it states the outcome, and where the larger max_iter
    moves the local dimension the fit is cut to the converged scales and the
    verdict is the cut fit's (re-derived here from the check itself)."""
    from stairbounce.dimension import max_iter_check, sliding_classifier, slicing_dimension

    (e, u), paper = F.DIMENSION_WINDOWS["fig7"]
    for max_iter in (50, 1000):
        s = F.Settings(out=tmp_path, scale=SCALE, max_iter=max_iter)
        row = F.dimension._slicing_row(s, "fig7", e, u, paper)
        assert f"checked at max_iter {4 * max_iter}" in row.quantity
        lines = max(8, round(F.dimension.SLICING_LINES * SCALE))
        scale_min, scale_max = F.dimension.SLICING_SCALES
        a, b = (slicing_dimension(sliding_classifier(max_iter=m), (e, u), n_lines=lines,
                                  scale_min=scale_min, scale_max=scale_max, seed=0)
                for m in (max_iter, 4 * max_iter))
        check = max_iter_check(a, b)
        assert not (max_iter == 50 and check.converged)  # the check can fail, and fails at 50 (test_slicing.py)
        head = f"max_iter {max_iter} -> {4 * max_iter}: "
        if check.converged:
            assert f"{head}converged at scales {a.scales[0]:.2g}..{a.scales[1]:.2g}" in row.measured
            assert _slicing_row_values(row)[0] == pytest.approx(a.dimension, abs=5e-4)
            continue
        lo, hi = check.not_converged
        assert (f"{head}not converged at scales {lo:.2g}..{hi:.2g} (local dimensions): fitted range cut to"
                in row.measured)
        cut = check.cut(a.scales)
        if cut is None or np.count_nonzero((a.local[0] >= cut[0]) & (a.local[0] <= cut[1])) < 3:
            assert row.verdict == "not comparable" and "not converged" in row.why
            assert max_iter == 50  # 50 truncates all but the coarsest scales (tests/test_slicing.py)
            continue
        fit = a.refit(cut)
        d, interval, scales = _slicing_row_values(row)
        assert d == pytest.approx(fit.dimension, abs=5e-4)
        assert scales[0] == pytest.approx(fit.scales[0], rel=0.05) and scales[0] > lo
        assert row.verdict == F.rows._compare(fit.dimension, paper, fit.interval)[0]


def test_box_rows_are_cut_where_four_times_max_iter_moves_the_local_slope():
    """The box-counting rows' check (F.dimension._box_checked) on counts with a known
    local slope: 1.5 at every size, and at 4 x max_iter 1.5 above 4 px but
    1.9 below (as if the finer boxes saw more border): the fit 1..64 px is cut
    to 4..64 px, where both slopes are exactly 1.5."""
    from stairbounce.dimension import box_dimension_from_counts

    sizes = 2 ** np.arange(8)  # 1 .. 128 px
    counts = np.round(1e6 * sizes ** -1.5)
    more = counts.copy()
    more[:2] = np.round(counts[2] * (sizes[:2] / 4.0) ** -1.9)  # steeper below 4 px
    a = box_dimension_from_counts(sizes, counts, fit_range=(1, 64))
    b = box_dimension_from_counts(sizes, more, fit_range=(1, 64))
    fit, text, ok = F.dimension._box_checked(a, b, 1000, 4000)
    assert ok and fit.fit_range == (4, 64)
    assert "max_iter 1000 -> 4000: not converged at the local slopes of boxes 1.41..2.83 px" in text
    assert text.endswith("fitted range cut to boxes 4..64 px")
    assert fit.dimension == pytest.approx(1.5, abs=2e-3)
    # nothing moves: the fit as it was
    fit, text, ok = F.dimension._box_checked(a, a, 1000, 4000)
    assert ok and fit is a and text.endswith("converged at boxes 1..64 px")
    # the slope moves at every size but the coarsest: no fit, no verdict
    worse = np.round(counts[-2] * (sizes / 64.0) ** -1.9)
    worse_fit = box_dimension_from_counts(sizes, worse, fit_range=(1, 64))
    fit, text, ok = F.dimension._box_checked(a, worse_fit, 1000, 4000)
    assert not ok and "fewer than 3 converged box sizes" in text


def test_every_dimension_row_computed_in_the_run_states_its_max_iter_check(made):
    _, _, manifest = made
    by_name = {f["name"]: f for f in manifest["figures"]}
    for name in ("fig6", "fig7"):
        rows = [r for r in by_name[name]["rows"] if r["quantity"].startswith(("box-counting", "dimension by"))]
        assert len(rows) == 3
        for row in rows:
            assert re.search(r"max_iter 1000 -> 4000: (converged at|not converged at)", row["measured"]), row


def manifest_max_iter(manifest, name):
    return next(f["params"]["max_iter"] for f in manifest["figures"] if f["name"] == name)


def test_every_row_states_its_basis_and_the_certifier_rows_are_proven(made):
    """Each row is proven (saying by what) or numerical; the certifier's rows
    (issue 36, item 8) are proven, re-verified by sb.verify, and agree."""
    out, _, manifest = made
    report = (out / "report.md").read_text()
    assert "| quantity | paper | here | verdict | basis |" in report
    assert F.BASIS_CRITERION[:40] in report
    proven = []
    for f in manifest["figures"]:
        for row in f["rows"]:
            assert row["basis"] in F.BASES, (f["name"], row)
            if row["basis"] == "proven":
                assert row["proof"], row
                proven.append((f["name"], row["quantity"]))
                if row["quantity"].startswith("proven box counts of the sliding region's border"):
                    # the perimeter's verdict is computed: the numerical D of this small
                    # picture against the finite proven slope bracket (depth 6: with the
                    # proven points inside undecided boxes every scale has a lower count > 0)
                    m = re.search(r"this picture's fit: D = ([0-9.]+)", row["measured"])
                    lo, hi = (float(x) for x in re.search(r"the proven bracket \[([-0-9.]+), ([-0-9.]+)\]",
                                                          row["why"]).groups())
                    d = float(m.group(1))
                    want = "differs" if not lo <= d <= hi else ("not comparable" if lo <= 1 and hi >= 2 else "agrees")
                    assert row["verdict"] == want, row
                    assert "proven points inside undecided boxes" in row["measured"], row
                    assert "re-verified by the checker" in row["proof"], row
                    continue
                assert row["verdict"] == "agrees", row
    depth = F.proven._certify_depth(F.Settings(out=out, scale=SCALE))
    assert depth == 6
    names = [name for name, q in proven]
    assert ("fig3", "tongues (n, 0^inf) proven over boxes up to their tips (Theorem 3.1, n = 1..8)") in proven
    for name in ("fig5e", "fig7"):
        assert (name, f"proven sliding area and number of words (certified atlas, depth {depth})") in proven
    for name in ("fig6", "fig7"):
        assert (name, f"proven box counts of the sliding region's border and their slope (certified atlas, depth "
                      f"{depth}, class-level proofs, trapping regions, max_iter "
                      f"{manifest_max_iter(manifest, name)})") in proven
    assert names.count("fig1") == 1  # the periodic solution, proven at its point
    # nothing else: every other row is a floating-point computation
    assert len(proven) == 6
