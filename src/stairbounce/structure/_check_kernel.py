"""The checker's compiled loops (numba): the step-by-step re-decision of
``structure/verify.py`` and the trapping-region check of
``structure/verify_trapping.py``, over boxes, steps, cells and impact numbers.

Independent of the certifier: this module shares no code with
``structure/_kernel.py``, ``structure/trapping.py`` or ``stairbounce.model``.
Its arithmetic is the checker's, operation for operation (the rigour argument
is ``verify.py``'s module docstring): every bound is one IEEE-754 operation
(+, -, *, /, sqrt; correctly rounded to nearest; numba compiles without
fastmath, so nothing is contracted into a fused multiply-add nor reordered)
moved one float outward by :func:`_dn` / :func:`_up` (``np.nextafter`` towards
-inf / +inf).  The scalar operations here are those the numpy version applied
to whole arrays, in the same order, so both give the same floats and the same
verdicts (tests/test_verify_fast.py compares them with the numpy checker kept
in tests/).
"""

from __future__ import annotations

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

# impact numbers k < _CACHED have their coefficients computed once per box
_CACHED = 64


@intrinsic
def _int_of(typingctx, x):
    """The bits of the float64 ``x``, as an int64 (reinterpreted, not converted)."""
    if x != types.float64:
        return None
    return types.int64(x), lambda context, builder, sig, args: builder.bitcast(args[0], ir.IntType(64))


@intrinsic
def _float_of(typingctx, n):
    """The float64 whose bits are the int64 ``n``."""
    if n != types.int64:
        return None
    return types.float64(n), lambda context, builder, sig, args: builder.bitcast(args[0], ir.DoubleType())


@njit(cache=True)
def _up(x):
    """``np.nextafter(x, inf)``, float for float (tests/test_verify_fast.py compares them
    on zeros, subnormals, infinities and NaN): the next float above a finite x is one
    step of its bits, up for x > 0, down (towards -0) for x < 0; from either zero the
    least subnormal; inf and NaN stay.  libm's call cost several times more."""
    if x != x or x == np.inf:
        return x
    if x == 0.0:
        return 5e-324
    b = _int_of(x)
    return _float_of(b + 1 if x > 0.0 else b - 1)


@njit(cache=True)
def _dn(x):
    """``np.nextafter(x, -inf)`` = ``-nextafter(-x, inf)``."""
    return -_up(-x)


@njit(cache=True, inline="always")
def _min(a, b):  # np.minimum: a NaN wins
    if a != a or b != b:
        return np.nan
    return a if a <= b else b


@njit(cache=True, inline="always")
def _max(a, b):  # np.maximum: a NaN wins
    if a != a or b != b:
        return np.nan
    return a if a >= b else b


@njit(cache=True, inline="always")
def _mul_pos(alo, ahi, blo, bhi):
    """Product of two non-negative intervals (bounds clipped at 0)."""
    return _max(_dn(alo * blo), 0.0), _max(_up(ahi * bhi), 0.0)


@njit(cache=True, inline="always")
def _div_pos(alo, ahi, blo, bhi):
    """``a / b`` for ``b`` positive, ``a`` of any sign."""
    return _dn(_min(alo / blo, alo / bhi)), _up(_max(ahi / bhi, ahi / blo))


@njit(cache=True, inline="always")
def _sqrt(alo, ahi):
    """Root of a non-negative interval."""
    return (_max(_dn(np.sqrt(_max(alo, 0.0))), 0.0), _max(_up(np.sqrt(_max(ahi, 0.0))), 0.0))


