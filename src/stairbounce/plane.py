"""The (e, u) parameter plane: where periodic sliding solutions exist (Section 3).

For every point of a grid of restitution coefficients ``e`` and horizontal
speeds ``u`` the Poincare map (Prop. 2.3) is iterated until the sliding test
(2.3)/(2.4) holds; the word of the periodic sliding solution then gives the
colour of the point (the paper's Figures 3, 4 and 5).

The public wrappers validate, allocate and call a private numba kernel:

- ``_scan_fast``: the kernel used by :func:`scan` and :func:`scan_coords`,
  the map of :func:`stairbounce.model._step` (impacts counted along the
  geometric series, no log/pow) evaluated on several pixels in lockstep,
  parallel over both cores with interleaved work so that cheap and expensive
  parts of the plane are shared evenly.
- ``_scan_plain``: the baseline, one pixel at a time with the plain closed
  form :func:`stairbounce.model._step_closed`, ``prange`` over rows.

Nothing here imports matplotlib, Typer or the web stack.
"""

from __future__ import annotations

import math
import os

import numpy as np
import xarray as xr
import numba
from numba import njit, prange

from ._interrupt import halted
from .model import (
    _COUNTED_IMPACTS,
    SLIDING,
    _constants,
    _finite,
    _slide_or_steps_with,
    _step_closed,
    check_count,
)

__all__ = [
    "pixel_centres",
    "scan",
    "scan_coords",
    "tongue_mask",
    "no_sliding_curve",
    "save",
    "load",
    "estimate_bytes",
]

CONVENTION = (
    "word of the periodic sliding solution through (1, 0): jump numbers between "
    "consecutive impacts, the first counted from the departure (landing on the step "
    "right below is 1); a step with k >= 1 impacts gives its jump then k-1 zeros; the "
    "accumulation tail 0^inf is not a letter. word_length = impacts + 1; period = sum "
    "of letters = steps per period; jumps = non-zero letters; impacts = finite impacts "
    "per period. status 0: periodic sliding solution found, 1: no slide within max_iter "
    "steps (then word_length = jumps = period = impacts = 0). Coordinates are pixel "
    "centres; the image covers [e_min, e_max] x [u_min, u_max]."
)

# Output variables, their dtypes and meaning.  word_length and impacts can
# exceed 2**31 only for absurd max_iter near e = 1, but they are int64 anyway.
_FIELDS = {
    "status": (np.uint8, "0: periodic sliding solution found; 1: no slide within max_iter steps"),
    "word_length": (np.int64, "length of the word of the periodic sliding solution (impacts + 1)"),
    "jumps": (np.int32, "non-zero letters of the word (steps of a period with a landing)"),
    "period": (np.int32, "steps per period (sum of the letters)"),
    "impacts": (np.int64, "finite impacts per period (the accumulation not counted)"),
}
_BYTES_PER_PIXEL = sum(np.dtype(dt).itemsize for dt, _ in _FIELDS.values())
# Zarr's fill values, what a chunk that was never written (or was deleted) reads
# as: none is a value a scan can produce, so a missing chunk is never taken for
# data (status 0 means "found"; 0 is a valid word length where nothing is found).
FILL_VALUES = {"status": 255, "word_length": -1, "jumps": -1, "period": -1, "impacts": -1}


# --------------------------------------------------------------------------- #
# Kernels                                                                     #
# --------------------------------------------------------------------------- #


@njit(cache=True)
def _slide_or_steps_closed(y, v, e, T, ratio, max_steps):
    """:func:`stairbounce.model._slide_or_steps` with the plain closed form."""
    return _slide_or_steps_with(_step_closed, y, v, e, T, ratio, max_steps)


@njit(cache=True)
def _store(i, j, n, imp, jmp, status, word_length, jumps, period, impacts):
    if n == 0:
        status[i, j] = 1
        word_length[i, j] = 0
        jumps[i, j] = 0
        period[i, j] = 0
        impacts[i, j] = 0
    else:
        status[i, j] = 0
        word_length[i, j] = imp + 1
        jumps[i, j] = jmp
        period[i, j] = n
        impacts[i, j] = imp


