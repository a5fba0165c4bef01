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
from ._store_read import _take_rows
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


_CELLS_AND_EDGES = "trapping cells and grid edges"


def _region_inputs(e0, e1, u0, u1, max_iter, itinerary, grid, cells):
    """One region's arguments checked and converted: ``(e0, e1, u0, u1,
    itinerary, nv, ns, cells, ev, es)`` (``ev``, ``es`` the cell edges), or
    ``None`` when they are not a box and a grid (the check ``"box"``;
    :func:`verify_regions` makes the same checks on many regions at once).  The
    work counted is the cells and the grid's edges (the checker reads a region
    by its own cells, never the whole grid: a region of a 8192 x 8192 grid costs
    what its cells cost)."""
    e0, e1, u0, u1 = (float(x) for x in (e0, e1, u0, u1))
    itinerary = np.asarray(itinerary, dtype=np.int64).ravel()
    v_lo, v_hi, nv, s_lo, s_hi, ns = grid
    nv, ns = int(nv), int(ns)
    cells = np.asarray(cells, dtype=np.int64).ravel()
    if not (0.0 < e0 <= e1 < 1.0 and 0.0 < u0 <= u1 and nv >= 1 and ns >= 1 and cells.size
            and np.all((cells >= 0) & (cells < nv * ns)) and len(itinerary) <= max_iter
            and np.isfinite([v_lo, v_hi, s_lo, s_hi]).all() and v_lo < v_hi and 0.0 < s_lo < s_hi):
        return None
    check_work(1, len(itinerary), cells.size + nv + ns, what="the trapping region", cells=_CELLS_AND_EDGES)
    ev, es = _edges(float(v_lo), float(v_hi), nv), _edges(float(s_lo), float(s_hi), ns)
    return e0, e1, u0, u1, itinerary, nv, ns, cells, ev, es


def verify_regions(e0, e1, u0, u1, max_iter, itinerary, offsets, grids, cell_off, cells):
    """verify_regions(e0, e1, u0, u1, max_iter, itinerary, offsets, grids, cell_off, cells) -> int array

    :func:`verify_region` on many regions at once: region ``r`` of the box
    ``(e0[r], e1[r], u0[r], u1[r])``, entry ``itinerary[offsets[r]:offsets[r +
    1]]``, grid ``grids[r]`` and cells ``cells[cell_off[r]:cell_off[r + 1]]``.
    Per region the index into :data:`TRAP_CHECKS` of the first failed check (0:
    ``"ok"``).  The same checks and floats as one region at a time: the box
    checks vectorised, the entries re-decided in one ``verify_codes`` call, the
    cells in one compiled loop over the regions (``_check_kernel.regions``).  The
    work limit applies to each region (``verify.MAX_WORK``)."""
    e0, e1, u0, u1 = (np.ascontiguousarray(np.asarray(a, dtype=np.float64).ravel()) for a in (e0, e1, u0, u1))
    n = e0.size
    itinerary = np.ascontiguousarray(np.asarray(itinerary, dtype=np.int64).ravel())
    offsets = np.ascontiguousarray(np.asarray(offsets, dtype=np.int64).ravel())
    grids = np.ascontiguousarray(np.asarray(grids, dtype=np.float64).reshape(-1, 6))
    cell_off = np.ascontiguousarray(np.asarray(cell_off, dtype=np.int64).ravel())
    cells = np.ascontiguousarray(np.asarray(cells, dtype=np.int64).ravel())
    max_iter = int(max_iter)
    if not (e1.size == u0.size == u1.size == n and offsets.size == n + 1 and cell_off.size == n + 1
            and grids.shape[0] == n):
        raise ValueError("verify_regions: one box, grid, offset and cell offset per region (plus one) expected")
    if n and not (offsets[0] == 0 and offsets[-1] == itinerary.size and np.all(np.diff(offsets) >= 0)
                  and cell_off[0] == 0 and cell_off[-1] == cells.size and np.all(np.diff(cell_off) >= 0)):
        raise ValueError("verify_regions: offsets must start at 0, never decrease and end at the arrays' lengths")
    out = np.zeros(n, np.int64)
    if not n:
        return out
    # the check "box": a box and a grid (verify_region's _region_inputs, region by region)
    with np.errstate(invalid="ignore"):
        g = grids
        fin = np.isfinite(g).all(axis=1)
        nv = np.where(fin, g[:, 2], 0).astype(np.int64)
        ns = np.where(fin, g[:, 5], 0).astype(np.int64)
        counts = np.diff(cell_off)
        region_of = np.repeat(np.arange(n), counts)
        size = nv * ns
        cell_ok = np.ones(n, bool)
        np.logical_and.at(cell_ok, region_of, (cells >= 0) & (cells < size[region_of]))
        good = ((0.0 < e0) & (e0 <= e1) & (e1 < 1.0) & (0.0 < u0) & (u0 <= u1) & (nv >= 1) & (ns >= 1)
                & (counts > 0) & cell_ok & (np.diff(offsets) <= max_iter) & fin
                & (g[:, 0] < g[:, 1]) & (0.0 < g[:, 3]) & (g[:, 3] < g[:, 4]))
    out[~good] = TRAP_CHECKS.index("box")
    run = np.flatnonzero(good)
    if not run.size:
        return out
    edges = nv + ns  # the checker reads a region by its cells and its grid's edges, not the grid
    work = 1 + np.diff(offsets)[run] + counts[run] + edges[run]
    r = run[int(np.argmax(work))]
    check_work(1, offsets[r + 1] - offsets[r], counts[r] + edges[r], what="the trapping region",
               cells=_CELLS_AND_EDGES)
    code, _ = verify_codes(e0[run], e1[run], u0[run], u1[run], ["undecided"] * run.size, max_iter,
                           _take_rows(itinerary, offsets[run], np.diff(offsets)[run]),
                           np.concatenate([[0], np.cumsum(np.diff(offsets)[run])]))
    out[run[code != 0]] = TRAP_CHECKS.index("entry")
    run = run[code == 0]
    _ck.regions(e0, e1, u0, u1, itinerary, offsets, grids, cell_off, cells, run, _IMPACT_CAP, out)
    return out


