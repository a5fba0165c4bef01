"""Never slides, where it can be proven: trapping regions (issue 36, item 7).

Below the Corollary 2.1 curve a box of parameters whose orbit of ``(1, 0)``
never slides cannot be proven by a finite itinerary: its enclosures widen until
an impact decision is undecided, and the certifier leaves it undecided with
the (numerical) reason ``"nonsliding"``.  A *trapping region* proves it.

The claim.  For every ``(e, u)`` of the box ``B = [e0, e1] x [u0, u1]``, the
orbit of the edge state ``(1, 0)`` under the Poincare map (Prop. 2.3) never
slides; since every periodic sliding solution passes through ``(1, 0)``, no
periodic sliding solution exists anywhere in B (status ``"no_sliding"``,
reason ``"trapping"``).  This is weaker than Corollary 2.1's ``no_sliding``
(no state with ``y >= 1`` slides there at all): here a solution started
elsewhere may slide once, and then never again.

The region.  States are carried as ``(v, s)``, ``s = sqrt(v^2 + 2y)`` (the
coordinates of the certifier's corners form).  A step with k impacts
(k = 0: the ball flies over) maps ``v' = v - T + B_k s``, ``s'^2 = 2 + (e^k
s)^2`` (``B_k = (1+e)(1 + e + ... + e^(k-1))``, Prop. 2.3, eq. (2.2)); the
decisions are the signs of the margins ``T - v - ratio s`` (slide, (2.4)) and
``T - t_j``, ``t_j = v + A_j s`` (impact j, ``A_j = 1 + 2(e + ... +
e^(j-1))``).  A region is a set of cells of a uniform grid of a rectangle of
the ``(v, s)`` plane.  It proves the claim when

(a) the orbit of ``(1, 0)`` enters it: a finite itinerary of decided steps
    (every decision proven over B, as in :func:`stairbounce.certify_box`)
    ends in a state enclosure lying in the union of the cells;
(b) it is invariant: for every cell C, every k that some state of C at some
    ``(e, u)`` of B can have (both sides of an undecided impact decision are
    followed), the enclosure of the image of C under the k-impact branch
    over B lies in the union of the cells;
(c) it misses the sliding set: on every cell the slide margin is proven < 0
    over the cell and B.

Then by induction every later state of the orbit lies in the region and does
not slide.

Enclosures (proven; the same monotonicity as the corners form).  On a cell
``[v0, v1] x [s0, s1]`` (``s >= sqrt 2 > 0``) with ``(e, u)`` in B, each margin
``T - v - C s`` (``C`` = ratio or ``A_j``, both >= 1 and non-decreasing in e;
``T = 1/u``) is non-increasing in v, s, e and u, and each branch's image
``v' = v - T + B_k s`` and ``s' = sqrt(2 + e^(2k) s^2)`` is non-decreasing in
each of them (``B_k >= 0`` and ``e^k`` non-decreasing in e).  So every quantity
takes its extremes at the two corners ``(v0, s0, e0, u0)`` and
``(v1, s1, e1, u1)``: the kernel evaluates the formulas there with each
operation rounded to nearest and moved one float outward (``_kernel._up``,
``_kernel._dn``), which encloses the exact value (docs/design.md, "Certified
boxes").  A branch's image is cut further by what the branch itself says:
after k >= 1 impacts ``v' = w_k - d`` with ``d = T - t_k`` in ``[0, 2 w_k)``
and in the margin's enclosure; after a fly-over ``v' = -(T - t_1) - s`` with
``T - t_1 < 0``.

The independent checker (``structure/verify_trapping.py``, numpy only)
re-verifies (a), (b) and (c) from the box, the entry itinerary and the region.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .. import model as _model
from .._interrupt import check_halt
from ._kernel import _dn, _up
from .certificate import Certificate, TrappingRegion, _check_e, _check_u

__all__ = ["TrappingRegion", "trapping_region"]

# why a try failed (codes of the kernel; TRAP_FAILURES[code])
TRAP_OK, TRAP_SLIDE, TRAP_ESCAPE, TRAP_CELLS, TRAP_IMPACTS, TRAP_ENTRY, TRAP_NAN = range(7)
TRAP_FAILURES = ("ok", "slide", "escape", "cells", "impacts", "entry", "nan")
"""Why no region was found: ``slide`` (a cell reached may slide), ``escape``
(an image left the grid's rectangle), ``cells`` (more cells than allowed),
``impacts`` (a step with more than the impact cap), ``entry`` (the orbit of
(1, 0) may slide before the region is entered) and ``nan`` (an overflow)."""

_CAP = 4096  # impacts followed on one step (as the certifier's IMPACT_CAP)


@njit(cache=True)
def _branches(v0, v1, s0, s1, E0, E1, Tl, Th, Rl, out):
    """The image enclosures of the cell ``[v0, v1] x [s0, s1]`` over the box,
    one row ``(a0, a1, b0, b1, k)`` of ``out`` per possible impact number k
    (``v'`` in ``[a0, a1]``, ``s'`` in ``[b0, b1]``).

    ``Tl, Th`` bound ``T = 1/u`` below (at u1) and above (at u0), ``Rl`` the
    ratio below (at e0).  Returns the number of rows, or ``-TRAP_SLIDE`` when
    the slide margin is not proven < 0, ``-TRAP_IMPACTS`` past the cap.
    """
    # the slide test (2.4): its largest value is at the lower corner
    hi = _up(_up(Th - v0) - max(_dn(Rl * s0), 0.0))
    if not hi < 0.0:
        return -TRAP_SLIDE
    n = 0
    # impact 1: t_1 = v + s
    tl = _dn(v0 + s0)
    th = _up(v1 + s1)
    lo_k = _dn(Tl - th)
    hi_k = _up(Th - tl)
    if not lo_k >= 0.0:  # some state flies over: v' = v - T = -(T - t_1) - s, T - t_1 < 0
        a0 = max(_dn(v0 - Th), _dn(_dn(-min(hi_k, 0.0)) - s1))
        a1 = min(_up(v1 - Tl), _up(-lo_k - s0))
        out[n, 0] = a0
        out[n, 1] = a1
        out[n, 2] = _dn(math.sqrt(_dn(2.0 + _dn(s0 * s0))))
        out[n, 3] = _up(math.sqrt(_up(2.0 + _up(s1 * s1))))
        out[n, 4] = 0.0
        n += 1
    wl = max(_dn(E0 * s0), 0.0)  # w_k = e^k s, the speed after impact k
    wh = _up(E1 * s1)
    k = 1
    while hi_k >= 0.0:  # some state has impact k
        tnl = _dn(tl + 2.0 * wl)
        tnh = _up(th + 2.0 * wh)
        lo_n = _dn(Tl - tnh)
        hi_n = _up(Th - tnl)
        if not lo_n >= 0.0:  # some state has no impact k + 1: exactly k impacts
            # v' = w_k - d, d = T - t_k in [max(lo_k, 0), hi_k], d < 2 w_k
            a0 = max(max(_dn(_dn(wl + tl) - Th), _dn(wl - hi_k)), -wh)
            a1 = min(_up(_up(wh + th) - Tl), _up(wh - max(lo_k, 0.0)))
            if n >= out.shape[0]:
                return -TRAP_IMPACTS
            out[n, 0] = a0
            out[n, 1] = a1
            out[n, 2] = _dn(math.sqrt(_dn(2.0 + _dn(wl * wl))))
            out[n, 3] = _up(math.sqrt(_up(2.0 + _up(wh * wh))))
            out[n, 4] = float(k)
            n += 1
        if k >= _CAP:
            return -TRAP_IMPACTS
        tl = tnl
        th = tnh
        lo_k = lo_n
        hi_k = hi_n
        wl = max(_dn(E0 * wl), 0.0)
        wh = _up(E1 * wh)
        k += 1
    return n


@njit(cache=True)
def _edge(lo, w, hi, i, n, inv):
    """The cell edge of ``certificate._cell_edge`` (``TrappingRegion.boxes``, the
    checker's), compiled, with ``inv = 1.0 / n`` computed once by the caller: the
    same float, bit for bit (``float(i) * inv`` is the product it forms)."""
    if i >= n:
        return hi
    return lo + w * (float(i) * inv)


@njit(cache=True)
def _guess(x, scale, n):
    """A cell index to start the search from: ``x * scale`` clamped to ``0 .. n - 1``
    before it becomes an int (so a NaN or an overflow cannot reach the conversion).
    Only a start: :func:`_axis_range` corrects it to the exact cell."""
    g = x * scale
    if not g >= 0.0:
        g = 0.0
    if g > n - 1.0:
        g = n - 1.0
    return int(g)


@njit(cache=True)
def _axis_range(a, b, lo, hi, n, inv, scale):
    """:func:`_cell_range` with the axis's ``inv = 1.0 / n`` and ``scale = n / (hi -
    lo)`` computed once by the caller (:func:`_close` calls it twice a branch)."""
    if not (a >= lo and b <= hi and a <= b):
        return -1, -1
    w = hi - lo
    i0 = _guess(a - lo, scale, n)
    while i0 > 0 and _edge(lo, w, hi, i0, n, inv) > a:
        i0 -= 1
    while i0 < n - 1 and _edge(lo, w, hi, i0 + 1, n, inv) <= a:
        i0 += 1
    i1 = max(_guess(b - lo, scale, n), i0)
    while i1 < n - 1 and _edge(lo, w, hi, i1 + 1, n, inv) < b:
        i1 += 1
    while i1 > i0 and _edge(lo, w, hi, i1, n, inv) >= b:
        i1 -= 1
    return i0, i1


@njit(cache=True)
def _cell_range(a, b, lo, hi, n):
    """Cells ``i0..i1`` of the axis whose union covers ``[a, b]`` (-1 when outside):
    ``i0`` the cell holding ``a`` (its lower edge ``<= a`` below the next one), ``i1``
    the last cell whose lower edge is ``< b``.  Whatever cell the search starts from,
    it ends at these, so the start is only a guess."""
    return _axis_range(a, b, lo, hi, n, 1.0 / n, n / (hi - lo))


@njit(cache=True)
def _entry(E0, E1, U0, U1, max_steps, itin, out):
    """Follow the orbit of ``(0, sqrt 2)`` while every step is decided over the box.

    Returns ``(code, n, v0, v1, s0, s1)``: the enclosure of the state before
    the first step with more than one possible impact number (or after
    ``max_steps``), the ``n`` decided steps written to ``itin``; ``out``
    (``(_CAP + 2, 5)``) is :func:`_branches`'s.
    """
    Tl = _dn(1.0 / U1)
    Th = _up(1.0 / U0)
    Rl = _dn(_dn(1.0 + E0) / _up(1.0 - E0))
    v0 = 0.0
    v1 = 0.0
    s0 = _dn(math.sqrt(2.0))
    s1 = _up(math.sqrt(2.0))
    for n in range(max_steps):
        m = _branches(v0, v1, s0, s1, E0, E1, Tl, Th, Rl, out)
        if m < 0:
            return -m, n, v0, v1, s0, s1
        if m != 1:
            return TRAP_OK, n, v0, v1, s0, s1
        itin[n] = int(out[0, 4])
        v0, v1, s0, s1 = out[0, 0], out[0, 1], out[0, 2], out[0, 3]
    return TRAP_OK, max_steps, v0, v1, s0, s1


@njit(cache=True)
def _seen_table(max_cells):
    """An empty set of cells for :func:`_close` (``-1``: a free slot): open addressing,
    twice as many slots as cells allowed, a power of 2 (the grid's size does not
    matter: a region of a 8192 x 8192 grid costs what one of 64 x 64 does)."""
    size = 1
    while size < 2 * max_cells:
        size *= 2
    return np.full(size, -1, np.int64)


@njit(cache=True, inline="always")
def _slot(c, seen):
    """The slot of cell ``c`` in the table ``seen``: its own, or the free one where
    it would go (multiplicative hash, linear probing)."""
    mask = seen.size - 1
    x = np.uint64(c) * np.uint64(0x9E3779B97F4A7C15)  # Fibonacci hashing (unsigned: it wraps)
    x ^= x >> np.uint64(29)
    h = np.int64(x & np.uint64(mask))
    while seen[h] != -1 and seen[h] != c:
        h = (h + 1) & mask
    return h


@njit(cache=True)
def _enqueue(c, seen, queue, slots, tail):
    """Put cell ``c`` at ``queue[tail]`` unless it was queued before (``seen``, its
    slot recorded in ``slots[tail]``): the new tail, or -1 when the queue
    (``max_cells`` long) is full."""
    h = _slot(c, seen)
    if seen[h] == c:
        return tail
    if tail >= queue.size:
        return -1
    seen[h] = c
    queue[tail] = c
    slots[tail] = h
    return tail + 1


@njit(cache=True)
def _forget(seen, slots, m):
    """Empty the table again after a region of ``m`` cells (its slots only)."""
    for k in range(m):
        seen[slots[k]] = -1


@njit(cache=True)
def _close(E0, E1, U0, U1, V0, V1, nv, S0, S1, ns, i0, i1, j0, j1, seen, queue, slots, out):
    """Grow the region from the cell rectangle ``i0 .. i1`` x ``j0 .. j1``: the
    cells reachable by the branches' image enclosures (breadth first).

    ``seen`` (:func:`_seen_table`, empty) holds the region's cells (index ``j * nv +
    i``), ``queue`` (its length the most cells allowed) lists them, in the order
    found, the first ``cells`` of it, and ``slots`` their slots in ``seen`` (empty
    it with :func:`_forget`); ``out`` (``(_CAP + 2, 5)``) is
    :func:`_branches`'s.  Returns ``(code, cells, miss)``; ``code`` is ``TRAP_OK`` when the
    region is closed: every cell's images lie in it and no cell may slide.  Where a
    cell may slide, ``miss`` is the float estimate of its slide margin's largest
    value over the cell's extent along the margin (``<= 1``: it fails by less
    than a cell, so finer cells may close the region; numerical, a choice only),
    else ``inf``.  (Scalars in and out: no array is allocated a try.)
    """
    Tl = _dn(1.0 / U1)
    Th = _up(1.0 / U0)
    Rl = _dn(_dn(1.0 + E0) / _up(1.0 - E0))
    wv = V1 - V0
    ws = S1 - S0
    iv, sv = 1.0 / nv, nv / wv  # each axis's 1/n and n/width, once a region
    is_, ss = 1.0 / ns, ns / ws
    shift = 0  # a queued cell's (i, j) by a mask and a shift when nv is a power of 2
    while (1 << shift) < nv:
        shift += 1
    pow2 = (1 << shift) == nv
    head = 0
    tail = 0
    for j in range(j0, j1 + 1):
        for i in range(i0, i1 + 1):
            t = _enqueue(j * nv + i, seen, queue, slots, tail)
            if t < 0:
                return TRAP_CELLS, tail, np.inf
            tail = t
    while head < tail:
        c = queue[head]
        head += 1
        if pow2:  # (a 64-bit division costs more than the rest of the cell's bookkeeping)
            i = c & (nv - 1)
            j = c >> shift
        else:
            i = c % nv
            j = c // nv
        v0 = _edge(V0, wv, V1, i, nv, iv)
        v1 = _edge(V0, wv, V1, i + 1, nv, iv)
        s0 = _edge(S0, ws, S1, j, ns, is_)
        s1 = _edge(S0, ws, S1, j + 1, ns, is_)
        m = _branches(v0, v1, s0, s1, E0, E1, Tl, Th, Rl, out)
        if m < 0:
            if m == -TRAP_SLIDE:  # by how much, in the cell's own extent along the margin
                return TRAP_SLIDE, tail, (Th - v0 - Rl * s0) / ((v1 - v0) + Rl * (s1 - s0))
            return -m, tail, np.inf
        for r in range(m):
            a0, a1 = _axis_range(out[r, 0], out[r, 1], V0, V1, nv, iv, sv)
            b0, b1 = _axis_range(out[r, 2], out[r, 3], S0, S1, ns, is_, ss)
            if a0 < 0 or b0 < 0:
                if np.isnan(out[r, 0]) or np.isnan(out[r, 1]) or np.isnan(out[r, 2]) or np.isnan(out[r, 3]):
                    return TRAP_NAN, tail, np.inf
                return TRAP_ESCAPE, tail, np.inf
            for jj in range(b0, b1 + 1):
                for ii in range(a0, a1 + 1):
                    t = _enqueue(jj * nv + ii, seen, queue, slots, tail)
                    if t < 0:
                        return TRAP_CELLS, tail, np.inf
                    tail = t
    return TRAP_OK, tail, np.inf


@njit(cache=True)
def _orbit_hull(e, u, y, v, skip, steps, Th, Rl, stop=np.inf):
    """Numerical: the rectangle of ``(v, s)`` visited by the float map from ``(y,
    v)`` after step ``skip`` up to step ``skip + steps`` (``slid``: it slid on
    the way), and the largest ``Th - v - Rl s`` over those states (the slide
    margin of a cell holding the state, at the box's worst corner):
    ``(v_lo, v_hi, s_lo, s_hi, slid, worst)``, scalars (no array a try).

    It returns as soon as ``worst`` exceeds ``stop`` (a running maximum only
    grows, so a caller that rejects ``worst > stop`` decides the same; the hull is
    then partial).  Each state's ``s`` is the root :func:`model._step_from` takes
    for the next step: one root a step."""
    T, ratio = _model._constants(e, u)
    h0, h1, h2, h3 = np.inf, -np.inf, np.inf, -np.inf
    worst = -np.inf
    s = math.sqrt(v * v + 2.0 * y)
    for n in range(skip + steps):
        y, v, k = _model._step_from(y, v, s, e, T, ratio)
        if k == _model.SLIDING:
            return h0, h1, h2, h3, True, worst
        s = math.sqrt(v * v + 2.0 * y)
        if n >= skip:
            h0 = min(h0, v)
            h1 = max(h1, v)
            h2 = min(h2, s)
            h3 = max(h3, s)
            worst = max(worst, Th - v - Rl * s)
            if worst > stop:
                return h0, h1, h2, h3, False, worst
    return h0, h1, h2, h3, False, worst


@njit(cache=True)
def _hull(e, u, n0, steps):
    """Numerical: the rectangle of ``(v, s)`` visited by the float map from (1, 0)
    between steps ``n0`` and ``n0 + steps`` (``slid``: it slid on the way).  Only
    chooses where the grid lies; nothing proven rests on it."""
    skip = max(n0 - 1, 0)
    h0, h1, h2, h3, slid, _ = _orbit_hull(e, u, 1.0, 0.0, skip, n0 + steps - skip, 0.0, 0.0)
    return np.array([h0, h1, h2, h3]), slid


@njit(cache=True)
def _hull_from(e, u, v, s, steps, Th, Rl, stop):
    """Numerical: as :func:`_hull`, from the state ``(v, s)`` (``y = (s^2 - v^2)/2``,
    the middle of the entry's enclosure) for ``steps`` steps, so that the orbit's
    first ``n`` steps are not iterated again, with :func:`_orbit_hull`'s largest
    slide margin (returned once past ``stop``).  Only chooses where the grid lies and
    which tries are skipped."""
    return _orbit_hull(e, u, max(0.5 * (s * s - v * v), 0.0), v, 0, steps, Th, Rl, stop)


# grid tries: (cells a side, padding of the float orbits' rectangle, in its extent)
_TRIES = ((64, 0.3), (128, 0.3), (64, 1.0))
_MAX_CELLS = 1 << 15
_HULL_STEPS = 2000


def _try(e0, e1, u0, u1, max_iter, tries=_TRIES, max_cells=_MAX_CELLS):
    """``(region or None, failure)``: the first try of ``tries`` that closes."""
    itin = np.empty(max(max_iter, 1), np.int64)
    out = np.empty((_CAP + 2, 5))
    code, n, v0, v1, s0, s1 = _entry(e0, e1, u0, u1, max_iter, itin, out)
    if code != TRAP_OK:
        return None, "entry" if code == TRAP_SLIDE else TRAP_FAILURES[code]
    hull = np.array([v0, v1, s0, s1])
    for e in (e0, e1, 0.5 * (e0 + e1)):
        for u in (u0, u1, 0.5 * (u0 + u1)):
            h, slid = _hull(e, u, n, _HULL_STEPS)
            if slid:
                return None, "slide"
            hull = np.array([min(hull[0], h[0]), max(hull[1], h[1]), min(hull[2], h[2]), max(hull[3], h[3])])
    dT = _up(1.0 / u0) - _dn(1.0 / u1)
    failure = "slide"
    seen, queue, slots = _seen_table(max_cells), np.empty(max_cells, np.int64), np.empty(max_cells, np.int64)
    for cells, pad in tries:
        dv, ds = hull[1] - hull[0], hull[3] - hull[2]
        grid = (hull[0] - pad * dv - 2 * dT, hull[1] + pad * dv + 2 * dT, cells,
                max(hull[2] - pad * ds - dT, 1.0), hull[3] + pad * ds + dT, cells)
        # the seed covers the entry enclosure with a little room (any superset will do)
        i0, i1 = _cell_range(v0 - 1e-9 * (1 + abs(v0)), v1 + 1e-9 * (1 + abs(v1)), grid[0], grid[1], cells)
        j0, j1 = _cell_range(s0 - 1e-9 * s0, s1 + 1e-9 * s1, grid[3], grid[4], cells)
        if i0 < 0 or j0 < 0:
            failure = "escape"
            continue
        code, m, _ = _close(e0, e1, u0, u1, grid[0], grid[1], cells, grid[3], grid[4], cells, i0, i1, j0, j1,
                            seen, queue, slots, out)
        _forget(seen, slots, m)  # empty again for the next try
        if code == TRAP_OK:
            return TrappingRegion(e=(e0, e1), u=(u0, u1), itinerary=tuple(int(k) for k in itin[:n]),
                                  grid=grid, cells=np.sort(queue[:m]),
                                  entry=(float(v0), float(v1), float(s0), float(s1))), "ok"
        failure = TRAP_FAILURES[code]
    return None, failure


# the atlas's pass (trap_atlas): one float orbit (at the box's centre) places the
# grid, the same three grid tries; a box that fails is split into its quadtree
# children, down to SPLIT_LEVELS levels below the atlas's depth
_FAST_HULL_STEPS = 100
_SPREAD_CELLS = 8.0
# (cells a side, padding, when it is tried): 0 always (until a try closes), 1 only where
# the try before failed by less than a cell, 2 not where it failed by more than a cell, 3
# only where an image left the rectangle of an earlier try, 4 only where the spread of T
# over the box is at most _SPREAD_CELLS of the grid's cells along v and the box has not
# tried that grid already (numerical choices: which tries are made; the region is proven
# whatever they are).
_FAST_TRIES = tuple(t + (g,) for t, g in zip(_TRIES, (0, 2, 3))) + ((256, 0.3, 1), (512, 0.3, 1))
# trap="fine": the default pass's tries as it makes them, then where the spread of T over
# the box is narrow the grids its gates skipped (a coarse grid that fails by many cells is
# no sign that a finer one fails: the motion there is nearly neutral along v, so a coarse
# region's overestimate grows a cell a round) and four finer grids (the set of cells is a
# hash table: a grid's size costs nothing, its region's cells do); the tries and what they
# prove: benchmarks/README.md ("Finer trapping grids ...")
_FINE_TRIES = _FAST_TRIES + tuple((c, p, 4) for c, p, g in _FAST_TRIES if g in (1, 2)) + (
    (1024, 0.3, 4), (2048, 0.3, 4), (4096, 0.3, 4), (8192, 0.3, 4))


def _tries_arrays(tries):
    """``(cells a side, paddings, gates)`` of ``tries`` as the kernel takes them."""
    cells, pads, gates = zip(*tries)
    return np.array(cells, np.int64), np.array(pads, np.float64), np.array(gates, np.int64)


_PASS_GRIDS = {False: _tries_arrays(_FAST_TRIES), True: _tries_arrays(_FINE_TRIES)}
TRAP_MODES = (False, True, "fine")
"""The values of ``trap`` (:func:`stairbounce.certify`, ``certify_to_zarr``): no
trapping pass, the pass, the pass followed, where the spread of T over a box is
narrow, by the grids its gates skipped and four finer grids (1024 to 8192 cells
a side)."""


def check_trap(trap):
    """``trap`` as one of :data:`TRAP_MODES` (numpy booleans taken as booleans), or a
    ValueError naming the allowed values."""
    if isinstance(trap, (bool, np.bool_)):
        return bool(trap)
    if isinstance(trap, str) and trap == "fine":
        return "fine"
    raise ValueError(f"trap must be True, False or 'fine', got {trap!r}")


def _try_grids(fine):
    """The grid tries' ``(cells a side, paddings, gates)`` of the pass."""
    return _PASS_GRIDS[bool(fine)]


SPLIT_LEVELS = 1
"""Levels below the atlas's depth that :func:`trap_atlas` splits a box whose
trapping region failed into (its quadtree children, tried in turn); an atlas
states its own in the attribute ``trap_split``, and ``sb.verify`` accepts boxes
down to ``depth + trap_split``."""


@njit(cache=True)
def _try_fast(e0, e1, u0, u1, max_iter, hull_steps, t_cells, t_pad, t_gate, seen, queue, slots, out, itin,
              grid, cells_out):
    """:func:`_try` compiled, the grid placed by one float orbit at the box's
    centre (``hull_steps`` steps after the entry): ``(code, n, m)``, the failure
    code (``TRAP_OK`` when a region closed), the entry's length ``n`` (in
    ``itin``) and the region's ``m`` cells (sorted, in ``cells_out``), its grid
    in ``grid``; ``seen``, ``queue`` (the most cells allowed) and ``slots`` are
    :func:`_close`'s, ``seen`` left empty.  The
    grid's place is a numerical choice only: the region is proven by
    :func:`_close` whatever it is."""
    code, n, v0, v1, s0, s1 = _entry(e0, e1, u0, u1, max_iter, itin, out)
    if code != TRAP_OK:
        return (TRAP_ENTRY if code == TRAP_SLIDE else code), 0, 0
    Th = 1.0 / u0
    Rl = (1.0 + e0) / (1.0 - e0)
    clear = 1e-9 * (1.0 + abs(Th))
    q0, q1, q2, q3, slid, worst = _hull_from(0.5 * (e0 + e1), 0.5 * (u0 + u1), 0.5 * (v0 + v1),
                                             0.5 * (s0 + s1), hull_steps, Th, Rl, clear)
    if slid or worst > clear:
        # the float orbit slides, or passes a state whose cell cannot be proven clear of
        # the sliding set over the box (its margin at the box's worst corner is positive
        # by more than rounding): no region can close (numerical; it skips the tries only)
        return TRAP_SLIDE, 0, 0
    h0, h1, h2, h3 = min(v0, q0), max(v1, q1), min(s0, q2), max(s1, q3)
    dT = _up(1.0 / u0) - _dn(1.0 / u1)
    failure = TRAP_SLIDE
    escaped = False
    miss = np.inf
    made = np.zeros(t_cells.size, np.bool_)
    for t in range(t_cells.size):
        cells, pad = t_cells[t], t_pad[t]
        g = t_gate[t]
        dv, ds = h1 - h0, h3 - h2
        g0, g1 = h0 - pad * dv - 2 * dT, h1 + pad * dv + 2 * dT
        # the spread of T over the box within _SPREAD_CELLS of the grid's cells along v (a
        # region's images are at least that wide: a grid much finer only makes more cells)
        narrow = dT <= _SPREAD_CELLS * (g1 - g0) / cells
        if g == 1:  # finer cells only where the region failed by less than a cell
            tried = failure == TRAP_SLIDE and miss <= 1.0
        elif g == 2:  # not where it missed the sliding set by more than a cell
            tried = not (failure == TRAP_SLIDE and miss > 1.0)
        elif g == 3:  # a wider rectangle only where an image left the one before
            tried = escaped
        elif g == 4:  # where the spread of T is narrow, on a grid not tried before
            tried = narrow
            for t2 in range(t):
                if made[t2] and t_cells[t2] == cells and t_pad[t2] == pad:
                    tried = False
        else:
            tried = True
        if not tried:
            continue
        made[t] = True
        g3, g4 = max(h2 - pad * ds - dT, 1.0), h3 + pad * ds + dT
        i0, i1 = _cell_range(v0 - 1e-9 * (1 + abs(v0)), v1 + 1e-9 * (1 + abs(v1)), g0, g1, cells)
        j0, j1 = _cell_range(s0 - 1e-9 * s0, s1 + 1e-9 * s1, g3, g4, cells)
        if i0 < 0 or j0 < 0:
            failure = TRAP_ESCAPE
            escaped = True
            continue
        code, m, miss = _close(e0, e1, u0, u1, g0, g1, cells, g3, g4, cells, i0, i1, j0, j1, seen, queue, slots,
                               out)
        _forget(seen, slots, m)  # empty again for the next try
        if code == TRAP_OK:
            grid[0], grid[1], grid[2], grid[3], grid[4], grid[5] = g0, g1, cells, g3, g4, cells
            cells_out[:m] = np.sort(queue[:m])
            return TRAP_OK, n, m
        failure = code
        escaped = escaped or code == TRAP_ESCAPE or code == TRAP_CELLS
    return failure, 0, 0


@njit(cache=True, nogil=True)
def _try_batch(E0, E1, U0, U1, start, max_iter, hull_steps, t_cells, t_pad, t_gate, max_cells,
               codes, grids, itin_len, itin_buf, cell_len, cell_buf):
    """:func:`_try_fast` on the boxes ``start, start + 1, ..`` while the buffers
    have room for one more: the entries one after another in ``itin_buf``, the
    cells in ``cell_buf`` (their lengths ``itin_len``, ``cell_len``, zero for a
    failure).  Returns ``(next box, itinerary steps, cells)`` written."""
    itin = np.empty(max(max_iter, 1), np.int64)
    found = np.empty(max_cells, np.int64)
    seen = _seen_table(max_cells)
    queue = np.empty(max_cells, np.int64)
    slots = np.empty(max_cells, np.int64)
    out = np.empty((_CAP + 2, 5))
    ip = 0
    cp = 0
    b = start
    while b < E0.size and ip + max_iter <= itin_buf.size and cp + max_cells <= cell_buf.size:
        code, n, m = _try_fast(E0[b], E1[b], U0[b], U1[b], max_iter, hull_steps, t_cells, t_pad, t_gate, seen,
                               queue, slots, out, itin, grids[b], found)
        codes[b] = code
        if code == TRAP_OK:
            itin_buf[ip:ip + n] = itin[:n]
            cell_buf[cp:cp + m] = found[:m]
            ip += n
            cp += m
            itin_len[b] = n
            cell_len[b] = m
        else:
            itin_len[b] = 0
            cell_len[b] = 0
        b += 1
    return b, ip, cp


def trapping_region(e, u, max_iter=1000):
    """trapping_region(e=(e0, e1), u=(u0, u1), max_iter=1000) -> TrappingRegion or None

    A proven trapping region of the box ``[e0, e1] x [u0, u1]``, or ``None``
    when none was found: the orbit of the edge state ``(1, 0)`` enters it after
    a finite itinerary decided over the box, every image of it over the box
    lies in it, and none of its states slides (test (2.4) proven false), so
    for every ``(e, u)`` of the box the orbit of (1, 0) never slides and no
    periodic sliding solution exists (the module's docstring gives the
    argument; ``sb.verify`` re-checks it independently).

    The grid is placed over the float orbits' states at the box's corners and
    centre after the entry (numerical, a choice only), padded, and tried at
    64 and 128 cells a side; at most ``max_iter`` entry steps.

    Parameters
    ----------
    e : pair (e0, e1), 0 < e0 <= e1 < 1, each >= 2^-53
    u : pair (u0, u1), 1e-150 <= u0 <= u1 <= 1e150
    max_iter : int >= 1, default 1000
    """
    from ..model import check_count
    e0, e1 = _check_e(e)
    u0, u1 = _check_u(u)
    max_iter = check_count("max_iter", max_iter, 1)
    from .. import _validate

    # refuses by name a max_iter whose entry record (8 bytes a step) cannot fit
    _validate.check_memory(f"max_iter = {max_iter}", 8 * max_iter)
    return _try(e0, e1, u0, u1, max_iter)[0]


# boxes a compiled call tries between two checks of Ctrl-C and progress (and a thread's task;
# about 12 ms of tries at 12 us a try: Ctrl-C stays immediate, and a task's overhead is small)
_BATCH = 1024


def _try_all(e0, e1, u0, u1, max_iter, progress=None, done=0, total=0, threads=None, fine=False):
    """:func:`_try_fast` on every box, in compiled batches of ``_BATCH`` boxes (Ctrl-C and
    ``progress`` between them): ``(codes, grids, itinerary lengths, itineraries, cell
    counts, cells)``, the entries and the cells concatenated box after box.

    ``threads`` (default: numba's thread count, so ``numba_threads`` of
    ``certify_to_zarr`` holds here too) runs the batches in that many threads (the
    kernel releases the GIL). Each box's try depends on that box alone and each
    batch writes only its own rows, and the parts are joined in box order, so the
    result is the same, bit for bit, for any number of threads (a test compares 1
    and 2)."""
    import threading
    from concurrent.futures import ThreadPoolExecutor

    import numba

    n = e0.size
    threads = numba.get_num_threads() if threads is None else int(threads)
    t_cells, t_pad, t_gate = _try_grids(fine)
    codes = np.zeros(n, np.int64)
    grids = np.zeros((n, 6))
    itin_len = np.zeros(n, np.int64)
    cell_len = np.zeros(n, np.int64)
    local = threading.local()

    def run(lo, hi):
        """The boxes lo .. hi - 1: (entries, cells) in box order, through this
        thread's buffers (a call stops early when they are full; the next goes on)."""
        if not hasattr(local, "itin"):
            local.itin = np.empty(max(max_iter, 1 << 18), np.int64)
            local.cell = np.empty(max(_MAX_CELLS, 1 << 20), np.int64)
        itins, cells = [], []
        pos = lo
        while pos < hi:
            got, ip, cp = _try_batch(e0[pos:hi], e1[pos:hi], u0[pos:hi], u1[pos:hi], 0, max_iter, _FAST_HULL_STEPS,
                                     t_cells, t_pad, t_gate, _MAX_CELLS, codes[pos:hi], grids[pos:hi],
                                     itin_len[pos:hi], local.itin, cell_len[pos:hi], local.cell)
            itins.append(local.itin[:ip].copy())
            cells.append(local.cell[:cp].copy())
            pos += got
        return itins, cells

    bounds = [(lo, min(n, lo + _BATCH)) for lo in range(0, n, _BATCH)]
    itins, cells = [], []

    def take(parts, hi):
        itins.extend(parts[0])
        cells.extend(parts[1])
        check_halt()   # a Ctrl-C of certify's caller (run_interruptible) stops the pass here
        if progress is not None:
            progress(done + hi, total)

    if threads <= 1 or len(bounds) <= 1:
        for lo, hi in bounds:
            take(run(lo, hi), hi)
    else:
        with ThreadPoolExecutor(threads) as pool:
            ahead = []   # at most 2 x threads batches in flight, taken in box order
            try:
                for lo, hi in bounds:
                    ahead.append((pool.submit(run, lo, hi), hi))
                    if len(ahead) >= 2 * threads:
                        f, h = ahead.pop(0)
                        take(f.result(), h)
                while ahead:
                    f, h = ahead.pop(0)
                    take(f.result(), h)
            finally:
                for f, _ in ahead:
                    f.cancel()
    cat = (lambda parts: np.concatenate(parts) if parts else np.zeros(0, np.int64))
    return codes, grids, itin_len, cat(itins), cell_len, cat(cells)


def trap_atlas(ds, progress=None, split=None, fine=False, tried=None):
    """The atlas table ``ds`` (``certify``'s Dataset) with its undecided
    ``"nonsliding"`` boxes tried for a trapping region (:func:`_try_fast`): a box
    whose region closes becomes ``no_sliding`` with reason ``"trapping"``; a box
    whose region fails is split into its four quadtree children, each tried in
    turn, down to ``split`` levels below the atlas's depth (default
    :data:`SPLIT_LEVELS`; a box coarser than the depth is split down to it and
    beyond).  A box some of whose descendants were proven is replaced by the
    leaves of its split: the proven ones ``no_sliding``, the others keeping the
    split box's status, reason and step (so ``"nonsliding"`` there was checked
    at the corners and centre of the box split, not of the leaf); a box none of
    whose descendants was proven stays one row.  The rows are in the atlas's
    order (level, then j, then i), each a quadtree box of the window at its
    level; ``attrs["trap_split"]`` states ``split`` (``sb.verify`` accepts boxes
    down to ``depth + trap_split``).  With ``fine`` the default pass's tries are
    followed, where the spread of T over the box is at most ``_SPREAD_CELLS``
    cells of the grid along v, by the grids their gates skipped and grids of
    1024, 2048, 4096 and 8192 cells a side (:data:`TRAP_MODES`);
    ``attrs["trap_grids"]`` lists the cells a side of the grids in the order
    they may be tried.

    The regions: entry itinerary in ``itinerary``/``offsets``, the region in
    ``trap_box`` (the box's row), ``trap_grid`` (``v_lo, v_hi, nv, s_lo, s_hi,
    ns``), ``trap_cell_offsets`` and ``trap_cells``; ``attrs["trap_seconds"]``,
    ``attrs["trap_tried"]`` (boxes tried, the split's included) and
    ``attrs["trap_failures"]`` (why the tries failed, :data:`TRAP_FAILURES`).

    ``tried`` (one int a row, or None): the deepest level down to which an earlier
    pass already tried the row's tree and failed everywhere (the rows of an earlier
    pass's table that it left unproven: a row kept whole, or an unproven leaf of a
    split).  The tries of those levels are not made again (the same box, the same
    try, the same failure: each try depends on its box alone); their children are,
    down to the new depth (``focus.refine``, which deepens such rows a level at a
    time).  ``trap_tried`` counts the tries made."""
    import time

    import xarray as xr

    from ._kernel import NO_SLIDING, UNDECIDED, _U_MIN, _box_edges
    from ._store_read import _take_rows, row_key
    from .tiling import MAX_TRAP_SPLIT

    t0 = time.perf_counter()
    split = SPLIT_LEVELS if split is None else split
    if not (isinstance(split, (int, np.integer)) and 0 <= split <= MAX_TRAP_SPLIT):
        raise ValueError(f"split must be an int in [0, {MAX_TRAP_SPLIT}], got {split!r}")
    depth = int(ds.attrs["depth"])
    lmax = min(depth + int(split), 26)
    win = np.array([*ds.attrs["e_range"], *ds.attrs["u_range"]], np.float64)
    max_iter = int(ds.attrs["max_iter"])
    st0 = ds["status"].values
    reason0 = ds["reason"].values
    e0c, e1c, u0c, u1c = (ds[k].values for k in ("e0", "e1", "u0", "u1"))
    sel = np.flatnonzero((st0 == UNDECIDED) & (reason0 == "nonsliding"))
    sel = sel[(e0c[sel] > 0.0) & (e1c[sel] < 1.0) & (u0c[sel] >= _U_MIN)]
    # the deepest level each row's tree was tried down to before (-1: none)
    before = np.full(st0.size, -1, np.int64) if tried is None else np.asarray(tried, np.int64)
    if before.shape != st0.shape:
        raise ValueError(f"tried must hold one level a row ({st0.size}), got shape {before.shape}")
    # the tree of tries, level by level: node -> (level, i, j, parent node, root row)
    lv = [ds["level"].values[sel].astype(np.int64)]
    ii = [ds["i"].values[sel].astype(np.int64)]
    jj = [ds["j"].values[sel].astype(np.int64)]
    parent = [np.full(sel.size, -1, np.int64)]
    root = [sel.astype(np.int64)]
    res = []
    base = 0
    done = 0
    while lv[-1].size:
        L, I, J = lv[-1], ii[-1], jj[-1]
        e0, e1, u0, u1 = (np.empty(L.size) for _ in range(4))
        _box_edges(win, L, I, J, e0, e1, u0, u1)
        # the tries of the levels tried before are not made again (code -1: failed before)
        new = np.flatnonzero(L > before[root[-1]])
        got = _try_all(e0[new], e1[new], u0[new], u1[new], max_iter, progress, done, done + new.size, fine=fine)
        done += new.size
        codes_l = np.full(L.size, -1, np.int64)
        grids_l = np.zeros((L.size, 6))
        ilen_l, clen_l = np.zeros(L.size, np.int64), np.zeros(L.size, np.int64)
        codes_l[new], grids_l[new], ilen_l[new], clen_l[new] = got[0], got[1], got[2], got[4]
        r = (codes_l, grids_l, ilen_l, got[3], clen_l, got[5])  # ragged parts: the tried ones, in order
        res.append(r)
        fail = np.flatnonzero((r[0] != TRAP_OK) & (L < lmax))
        i2, j2 = 2 * I[fail], 2 * J[fail]
        lv.append(np.repeat(L[fail] + 1, 4))
        ii.append(np.stack([i2, i2 + 1, i2, i2 + 1], 1).ravel())
        jj.append(np.stack([j2, j2, j2 + 1, j2 + 1], 1).ravel())
        parent.append(np.repeat(base + fail, 4))
        root.append(np.repeat(root[-1][fail], 4))
        base += L.size
    lv, ii, jj, parent, root = (np.concatenate(x) for x in (lv, ii, jj, parent, root))
    codes = np.concatenate([r[0] for r in res]) if res else np.zeros(0, np.int64)
    grids = np.concatenate([r[1] for r in res]) if res else np.zeros((0, 6))
    ilen = np.concatenate([r[2] for r in res]) if res else np.zeros(0, np.int64)
    entries = np.concatenate([r[3] for r in res]) if res else np.zeros(0, np.int64)
    clen = np.concatenate([r[4] for r in res]) if res else np.zeros(0, np.int64)
    cells = np.concatenate([r[5] for r in res]) if res else np.zeros(0, np.int64)
    proven = codes == TRAP_OK
    # a node is useful when it or a descendant is proven (children come after parents)
    useful = proven.copy()
    up = np.flatnonzero(useful & (parent >= 0))
    while up.size:  # one level of ancestors a pass (a tree of len(res) levels)
        p = np.unique(parent[up])
        p = p[~useful[p]]
        useful[p] = True
        up = p[parent[p] >= 0]
    is_split = useful & ~proven
    has_parent = parent >= 0
    emit = np.zeros(lv.size, bool)
    emit[has_parent] = is_split[parent[has_parent]] & (proven[has_parent] | ~useful[has_parent])
    emit[~has_parent] = ~is_split[~has_parent]  # roots not split stay (changed if proven)
    why, count = np.unique(codes[~proven & (codes >= 0)], return_counts=True)
    failures = {TRAP_FAILURES[int(c)]: int(n) for c, n in zip(why, count)}
    # the new table: the rows not split, then the leaves of the splits; each from a source row
    split_rows = np.zeros(st0.size, bool)
    split_rows[root[~has_parent & is_split]] = True
    keep = np.flatnonzero(~split_rows)
    node_of = np.full(st0.size, -1, np.int64)  # a kept row's node (a root tried)
    node_of[root[~has_parent]] = np.flatnonzero(~has_parent)
    leaves = np.flatnonzero(emit & has_parent)
    # the atlas's order: by level, then j, then i
    L_out = np.concatenate([ds["level"].values[keep].astype(np.int64), lv[leaves]])
    I_out = np.concatenate([ds["i"].values[keep].astype(np.int64), ii[leaves]])
    J_out = np.concatenate([ds["j"].values[keep].astype(np.int64), jj[leaves]])
    order = np.argsort(row_key(L_out, I_out, J_out), kind="stable")
    src = np.concatenate([keep, root[leaves]])[order]
    node = np.concatenate([node_of[keep], leaves])[order]  # -1: a row not tried
    leaf = np.concatenate([np.full(keep.size, -1, np.int64), np.arange(leaves.size)])[order]
    n_out = src.size
    box_vars = [k for k in ds.variables if ds[k].dims == ("box",)]
    cols = {k: ds[k].values[src] for k in box_vars}
    new = np.flatnonzero(leaf >= 0)
    pieces = leaves[leaf[new]]
    for k, vals in (("level", lv[pieces]), ("i", ii[pieces]), ("j", jj[pieces])):
        cols[k][new] = vals.astype(cols[k].dtype)
    e0n, e1n, u0n, u1n = (np.empty(pieces.size) for _ in range(4))
    _box_edges(win, lv[pieces], ii[pieces], jj[pieces], e0n, e1n, u0n, u1n)
    for k, vals in (("e0", e0n), ("e1", e1n), ("u0", u0n), ("u1", u1n)):
        cols[k][new] = vals

    def proven_at(nodes):  # whether each row's node (-1: not tried) was proven
        hit = np.zeros(nodes.size, bool)
        hit[nodes >= 0] = proven[nodes[nodes >= 0]]
        return hit

    trapped = np.flatnonzero(proven_at(node))
    cols["status"][trapped] = NO_SLIDING
    # Python strings, as certify's table holds them (one object per distinct text)
    reason = cols["reason"].astype(object, copy=False)
    reason[trapped] = "trapping"
    cols["reason"] = reason
    cols["step"][trapped] = 0
    tn = node[trapped]
    # itineraries: a proven box's entry, else its source row's
    off0 = ds["offsets"].values
    itin0 = ds["itinerary"].values
    ioff = np.zeros(ilen.size + 1, np.int64)
    np.cumsum(ilen, out=ioff[1:])
    starts = off0[src].copy()
    lengths = np.diff(off0)[src]
    starts[trapped] = itin0.size + ioff[tn]
    lengths[trapped] = ilen[tn]
    offsets = np.zeros(n_out + 1, np.int64)
    np.cumsum(lengths, out=offsets[1:])
    itinerary = _take_rows(np.concatenate([itin0, entries.astype(np.int64, copy=False)]), starts, lengths)
    coff = np.zeros(clen.size + 1, np.int64)
    np.cumsum(clen, out=coff[1:])
    cell_off = np.zeros(trapped.size + 1, np.int64)
    np.cumsum(clen[tn], out=cell_off[1:])
    data = {k: ("box", cols[k]) for k in box_vars}
    data.update(offsets=("offset", offsets), itinerary=("itinerary_step", itinerary),
                trap_box=("trap", trapped.astype(np.int64)),
                trap_grid=(("trap", "trap_grid_field"), grids[tn].reshape(-1, 6)),
                trap_cell_offsets=("trap_offset", cell_off),
                trap_cells=("trap_cell", _take_rows(cells.astype(np.int64, copy=False), coff[tn], clen[tn])))
    out = xr.Dataset(data)
    for k in box_vars:
        out[k].attrs = ds[k].attrs
    out.attrs = dict(ds.attrs, trap_split=int(split), trap_grids=[int(c) for c in _try_grids(fine)[0]],
                     trap_tried=int(done),
                     trap_seconds=time.perf_counter() - t0,
                     trap_failures=", ".join(f"{k} {v}" for k, v in sorted(failures.items())))
    return out


def region_of(ds, b):
    """The :class:`TrappingRegion` stored for row ``b`` of an atlas table."""
    r = int(np.flatnonzero(ds["trap_box"].values == b)[0])
    off = ds["trap_cell_offsets"].values
    g = ds["trap_grid"].values[r]
    io = ds["offsets"].values
    return TrappingRegion(
        e=(float(ds["e0"].values[b]), float(ds["e1"].values[b])),
        u=(float(ds["u0"].values[b]), float(ds["u1"].values[b])),
        itinerary=tuple(int(k) for k in ds["itinerary"].values[io[b]:io[b + 1]]),
        grid=(float(g[0]), float(g[1]), int(g[2]), float(g[3]), float(g[4]), int(g[5])),
        cells=ds["trap_cells"].values[off[r]:off[r + 1]].astype(np.int64), entry=(np.nan,) * 4)


def certificate_of(region, max_iter):
    """The ``no_sliding`` :class:`Certificate` (reason ``"trapping"``) of a region."""
    return Certificate(e=region.e, u=region.u, max_iter=int(max_iter), status="no_sliding",
                       reason="trapping", itinerary=region.itinerary, decisions=("trapping region",),
                       margins=np.zeros((0, 2)), region=region)