@njit(cache=True)
def _coefficients(e, k):
    """At the float ``e`` (exact), enclosures of ``e^k``, ``A_k``, ``A_{k+1}``
    and ``B_k`` (verify.py's docstring), as eight floats ``(E_lo, E_hi, A_lo,
    A_hi, A1_lo, A1_hi, B_lo, B_hi)``; ``e^k`` by binary powering with each
    product rounded outward."""
    elo, ehi = 1.0, 1.0
    blo, bhi = e, e
    while True:
        if k & 1:
            elo, ehi = _mul_pos(elo, ehi, blo, bhi)
        k >>= 1
        if k == 0:
            break
        blo, bhi = _mul_pos(blo, bhi, blo, bhi)
    ope_lo, ope_hi = _dn(1.0 + e), _up(1.0 + e)  # 1 + e
    ome_lo, ome_hi = _dn(1.0 - e), _up(1.0 - e)  # 1 - e
    eelo, eehi = _mul_pos(e, e, elo, ehi)  # e^(k+1)
    # 1 + e - 2 e^k (2 e^k exact: a power of two), over 1 - e
    alo, ahi = _div_pos(_dn(ope_lo - 2.0 * ehi), _up(ope_hi - 2.0 * elo), ome_lo, ome_hi)
    a1lo, a1hi = _div_pos(_dn(ope_lo - 2.0 * eehi), _up(ope_hi - 2.0 * eelo), ome_lo, ome_hi)
    # 1 - e^k >= 0
    omlo, omhi = _max(_dn(1.0 - ehi), 0.0), _max(_up(1.0 - elo), 0.0)
    plo, phi = _mul_pos(ope_lo, ope_hi, omlo, omhi)
    b_lo, b_hi = _div_pos(plo, phi, ome_lo, ome_hi)
    return elo, ehi, alo, ahi, a1lo, a1hi, b_lo, b_hi


@njit(cache=True, inline="always")
def _times(u0, u1):
    """``T = 1/u`` over ``[u0, u1]`` (decreasing in u): lower at u1, upper at u0."""
    return _div_pos(1.0, 1.0, u1, u1)[0], _div_pos(1.0, 1.0, u0, u0)[1]


@njit(cache=True)
def _fill(coef, at, e0, e1, k):
    """The coefficients of impact number ``k`` over ``[e0, e1]`` into ``coef[at]``:
    each increases with e, so its lower bound at e0 and upper bound at e1."""
    c0 = _coefficients(e0, k)
    c1 = _coefficients(e1, k)
    for q in range(4):
        coef[at, 2 * q] = c0[2 * q]
        coef[at, 2 * q + 1] = c1[2 * q + 1]


@njit(cache=True, nogil=True)
def follow(e0, e1, u0, u1, itinerary, offsets, boxes, code, step, c_slide, c_impact, c_noimpact):
    """Re-decide every step of the boxes ``boxes``; writes the first failure of
    box ``b`` (``c_slide``, ``c_impact`` or ``c_noimpact``) into ``code[b]`` and
    its 1-based step into ``step[b]``.  Box ``b``'s itinerary is
    ``itinerary[offsets[b]:offsets[b + 1]]`` (entries >= -1, checked before)."""
    stamp = np.full(_CACHED, -1, np.int64)
    cache = np.empty((_CACHED, 8))
    one_c = np.empty((1, 8))
    for bi in range(len(boxes)):
        b = boxes[bi]
        a, z = e0[b], e1[b]
        tlo, thi = _times(u0[b], u1[b])
        # ratio = (1+e)/(1-e) over the box: its value at e0 (lower) and e1 (upper)
        rlo = _div_pos(_dn(1.0 + a), _up(1.0 + a), _dn(1.0 - a), _up(1.0 - a))[0]
        rhi = _div_pos(_dn(1.0 + z), _up(1.0 + z), _dn(1.0 - z), _up(1.0 - z))[1]
        vlo, vhi = 0.0, 0.0
        slo, shi = _sqrt(2.0, 2.0)
        for n in range(offsets[b], offsets[b + 1]):
            k = itinerary[n]
            kk = k if k > 0 else 0
            if kk < _CACHED:
                if stamp[kk] != bi:
                    _fill(cache, kk, a, z, kk)
                    stamp[kk] = bi
                c = cache[kk]
            else:
                _fill(one_c, 0, a, z, kk)
                c = one_c[0]
            tvlo, tvhi = _dn(tlo - vhi), _up(thi - vlo)  # T - v
            rs = _mul_pos(rlo, rhi, slo, shi)
            slide_lo, slide_hi = _dn(tvlo - rs[1]), _up(tvhi - rs[0])  # (2.4)
            bad = 0
            if k == -1:
                if not slide_lo >= 0.0:
                    bad = c_slide
            else:
                if not slide_hi < 0.0:
                    bad = c_slide
                else:
                    if k >= 1:  # T - t_k, t_k = v + A_k s (A_k >= 0 here)
                        hs = _mul_pos(_max(c[2], 0.0), _max(c[3], 0.0), slo, shi)
                        if not _dn(tvlo - hs[1]) >= 0.0:
                            bad = c_impact
                    if bad == 0:  # T - t_{k+1}
                        ms = _mul_pos(c[4], c[5], slo, shi)
                        if not _up(tvhi - ms[0]) < 0.0:
                            bad = c_noimpact
            if bad != 0:
                code[b] = bad
                step[b] = n - offsets[b] + 1
                break
            # the next state: v' = v - T + B_k s, s' = sqrt(2 + (e^k s)^2)
            es_lo, es_hi = _mul_pos(c[0], c[1], slo, shi)
            bs_lo, bs_hi = _mul_pos(c[6], c[7], slo, shi)
            vlo, vhi = _dn(_dn(vlo - thi) + bs_lo), _up(_up(vhi - tlo) + bs_hi)
            q_lo, q_hi = _mul_pos(es_lo, es_hi, es_lo, es_hi)
            slo, shi = _sqrt(_dn(q_lo + 2.0), _up(q_hi + 2.0))


