"""Throughput of box counting (issue 4): a 16384 x 16384 boolean image.

Target: all power-of-two box counts of a 16384^2 image in under 0.5 s on 2
cores.  Measured in this process, JIT warm, against baselines run here too (so
the ratios hold on a busy machine):

- ``box_counts(img)``: the OR-pyramid (numba ``_pool_count``, rows over all
  threads), 15 sizes 1..16384 px; then the same on one numba thread;
- ``box_counts(img, sizes=..., offsets=2)``: the direct kernel
  ``_count_boxes`` (one read of the image per size and shift);
- NumPy, plain: for each size, ``img.reshape(h/s, s, w/s, s).any((1, 3)).sum()``
  (the textbook one-liner);
- NumPy, pyramid: the same OR-pyramid with four strided slices per level.

All methods are checked to give the same counts.  Images: the Sierpinski
triangle of Pascal's triangle mod 2 (``(i & j) == 0``, 1.8% of the pixels),
a random image with 1% of the pixels set, and the one-pixel border of a disk
(``boundary``, also timed).

Run: ``python benchmarks/fractal.py [--n 16384] [--repeat 5]``.
"""

from __future__ import annotations

import argparse
import statistics

import numba
import numpy as np

from stairbounce.dimension import boundary, box_counts
from stairbounce.dimension.boxes import _count_boxes
from _timing import wall_times


def best(fn, repeat):
    times, out = wall_times(fn, repeat)
    return min(times), statistics.median(times), out


def numpy_plain(img):
    n = img.shape[0]
    sizes = 2 ** np.arange(int(np.log2(n)) + 1)
    return sizes, np.array([img.reshape(n // s, s, n // s, s).any(axis=(1, 3)).sum() for s in sizes])


def numpy_pyramid(img):
    counts = [np.count_nonzero(img)]
    level = img
    while level.shape[0] > 1:
        level = level[0::2, 0::2] | level[1::2, 0::2] | level[0::2, 1::2] | level[1::2, 1::2]
        counts.append(np.count_nonzero(level))
    return 2 ** np.arange(len(counts)), np.array(counts)


def images(n):
    i = np.arange(n, dtype=np.int64)
    yield "Sierpinski (i & j) == 0", (i[:, None] & i[None, :]) == 0
    rng = np.random.default_rng(1)
    yield "random, 1% set", rng.random((n, n), dtype=np.float32) < 0.01
    c = (np.arange(n, dtype=np.float32) + 0.5 - n / 2) ** 2
    yield "disk", (c[:, None] + c[None, :]) <= (0.4 * n) ** 2


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--n", type=int, default=16384, help="image side in pixels (a power of two)")
    p.add_argument("--repeat", type=int, default=5)
    args = p.parse_args()
    n, rep = args.n, args.repeat
    threads = numba.get_num_threads()
    px = n * n
    # compile (numba caches to disk; the first run of a session still loads)
    box_counts(np.ones((64, 64), bool))
    box_counts(np.ones((64, 64), bool), sizes=[3], offsets=2)

    print(f"box counting of a {n} x {n} boolean image ({px / 1e6:.0f} Mpx), "
          f"numba {numba.__version__}, {threads} threads, best of {rep} (median)")
    for name, img in images(n):
        print(f"\n{name}:")
        if name == "disk":
            tb, mb, border = best(lambda: boundary(img), max(1, rep // 2))
            print(f"  boundary(disk)                   {tb:7.3f} s ({mb:.3f})  {px / tb / 1e9:5.2f} Gpx/s")
            img = border
        rows = []
        t, m, (s, c) = best(lambda: box_counts(img), rep)
        rows.append(("box_counts (numba pyramid)", t, m))
        numba.set_num_threads(1)
        t1, m1, (_, c1) = best(lambda: box_counts(img), rep)
        numba.set_num_threads(threads)
        rows.append(("box_counts, 1 numba thread", t1, m1))
        tp, mp, (_, cp) = best(lambda: numpy_pyramid(img), max(1, rep // 2))
        rows.append(("NumPy pyramid", tp, mp))
        tn, mn, (_, cn) = best(lambda: numpy_plain(img), max(1, rep // 2))
        rows.append(("NumPy reshape-any per size", tn, mn))
        td, md, cd = best(lambda: [_count_boxes(img.view(np.uint8), int(x), 0, 0) for x in s], max(1, rep // 2))
        rows.append(("direct kernel, every size", td, md))
        assert c.tolist() == c1.tolist() == cp.tolist() == cn.tolist() == list(cd)
        for label, tt, mm in rows:
            print(f"  {label:32s} {tt:7.3f} s ({mm:.3f})  {px / tt / 1e9:5.2f} Gpx/s  x{tt / t:6.1f}")
        to, mo, _ = best(lambda: box_counts(img, offsets=2), max(1, rep // 2))
        print(f"  box_counts, offsets=2 (4 grids)  {to:7.3f} s ({mo:.3f})  "
              f"{px / to / 1e9:5.2f} Gpx/s  x{to / t:6.1f}")
    print("\n(x: time relative to box_counts with all threads, same image)")


if __name__ == "__main__":
    main()