@njit(cache=True, parallel=True)
def _scan_plain(es, us, max_iter, y0, v0, status, word_length, jumps, period, impacts):
    """Baseline kernel: per pixel, the closed form of Prop. 2.2/2.3, prange over rows.

    A transient from ``(y0, v0)`` up to its first slide, then one period from
    ``(1, 0)``; the transient is skipped when ``(y0, v0) = (1, 0)``.
    """
    from_rest = y0 == 1.0 and v0 == 0.0
    for i in prange(us.shape[0]):
        for j in range(es.shape[0]):
            e = es[j]
            T, ratio = _constants(e, us[i])
            n = 1
            if not from_rest:
                n, _, _ = _slide_or_steps_closed(y0, v0, e, T, ratio, max_iter)
            imp = 0
            jmp = 0
            if n != 0:
                n, imp, jmp = _slide_or_steps_closed(1.0, 0.0, e, T, ratio, max_iter)
            _store(i, j, n, imp, jmp, status, word_length, jumps, period, impacts)


# The fast kernel runs LANES pixels in lockstep.  The lane loops below are
# written branch-free (selects only) so that LLVM vectorises them: 8 float64
# per AVX-512 register, and it only enters the vector body for 16 lanes or more;
# 32 measured fastest on the development machine (see benchmarks/README.md).
LANES = 32
# Pixels per unit of parallel work: small enough to share the uneven plane
# between threads, large enough that lanes rarely idle at the end of a chunk.
_CHUNK_MAX = 1024


@njit(cache=True, inline="always")
def _lane_step(y, v, e, T, ratio, half_TT):
    """One step of :func:`stairbounce.model._step` for the common cases, branch-free.

    Same operations in the same order as ``_step``, so bit-identical where it
    answers: sliding, flying over, or exactly one impact.  ``more`` is set when
    a second impact happens on this step; the caller then counts on from
    ``(t, w)`` (first impact time, velocity after it).
    """
    s = math.sqrt(v * v + 2.0 * y)
    slide = v + ratio * s <= T
    t = v + s
    fly = t > T
    w = e * s
    more = (t + 2.0 * w <= T) and not fly and not slide
    d = T - t
    y_bounce = -0.5 * d * d + w * d + 1.0
    v_bounce = w - d
    y_fly = y + v * T - half_TT + 1.0
    v_fly = v - T
    yn = 1.0 if slide else (y_fly if fly else y_bounce)
    vn = 0.0 if slide else (v_fly if fly else v_bounce)
    k = SLIDING if slide else (0 if fly else 1)
    return yn, vn, k, more, t, w