@njit(cache=True)
def entered(e0, e1, u0, u1, itinerary):
    """The enclosure ``(v0, v1, s0, s1)`` of the state after the itinerary
    (impact numbers >= 0), from ``(v, s) = (0, sqrt 2)`` with ``v' = v - T +
    B_k s``, ``s' = sqrt(2 + (e^k s)^2)``."""
    tlo, thi = _times(u0, u1)
    vlo, vhi = 0.0, 0.0
    slo, shi = _sqrt(2.0, 2.0)
    for n in range(len(itinerary)):
        k = itinerary[n]
        c0 = _coefficients(e0, k if k > 0 else 0)
        c1 = _coefficients(e1, k if k > 0 else 0)
        es_lo, es_hi = _mul_pos(c0[0], c1[1], slo, shi)
        bs_lo, bs_hi = _mul_pos(_max(c0[6], 0.0), _max(c1[7], 0.0), slo, shi)
        vlo, vhi = _dn(_dn(vlo - thi) + bs_lo), _up(_up(vhi - tlo) + bs_hi)
        q_lo, q_hi = _mul_pos(es_lo, es_hi, es_lo, es_hi)
        slo, shi = _sqrt(_dn(q_lo + 2.0), _up(q_hi + 2.0))
    return vlo, vhi, slo, shi


@njit(cache=True)
def _search_right(edges, x):
    """``np.searchsorted(edges, x, "right")`` for a finite ``x``."""
    lo, hi = 0, len(edges)
    while lo < hi:
        mid = (lo + hi) // 2
        if edges[mid] <= x:
            lo = mid + 1
        else:
            hi = mid
    return lo


@njit(cache=True)
def _search_left(edges, x):
    """``np.searchsorted(edges, x, "left")`` for a finite ``x``."""
    lo, hi = 0, len(edges)
    while lo < hi:
        mid = (lo + hi) // 2
        if edges[mid] < x:
            lo = mid + 1
        else:
            hi = mid
    return lo


@njit(cache=True)
def runs(cells, nv):
    """A region's cells (indices ``j * nv + i``) as the coverage test reads them:
    sorted row by row without repeats, and for each the last column of the run of
    region cells in its row that holds it.  Memory and time scale with the
    region's cells, not with the rectangle of the grid that holds them (a thin
    ring on a fine grid)."""
    s = np.unique(cells)
    m = s.size
    last = np.empty(m, np.int64)
    for k in range(m - 1, -1, -1):
        i = s[k] % nv
        if k + 1 < m and s[k + 1] == s[k] + 1 and i + 1 < nv:  # the next cell, in the same row
            last[k] = last[k + 1]
        else:
            last[k] = i
    return s, last


