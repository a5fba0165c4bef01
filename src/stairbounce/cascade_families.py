"""How the cascades are organised (issue 39, items 3-5): the families of a
window at two levels of nesting, the Farey / Stern-Brocot test of the order of
words along lines, the number of members of a family against e, and the
organising centres (the corners where most border arcs meet, beside the
accumulation curves of the cascades).

Everything here is built on :mod:`stairbounce.cascades`: members and edges
are located exactly (to rounding) on lines of the plane by the lexicographic
order of itineraries; what is sampled (the words a scan sees, the points of a
line between two words) only proposes candidates, and the module says where a
statement depends on it.  Laws and verdicts are numerical, each with its
criterion.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .structure.borders import _shrink_secant
from .structure.words import _word_groups
from .cascades import (
    _FOUND,
    _Pattern,
    _candidates,
    _line_args,
    _parse_pattern,
    _pattern_text,
    _search,
    cascade,
    cascade_law,
    word_impacts,
)
from .model import check_count, check_e, check_u
from .symbolic import Word, word_from_impacts

__all__ = ["FareyTest", "farey_test", "member_count", "organising_centres"]


# --------------------------------------------------------------------------- #
# Words at points                                                             #
# --------------------------------------------------------------------------- #


def _words_at(es, us, max_iter):
    """The word of the orbit of (1, 0) at each point: ``(ids, letters)``,
    ``letters[ids[i]]`` the letters of point i's word (id -1: no slide within
    ``max_iter``), as :func:`stairbounce.word_table` groups them."""
    from .plane import scan_points

    es = np.ascontiguousarray(es, np.float64)
    us = np.ascontiguousarray(us, np.float64)
    ds = scan_points(es, us, max_iter=max_iter)
    period = np.where(ds.status.values == 0, ds.period.values, 0).astype(np.int64)
    ids, rows = _word_groups(es, us, period)
    return ids, [word_from_impacts(r).letters for r in rows]


def _centres(lo, hi, n):
    return lo + (np.arange(n) + 0.5) * (hi - lo) / n


def _window(name, rng):
    if not isinstance(rng, (tuple, list, np.ndarray)) or len(rng) != 2:
        raise ValueError(f"{name} must be a range (lo, hi) of two numbers, got {rng!r}")
    check = check_e if name == "e" else check_u
    lo, hi = check(rng[0]), check(rng[1])
    if not lo < hi:
        raise ValueError(f"{name} must be a range (lo, hi) with lo < hi, got {rng!r}")
    return lo, hi


# --------------------------------------------------------------------------- #
# Families of a window, two levels                                           #
# --------------------------------------------------------------------------- #


def _runs(letters):
    """Run-length code ``[(letter, count), ...]``."""
    out = []
    for a in letters:
        if out and out[-1][0] == a:
            out[-1][1] += 1
        else:
            out.append([a, 1])
    return [tuple(r) for r in out]


def _free_count_text(runs, var_runs, base):
    """Letters of runs with the counts of ``var_runs`` written as n + offset."""
    parts = []
    for i, (a, c) in enumerate(runs):
        if i in var_runs:
            off = c - base
            exp = "n" if off == 0 else f"(n{off:+d})"
            parts.append(f"{a}^{exp}")
        else:
            parts.extend([str(a)] * c)
    return parts


def _level2(fams):
    """Families of families: level-1 patterns ``(P, X, S)`` whose run-length
    codes have the same letters and whose counts differ by one free ``n`` on
    a fixed set of runs.  Returns ``[(text, [(n, index into fams), ...]), ...]``
    with at least 3 distinct n."""
    groups: dict = {}
    for idx, (p, x, s) in enumerate(fams):
        parts = [_runs(p), _runs(x), _runs(s)]
        flat = [c for part in parts for (_, c) in part]
        shape = tuple(tuple(a for a, _ in part) for part in parts)
        groups.setdefault(shape, []).append((idx, parts, flat))
    out, used = [], set()
    for shape, mem in groups.items():
        if len(mem) < 3:
            continue
        size = len(mem[0][2])
        # every mask of runs that vary together (the one free count n), from pairwise differences
        masks = set()
        for i in range(len(mem)):
            for j in range(i + 1, len(mem)):
                d = [b - a for a, b in zip(mem[i][2], mem[j][2])]
                nz = [t for t in range(size) if d[t] != 0]
                if nz and len({d[t] for t in nz}) == 1:
                    masks.add(tuple(nz))
        for mask in sorted(masks, key=len):
            fam: dict = {}
            for idx, parts, flat in mem:
                n = flat[mask[0]]
                key = (tuple(flat[t] for t in range(size) if t not in mask),
                       tuple(flat[t] - n for t in mask))
                fam.setdefault(key, {}).setdefault(n, idx)
            for key, by_n in fam.items():
                if len(by_n) < 3 or frozenset(by_n.values()) in used:
                    continue
                used.add(frozenset(by_n.values()))
                n0 = min(by_n)
                idx0 = by_n[n0]
                parts = [_runs(t) for t in fams[idx0]]
                # the free runs' texts, offsets relative to n
                sizes = [len(pt) for pt in parts]
                texts, at = [], 0
                for pt, sz in zip(parts, sizes):
                    var = {t - at for t in mask if at <= t < at + sz}
                    texts.append(_free_count_text(pt, var, n0))
                    at += sz
                block = texts[1]
                body = (f"{block[0]}^k" if len(block) == 1 and "^" not in block[0]
                        else "(" + ", ".join(block) + ")^k")
                text = "(" + ", ".join([*texts[0], body, *texts[2], "0^inf"]) + ")"
                out.append((text, sorted(by_n.items()), _member_maker(parts, set(mask), n0)))
    return out


def _member_maker(parts, mask, n0):
    """The level-1 pattern ``(P, X, S)`` of a family of families at any n: the
    runs in ``mask`` (flat indices) get count ``n + (c - n0)``; None where a
    count would be below 1."""

    def make(n):
        out, at = [], 0
        for pt in parts:
            letters = []
            for a, c in pt:
                c2 = n + (c - n0) if at in mask else c
                if c2 < 1:
                    return None
                letters.extend([a] * c2)
                at += 1
            out.append(tuple(letters))
        return tuple(out)

    return make


def window_families(e, u, *, resolution=128, lines=3, min_members=4, block_max=4, k_max=100, max_iter=1000,
                    n_max=8):
    """The families of a window, as :func:`stairbounce.cascades` with two ranges
    lists them (see there); here is the work."""
    import pandas as pd

    e_lo, e_hi = _window("e", e)
    u_lo, u_hi = _window("u", u)
    resolution = check_count("resolution", resolution, 8, 4096)
    lines = check_count("lines", lines, 1, 64)
    min_members = check_count("min_members", min_members, 2)
    block_max = check_count("block_max", block_max, 1, 64)
    es, us = _centres(e_lo, e_hi, resolution), _centres(u_lo, u_hi, resolution)
    E, U = np.meshgrid(es, us)
    ids, letters = _words_at(E.ravel(), U.ravel(), max_iter)
    cols = ids.reshape(U.shape)  # (u, e)
    # where (which e columns) each word was seen
    seen_cols: dict = {}
    for w, row in enumerate(letters):
        seen_cols[row] = np.flatnonzero((cols == w).any(axis=0))
    seen = set(letters)
    rows, done, fams, cascs = [], set(), [], []
    for n_seen, p, x, s in _candidates(seen, min_members, block_max):
        pat = _Pattern("", "k", p, x, s)
        text = _pattern_text(p, x, s)
        # the e columns where members were seen, by how many members each shows
        count = np.zeros(resolution, int)
        for k in range(0, 2 + max(len(w) for w in seen) // len(x)):
            lt = pat.letters(k)
            if lt in seen_cols:
                count[seen_cols[lt]] += 1
        order = np.flatnonzero(count)
        if not order.size:
            continue
        main = int(order[np.argmax(count[order])])
        picks = [main] + [int(c) for c in order[np.linspace(0, order.size - 1, lines).round().astype(int)]
                          if int(c) != main]
        picks = list(dict.fromkeys(picks))[:lines]
        found, curve, first = set(), [], None
        for c in picks:
            cc = cascade(text, e=float(es[c]), u=(u_lo, u_hi), k_max=k_max, max_iter=max_iter)
            found.update(cc.members.word)
            if first is None:
                first = cc
            if cc.limit_enclosure is not None:
                curve.append((float(es[c]), cc.limit_enclosure[0], cc.limit_enclosure[1]))
        key = frozenset(found)
        if len(key) < min_members or key in done:
            continue
        done.add(key)
        law, enc = first.law, first.limit_enclosure
        m = first.members
        rows.append({"pattern": text, "level": 1, "seen": n_seen, "members": len(key),
                     "k_first": int(m.k.iloc[0]) if len(m) else -1,
                     "k_last": int(m.k.iloc[-1]) if len(m) else -1,
                     "stop": first.stop, "law": law.kind, "exponent": law.exponent,
                     "exponent_lo": law.exponent_interval[0], "exponent_hi": law.exponent_interval[1],
                     "ratio": law.ratio, "ratio_lo": law.ratio_interval[0], "ratio_hi": law.ratio_interval[1],
                     "limit_lo": enc[0] if enc else math.nan, "limit_hi": enc[1] if enc else math.nan,
                     "limit_name": first.limit_name, "e_line": float(es[main]),
                     "limit_curve": tuple(sorted(curve)), "n_values": ()})
        fams.append((p, x, s))
        cascs.append(first)
    # level 2: families of families; the level-1 family of every n = 1..n_max located on one
    # line (the line of the first one seen), its accumulation points' law against n
    for text, members, make in _level2(fams):
        line = cascs[members[0][1]].fixed
        ns, pts, curve = [], [], []
        for n in range(1, n_max + 1):
            pxs = make(n)
            if pxs is None:
                continue
            c = cascade(_pattern_text(*pxs), e=line, u=(u_lo, u_hi), k_max=k_max, max_iter=max_iter)
            if c.limit_enclosure is not None and len(c.members):
                ns.append(n)
                pts.append(0.5 * (c.limit_enclosure[0] + c.limit_enclosure[1]))
                curve.append((line, c.limit_enclosure[0], c.limit_enclosure[1]))
        row = {"pattern": text, "level": 2, "seen": len(members), "members": len(ns),
               "k_first": ns[0] if ns else -1, "k_last": ns[-1] if ns else -1,
               "stop": f"n = 1..{n_max} tried on the line e = {line:.17g}", "law": "undecided",
               "exponent": math.nan, "exponent_lo": math.nan,
               "exponent_hi": math.nan, "ratio": math.nan, "ratio_lo": math.nan, "ratio_hi": math.nan,
               "limit_lo": math.nan, "limit_hi": math.nan, "limit_name": None, "e_line": line,
               "limit_curve": tuple(curve), "n_values": tuple(ns)}
        gaps = np.abs(np.diff(pts))
        ok = np.diff(ns) == 1
        if ok.sum() >= 4 and np.all(gaps[ok] > 0):
            kk = np.asarray(ns[:-1], float)[ok]
            law = cascade_law(kk, gaps[ok], np.asarray(pts[:-1])[ok], tail=int(ok.sum()))
            row.update({"law": law.kind, "exponent": law.exponent, "exponent_lo": law.exponent_interval[0],
                        "exponent_hi": law.exponent_interval[1], "ratio": law.ratio,
                        "ratio_lo": law.ratio_interval[0], "ratio_hi": law.ratio_interval[1],
                        "limit_lo": law.limit_interval[0], "limit_hi": law.limit_interval[1]})
        rows.append(row)
    cols_out = ["pattern", "level", "seen", "members", "k_first", "k_last", "stop", "law", "exponent",
                "exponent_lo", "exponent_hi", "ratio", "ratio_lo", "ratio_hi", "limit_lo", "limit_hi",
                "limit_name", "e_line", "limit_curve", "n_values"]
    out = pd.DataFrame(rows, columns=cols_out)
    return out.sort_values(["level", "members", "seen"], ascending=[True, False, False],
                           kind="stable").reset_index(drop=True)


# --------------------------------------------------------------------------- #
# How many members, against e                                                 #
# --------------------------------------------------------------------------- #


def _exists(ref, e, u_lo, u_hi):
    """Whether a float of the line e = const in [u_lo, u_hi] has the impact
    numbers ``ref`` (exact, to rounding: the bisection of cascades._search)."""
    return _search(u_lo, u_hi, e, 1, ref, ref.shape[0])[0] == _FOUND


def _refs(pat, k_max):
    out = {}
    for k in range(0 if pat.word(0) is not None else 1, k_max + 1):
        w = pat.word(k)
        if w is not None:
            out[k] = word_impacts(w)
    return out


def _count(refs, e, u_lo, u_hi, cache=None):
    """Members of the family on the line e: consecutive k from the first that
    exists (as :func:`stairbounce.cascade` lists them, up to 64 leading
    misses); ``(count, k_first, k_last)``."""
    n, first, last, misses = 0, None, None, 0
    for k, ref in refs.items():
        ok = _exists(ref, e, u_lo, u_hi)
        if cache is not None:
            cache[(k, e)] = ok
        if ok:
            n, last = n + 1, k
            first = k if first is None else first
        elif first is not None:
            break
        else:
            misses += 1
            if misses >= 64:
                break
    return n, first, last


def member_count(pattern, e, u, *, k_max=200, n=32):
    """member_count(pattern, e, u, *, k_max=200, n=32) -> int or pandas.DataFrame

    How many members of a family exist on the line e = const inside the u
    range, exactly; over a range of e, every value of e where that number
    changes.

    With a number ``e``: the members :func:`stairbounce.cascade` would list
    (consecutive k from the first one on the line, up to ``k_max``), each
    member's existence decided by the bisection on the lexicographic order of
    itineraries (a float of the line with the member's impact numbers, or two
    adjacent floats that leave them on opposite sides; to rounding).

    With a range ``e = (lo, hi)``: the count at ``n`` evenly spaced e
    (both ends included) and, for every member k whose existence differs
    between two consecutive of them, the value of e where it changes,
    bisected on e to adjacent floats (each step an exact existence test on
    its line).  Returns one row per change, in increasing e: ``k``,
    ``e_below`` and ``e_above`` (adjacent floats; the member exists at
    ``e_below`` and not at ``e_above``, or the reverse: ``appears``),
    ``count_below`` and ``count_above`` (the exact count at those two
    values of e).  Two changes of one member between the same two grid
    values are not seen (raise ``n``).

    Parameters
    ----------
    pattern : str, as in :func:`stairbounce.cascade`
    e : float in [0, 1), or (lo, hi)
    u : (lo, hi), u > 0
    k_max : int >= 1, default 200
    n : int >= 2, default 32
    """
    import pandas as pd

    pat = _parse_pattern(pattern)
    k_max = check_count("k_max", k_max, 1, 10**5)
    n = check_count("n", n, 2, 10**5)
    if not isinstance(u, (tuple, list, np.ndarray)):
        raise ValueError(f"u must be a range (lo, hi) of two numbers, got {u!r}")
    u_lo, u_hi = _window("u", u)
    refs = _refs(pat, k_max)
    if not isinstance(e, (tuple, list, np.ndarray)):
        return _count(refs, check_e(e), u_lo, u_hi)[0]
    e_lo, e_hi = _window("e", e)
    grid = np.linspace(e_lo, e_hi, n)
    counts = [_count(refs, float(x), u_lo, u_hi) for x in grid]
    top = max((c[2] for c in counts if c[2] is not None), default=0)
    ks = [k for k in refs if k <= min(k_max, top + 2)]
    rows = []
    for k in ks:
        have = [_exists(refs[k], float(x), u_lo, u_hi) for x in grid]
        for i in range(n - 1):
            if have[i] == have[i + 1]:
                continue
            a, b = float(grid[i]), float(grid[i + 1])
            while True:
                m = 0.5 * (a + b)
                if m <= a or m >= b:
                    break
                if _exists(refs[k], m, u_lo, u_hi) == have[i]:
                    a = m
                else:
                    b = m
            rows.append({"k": k, "e_below": a, "e_above": b, "appears": not have[i],
                         "count_below": _count(refs, a, u_lo, u_hi)[0],
                         "count_above": _count(refs, b, u_lo, u_hi)[0]})
    out = pd.DataFrame(rows, columns=["k", "e_below", "e_above", "appears", "count_below", "count_above"])
    out.attrs.update({"pattern": pat.text, "u": (u_lo, u_hi), "e": (e_lo, e_hi), "n": n,
                      "counts": [(float(x), c[0]) for x, c in zip(grid, counts)]})
    return out.sort_values("e_below", kind="stable").reset_index(drop=True)


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


# --------------------------------------------------------------------------- #
# Organising centres                                                          #
# --------------------------------------------------------------------------- #


def _node_degrees(graph):
    """Arcs (not the window's) that end at each node of a border graph."""
    deg = np.zeros(len(graph.nodes), int)
    for i, j, arc in graph.edges:
        if arc.kind == "window":
            continue
        deg[i] += 1
        if j != i:
            deg[j] += 1
    return deg


def organising_centres(e, u, patterns=(), *, resolution=64, top=8, lines=5, k_max=60, max_iter=1000,
                       regions=None):
    """organising_centres(e, u, patterns=(), *, resolution=64, top=8, lines=5, k_max=60, max_iter=1000, regions=None) -> pandas.DataFrame

    The corners of a window's border graph where the most arcs meet, each
    with its distance to the accumulation curves of the given cascades.

    The regions of the window (:func:`stairbounce.window_regions` at
    ``resolution``, or ``regions`` given) make a
    :func:`stairbounce.border_graph`; each node's degree is the number of
    border arcs (not the window's edges) that end there.  The ``top`` nodes
    of highest degree are listed: ``e``, ``u``, ``degree``, ``events`` (the
    pairs of events that meet); and for each pattern its accumulation curve,
    the enclosure of the accumulation point (:func:`stairbounce.cascade`) on
    ``lines`` lines e = const across the window, interpolated linearly in e
    at the corner: ``nearest`` (the pattern whose curve passes closest in u),
    ``distance`` (``abs(u - curve(e))``, NaN outside the curve's e span) and
    ``on_curve`` (the corner's u within the curve's enclosure interval,
    interpolated, widened by the interpolation's change between lines).
    Returns the corners table; ``attrs["curves"]`` holds each pattern's
    curve as ``[(e, lo, hi), ...]``.  Numerical (the corners are traced to
    rounding, the curves are enclosures on lines, the interpolation between
    lines is linear).

    Parameters
    ----------
    e, u : (lo, hi)
    patterns : iterable of str, as in :func:`stairbounce.cascade`
    resolution : int >= 2, default 64
    top : int >= 1, default 8
    lines : int >= 2, default 5
    k_max, max_iter : as in :func:`stairbounce.cascade`
    regions : list of Region, optional (from :func:`stairbounce.window_regions` of this window)
    """
    import pandas as pd

    from .structure.graph import border_graph
    from .structure.regions import window_regions

    e_lo, e_hi = _window("e", e)
    u_lo, u_hi = _window("u", u)
    top = check_count("top", top, 1)
    lines = check_count("lines", lines, 2, 1000)
    patterns = [str(p) for p in patterns]
    for p in patterns:
        _parse_pattern(p)
    if regions is None:
        resolution = check_count("resolution", resolution, 2, 4096)
        regions = window_regions((e_lo, e_hi), (u_lo, u_hi), resolution=resolution, max_iter=max_iter)
    graph = border_graph(regions)
    deg = _node_degrees(graph)
    curves = {}
    for p in patterns:
        pts = []
        for ev in np.linspace(e_lo, e_hi, lines):
            c = cascade(p, e=float(ev), u=(u_lo, u_hi), k_max=k_max, max_iter=max_iter)
            if c.limit_enclosure is not None:
                pts.append((float(ev), c.limit_enclosure[0], c.limit_enclosure[1]))
        curves[p] = pts
    # the corners inside the window (a node where an arc meets the window's edge is no corner)
    inner = [i for i, c in enumerate(graph.nodes) if all(ev[0] != "window" for ev in c.events)]
    order = sorted(inner, key=lambda i: -deg[i])[:top]
    rows = []
    for i in order:
        node = graph.nodes[int(i)]
        row = {"e": node.e, "u": node.u, "degree": int(deg[i]),
               "events": "; ".join(f"{k} {s}" for k, s in node.events), "nearest": None,
               "distance": math.nan, "on_curve": False}
        for p, pts in curves.items():
            if len(pts) < 2:
                continue
            es_ = np.array([q[0] for q in pts])
            if not es_[0] <= node.e <= es_[-1]:
                continue
            lo_ = np.interp(node.e, es_, [q[1] for q in pts])
            hi_ = np.interp(node.e, es_, [q[2] for q in pts])
            mid = 0.5 * (lo_ + hi_)
            d = abs(node.u - mid)
            if row["nearest"] is None or d < row["distance"]:
                slack = float(np.max(np.abs(np.diff([0.5 * (q[1] + q[2]) for q in pts])))) / 2
                row.update(nearest=p, distance=d, on_curve=bool(lo_ - slack <= node.u <= hi_ + slack))
        rows.append(row)
    out = pd.DataFrame(rows, columns=["e", "u", "degree", "events", "nearest", "distance", "on_curve"])
    out.attrs["curves"] = curves
    out.attrs["nodes"] = len(graph.nodes)
    out.attrs["corners"] = len(inner)
    return out
