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
from .certificate import _cell_edge as _cell_edge_py

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


# the edge of certificate.py (TrappingRegion.boxes), compiled for the kernels below
_cell_edge = njit(cache=True)(_cell_edge_py)


@njit(cache=True)
def _cell_range(a, b, lo, hi, n):
    """Cells ``i0..i1`` of the axis whose union covers ``[a, b]`` (-1 when outside)."""
    if not (a >= lo and b <= hi and a <= b):
        return -1, -1
    w = hi - lo
    i0 = min(max(int((a - lo) / w * n), 0), n - 1)
    while i0 > 0 and _cell_edge(lo, w, hi, i0, n) > a:
        i0 -= 1
    while i0 < n - 1 and _cell_edge(lo, w, hi, i0 + 1, n) <= a:
        i0 += 1
    i1 = min(max(int((b - lo) / w * n), i0), n - 1)
    while i1 < n - 1 and _cell_edge(lo, w, hi, i1 + 1, n) < b:
        i1 += 1
    while i1 > i0 and _cell_edge(lo, w, hi, i1, n) >= b:
        i1 -= 1
    return i0, i1


@njit(cache=True)
def _entry(E0, E1, U0, U1, max_steps, itin):
    """Follow the orbit of ``(0, sqrt 2)`` while every step is decided over the box.

    Returns ``(code, n, v0, v1, s0, s1)``: the enclosure of the state before
    the first step with more than one possible impact number (or after
    ``max_steps``), the ``n`` decided steps written to ``itin``.
    """
    Tl = _dn(1.0 / U1)
    Th = _up(1.0 / U0)
    Rl = _dn(_dn(1.0 + E0) / _up(1.0 - E0))
    out = np.empty((_CAP + 2, 5))
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
def _enqueue(c, flags, queue, tail):
    """Put cell ``c`` at ``queue[tail]`` unless it was queued before (``flags``): the
    new tail, or -1 when the queue (``max_cells`` long) is full."""
    if flags[c] != 0:
        return tail
    if tail >= queue.size:
        return -1
    flags[c] = 1
    queue[tail] = c
    return tail + 1


@njit(cache=True)
def _close(E0, E1, U0, U1, V0, V1, nv, S0, S1, ns, seed, max_cells, flags):
    """Grow the region from the cell rectangle ``seed = (i0, i1, j0, j1)``: the
    cells reachable by the branches' image enclosures (breadth first).

    ``flags`` (``nv * ns``, zeroed) marks the region's cells (index ``j * nv +
    i``).  Returns ``(code, cells)``; ``code`` is ``TRAP_OK`` when the region is
    closed: every cell's images lie in it and no cell may slide.
    """
    Tl = _dn(1.0 / U1)
    Th = _up(1.0 / U0)
    Rl = _dn(_dn(1.0 + E0) / _up(1.0 - E0))
    wv = V1 - V0
    ws = S1 - S0
    out = np.empty((_CAP + 2, 5))
    queue = np.empty(max_cells, np.int64)
    head = 0
    tail = 0
    for j in range(seed[2], seed[3] + 1):
        for i in range(seed[0], seed[1] + 1):
            t = _enqueue(j * nv + i, flags, queue, tail)
            if t < 0:
                return TRAP_CELLS, tail
            tail = t
    while head < tail:
        c = queue[head]
        head += 1
        i = c % nv
        j = c // nv
        v0 = _cell_edge(V0, wv, V1, i, nv)
        v1 = _cell_edge(V0, wv, V1, i + 1, nv)
        s0 = _cell_edge(S0, ws, S1, j, ns)
        s1 = _cell_edge(S0, ws, S1, j + 1, ns)
        m = _branches(v0, v1, s0, s1, E0, E1, Tl, Th, Rl, out)
        if m < 0:
            return -m, tail
        for r in range(m):
            i0, i1 = _cell_range(out[r, 0], out[r, 1], V0, V1, nv)
            j0, j1 = _cell_range(out[r, 2], out[r, 3], S0, S1, ns)
            if i0 < 0 or j0 < 0:
                if np.isnan(out[r, 0]) or np.isnan(out[r, 1]) or np.isnan(out[r, 2]) or np.isnan(out[r, 3]):
                    return TRAP_NAN, tail
                return TRAP_ESCAPE, tail
            for jj in range(j0, j1 + 1):
                for ii in range(i0, i1 + 1):
                    t = _enqueue(jj * nv + ii, flags, queue, tail)
                    if t < 0:
                        return TRAP_CELLS, tail
                    tail = t
    return TRAP_OK, tail


@njit(cache=True)
def _hull(e, u, n0, steps):
    """Numerical: the rectangle of ``(v, s)`` visited by the float map from (1, 0)
    between steps ``n0`` and ``n0 + steps`` (``slid``: it slid on the way).  Only
    chooses where the grid lies; nothing proven rests on it."""
    T, ratio = _model._constants(e, u)
    y = 1.0
    v = 0.0
    h = np.array([np.inf, -np.inf, np.inf, -np.inf])
    for n in range(n0 + steps):
        y, v, k = _model._step(y, v, e, T, ratio)
        if k == _model.SLIDING:
            return h, True
        if n + 1 >= n0:
            s = math.sqrt(v * v + 2.0 * y)
            h[0] = min(h[0], v)
            h[1] = max(h[1], v)
            h[2] = min(h[2], s)
            h[3] = max(h[3], s)
    return h, False