@njit(cache=True, inline="always")
def _index(s, key):
    """The position of ``key`` in the sorted ``s``, or -1."""
    p = _search_left(s, key)
    return p if p < s.size and s[p] == key else -1


@njit(cache=True)
def covered(s, last, ev, es, a0, a1, b0, b1):
    """Whether the rectangle ``[a0, a1] x [b0, b1]`` lies in the union of the
    region cells ``s`` (with their runs ``last``, from :func:`runs`) of the grid
    with edges ``ev`` (v) and ``es`` (s): every grid cell it meets, row by row,
    lies in one run of region cells."""
    nv, ns = len(ev) - 1, len(es) - 1
    if not (a0 >= ev[0] and a1 <= ev[nv] and b0 >= es[0] and b1 <= es[ns] and a0 <= a1 and b0 <= b1):
        return False
    i0 = min(max(_search_right(ev, a0) - 1, 0), nv - 1)
    i1 = max(min(max(_search_left(ev, a1) - 1, 0), nv - 1), i0)
    j0 = min(max(_search_right(es, b0) - 1, 0), ns - 1)
    j1 = max(min(max(_search_left(es, b1) - 1, 0), ns - 1), j0)
    for j in range(j0, j1 + 1):
        p = _index(s, j * nv + i0)
        if p < 0 or last[p] < i1:
            return False
    return True


@njit(cache=True)
def region_check(e0, e1, u0, u1, v0, v1, s0, s1, cs, last, ev, es, cap):
    """The ``slide`` and ``invariant`` checks of ``verify_trapping.verify_region``
    on the cells ``[v0, v1] x [s0, s1]`` (arrays): 0 when both hold, 1 when the
    slide margin is not proven < 0 on a cell, 2 when an image is not covered (or
    an impact number beyond ``cap`` stays possible).  The loop over impact
    numbers k runs while some cell may still take impact k (as the numpy
    version did)."""
    m = len(v0)
    th = _times(u0, u1)[1]  # T at u0, upper bound
    tl = _times(u0, u1)[0]  # T at u1, lower bound
    ratio0 = _div_pos(_dn(1.0 + e0), _up(1.0 + e0), _dn(1.0 - e0), _up(1.0 - e0))[0]
    for c in range(m):
        if not _up(_up(th - v0[c]) - _dn(ratio0 * s0[c])) < 0.0:
            return 1
    live = np.ones(m, np.bool_)
    hi_prev = np.full(m, np.inf)
    for k in range(cap + 1):
        E_lo, _, A_lo, _, A1_lo, _, B_lo, _ = _coefficients(e0, k)
        _, E_hi, _, A_hi, _, A1_hi, _, B_hi = _coefficients(e1, k)
        any_live = False
        for c in range(m):
            # margins T - v - A s: least at the upper corner, largest at the lower one
            lo_next = _dn(tl - _up(v1[c] + _up(A1_hi * s1[c])))  # T - t_{k+1}, least
            if k:
                lo_k = _dn(tl - _up(v1[c] + _up(A_hi * s1[c])))
                hi_k = _up(th - _dn(v0[c] + _max(_dn(A_lo * s0[c]), 0.0)))
            else:
                lo_k = -np.inf
                hi_k = hi_prev[c]
            can = live[c] and not (lo_next >= 0.0)
            if k and hi_k < 0.0:
                can = False
            if can:
                # v' = v - T + B_k s, s' = sqrt(2 + (e^k s)^2), increasing: the corners
                a0 = _dn(_dn(v0[c] - th) + _max(_dn(B_lo * s0[c]), 0.0))
                a1 = _up(_up(v1[c] - tl) + _up(B_hi * s1[c]))
                w_lo = _max(_dn(E_lo * s0[c]), 0.0)
                w_hi = _up(E_hi * s1[c])
                if k:  # v' = w_k - d, d = T - t_k in [max(lo_k, 0), hi_k] and [0, 2 w_k)
                    a0 = _max(_max(a0, _dn(w_lo - hi_k)), -w_hi)
                    a1 = _min(a1, _up(w_hi - _max(lo_k, 0.0)))
                else:  # v' = -(T - t_1) - s with T - t_1 < 0 and >= its lower bound
                    hi1 = _up(th - _dn(v0[c] + _max(_dn(1.0 * s0[c]), 0.0)))
                    a0 = _max(a0, _dn(-_min(hi1, 0.0) - s1[c]))
                    a1 = _min(a1, _up(-lo_next - s0[c]))
                q0 = _mul_pos(w_lo, w_lo, w_lo, w_lo)[0]
                b0 = _sqrt(_dn(q0 + 2.0), _dn(q0 + 2.0))[0]
                q1 = _mul_pos(w_hi, w_hi, w_hi, w_hi)[1]
                b1 = _sqrt(_up(q1 + 2.0), _up(q1 + 2.0))[1]
                if not covered(cs, last, ev, es, a0, a1, b0, b1):
                    return 2
            # impact k + 1 may happen where T - t_{k+1} is not proven < 0
            hi_prev[c] = _up(th - _dn(v0[c] + _max(_dn(A1_lo * s0[c]), 0.0)))
            live[c] = not (hi_prev[c] < 0.0)
            any_live = any_live or live[c]
        if not any_live:
            return 0
    return 2


