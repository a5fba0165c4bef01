"""The independent checker of certificates: re-verifies what a certificate claims.

``verify_arrays(e0, e1, u0, u1, status, max_iter, itinerary, offsets)`` checks
N certificates in the array form of ``structure/certificate.py`` at once, with
its own rigorous arithmetic (float64 intervals, outward rounded; the step loops
compiled in ``structure/_check_kernel.py``, numba without fastmath), and
shares no code with the certifier's kernel nor with ``stairbounce.model``; only
``stairbounce.symbolic`` is used, to spell a word from an itinerary.

What is checked, per box (the first failure is the box's verdict):

* ``box``: ``0 <= e0 <= e1 < 1`` and ``1e-150 <= u0 <= u1 <= 1e150``, finite (an
  undecided box with no listed step, which claims nothing, may touch e = 1 and
  u = 0: an atlas's boxes on its window's edges).  e0 = 0 is a box like the others:
  the coefficients below increase with e on [0, 1), so the bounds at e0 = 0 hold
  (e = 0, the perfectly plastic impact, has ``ratio = 1``, ``e^k = 0`` for k >= 1);
* ``status``: a known status code;
* ``itinerary``: impact numbers >= -1, the slide (-1) only as the last entry;
  ``word``: ends with -1 and has at most ``max_iter`` steps;
  ``no_slide_within``: exactly ``max_iter`` steps, none -1; the others at most
  ``max_iter`` steps, none -1;
* ``corollary``: a ``no_sliding`` box satisfies Corollary 2.1 over the whole
  box, ``8 e0 u0^2 > (1 - e0)^2`` (that is ``u0 > (1-e0)/(2 sqrt(2 e0))``,
  the bound decreasing in e), enclosed;
* ``branches``: a ``sliding`` box, or a ``no_slide_within`` box with reason
  ``"branches"`` (atlas rows), is re-verified by following every branch of its
  undecided decisions (``structure/verify_branches.py``);
* ``trapping``: a ``no_sliding`` box with reason ``"trapping"`` (certificate or
  atlas row) is re-verified from its trapping region by
  ``structure/verify_trapping.py`` (numpy, this module's arithmetic) instead of
  Corollary 2.1;
* along the itinerary, from ``(y, v) = (1, 0)``, every decision of every
  listed step proven with the sign the itinerary says: the slide margin
  ``T - (v + ratio s)`` (Prop. 2.1, eq. (2.4)) proven >= 0 on the sliding
  step and < 0 on the others (``slide``); on a step with k >= 1 impacts the
  margin ``T - t_k`` proven >= 0 (``impact``), and ``T - t_{k+1}`` proven < 0
  (``no impact``).  The impact times increase (``t_{j+1} - t_j = 2 e^j s > 0``,
  eq. (2.2)), so ``T - t_k >= 0`` proves the decisions of impacts 1..k too.

The formulas (eq. (2.2), Prop. 2.3; ``s = sqrt(v^2 + 2y)``, ``T = 1/u``):
``t_j = v + A_j s`` with ``A_j = (1 + e - 2 e^j) / (1 - e)``; after k impacts
(k = 0: the fly-over) ``v' = v - T + B_k s`` with
``B_k = (1+e)(1 - e^k)/(1 - e)`` (that is ``v_k - (T - t_k)``, ``v_k = e^k s``)
and ``s'^2 = 2 + (e^k s)^2`` (energy: ``v'^2 + 2y' = v_k^2 + 2`` for Prop.
2.3's ``y' = 1 - d^2/2 + v_k d``, and ``s^2 + 2`` after a fly-over).  The
coefficients ``ratio = (1+e)/(1-e)``, ``A_j`` (a sum ``1 + 2e + ... + 2e^{j-1}``),
``B_k`` and ``e^k`` increase with e on [0, 1): over ``[e0, e1]`` each lies
between its values at e0 and e1, which are enclosed at those two floats.

Monotonicity (proven; why these enclosures are the exact ranges up to
rounding).  Along a fixed itinerary ``s_{n+1}^2 = 2 + e^{2k} s_n^2`` and
``v_{n+1} = v_n - 1/u + B_k(e) s_n`` from ``v = 0``, ``s = sqrt 2``, with
``ratio``, ``A_j``, ``B_k``, ``e^k`` non-negative and increasing in e.  By
induction ``s_n`` increases with e (and does not depend on u) and ``v_n``
increases with e and with u; so every margin ``T - v - C s`` (``C`` = ratio or
``A_j``) decreases with e and, strictly, with u.  Over the box a margin's least
value is at the corner ``(e1, u1)`` and its largest at ``(e0, u0)``, and every
interval below is computed from the bounds at those two corners: it is the
exact range up to rounding, and no other enclosure (a mean-value form, say)
can decide more.  A claim holds on a box exactly when it holds at its two
corners (tests/test_verify.py checks the checker against this), and each
border arc along a fixed itinerary (the zero set of one margin) is the graph
of a non-increasing function ``u(e)``.

Rigour.  Every quantity is an interval ``[lo, hi]`` of float64 containing the
exact real value for every (e, u) of the box.  The box's bounds are floats, so
``e`` and ``u`` are exact intervals.  Each bound is computed by one IEEE-754
operation (+, -, *, /, sqrt: correctly rounded to nearest in numpy, which
neither contracts to fused multiply-adds nor uses another rounding mode) and
then moved one float outward with ``np.nextafter`` (down for a lower bound, up
for an upper): the exact result of the operation on the float operands lies
within half an ulp of the rounded one, hence between the rounded value's two
neighbours.  Sums and differences take the matching bounds
(``[a - b] = [a_lo - b_hi, a_hi - b_lo]``), products of non-negative
intervals the bound products, doubling is exact, quotients by positive intervals the
least and largest of the four bound quotients, and ``sqrt`` (increasing) the
roots of the bounds.  By induction over the operations every interval contains
the exact value of its expression at every point of the box, and an exact value
known to be >= 0 keeps its lower bound clipped at 0.  A decision accepted
(``lo >= 0`` or ``hi < 0``) therefore holds at every point of the box.  The
first step starts from the exact ``v = 0`` and ``s = sqrt 2`` (enclosed);
every later state is the map applied along the decided itinerary, so the
formulas of the step with k impacts apply to every point of the box.
"""

