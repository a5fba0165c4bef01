"""The report's basis column (issue 36, item 8): every row proven or
numerical, and the rows the certifier proves, re-verified by the checker."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import pytest

import stairbounce
from stairbounce import figures as F
from stairbounce.plane import scan
from stairbounce.structure.verdict import Verdict

CERTIFY = sys.modules["stairbounce.structure.certify"]


def _settings(tmp_path, scale):
    return F.Settings(out=Path(tmp_path), scale=scale)


def test_row_basis_is_checked():
    assert F.Row("q", "p", "m", True).basis == "numerical"
    assert F.Row("q", "p", "m", True, basis="proven", proof="Theorem").basis_text() == "proven: Theorem"
    with pytest.raises(ValueError, match="basis must be one of"):
        F.Row("q", "p", "m", True, basis="certain")
    with pytest.raises(ValueError, match="by what"):
        F.Row("q", "p", "m", True, basis="proven")


def test_depth_follows_the_scale(tmp_path):
    assert F.proven._certify_depth(_settings(tmp_path, 1.0)) == F.proven.CERTIFY_DEPTH
    assert F.proven._certify_depth(_settings(tmp_path, 0.5)) == F.proven.CERTIFY_DEPTH - 1
    assert F.proven._certify_depth(_settings(tmp_path, 0.01)) == 4
    assert F.proven._certify_depth(_settings(tmp_path, 16)) == 12


def test_tongue_row_is_proven(tmp_path):
    row = F.plane._tongue_proof_row(_settings(tmp_path, 0.05))
    assert row.basis == "proven" and "re-verified by sb.verify" in row.proof
    assert row.verdict == "agrees", row
    n = int(row.measured.split(" boxes")[0])
    assert n > 8 * 30  # at least a column per halving towards each end, per tongue
    assert f"{n} proven (n, 0^inf) by certify_box, 0 not" in row.measured
    assert "0 of 45 boxes straddling" in row.measured


def _window_rows(tmp_path, name, e, u, scale=1 / 32):
    s = _settings(tmp_path, scale)
    n = s.px(400)
    ds = scan(e=(e[0], e[1], n), u=(u[0], u[1], n))
    certified = F.proven._certified_atlas(s, name, e, u, perimeter=True)
    est = type("Fit", (), {"dimension": 1.4})()
    return certified, F.proven._proven_area_row(s, name, e, u, ds, certified), F.proven._border_bracket_row(s, name, certified, est)


def test_window_rows_are_proven_and_their_verdicts_computed(tmp_path):
    (e, u), _ = F.DIMENSION_WINDOWS["fig7"]
    certified, area, bracket = _window_rows(tmp_path, "fig7", e, u)
    atlas, depth = certified[0], certified[1]
    assert depth == 4
    for row in (area, bracket):
        assert row.basis == "proven" and "re-verified by sb.verify" in row.proof, row
        assert f"depth {depth}" in row.quantity
    assert area.verdict == "agrees", area
    # the stated numbers are the atlas's: the share rounded down, the word count exact
    share = math.floor(1000 * atlas.fraction()["word"]) / 10
    assert f"at least {share:.1f}% of the window proven to slide" in area.measured
    assert f"at least {len(atlas.words())} distinct words" in area.measured
    # the row is the paper's perimeter: the sliding border's counts, k = 3 .. depth
    counts = atlas.border_box_counts(border="sliding")
    assert "sliding region's border" in bracket.quantity
    for k in range(3, depth + 1):
        assert f"k = {k}: {counts.lower[k]}..{counts.upper[k]}" in bracket.measured
    # at depth 4 no cell of k >= 3 holds proven sliding and non-sliding boxes; the proven
    # points inside the undecided boxes give every one of those scales a lower count, so
    # the bracket is finite and the verdict is taken from it (the row says how many points)
    assert (atlas.border_box_counts(witnesses=False).lower[3:] == 0).all()
    assert (counts.lower[3:] > 0).all() and counts.attrs["witnesses"] > 0
    assert f"{counts.attrs['witnesses']} proven points inside undecided boxes" in bracket.measured
    r = atlas.perimeter_bracket(verify=False)
    assert r["finite"] is not None and r["across"] is not None
    assert (bracket.verdict, bracket.why) == CERTIFY.slope_verdict(1.4, r["across"])
    assert "re-verified by the checker" in bracket.proof
    assert "max_iter -> infinity" in bracket.measured and "limit of small scales" in bracket.measured


def test_the_perimeter_row_differs_outside_its_bracket_across_the_scales(tmp_path):
    # depth 8: lower counts > 0 at k = 3 .. 5, so a finite bracket, and a verdict either way
    (e, u), _ = F.DIMENSION_WINDOWS["fig7"]
    certified = F.proven._certified_atlas(_settings(tmp_path, 0.5), "fig7", e, u, perimeter=True)
    atlas = certified[0]
    assert certified[1] == 8 and certified[3] == "proven"
    r = atlas.perimeter_bracket(verify=False)
    a, b, lo, hi = r["across"]
    assert 3 <= a < b <= 8 and math.isfinite(lo) and math.isfinite(hi)
    for d, verdict in ((hi + 0.5, "differs"), (lo - 0.5, "differs"), ((lo + hi) / 2, None)):
        row = F.proven._border_bracket_row(None, "fig7", certified, type("Fit", (), {"dimension": d})())
        expected = verdict or ("not comparable" if lo <= 1 and hi >= 2 else "agrees")
        assert row.verdict == expected, row
        assert f"{d:.3f}" in row.why
    if lo <= 1 and hi >= 2:  # today's bracket: too wide to decide, said so
        assert "too wide to decide" in row.why


def test_a_window_from_e_0_is_certified_from_the_checkers_domain(tmp_path):
    # the Fig. 6 window starts at e = 0: it is certified as it is, its boxes on e = 0
    # certified like the others (the corners form on [0, e1], the checker's domain
    # 0 <= e0), and every certificate of the atlas passes the checker, so the rows
    # are proven
    (e, u), _ = F.DIMENSION_WINDOWS["fig6"]
    assert e[0] == 0.0
    certified, area, bracket = _window_rows(tmp_path, "fig6", e, u)
    atlas = certified[0]
    assert atlas.window[0] == tuple(e)
    b = atlas.boxes
    at_zero = b["e0"].values == 0.0
    assert at_zero.any() and (b["status"].values[at_zero] != F.proven._undecided_code()).any()
    assert "range" not in set(b["reason"].values.tolist())
    assert area.measured.startswith(f"[0, {e[1]:g}] x") and "2^-53" not in area.proof
    assert area.basis == bracket.basis == "proven"
    assert area.verdict == "agrees"
    assert bracket.verdict == "not comparable"  # depth 4: no finite bracket (the fig7 test says why)


def test_rejected_certificates_fail_the_rows(tmp_path, monkeypatch):
    """The checker has the last word: if it rejects, no row is proven or agrees."""
    def reject(obj):
        return Verdict(False, "word", None, "tampered", checked=1, rejected=1)

    monkeypatch.setattr(stairbounce, "verify", reject)
    row = F.plane._tongue_proof_row(_settings(tmp_path, 0.05))
    assert row.verdict == "differs" and row.basis == "numerical" and "NOT proven" in row.proof
    (e, u), _ = F.DIMENSION_WINDOWS["fig7"]
    _, area, bracket = _window_rows(tmp_path, "fig7", e, u)
    for r in (area, bracket):
        assert r.verdict == "differs" and r.basis == "numerical" and "rejected" in r.why


def test_a_wrong_word_fails_the_tongue_row(tmp_path, monkeypatch):
    """The theorem checks the certifier: a box of tongue 3 said to be another word differs."""
    real = stairbounce.certify_box

    def shifted(e, u, max_iter=1000):
        c = real(e=e, u=u, max_iter=max_iter)
        if c.status == "word" and tuple(c.word.letters) == (3,):
            return real(e=(0.18, 0.1801), u=(0.62, 0.6201), max_iter=max_iter)  # (1, 1, 1, 2, 0^inf)
        return c

    monkeypatch.setattr(stairbounce, "certify_box", shifted)
    row = F.plane._tongue_proof_row(_settings(tmp_path, 0.05))
    assert row.verdict == "differs" and "not proven (n, 0^inf)" in row.why


def test_report_shows_the_basis(tmp_path):
    s = _settings(tmp_path, 0.05)
    rows = [F.Row("a", "p", "m", True), F.Row("b", "p", "m", True, basis="proven", proof="Theorem 9")]
    paths, _ = F.write_report([F.Result("fig1", "t", rows=rows, caption="c")], s, merge=False)
    md = (tmp_path / "report.md").read_text()
    html = (tmp_path / "report.html").read_text()
    manifest = json.loads((tmp_path / "manifest.json").read_text())
    assert "| quantity | paper | here | verdict | basis |" in md
    assert "| **proven: Theorem 9** |" in md and "| numerical |" in md
    assert F.BASIS_CRITERION[:40] in md and "1 proven, 1 numerical" in md
    assert "<th>basis</th>" in html and "proven: Theorem 9" in html
    got = [(x["basis"], x["proof"]) for x in manifest["figures"][0]["rows"]]
    assert got == [("numerical", ""), ("proven", "Theorem 9")]
    # a manifest of an earlier version (no basis) reads back as numerical
    for x in manifest["figures"][0]["rows"]:
        del x["basis"], x["proof"]
    (tmp_path / "manifest.json").write_text(json.dumps(manifest))
    assert [x.basis for x in F.read_manifest(tmp_path)[0].rows] == ["numerical", "numerical"]