@njit(cache=True)
def edges(lo, hi, n):
    """The cell edges of an axis: ``lo + (hi - lo) * (i * (1/n))``, the last ``hi``
    (``verify_trapping._edges``, the same operations)."""
    e = np.empty(n + 1)
    w = hi - lo
    r = 1.0 / n
    for i in range(n + 1):
        e[i] = lo + w * (i * r)
    e[n] = hi
    return e


@njit(cache=True)
def regions(e0, e1, u0, u1, itinerary, offsets, grids, cell_off, cells, todo, cap, out):
    """The ``entered``, ``slide`` and ``invariant`` checks of
    ``verify_trapping.verify_region`` on the regions ``todo``, one after another:
    region ``r`` of box ``(e0[r], e1[r], u0[r], u1[r])``, entry
    ``itinerary[offsets[r]:offsets[r + 1]]``, grid ``grids[r]`` (``v_lo, v_hi, nv,
    s_lo, s_hi, ns``, checked before) and cells ``cells[cell_off[r]:cell_off[r +
    1]]``; writes 0 (all hold), 3 (``entered``), 4 (``slide``) or 5
    (``invariant``) into ``out[r]``, the indices of ``verify_trapping.TRAP_CHECKS``."""
    for t in range(todo.size):
        r = todo[t]
        nv = int(grids[r, 2])
        ns = int(grids[r, 5])
        ev = edges(grids[r, 0], grids[r, 1], nv)
        es = edges(grids[r, 3], grids[r, 4], ns)
        c0, c1 = cell_off[r], cell_off[r + 1]
        cs, last = runs(cells[c0:c1], nv)
        a0, a1, b0, b1 = entered(e0[r], e1[r], u0[r], u1[r], itinerary[offsets[r]:offsets[r + 1]])
        if not covered(cs, last, ev, es, a0, a1, b0, b1):
            out[r] = 3
            continue
        m = c1 - c0
        v0, v1, s0, s1 = np.empty(m), np.empty(m), np.empty(m), np.empty(m)
        for k in range(m):
            i = cells[c0 + k] % nv
            j = cells[c0 + k] // nv
            v0[k], v1[k], s0[k], s1[k] = ev[i], ev[i + 1], es[j], es[j + 1]
        what = region_check(e0[r], e1[r], u0[r], u1[r], v0, v1, s0, s1, cs, last, ev, es, cap)
        out[r] = 0 if what == 0 else (4 if what == 1 else 5)


# --------------------------------------------------------------------------- #
# the branch rule (verify_branches.follow, compiled)                          #
# --------------------------------------------------------------------------- #


