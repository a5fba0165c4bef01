"""The exact search on a line of the plane: the compiled bisection on the order of
itineraries (the package docstring), the members' edges, the lines' arguments, the
enclosure of an accumulation point, and the words at points.  Moved verbatim from
``cascades.py`` and ``cascade_families.py``."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..structure.borders import _event_of, _first_difference, _shrink_secant, _trial
from ..structure.itinerary import KINDS
from ..structure.words import _word_groups
from ..model import SLIDING, check_e, check_u
from ..symbolic import sliding_word, word_from_impacts

# search outcomes
_FOUND, _BEHIND, _BEYOND, _EMPTY = 0, 1, 2, 3


# --------------------------------------------------------------------------- #
# Compiled search                                                             #
# --------------------------------------------------------------------------- #


@njit(cache=True)
def _side(x, f, axis, ref, p):
    """Where the points with the impact numbers ``ref[:p]`` lie from ``x``:
    0 at ``x``, +1 at larger x, -1 at smaller x (module docstring: the
    impact numbers are lexicographically non-increasing along the line).
    Returns ``(side, step of the first difference)``."""
    follows, dev, kdev, _, _ = _trial(x, f, axis, ref, p, 0, 0, 0)
    if follows:
        return 0, 0
    r = ref[dev - 1]
    a = 1 << 62 if kdev == SLIDING else kdev
    b = 1 << 62 if r == SLIDING else r
    return (1 if a > b else -1), dev


@njit(cache=True)
def _search(lo, hi, f, axis, ref, p):
    """Bisect ``[lo, hi]`` on :func:`_side` for a point with ``ref[:p]``.

    Returns ``(outcome, x, lo, hi, trials)``: ``_FOUND`` with ``x`` such a
    point; ``_BEHIND`` / ``_BEYOND`` when the points lie below ``lo`` /
    above ``hi``; ``_EMPTY`` when the bracket shrank to adjacent floats
    ``lo``, ``hi`` without one (no float of the line has ``ref``).
    """
    s, _ = _side(lo, f, axis, ref, p)
    if s == 0:
        return _FOUND, lo, lo, hi, 1
    if s < 0:
        return _BEHIND, math.nan, lo, hi, 1
    s, _ = _side(hi, f, axis, ref, p)
    if s == 0:
        return _FOUND, hi, lo, hi, 2
    if s > 0:
        return _BEYOND, math.nan, lo, hi, 2
    trials = 2
    while True:
        m = 0.5 * (lo + hi)
        if m <= lo or m >= hi:
            return _EMPTY, math.nan, lo, hi, trials
        s, _ = _side(m, f, axis, ref, p)
        trials += 1
        if s == 0:
            return _FOUND, m, lo, hi, trials
        if s > 0:
            lo = m
        else:
            hi = m


# --------------------------------------------------------------------------- #
# Members                                                                     #
# --------------------------------------------------------------------------- #


def _edge(x_in, x_out, f, axis, ref):
    """Shrink ``[x_in, x_out]`` (``x_in`` has ``ref``, ``x_out`` not) to
    adjacent floats; the edge's label as border_points gives it."""
    p = ref.shape[0]
    xc, xo, trials, _ = _shrink_secant(x_in, x_out, f, axis, ref, p)
    j, kc, ko, _, _ = _first_difference(xc, xo, f, axis, p)
    kind, index = _event_of(kc, ko)
    return xc, xo, int(j), KINDS[kind], int(index), int(ko), int(trials)


def _neighbour(x, f, axis, max_iter):
    e, u = (x, f) if axis == 0 else (f, x)
    w = sliding_word(e, u, max_iter)
    return w.format(ascii=True) if w is not None else "none within max_iter"


def _is_pair(x):
    return isinstance(x, (tuple, list, np.ndarray))


def _line_args(e, u):
    """Which coordinate varies: ``(axis, name, lo, hi, fixed)``."""
    e_pair, u_pair = _is_pair(e), _is_pair(u)
    if e_pair == u_pair:
        raise ValueError("e and u: give one as a range (lo, hi) and the other as a number "
                         f"(a line of the plane), got e={e!r}, u={u!r}")
    axis, name, rng, fixed = (0, "e", e, u) if e_pair else (1, "u", u, e)
    if len(rng) != 2:
        raise ValueError(f"{name} must be a range (lo, hi) of two numbers, got {rng!r}")
    if axis == 0:
        lo, hi = check_e(rng[0]), check_e(rng[1])
        fixed = check_u(fixed)
    else:
        lo, hi = check_u(rng[0]), check_u(rng[1])
        fixed = check_e(fixed)
    if not lo < hi:
        raise ValueError(f"{name} must be a range (lo, hi) with lo < hi, got {rng!r}")
    return axis, name, lo, hi, fixed


def _limit_enclosure(pat, n, lo, hi, f, axis):
    """The closure of I_n (the points whose first ``n`` impact numbers are the
    limit's), as ``(lo, hi, n)``, or None where it cannot be located."""
    ref = pat.limit_impacts(n)
    if ref is None or ref.shape[0] == 0:
        return None
    m = ref.shape[0]
    out, x, a, b, _ = _search(lo, hi, f, axis, ref, m)
    if out == _EMPTY:
        return float(a), float(b), m
    if out != _FOUND:
        return None
    lo_out = lo if x == lo else float(_shrink_secant(x, a, f, axis, ref, m)[1])
    hi_out = hi if x == hi else float(_shrink_secant(x, b, f, axis, ref, m)[1])
    return lo_out, hi_out, m


# --------------------------------------------------------------------------- #
# Words at points                                                             #
# --------------------------------------------------------------------------- #


def _words_at(es, us, max_iter):
    """The word of the orbit of (1, 0) at each point: ``(ids, letters)``,
    ``letters[ids[i]]`` the letters of point i's word (id -1: no slide within
    ``max_iter``), as :func:`stairbounce.word_table` groups them."""
    from ..plane import scan_points

    es = np.ascontiguousarray(es, np.float64)
    us = np.ascontiguousarray(us, np.float64)
    ds = scan_points(es, us, max_iter=max_iter)
    period = np.where(ds.status.values == 0, ds.period.values, 0).astype(np.int64)
    ids, rows = _word_groups(es, us, period)
    return ids, [word_from_impacts(r).letters for r in rows]


def _centres(lo, hi, n):
    return lo + (np.arange(n) + 0.5) * (hi - lo) / n


def _window(name, rng):
    if not isinstance(rng, (tuple, list, np.ndarray)) or len(rng) != 2:
        raise ValueError(f"{name} must be a range (lo, hi) of two numbers, got {rng!r}")
    check = check_e if name == "e" else check_u
    lo, hi = check(rng[0]), check(rng[1])
    if not lo < hi:
        raise ValueError(f"{name} must be a range (lo, hi) with lo < hi, got {rng!r}")
    return lo, hi


