"""The words of points: the text of the periodic sliding solution through
``(1, 0)`` at many points at once (:func:`_words`), the points grouped by
equal itineraries (:func:`_word_groups`: hashed rows, checked equal), and
:data:`NONE_WORD` for a point whose orbit does not slide within ``max_iter``.
The border points (:mod:`.borders`) and the checks (:mod:`.checks`) label
their sides with them.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from .. import _validate as _v
from .itinerary import _impacts_from_rest


NONE_WORD = "none within max_iter"
"""The word given to a side whose orbit of ``(1, 0)`` does not slide within max_iter steps."""


@njit(cache=True, parallel=True)
def _fill_impacts(e, u, periods, offsets, flat):
    """Impact numbers of the orbit of ``(1, 0)`` at each ``(e[i], u[i])`` into
    ``flat[offsets[i]:offsets[i] + periods[i]]`` (sides that slide only)."""
    for i in prange(e.shape[0]):
        p = periods[i]
        if p > 0:
            _impacts_from_rest(e[i], u[i], p, flat[offsets[i]:offsets[i] + p])


def _word_text(ks):
    """ASCII text of the word of one period from its impact numbers (the last
    ``SLIDING``): the text of ``symbolic.word_from_impacts(ks).format(ascii=True)``
    (a test compares them) without validating every letter again."""
    letters = []
    jump = 0
    for k in ks.tolist():
        jump += 1
        if k == 0:
            continue
        letters.append(str(jump))
        jump = 0
        if k > 1:
            letters.extend(["0"] * (k - 1))
    return "(" + ", ".join(letters) + ", 0^inf)"


def _word_groups(e, u, periods):
    """The distinct words of the orbits of ``(1, 0)`` at ``(e[i], u[i])``.

    ``periods[i]``: the period of the word there (0: no slide, id -1).
    Returns ``(ids, rows)``: ``rows[ids[i]]`` is the impact numbers of point
    i's period.  All impact numbers are computed in one parallel pass and
    grouped by a hash; every row is then compared whole with its group's
    first row (exact: on a collision the rows are grouped by comparing them
    whole, period by period)."""
    periods = np.asarray(periods, np.int64)
    ids = np.full(e.size, -1, np.int64)
    offsets = np.concatenate([[0], np.cumsum(periods)]).astype(np.int64)
    _v.check_memory(f"the words of {e.size} points", 8 * int(offsets[-1]))
    flat = np.empty(int(offsets[-1]), np.int64)
    _fill_impacts(np.ascontiguousarray(e, np.float64), np.ascontiguousarray(u, np.float64),
                  periods, offsets, flat)
    hashes = np.empty(e.size, np.uint64)
    _hash_rows(periods, offsets, flat, hashes)
    sl = np.flatnonzero(periods > 0)
    keys, first, inverse = np.unique(hashes[sl], return_index=True, return_inverse=True)
    inverse = inverse.ravel()
    rep = sl[first]
    if _rows_equal(periods, offsets, flat, sl, rep[inverse]):
        ids[sl] = inverse
        rows = [flat[offsets[r]:offsets[r] + periods[r]] for r in rep]
        return ids, rows
    # a hash collision (never seen): compare whole rows, period by period
    rows = []
    for p in np.unique(periods[periods > 0]):
        where = np.flatnonzero(periods == p)
        block = flat[offsets[where][:, None] + np.arange(p)]
        distinct, inverse = np.unique(block, axis=0, return_inverse=True)
        ids[where] = len(rows) + inverse.ravel()
        rows.extend(distinct)
    return ids, rows


@njit(cache=True, parallel=True)
def _hash_rows(periods, offsets, flat, out):
    """A 64-bit FNV-1a hash of each row ``flat[offsets[i]:offsets[i] + periods[i]]``."""
    for i in prange(periods.shape[0]):
        h = np.uint64(14695981039346656037)
        for n in range(offsets[i], offsets[i] + periods[i]):
            h = (h ^ np.uint64(flat[n] & 0xFFFFFFFFFFFF)) * np.uint64(1099511628211)
        out[i] = h ^ np.uint64(periods[i])


@njit(cache=True)
def _rows_equal(periods, offsets, flat, rows, reps):
    """Whether each row ``rows[i]`` equals the row ``reps[i]``, element by element."""
    for i in range(rows.shape[0]):
        a, b = rows[i], reps[i]
        if periods[a] != periods[b]:
            return False
        for n in range(periods[a]):
            if flat[offsets[a] + n] != flat[offsets[b] + n]:
                return False
    return True


def _words(e, u, periods):
    """Word text of each point: ASCII ``(2, 0, 1, 0^inf)`` or :data:`NONE_WORD`."""
    ids, rows = _word_groups(e, u, periods)
    names = np.array([_word_text(r) for r in rows] + [NONE_WORD], dtype=object)
    return names[ids]  # id -1: the last name
