"""The Farey / Stern-Brocot test of the order of words along lines.  Moved verbatim
from ``cascade_families.py``."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..structure.borders import _shrink_secant
from ..model import check_count
from ..symbolic import Word
from .patterns import word_impacts
from .search import _FOUND, _centres, _line_args, _search, _window, _words_at

__all__ = ["FareyTest", "farey_test"]


# --------------------------------------------------------------------------- #
# Farey / Stern-Brocot order along lines                                      #
# --------------------------------------------------------------------------- #

_LABELS = ("letters", "impacts")


def _label(letters, label):
    w = Word(tuple(letters))
    return (len(letters) if label == "letters" else w.impacts), w.period


def _increment(a, b):
    """Whether one of the words is the other with one block inserted beside
    an equal block (consecutive members of a family X^m -> X^(m+1))."""
    if len(a) > len(b):
        a, b = b, a
    d = len(b) - len(a)
    if d == 0:
        return False
    for i in range(len(b) - d + 1):
        if b[:i] + b[i + d:] == a:
            x = b[i:i + d]
            if b[i + d:i + 2 * d] == x or (i >= d and b[i - d:i] == x):
                return True
    return False


def _text(letters):
    return Word(tuple(letters)).format(ascii=True)


@dataclass(frozen=True)
class FareyTest:
    """The Farey / Stern-Brocot test of the words along lines; see :func:`farey_test`.

    ``pairs``: one row per pair of neighbouring words (consecutive distinct
    words of the samples along a line): ``e``, ``u_a``/``u_b`` (the last and
    first sample of each), ``word_a``, ``word_b``, their labels ``p_a, q_a,
    p_b, q_b``, ``det`` = ``|p_a q_b - p_b q_a|`` (1: Farey neighbours),
    ``relation`` (``adjacent``: the float just past a's edge has b; ``mediant``:
    a word with the mediant label ``(p_a + p_b, q_a + q_b)`` lies between
    them; ``other``: a gap without one), ``between`` (that mediant word, or
    the word of smallest period seen in the gap), ``increment`` (one word is
    the other with one more block: consecutive members of a cascade).
    ``counts`` and ``verdict`` summarise them with ``criterion``.
    """

    label: str
    pairs: Any
    counts: dict
    verdict: str
    criterion: str

    def text(self) -> str:
        c = self.counts
        return (f"Farey test ({self.label} per period, steps per period): {c['pairs']} neighbour pairs on "
                f"{c['lines']} line(s): mediant between {c['mediant']}, gap without it {c['other']}, "
                f"adjacent {c['adjacent']}; Farey neighbours (det 1) {c['farey']}, with the mediant "
                f"{c['farey_mediant']}; consecutive members of a cascade {c['increment']}.\n"
                f"verdict: {self.verdict}\ncriterion: {self.criterion}")


def farey_test(e, u, *, label="letters", samples=2000, lines=5, gap_samples=64, max_iter=1000):
    """farey_test(e, u, *, label="letters", samples=2000, lines=5, gap_samples=64, max_iter=1000) -> FareyTest

    Whether the words along lines of the plane follow the Farey (period
    adding) order: between two neighbouring words, a word whose label is the
    mediant of theirs.

    Each word gets the label ``(p, q)``: ``q`` its period in steps and ``p``
    its letters (impacts per period, counting the one where the impacts
    accumulate; ``label="letters"``, the default, additive under
    concatenation, so the concatenation ``AB`` that period adding puts
    between ``A`` and ``B`` carries exactly the mediant) or its finite impacts
    (``label="impacts"``, one less).  On each line (the line given, or
    ``lines`` lines e = const across a window) the words at ``samples``
    evenly spaced points are read in order; for each two consecutive
    distinct words A, B the edges of A and B facing each other are located
    to adjacent floats (exact); if the float past A's edge has B they are
    adjacent (nothing between: no mediant), else the concatenations AB and
    BA are searched for exactly in the gap and ``gap_samples`` points of the
    gap are read: a word there with the mediant label makes the pair
    ``mediant``, else ``other``.

    The verdict (numerical; it could come out either way): "period adding
    (Farey order)" when more than half of the pairs have the mediant
    between them, "period incrementing" when more than half are consecutive
    members of a cascade (one word the other with one more block) and
    fewer than half have the mediant, "mixed" otherwise; and whether every
    pair of Farey neighbours (det 1) with a gap has its mediant between.

    Parameters
    ----------
    e, u : a line (one a number, the other a range) or a window (two ranges)
    label : "letters" or "impacts"
    samples : int >= 3, default 2000
    lines : int >= 1, default 5 (windows only)
    gap_samples : int >= 0, default 64
    max_iter : int >= 1, default 1000
    """
    import pandas as pd

    if label not in _LABELS:
        raise ValueError(f"label must be one of {_LABELS}, got {label!r}")
    samples = check_count("samples", samples, 3, 10**6)
    lines = check_count("lines", lines, 1, 1000)
    gap_samples = check_count("gap_samples", gap_samples, 0, 10**5)
    max_iter = check_count("max_iter", max_iter, 1, 2**31 - 1)
    if isinstance(e, (tuple, list, np.ndarray)) and isinstance(u, (tuple, list, np.ndarray)):
        e_lo, e_hi = _window("e", e)
        u_lo, u_hi = _window("u", u)
        todo = [(float(x), (u_lo, u_hi)) for x in _centres(e_lo, e_hi, lines)]
    else:
        axis, _, lo, hi, fixed = _line_args(e, u)
        if axis == 0:
            raise ValueError("e must be a number here (lines e = const), with u a range; got a range of e")
        todo = [(fixed, (lo, hi))]
    rows = []
    for ev, (lo, hi) in todo:
        xs = _centres(lo, hi, samples)
        ids, letters = _words_at(np.full(samples, ev), xs, max_iter)
        seq = [(int(i), float(x)) for i, x in zip(ids, xs) if i >= 0]
        for (ia, xa), (ib, xb) in zip(seq, seq[1:]):
            if ia == ib:
                continue
            a, b = letters[ia], letters[ib]
            rows.append(_pair(ev, xa, xb, a, b, label, gap_samples, max_iter))
    pairs = pd.DataFrame(rows, columns=["e", "u_a", "u_b", "word_a", "word_b", "p_a", "q_a", "p_b", "q_b",
                                        "det", "relation", "between", "increment"])
    n = len(pairs)
    rel = pairs.relation.value_counts() if n else {}
    farey = pairs[(pairs.det == 1) & (pairs.relation != "adjacent")] if n else pairs
    counts = {"lines": len(todo), "pairs": n, "mediant": int(rel.get("mediant", 0)),
              "other": int(rel.get("other", 0)), "adjacent": int(rel.get("adjacent", 0)),
              "farey": len(farey), "farey_mediant": int((farey.relation == "mediant").sum()) if n else 0,
              "increment": int(pairs.increment.sum()) if n else 0}
    if n == 0:
        verdict = "no neighbour pairs (no two distinct words on the lines)"
    elif counts["mediant"] * 2 > n:
        verdict = "period adding (Farey order)"
    elif counts["increment"] * 2 > n:
        verdict = "period incrementing"
    else:
        verdict = "mixed"
    if counts["farey"]:
        verdict += ("; every Farey pair with a gap has its mediant between" if
                    counts["farey_mediant"] == counts["farey"] else
                    f"; the Farey order fails for {counts['farey'] - counts['farey_mediant']} of "
                    f"{counts['farey']} Farey pairs with a gap")
    criterion = ("period adding if more than half of the neighbour pairs have a word with the mediant label "
                 "between them; period incrementing if more than half are consecutive members of a cascade "
                 "and fewer than half have the mediant; mixed otherwise (neighbours: consecutive distinct words "
                 f"of {samples} samples per line; adjacency and the concatenations decided exactly)")
    return FareyTest(label, pairs, counts, verdict, criterion)


def _pair(ev, xa, xb, a, b, label, gap_samples, max_iter):
    """One neighbour pair's row (see FareyTest)."""
    pa, qa = _label(a, label)
    pb, qb = _label(b, label)
    ra, rb = word_impacts(Word(a)), word_impacts(Word(b))
    # the edges facing each other, to adjacent floats
    _, xa_out, _, _ = _shrink_secant(xa, xb, ev, 1, ra, ra.shape[0])
    _, xb_out, _, _ = _shrink_secant(xb, xa, ev, 1, rb, rb.shape[0])
    xa_out, xb_out = float(xa_out), float(xb_out)
    row = {"e": ev, "u_a": xa, "u_b": xb, "word_a": _text(a), "word_b": _text(b), "p_a": pa, "q_a": qa,
           "p_b": pb, "q_b": qb, "det": abs(pa * qb - pb * qa), "increment": _increment(a, b)}
    if xa_out > xb_out:  # the float past a's edge is b's (and the reverse): nothing between
        row.update(relation="adjacent", between="")
        return row
    lo, hi = xa_out, xb_out
    med = (pa + pb, qa + qb)
    for cat in (a + b, b + a):
        ref = word_impacts(Word(cat))
        if _search(lo, hi, ev, 1, ref, ref.shape[0])[0] == _FOUND:
            row.update(relation="mediant", between=_text(cat))
            return row
    best = None
    if gap_samples:
        xs = np.linspace(lo, hi, gap_samples)
        ids, letters = _words_at(np.full(gap_samples, ev), xs, max_iter)
        for i in np.unique(ids[ids >= 0]):
            w = letters[i]
            if _label(w, label) == med:
                row.update(relation="mediant", between=_text(w))
                return row
            if best is None or Word(w).period < Word(best).period:
                best = w
    row.update(relation="other", between=_text(best) if best is not None else "")
    return row


