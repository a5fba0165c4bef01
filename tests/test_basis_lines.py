"""Issue 43, item 4: `word`, `scan` and `cascade` print their basis (proven or
numerical, with the criterion), as docs/guide/proven.md says every printed
statement does."""

from __future__ import annotations

import pytest

from stairbounce.cli import main


def _run(args, capsys):
    with pytest.raises(SystemExit) as exc:
        main(args)
    out, err = capsys.readouterr()
    return exc.value.code, out, err


@pytest.mark.parametrize("e, u, basis", [
    ("0.1", "0.5", "basis:   proven at this point"),  # (1, 0^inf), certify_box proves it
    ("0.3", "0.7", "basis:   proven (Corollary 2.1"),  # above the bound: impossible
    # a point on the border of member 26 of (1^k, 0^inf) at e = 0.02: the float orbit
    # does not slide, certify_box leaves it undecided
    ("0.02", "0.6925656346469531", "basis:   numerical (the float64 orbit"),
])
def test_word_states_its_basis(e, u, basis, capsys):
    code, out, err = _run(["word", "--e", e, "--u", u], capsys)
    assert code == 0, err
    lines = [ln for ln in out.splitlines() if ln.startswith("basis:")]
    assert len(lines) == 1 and lines[0].startswith(basis)


def test_word_basis_is_proven_no_slide_within_where_certify_box_proves_it(capsys):
    # near u_1 at e = 0.02 the orbit lands once per step for long: no slide in 50 steps, proven
    code, out, _ = _run(["word", "--e", "0.02", "--u", "0.69310328", "--max-iter", "50"], capsys)
    assert code == 0 and "basis:   proven at this point" in out and "no slide within the first 50 steps" in out


def test_scan_states_its_basis(tmp_path, capsys):
    code, out, err = _run(["scan", "--e", "0:1", "--u", "0:1.5", "--size", "12x12",
                           "--png", str(tmp_path / "s.png")], capsys)
    assert code == 0, err
    assert out.strip().splitlines()[-1].startswith("basis: numerical (each pixel centre's float64 orbit")