@njit(cache=True)
def _run_chunk(es, us, max_iter, y0, v0, start, stop, status, word_length, jumps, period, impacts, halt):
    """Pixels ``start..stop-1`` (row-major) of the grid, LANES at a time.

    A lane takes the next pixel as soon as its own finishes, so lanes stay busy
    whatever the mix of cheap and expensive pixels.  Each pixel sees exactly
    the sequence of operations of ``_slide_or_steps`` with ``model._step``.
    Returns early, leaving pixels unwritten, once ``halt[0]`` is set (Ctrl-C,
    :mod:`stairbounce._interrupt`); it is read once per lockstep step.
    """
    L = LANES
    ne = es.shape[0]
    from_rest = y0 == 1.0 and v0 == 0.0
    Y = np.ones(L)
    V = np.zeros(L)
    E = np.zeros(L)
    TT = np.ones(L)
    RATIO = np.ones(L)
    HALF_TT = np.full(L, 0.5)
    YN = np.empty(L)
    VN = np.empty(L)
    K = np.zeros(L, np.int64)
    MORE = np.zeros(L, np.int64)
    TS = np.empty(L)
    WS = np.empty(L)
    KS = np.zeros(L, np.int64)
    CLOSED = np.zeros(L, np.int64)
    N = np.zeros(L, np.int64)  # steps in the current phase
    IMP = np.zeros(L, np.int64)
    JMP = np.zeros(L, np.int64)
    PERIODIC = np.zeros(L, np.int64)  # 0: transient from (y0, v0), 1: period from (1, 0)
    PIX = np.full(L, -1, np.int64)
    LIVE = np.zeros(L, np.int64)

    nxt = start
    active = 0
    for l in range(L):
        if nxt < stop:
            _load_lane(l, nxt, es, us, y0, v0, from_rest, Y, V, E, TT, RATIO, HALF_TT, PERIODIC, PIX)
            LIVE[l] = 1
            nxt += 1
            active += 1

    while active > 0:
        if halted(halt):
            return
        # the common step, vectorised over lanes
        nmore = 0
        for l in range(L):
            yn, vn, k, more, t, w = _lane_step(Y[l], V[l], E[l], TT[l], RATIO[l], HALF_TT[l])
            YN[l] = yn
            VN[l] = vn
            K[l] = k
            MORE[l] = more
            TS[l] = t
            WS[l] = w
            KS[l] = 1
            nmore += more
        if nmore > 0:
            # lanes with two impacts or more: count on along t += 2w, w *= e as
            # model._step does, up to its _COUNTED_IMPACTS; past that, its closed form
            nclosed = 0
            while nmore > 0:
                nmore = 0
                for l in range(L):
                    m = MORE[l]
                    T = TT[l]
                    t = TS[l] + 2.0 * WS[l] if m else TS[l]
                    w = WS[l] * E[l] if m else WS[l]
                    k = KS[l] + m
                    closed = m & (k >= _COUNTED_IMPACTS)
                    more = m & (1 - closed) & (t + 2.0 * w <= T)
                    last = m & (1 - closed) & (1 - more)
                    d = T - t
                    YN[l] = (-0.5 * d * d + w * d + 1.0) if last else YN[l]
                    VN[l] = (w - d) if last else VN[l]
                    K[l] = k if last else K[l]
                    TS[l] = t
                    WS[l] = w
                    KS[l] = k
                    CLOSED[l] = CLOSED[l] | closed
                    MORE[l] = more
                    nmore += more
                    nclosed += closed
            if nclosed > 0:
                for l in range(L):
                    if CLOSED[l]:
                        CLOSED[l] = 0
                        YN[l], VN[l], K[l] = _step_closed(Y[l], V[l], E[l], TT[l], RATIO[l])
        # bookkeeping, vectorised over lanes
        nfin = 0
        for l in range(L):
            k = K[l]
            N[l] += 1
            IMP[l] += k if k > 0 else 0
            JMP[l] += 1 if k != 0 else 0
            Y[l] = YN[l]
            V[l] = VN[l]
            nfin += LIVE[l] & ((k == SLIDING) | (N[l] >= max_iter))
        if nfin == 0:
            continue
        for l in range(L):
            if LIVE[l] == 0 or (K[l] != SLIDING and N[l] < max_iter):
                continue
            if K[l] == SLIDING and PERIODIC[l] == 0:
                # end of the transient: the ball leaves the edge at (1, 0)
                PERIODIC[l] = 1
                N[l] = 0
                IMP[l] = 0
                JMP[l] = 0
                continue
            p = PIX[l]
            n = N[l] if K[l] == SLIDING else 0
            _store(p // ne, p % ne, n, IMP[l], JMP[l], status, word_length, jumps, period, impacts)
            N[l] = 0
            IMP[l] = 0
            JMP[l] = 0
            if nxt < stop:
                _load_lane(l, nxt, es, us, y0, v0, from_rest, Y, V, E, TT, RATIO, HALF_TT, PERIODIC, PIX)
                nxt += 1
            else:
                LIVE[l] = 0
                active -= 1


@njit(cache=True)
def _load_lane(l, p, es, us, y0, v0, from_rest, Y, V, E, TT, RATIO, HALF_TT, PERIODIC, PIX):
    ne = es.shape[0]
    e = es[p % ne]
    T, ratio = _constants(e, us[p // ne])
    E[l] = e
    TT[l] = T
    RATIO[l] = ratio
    HALF_TT[l] = 0.5 * T * T  # as model._step evaluates it
    Y[l] = 1.0 if from_rest else y0
    V[l] = 0.0 if from_rest else v0
    PERIODIC[l] = 1 if from_rest else 0
    PIX[l] = p


@njit(cache=True, parallel=True, nogil=True)
def _scan_fast(es, us, max_iter, y0, v0, order, chunk, status, word_length, jumps, period, impacts, halt):
    """Fast kernel: chunks of ``chunk`` pixels in the order ``order``, LANES
    pixels of a chunk in lockstep (:func:`_run_chunk`); stops early once
    ``halt[0]`` is set (then the outputs are incomplete and must be dropped)."""
    npix = es.shape[0] * us.shape[0]
    for c in prange(order.shape[0]):
        s = order[c] * chunk
        _run_chunk(es, us, max_iter, y0, v0, s, min(s + chunk, npix),
                   status, word_length, jumps, period, impacts, halt)


def _chunking(npix, threads):
    """Chunk size and chunk order for :func:`_scan_fast`.

    prange hands each thread one contiguous block of iterations; the order
    ``0, 16, 32, ..., 1, 17, ...`` makes every block sample the whole plane,
    so threads get similar work although low u slides in a step or two and
    high u runs to max_iter.  Results do not depend on either choice.
    """
    chunk = int(min(_CHUNK_MAX, max(4 * LANES, -(-npix // (16 * max(threads, 1))))))
    n = -(-npix // chunk)
    order = np.concatenate([np.arange(k, n, 16) for k in range(min(16, n))]).astype(np.int64)
    return chunk, order


# --------------------------------------------------------------------------- #
# Validation and memory                                                       #
# --------------------------------------------------------------------------- #


def _window(name, spec, lo_min, hi_max, lo_text):
    try:
        lo, hi, n = spec
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a tuple ({name}_min, {name}_max, n_{name}), got {spec!r}") from None
    lo = _finite(f"{name}_min", lo)
    hi = _finite(f"{name}_max", hi)
    n = check_count(f"n_{name}", n, 1)
    if lo < lo_min or hi > hi_max:
        raise ValueError(f"{name} window must lie in {lo_text}, got [{lo}, {hi}]")
    if not lo < hi:
        raise ValueError(f"{name}_min must be < {name}_max, got {name}_min = {lo}, {name}_max = {hi}")
    return lo, hi, n


def _coords(name, values):
    a = np.asarray(values, dtype=np.float64)
    if a.ndim != 1 or a.size == 0:
        raise ValueError(f"{name} values must be a non-empty 1-D array, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} values must be finite")
    if name == "e" and not np.all((a >= 0.0) & (a < 1.0)):
        raise ValueError(
            f"e (restitution coefficient) values must be in [0, 1), got [{a.min()}, {a.max()}]"
        )
    if name == "u" and not np.all(a > 0.0):
        raise ValueError(f"u (horizontal speed) values must be > 0, got min {a.min()}")
    return np.ascontiguousarray(a)


def estimate_bytes(n_e, n_u):
    """estimate_bytes(n_e, n_u) -> int

    Memory the outputs of a scan of ``n_e x n_u`` pixels take: one uint8,
    two int32 and two int64 per pixel (25 bytes) plus the coordinates.
    """
    return int(n_e) * int(n_u) * _BYTES_PER_PIXEL + 8 * (int(n_e) + int(n_u))


def _available_memory():
    """Bytes of memory available now (MemAvailable on Linux, else free pages)."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):  # pragma: no cover - no way to tell
        return None


def _check_memory(n_e, n_u):
    need = estimate_bytes(n_e, n_u)
    avail = _available_memory()
    if avail is not None and need > avail:
        raise ValueError(
            f"a scan of {n_e} x {n_u} pixels needs about {_human(need)} for its outputs, "
            f"more than the {_human(avail)} of memory available: reduce the size or scan tiles"
        )
    return need


def _human(n):
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if n < 1024 or unit == "TiB":
            return f"{n:.1f} {unit}" if unit != "B" else f"{n} B"
        n /= 1024.0
    return f"{n} B"  # pragma: no cover


# --------------------------------------------------------------------------- #
# Public API                                                                  #
# --------------------------------------------------------------------------- #


def pixel_centres(lo, hi, n):
    """pixel_centres(lo, hi, n) -> np.ndarray

    Centres of ``n`` equal pixels covering exactly ``[lo, hi]``.

    ``c_j = lo + (j + 1/2) (hi - lo) / n``, j = 0..n-1.  Sub-windows of a scan
    must be cut out of this array (not recomputed from their own bounds) to be
    bit-identical to the whole scan.
    """
    lo = _finite("lo", lo)
    hi = _finite("hi", hi)
    n = check_count("n", n, 1)
    return lo + (np.arange(n) + 0.5) * (hi - lo) / n


def scan_coords(e_values, u_values, max_iter=1000, y0=1.0, v0=0.0):
    """scan_coords(e_values, u_values, max_iter=1000, y0=1.0, v0=0.0) -> xarray.Dataset

    The scan of :func:`scan` on arbitrary 1-D coordinate arrays.

    Same kernel, same data variables and attributes as :func:`scan`, without
    the window bounds (the coordinates need not be evenly spaced).  Pixels are
    independent, so a tile cut out of a :func:`pixel_centres` grid gives the
    same values, bit for bit, as the whole scan.

    Parameters
    ----------
    e_values : 1-D array of floats in [0, 1)
    u_values : 1-D array of floats > 0
    max_iter, y0, v0 : as in :func:`scan`.
    """
    es = _coords("e", e_values)
    us = _coords("u", u_values)
    max_iter = check_count("max_iter", max_iter, 1)
    if max_iter > 2**31 - 1:
        raise ValueError(f"max_iter must be an integer in [1, 2**31 - 1], got {max_iter}")
    y0 = _finite("y0", y0)
    v0 = _finite("v0", v0)
    if y0 < 0.0:
        raise ValueError(f"y0 (initial height above the step's floor) must be >= 0, got {y0}")
    _check_memory(es.size, us.size)
    out = {k: np.empty((us.size, es.size), dtype=dt) for k, (dt, _) in _FIELDS.items()}
    chunk, order = _chunking(es.size * us.size, numba.get_num_threads())
    from ._interrupt import run_kernel

    # in a helper thread when called from the main thread: Ctrl-C stops it at once
    run_kernel(
        _scan_fast, es, us, max_iter, y0, v0, order, chunk,
        out["status"], out["word_length"], out["jumps"], out["period"], out["impacts"],
    )
    from . import __version__

    data_vars = {
        k: (("u", "e"), out[k], {"long_name": desc}) for k, (_, desc) in _FIELDS.items()
    }
    coords = {
        "e": ("e", es, {"long_name": "restitution coefficient e"}),
        "u": ("u", us, {"long_name": "horizontal speed u (normalised units)"}),
    }
    attrs = {
        "title": "periodic sliding solutions in the (e, u) plane",
        "max_iter": max_iter,
        "y0": y0,
        "v0": v0,
        "kernel": "stairbounce.plane._scan_fast",
        "stairbounce_version": __version__,
        "convention": CONVENTION,
        "reference": "Campos, Romero-Valles, Torres, A fractal structure in a bouncing ball model, Section 3",
    }
    return xr.Dataset(data_vars, coords=coords, attrs=attrs)


def scan(e=(0.0, 1.0, 500), u=(0.0, 1.5, 350), max_iter=1000, y0=1.0, v0=0.0, *, progress=None):
    """scan(e=(e_min, e_max, n_e), u=(u_min, u_max, n_u), max_iter=1000, y0=1.0, v0=0.0, *, progress=None) -> xarray.Dataset

    Periodic sliding solutions on an ``n_u x n_e`` grid of the (e, u) plane.

    At every pixel centre (:func:`pixel_centres`) the Poincare map (Prop. 2.3)
    is iterated with the sliding test (2.3)/(2.4) as stop criterion.  From
    ``(y0, v0) = (1, 0)`` the steps up to the first slide are one period of
    the periodic sliding solution.  From any other state the orbit is first
    iterated up to its first slide (a transient); the ball then leaves the edge
    at ``(1, 0)``, so the periodic sliding solution is the orbit of ``(1, 0)``
    and its period is measured from there until it slides again.  ``status``
    is 0 only when both happen, each within ``max_iter`` steps.

    Data variables (dims ``("u", "e")``): ``status`` (0 found, 1 not),
    ``word_length`` (impacts + 1), ``jumps`` (non-zero letters), ``period``
    (steps per period), ``impacts`` (finite impacts per period); all zero
    where ``status`` is 1.  Attributes record every input, the window, the
    package version and the word convention.

    Kernel: ``_scan_fast`` (the fast map of :func:`stairbounce.model._step`,
    several pixels in lockstep, interleaved over threads); ``_scan_plain`` is
    the closed-form baseline it is tested and benchmarked against.

    Parameters
    ----------
    e : (e_min, e_max, n_e), default (0, 1, 500)
        Image edges along e, within [0, 1] (pixel centres lie inside, < 1).
    u : (u_min, u_max, n_u), default (0, 1.5, 350)
        Image edges along u, u_min >= 0 (pixel centres lie inside, > 0).
    max_iter : int >= 1, default 1000
        Steps allowed for the transient and for the period, each.
    y0, v0 : float, default 1.0, 0.0
        Initial state at a step edge (y0 >= 0).
    progress : callable ``progress(rows_done, rows_total)``, optional
        When given, the rows are scanned in blocks (about 1/50 of the rows
        each; the values are the same, pixels are independent) and it is
        called after each block, and once with 0 before the first.

    Raises
    ------
    ValueError
        A bound or size out of range (naming it), or outputs that would not
        fit in the memory available (with the estimate).

    Reference: Section 3 of the paper (the scheme behind Figures 4 and 5).
    """
    e_min, e_max, n_e = _window("e", e, 0.0, 1.0, "[0, 1]")
    u_min, u_max, n_u = _window("u", u, 0.0, math.inf, "[0, inf)")
    _check_memory(n_e, n_u)
    es = pixel_centres(e_min, e_max, n_e)
    us = pixel_centres(u_min, u_max, n_u)
    if progress is None:
        ds = scan_coords(es, us, max_iter, y0, v0)
    else:
        progress(0, n_u)
        block = max(1, -(-n_u // 50))
        parts = []
        for r in range(0, n_u, block):
            parts.append(scan_coords(es, us[r : r + block], max_iter, y0, v0))
            progress(min(r + block, n_u), n_u)
        ds = xr.concat(parts, dim="u", combine_attrs="override") if len(parts) > 1 else parts[0]
    ds.attrs.update(
        e_min=e_min, e_max=e_max, n_e=n_e, u_min=u_min, u_max=u_max, n_u=n_u
    )
    return ds


def tongue_mask(e, u, n_max):
    """tongue_mask(e, u, n_max) -> np.ndarray of bool

    Theorem 3.1: where a periodic solution of type ``(n, 0^inf)`` exists for some n <= n_max.

    True where ``sqrt((n-1)/2) < u <= sqrt(n/2) (1-e)/(1+e)`` for some
    ``1 <= n <= n_max`` (inequalities (3.1), the bounds evaluated as in
    :func:`stairbounce.tongue`).  ``e`` and ``u`` broadcast against each other.
    """
    n_max = check_count("n_max", n_max, 1)
    e, u = np.broadcast_arrays(np.asarray(e, dtype=float), np.asarray(u, dtype=float))
    mask = np.zeros(e.shape, dtype=bool)
    if mask.size == 0:
        return mask
    # only tongues with sqrt((n-1)/2) < max(u) can contain a point
    n_top = min(n_max, int(2.0 * float(np.nanmax(u)) ** 2) + 2)
    shrink = (1.0 - e) / (1.0 + e)
    for n in range(1, n_top + 1):
        mask |= (math.sqrt((n - 1) / 2.0) < u) & (u <= math.sqrt(n / 2.0) * shrink)
    return mask


def no_sliding_curve(e):
    """no_sliding_curve(e) -> np.ndarray

    Corollary 2.1: above ``u = (1-e) / (2 sqrt(2e))`` no solution slides.

    Vectorised over ``e``; infinite at ``e = 0``.
    """
    e = np.asarray(e, dtype=float)
    with np.errstate(divide="ignore"):
        return (1.0 - e) / (2.0 * np.sqrt(2.0 * e))


# --------------------------------------------------------------------------- #
# Files                                                                       #
# --------------------------------------------------------------------------- #


def _format(path):
    s = str(path).rstrip("/")
    if s.endswith(".zarr"):
        return "zarr"
    if s.endswith(".nc"):
        return "nc"
    raise ValueError(f"path must end in .zarr or .nc, got {str(path)!r}")


def save(ds, path, chunks=256, overwrite=False):
    """save(ds, path, chunks=256, overwrite=False) -> None

    Write a scan to ``.zarr`` (chunked ``chunks x chunks``) or ``.nc`` (netCDF4,
    compressed), atomically: under a temporary name, renamed when complete.

    An existing ``path`` is replaced only with ``overwrite=True``, and an
    existing folder only when it is a store this package wrote
    (:func:`stairbounce._io.atomic_path`); otherwise ``ValueError`` names it.
    In a Zarr store a chunk that is missing reads as :data:`FILL_VALUES`
    (status 255, counts -1), never as a valid result.
    """
    from ._io import atomic_path

    fmt = _format(path)
    chunks = check_count("chunks", chunks, 1)
    with atomic_path(path, overwrite=overwrite) as tmp:
        if fmt == "zarr":
            enc = {
                k: {"chunks": tuple(min(chunks, s) for s in ds[k].shape)}
                for k in ds.data_vars
            }
            for k in enc:
                if k in FILL_VALUES and ds[k].dtype == _FIELDS[k][0]:
                    enc[k]["fill_value"] = FILL_VALUES[k]
            ds.to_zarr(tmp, mode="w", encoding=enc, consolidated=False)
        else:
            enc = {k: {"zlib": True, "complevel": 4} for k in ds.data_vars}
            ds.to_netcdf(tmp, engine="netcdf4", format="NETCDF4", encoding=enc)


def load(path):
    """load(path) -> xarray.Dataset

    Read a scan written by :func:`save` (``.zarr`` or ``.nc``) into memory.

    A tiled store (:func:`stairbounce.atlas.scan_to_zarr`) reads the same way;
    where a tile is not computed yet (or a chunk was deleted) it reads as
    :data:`FILL_VALUES` (status 255), never as a result.  A file or chunk that
    cannot be decoded raises ``ValueError`` naming the file.
    """
    fmt = _format(path)
    if not os.path.exists(path):
        raise ValueError(f"no such file: {path}")
    engine = "zarr" if fmt == "zarr" else "netcdf4"
    kw = {"consolidated": False} if fmt == "zarr" else {}
    try:
        with xr.open_dataset(path, engine=engine, chunks=None, **kw) as ds:
            return ds.load()
    except (OSError, RuntimeError, ValueError, KeyError, TypeError) as exc:
        # a damaged file or chunk (a decompression error, a truncated file):
        # one line naming the file, not the reader's traceback
        reason = " ".join(str(exc).split()) or type(exc).__name__
        raise ValueError(f"cannot read {path} as a scan ({type(exc).__name__}: {reason})") from None