# grid tries: (cells a side, padding of the float orbits' rectangle, in its extent)
_TRIES = ((64, 0.3), (128, 0.3), (64, 1.0))
_MAX_CELLS = 1 << 15
_HULL_STEPS = 2000


def _try(e0, e1, u0, u1, max_iter, tries=_TRIES, max_cells=_MAX_CELLS):
    """``(region or None, failure)``: the first try of ``tries`` that closes."""
    itin = np.empty(max(max_iter, 1), np.int64)
    code, n, v0, v1, s0, s1 = _entry(e0, e1, u0, u1, max_iter, itin)
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
        flags = np.zeros(cells * cells, np.uint8)
        code, m = _close(e0, e1, u0, u1, grid[0], grid[1], cells, grid[3], grid[4], cells,
                         np.array([i0, i1, j0, j1], np.int64), max_cells, flags)
        if code == TRAP_OK:
            return TrappingRegion(e=(e0, e1), u=(u0, u1), itinerary=tuple(int(k) for k in itin[:n]),
                                  grid=grid, cells=np.flatnonzero(flags).astype(np.int64),
                                  entry=(float(v0), float(v1), float(s0), float(s1))), "ok"
        failure = TRAP_FAILURES[code]
    return None, failure


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


def trap_atlas(ds, progress=None):
    """The atlas table ``ds`` (``certify``'s Dataset) with its undecided
    ``"nonsliding"`` boxes tried by :func:`_try`: those with a trapping region
    become ``no_sliding`` with reason ``"trapping"``, their entry itinerary in
    ``itinerary``/``offsets`` and the region in ``trap_box`` (the box's row),
    ``trap_grid`` (``v_lo, v_hi, nv, s_lo, s_hi, ns``), ``trap_cell_offsets``
    and ``trap_cells``; ``attrs["trap_seconds"]``, ``attrs["trap_tried"]`` and
    ``attrs["trap_failures"]`` (why the others failed, :data:`TRAP_FAILURES`)."""
    import time

    from ._kernel import NO_SLIDING, UNDECIDED, _U_MIN

    t0 = time.perf_counter()
    st = ds["status"].values.copy()
    reason = ds["reason"].values.astype(object).copy()
    cols = [ds[k].values for k in ("e0", "e1", "u0", "u1")]
    max_iter = int(ds.attrs["max_iter"])
    sel = np.flatnonzero((st == UNDECIDED) & (reason == "nonsliding"))
    found = {}
    failures = {}
    for n, b in enumerate(sel):
        e0, e1, u0, u1 = (float(c[b]) for c in cols)
        if e0 > 0.0 and e1 < 1.0 and u0 >= _U_MIN:
            r, why = _try(e0, e1, u0, u1, max_iter)
            if r is not None:
                found[int(b)] = r
            else:
                failures[why] = failures.get(why, 0) + 1
        if (n + 1) % 256 == 0:
            check_halt()   # a Ctrl-C of certify's caller (run_interruptible) stops the pass here
            if progress is not None:
                progress(n + 1, sel.size)
    off = ds["offsets"].values
    itin = ds["itinerary"].values
    pieces = [itin[off[b]:off[b + 1]] if b not in found else np.asarray(found[b].itinerary, np.int64)
              for b in range(st.size)]
    lengths = np.array([p.size for p in pieces], np.int64)
    offsets = np.zeros(st.size + 1, np.int64)
    np.cumsum(lengths, out=offsets[1:])
    boxes = np.array(sorted(found), np.int64)
    for b in boxes:
        st[b] = NO_SLIDING
        reason[b] = "trapping"
    step = ds["step"].values.copy()
    step[boxes] = 0
    regions = [found[int(b)] for b in boxes]
    counts = np.array([r.cells.size for r in regions], np.int64)
    cell_off = np.zeros(boxes.size + 1, np.int64)
    np.cumsum(counts, out=cell_off[1:])
    out = ds.drop_vars(["offsets", "itinerary"]).assign(
        status=("box", st.astype(np.int8)), reason=("box", reason.astype(str)), step=("box", step),
        offsets=("offset", offsets),
        itinerary=("itinerary_step", np.concatenate(pieces) if pieces else np.zeros(0, np.int64)),
        trap_box=("trap", boxes),
        trap_grid=(("trap", "trap_grid_field"), np.array([r.grid for r in regions], np.float64).reshape(-1, 6)),
        trap_cell_offsets=("trap_offset", cell_off),
        trap_cells=("trap_cell", np.concatenate([r.cells for r in regions]) if regions else np.zeros(0, np.int64)),
    )
    out.attrs = dict(ds.attrs, trap_tried=int(sel.size), trap_seconds=time.perf_counter() - t0,
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
