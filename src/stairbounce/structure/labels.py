"""Labels that say whether rounding chose them: border points and words, proven or not.

A border point of :func:`stairbounce.border_points` is a bracket of two
adjacent floats along one axis whose ends' itineraries (the float map
:func:`stairbounce.model._step` from ``(1, 0)``) agree up to step ``j - 1``
and differ at step ``j`` by one event.  Its label (kind and step) is
*proven* when, at each end taken as a point box (``e0 = e1``, ``u0 = u1``),
every decision of steps ``1..j`` (the common prefix, then that end's own
impact number at step ``j``) is proven by the independent checker's
outward-rounded intervals (``structure/verify.py``): the slide margin's sign,
``T - t_k >= 0`` and ``T - t_{k+1} < 0``.  Then the event's margin has proven
opposite signs at the two ends, and, since along a fixed itinerary every
margin decreases in e and strictly in u (proven in ``verify.py``), a decision
proven at both ends of the bracket (the corners of the degenerate box they
span) holds on the whole segment between them: the prefix is the true
itinerary on the bracket and the event's border crosses it, exactly once.
A label that is not proven was fixed by rounding somewhere: its ``reason``
says which decision, at which end and which step, the intervals could not
take (near a chatter border, often a step tens or hundreds of steps before
the event where an impact falls within rounding of an edge).

A word of :func:`stairbounce.word_table` is *proven* when its point
certificate (status ``word``: every decision of its period, ending with the
slide) is re-verified at one of its pixel centres: then the word is, as a
theorem, the word of the periodic sliding solution at that point.  Distinct
proven words are distinct words of the window, so their number is a proven
lower bound on the number of distinct words (per period: on N(p)).
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from numba import njit

from .. import _validate as _v
from ..model import SLIDING, _constants, _step
from .certificate import STATUSES
from .verify import CHECKS, verify_codes

__all__ = ["prove_labels", "word_proofs"]

_WORD_S, _UNDECIDED_S = STATUSES.index("word"), STATUSES.index("undecided")


@njit(cache=True)
def _impacts_upto(e, u, steps, offsets, flat):
    """The float map's impact numbers of the orbit of ``(1, 0)`` at each point
    ``(e[i], u[i])`` for its first ``steps[i]`` steps (stopping after a slide),
    into ``flat[offsets[i]:]``; returns the steps filled per point."""
    n = e.shape[0]
    filled = np.zeros(n, np.int64)
    for i in range(n):
        T, ratio = _constants(e[i], u[i])
        y, v = 1.0, 0.0
        for m in range(steps[i]):
            y, v, k = _step(y, v, e[i], T, ratio)
            flat[offsets[i] + m] = k
            filled[i] = m + 1
            if k == SLIDING:
                break
    return filled


def _itineraries(e, u, steps):
    """Flat itineraries (``flat``, ``offsets``) of the float map at the points,
    each up to ``steps`` steps or its slide."""
    steps = np.asarray(steps, np.int64)
    off = np.concatenate([[0], np.cumsum(steps)]).astype(np.int64)
    _v.check_memory(f"the itineraries of {e.size} points", 8 * int(off[-1]))
    flat = np.empty(int(off[-1]), np.int64)
    filled = _impacts_upto(np.ascontiguousarray(e, np.float64), np.ascontiguousarray(u, np.float64),
                           steps, off, flat)
    new_off = np.concatenate([[0], np.cumsum(filled)]).astype(np.int64)
    keep = np.repeat(off[:-1] - new_off[:-1], filled) + np.arange(int(new_off[-1]))
    return flat[keep], new_off, filled


def _point_codes(e, u, flat, offsets):
    """The checker's verdict on the point certificates ``(e, u)`` with the
    given itineraries (status ``word`` where one ends with the slide, else
    ``undecided``, whose listed steps are all checked)."""
    n = e.size
    length = np.diff(offsets)
    last = np.full(n, 0, np.int64)
    last[length > 0] = flat[offsets[1:][length > 0] - 1]
    status = np.where(last == SLIDING, _WORD_S, _UNDECIDED_S)
    max_iter = max(int(length.max()) if n else 1, 1)
    return verify_codes(e, e, u, u, status, max_iter, flat, offsets)


# the widenings tried: d = width * _GROWTH**i, i = 0 .. _LEVELS - 1 (up to about
# 1e9 ulps; a label still unproven there is fixed by rounding or by an event
# of another step that close)
_GROWTH, _LEVELS = 4.0, 16
# the non-sliding side of a chatter label: its impact number at the labelled
# step is unbounded near the border (edge borders k <-> k+1 accumulate on the
# chatter border), so only "finite" is claimed there
_FINITE = -2


def _check_ends(e_lo, u_lo, e_hi, u_hi, j, claimed_lo, claimed_hi):
    """Whether the labels are proven at the given ends: both point
    certificates (steps ``1..j``) re-verified, the same first ``j - 1``
    impact numbers, the claimed ones at step ``j``.  Returns ``(ok, reason,
    step, final)``: the failing step where not ok, and whether a wider
    bracket cannot help (a failure before step ``j``, or another border of
    step ``j`` that close; only an undecided decision of step ``j`` itself
    leaves room to widen)."""
    n = e_lo.size
    ok = np.ones(n, bool)
    reason = np.full(n, "", dtype=object)
    first = np.zeros(n, np.int64)
    final = np.zeros(n, bool)
    its = []
    for side, pe, pu, claimed in (("low", e_lo, u_lo, claimed_lo), ("high", e_hi, u_hi, claimed_hi)):
        flat, off, filled = _itineraries(pe, pu, np.maximum(j, 1))
        its.append((flat, off))
        code, step = _point_codes(pe, pu, flat, off)
        last = np.zeros(n, np.int64)
        full = filled == j
        last[full] = flat[off[1:][full] - 1]
        match = (last == claimed) | ((claimed == _FINITE) & (last >= 0))
        for i in np.flatnonzero(~(full & match) & ok):
            ok[i] = False
            if filled[i] < j[i]:
                first[i] = filled[i]
                reason[i] = f"{side} end: the float map's orbit slides at step {filled[i]}, before the label's"
            else:  # a wider bracket holds that border too: stop widening
                first[i] = j[i]
                final[i] = True
                reason[i] = (f"{side} end: another border of step {j[i]} that close (the float map's "
                             f"impact number there changes)")
        for i in np.flatnonzero((code != 0) & ok):
            ok[i] = False
            first[i] = step[i]
            reason[i] = f"{side} end: {CHECKS[code[i]]} undecided at step {step[i]}"
    (fl, ol), (fh, oh) = its
    for i in np.flatnonzero(ok):
        a, b = fl[ol[i]:ol[i + 1] - 1], fh[oh[i]:oh[i + 1] - 1]
        if a.size != b.size or np.any(a != b):
            ok[i] = False
            diff = np.flatnonzero(a[:min(a.size, b.size)] != b[:min(a.size, b.size)])
            first[i] = int(diff[0]) + 1 if diff.size else min(a.size, b.size) + 1
            reason[i] = f"the ends' itineraries differ at step {first[i]}"
    return ok, reason, first, final


def prove_labels(points):
    """prove_labels(points) -> xarray.Dataset

    Which labels of :func:`stairbounce.border_points` are proven and which
    were fixed by rounding (issue 36, item 6).

    At the bracket's two adjacent floats the event's margin is itself within
    rounding, so no interval can sign it there; the bracket is widened by
    ``d`` on each side along its axis (``d = width * 4**i``, i = 0, 1, ...,
    up to about 1e9 ulps, the smallest that works).  The label is proven
    within ``d`` when, at both widened ends taken as point certificates, the
    float map's itinerary up to the labelled step ``j`` is re-decided by the
    independent checker (``stairbounce.structure.verify``, outward-rounded
    float64 intervals), the ends' first ``j - 1`` impact numbers agree and
    those at step ``j`` are the table's ``impacts_low`` and ``impacts_high``
    (for a chatter label, the non-sliding side's only "finite": edge borders
    ``k <-> k+1`` of step ``j`` accumulate on the chatter border, so that
    number is never fixed near it).  Then (theorem): along the widened segment the first ``j - 1`` impact
    numbers are those, everywhere (a decision proven at the two corners of a
    box holds on it, every margin being monotone along a fixed itinerary,
    ``structure/verify.py``), and step ``j`` changes once, by the labelled
    event (its margin has proven opposite signs at the ends and is monotone):
    the exact border crossed within ``d`` of the bracket is of the labelled
    kind at the labelled step.  A label not proven up to the largest ``d``
    was chosen by rounding, or another border (an earlier step's event) lies
    that close; ``reason`` names the decision the intervals could not take
    at that ``d``.

    Parameters
    ----------
    points : xarray.Dataset from :func:`stairbounce.border_points`

    Returns
    -------
    xarray.Dataset
        ``points`` with ``proven`` (bool), ``proof_distance`` (``d``, NaN
        where not proven), ``tried_distance`` (the last ``d`` tried), ``reason`` (``""`` where proven; else which end,
        which check of ``structure.verify.CHECKS`` failed and at which step,
        e.g. ``"high end: slide undecided at step 37"``) and
        ``unproven_step`` (that step, 0 where proven).  The widening stops
        at the first failure before the labelled step: an earlier step's
        border (or a decision within rounding) is that close, and every
        wider bracket holds it too.  Attribute
        ``proven_fraction``.
    """
    if not (isinstance(points, xr.Dataset) and {"e", "u", "width", "axis", "step", "impacts_low",
                                                "impacts_high"} <= set(points.variables)):
        raise ValueError("points must be a Dataset from border_points")
    e = np.asarray(points["e"].values, np.float64)
    u = np.asarray(points["u"].values, np.float64)
    width = np.asarray(points["width"].values, np.float64)
    along_e = np.asarray(points["axis"].values).astype(str) == "e"
    j = np.asarray(points["step"].values, np.int64)
    k_lo = np.asarray(points["impacts_low"].values, np.int64)
    k_hi = np.asarray(points["impacts_high"].values, np.int64)
    chatter = (k_lo == SLIDING) | (k_hi == SLIDING)
    k_lo = np.where(chatter & (k_lo != SLIDING), _FINITE, k_lo)
    k_hi = np.where(chatter & (k_hi != SLIDING), _FINITE, k_hi)
    n = e.size
    proven = np.zeros(n, bool)
    dist = np.full(n, np.nan)
    tried = np.full(n, np.nan)
    reason = np.full(n, "", dtype=object)
    first = np.zeros(n, np.int64)
    todo = np.arange(n)
    for level in range(_LEVELS):
        if not todo.size:
            break
        d = width[todo] * _GROWTH ** level
        x_lo = np.where(along_e[todo], e[todo], u[todo]) - d
        x_hi = np.where(along_e[todo], e[todo], u[todo]) + width[todo] + d
        inside = x_lo > 0
        inside &= np.where(along_e[todo], x_hi < 1.0, True)
        e_lo = np.where(along_e[todo], x_lo, e[todo])
        e_hi = np.where(along_e[todo], x_hi, e[todo])
        u_lo = np.where(along_e[todo], u[todo], x_lo)
        u_hi = np.where(along_e[todo], u[todo], x_hi)
        ok, why, st, final = _check_ends(e_lo, u_lo, e_hi, u_hi, j[todo], k_lo[todo], k_hi[todo])
        why[~inside] = "the widened bracket leaves the plane"
        ok &= inside
        proven[todo[ok]] = True
        dist[todo[ok]] = d[ok]
        tried[todo] = d
        reason[todo[~ok]] = why[~ok]
        first[todo[~ok]] = st[~ok]
        # a failure before the labelled step is a border of an earlier step (or
        # a decision within rounding) that close: a wider bracket holds it too
        todo = todo[~ok & inside & (st >= j[todo]) & ~final]
    first[proven] = 0
    reason[proven] = ""
    dim = ("point",)
    out = points.assign(
        proven=(dim, proven, {"long_name": "label proven by intervals at both ends of the widened bracket"}),
        proof_distance=(dim, dist, {"long_name": "the bracket widened by this on each side (NaN: unproven)"}),
        tried_distance=(dim, tried, {"long_name": "the last widening tried (= proof_distance where proven)"}),
        reason=(dim, reason, {"long_name": "why the label is not proven ('' where it is)"}),
        unproven_step=(dim, first, {"long_name": "the step not proven at the largest widening (0: proven)"}),
    )
    out.attrs["proven_fraction"] = float(proven.mean()) if n else 1.0
    return out


def word_proofs(e, u, ids, rows, per_word=8):
    """word_proofs(e, u, ids, rows, per_word=8) -> (proven, e_proven, u_proven)

    For each word ``w`` (``rows[w]`` its impact numbers over one period,
    ending with the slide) and the points ``(e[i], u[i])`` with
    ``ids[i] == w``: whether its point certificate (status ``word``) is
    re-verified by the independent checker at one of up to ``per_word`` of
    its points (evenly spread over their order), and that point (NaN where
    none).  A proven word is, as a theorem, the word of the periodic sliding
    solution at that point.
    """
    per_word = _v.count("per_word", per_word, 1)
    e = np.asarray(e, np.float64).ravel()
    u = np.asarray(u, np.float64).ravel()
    ids = np.asarray(ids, np.int64).ravel()
    nw = len(rows)
    proven = np.zeros(nw, bool)
    e_p = np.full(nw, np.nan)
    u_p = np.full(nw, np.nan)
    sel = np.flatnonzero(ids >= 0)
    if not nw or not sel.size:
        return proven, e_p, u_p
    order = sel[np.argsort(ids[sel], kind="stable")]
    counts = np.bincount(ids[sel], minlength=nw)
    starts = np.concatenate([[0], np.cumsum(counts)])
    cand = []
    for w in range(nw):
        c = counts[w]
        pick = np.unique(np.linspace(0, c - 1, min(c, per_word)).round().astype(np.int64))
        cand.append(order[starts[w] + pick])
    cand = np.concatenate(cand)
    word = ids[cand]
    lengths = np.array([rows[w].size for w in word], np.int64)
    offsets = np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)
    flat = np.concatenate([rows[w] for w in word]).astype(np.int64)
    max_iter = int(lengths.max())
    status = np.full(cand.size, _WORD_S)
    code, _ = verify_codes(e[cand], e[cand], u[cand], u[cand], status, max_iter, flat, offsets)
    ok = np.flatnonzero(code == 0)
    # the first proven candidate of each word
    w_ok, first = np.unique(word[ok], return_index=True)
    proven[w_ok] = True
    e_p[w_ok] = e[cand[ok[first]]]
    u_p[w_ok] = u[cand[ok[first]]]
    return proven, e_p, u_p
