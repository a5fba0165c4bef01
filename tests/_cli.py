"""The tests' way to run the command line in-process."""

import pytest

from stairbounce.cli import main


def run_cli(args, capsys):
    """``stairbounce ARGS`` in this process: ``(exit code, stdout, stderr)``
    (every command exits through SystemExit, success included)."""
    with pytest.raises(SystemExit) as exc:
        main(args)
    out, err = capsys.readouterr()
    return exc.value.code, out, err
