"""Throughput of the (e, u) parameter-plane scan (issue 3), baselines in the same process.

    python benchmarks/scan.py [--repeat 5] [--big 2048] [--no-big]

Cases: the paper's grid (500 x 350 over e in (0, 1), u in (0, 1.5), max_iter
1000) and a big x big window of the same plane.  Rows:

- ``scan``: the public wrapper, kernel ``_scan_fast`` (32 lanes in lockstep,
  interleaved chunks), JIT warm, all numba threads;
- the same on one thread (how much the second core gives);
- ``_scan_plain``: the baseline, per pixel the closed form ``_step_closed``
  (log and pow), ``prange`` over rows;
- NumPy: ``numpy_scan`` below, the map vectorised over the pixels still
  running (compacted every step), impacts counted with masked array updates.
  It runs on every k-th row only and is scaled by useful iterations.

Useful map iterations are the steps the answer needs: per pixel, the steps up
to the slide (the period) or max_iter where it does not slide.  Every row
reports useful iterations per second and the ratio to the fast kernel, and the
plain and NumPy answers are checked against the fast one.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time

import numba
import numpy as np

from stairbounce.model import _COUNTED_IMPACTS
from stairbounce.plane import _FIELDS, _scan_plain, pixel_centres, scan, scan_coords


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


def case(name, e, u, max_iter, repeat, plain_stride, numpy_stride):
    es, us = pixel_centres(*e), pixel_centres(*u)
    threads = numba.get_num_threads()
    (t_fast, c_fast), ds = best(lambda: scan(e, u, max_iter), repeat)
    work = useful_iterations(ds)

    numba.set_num_threads(1)
    try:
        (t_one, c_one), _ = best(lambda: scan(e, u, max_iter), max(1, repeat // 2))
    finally:
        numba.set_num_threads(threads)

    sub_p = slice(None, None, plain_stride)
    (t_pl, c_pl), pl = best(lambda: plain(es, us[sub_p], max_iter), 1 if plain_stride > 1 else 2)
    ref_p = ds.isel(u=sub_p)
    work_p = useful_iterations(ref_p)
    agree_p = np.mean(np.all([pl[k] == ref_p[k].values for k in _FIELDS], axis=0))

    sub_n = slice(None, None, numpy_stride)
    (t_np, c_np), per = best(lambda: numpy_scan(es, us[sub_n], max_iter), 1)
    ref_n = ds.isel(u=sub_n)
    work_n = useful_iterations(ref_n)
    agree_n = np.mean(per == ref_n.period.values)

    ghz = _clock_ghz()
    print(f"\n{name}: {ds.sizes['e']} x {ds.sizes['u']} pixels, {work / 1e6:.1f} M useful map "
          f"iterations; wall / CPU time (rates per wall s / per CPU s)")

    def row(label, wall, cpu, w, note=""):
        print(f"  {label:24s} {wall:8.3f} s / {cpu:8.3f} s  {w / wall / 1e6:7.1f} / {w / cpu / 1e6:7.1f} "
              f"M it/s{note}")

    row("scan (_scan_fast)", t_fast, c_fast, work,
        f"  ~{ghz * 1e9 * c_fast / work:.1f} cycles per step (CPU time)" if ghz else "")
    row("scan, 1 thread", t_one, c_one, work, f"  x{t_one / t_fast:.2f} the wall time of all threads")
    for label, wall, cpu, w, stride, agree, what in (
        ("_scan_plain (prange)", t_pl, c_pl, work_p, plain_stride, agree_p, "same answer"),
        ("NumPy vectorised", t_np, c_np, work_n, numpy_stride, agree_n, "same period"),
    ):
        # a subsample is scaled to the whole grid by useful iterations
        sub = "" if stride == 1 else f", every {stride}th row, scaled"
        wall, cpu = wall * work / w, cpu * work / w
        row(label, wall, cpu, work,
            f"  x{wall / t_fast:.1f} / x{cpu / c_fast:.1f} slower{sub}; "
            f"{what} at {100 * agree:.3f}% of pixels")


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
    p.add_argument("--big", type=int, default=2048, help="side of the big window (pixels)")
    p.add_argument("--no-big", action="store_true", help="only the paper's grid")
    a = p.parse_args(argv)

    # compile everything once, outside the timings
    scan((0.0, 1.0, 40), (0.0, 1.5, 30), 50)
    plain(pixel_centres(0.0, 1.0, 4), pixel_centres(0.0, 1.5, 3), 5)
    scan_coords([0.5], [0.5], 5)

    print(f"machine: {os.cpu_count()} CPUs, numba {numba.__version__} ({numba.threading_layer()} "
          f"layer, {numba.get_num_threads()} threads), clock {_clock_ghz()} GHz, "
          f"load average {os.getloadavg()[0]:.1f}; python {sys.version.split()[0]}")
    case("paper grid (Fig. 4)", (0.0, 1.0, 500), (0.0, 1.5, 350), 1000, a.repeat, 1, 7)
    if not a.no_big:
        case(f"{a.big} x {a.big}, same plane", (0.0, 1.0, a.big), (0.0, 1.5, a.big), 1000,
             max(1, a.repeat // 3), 8, 128)
    print(f"\nload average at the end {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
