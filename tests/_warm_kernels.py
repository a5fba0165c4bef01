"""Compile the package's numba kernels into their on-disk cache before the suite's
processes start (tests/conftest.py runs ``python tests/_warm_kernels.py PART`` for
both parts at once, one process each, when pytest-xdist runs the suite).

In a fresh clone nothing is cached, and each of the suite's processes would compile
the kernels it meets on its own: the certifier's alone take about 50 s to compile on
the 2-core machine.  Run first, in two processes, they are compiled once and each
later process loads them from the cache.  A kernel met only later is compiled then,
as before; this only moves work, it is not a test and asserts nothing.  Small
windows: what is compiled is the kernels' signatures, not the answers."""

import sys
import time


def _scans():
    import numpy as np

    import stairbounce as sb

    from stairbounce.structure import trapping

    # the trapping regions' tries first (the proofs part reaches them last, and loads them)
    box = [np.array([x]) for x in (0.299, 0.30, 0.413, 0.414)]
    trapping._try_all(*box, 1000, threads=1)
    sb.scan(e=(0.1, 0.5, 8), u=(0.3, 1.2, 8), max_iter=100)
    sb.scan(e=(0.1, 0.5, 8), u=(0.3, 1.2, 8), max_iter=100, prune=False)
    pts = sb.border_points(e=(0.155, 0.2138, 16), u=(0.6, 0.658, 16), max_iter=200, outcome="sliding")
    sb.border_points(e=(0.155, 0.2138, 16), u=(0.6, 0.658, 16), max_iter=200)
    sb.word_table(e=(0.155, 0.2138, 16), u=(0.6, 0.658, 16), max_iter=200)
    sb.prove_labels(pts)
    sb.sliding_word(0.05, 0.93)
    sb.impact_times(1.0, 0.0, 0.2, 3)
    sb.trajectory(0.2, 0.6, steps=5)
    sb.prunable(np.array([0.2]), np.array([0.6]))
    sb.orbit_diagram(0.2, (0.5, 0.6, 8), transient=20, keep=5)
    sb.orbit_diagram(0.2, (0.5, 0.6, 8), transient=20, keep=5, warm_start=True)
    sb.bifurcations(0.2, (0.5, 0.6, 8), transient=20, keep=5)
    sb.motion(0.2, 0.3, steps=20, transient=20)
    sb.motion_scan(e=(0.1, 0.3, 4), u=(0.1, 0.3, 4), steps=20, transient=20)
    sb.itinerary(0.2, 0.6, max_iter=100)
    sb.window_regions((0.04, 0.065), (0.92, 0.945), resolution=16, max_iter=200)
    sb.box_dimension(np.eye(64, dtype=bool))


def _proofs():
    import stairbounce as sb

    fig7 = dict(e=(0.155, 0.2138), u=(0.6, 0.658))
    sb.verify(sb.certify(depth=5, **fig7))
    sb.verify(sb.certify(depth=5, classes=True, **fig7))
    sb.verify(sb.certify(e=(0.29, 0.31), u=(0.40, 0.42), depth=5, trap=True))
    sb.certify_box((0.2, 0.2001), (0.62, 0.6201))
    import numpy as np

    from stairbounce.structure.border_counts import StreamedCounts

    # a store's perimeter counts, tile by tile, with the proven points inside the undecided
    # boxes (structure/witnesses.py: max_iter 10)
    counts = StreamedCounts(((0.0, 1.0), (0.0, 1.0)), 2, 2, 1, 10)
    counts.add(0, np.array([1, 1, 1, 1]), np.array([0, 1, 0, 1]), np.array([0, 0, 1, 1]), np.array([0, 3, 1, 3], np.int8))
    counts.rows()


PARTS = {"scans": _scans, "proofs": _proofs}

if __name__ == "__main__":
    t0 = time.perf_counter()
    PARTS[sys.argv[1]]()
    print(f"{sys.argv[1]}: {time.perf_counter() - t0:.1f} s")