from __future__ import annotations

import numpy as np

from .. import _validate as _v
from . import _check_kernel as _ck
from .certificate import STATUSES

__all__ = ["CHECKS", "MAX_WORK", "check_work", "verify_arrays", "verify_codes"]

CHECKS = ("ok", "box", "status", "itinerary", "corollary", "slide", "impact", "no impact", "word", "trapping",
          "branches")
"""Names of the checks; ``verify_codes`` returns indices into this tuple (0: accepted)."""

MAX_WORK = 5 * 10**8
"""The checker's work limit: boxes plus itinerary entries (steps) plus trapping
cells of one call.  The compiled checker re-decides about 10^7 steps a second
on one core (benchmarks/README.md), so the limit is about a minute of work and
4 GB of itinerary; beyond it ``verify``, ``verify_codes`` and ``verify_file``
refuse with a ValueError naming the size, before reading a file's arrays
(``stairbounce certify --verify``: one line, exit 2).  A streamed atlas's store
(``certify_to_zarr``) is checked a tile at a time, and the limit holds for each
tile, as its memory does: a store of any size can be checked.  Raise it here (it
is read at each call) to check more in one call."""

_OK, _BOX, _STATUS, _ITIN, _COR, _SLIDE, _IMPACT, _NOIMPACT, _WORD, _TRAP, _BRANCHES = range(len(CHECKS))
_SLIDING_S = STATUSES.index("sliding")
_WORD_S, _NOSLIDING_S, _WITHIN_S, _UNDECIDED_S = (STATUSES.index(s) for s in
                                                   ("word", "no_sliding", "no_slide_within", "undecided"))
# an interval is a (2, n) array: row 0 the lower bounds, row 1 the upper ones;
# one nextafter call moves both rows outward
_OUTWARD = np.array([[-np.inf], [np.inf]])


def _out(x):
    """Each lower bound one float down, each upper bound one float up."""
    return np.nextafter(x, _OUTWARD)


def _point(x):
    """The exact interval ``[x, x]`` of floats ``x``."""
    return np.stack([x, x])


def _add(a, b):
    return _out(a + b)


def _sub(a, b):
    return _out(a - b[::-1])  # [a_lo - b_hi, a_hi - b_lo]


def _mul_pos(a, b):
    """Product of two non-negative intervals (bounds clipped at 0)."""
    return np.maximum(_out(a * b), 0.0)