def verify_region(e0, e1, u0, u1, max_iter, itinerary, grid, cells):
    """verify_region(e0, e1, u0, u1, max_iter, itinerary, grid, cells) -> str

    Re-verify that the cells ``cells`` (indices ``j * nv + i``) of ``grid =
    (v_lo, v_hi, nv, s_lo, s_hi, ns)`` form a trapping region of the box that
    the orbit of (1, 0) enters after ``itinerary``: ``"ok"``, or the name of the
    first failed check (:data:`TRAP_CHECKS`; the module's docstring); one region
    of :func:`verify_regions`.
    """
    if _region_inputs(e0, e1, u0, u1, max_iter, itinerary, grid, cells) is None:
        return "box"
    itinerary = np.asarray(itinerary, dtype=np.int64).ravel()
    cells = np.asarray(cells, dtype=np.int64).ravel()
    grid = np.array([float(x) for x in grid], dtype=np.float64)
    code = verify_regions([e0], [e1], [u0], [u1], max_iter, itinerary, [0, itinerary.size], grid[None, :],
                          [0, cells.size], cells)
    return TRAP_CHECKS[int(code[0])]


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
    itin, ioff = np.asarray(arrays["itinerary"], dtype=np.int64), np.asarray(arrays["offsets"], dtype=np.int64)
    # the trapped boxes that have a region, each checked with its own (one batch)
    rows = {int(b): r for r, b in enumerate(np.asarray(data["trap_box"].values, dtype=np.int64))} \
        if "trap_box" in data.variables else {}
    code[trapped] = trap_code
    mine = np.array([rows.get(int(b), -1) for b in trapped], np.int64)
    sel = trapped[mine >= 0]
    if not sel.size:
        return
    r = mine[mine >= 0]
    grid = np.asarray(data["trap_grid"].values, dtype=np.float64).reshape(-1, 6)[r]
    off = np.asarray(data["trap_cell_offsets"].values, dtype=np.int64)
    cells = np.asarray(data["trap_cells"].values, dtype=np.int64)
    counts = off[r + 1] - off[r]
    lengths = ioff[sel + 1] - ioff[sel]
    e = [np.asarray(arrays[k], dtype=np.float64)[sel] for k in ("e0", "e1", "u0", "u1")]
    got = verify_regions(*e, arrays["max_iter"], _take_rows(itin, ioff[sel], lengths),
                         np.concatenate([[0], np.cumsum(lengths)]), grid, np.concatenate([[0], np.cumsum(counts)]),
                         _take_rows(cells, off[r], counts))
    code[sel[got == 0]] = 0
