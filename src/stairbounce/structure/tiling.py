"""An atlas's boxes as a tiling of its window, and the areas they prove.

Shared by the atlas (:class:`~stairbounce.CertifiedAtlas`, ``structure/certify.py``)
and the checker's verdict (``structure/verdict.py``), so that the numbers a user cites
from either are the same proven numbers; no code of the certifier's kernel is used.

Placement.  Box ``(level, i, j)`` of the window ``[e_lo, e_hi] x [u_lo, u_hi]`` at
``depth`` has the edges ``edge(e_lo, e_hi, i, level)``, ``edge(.., i + 1, level)``
(and the same along u with ``j``), ``edge(lo, hi, k, L) = lo + (hi - lo) * (k *
2^-L)`` for ``k < 2^L`` and ``hi`` for ``k = 2^L``: the float operations of the
certifier (``_kernel._edge``), each correctly rounded in numpy as in the compiled
kernel, so the edges are recomputed bit for bit.  ``k * 2^-L = (k 2^(D-L)) 2^-D``
exactly, so a box's edges are the edges of its index at the deepest level ``D``:
neighbouring boxes share their edges, at every level.  Rounding is monotone, so the
edges do not decrease with the index and every box lies in the window.

Overlap and coverage.  Box ``(L, i, j)`` is the set of cells ``(a, b)`` of level ``D``
with ``a >> (D - L) == i`` and ``b >> (D - L) == j``: a run of ``4^(D - L)``
consecutive Morton (Z-order) codes from ``morton(i, j) << 2(D - L)``.  Two boxes
overlap exactly when their runs do, and the boxes cover the window's ``4^D`` cells
exactly when the runs, sorted, do not overlap and add up to ``4^D``.  Because
neighbouring boxes share their float edges, the union of the float boxes of a
cover is then exactly the window.

Areas (proven).  A box's area ``(e1 - e0)(u1 - u0)`` is enclosed by outward
rounding: each difference and the product correctly rounded and moved one float
outward (``np.nextafter``), lower bounds clipped at 0.  A sum of such bounds is
taken with ``math.fsum`` (the correctly rounded sum of the floats) and moved one
float outward.  A share is a lower bound over an upper bound (and the reverse),
rounded outward.  So every ``lower <= exact <= upper``, where "exact" is the real
area (or share) of the float boxes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .certificate import STATUSES

__all__ = ["Tiling", "AreaBook", "box_edges", "tiling"]

_MAX_DEPTH = 26
_WORD_S, _NOSLIDING_S, _WITHIN_S, _UNDECIDED_S = (STATUSES.index(s) for s in
                                                   ("word", "no_sliding", "no_slide_within", "undecided"))


def _down(x):
    return np.nextafter(x, -np.inf)


def _up(x):
    return np.nextafter(x, np.inf)


def box_edges(lo, hi, level, k):
    """The edges ``k`` (int array) of the quadtree levels ``level`` (int array) of the
    axis ``[lo, hi]``: the certifier's floats (see the module's docstring)."""
    level = np.asarray(level, dtype=np.int64)
    k = np.asarray(k, dtype=np.int64)
    n = np.left_shift(np.int64(1), level)
    x = lo + (hi - lo) * (k.astype(np.float64) * (1.0 / n.astype(np.float64)))
    return np.where(k >= n, hi, x)


def _spread(x):
    """The bits of ``x`` (< 2^27) moved to the even positions (a Morton half)."""
    x = x.astype(np.uint64) & np.uint64(0xFFFFFFFF)
    for shift, mask in ((16, 0x0000FFFF0000FFFF), (8, 0x00FF00FF00FF00FF), (4, 0x0F0F0F0F0F0F0F0F),
                        (2, 0x3333333333333333), (1, 0x5555555555555555)):
        x = (x | (x << np.uint64(shift))) & np.uint64(mask)
    return x


@dataclass(frozen=True)
class Tiling:
    """How an atlas's boxes tile its window (:func:`tiling`).

    ``placed``: per box, whether it is the quadtree box ``(level, i, j)`` of the
    window at the depth, edges bit for bit; ``overlapping``: per box, whether it
    shares a cell of the deepest level with another box; ``complete``: the placed
    boxes, none overlapping, cover the window; ``missing``: the cells of the deepest
    level that no box covers (``4^depth`` minus the covered ones; meaningful when
    nothing overlaps).
    """

    placed: np.ndarray
    overlapping: np.ndarray
    complete: bool
    missing: int


def tiling(window, depth, level, i, j, e0, e1, u0, u1):
    """tiling(window, depth, level, i, j, e0, e1, u0, u1) -> Tiling

    Check the boxes against the quadtree of ``window = ((e_lo, e_hi), (u_lo, u_hi))``
    at ``depth`` (the module's docstring).  ``depth`` must be an int in [0, 26] and
    the window's bounds floats with ``e_lo < e_hi``, ``u_lo < u_hi`` (ValueError
    otherwise)."""
    (e_lo, e_hi), (u_lo, u_hi) = window
    if not (isinstance(depth, (int, np.integer)) and 0 <= depth <= _MAX_DEPTH):
        raise ValueError(f"depth must be an int in [0, {_MAX_DEPTH}], got {depth!r}")
    bounds = np.array([e_lo, e_hi, u_lo, u_hi], dtype=np.float64)
    if not (np.all(np.isfinite(bounds)) and e_lo < e_hi and u_lo < u_hi):
        raise ValueError(f"e_range and u_range must be increasing pairs of finite floats, got "
                         f"({e_lo}, {e_hi}), ({u_lo}, {u_hi})")
    level = np.asarray(level, dtype=np.int64)
    i = np.asarray(i, dtype=np.int64)
    j = np.asarray(j, dtype=np.int64)
    n_box = level.size
    ok = (level >= 0) & (level <= depth)
    safe = np.where(ok, level, 0)
    side = np.left_shift(np.int64(1), safe)
    ok &= (i >= 0) & (i < side) & (j >= 0) & (j < side)
    ii, jj = np.where(ok, i, 0), np.where(ok, j, 0)

    def same(a, b):  # bit for bit
        return np.asarray(a, np.float64).view(np.int64) == np.asarray(b, np.float64).view(np.int64)

    ok &= same(e0, box_edges(e_lo, e_hi, safe, ii)) & same(e1, box_edges(e_lo, e_hi, safe, ii + 1))
    ok &= same(u0, box_edges(u_lo, u_hi, safe, jj)) & same(u1, box_edges(u_lo, u_hi, safe, jj + 1))
    with np.errstate(invalid="ignore"):  # inside the window (NaN edges fail)
        ok &= (e_lo <= e0) & (e0 <= e1) & (e1 <= e_hi) & (u_lo <= u0) & (u0 <= u1) & (u1 <= u_hi)
    overlapping = np.zeros(n_box, dtype=bool)
    sel = np.flatnonzero(ok)
    shift = 2 * (depth - level[sel])
    start = ((_spread(ii[sel]) | (_spread(jj[sel]) << np.uint64(1))).astype(np.int64)) << shift
    end = start + (np.int64(1) << shift)
    order = np.argsort(start, kind="stable")
    s, t = start[order], end[order]
    # a box overlaps a box sorted before it when it starts before the furthest end so far
    clash = np.zeros(s.size, dtype=bool)
    if s.size:
        clash[1:] = s[1:] < np.maximum.accumulate(t)[:-1]
    overlapping[sel[order[clash]]] = True
    # without overlaps the runs add up to at most 4^depth <= 2^52: no int64 overflow
    covered = int((end - start).sum()) if not clash.any() else -1
    total = 4 ** depth
    return Tiling(placed=ok, overlapping=overlapping, complete=bool(ok.all() and covered == total),
                  missing=total - covered if covered >= 0 else -1)


MAX_TRAP_SPLIT = 4
"""The most levels below its depth an atlas's trapping pass may split a box into
(attribute ``trap_split``, ``structure/trapping.py``)."""


def deepest_level(depth, attrs):
    """The deepest level an atlas's boxes may have: ``depth`` plus the levels its
    trapping pass split boxes below it (``attrs["trap_split"]``, 0 when absent; an
    int in [0, :data:`MAX_TRAP_SPLIT`], the sum at most 26, else ValueError)."""
    split = attrs.get("trap_split", 0)
    if isinstance(split, np.ndarray) and split.size == 1:
        split = split.item()
    if not (isinstance(split, (int, np.integer)) and not isinstance(split, bool)
            and 0 <= split <= MAX_TRAP_SPLIT and int(depth) + int(split) <= _MAX_DEPTH):
        raise ValueError(f"atlas: the attribute trap_split must be an int in [0, {MAX_TRAP_SPLIT}] with depth + "
                         f"trap_split <= {_MAX_DEPTH}, got {split!r} (depth {depth})")
    return int(depth) + int(split)


def _sum_bounds(lo, hi):
    """Bounds on the exact sums of the floats ``lo`` (below) and ``hi`` (above)."""
    if not len(lo):
        return 0.0, 0.0
    return max(float(_down(math.fsum(lo))), 0.0), float(_up(math.fsum(hi)))


def area_bounds(e0, e1, u0, u1):
    """Per box, ``(lo, hi)`` arrays enclosing the exact area ``(e1 - e0)(u1 - u0)``."""
    we, wu = np.asarray(e1) - np.asarray(e0), np.asarray(u1) - np.asarray(u0)
    lo = np.maximum(_down(np.maximum(_down(we), 0.0) * np.maximum(_down(wu), 0.0)), 0.0)
    hi = _up(_up(we) * _up(wu))
    return lo, hi


def unique_inverse(values):
    """``(names, inverse)`` as ``np.unique(values, return_inverse=True)`` gives them
    (the distinct values sorted; ``names[inverse] == values``), by hashing
    (``pandas.factorize``): ``np.unique`` sorts an object array of millions of
    words in one call that holds Python's lock for seconds, so that Ctrl-C
    waited for it (issue 45, item 5); the hash table is a fraction of that."""
    import pandas as pd

    values = np.asarray(values)
    if values.dtype.kind != "O":
        names, inverse = np.unique(values, return_inverse=True)
        return names, inverse.ravel()
    codes, names = pd.factorize(values, sort=True)
    return np.asarray(names, dtype=object), codes.astype(np.int64, copy=False)


class AreaBook:
    """Proven areas and shares of sets of an atlas's boxes.

    ``e0, e1, u0, u1``: the boxes; ``window``: ``((e_lo, e_hi), (u_lo, u_hi))``;
    ``complete``: whether the boxes tile the window (:class:`Tiling`).  Shares are of
    the window when complete, else of the covered part (the boxes' union), which
    ``of`` names.
    """

    def __init__(self, e0, e1, u0, u1, window, complete):
        self.lo, self.hi = area_bounds(e0, e1, u0, u1)
        self.complete = bool(complete)
        (a, b), (c, d) = window
        wlo, whi = area_bounds(np.array([a]), np.array([b]), np.array([c]), np.array([d]))
        self.window = (float(wlo[0]), float(whi[0]))
        self.covered = self.window if self.complete else _sum_bounds(self.lo, self.hi)
        self.of = "the window" if self.complete else "the covered part"

    def area(self, mask):
        """``(lower, upper)`` on the total area of the boxes ``mask``."""
        return _sum_bounds(self.lo[mask], self.hi[mask])

    def share(self, mask):
        """``(lower, upper)`` on the share of the boxes ``mask`` in :attr:`covered`."""
        lo, hi = self.area(mask)
        return self._ratio(lo, hi)

    def _ratio(self, lo, hi):
        clo, chi = self.covered
        return (max(float(_down(lo / chi)), 0.0) if chi > 0 else 0.0,
                min(float(_up(hi / clo)), 1.0) if clo > 0 else 1.0)

    def groups(self, keys, mask):
        """``{key: (lower, upper)}`` on the area of the boxes ``mask`` by ``keys``."""
        sel = np.flatnonzero(mask)
        if not sel.size:
            return {}
        names, inverse = unique_inverse(np.asarray(keys)[sel])
        order = np.argsort(inverse, kind="stable")
        cuts = np.searchsorted(inverse[order], np.arange(names.size + 1))
        lo, hi = self.lo[sel][order], self.hi[sel][order]
        return {names[k]: _sum_bounds(lo[cuts[k]:cuts[k + 1]], hi[cuts[k]:cuts[k + 1]]) for k in range(names.size)}

    def word_bounds(self, status, words, max_iter, period, only=None):
        """``{word: (lower, upper)}`` on the area (of :attr:`covered`) of the points whose
        periodic sliding solution has the word, for every proven word (or the word
        ``only``): lower, its proven boxes; upper, the covered area less every box
        proven to be something else (another word, ``no_sliding``, and
        ``no_slide_within`` when the word's period, ``period(word)``, is at most
        ``max_iter``)."""
        is_word = status == _WORD_S
        sums = self.groups(words, is_word)
        if only is not None:
            sums = {only: sums.get(only, (0.0, 0.0))}
        return word_area_bounds(sums, self.area(is_word)[0], self.area(status == _NOSLIDING_S)[0],
                                self.area(status == _WITHIN_S)[0], self.covered[1], max_iter, period)


def word_area_bounds(bounds, all_words, nos, within, covered_hi, max_iter, period):
    """``{word: (lower, upper)}`` from each word's ``(lower, upper)`` on the area of its
    proven boxes (``bounds``): lower, that of its boxes; upper, ``covered_hi`` less
    every box proven to be something else: the other words' (at least the lower bound
    ``all_words`` on all the words' boxes less this word's upper bound), ``no_sliding``'s
    (``nos``, a lower bound) and ``no_slide_within``'s (``within``) when the word's
    ``period(word)`` is at most ``max_iter``; rounded outward.  :meth:`AreaBook.word_bounds`
    and a streamed store's verdict (its exact sums) give it their bounds."""
    out = {}
    for w, (lo, hi) in bounds.items():
        other = _down(max(float(_down(all_words - hi)), 0.0) + nos)
        if period(w) <= max_iter:
            other = _down(other + within)
        out[w] = (lo, float(_up(covered_hi - other)))
    return out


def log2_ratio_bounds(num, den):
    """Bounds on ``log2(num / den)`` for positive integer arrays (``-inf``/``inf``/nan
    where a count is 0): the float value moved 4 floats outward, beyond the error of
    the division (half an ulp) and of numpy's ``log2`` (within an ulp)."""
    num = np.asarray(num, dtype=np.float64)
    den = np.asarray(den, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        x = np.log2(num / den)
    lo, hi = x.copy(), x.copy()
    for _ in range(4):
        lo, hi = _down(lo), _up(hi)
    exact = np.isinf(x) | np.isnan(x)
    return np.where(exact, x, lo), np.where(exact, x, hi)
