"""The independent checker of trapping regions (issue 36, item 7).

Re-verifies a ``no_sliding`` certificate proven by a trapping region
(``structure/trapping.py``) from the box, ``max_iter``, the entry itinerary
and the region (its grid and cells) alone, with numpy float64 intervals
rounded outward (the arithmetic of ``structure/verify.py``, whose rigour
argument applies word for word); it shares no code with the certifier's
kernel, with ``trapping.py`` nor with ``stairbounce.model``.

Checks (the first failure is the verdict):

* ``entry``: the itinerary's decisions, re-decided by ``verify.verify_codes``
  (as an ``undecided`` claim, which lists decided steps only);
* ``entered``: the state enclosure after the itinerary, followed here from
  ``(v, s) = (0, sqrt 2)`` with ``v' = v - T + B_k s``, ``s'^2 = 2 + (e^k
  s)^2``, lies in the union of the region's cells;
* ``slide``: on every cell the slide margin ``T - v - ratio s`` is proven < 0
  (its largest value is at the corner ``(v0, s0, e0, u0)``);
* ``invariant``: for every cell and every impact number k that is not proven
  impossible on it (``T - t_{k+1} >= 0`` everywhere, or ``T - t_k < 0``
  everywhere, ``t_j = v + A_j s``), the enclosure of the k-branch's image lies
  in the union of the cells.  Margins decrease, images increase, in v, s, e
  and u (``A_j, B_k, e^k, ratio`` >= 0 and increasing in e, ``T = 1/u``), so
  the corners ``(v0, s0, e0, u0)`` and ``(v1, s1, e1, u1)`` bound them; the
  image is cut by the branch's own facts (``v' = w_k - d``, ``d = T - t_k`` in
  ``[0, 2 w_k)`` and its margin's enclosure; ``v' = -(T - t_1) - s``,
  ``T - t_1 < 0`` for a fly-over).

Cell ``(i, j)`` of the grid ``(v_lo, v_hi, nv, s_lo, s_hi, ns)`` is the
product of ``[edge(i), edge(i+1)]`` on each axis, ``edge(i) = lo + (hi - lo)
* (i * (1/n))``, ``edge(n) = hi``: whatever floats these are, the checker's
cells are its own, so an image it finds covered is covered.
"""

from __future__ import annotations

import numpy as np

from .. import _validate as _v
from .verify import (_OUTWARD, _add, _coefficients, _div_pos, _mul_pos, _out, _point, _sqrt, _sub,
                     verify_codes)

__all__ = ["TRAP_CHECKS", "verify_region"]

TRAP_CHECKS = ("ok", "box", "entry", "entered", "slide", "invariant")
"""Names of the trapping checks (``verify_region`` returns one)."""

_IMPACT_CAP = 4096


def _edges(lo, hi, n):
    i = np.arange(n + 1, dtype=np.float64)
    e = lo + (hi - lo) * (i * (1.0 / n))
    e[n] = hi
    return e


def _covered(flags, ev, es, a0, a1, b0, b1):
    """Whether each rectangle ``[a0, a1] x [b0, b1]`` lies in the union of the flagged cells."""
    nv, ns = len(ev) - 1, len(es) - 1
    with np.errstate(invalid="ignore"):
        inside = (a0 >= ev[0]) & (a1 <= ev[-1]) & (b0 >= es[0]) & (b1 <= es[-1]) & (a0 <= a1) & (b0 <= b1)
    i0 = np.clip(np.searchsorted(ev, a0, "right") - 1, 0, nv - 1)
    i1 = np.clip(np.searchsorted(ev, a1, "left") - 1, 0, nv - 1)
    j0 = np.clip(np.searchsorted(es, b0, "right") - 1, 0, ns - 1)
    j1 = np.clip(np.searchsorted(es, b1, "left") - 1, 0, ns - 1)
    i1 = np.maximum(i1, i0)
    j1 = np.maximum(j1, j0)
    # flagged cells in the rectangle by a 2-D prefix sum
    P = np.zeros((ns + 1, nv + 1), np.int64)
    P[1:, 1:] = np.cumsum(np.cumsum(flags.reshape(ns, nv), axis=0), axis=1)
    count = P[j1 + 1, i1 + 1] - P[j0, i1 + 1] - P[j1 + 1, i0] + P[j0, i0]
    return inside & (count == (i1 - i0 + 1) * (j1 - j0 + 1))


def _entered(e0, e1, u0, u1, itinerary):
    """The enclosure ``(v0, v1, s0, s1)`` of the state after the itinerary."""
    one = np.ones((2, 1))
    T = np.stack([_div_pos(one, _point(np.array([u1])))[0], _div_pos(one, _point(np.array([u0])))[1]])
    V = np.zeros((2, 1))
    S = _sqrt(2.0 * one)
    k = np.asarray(itinerary, dtype=np.int64)
    if k.size:
        lo = _coefficients(np.full(k.size, e0), k)
        hi = _coefficients(np.full(k.size, e1), k)
        E = np.stack([lo[0][0], hi[0][1]])
        B = np.stack([lo[3][0], hi[3][1]])
        for n in range(k.size):
            es = _mul_pos(E[:, n:n + 1], S)
            V = _add(_sub(V, T), _mul_pos(np.maximum(B[:, n:n + 1], 0.0), S))
            S = _sqrt(_add(_mul_pos(es, es), 2.0 * one))
    return V[0, 0], V[1, 0], S[0, 0], S[1, 0]


