"""The independent checker of trapping regions (issue 36, item 7).

Re-verifies a ``no_sliding`` certificate proven by a trapping region
(``structure/trapping.py``) from the box, ``max_iter``, the entry itinerary
and the region (its grid and cells) alone, with float64 intervals rounded
outward, compiled in ``structure/_check_kernel.py`` (the arithmetic of
``structure/verify.py``, whose rigour argument applies word for word); it shares no code with the certifier's
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

from . import _check_kernel as _ck
from .verify import WorkLimitError, check_work, verify_codes

__all__ = ["TRAP_CHECKS", "verify_region"]

TRAP_CHECKS = ("ok", "box", "entry", "entered", "slide", "invariant")
"""Names of the trapping checks (``verify_region`` returns one)."""

_IMPACT_CAP = 4096


def _edges(lo, hi, n):
    i = np.arange(n + 1, dtype=np.float64)
    e = lo + (hi - lo) * (i * (1.0 / n))
    e[n] = hi
    return e


def _region_inputs(e0, e1, u0, u1, max_iter, itinerary, grid, cells):
    """The region's arguments checked and converted: ``(e0, e1, u0, u1,
    itinerary, nv, ns, cells, ev, es, flags)`` (``ev``, ``es`` the cell edges,
    ``flags`` 1 on the region's cells), or ``None`` when they are not a box and
    a grid (the check ``"box"``)."""
    e0, e1, u0, u1 = (float(x) for x in (e0, e1, u0, u1))
    itinerary = np.asarray(itinerary, dtype=np.int64).ravel()
    v_lo, v_hi, nv, s_lo, s_hi, ns = grid
    nv, ns = int(nv), int(ns)
    cells = np.asarray(cells, dtype=np.int64).ravel()
    if not (0.0 < e0 <= e1 < 1.0 and 0.0 < u0 <= u1 and nv >= 1 and ns >= 1 and cells.size
            and np.all((cells >= 0) & (cells < nv * ns)) and len(itinerary) <= max_iter
            and np.isfinite([v_lo, v_hi, s_lo, s_hi]).all() and v_lo < v_hi and 0.0 < s_lo < s_hi):
        return None
    check_work(1, len(itinerary), cells.size + nv * ns, what="the trapping region")
    ev, es = _edges(float(v_lo), float(v_hi), nv), _edges(float(s_lo), float(s_hi), ns)
    flags = np.zeros(nv * ns, np.int64)
    flags[cells] = 1
    return e0, e1, u0, u1, itinerary, nv, ns, cells, ev, es, flags


def verify_region(e0, e1, u0, u1, max_iter, itinerary, grid, cells):
    """verify_region(e0, e1, u0, u1, max_iter, itinerary, grid, cells) -> str

    Re-verify that the cells ``cells`` (indices ``j * nv + i``) of ``grid =
    (v_lo, v_hi, nv, s_lo, s_hi, ns)`` form a trapping region of the box that
    the orbit of (1, 0) enters after ``itinerary``: ``"ok"``, or the name of the
    first failed check (:data:`TRAP_CHECKS`; the module's docstring).
    """
    args = _region_inputs(e0, e1, u0, u1, max_iter, itinerary, grid, cells)
    if args is None:
        return "box"
    e0, e1, u0, u1, itinerary, nv, ns, cells, ev, es, flags = args
    code, _ = verify_codes([e0], [e1], [u0], [u1], ["undecided"], max_iter, itinerary, [0, len(itinerary)])
    if code[0] != 0:
        return "entry"
    # a 2-D prefix sum of the flagged cells: P[j, i] counts those below row j, left of column i
    P = np.zeros((ns + 1, nv + 1), np.int64)
    P[1:, 1:] = np.cumsum(np.cumsum(flags.reshape(ns, nv), axis=0), axis=1)
    a0, a1, b0, b1 = _ck.entered(e0, e1, u0, u1, itinerary)
    if not _ck.covered(P, ev, es, a0, a1, b0, b1):
        return "entered"
    i, j = cells % nv, cells // nv
    # per cell the corners (v0, s0, e0, u0) and (v1, s1, e1, u1), per impact
    # number k the branch's image (structure/_check_kernel.py, region_check)
    what = _ck.region_check(e0, e1, u0, u1, ev[i], ev[i + 1], es[j], es[j + 1], P, ev, es, _IMPACT_CAP)
    return ("ok", "slide", "invariant")[what]


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
    except WorkLimitError:
        raise  # too large to check: refused by name, not a verdict
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
