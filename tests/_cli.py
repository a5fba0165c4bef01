"""The tests' way to run the command line in-process."""

import pytest

from stairbounce.cli import main


def run_cli(args, capsys):
    """``stairbounce ARGS`` in this process: ``(exit code, stdout, stderr)``
    (every command exits through SystemExit, success included); each argument
    is passed as text (paths and numbers may be given as they are)."""
    with pytest.raises(SystemExit) as exc:
        main([str(a) for a in args])
    out, err = capsys.readouterr()
    return exc.value.code, out, err