def verify_region(e0, e1, u0, u1, max_iter, itinerary, grid, cells):
    """verify_region(e0, e1, u0, u1, max_iter, itinerary, grid, cells) -> str

    Re-verify that the cells ``cells`` (indices ``j * nv + i``) of ``grid =
    (v_lo, v_hi, nv, s_lo, s_hi, ns)`` form a trapping region of the box that
    the orbit of (1, 0) enters after ``itinerary``: ``"ok"``, or the name of the
    first failed check (:data:`TRAP_CHECKS`; the module's docstring).
    """
    e0, e1, u0, u1 = (float(x) for x in (e0, e1, u0, u1))
    itinerary = np.asarray(itinerary, dtype=np.int64).ravel()
    v_lo, v_hi, nv, s_lo, s_hi, ns = grid
    nv, ns = int(nv), int(ns)
    cells = np.asarray(cells, dtype=np.int64).ravel()
    if not (0.0 < e0 <= e1 < 1.0 and 0.0 < u0 <= u1 and nv >= 1 and ns >= 1 and cells.size
            and np.all((cells >= 0) & (cells < nv * ns)) and len(itinerary) <= max_iter
            and np.isfinite([v_lo, v_hi, s_lo, s_hi]).all() and v_lo < v_hi and 0.0 < s_lo < s_hi):
        return "box"
    code, _ = verify_codes([e0], [e1], [u0], [u1], ["undecided"], max_iter, itinerary, [0, len(itinerary)])
    if code[0] != 0:
        return "entry"
    # the cell flags and their two-dimensional prefix sums: 24 bytes a cell, refused by
    # name before they are made (a grid of 1e9 x 1e9 cells in a file is no MemoryError)
    _v.check_memory(f"the trapping region's grid of {nv} x {ns} cells", 24 * (nv + 1) * (ns + 1))
    ev, es = _edges(float(v_lo), float(v_hi), nv), _edges(float(s_lo), float(s_hi), ns)
    flags = np.zeros(nv * ns, np.int64)
    flags[cells] = 1
    a0, a1, b0, b1 = _entered(e0, e1, u0, u1, itinerary)
    if not _covered(flags, ev, es, np.array([a0]), np.array([a1]), np.array([b0]), np.array([b1]))[0]:
        return "entered"
    i, j = cells % nv, cells // nv
    v0, v1, s0, s1 = ev[i], ev[i + 1], es[j], es[j + 1]
    m = cells.size
    one = np.ones((2, m))
    # the corners: "lo" quantities at (v0, s0, e0, u0), "hi" at (v1, s1, e1, u1)
    Th = _div_pos(one[:, :1], _point(np.array([u0])))[1, 0]  # T at u0, upper bound
    Tl = _div_pos(one[:, :1], _point(np.array([u1])))[0, 0]  # T at u1, lower bound
    ratio0 = _div_pos(_add(one[:, :1], _point(np.array([e0]))), _sub(one[:, :1], _point(np.array([e0]))))[0, 0]
    slide_hi = _out(np.stack([Th - v0, Th - v0]))[1]
    slide_hi = _out(np.stack([slide_hi - _out(np.stack([ratio0 * s0, ratio0 * s0]))[0]] * 2))[1]
    if not np.all(slide_hi < 0.0):
        return "slide"

    def at(x, n):
        return np.full(n, x)

    def margin_lo(A1_hi):  # T - v - A s at the upper corner, a lower bound
        t = _out(np.stack([v1 + _out(np.stack([A1_hi * s1] * 2))[1]] * 2))[1]
        return _out(np.stack([Tl - t] * 2))[0]

    def margin_hi(A0_lo):  # at the lower corner, an upper bound
        t = _out(np.stack([v0 + np.maximum(_out(np.stack([A0_lo * s0] * 2))[0], 0.0)] * 2))[0]
        return _out(np.stack([Th - t] * 2))[1]

    boxes = []
    live = np.ones(m, bool)  # cells where impact k may happen (k = 0: all)
    hi_prev = np.full(m, np.inf)
    for k in range(_IMPACT_CAP + 1):
        kk = np.full(1, k, np.int64)
        E_lo, A_lo, A1_lo, B_lo = (c[0, 0] for c in _coefficients(np.array([e0]), kk))
        E_hi, A_hi, A1_hi, B_hi = (c[1, 0] for c in _coefficients(np.array([e1]), kk))
        lo_next = margin_lo(A1_hi)  # T - t_{k+1}, least
        lo_k = margin_lo(A_hi) if k else np.full(m, -np.inf)
        hi_k = hi_prev if k == 0 else margin_hi(A_lo)
        can = live & ~(lo_next >= 0.0)
        if k:
            can &= ~(hi_k < 0.0)
        if can.any():
            c = np.flatnonzero(can)
            # v' = v - T + B_k s, s' = sqrt(2 + (e^k s)^2), increasing: the corners
            a0 = _out(np.stack([_out(np.stack([v0[c] - Th] * 2))[0]
                                + np.maximum(_out(np.stack([B_lo * s0[c]] * 2))[0], 0.0)] * 2))[0]
            a1 = _out(np.stack([_out(np.stack([v1[c] - Tl] * 2))[1] + _out(np.stack([B_hi * s1[c]] * 2))[1]] * 2))[1]
            w_lo = np.maximum(_out(np.stack([E_lo * s0[c]] * 2))[0], 0.0)
            w_hi = _out(np.stack([E_hi * s1[c]] * 2))[1]
            if k:  # v' = w_k - d, d = T - t_k in [max(lo_k, 0), hi_k] and [0, 2 w_k)
                a0 = np.maximum(np.maximum(a0, _out(np.stack([w_lo - hi_k[c]] * 2))[0]), -w_hi)
                a1 = np.minimum(a1, _out(np.stack([w_hi - np.maximum(lo_k[c], 0.0)] * 2))[1])
            else:  # v' = -(T - t_1) - s with T - t_1 < 0 and >= its lower bound
                lo1 = lo_next[c]
                hi1 = margin_hi(np.float64(1.0))[c]
                a0 = np.maximum(a0, _out(np.stack([-np.minimum(hi1, 0.0) - s1[c]] * 2))[0])
                a1 = np.minimum(a1, _out(np.stack([-lo1 - s0[c]] * 2))[1])
            b0 = _sqrt(_add(_mul_pos(np.stack([w_lo, w_lo]), np.stack([w_lo, w_lo])), 2.0 * np.ones((2, c.size))))[0]
            b1 = _sqrt(_add(_mul_pos(np.stack([w_hi, w_hi]), np.stack([w_hi, w_hi])), 2.0 * np.ones((2, c.size))))[1]
            boxes.append((a0, a1, b0, b1))
        # impact k + 1 may happen where T - t_{k+1} is not proven < 0
        hi_prev = margin_hi(A1_lo)
        live = ~(hi_prev < 0.0)
        if not live.any():
            break
    else:
        return "invariant"
    a0, a1, b0, b1 = (np.concatenate([b[q] for b in boxes]) for q in range(4))
    if not np.all(_covered(flags, ev, es, a0, a1, b0, b1)):
        return "invariant"
    return "ok"


