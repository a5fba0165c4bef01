"""Importing a script of ``benchmarks/`` or ``scripts/`` in the tests."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

BENCHMARKS = Path(__file__).resolve().parent.parent / "benchmarks"
SCRIPTS = BENCHMARKS.parent / "scripts"


def import_benchmark(name: str):
    """import_benchmark(name) -> module

    ``benchmarks/<name>.py`` imported under its own name (numba's cache keys
    compiled code by the module), with ``benchmarks/`` on ``sys.path`` only
    while it is imported.
    """
    return _import_from(BENCHMARKS, name)


def import_script(name: str):
    """import_script(name) -> module

    ``scripts/<name>.py`` imported as :func:`import_benchmark` imports a
    benchmark.
    """
    return _import_from(SCRIPTS, name)


def _import_from(folder: Path, name: str):
    sys.path.insert(0, str(folder))
    try:
        return importlib.import_module(name)
    finally:
        sys.path.remove(str(folder))
