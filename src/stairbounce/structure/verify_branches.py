"""The checker of class-level proofs (``structure/classes.py``): the branch rule
followed again with this checker's own arithmetic, sharing no code with the
certifier (its kernel, ``structure/classes.py``) nor with ``stairbounce.model``.

A box with status ``sliding`` (its possible words in ``word``, separated by
" | ") or ``no_slide_within`` with reason ``"branches"`` (no itinerary) claims
that every point of the box slides within ``max_iter`` steps, with one of the
words, or that none does.  The claim is re-verified by following every branch
(both sides of each decision that cannot be taken over a branch's enclosures)
from ``(v, s) = (0, sqrt 2)``: intervals ``[lo, hi]`` of Python floats, each
operation rounded to nearest (IEEE-754) and moved one float outward
(``math.nextafter``), so each interval contains the exact value for every
point following the branch.  The step with k impacts ``v' = v - T + B_k s``,
``s'^2 = 2 + e^(2k) s^2`` and the margins ``T - v - C s`` (``C`` = ratio or
``A_j``) are monotone in ``v, s, e, T`` (``B_k, C, e^k >= 0``), so bounds on a
set of points give bounds after the step on it, and the hull of several
branches' bounds is valid for their union (a *merge*: more than ``max_live``
branches after a step, itinerary unknown; the atlas's attribute
``branch_max_live``).  ``sliding`` holds when every branch ends in a slide
within ``max_iter`` steps, none of a merged branch, and the leaves' words are
among the stated ones; ``no_slide_within`` when no branch may slide.

:func:`follow` states the rule in Python; the atlas's rows are checked by its
compiled twin ``_check_kernel.follow_boxes`` (the same operations in the same
order, ``np.nextafter`` for ``math.nextafter``; the leaves' itineraries come back
as a tree and are made words here), which ``tests/test_classes.py`` compares with
:func:`follow` box for box.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from ..symbolic import word_from_impacts
from ._check_kernel import follow_boxes

_INF = math.inf
_CHUNK = 1 << 15  # rows followed by one compiled call
_CAP = 4096  # impacts followed on one step (as the certifier's IMPACT_CAP)


def _d(x):
    return math.nextafter(x, -_INF)


def _u(x):
    return math.nextafter(x, _INF)


def _sqrt_lo(x):
    return max(_d(math.sqrt(max(x, 0.0))), 0.0)


@lru_cache(maxsize=1 << 16)
def _word_text(itinerary):
    """The word's text of a branch that slides after ``itinerary`` (a tuple of impact
    numbers); remembered, since the leaves of neighbouring boxes repeat their words."""
    return word_from_impacts(list(itinerary) + [-1]).format(ascii=True)


def follow(e0, e1, u0, u1, max_iter, max_live, max_leaves, cap=_CAP):
    """follow(e0, e1, u0, u1, max_iter, max_live, max_leaves) -> (claim, words)

    ``claim``: "sliding" (``words``: the set of the leaves' word texts),
    "no_slide_within", or None (neither could be re-verified)."""
    T = (_d(1.0 / u1), _u(1.0 / u0))
    R = (_d(_d(1.0 + e0) / _u(1.0 - e0)), _u(_u(1.0 + e1) / _d(1.0 - e1)))
    r2 = math.sqrt(2.0)
    live = [((0.0, 0.0), (_d(r2), _u(r2)), ())]  # (v, s, itinerary or None when merged)
    words = set()
    for _ in range(max_iter):
        nxt = []
        for v, s, it in live:
            tv = (_d(T[0] - v[1]), _u(T[1] - v[0]))  # T - v
            m = (_d(tv[0] - _u(R[1] * s[1])), _u(tv[1] - max(_d(R[0] * s[0]), 0.0)))
            if not m[1] < 0.0:  # may slide
                if it is None or len(words) >= max_leaves:
                    return None, set()
                words.add(_word_text(it))
                if m[0] >= 0.0:
                    continue
            t = (_d(v[0] + s[0]), _u(v[1] + s[1]))  # t_1 = v + s
            m = (_d(T[0] - t[1]), _u(T[1] - t[0]))
            if not m[0] >= 0.0:  # may fly over: v' = v - T, s'^2 = 2 + s^2
                nxt.append(((_d(v[0] - T[1]), _u(v[1] - T[0])),
                            (_sqrt_lo(_d(2.0 + _d(s[0] * s[0]))), _u(math.sqrt(_u(2.0 + _u(s[1] * s[1]))))),
                            None if it is None else it + (0,)))
            if m[1] < 0.0:
                continue
            w = (max(_d(e0 * s[0]), 0.0), _u(e1 * s[1]))  # w_1 = e s
            k = 1
            while True:
                tn = (_d(t[0] + 2.0 * w[0]), _u(t[1] + 2.0 * w[1]))  # t_{k+1} = t_k + 2 w_k
                m = (_d(T[0] - tn[1]), _u(T[1] - tn[0]))
                if not m[0] >= 0.0:  # may stop after k impacts: v' = w_k + t_k - T, s'^2 = 2 + w_k^2
                    nxt.append(((_d(_d(w[0] + t[0]) - T[1]), _u(_u(w[1] + t[1]) - T[0])),
                                (_sqrt_lo(_d(2.0 + _d(w[0] * w[0]))), _u(math.sqrt(_u(2.0 + _u(w[1] * w[1]))))),
                                None if it is None else it + (k,)))
                if m[1] < 0.0:
                    break
                if k >= cap:
                    return None, set()
                t = tn
                w = (max(_d(e0 * w[0]), 0.0), _u(e1 * w[1]))
                k += 1
        if len(nxt) > max_live:
            nxt = [((min(b[0][0] for b in nxt), max(b[0][1] for b in nxt)),
                    (min(b[1][0] for b in nxt), max(b[1][1] for b in nxt)), None)]
        live = nxt
        if not live:
            return "sliding", words
    return ("no_slide_within", set()) if not words else (None, set())


def _texts(data, name):
    """The text column ``name`` of an atlas: stored as text (.nc, in memory) or as codes
    into a names list (.zarr: ``name_code`` and the attribute ``name_names``); None if absent."""
    # kept as Python strings (objects): a fixed-width copy takes the longest text's width for
    # every row (depth 12 of Fig. 7 with class-level proofs: a 34,733-character word list,
    # 191 GiB for 1.5 million rows)
    if name in data.variables:
        values = np.asarray(data[name].values)
        if values.dtype.kind == "S":
            return np.array([x.decode() for x in values], dtype=object)
        return values.astype(object) if values.dtype.kind == "U" else np.array([str(x) for x in values], dtype=object)
    if f"{name}_code" in data.variables and f"{name}_names" in data.attrs:
        names = np.array([str(x) for x in data.attrs[f"{name}_names"]] or [""], dtype=object)
        codes = np.asarray(data[f"{name}_code"].values)
        if codes.size and (codes.min() < 0 or codes.max() >= names.size):
            raise ValueError(f"{name}_code holds codes outside its {name}_names list")
        return names[codes]
    return None


def check_atlas_branches(data, arrays, code, failed_code):
    """Re-verify the atlas rows proven by the branch rule (status ``sliding``, or
    reason ``"branches"``); set ``code`` to ``failed_code`` where the claim fails,
    to 0 where it holds."""
    from .certificate import STATUSES

    status = np.asarray(arrays["status"])
    if status.dtype.kind in "USO":
        status = np.array([STATUSES.index(str(s)) if str(s) in STATUSES else -1 for s in status])
    reason = _texts(data, "reason")
    sliding = status == STATUSES.index("sliding")
    within = (status == STATUSES.index("no_slide_within")) & (reason == "branches" if reason is not None else False)
    rows = np.flatnonzero(sliding | within)
    if not rows.size:
        return
    max_live = int(data.attrs.get("branch_max_live", 0))
    max_leaves = int(data.attrs.get("branch_max_leaves", 0))
    off = np.asarray(arrays["offsets"])
    words = _texts(data, "word")
    cols = [np.asarray(arrays[k], dtype=np.float64)[rows] for k in ("e0", "e1", "u0", "u1")]
    e0, e1, u0, u1 = cols
    ok = ((off[rows + 1] == off[rows]) & (0.0 <= e0) & (e0 <= e1) & (e1 < 1.0) & (0.0 < u0) & (u0 <= u1)
          & (max_live >= 1) & (max_leaves >= 1))
    code[rows[~ok]] = failed_code
    rows, e0, e1, u0, u1 = rows[ok], e0[ok], e1[ok], u0[ok], u1[ok]
    # follow compiled (_check_kernel.follow_boxes: the same operations as follow above, in
    # the same order; tests/test_classes.py compares the two box for box)
    # in chunks of _CHUNK rows: the leaves' itineraries of a chunk are held at once
    for c in range(0, rows.size, _CHUNK):
        part = slice(c, c + _CHUNK)
        claims, leaf_off, it_off, impacts = follow_boxes(e0[part], e1[part], u0[part], u1[part],
                                                         int(arrays["max_iter"]), max_live, max_leaves, _CAP)
        for n, b in enumerate(rows[part]):
            if sliding[b]:
                got = {_word_text(tuple(impacts[it_off[q]:it_off[q + 1]].tolist()))
                       for q in range(leaf_off[n], leaf_off[n + 1])}
                stated = set(str(words[b]).split(" | ")) if words is not None else set()
                good = claims[n] == 1 and got <= stated and len(got) > 0
            else:
                good = claims[n] == 2
            code[b] = 0 if good else failed_code
