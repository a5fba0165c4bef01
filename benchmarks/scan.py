"""Throughput of the (e, u) parameter-plane scan (issues 3, 11), baselines in the same process.

    python benchmarks/scan.py [--repeat 5] [--big 2048] [--points 1000000] [--quick]

Cases (max_iter 1000): the paper's grid (500 x 350 over e in (0, 1), u in
(0, 1.5)), the explorer's Fig. 4 view (the same plane at 600 x 600), the
Fig. 5e window at big x big (all below the Corollary 2.1 curve: pruning does
nothing there), and ``scan_points`` on random points of the Fig. 7 window
(the uncertainty-dimension workload).  Rows:

- ``scan``: the public wrapper, kernel ``_scan_fast`` (32 lanes in lockstep,
  interleaved chunks, pixels above the Corollary 2.1 curve answered without
  iterating), JIT warm, all numba threads;
- the same with ``prune=False`` (every pixel iterated): the kernel alone;
- the pruned scan on one thread (how much the second core gives);
- the frozen baseline (``benchmarks/baseline_kernel.py``, never edited: per
  pixel the printed closed form, ``prange`` over rows, every pixel iterated):
  every factor is against it (issue 26);
- ``_scan_plain``: today's plain kernel, the same loop with the
  cancellation-free closed form ``_step_closed`` (1.6-1.7x slower per step
  than the frozen one since issue 17), beside it; the factor against it is
  split into the kernel's (prune=False) and the pruning's;
- NumPy (paper grid only): ``numpy_scan`` below, the map vectorised over the
  pixels still running (compacted every step), impacts counted with masked
  array updates.

Baselines on a subsample of rows are scaled by useful iterations.  Useful map
iterations are the steps iterating every pixel needs: per pixel, the steps up
to the slide (the period) or max_iter where it does not slide.  Every answer
is checked against the pruned scan's.  Cycles per step are CPU time x clock
/ steps actually done.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time

import numba
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from baseline_kernel import baseline_scan  # noqa: E402  (the frozen yardstick, benchmarks/)

from stairbounce.model import _COUNTED_IMPACTS
from stairbounce.plane import _FIELDS, _scan_plain, pixel_centres, prunable, scan, scan_points

THREADS = numba.get_num_threads()


def useful_iterations(ds):
    """Steps the answer needs (start from (1, 0)): the period, or max_iter."""
    mi = int(ds.attrs["max_iter"])
    return int(np.where(ds.status.values == 0, ds.period.values, mi).sum())


def plain(es, us, max_iter):
    out = {k: np.empty((len(us), len(es)), dtype=dt) for k, (dt, _) in _FIELDS.items()}
    _scan_plain(es, us, max_iter, 1.0, 0.0, out["status"], out["word_length"], out["jumps"],
                out["period"], out["impacts"])
    return out


def _closed_step(y, v, e, T):
    """model._step_closed for a step known to have >= 2 impacts, in Python
    (math.log and ** call the same C library as the compiled version)."""
    s = math.sqrt(v * v + 2.0 * y)
    arg = (v - T) * (1.0 - e) / (2.0 * s) + 0.5 * (1.0 + e)
    if arg <= 0.0:
        return 1.0, 0.0, -1
    kf = min(math.floor(math.log(arg) / math.log(e)), 1.0e6)
    k = max(int(kf), 1)

    def tk(j):
        return v + (1.0 + e - 2.0 * e**j) / (1.0 - e) * s

    for _ in range(4):
        if k > 1 and tk(k) > T:
            k -= 1
        elif tk(k + 1) <= T:
            k += 1
        else:
            break
    vk = e**k * s
    d = T - tk(k)
    return -0.5 * d * d + vk * d + 1.0, vk - d, k


def numpy_scan(es, us, max_iter):
    """The scan vectorised with NumPy over the pixels still running.

    One array operation per term of model._step on the running pixels; pixels
    that slide leave the arrays; the rare steps with more than
    model._COUNTED_IMPACTS impacts take the closed form in a Python loop.
    Returns the period per pixel (0: no slide).
    """
    E, U = np.meshgrid(es, us)
    e = E.ravel().copy()
    T = 1.0 / U.ravel()
    ratio = (1.0 + e) / (1.0 - e)
    half_TT = 0.5 * T * T
    idx = np.arange(e.size)
    y = np.ones(e.size)
    v = np.zeros(e.size)
    period = np.zeros(e.size, np.int64)
    for n in range(1, max_iter + 1):
        s = np.sqrt(v * v + 2.0 * y)
        slide = v + ratio * s <= T
        t = v + s
        fly = t > T
        w = e * s
        k = np.ones(t.size, np.int64)
        more = ~fly & ~slide & (t + 2.0 * w <= T)
        while more.any():
            t = np.where(more, t + 2.0 * w, t)
            w = np.where(more, w * e, w)
            k += more
            more &= (k < _COUNTED_IMPACTS) & (t + 2.0 * w <= T)
        d = T - t
        yn = np.where(fly, y + v * T - half_TT + 1.0, -0.5 * d * d + w * d + 1.0)
        vn = np.where(fly, v - T, w - d)
        closed = np.flatnonzero(~fly & ~slide & (k >= _COUNTED_IMPACTS))
        for i in closed:
            yn[i], vn[i], kk = _closed_step(y[i], v[i], e[i], T[i])
            slide[i] = kk == -1
        period[idx[slide]] = n
        keep = ~slide
        idx, e, T, ratio, half_TT = idx[keep], e[keep], T[keep], ratio[keep], half_TT[keep]
        y, v = yn[keep], vn[keep]
        if idx.size == 0:
            break
    return period.reshape(E.shape)


def best(f, repeat):
    """Best wall time and best process CPU time (all threads) of ``repeat`` runs.

    On a shared machine the CPU time is the steadier measure of work: it does
    not count the time the threads wait for a core."""
    walls, cpus = [], []
    out = None
    for _ in range(repeat):
        c, t = time.process_time(), time.perf_counter()
        out = f()
        walls.append(time.perf_counter() - t)
        cpus.append(time.process_time() - c)
    return (min(walls), min(cpus)), out


def steps_done(ds, pruned_mask):
    """Map steps the pruned kernel still does: useful iterations of the pixels it iterates."""
    mi = int(ds.attrs["max_iter"])
    per = np.where(ds.status.values == 0, ds.period.values, mi)
    return int(per[~pruned_mask].sum())


def _row(label, wall, cpu, w, note=""):
    print(f"  {label:26s} {wall:8.4f} s / {cpu:8.4f} s  {w / wall / 1e6:8.1f} / {w / cpu / 1e6:8.1f} "
          f"M it/s{note}")


def case(name, e, u, max_iter, repeat, plain_stride, numpy_stride=None):
    """One window: the pruned scan (default), the unpruned fast kernel, one
    thread, the plain kernel (every plain_stride-th row, scaled) and NumPy
    (every numpy_stride-th row, scaled; None: left out).  Rates are per useful
    map iteration (the steps iterating every pixel needs)."""
    es, us = pixel_centres(*e), pixel_centres(*u)
    E, U = np.meshgrid(es, us)
    mask = prunable(E, U)
    (t_pr, c_pr), ds = best(lambda: scan(e, u, max_iter), repeat)
    (t_fast, c_fast), full = best(lambda: scan(e, u, max_iter, prune=False), repeat)
    same = all(np.array_equal(ds[k].values, full[k].values) for k in _FIELDS)
    work = useful_iterations(ds)
    done = steps_done(ds, mask)

    numba.set_num_threads(1)
    try:
        (t_one, c_one), _ = best(lambda: scan(e, u, max_iter), max(1, repeat // 2))
    finally:
        numba.set_num_threads(THREADS)

    sub_p = slice(None, None, plain_stride)
    (t_fr, c_fr), fr = best(lambda: baseline_scan(es, us[sub_p], max_iter), 1 if plain_stride > 1 else 2)
    (t_pl, c_pl), pl = best(lambda: plain(es, us[sub_p], max_iter), 1 if plain_stride > 1 else 2)
    ref_p = ds.isel(u=sub_p)
    work_p = useful_iterations(ref_p)
    agree_p = np.mean(np.all([pl[k] == ref_p[k].values for k in _FIELDS], axis=0))
    agree_f = np.mean(np.all([fr[k] == ref_p[k].values for k in _FIELDS], axis=0))
    # a subsample is scaled to the whole grid by useful iterations
    t_pl, c_pl = t_pl * work / work_p, c_pl * work / work_p
    t_fr, c_fr = t_fr * work / work_p, c_fr * work / work_p

    ghz = _clock_ghz()
    print(f"\n{name}: {ds.sizes['e']} x {ds.sizes['u']} pixels, max_iter {max_iter}, "
          f"{work / 1e6:.1f} M useful map iterations; pruned {100 * mask.mean():.1f} % of the pixels, "
          f"{100 * (1 - done / work):.1f} % of the iterations; wall / CPU time "
          f"(rates: useful iterations per wall s / per CPU s)")
    cyc = (lambda c, w: f"  ~{ghz * 1e9 * c / w:.1f} cycles per step done per core") if ghz else (lambda c, w: "")
    _row("scan (prune=True)", t_pr, c_pr, work,
         f"  {done / 1e6:.1f} M steps done;{cyc(c_pr, done)}")
    _row("scan (prune=False)", t_fast, c_fast, work,
         f"  x{t_fast / t_pr:.1f} / x{c_fast / c_pr:.1f} the pruned time;{cyc(c_fast, work)}; "
         f"identical arrays: {same}")
    _row("scan (prune=True), 1 thread", t_one, c_one, work,
         f"  x{t_one / t_pr:.2f} the wall time on {THREADS} threads")
    sub = "" if plain_stride == 1 else f", every {plain_stride}th row, scaled"
    _row("frozen baseline (prange)", t_fr, c_fr, work,
         f"  x{t_fr / t_pr:.1f} / x{c_fr / c_pr:.1f} the pruned scan, x{t_fr / t_fast:.1f} / "
         f"x{c_fr / c_fast:.1f} the unpruned (wall / CPU){sub}; same answer at {100 * agree_f:.3f}% of pixels")
    _row("_scan_plain (prange)", t_pl, c_pl, work,
         f"  x{t_pl / t_pr:.1f} / x{c_pl / c_pr:.1f} the pruned scan = kernel x{t_pl / t_fast:.1f} "
         f"(x{c_pl / c_fast:.1f} CPU) * pruning x{t_fast / t_pr:.1f} (x{c_fast / c_pr:.1f} CPU)"
         f"{sub}; same answer at {100 * agree_p:.3f}% of pixels")
    if numpy_stride:
        sub_n = slice(None, None, numpy_stride)
        (t_np, c_np), per = best(lambda: numpy_scan(es, us[sub_n], max_iter), 1)
        ref_n = ds.isel(u=sub_n)
        work_n = useful_iterations(ref_n)
        agree_n = np.mean(per == ref_n.period.values)
        t_np, c_np = t_np * work / work_n, c_np * work / work_n
        _row("NumPy vectorised", t_np, c_np, work,
             f"  x{t_np / t_pr:.1f} / x{c_np / c_pr:.1f} the pruned scan, every {numpy_stride}th "
             f"row, scaled; same period at {100 * agree_n:.3f}% of pixels")


def points_case(n, max_iter, repeat, window=((0.155, 0.2138), (0.6, 0.658))):
    """scan_points on n random points of a window (default Fig. 7's, the
    uncertainty-dimension workload), pruned and not, and the same number of
    pixels as a grid scan."""
    (e0, e1), (u0, u1) = window
    rng = np.random.default_rng(0)
    e = rng.uniform(e0, e1, n)
    u = rng.uniform(u0, u1, n)
    mask = prunable(e, u)
    (t_pr, c_pr), ds = best(lambda: scan_points(e, u, max_iter), repeat)
    (t_full, c_full), full = best(lambda: scan_points(e, u, max_iter, prune=False), repeat)
    side = int(round(math.sqrt(n)))
    # the frozen baseline has no point path: its rate on every 16th row of the same
    # window as a side x side grid, scaled to the points' useful iterations
    ge, gu = pixel_centres(e0, e1, side), pixel_centres(u0, u1, side)[::16]
    (t_fr, c_fr), fr = best(lambda: baseline_scan(ge, gu, max_iter), 1)
    work_fr = int(np.where(fr["status"] == 0, fr["period"], max_iter).sum())
    same = all(np.array_equal(ds[k].values, full[k].values) for k in _FIELDS)
    (t_grid, c_grid), grid = best(lambda: scan((e0, e1, side), (u0, u1, side), max_iter), repeat)
    per = np.where(ds.status.values == 0, ds.period.values, max_iter)
    work = int(per.sum())
    done = int(per[~mask].sum())
    t_fr, c_fr = t_fr * work / work_fr, c_fr * work / work_fr
    print(f"\nscan_points, {n} random points in [{e0}, {e1}] x [{u0}, {u1}], max_iter {max_iter}: "
          f"{work / 1e6:.1f} M useful iterations, pruned {100 * mask.mean():.1f} % of the points, "
          f"{100 * (1 - done / work):.1f} % of the iterations")
    _row("scan_points (prune=True)", t_pr, c_pr, work,
         f"  {n / t_pr / 1e6:.2f} M points/s; x{t_fr / t_pr:.1f} / x{c_fr / c_pr:.1f} the frozen baseline")
    _row("scan_points (prune=False)", t_full, c_full, work,
         f"  x{t_full / t_pr:.2f} / x{c_full / c_pr:.2f} the pruned time; identical arrays: {same}")
    wg = useful_iterations(grid)
    _row(f"scan, {side} x {side} grid", t_grid, c_grid, wg,
         "  same window as a grid, for comparison (pruned)")
    _row("frozen baseline (scaled)", t_fr, c_fr, work,
         "  its rate on every 16th row of the grid, scaled to the points' useful iterations")


def _clock_ghz():
    try:
        with open("/proc/cpuinfo") as f:
            mhz = [float(line.split(":")[1]) for line in f if line.startswith("cpu MHz")]
        return mhz[0] / 1000.0 if mhz else None
    except OSError:
        return None


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeat", type=int, default=5)
    p.add_argument("--big", type=int, default=2048, help="side of the Fig. 5e window (pixels)")
    p.add_argument("--points", type=int, default=1_000_000, help="points of the scan_points case")
    p.add_argument("--quick", action="store_true",
                   help="the paper grid, the Fig. 4 view, a 512 px Fig. 5e, 10^5 points")
    a = p.parse_args(argv)
    if a.quick:
        a.big, a.points = min(a.big, 512), min(a.points, 100_000)

    # compile everything once, outside the timings
    scan((0.0, 1.0, 40), (0.0, 1.5, 30), 50)
    scan((0.0, 1.0, 40), (0.0, 1.5, 30), 50, prune=False)
    scan_points([0.5, 0.1], [0.5, 3.0], 5)
    plain(pixel_centres(0.0, 1.0, 4), pixel_centres(0.0, 1.5, 3), 5)
    baseline_scan(pixel_centres(0.0, 1.0, 4), pixel_centres(0.0, 1.5, 3), 5)

    print(f"machine: {os.cpu_count()} CPUs, numba {numba.__version__} ({numba.threading_layer()} "
          f"layer, {THREADS} threads), clock {_clock_ghz()} GHz, "
          f"load average {os.getloadavg()[0]:.1f}; python {sys.version.split()[0]}")
    case("paper grid (Fig. 4)", (0.0, 1.0, 500), (0.0, 1.5, 350), 1000, a.repeat, 1, 7)
    case("Fig. 4 view of the explorer", (0.0, 1.0, 600), (0.0, 1.5, 600), 1000, a.repeat, 4)
    case("Fig. 5e window", (0.04, 0.065, a.big), (0.92, 0.945, a.big), 1000,
         max(1, a.repeat // 3), 16 * max(1, a.big // 512))
    points_case(a.points, 1000, max(1, a.repeat // 2))
    print(f"\nload average at the end {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