_ = _OUTWARD  # the outward directions, shared with verify.py's _out


def verify_certificate_region(cert, verdict):
    """The :class:`verify.Verdict` of a ``no_sliding`` certificate with reason
    ``"trapping"``: its region re-verified for the certificate's own box."""
    r = cert.region
    if r is None or tuple(r.e) != tuple(cert.e) or tuple(r.u) != tuple(cert.u) or \
            tuple(r.itinerary) != tuple(cert.itinerary) or cert.word is not None:
        return verdict(False, "trapping", None, "no_sliding (trapping): the region does not match the certificate")
    try:
        what = verify_region(cert.e[0], cert.e[1], cert.u[0], cert.u[1], cert.max_iter, cert.itinerary,
                             r.grid, r.cells)
    except (ValueError, TypeError) as exc:
        return verdict(False, "trapping", None, f"malformed trapping region: {exc}")
    if what == "ok":
        return verdict(True, None, None, "no_sliding (trapping region): re-verified")
    return verdict(False, "trapping", None, f"no_sliding (trapping region): check '{what}' failed")


def check_atlas_regions(data, arrays, code, trap_code):
    """Re-verify the atlas's ``no_sliding`` boxes with reason ``"trapping"`` from
    its variables ``trap_box, trap_grid, trap_cell_offsets, trap_cells``; writes
    ``trap_code`` into ``code`` where a region fails (or is missing)."""
    status = np.asarray(arrays["status"])
    nos = (np.array([str(s) == "no_sliding" for s in status]) if status.dtype.kind in "USO"
           else status == 1)
    trapped = np.flatnonzero(nos & (np.asarray(data["reason"].values).astype(str) == "trapping"))
    if not trapped.size:
        return
    have = {}
    if "trap_box" in data.variables:
        boxes = np.asarray(data["trap_box"].values, dtype=np.int64)
        grid = np.asarray(data["trap_grid"].values, dtype=np.float64)
        off = np.asarray(data["trap_cell_offsets"].values, dtype=np.int64)
        cells = np.asarray(data["trap_cells"].values, dtype=np.int64)
        have = {int(b): (grid[r], cells[off[r]:off[r + 1]]) for r, b in enumerate(boxes)}
    itin, ioff = np.asarray(arrays["itinerary"], dtype=np.int64), np.asarray(arrays["offsets"], dtype=np.int64)
    for b in trapped:
        ev = have.get(int(b))
        ok = ev is not None and verify_region(
            arrays["e0"][b], arrays["e1"][b], arrays["u0"][b], arrays["u1"][b], arrays["max_iter"],
            itin[ioff[b]:ioff[b + 1]], ev[0], ev[1]) == "ok"
        code[b] = 0 if ok else trap_code
