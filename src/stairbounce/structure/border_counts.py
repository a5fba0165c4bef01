"""The proven box counts of the paper's perimeter taken from a streamed atlas
(:func:`stairbounce.certify_to_zarr`) one tile at a time (issue 44, items 1 and 4).

:meth:`CertifiedAtlas.border_box_counts` holds every box; at depth 14 that is about
4 GiB for the Fig. 7 window.  Here the store's tiles are read one after another and
each is let go before the next, so the memory is that of a tile plus one bit per cell
of every scale (a bitmap of the cells meeting an undecided box, ``4^k / 8`` bytes at
scale k: about 0.7 GiB for all scales at depth 16).

The counts are those of :meth:`CertifiedAtlas.border_box_counts` with
``border="sliding"``, integer for integer (the tests compare them on stores of several
windows, with and without class-level proofs and trapping regions):

* ``upper`` at scale k: the cells whose closure meets an undecided box, or which hold
  boxes of both classes.  A cell meets an undecided box of its own level or finer when
  it holds it, or when the box touches the cell's side (then the neighbour across that
  side, or corner, meets its closure); an undecided box coarser than the cell meets the
  cells it covers and the ring around them.  Each such cell sets its bit; the count is
  the bits set.
* ``lower`` at scale k: the cells holding a proven sliding box and a proven non-sliding
  box.  A cell of scale ``k >= T`` (the store's tile level) lies in one level-T cell, and
  every box in a level-T cell is in one tile (``certify_to_zarr`` cuts the quadtree
  there; checked here, and a store cut otherwise is refused), so such a cell's classes
  are all in one tile and it is counted with its tile.  The coarser scales (at most
  ``4^(T-1)`` cells) keep a bitmap per class across the tiles.

What the counts assume: the boxes tile the window (they are its quadtree's and do
not overlap).  That is what ``sb.verify(path)`` checks, box by box and across tiles;
:meth:`CertifiedStore.perimeter_bracket` runs it and calls the counts proven only when
it passes.  Here the boxes' cells are summed (a Python integer) and a store whose boxes
do not add up to the window is refused, as :meth:`CertifiedAtlas.border_box_counts`
refuses an atlas that does not cover its window.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .certify import _border_classes, counted_depth


@njit(cache=True, nogil=True)
def _set(bits, c):
    bits[c >> 3] |= np.uint8(1 << (c & 7))


@njit(cache=True, nogil=True, inline="always")
def closure_cells(k, L, i, j):
    """``(a0, a1, b0, b1)``: the scale-k cells ``a0 .. a1`` by ``b0 .. b1`` (along e, u;
    not clipped to the window) whose closure meets the box ``(L, i, j)``: its own cell and
    the neighbours across the sides (and corners) it touches, or for a box coarser than
    the cells those it covers and the ring around them."""
    if L >= k:
        sh = L - k
        m = (np.int64(1) << sh) - 1
        ci, cj = i >> sh, j >> sh
        a0 = ci - 1 if (i & m) == 0 else ci
        a1 = ci + 1 if (i & m) == m else ci
        b0 = cj - 1 if (j & m) == 0 else cj
        b1 = cj + 1 if (j & m) == m else cj
        return a0, a1, b0, b1
    f = np.int64(1) << (k - L)
    return i * f - 1, (i + 1) * f, j * f - 1, (j + 1) * f


@njit(cache=True, nogil=True)
def _touch(bits, k, level, ii, jj):
    """Set the bits of the scale-k cells (``2^k`` a side, code ``ci * 2^k + cj``) whose
    closure meets one of the boxes ``(level, i, j)`` (the undecided ones)."""
    n = np.int64(1) << k
    for b in range(level.size):
        a0, a1, b0, b1 = closure_cells(np.int64(k), np.int64(level[b]), np.int64(ii[b]), np.int64(jj[b]))
        for a in range(max(a0, 0), min(a1, n - 1) + 1):
            for c in range(max(b0, 0), min(b1, n - 1) + 1):
                _set(bits, a * n + c)


@njit(cache=True, nogil=True)
def _mark(bits, k, level, ii, jj):
    """Set the bit of the scale-k cell holding each box ``(level >= k, i, j)``."""
    for b in range(level.size):
        sh = np.int64(level[b]) - k
        _set(bits, (np.int64(ii[b]) >> sh) * (np.int64(1) << k) + (np.int64(jj[b]) >> sh))


@njit(cache=True, nogil=True)
def _set_all(bits, cells):
    for c in cells:
        _set(bits, c)


@njit(cache=True, nogil=True)
def _count(bits):
    total = 0
    for x in bits:
        while x:
            x &= x - np.uint8(1)
            total += 1
    return total


@njit(cache=True, nogil=True)
def _claim(owner, T, tile, level, ii, jj):
    """Mark the level-T cells the boxes ``(level, i, j)`` meet as ``tile``'s in
    ``owner``: -1, or the other tile that holds one of them already, or -2 for a box
    outside the quadtree."""
    n = np.int64(1) << T
    for b in range(level.size):
        L = np.int64(level[b])
        if L >= T:
            sh = L - T
            a0, c0 = np.int64(ii[b]) >> sh, np.int64(jj[b]) >> sh
            a1, c1 = a0, c0
        else:
            f = np.int64(1) << (T - L)
            a0, c0 = np.int64(ii[b]) * f, np.int64(jj[b]) * f
            a1, c1 = a0 + f - 1, c0 + f - 1
        if a0 < 0 or c0 < 0 or a1 >= n or c1 >= n:
            return -2
        for a in range(a0, a1 + 1):
            for c in range(c0, c1 + 1):
                o = owner[a * n + c]
                if o >= 0 and o != tile:
                    return o
                owner[a * n + c] = tile
    return -1


def _bitmap(k):
    return np.zeros(max((1 << (2 * k)) // 8, 1), np.uint8)


class StreamedCounts:
    """Accumulates the sliding border's box counts tile by tile: :meth:`add` each tile's
    ``(level, i, j, status)``, then :meth:`rows` (one dict a scale, as
    :meth:`CertifiedAtlas.border_box_counts`' rows)."""

    def __init__(self, window, depth, deepest, tile_level, max_iter=None):
        self.window, self.depth, self.deepest = window, int(depth), int(deepest)
        self.T = min(max(int(tile_level), 0), self.depth)
        self.touched = [_bitmap(k) for k in range(self.depth + 1)]
        self.classes = [(_bitmap(k), _bitmap(k)) for k in range(self.T)]  # not sliding, sliding
        self.lower = np.zeros(self.depth + 1, np.int64)
        self.owner = np.full(1 << (2 * self.T), -1, np.int32)  # the tile of each level-T cell
        self.cells = 0  # deepest-level cells the boxes cover, a Python int
        self.max_iter = max_iter  # given: proven points inside the undecided boxes too (witnesses.py)
        self.witnesses = self.witnesses_tried = 0

    def add(self, tile, level, ii, jj, status):
        """Count one tile's boxes; with ``max_iter`` (the atlas's) given, also the proven
        points inside its undecided boxes that the lower counts need
        (:func:`witnesses.witness_rows`, exact from the tile level on)."""
        level = np.asarray(level).astype(np.int64)
        ii, jj = np.asarray(ii).astype(np.int64), np.asarray(jj).astype(np.int64)
        if level.size and (level.min() < 0 or level.max() > self.deepest):
            raise ValueError(f"tile {tile}: a box's level lies outside 0 .. {self.deepest}")
        self.cells += sum(int(c) << (2 * (self.deepest - lv))
                          for lv, c in zip(*np.unique(level, return_counts=True)))
        self._own(tile, level, ii, jj)
        # CertifiedAtlas.border_box_counts' classes: -2 undecided, 0 sliding, -1 not sliding
        sliding = _border_classes(np.asarray(status), None, "sliding") + 1  # -1 undecided, 1, 0
        und = sliding < 0
        # the proven points the lower counts need, as proven "boxes" of their level-depth
        # cell; they enter the lower counts only (every one lies in an undecided box)
        wl = wi = wj = wc = np.zeros(0, np.int64)
        if self.max_iter is not None and und.any():
            from .witnesses import witness_rows

            wi, wj, wc, _, _, tried = witness_rows(self.window, self.depth, self.max_iter, level, ii, jj, sliding,
                                             exact_from=self.T)
            wl = np.full(wi.size, self.depth, np.int64)
            self.witnesses += wi.size
            self.witnesses_tried += tried
        pl = np.concatenate([level[~und], wl])
        pi, pj = np.concatenate([ii[~und], wi]), np.concatenate([jj[~und], wj])
        pc = np.concatenate([sliding[~und], wc])
        for k in range(self.depth + 1):
            _touch(self.touched[k], k, level[und], ii[und], jj[und])
            fine = pl >= k
            if k < self.T:
                for c in (0, 1):
                    s = fine & (pc == c)
                    _mark(self.classes[k][c], k, pl[s], pi[s], pj[s])
                continue
            sh = pl[fine] - k
            code = ((pi[fine] >> sh) << k) + (pj[fine] >> sh)
            keys = np.unique(code * 2 + pc[fine])
            cell = keys >> 1
            two = cell[1:][cell[1:] == cell[:-1]]
            self.lower[k] += two.size
            _set_all(self.touched[k], two)

    def _own(self, tile, level, ii, jj):
        """Each level-T cell's boxes in one tile (see the module's docstring)."""
        bad = _claim(self.owner, self.T, tile, level, ii, jj)
        if bad == -2:
            raise ValueError(f"tile {tile}: a box lies outside the window's quadtree")
        if bad >= 0:
            raise ValueError(f"the store's tiles are not cut at its tile level {self.T} (tile {tile} shares a "
                             f"level-{self.T} cell with tile {bad}): load the atlas (CertifiedAtlas.load) and "
                             "count it in memory")

    def rows(self):
        if self.cells != 1 << (2 * self.deepest):
            raise ValueError("border_box_counts: the boxes do not cover the window (sb.verify says how much is "
                             "uncovered): an uncovered part may hold the border, so no upper count is proven")
        for k in range(self.T):
            a, b = self.classes[k]
            both = a & b
            self.lower[k] = _count(both)
            self.touched[k] |= both
        (e_lo, e_hi), (u_lo, u_hi) = self.window
        return [{"k": k, "size_e": (e_hi - e_lo) / (1 << k), "size_u": (u_hi - u_lo) / (1 << k),
                 "lower": int(self.lower[k]), "upper": int(_count(self.touched[k]))} for k in range(self.depth + 1)]


def store_rows(path, progress=None, witnesses=True):
    """``(rows, attrs, found)``: the sliding border's counts of the store at ``path``, its
    tiles read one at a time, each checked against its checksum (a damaged or incomplete
    store refused with ValueError naming the tile), the atlas's attributes (tile 0's)
    and ``found = (witnesses, tried)`` (the proven points the lower counts used, and
    the points certified; 0 without ``witnesses``).  ``progress(done, total)`` after
    each tile."""
    from . import _store_read as R
    from .tiling import deepest_level

    root, token, crc = R.complete_state(path)
    acc, attrs0 = None, None
    for t in range(crc.size):
        got = R.check_tile(path, t, token, crc[t])
        if got is None:
            raise ValueError(f"tile {t} of {path} does not match its checksum (a chunk deleted or damaged): "
                             "run certify_to_zarr with the same arguments to compute it again")
        arrays, attrs = got
        if acc is None:
            attrs0 = {k: v for k, v in attrs.items() if k not in R.TILE_ATTRS}
            depth = int(attrs0["depth"])
            window = (tuple(float(x) for x in attrs0["e_range"]), tuple(float(x) for x in attrs0["u_range"]))
            # the scales counted: 0 .. depth, or 0 .. focus for a store refined for them (focus.py)
            acc = StreamedCounts(window, counted_depth(attrs0), deepest_level(depth, attrs0), R.tile_level(root, depth),
                                 int(attrs0["max_iter"]) if witnesses else None)
        acc.add(t, arrays["level"], arrays["i"], arrays["j"], np.asarray(arrays["status"]))
        del arrays, got
        if progress is not None:
            progress(t + 1, crc.size)
    return acc.rows(), attrs0, (acc.witnesses, acc.witnesses_tried)
