"""`stairbounce figures`: the whole paper at reduced resolution, with its report."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from PIL import Image

from stairbounce import figures as F
from stairbounce.cli import main
from stairbounce.fractal import box_dimension, boundary
from stairbounce.plane import scan, tongue_mask

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
    assert row["agrees"] is True


def test_rerun_reads_the_cache(made, tmp_path, monkeypatch):
    out, cache, _ = made
    before = sorted(p.name for p in cache.iterdir())
    assert any(n.startswith("scan-") for n in before) and any(n.startswith("orbits-") for n in before)
    real = F._cached
    calls = []

    def spy(settings, kind, inputs, compute):
        calls.append(kind)
        return real(settings, kind, inputs, lambda: pytest.fail("recomputed a cached scan"))

    monkeypatch.setattr(F, "_cached", spy)
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
