"""A cascade's members on a line of the plane (:func:`cascade`), and how many of them
exist against e (:func:`member_count`).  Moved verbatim from ``cascades.py`` and
``cascade_families.py``."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .. import _validate as _v
from ..structure.borders import _event_of, _first_difference
from ..structure.itinerary import KINDS
from ..model import check_count, check_e
from .laws import CascadeLaw, _curve_at, _known_curves, cascade_law
from .patterns import (_check_work, _lower_k, _lex_before, _member_cost, _parse_pattern,
                       word_impacts)
from .search import (_BEHIND, _BEYOND, _FOUND, _edge, _limit_enclosure, _line_args, _neighbour,
                     _search, _side, _window)

__all__ = ["Cascade", "cascade", "member_count"]


# --------------------------------------------------------------------------- #
# The cascade                                                                 #
# --------------------------------------------------------------------------- #


@dataclass(frozen=True, repr=False)
class Cascade:
    """A cascade's members on a line of the plane; see :func:`cascade`.

    ``members`` is a pandas DataFrame, one row per member found: ``k``,
    ``word`` (ASCII), ``period`` (steps), ``impacts`` (finite, per period),
    ``lo`` and ``hi`` (the first and last float of the line with the word),
    ``width`` (``hi - lo``), and for each edge its event ``lo_kind`` /
    ``hi_kind`` (graze, edge, chatter; ``range`` where the line's range cuts
    the member), the step ``lo_step`` / ``hi_step``, the impact ``lo_index`` /
    ``hi_index`` (for edge events) and the word just outside
    (``lo_neighbour`` / ``hi_neighbour``).  ``stop`` says why the member
    after the last one is not listed.  ``limit_enclosure`` ``(lo, hi, n)``:
    the closure of the points whose first n impact numbers are the limit
    itinerary's, which contains the accumulation point (the argument is
    exact, module docstring; its ends are located by float decisions, so the
    enclosure is numerical, to rounding); ``law`` the fitted :class:`CascadeLaw`; ``limit_name``
    the known curve (Theorem 3.1 tongue edges, the neutral one-impact
    families, Corollary 2.1) that crosses the line inside the enclosure, or
    None.
    """

    pattern: str
    axis: str
    fixed: float
    range: tuple[float, float]
    members: Any
    stop: str
    law: CascadeLaw
    limit_enclosure: tuple[float, float, int] | None
    limit_name: str | None
    limit_curve: float | None
    skipped: tuple[int, ...] = field(default=())

    @property
    def last(self) -> int | None:
        """The exponent of the last member found, None when none was."""
        return int(self.members["k"].iloc[-1]) if len(self.members) else None

    def text(self, max_rows: int = 60) -> str:
        """The members as a table, then the stop, the law and the accumulation point."""
        other = "u" if self.axis == "e" else "e"
        lines = [f"cascade {self.pattern} at {other} = {self.fixed:g}, {self.axis} in "
                 f"[{self.range[0]:g}, {self.range[1]:g}]: {len(self.members)} member(s)",
                 "basis: numerical, to rounding (each member and edge is located by float decisions of the "
                 "orbit, exact but for rounding near a border; Cascade.prove / --prove proves the members' "
                 "intervals by interval arithmetic)"]
        lines.append(f"{'k':>4} {'period':>6} {self.axis + ' lo':>20} {self.axis + ' hi':>20} "
                     f"{'width':>10}  lo edge            hi edge")
        rows = self.members.itertuples()
        for i, r in enumerate(rows):
            if i == max_rows:
                lines.append(f"... {len(self.members) - max_rows} more")
                break
            lo = f"{r.lo_kind} step {r.lo_step}" if r.lo_kind != "range" else "range"
            hi = f"{r.hi_kind} step {r.hi_step}" if r.hi_kind != "range" else "range"
            lines.append(f"{r.k:>4} {r.period:>6} {r.lo:>20.17g} {r.hi:>20.17g} {r.width:>10.3e}  "
                         f"{lo:<18} {hi}")
        lines.append(f"stop: {self.stop}")
        lines.append(f"law of the widths: {self.law.text()}")
        if math.isfinite(self.law.limit):
            a, b = self.law.limit_interval
            par = "ratio" if self.law.approach_kind == "geometric" else "exponent"
            lines.append(f"accumulation (extrapolation, numerical, not an enclosure: the local limits of "
                         f"consecutive members extrapolated to k -> inf): {self.axis} -> {self.law.limit:.12g} in "
                         f"[{a:.12g}, {b:.12g}]; positions approach it {self.law.approach_kind}ally, local "
                         f"{par}s {self.law.approach_interval[0]:.4g}..{self.law.approach_interval[1]:.4g}")
        if self.limit_enclosure is not None:
            a, b, n = self.limit_enclosure
            lines.append(f"accumulation (enclosure to rounding, numerical: its ends are float decisions; first {n} steps of the limit itinerary): "
                         f"{self.axis} in [{a:.15g}, {b:.15g}]")
        if self.limit_name is not None:
            lines.append(f"accumulation lies on: {self.limit_name} ({self.axis} = {self.limit_curve:.15g})")
        return "\n".join(lines)

    def regions(self, e, u, *, ks=None, resolution=None, max_iter=1000):
        """The members' regions in the window ``e`` x ``u``, ``{k: Region}``, each
        from :func:`stairbounce.word_region` (all members, or those in ``ks``)."""
        from ..structure.regions import word_region

        rows = self.members if ks is None else self.members[self.members.k.isin(list(ks))]
        return {int(r.k): word_region(r.word, e, u, resolution=resolution, max_iter=max_iter)
                for r in rows.itertuples()}

    def prove(self, ks=None, max_iter=None):
        """prove(ks=None, max_iter=None) -> pandas.DataFrame

        Each member's interval proven with :func:`stairbounce.certify_box`: the
        segment of the line from ``lo`` to ``hi`` (a box with one side of zero
        width) is certified, every decision of the orbit of (1, 0) taken by
        outward-rounded interval arithmetic over all its real points.  Where the
        whole float interval is not proven (its ends lie within rounding of the
        borders), the segment shrunk by 1e-9, 1e-6, 1e-3, 1e-2 and 0.1 of the
        width at each end is tried, in that order.  One row per member (all, or
        those in ``ks``): ``k``, ``word``, ``proven`` (bool), ``lo`` and ``hi`` (the
        segment proven, NaN when none), ``share`` (its part of the member's
        width; 1 for the whole), ``status`` / ``reason`` / ``step`` (of the last
        certificate tried when none is proven).  ``max_iter`` defaults to each
        member's period + 1.  A proven row is a theorem about every real point
        of its segment (at the line's binary float); the members' edges
        themselves stay numerical (float decisions).
        """
        import pandas as pd

        from ..structure.certify import certify_box
        from ..symbolic import parse_word

        rows = self.members if ks is None else self.members[self.members.k.isin(list(ks))]
        out = []
        f = self.fixed
        for r in rows.itertuples():
            w = parse_word(r.word)
            iters = max_iter if max_iter is not None else w.period + 1
            row = {"k": int(r.k), "word": r.word, "proven": False, "lo": math.nan, "hi": math.nan,
                   "share": 0.0, "status": "", "reason": "", "step": 0}
            for pad in _PROVE_PADS:
                a, b = r.lo + pad * r.width, r.hi - pad * r.width
                if not a <= b:
                    continue
                box = {"e": (f, f), "u": (a, b)} if self.axis == "u" else {"e": (a, b), "u": (f, f)}
                cert = certify_box(**box, max_iter=iters)
                row.update(status=cert.status, reason=cert.reason or "", step=int(cert.step or 0))
                if cert.status == "word" and cert.word == w:
                    row.update(proven=True, lo=a, hi=b, share=(b - a) / r.width if r.width > 0 else 1.0)
                    break
            out.append(row)
        return pd.DataFrame(out, columns=["k", "word", "proven", "lo", "hi", "share", "status", "reason", "step"])

    def __repr__(self) -> str:
        return (f"Cascade({self.pattern!r}, {len(self.members)} members, last k={self.last}, "
                f"law={self.law.kind})")


# Cascade.prove: the parts of each member's width cut from both ends, tried in turn
_PROVE_PADS = (0.0, 1e-9, 1e-6, 1e-3, 1e-2, 0.1)

# searches per member: the member itself, then each of its two edges
_SEARCHES = 3


def _limit_n(pat, k_max, limit_steps):
    """Steps of the limit itinerary the enclosure follows (``cascade``'s default
    at the last member k_max, an upper bound)."""
    return limit_steps or max(200, 4 * _member_cost(pat, k_max, one=True))


def _cascade_work(pat, k_max, limit_steps=None):
    """The steps :func:`cascade` follows at most (``_check_work``'s unit): three
    searches of every member up to ``k_max``, three of the limit itinerary."""
    return _SEARCHES * (_member_cost(pat, k_max) + _limit_n(pat, k_max, limit_steps))


def cascade(pattern, e, u, *, k_max=100, max_iter=1000, limit_steps=None, law_k=None):
    """cascade(pattern, e, u, *, k_max=100, max_iter=1000, limit_steps=None, law_k=None) -> Cascade

    Every member of a family of words that exists on a line of the (e, u)
    plane, each located exactly, with the family's scaling law and
    accumulation point.

    ``pattern`` raises one block to a free exponent, ``"(1^k, 0^inf)"`` or
    ``"((1, 0)^k, 1, 1, 0^inf)"``; one of ``e`` and ``u`` is a range
    ``(lo, hi)``, the other a number (the line e = const, or u = const).
    Members are taken in increasing k from the first whose word exists: a
    member is found by bisection on the side its word lies on (the impact
    numbers are lexicographically non-increasing along the line, proven: the
    module docstring), its edges are shrunk to adjacent floats and labelled
    by their event as in :func:`stairbounce.border_points`, and member k+1 is
    searched only beyond member k, on the side the order of their words
    gives.  Members before the first one on the line are skipped
    (``skipped``); the search stops at the first member after it that lies
    beyond the range or has no float on the line, or at ``k_max``
    (``stop`` says which, with the orbit's first deviation on both sides of
    where it would be).  The law is :func:`cascade_law` on the members' widths
    and on the edges that face the accumulation point; the accumulation point
    is enclosed exactly by the points that follow the limit itinerary for
    ``limit_steps`` steps (default: four times the last member's period, at
    least 200).

    Parameters
    ----------
    pattern : str
    e, u : float, or (lo, hi)
        The line: e in [0, 1), u > 0 (the valid numeric range).
    k_max : int >= 1, default 100
        Largest exponent tried (the longest word has about k_max times the
        block's letters).
    max_iter : int >= 1, default 1000
        Steps iterated to name the words just outside each edge (the search
        itself follows each member's own word, its period).
    limit_steps : int >= 1, optional
    law_k : (k_lo, k_hi), optional
        The members the law is fitted on (all of them in that range); by
        default the last 8 members not cut by the range.  A cascade that
        ends at a finite k (its members' edges cross) shrinks faster near its
        end than its law says: ``law_k`` leaves those members out.
    """
    pat = _parse_pattern(pattern)
    axis, name, lo, hi, fixed = _line_args(e, u)
    k_max = check_count("k_max", k_max, 1, 10**6)
    max_iter = check_count("max_iter", max_iter, 1, 2**31 - 1)
    if limit_steps is not None:
        limit_steps = check_count("limit_steps", limit_steps, 1, 10**7)
    if law_k is not None:
        if not isinstance(law_k, (tuple, list)) or len(law_k) != 2:
            raise ValueError(f"law_k must be a pair (k_lo, k_hi) of integers >= 1, got {law_k!r}")
        law_k = (check_count("law_k[0]", law_k[0], 1), check_count("law_k[1]", law_k[1], 1))
        if law_k[1] - law_k[0] < 3:
            raise ValueError(f"law_k must span at least 4 members (k_hi >= k_lo + 3), got {law_k!r}")
    _check_work(f"cascade {pat.text!r} with k_max = {k_max}", _cascade_work(pat, k_max, limit_steps),
                lambda: _lower_k(lambda k: _cascade_work(pat, k, limit_steps), ""))
    per_k = max(1, sum(pat.block))
    _v.check_memory(f"k_max = {k_max}", 8 * (len(pat.prefix) + len(pat.suffix) + per_k * k_max + 1) * 4)

    rows, skipped = [], []
    stop = f"k_max = {k_max} reached"
    prev_ref, prev_row = None, None
    k_first = 0 if pat.word(0) is not None else 1
    for k in range(k_first, k_max + 1):
        w = pat.word(k)
        if w is None:
            continue
        ref = word_impacts(w)
        p = ref.shape[0]
        if prev_row is None:
            a, b = lo, hi
            ahead = None
        else:
            ahead = not _lex_before(ref, prev_ref)  # member k lies at larger x than k-1
            a, b = (prev_row["hi_out"], hi) if ahead else (lo, prev_row["lo_out"])
        out, x, ba, bb, _ = _search(a, b, fixed, axis, ref, p)
        if out != _FOUND:
            if prev_row is None:  # not on the line yet: the next member may be
                skipped.append(k)
                if len(skipped) >= 64:
                    stop = f"no member found for k = {skipped[0]}..{k}"
                    break
                continue
            stop = _why_not(k, w, out, ba, bb, fixed, axis, ref, name)
            break
        row = {"k": k, "word": w.format(ascii=True), "period": w.period, "impacts": w.impacts}
        for side, end in (("lo", ba), ("hi", bb)):
            if x == end:  # the member reaches the bracket's end: its edge is there
                xin = end
                xout = float(np.nextafter(end, -np.inf if side == "lo" else np.inf))
                if not lo <= xout <= hi:
                    row.update({side: end, f"{side}_out": end, f"{side}_kind": "range",
                                f"{side}_step": 0, f"{side}_index": 0,
                                f"{side}_neighbour": "(range end)"})
                    continue
                j, kc, ko, _, _ = _first_difference(xin, xout, fixed, axis, p)
                kind, index = _event_of(kc, ko)
                kind = KINDS[kind]
            else:
                xin, xout, j, kind, index, _, _ = _edge(x, end, fixed, axis, ref)
            row.update({side: xin, f"{side}_out": xout, f"{side}_kind": kind, f"{side}_step": int(j),
                        f"{side}_index": int(index) if kind == "edge" else 0,
                        f"{side}_neighbour": _neighbour(xout, fixed, axis, max_iter)})
        row["width"] = row["hi"] - row["lo"]
        rows.append(row)
        prev_ref, prev_row = ref, row
    else:
        stop = f"k_max = {k_max} reached"

    import pandas as pd  # (xarray's dependency)

    cols = ["k", "word", "period", "impacts", "lo", "hi", "width", "lo_kind", "lo_step", "lo_index",
            "hi_kind", "hi_step", "hi_index", "lo_neighbour", "hi_neighbour", "lo_out", "hi_out"]
    members = pd.DataFrame(rows, columns=cols)
    # the law on the members not cut by the range
    whole = members[(members.lo_kind != "range") & (members.hi_kind != "range") & (members.k >= 1)]
    # local ratio and exponent of the widths, between consecutive members not cut by the range
    prev_k = whole.k.shift(1)
    ok = (whole.k - prev_k) == 1
    ratio = whole.width / whole.width.shift(1)
    with np.errstate(divide="ignore", invalid="ignore"):  # a member one float wide has width 0
        members["local_ratio"] = ratio.where(ok)
        members["local_exponent"] = (-np.log(ratio) / np.log(whole.k / prev_k)).where(ok)
    whole = whole[whole.width > 0]
    tail = 8
    if law_k is not None:
        whole = whole[(whole.k >= law_k[0]) & (whole.k <= law_k[1])]
        tail = max(4, len(whole))
    ahead = len(members) < 2 or bool(members["lo"].iloc[-1] > members["lo"].iloc[0])
    facing = "hi" if ahead else "lo"  # the edge that faces the accumulation point
    law = cascade_law(whole.k.values.astype(float), whole.width.values.astype(float),
                      whole[facing].values.astype(float), tail=tail)
    enclosure = None
    if len(members):
        n = limit_steps or max(200, 4 * int(members.period.iloc[-1]))
        last = members.iloc[-1]
        a, b = (float(last.hi_out), hi) if ahead else (lo, float(last.lo_out))
        if a < b:
            enclosure = _limit_enclosure(pat, n, a, b, fixed, axis)
    lim_name = lim_curve = None
    if enclosure is not None:
        ea, eb, _ = enclosure
        best = None
        for label, curve in _known_curves():
            xc = _curve_at(curve, 1 if axis == 1 else 0, fixed, lo, hi)
            if xc is not None and ea <= xc <= eb:
                d = abs(xc - law.limit) if math.isfinite(law.limit) else 0.0
                if best is None or d < best[0]:
                    best = (d, label, xc)
        if best is not None:
            lim_name, lim_curve = best[1], float(best[2])
    return Cascade(pat.text, name, fixed, (lo, hi), members.drop(columns=["lo_out", "hi_out"]), stop,
                   law, enclosure, lim_name, lim_curve, tuple(skipped))


def _why_not(k, w, out, a, b, f, axis, ref, name):
    """Why member ``k`` is not listed, in one sentence."""
    text = f"member k = {k} {w.format(ascii=True) if len(w) <= 24 else f'(period {w.period})'}"
    if out == _BEYOND:
        return f"{text} lies beyond the range ({name} > {b:.17g})"
    if out == _BEHIND:
        return f"{text} lies before the range ({name} < {a:.17g})"
    p = ref.shape[0]
    _, ja = _side(a, f, axis, ref, p)
    _, jb = _side(b, f, axis, ref, p)
    ulp = b - a
    return (f"{text} has no float on the line: the search ends on adjacent floats {name} = {a:.17g} "
            f"and {b:.17g} (spacing {ulp:.2g}), whose orbits leave its impact numbers at steps "
            f"{ja} and {jb} on opposite sides (its interval is empty or narrower than the spacing)")


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
    # the work before it starts: one search per member at one e; over a range, the counts and
    # every member's existence at the n values of e (each change found adds about 60 tests of
    # one member and two counts)
    grid_n = 2 * n if isinstance(e, (tuple, list, np.ndarray)) else 1
    what = f"member_count of {pat.text!r} with k_max = {k_max}" + (f", n = {n}" if grid_n > 1 else "")
    _check_work(what, grid_n * _member_cost(pat, k_max),
                lambda: _lower_k(lambda k: grid_n * _member_cost(pat, k), " or n" if grid_n > 1 else ""))
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