@njit(cache=True, inline="always")
def _pmax(a, b):  # Python's max(a, b): b only when b > a (a NaN first argument stays)
    return b if b > a else a


@njit(cache=True, inline="always")
def _pmin(a, b):  # Python's min(a, b)
    return b if b < a else a


@njit(cache=True, inline="always")
def _root_lo(x):  # verify_branches._sqrt_lo
    return _pmax(_dn(np.sqrt(_pmax(x, 0.0))), 0.0)


@njit(cache=True)
def _grow(a, n):
    """``a`` with room for at least ``n`` rows (doubled), its rows kept."""
    if n <= a.shape[0]:
        return a
    b = np.empty((max(n, 2 * a.shape[0]),) + a.shape[1:], a.dtype)
    b[:a.shape[0]] = a
    return b


@njit(cache=True, inline="always")
def _push(nxt, nxt_node, nodes, nx, nn, it, k, v0, v1, r0, r1):
    """Append the branch ``v in [v0, v1]``, ``s^2 = 2 + r^2`` for ``r in [r0, r1]`` (``r`` the
    speed before the step: ``s`` for a fly-over, ``w_k`` after k impacts) to ``nxt``, its
    itinerary the node of ``it`` followed by ``k`` (none when ``it`` is merged, -1)."""
    nxt = _grow(nxt, nx + 1)
    nxt_node = _grow(nxt_node, nx + 1)
    nxt[nx, 0], nxt[nx, 1] = v0, v1
    nxt[nx, 2] = _root_lo(_dn(2.0 + _dn(r0 * r0)))
    nxt[nx, 3] = _up(np.sqrt(_up(2.0 + _up(r1 * r1))))
    if it < 0:
        nxt_node[nx] = -1
    else:
        nodes = _grow(nodes, nn + 1)
        nodes[nn, 0], nodes[nn, 1] = it, k
        nxt_node[nx] = nn
        nn += 1
    return nxt, nxt_node, nodes, nx + 1, nn