def _div_pos(a, b):
    """``a / b`` for ``b`` positive, ``a`` of any sign."""
    q, r = a / b, a / b[::-1]  # [a_lo/b_lo, a_hi/b_hi], [a_lo/b_hi, a_hi/b_lo]
    return _out(np.stack([np.minimum(q[0], r[0]), np.maximum(q[1], r[1])]))


def _over_box(at_e0, at_e1):
    """A function increasing in e over [e0, e1]: its lower bound at e0, upper at e1."""
    return np.stack([at_e0[0], at_e1[1]])


def _sqrt(a):
    """Root of a non-negative interval."""
    return np.maximum(_out(np.sqrt(np.maximum(a, 0.0))), 0.0)


def _pow_point(e, k):
    """``e^k`` enclosed, for floats ``0 < e < 1`` and ints ``k >= 0`` (arrays),
    by binary powering with each product rounded outward."""
    result = np.ones((2, len(e)))
    base = _point(e)
    k = k.copy()
    while True:
        odd = (k & 1).astype(bool)
        if odd.any():
            result = np.where(odd, _mul_pos(result, base), result)
        k >>= 1
        if not k.any():
            return result
        base = _mul_pos(base, base)


def _size(a):
    """Entries of an array-like, without converting it (0 for a scalar)."""
    if hasattr(a, "size") and not callable(a.size):
        return int(a.size)
    return len(a) if hasattr(a, "__len__") else 0


class WorkLimitError(ValueError):
    """The checking asked for is beyond :data:`MAX_WORK`: refused, not judged
    (a claim too large to check is neither verified nor rejected)."""


def check_work(n_boxes, n_entries, n_cells=0, what="the certificates", cells="trapping cells"):
    """check_work(n_boxes, n_entries, n_cells=0, what="the certificates", cells="trapping cells") -> int

    The checker's work estimate ``n_boxes + n_entries + n_cells`` (boxes,
    itinerary entries, trapping cells; ``cells`` names the last in the message),
    refused beyond :data:`MAX_WORK`."""
    work = int(n_boxes) + int(n_entries) + int(n_cells)
    if work > MAX_WORK:
        raise WorkLimitError(
            f"{what}: {int(n_boxes):,} boxes, {int(n_entries):,} itinerary entries (steps)"
            + (f" and {int(n_cells):,} {cells}" if n_cells else "")
            + f" are {work:,} units of checking work, more than the checker's limit of {MAX_WORK:,} "
            "(stairbounce.structure.verify.MAX_WORK, about a minute): split the atlas or raise the limit")
    return work


def _structure(e0, e1, u0, u1, status, max_iter, itinerary, offsets):
    """The checks that need no arithmetic; returns (code, step) arrays."""
    n = len(e0)
    code = np.zeros(n, dtype=np.int8)
    step = np.zeros(n, dtype=np.int64)
    with np.errstate(invalid="ignore"):
        bad_box = ~(np.isfinite(e0) & np.isfinite(e1) & np.isfinite(u0) & np.isfinite(u1)
                    & (e0 >= 0.0) & (e0 <= e1) & (e1 < 1.0) & (u0 >= _v.U_MIN) & (u0 <= u1) & (u1 <= _v.U_MAX))
        # an undecided box with no listed step claims nothing: an atlas's boxes on
        # its window's edges e = 1, u = 0 (reason "range"; e = 0 too for the forms other than
        # the corners) are such boxes
        edge_box = ((status == _UNDECIDED_S) & (np.diff(offsets) == 0) & (e0 >= 0.0) & (e0 <= e1)
                    & (e1 <= 1.0) & (u0 >= 0.0) & (u0 <= u1) & (u1 <= _v.U_MAX))
    code[bad_box & ~edge_box] = _BOX
    bad_status = (status < 0) | (status >= len(STATUSES))
    code[(code == 0) & bad_status] = _STATUS
    length = np.diff(offsets)
    last = np.zeros(n, dtype=np.int64)
    last[length > 0] = itinerary[offsets[1:][length > 0] - 1]
    # entries < -1 anywhere, or -1 before the last entry of its box
    box_of = np.repeat(np.arange(n), length)
    is_last = np.zeros(len(itinerary), dtype=bool)
    is_last[offsets[1:][length > 0] - 1] = True
    bad_entry = (itinerary < -1) | ((itinerary == -1) & ~is_last)
    bad_itin = np.zeros(n, dtype=bool)
    bad_itin[box_of[bad_entry]] = True
    ends_slide = (length > 0) & (last == -1)
    bad_itin |= length > max_iter
    bad_itin |= (status == _WORD_S) & ~ends_slide
    bad_itin |= (status == _WITHIN_S) & ((length != max_iter) | ends_slide)
    bad_itin |= ((status == _NOSLIDING_S) | (status == _UNDECIDED_S)) & ends_slide
    # a class-level proof (status sliding) has no single itinerary: only the branch
    # checker (verify_branches.py) accepts it, from an atlas
    bad_itin |= status == _SLIDING_S
    code[(code == 0) & bad_itin] = _ITIN
    return code, step


