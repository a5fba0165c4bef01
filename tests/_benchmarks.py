"""Importing a script of ``benchmarks/`` in the tests."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

BENCHMARKS = Path(__file__).resolve().parent.parent / "benchmarks"


def import_benchmark(name: str):
    """import_benchmark(name) -> module

    ``benchmarks/<name>.py`` imported under its own name (numba's cache keys
    compiled code by the module), with ``benchmarks/`` on ``sys.path`` only
    while it is imported.
    """
    sys.path.insert(0, str(BENCHMARKS))
    try:
        return importlib.import_module(name)
    finally:
        sys.path.remove(str(BENCHMARKS))
