"""The release: one version (``stairbounce --version``, the package, the
build), and the files people need to use and cite it."""

from __future__ import annotations

import stairbounce as sb
from stairbounce.cli import main

import pytest


def test_version_option_prints_the_package_version_and_exits_0(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out == f"stairbounce {sb.__version__}\n"

