"""Discontinuity-induced bifurcations along an orbit diagram's parameter
(:func:`bifurcations`): the changes of the long-run itinerary between swept
values, bisected to rounding and labelled by their event as the border points
are (:mod:`.borders`).
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from numba import njit, prange

from .. import _validate as _v
from .._interrupt import halted
from ..model import SLIDING, _constants, _step, check_count, check_state
from .borders import _at, _event_of
from .itinerary import KINDS
from .words import _word_text

__all__ = ["bifurcations"]


# --------------------------------------------------------------------------- #
# Discontinuity-induced bifurcations along an orbit diagram's parameter       #
# --------------------------------------------------------------------------- #


@njit(cache=True)
def _long_run(e, u, y0, v0, transient, keep, buf, halt):
    """The long-run itinerary at ``(e, u)`` from ``(y0, v0)``: the impact numbers
    of steps ``transient + 1 .. transient + keep`` (the orbit diagram's kept
    steps) into ``buf[:keep]``, then their period ``P`` (the smallest
    ``P <= keep // 2`` with ``k[i] = k[i + P]`` over the window; 0: none, the
    itinerary is not periodic within the window) and, when ``P > 0``, the
    pattern rotated to its smallest lexicographic rotation in ``buf[:P]``, so
    that two parameters with the same periodic itinerary give the same
    ``(P, buf[:P])`` whatever their phase."""
    T, ratio = _constants(e, u)
    y, v = y0, v0
    for n in range(transient):
        if (n & 0xFFFF) == 0xFFFF and halted(halt):
            return 0
        y, v, k = _step(y, v, e, T, ratio)
    for n in range(keep):
        y, v, k = _step(y, v, e, T, ratio)
        buf[n] = k
    P = 0
    for p in range(1, keep // 2 + 1):
        same = True
        for i in range(keep - p):
            if buf[i] != buf[i + p]:
                same = False
                break
        if same:
            P = p
            break
    if P == 0:
        return 0
    best = 0
    for r in range(1, P):
        for i in range(P):
            a = buf[(r + i) % P]
            b = buf[(best + i) % P]
            if a != b:
                if a < b:
                    best = r
                break
    tmp = buf[keep:keep + P]
    for i in range(P):
        tmp[i] = buf[(best + i) % P]
    for i in range(P):
        buf[i] = tmp[i]
    return P


@njit(cache=True)
def _same_run(pa, a, pb, b):
    """Whether two long-run itineraries ``(P, pattern)`` are the same."""
    if pa != pb:
        return False
    for i in range(pa):
        if a[i] != b[i]:
            return False
    return True


@njit(cache=True, parallel=True, nogil=True)
def _long_run_kernel(xs, f, axis, y0, v0, transient, keep, periods, patterns, halt):
    """:func:`_long_run` at every swept value ``xs[i]`` (the other parameter ``f``)."""
    for i in prange(xs.shape[0]):
        if halted(halt):
            continue
        e, u = _at(xs[i], f, axis)
        periods[i] = _long_run(e, u, y0, v0, transient, keep, patterns[i], halt)


@njit(cache=True, parallel=True, nogil=True)
def _bifurcation_kernel(xa, xb, pa, pb, f, axis, y0, v0, transient, keep, pat_a, pat_b, out, halt):
    """Bisect each interval ``[xa[i], xb[i]]`` whose ends have different long-run
    itineraries (``pa``/``pat_a``, ``pb``/``pat_b``, updated in place to the
    final low and high ends') to adjacent floats, keeping the itinerary of a
    periodic end (the shorter period) as the reference, so that the border
    found is that reference's; ``out[i]``: the low end, the width, the
    first step from ``(y0, v0)`` where the two ends' impact numbers differ, the
    event's kind code and index, the impact numbers there (low, high)."""
    for i in prange(xa.shape[0]):
        if halted(halt):
            continue
        buf = np.empty(2 * keep, np.int64)
        # the reference end: a periodic one (the shorter period), as in border_points
        a_ref = pa[i] != 0 and (pb[i] == 0 or pa[i] <= pb[i])
        xr_, xo = (xa[i], xb[i]) if a_ref else (xb[i], xa[i])
        pr = pa[i] if a_ref else pb[i]
        ref = pat_a[i].copy() if a_ref else pat_b[i].copy()
        po = pb[i] if a_ref else pa[i]
        pat_o = pat_b[i].copy() if a_ref else pat_a[i].copy()
        while True:
            m = 0.5 * (xr_ + xo)
            if m == xr_ or m == xo:
                break
            e, u = _at(m, f, axis)
            pm = _long_run(e, u, y0, v0, transient, keep, buf, halt)
            if _same_run(pm, buf, pr, ref):
                xr_ = m
            else:
                xo = m
                po = pm
                for n in range(2 * keep):
                    pat_o[n] = buf[n]
        lo, hi = min(xr_, xo), max(xr_, xo)
        low_ref = xr_ < xo
        pa[i] = pr if low_ref else po
        pb[i] = po if low_ref else pr
        for n in range(2 * keep):
            pat_a[i, n] = ref[n] if low_ref else pat_o[n]
            pat_b[i, n] = pat_o[n] if low_ref else ref[n]
        el, ul = _at(lo, f, axis)
        eh, uh = _at(hi, f, axis)
        Tl, rl = _constants(el, ul)
        Th, rh = _constants(eh, uh)
        yl, vl, yh, vh = y0, v0, y0, v0
        j = 0
        kl = kh = 0
        for n in range(transient + keep):
            yl, vl, kl = _step(yl, vl, el, Tl, rl)
            yh, vh, kh = _step(yh, vh, eh, Th, rh)
            if kl != kh:
                j = n + 1
                break
        kind, index = _event_of(kl, kh)
        out[i, 0] = lo
        out[i, 1] = hi - lo
        out[i, 2] = j
        out[i, 3] = kind
        out[i, 4] = index
        out[i, 5] = kl
        out[i, 6] = kh
        out[i, 7] = low_ref


def _run_text(p, pattern):
    """Text of a long-run itinerary: the word of a periodic sliding solution, the
    impact numbers of one period of a periodic orbit, or "not periodic"."""
    if p == 0:
        return "not periodic within keep"
    ks = np.asarray(pattern[:p])
    if np.any(ks == SLIDING):
        # rotate so that the period ends with its slide: the orbit of (1, 0)
        last = int(np.flatnonzero(ks == SLIDING)[-1])
        return _word_text(np.roll(ks, p - 1 - last))
    return "periodic, impacts (" + ", ".join(str(int(k)) for k in ks) + ") per period"


# rounds of bisection per interval between two swept values (changes found in one)
_MAX_ROUNDS = 64


def bifurcations(e, u, y0=0.1, v0=0.0, transient=2000, keep=200):
    """bifurcations(e, u, y0=0.1, v0=0.0, transient=2000, keep=200) -> xarray.Dataset

    The discontinuity-induced bifurcations along an orbit diagram's parameter
    range, located to rounding and labelled by their event.

    Arguments as :func:`stairbounce.orbit_diagram`: exactly one of ``e``,
    ``u`` is a 1-D array (the swept values, sorted here), the orbit starts at
    ``(y0, v0)``, ``transient`` steps are discarded and the next ``keep`` give
    the long-run itinerary (their impact numbers, as a periodic pattern up to
    its phase, or "not periodic" when no period ``<= keep/2`` repeats over
    the window).  Between consecutive swept values whose long-run
    itineraries differ the parameter is bisected (the outcome: the long-run
    itinerary; the reference is a periodic end, the shorter period) until no
    float lies in between; the rest of the interval, beyond the change found,
    is bisected again while its ends differ (up to 64 changes per interval).  The orbits from ``(y0, v0)``
    at the two final ends then agree up to a step ``j - 1`` and differ at
    step ``j`` by one event at the step's edge, labelled as in
    :func:`border_points`: ``graze`` (the grazing bifurcations of Section 4
    where new branches of Fig. 8 arise), ``edge`` or ``chatter``.  Changes
    between two values that both are not periodic are not bisected (chaos
    has no single itinerary), nor is a cascade whose far end is not periodic
    beyond its first change; a change that happens and undoes itself between
    two swept values is not seen.

    Returns
    -------
    xarray.Dataset
        Dimension ``bifurcation``; variables: ``value`` (the swept parameter
        at the low end of the final bracket), ``width``, ``kind``, ``step``
        (j, from the start, transient included), ``index``,
        ``impacts_low``, ``impacts_high`` (at step j), ``period_low``,
        ``period_high`` (steps per period of the long-run itinerary, 0 when
        not periodic), ``itinerary_low``, ``itinerary_high`` (text: a sliding
        solution's word, or a periodic orbit's impact numbers per period).
        Attributes: ``varied``, the fixed parameter, ``y0``, ``v0``,
        ``transient``, ``keep``.

    Raises
    ------
    ValueError
        As :func:`stairbounce.orbit_diagram`.
    """
    from .._interrupt import run_kernel
    from ..orbits import _parameter

    ea, e_swept = _parameter("e", e)
    ua, u_swept = _parameter("u", u)
    if e_swept == u_swept:
        raise ValueError("exactly one of e, u must be a 1-D array (the swept parameter) and the other "
                         f"a float, got {'two arrays' if e_swept else 'two floats'}")
    y0, v0 = check_state(y0, v0, "y0", "v0")
    transient = check_count("transient", transient, 0)
    keep = check_count("keep", keep, 2, 10**6)
    varied = "e" if e_swept else "u"
    xs = np.unique(ea if e_swept else ua)
    f = float(ua if e_swept else ea)
    axis = 0 if e_swept else 1
    _v.check_memory(f"{xs.size} long-run itineraries of {keep} steps", 16 * keep * xs.size)
    periods = np.zeros(xs.size, np.int64)
    patterns = np.zeros((xs.size, 2 * keep), np.int64)
    run_kernel(_long_run_kernel, xs, f, axis, y0, v0, transient, keep, periods, patterns)
    differ = np.zeros(max(xs.size - 1, 0), bool)
    for i in range(xs.size - 1):
        if periods[i] == 0 and periods[i + 1] == 0:
            continue
        differ[i] = not _same_run(periods[i], patterns[i], periods[i + 1], patterns[i + 1])
    idx = np.flatnonzero(differ)
    # each round bisects every open interval once; the part of an interval on
    # the far side of the change found is bisected again in the next round
    # while its ends still differ (a cascade of changes between two values)
    xa, xb = xs[idx], xs[idx + 1]
    qa, qb = periods[idx], periods[idx + 1]
    ra, rb = patterns[idx], patterns[idx + 1]
    found = []
    for _ in range(_MAX_ROUNDS):
        if xa.size == 0:
            break
        pa, pb, pat_a, pat_b = qa.copy(), qb.copy(), ra.copy(), rb.copy()
        out = np.zeros((xa.size, 8))
        run_kernel(_bifurcation_kernel, xa, xb, pa, pb, f, axis, y0, v0, transient, keep,
                   pat_a, pat_b, out)
        found.append((out, pa, pb, pat_a, pat_b))
        low_ref = out[:, 7] == 1
        lo, hi = out[:, 0], out[:, 0] + out[:, 1]
        # the rest: [hi, xb] (the reference was the low end) or [xa, lo]
        na = np.where(low_ref, hi, xa)
        nb = np.where(low_ref, xb, lo)
        npa = np.where(low_ref, pb, qa)
        npb = np.where(low_ref, qb, pa)
        nra = np.where(low_ref[:, None], pat_b, ra)
        nrb = np.where(low_ref[:, None], rb, pat_a)
        keep_on = np.array([na[i] < nb[i] and not (npa[i] == 0 and npb[i] == 0)
                            and not _same_run(npa[i], nra[i], npb[i], nrb[i]) for i in range(na.size)],
                           dtype=bool)
        xa, xb, qa, qb, ra, rb = (na[keep_on], nb[keep_on], npa[keep_on], npb[keep_on],
                                  nra[keep_on], nrb[keep_on])
    if found:
        out = np.concatenate([o for o, *_ in found])
        pa = np.concatenate([p for _, p, *_ in found])
        pb = np.concatenate([p for _, _, p, *_ in found])
        pat_a = np.concatenate([p for *_, p, _ in found])
        pat_b = np.concatenate([p for *_, p in found])
        order = np.argsort(out[:, 0], kind="stable")
        out, pa, pb, pat_a, pat_b = out[order], pa[order], pb[order], pat_a[order], pat_b[order]
    else:
        out = np.zeros((0, 8))
        pa = pb = np.zeros(0, np.int64)
        pat_a = pat_b = np.zeros((0, 2 * keep), np.int64)
    dim = ("bifurcation",)
    kinds = np.array(KINDS, dtype=object)[out[:, 3].astype(np.int64)]
    data = {
        "value": (dim, out[:, 0], {"long_name": f"{varied} at the low end of the final bracket"}),
        "width": (dim, out[:, 1], {"long_name": "width of the final bracket"}),
        "kind": (dim, kinds, {"long_name": "event at the step's edge: graze, edge or chatter"}),
        "step": (dim, out[:, 2].astype(np.int64), {"long_name": "first step from (y0, v0) that differs"}),
        "index": (dim, out[:, 4].astype(np.int64), {"long_name": "impact whose time equals T"}),
        "impacts_low": (dim, out[:, 5].astype(np.int64), {"long_name": "impact number at the step, low side"}),
        "impacts_high": (dim, out[:, 6].astype(np.int64), {"long_name": "impact number at the step, high side"}),
        "period_low": (dim, pa, {"long_name": "period of the long-run itinerary, low side (0: not periodic)"}),
        "period_high": (dim, pb, {"long_name": "period of the long-run itinerary, high side (0: not periodic)"}),
        "itinerary_low": (dim, np.array([_run_text(p, r) for p, r in zip(pa, pat_a)], dtype=object),
                          {"long_name": "long-run itinerary, low side"}),
        "itinerary_high": (dim, np.array([_run_text(p, r) for p, r in zip(pb, pat_b)], dtype=object),
                           {"long_name": "long-run itinerary, high side"}),
    }
    fixed = "u" if e_swept else "e"
    return xr.Dataset(data, attrs={"title": "discontinuity-induced bifurcations", "varied": varied,
                                   fixed: f, "y0": y0, "v0": v0, "transient": transient, "keep": keep})
