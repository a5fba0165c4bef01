"""The release: one version (``stairbounce --version``, the package, the
build), and the files people need to use and cite it."""

from __future__ import annotations

import re
from pathlib import Path

import stairbounce as sb
from stairbounce.cli import main

import pytest


def test_version_option_prints_the_package_version_and_exits_0(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out == f"stairbounce {sb.__version__}\n"



ROOT = Path(__file__).resolve().parents[1]


def test_license_file_is_the_license_pyproject_declares():
    text = (ROOT / "LICENSE").read_text()
    assert text.startswith("BSD 3-Clause License")
    assert "stairbounce developers" in text
    assert 'license = "BSD-3-Clause"' in (ROOT / "pyproject.toml").read_text()


def test_citation_file_cites_this_version_and_the_paper():
    import yaml
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    # the keys CFF 1.2.0 requires of the software and of each reference
    assert cff["cff-version"] == "1.2.0"
    assert {"message", "title", "authors"} <= set(cff)
    assert cff["version"] == sb.__version__
    assert cff["license"] == "BSD-3-Clause"
    assert re.fullmatch(r"\d{4}-\d{2}-\d{2}", str(cff["date-released"]))
    for ref in cff["references"]:
        assert {"type", "title", "authors"} <= set(ref)
        assert all("family-names" in a or "name" in a for a in ref["authors"])
    paper = cff["references"][0]
    assert paper["title"] == "A fractal structure in a bouncing ball model"
    assert [a["family-names"] for a in paper["authors"]] == ["Campos", "Romero-Valles", "Torres"]


def test_changelog_says_what_this_release_is():
    text = (ROOT / "CHANGELOG.md").read_text()
    # the newest release entry is the package's version; changes not yet released
    # stand above it under "## Unreleased"
    heads = re.findall(r"^## (\S+)", text, re.M)
    released = heads[1:] if heads[:1] == ["Unreleased"] else heads
    assert released and released[0] == sb.__version__, "the newest entry is the package's version"
    assert "Unreleased" not in released
    # and the history before it, from the first commit's date
    assert "## 0.1.0" in text
