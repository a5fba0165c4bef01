"""Wall-clock timing shared by the benchmark scripts."""

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