@njit(cache=True)
def _follow_one(e0, e1, u0, u1, max_iter, max_live, max_leaves, cap, nodes, leaves):
    """``verify_branches.follow`` on one box, operation for operation: ``(claim, n
    nodes, n leaves, nodes, leaves)``, claim 0 (None), 1 ("sliding") or 2
    ("no_slide_within"); the itineraries as a tree, ``nodes[i] = (parent, k)`` (node 0
    the empty itinerary), a leaf the node of a branch that may slide."""
    T0, T1 = _dn(1.0 / u1), _up(1.0 / u0)
    R0 = _dn(_dn(1.0 + e0) / _up(1.0 - e0))
    R1 = _up(_up(1.0 + e1) / _dn(1.0 - e1))
    r2 = np.sqrt(2.0)
    live = np.empty((max_live + 1, 4))
    live_node = np.empty(max_live + 1, np.int64)
    live[0, 0], live[0, 1], live[0, 2], live[0, 3] = 0.0, 0.0, _dn(r2), _up(r2)
    live_node[0] = 0
    nodes[0, 0], nodes[0, 1] = -1, 0
    nn, nl, n_live = 1, 0, 1
    nxt = np.empty((2 * max_live + 2, 4))
    nxt_node = np.empty(2 * max_live + 2, np.int64)
    for _ in range(max_iter):
        nx = 0
        for b in range(n_live):
            v0, v1, s0, s1 = live[b, 0], live[b, 1], live[b, 2], live[b, 3]
            it = live_node[b]
            tv0, tv1 = _dn(T0 - v1), _up(T1 - v0)
            m0, m1 = _dn(tv0 - _up(R1 * s1)), _up(tv1 - _pmax(_dn(R0 * s0), 0.0))
            if not m1 < 0.0:  # may slide
                if it < 0 or nl >= max_leaves:
                    return 0, nn, nl, nodes, leaves
                leaves = _grow(leaves, nl + 1)
                leaves[nl] = it
                nl += 1
                if m0 >= 0.0:
                    continue
            t0, t1 = _dn(v0 + s0), _up(v1 + s1)
            m0, m1 = _dn(T0 - t1), _up(T1 - t0)
            if not m0 >= 0.0:  # may fly over
                nxt, nxt_node, nodes, nx, nn = _push(nxt, nxt_node, nodes, nx, nn, it, 0, _dn(v0 - T1),
                                                     _up(v1 - T0), s0, s1)
            if m1 < 0.0:
                continue
            w0, w1 = _pmax(_dn(e0 * s0), 0.0), _up(e1 * s1)
            k = 1
            while True:
                n0, n1 = _dn(t0 + 2.0 * w0), _up(t1 + 2.0 * w1)
                m0, m1 = _dn(T0 - n1), _up(T1 - n0)
                if not m0 >= 0.0:  # may stop after k impacts
                    nxt, nxt_node, nodes, nx, nn = _push(nxt, nxt_node, nodes, nx, nn, it, k,
                                                         _dn(_dn(w0 + t0) - T1), _up(_up(w1 + t1) - T0), w0, w1)
                if m1 < 0.0:
                    break
                if k >= cap:
                    return 0, nn, nl, nodes, leaves
                t0, t1 = n0, n1
                w0, w1 = _pmax(_dn(e0 * w0), 0.0), _up(e1 * w1)
                k += 1
        if nx > max_live:  # merged: the hull, in the order Python's min and max take it
            a0, a1, a2, a3 = nxt[0, 0], nxt[0, 1], nxt[0, 2], nxt[0, 3]
            for b in range(1, nx):
                a0, a1 = _pmin(a0, nxt[b, 0]), _pmax(a1, nxt[b, 1])
                a2, a3 = _pmin(a2, nxt[b, 2]), _pmax(a3, nxt[b, 3])
            live[0, 0], live[0, 1], live[0, 2], live[0, 3] = a0, a1, a2, a3
            live_node[0] = -1
            n_live = 1
        else:
            for b in range(nx):
                live[b, 0], live[b, 1], live[b, 2], live[b, 3] = nxt[b, 0], nxt[b, 1], nxt[b, 2], nxt[b, 3]
                live_node[b] = nxt_node[b]
            n_live = nx
        if n_live == 0:
            return 1, nn, nl, nodes, leaves
    return (2 if nl == 0 else 0), nn, nl, nodes, leaves


@njit(cache=True)
def follow_boxes(e0, e1, u0, u1, max_iter, max_live, max_leaves, cap):
    """:func:`_follow_one` on every box: ``(claims, leaf offsets, leaf itineraries'
    offsets, impact numbers)``: box ``b``'s leaves are ``leaf_off[b] ..
    leaf_off[b + 1] - 1``, leaf ``l``'s itinerary ``impacts[it_off[l]:it_off[l + 1]]``
    (the claim 0 boxes have no leaves)."""
    n = e0.size
    claims = np.zeros(n, np.int64)
    leaf_off = np.zeros(n + 1, np.int64)
    it_off = np.zeros(1, np.int64)
    impacts = np.empty(64, np.int64)
    nodes = np.empty((1024, 2), np.int64)
    leaves = np.empty(64, np.int64)
    path = np.empty(64, np.int64)
    nlt, ni = 0, 0
    for b in range(n):
        claim, nn, nl, nodes, leaves = _follow_one(e0[b], e1[b], u0[b], u1[b], max_iter, max_live, max_leaves,
                                                   cap, nodes, leaves)
        claims[b] = claim
        if claim == 1:
            it_off = _grow(it_off, nlt + nl + 1)
            for l in range(nl):
                d = 0
                x = leaves[l]
                while x > 0:  # the path from the leaf up to the root, then reversed
                    path = _grow(path, d + 1)
                    path[d] = nodes[x, 1]
                    d += 1
                    x = nodes[x, 0]
                impacts = _grow(impacts, ni + d)
                for q in range(d):
                    impacts[ni + q] = path[d - 1 - q]
                ni += d
                nlt += 1
                it_off[nlt] = ni
        leaf_off[b + 1] = nlt
    return claims, leaf_off, it_off[:nlt + 1].copy(), impacts[:ni].copy()