def _corollary(e0, u0):
    """Where Corollary 2.1 is proven over the box: ``8 e0 u0^2 > (1 - e0)^2``."""
    u = _point(u0)
    lhs = _mul_pos(_mul_pos(_point(8.0 * e0), u), u)  # 8 e0 exact
    one_m = _sub(np.ones((2, len(e0))), _point(e0))
    return lhs[0] > _mul_pos(one_m, one_m)[1]


def verify_codes(e0, e1, u0, u1, status, max_iter, itinerary, offsets):
    """verify_codes(e0, e1, u0, u1, status, max_iter, itinerary, offsets) -> (code, step)

    The verdict of every box of the array form: ``code`` (int8, index into
    :data:`CHECKS`, 0 when the certificate's claim is re-verified) and the
    1-based ``step`` of the failed decision (0 when the failure is not a
    step's).  The checks and the argument for their rigour are in the module's
    docstring.
    """
    check_work(_size(e0), _size(itinerary))
    e0, e1, u0, u1 = (np.ascontiguousarray(np.asarray(a, dtype=np.float64).ravel()) for a in (e0, e1, u0, u1))
    n = len(e0)
    status = np.asarray(status).ravel()
    if status.dtype.kind in "USO":
        names = {s: i for i, s in enumerate(STATUSES)}
        status = np.array([names.get(str(s), -1) for s in status], dtype=np.int64)
    status = status.astype(np.int64)
    itinerary = np.ascontiguousarray(np.asarray(itinerary, dtype=np.int64).ravel())
    offsets = np.ascontiguousarray(np.asarray(offsets, dtype=np.int64).ravel())
    max_iter = _v.count("max_iter", max_iter, 1)
    if not (len(e1) == len(u0) == len(u1) == len(status) == n):
        raise ValueError(f"e0, e1, u0, u1 and status must have one entry per box, got lengths "
                         f"{[len(a) for a in (e0, e1, u0, u1, status)]}")
    if (len(offsets) != n + 1 or offsets[0] != 0 or offsets[-1] != len(itinerary)
            or np.any(np.diff(offsets) < 0)):
        raise ValueError("offsets must have one entry per box plus one, start at 0, never decrease and "
                         f"end at len(itinerary) = {len(itinerary)}")
    code, step = _structure(e0, e1, u0, u1, status, max_iter, itinerary, offsets)

    nos = (code == 0) & (status == _NOSLIDING_S)
    code[nos & ~_corollary(e0, u0)] = _COR

    # the dynamics, along each itinerary: compiled, one box after another, its
    # steps in order (structure/_check_kernel.py: this module's arithmetic)
    run = np.flatnonzero((code == 0) & (np.diff(offsets) > 0))
    _ck.follow(e0, e1, u0, u1, itinerary, offsets, run, code, step, _SLIDE, _IMPACT, _NOIMPACT)
    return code, step


def verify_arrays(e0, e1, u0, u1, status, max_iter, itinerary, offsets):
    """verify_arrays(e0, e1, u0, u1, status, max_iter, itinerary, offsets) -> bool array

    Whether each box's certificate (the array form of
    ``structure/certificate.py``) is re-verified: its itinerary re-decided
    step by step with outward-rounded float64 intervals, vectorised across the
    boxes (see the module's docstring for the checks and the rigour).  A
    ``True`` is a proof of the box's claim; a ``False`` says the claim could
    not be re-verified (``verify_codes`` says which check failed).
    """
    return verify_codes(e0, e1, u0, u1, status, max_iter, itinerary, offsets)[0] == _OK
