"""Wall-clock timing, and the integer options of ``main``, shared by the benchmark scripts."""

from __future__ import annotations

import time


def wall_times(fn, repeat, warm=False):
    """wall_times(fn, repeat, warm=False) -> (list of float, last result)

    The wall times (``time.perf_counter``) of ``repeat`` calls of ``fn`` and
    what the last call returned (``None`` when ``repeat`` is 0); with
    ``warm``, one untimed call first (compilation, caches).
    """
    if warm:
        fn()
    times = []
    out = None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return times, out


def int_options(parser, **defaults):
    """int_options(parser, **defaults) -> parser

    Add one integer option per keyword to the ``argparse`` parser: ``--NAME``
    (underscores written as dashes) with that default, as in
    ``int_options(parser, repeat=5, size=300)``.
    """
    for name, default in defaults.items():
        parser.add_argument("--" + name.replace("_", "-"), type=int, default=default)
    return parser
