"""Cascades of words: a family of words with one block raised to a free exponent,
its members located exactly on a line of the (e, u) plane, and its scaling law.

A *pattern* is written as the paper writes words, with one block raised to a
free exponent: ``(1^k, 0^inf)`` is the family ``(1, 0^inf)``, ``(1, 1, 0^inf)``,
``(1, 1, 1, 0^inf)``, ...; ``((1, 0)^k, 1, 1, 0^inf)`` raises the block
``(1, 0)``.  A zero written just before the tail belongs to the tail
(``0, 0^inf`` is ``0^inf``), so ``((1, 0)^k, 0^inf)`` is ``(1, 0, ..., 1, 0^inf)``.

**The order that makes the search exact (proven).**  Along a fixed itinerary
every event margin ``T - v - C s`` decreases strictly with u and with e
(:mod:`stairbounce.structure.verify`, "Monotonicity").  On a line e = const
(or u = const) the impact number of step ``j`` is the number of margins of that
step that are >= 0 (sliding: all of them), so among points that share the
impact numbers of steps ``1..j-1`` it is a non-increasing function of u; by
induction the set of points with a given prefix is an interval, and the
sequence of impact numbers of the orbit of ``(1, 0)`` (sliding ranked above
every finite number) is *lexicographically non-increasing* along the line.
Hence (i) each word's set on the line is one interval, and (ii) at any point
the first step where the orbit leaves a word's impact numbers says on which
side of the point the word's interval lies (more impacts than the word there:
the word lies at larger u).  So a member is found by bisection on that sign
(:func:`_search`), its two edges are shrunk to adjacent floats with the
secant/bisection of :func:`stairbounce.structure.borders._shrink_secant` and labelled
with :func:`stairbounce.structure.borders._first_difference` (graze / edge / chatter and
the step, as :func:`stairbounce.border_points` labels them), and member k+1 is
searched beyond member k on the side the order of their words gives: nothing
is sampled, so a member narrower than any grid is not missed, and a member that
is not found has no float on the line (its interval is empty or narrower than
the float spacing: the bisection ends on two adjacent floats that both
differ from it).  The same order bounds the accumulation point: every member
with large k has the first N impact numbers of the limit itinerary (prefix,
then the block forever), and the points with that prefix form one interval
I_N, so the limit of the members lies in the closure of I_N for every N.

The search relies on the float map reproducing the exact order, which it does
except within a few ulps of a border (rounding), so every statement here holds
"to rounding", as for :func:`stairbounce.border_points`.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numba import njit

from . import _validate as _v
from .structure.borders import _event_of, _first_difference, _shrink_secant, _trial
from .structure.itinerary import KINDS
from .model import SLIDING, check_count, check_e, check_u, no_sliding_bound
from .symbolic import Word, sliding_word

__all__ = ["Cascade", "CascadeLaw", "cascade", "cascade_law", "cascades", "family_of"]

# longest pattern text read, and most letters a member may have (memory and time
# grow with them; a million letters is far beyond any cascade on a line)
_MAX_PATTERN_TEXT = 1000
_MAX_LETTERS = 10**6
# impact number standing for "slides" in the lexicographic order
_SLIDE_RANK = np.iinfo(np.int64).max

# search outcomes
_FOUND, _BEHIND, _BEYOND, _EMPTY = 0, 1, 2, 3


# --------------------------------------------------------------------------- #
# Patterns                                                                    #
# --------------------------------------------------------------------------- #


@dataclass(frozen=True)
class _Pattern:
    """A parsed pattern: ``prefix + block * k + suffix``, then the tail 0^inf."""

    text: str
    var: str
    prefix: tuple[int, ...]
    block: tuple[int, ...]
    suffix: tuple[int, ...]

    def letters(self, k: int) -> tuple[int, ...]:
        letters = list(self.prefix + self.block * k + self.suffix)
        while letters and letters[-1] == 0:  # 0, 0^inf is 0^inf
            letters.pop()
        return tuple(letters)

    def word(self, k: int) -> Word | None:
        """Member ``k`` as a word, None when the letters make no word (empty,
        or a leading zero)."""
        letters = self.letters(k)
        if not letters or letters[0] < 1:
            return None
        return Word(letters)

    def limit_impacts(self, n: int) -> np.ndarray | None:
        """The first ``n`` impact numbers of the limit k -> inf (prefix, then
        the block forever); None when the block has no jump (its limit is a
        slide, not an itinerary)."""
        if sum(self.block) == 0:
            return None
        reps = (n + 2) // sum(self.block) + 2
        steps = _steps(self.prefix + self.block * reps)
        # the last step may still gain impacts from later zeros: dropped
        return np.asarray(steps[:-1][:n], dtype=np.int64)


_TOKEN = re.compile(r"\s*(?:(\d+)|(inf|\u221e)|([A-Za-z_]\w*)|([(),^]))")


def _parse_pattern(text) -> _Pattern:
    """Read a pattern such as ``((1, 0)^k, 1, 1, 0^inf)``; ValueError otherwise."""
    rule = "pattern must be a word with one block raised to a free exponent, like (1^k, 0^inf) or ((1, 0)^k, 1, 1, 0^inf)"
    if not isinstance(text, str):
        raise ValueError(f"{rule}, got {text!r}")
    if len(text) > _MAX_PATTERN_TEXT:
        raise ValueError(f"pattern must be at most {_MAX_PATTERN_TEXT} characters long, got {len(text)}")
    tokens, pos, s = [], 0, text.rstrip()
    while pos < len(s):
        m = _TOKEN.match(s, pos)
        if not m:
            raise ValueError(f"{rule}, got {text!r} (cannot read {s[pos:pos + 10]!r})")
        num, inf, name, sym = m.groups()
        tokens.append(("int", int(num)) if num is not None and len(num) <= 7 else
                      ("bad", num) if num is not None else
                      ("inf", None) if inf is not None else
                      ("name", name) if name is not None else (sym, None))
        pos = m.end()
    if any(t[0] == "bad" for t in tokens):
        raise ValueError(f"{rule}: numbers must be below 10^7, got {text!r}")
    at = 0

    def peek():
        return tokens[at][0] if at < len(tokens) else None

    def take(kind):
        nonlocal at
        if peek() != kind:
            raise ValueError(f"{rule}, got {text!r}")
        at += 1
        return tokens[at - 1][1]

    def seq(top):
        """A parenthesised list: each item (letters, exponent)."""
        take("(")
        items = []
        while True:
            if peek() == "(":
                letters = tuple(a for item in seq(False) for a in _expand(item, text, rule))
            else:
                letters = (take("int"),)
            exp = 1
            if peek() == "^":
                take("^")
                kind = peek()
                exp = take(kind) if kind in ("int", "name") else (take("inf") or "inf")
            if not top and isinstance(exp, str):
                raise ValueError(f"{rule}: the free exponent must be on a block at the top level, got {text!r}")
            items.append((letters, exp))
            if peek() == ",":
                take(",")
                continue
            take(")")
            return items

    items = seq(True)
    if at != len(tokens):
        raise ValueError(f"{rule}, got {text!r}")
    if not items or items[-1] != ((0,), "inf"):
        raise ValueError(f"{rule}: it must end with the tail 0^inf, got {text!r}")
    items = items[:-1]
    free = [i for i, (_, exp) in enumerate(items) if isinstance(exp, str)]
    if any(items[i][1] == "inf" for i in free):
        raise ValueError(f"{rule}: only the tail is 0^inf, got {text!r}")
    if len(free) != 1:
        raise ValueError(f"{rule}: exactly one block needs a free exponent such as ^k, got {text!r}")
    i = free[0]
    prefix = tuple(a for item in items[:i] for a in _expand(item, text, rule))
    suffix = tuple(a for item in items[i + 1:] for a in _expand(item, text, rule))
    block = items[i][0]
    if not block:
        raise ValueError(f"{rule}: the raised block is empty, got {text!r}")
    return _Pattern(text.strip(), items[i][1], prefix, block, suffix)


def _expand(item, text, rule):
    letters, exp = item
    if isinstance(exp, str):
        raise ValueError(f"{rule}: exactly one free exponent, at the top level, got {text!r}")
    if len(letters) * exp > _MAX_LETTERS:
        raise ValueError(f"pattern must expand to at most {_MAX_LETTERS} letters, got {text!r}")
    return letters * exp


def _steps(letters) -> list[int]:
    """Impact numbers of the steps that a sequence of letters (jump numbers)
    describes, from the departure at (1, 0): a jump ``a`` flies over ``a - 1``
    steps and lands on the next, every zero adds an impact on the same step."""
    ks: list[int] = []
    for a in letters:
        if a >= 1:
            ks.extend([0] * (a - 1))
            ks.append(1)
        elif ks:
            ks[-1] += 1
    return ks


def word_impacts(word: Word) -> np.ndarray:
    """The impact numbers of the steps of one period of ``word``, the last one
    ``SLIDING`` (the inverse of :func:`stairbounce.symbolic.word_from_impacts`)."""
    ks = _steps(word.letters)
    ks[-1] = SLIDING
    return np.asarray(ks, dtype=np.int64)


def _rank(k):
    return _SLIDE_RANK if k == SLIDING else int(k)


def _lex_before(a, b) -> bool:
    """Whether impact sequence ``a`` is lexicographically larger than ``b``
    (sliding ranked highest), i.e. ``a`` lies at smaller u (or e) than ``b``."""
    for x, y in zip(a, b):
        if x != y:
            return _rank(x) > _rank(y)
    return len(a) < len(b)


# --------------------------------------------------------------------------- #
# Compiled search                                                             #
# --------------------------------------------------------------------------- #


@njit(cache=True)
def _side(x, f, axis, ref, p):
    """Where the points with the impact numbers ``ref[:p]`` lie from ``x``:
    0 at ``x``, +1 at larger x, -1 at smaller x (module docstring: the
    impact numbers are lexicographically non-increasing along the line).
    Returns ``(side, step of the first difference)``."""
    follows, dev, kdev, _, _ = _trial(x, f, axis, ref, p, 0, 0, 0)
    if follows:
        return 0, 0
    r = ref[dev - 1]
    a = 1 << 62 if kdev == SLIDING else kdev
    b = 1 << 62 if r == SLIDING else r
    return (1 if a > b else -1), dev


@njit(cache=True)
def _search(lo, hi, f, axis, ref, p):
    """Bisect ``[lo, hi]`` on :func:`_side` for a point with ``ref[:p]``.

    Returns ``(outcome, x, lo, hi, trials)``: ``_FOUND`` with ``x`` such a
    point; ``_BEHIND`` / ``_BEYOND`` when the points lie below ``lo`` /
    above ``hi``; ``_EMPTY`` when the bracket shrank to adjacent floats
    ``lo``, ``hi`` without one (no float of the line has ``ref``).
    """
    s, _ = _side(lo, f, axis, ref, p)
    if s == 0:
        return _FOUND, lo, lo, hi, 1
    if s < 0:
        return _BEHIND, math.nan, lo, hi, 1
    s, _ = _side(hi, f, axis, ref, p)
    if s == 0:
        return _FOUND, hi, lo, hi, 2
    if s > 0:
        return _BEYOND, math.nan, lo, hi, 2
    trials = 2
    while True:
        m = 0.5 * (lo + hi)
        if m <= lo or m >= hi:
            return _EMPTY, math.nan, lo, hi, trials
        s, _ = _side(m, f, axis, ref, p)
        trials += 1
        if s == 0:
            return _FOUND, m, lo, hi, trials
        if s > 0:
            lo = m
        else:
            hi = m


# --------------------------------------------------------------------------- #
# Members                                                                     #
# --------------------------------------------------------------------------- #


def _edge(x_in, x_out, f, axis, ref):
    """Shrink ``[x_in, x_out]`` (``x_in`` has ``ref``, ``x_out`` not) to
    adjacent floats; the edge's label as border_points gives it."""
    p = ref.shape[0]
    xc, xo, trials, _ = _shrink_secant(x_in, x_out, f, axis, ref, p)
    j, kc, ko, _, _ = _first_difference(xc, xo, f, axis, p)
    kind, index = _event_of(kc, ko)
    return xc, xo, int(j), KINDS[kind], int(index), int(ko), int(trials)


def _neighbour(x, f, axis, max_iter):
    e, u = (x, f) if axis == 0 else (f, x)
    w = sliding_word(e, u, max_iter)
    return w.format(ascii=True) if w is not None else "none within max_iter"


def _is_pair(x):
    return isinstance(x, (tuple, list, np.ndarray))


def _line_args(e, u):
    """Which coordinate varies: ``(axis, name, lo, hi, fixed)``."""
    e_pair, u_pair = _is_pair(e), _is_pair(u)
    if e_pair == u_pair:
        raise ValueError("e and u: give one as a range (lo, hi) and the other as a number "
                         f"(a line of the plane), got e={e!r}, u={u!r}")
    axis, name, rng, fixed = (0, "e", e, u) if e_pair else (1, "u", u, e)
    if len(rng) != 2:
        raise ValueError(f"{name} must be a range (lo, hi) of two numbers, got {rng!r}")
    if axis == 0:
        lo, hi = check_e(rng[0]), check_e(rng[1])
        fixed = check_u(fixed)
    else:
        lo, hi = check_u(rng[0]), check_u(rng[1])
        fixed = check_e(fixed)
    if not lo < hi:
        raise ValueError(f"{name} must be a range (lo, hi) with lo < hi, got {rng!r}")
    return axis, name, lo, hi, fixed


def _limit_enclosure(pat, n, lo, hi, f, axis):
    """The closure of I_n (the points whose first ``n`` impact numbers are the
    limit's), as ``(lo, hi, n)``, or None where it cannot be located."""
    ref = pat.limit_impacts(n)
    if ref is None or ref.shape[0] == 0:
        return None
    m = ref.shape[0]
    out, x, a, b, _ = _search(lo, hi, f, axis, ref, m)
    if out == _EMPTY:
        return float(a), float(b), m
    if out != _FOUND:
        return None
    lo_out = lo if x == lo else float(_shrink_secant(x, a, f, axis, ref, m)[1])
    hi_out = hi if x == hi else float(_shrink_secant(x, b, f, axis, ref, m)[1])
    return lo_out, hi_out, m


# --------------------------------------------------------------------------- #
# The law                                                                     #
# --------------------------------------------------------------------------- #


@dataclass(frozen=True)
class CascadeLaw:
    """How a cascade's members shrink and where they accumulate; see :func:`cascade_law`.

    ``kind`` is ``"geometric"`` (``w_k ~ C r^k``: ``ratio`` r and
    ``ratio_interval``), ``"algebraic"`` (``w_k ~ C k^-gamma``: ``exponent``
    gamma and ``exponent_interval``) or ``"undecided"`` (neither model fits
    ``threshold`` times better than the other, or too few members).  Both
    estimates are always given.  ``residual_geometric`` and
    ``residual_algebraic`` are the RMS residuals of the two straight-line fits
    (log w against k, log w against log k) on the members ``ks_used``.
    ``limit`` (with ``limit_interval``) is the extrapolated accumulation point
    of the positions, by their own law ``approach_kind`` (decided by the same
    criterion on the gaps between consecutive positions; three-point fits,
    Aitken's for the geometric law); ``approach`` is that law's local
    parameter there (the ratio of successive gaps, or the exponent beta of
    ``a_k = L + C k^-beta``), with ``approach_interval``.  All numerical.
    """

    kind: str
    ratio: float
    ratio_interval: tuple[float, float]
    exponent: float
    exponent_interval: tuple[float, float]
    residual_geometric: float
    residual_algebraic: float
    threshold: float
    ks_used: tuple[int, ...]
    limit: float = math.nan
    limit_interval: tuple[float, float] = (math.nan, math.nan)
    approach: float = math.nan
    approach_interval: tuple[float, float] = (math.nan, math.nan)
    approach_kind: str = "undecided"

    @property
    def criterion(self) -> str:
        """The rule that decided ``kind``, in words."""
        return (f"geometric if the RMS residual of log w against k is {self.threshold:g} times smaller "
                f"than that of log w against log k on the last {len(self.ks_used)} members, algebraic "
                "if the reverse, undecided otherwise; intervals span the local ratios / exponents of "
                "those members")

    def text(self) -> str:
        """One line: the law, its parameter with its interval, and the residuals."""
        if self.kind == "geometric":
            law = (f"geometric: ratio {self.ratio:.4g} in [{self.ratio_interval[0]:.4g}, "
                   f"{self.ratio_interval[1]:.4g}]")
        elif self.kind == "algebraic":
            law = (f"algebraic: exponent {self.exponent:.4g} in [{self.exponent_interval[0]:.4g}, "
                   f"{self.exponent_interval[1]:.4g}]")
        else:
            law = (f"undecided (ratio {self.ratio:.4g}, exponent {self.exponent:.4g})")
        k = self.ks_used
        span = f"k = {k[0]}..{k[-1]}" if k else "no members"
        return (f"{law}; residuals geometric {self.residual_geometric:.2g}, algebraic "
                f"{self.residual_algebraic:.2g} ({span})")


def _line_fit(x, y):
    a = np.vstack([np.ones_like(x), x]).T
    coef, *_ = np.linalg.lstsq(a, y, rcond=None)
    res = y - a @ coef
    return coef, float(np.sqrt(np.mean(res**2)))


def _algebraic_beta(k, a):
    """beta such that a_k = L + C k^-beta passes through three consecutive
    points (k, k+1, k+2): the ratio of the two gaps fixes beta (bisection)."""
    g = (a[2] - a[1]) / (a[1] - a[0])
    if not (0.0 < g < 1.0):
        return math.nan

    def ratio(b):
        return ((k + 2) ** -b - (k + 1) ** -b) / ((k + 1) ** -b - k**-b)

    lo, hi = 1e-6, 60.0
    if not (ratio(hi) < g < ratio(lo)):
        return math.nan
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if ratio(mid) > g:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _limits(kind, ks, pos):
    """Local estimates of the accumulation point and of the approach
    parameter, one per triple of consecutive members."""
    lims, pars = [], []
    for i in range(len(ks) - 2):
        if ks[i + 2] - ks[i] != 2:
            continue
        a = pos[i:i + 3]
        d0, d1 = a[1] - a[0], a[2] - a[1]
        if d0 == 0 or (d1 / d0) <= 0:
            continue
        if kind == "geometric":
            if d1 == d0:
                continue
            lims.append(a[2] - d1 * d1 / (d1 - d0))  # Aitken's delta-squared
            pars.append(d1 / d0)
        else:
            b = _algebraic_beta(float(ks[i]), a)
            if not math.isfinite(b):
                continue
            c = d0 / ((ks[i] + 1) ** -b - ks[i] ** -b)
            lims.append(a[2] - c * (ks[i] + 2) ** -b)
            pars.append(b)
    return np.asarray(lims), np.asarray(pars)


def cascade_law(k, widths, positions=None, *, tail=8, threshold=3.0):
    """cascade_law(k, widths, positions=None, *, tail=8, threshold=3.0) -> CascadeLaw

    Decide whether the widths of a cascade's members shrink geometrically or
    algebraically, and extrapolate where the members accumulate.

    On the last ``tail`` members (at least 4) two straight lines are fitted:
    ``log w_k = a + k log r`` (geometric: a hyperbolic limit orbit, multiplier
    1/r) and ``log w_k = a - gamma log k`` (algebraic: a neutral limit,
    multiplier 1; Jeffrey and Dankowicz's two scaling laws of discontinuity
    induced cascades).  The law whose RMS residual is ``threshold`` times
    smaller than the other's is chosen, else ``"undecided"``: the criterion
    fails on sequences that follow neither.  Intervals are the ranges of the
    local values on those members: ``w_{k+1} / w_k`` for the ratio,
    ``-log(w_{k+1}/w_k) / log((k+1)/k)`` for the exponent (they drift where
    the law holds only asymptotically; the interval shows the drift).  With
    ``positions`` (an edge of each member), the limit is extrapolated from
    each triple of consecutive members with the law decided (Aitken's
    delta-squared for geometric, ``a_k = L + C k^-beta`` through the three
    points for algebraic), the positions' law decided by the same criterion
    on their gaps (``approach_kind``); ``limit`` is the last triple's,
    ``limit_interval`` the range over the last ``tail`` triples.  Numerical, not proven; checked
    on maps whose laws are known in closed form (tests/test_cascades.py).

    Parameters
    ----------
    k : sequence of int
        The members' exponents, increasing.
    widths : sequence of float > 0
    positions : sequence of float, optional
    tail : int >= 4, default 8
    threshold : float > 1, default 3.0
    """
    ks = np.asarray(k, dtype=float)
    w = np.asarray(widths, dtype=float)
    if ks.ndim != 1 or w.shape != ks.shape:
        raise ValueError(f"k and widths must be 1-d sequences of equal length, got {ks.shape} and {w.shape}")
    if ks.size and (not np.all(np.isfinite(ks)) or np.any(np.diff(ks) <= 0) or ks[0] < 1):
        raise ValueError("k must be increasing integers >= 1")
    if not np.all(np.isfinite(w) & (w > 0)):
        raise ValueError("widths must be finite and > 0")
    tail = check_count("tail", tail, 4)
    threshold = _v.real("threshold", threshold)
    if not threshold > 1.0:
        raise ValueError(f"threshold must be a number > 1, got {threshold}")
    pos = None
    if positions is not None:
        pos = np.asarray(positions, dtype=float)
        if pos.shape != ks.shape or not np.all(np.isfinite(pos)):
            raise ValueError(f"positions must be finite, one per member, got shape {pos.shape}")
    nan2 = (math.nan, math.nan)
    sel = slice(max(0, ks.size - tail), None)
    kt, wt = ks[sel], w[sel]
    used = tuple(int(a) for a in kt)
    if kt.size < 4:
        return CascadeLaw("undecided", math.nan, nan2, math.nan, nan2, math.nan, math.nan,
                          threshold, used)
    lw = np.log(wt)
    (_, slope_g), res_g = _line_fit(kt, lw)
    (_, slope_a), res_a = _line_fit(np.log(kt), lw)
    consecutive = np.diff(kt) == 1
    loc_r = (wt[1:] / wt[:-1])[consecutive]
    loc_g = (-np.log(wt[1:] / wt[:-1]) / np.log(kt[1:] / kt[:-1]))[consecutive]
    ratio, exponent = float(np.exp(slope_g)), float(-slope_a)
    r_int = (float(loc_r.min()), float(loc_r.max())) if loc_r.size else nan2
    g_int = (float(loc_g.min()), float(loc_g.max())) if loc_g.size else nan2
    floor = 1e-14  # residuals below rounding of log w are ties
    if max(res_g, floor) * threshold < max(res_a, floor):
        kind = "geometric"
    elif max(res_a, floor) * threshold < max(res_g, floor):
        kind = "algebraic"
    else:
        kind = "undecided"
    law = CascadeLaw(kind, ratio, r_int, exponent, g_int, res_g, res_a, threshold, used)
    if pos is None:
        return law
    # the positions' own law, decided the same way on the gaps between consecutive members
    # (a family that ends at finite k can shrink faster than any law while its members'
    # positions still approach the limit by one)
    pt_, kt_ = pos[sel], kt
    ok = np.diff(kt_) == 1
    gaps = np.abs(np.diff(pt_))[ok]
    kmid = (kt_[:-1] + 0.5)[ok]
    if gaps.size < 3 or not np.all(gaps > 0):
        return law
    (_, _), dg = _line_fit(kmid, np.log(gaps))
    (_, _), da = _line_fit(np.log(kmid), np.log(gaps))
    if max(dg, floor) * threshold < max(da, floor):
        approach_kind = "geometric"
    elif max(da, floor) * threshold < max(dg, floor):
        approach_kind = "algebraic"
    else:
        return law
    lims, pars = _limits(approach_kind, ks, pos)
    if lims.size == 0:
        return law
    lt, pt = lims[-tail:], pars[-tail:]
    return CascadeLaw(kind, ratio, r_int, exponent, g_int, res_g, res_a, threshold, used,
                      float(lt[-1]), (float(lt.min()), float(lt.max())),
                      float(pt[-1]), (float(pt.min()), float(pt.max())), approach_kind)


# --------------------------------------------------------------------------- #
# Known curves an accumulation point may lie on                               #
# --------------------------------------------------------------------------- #


def _known_curves(n_max=8):
    """u(e) of the families the paper and the package know in closed form."""
    from .nonsliding import one_impact_family

    curves = [("Corollary 2.1 no-sliding bound", lambda e: no_sliding_bound(e) if e > 0 else math.inf)]
    for n in range(1, n_max + 1):
        curves.append((f"neutral one-impact family u_{n}: one landing every {n} step(s) "
                       f"(sqrt({n}(1-e)/(2(1+e))))",
                       lambda e, n=n: one_impact_family(n, e) if 0 < e < 1 else math.sqrt(n / 2.0)))
        curves.append((f"tongue ({n}, 0^inf) upper edge (Theorem 3.1)",
                       lambda e, n=n: math.sqrt(n / 2.0) * (1 - e) / (1 + e)))
        if n > 1:
            curves.append((f"tongue ({n}, 0^inf) lower edge (Theorem 3.1)",
                           lambda e, n=n: math.sqrt((n - 1) / 2.0)))
    return curves


def _curve_at(curve, axis, fixed, lo, hi):
    """Where ``curve`` crosses the line, or None."""
    if axis == 1:
        x = curve(fixed)
        return x if lo <= x <= hi else None
    g_lo, g_hi = curve(lo) - fixed, curve(hi) - fixed
    if not (math.isfinite(g_lo) and math.isfinite(g_hi)) or (g_lo > 0) == (g_hi > 0):
        return None
    a, b = lo, hi
    for _ in range(200):  # every curve here is monotone in e
        m = 0.5 * (a + b)
        if m <= a or m >= b:
            break
        if (curve(m) - fixed > 0) == (g_lo > 0):
            a = m
        else:
            b = m
    return 0.5 * (a + b)


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
                 f"[{self.range[0]:g}, {self.range[1]:g}]: {len(self.members)} member(s)"]
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
            lines.append(f"accumulation (extrapolated): {self.axis} = {self.law.limit:.12g} in "
                         f"[{a:.12g}, {b:.12g}]; positions approach it {self.law.approach_kind}ally, "
                         f"{par} {self.law.approach:.4g} in "
                         f"[{self.law.approach_interval[0]:.4g}, {self.law.approach_interval[1]:.4g}]")
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
        from .structure.regions import word_region

        rows = self.members if ks is None else self.members[self.members.k.isin(list(ks))]
        return {int(r.k): word_region(r.word, e, u, resolution=resolution, max_iter=max_iter)
                for r in rows.itertuples()}

    def __repr__(self) -> str:
        return (f"Cascade({self.pattern!r}, {len(self.members)} members, last k={self.last}, "
                f"law={self.law.kind})")


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
# Families found                                                              #
# --------------------------------------------------------------------------- #


def _primitive(block) -> bool:
    """Whether ``block`` is no power of a shorter block."""
    b = len(block)
    return not any(b % d == 0 and block == block[:d] * (b // d) for d in range(1, b))


def _attachments(letters, block_max):
    """The decompositions ``P + X^m + S`` of one word with ``m >= 2``, ``X``
    primitive with a jump, each run taken once (from its first letter)."""
    out = []
    n = len(letters)
    for b in range(1, block_max + 1):
        i = 0
        while i + 2 * b <= n:
            x = letters[i:i + b]
            m = 1
            while letters[i + m * b:i + (m + 1) * b] == x:
                m += 1
            if m >= 2 and _primitive(x) and any(x):
                out.append(((letters[:i], x, letters[i + m * b:]), m))
                i += m * b
            else:
                i += 1
    return out


def _candidates(seen, min_members, block_max):
    """The candidate families ``(seen members, P, X, S)`` of a set of words
    (letter tuples) by block attachment, most members seen first."""
    families: dict = {}
    for letters in seen:
        for key, m in _attachments(letters, block_max):
            families.setdefault(key, set()).add(m)
    cands = []
    for (p, x, s), ks in families.items():
        # the exponents seen: those of the words' own runs, and k = 0, 1 (no run)
        pat = _Pattern("", "k", p, x, s)
        ks = ks | {k for k in (0, 1) if pat.letters(k) in seen}
        n_seen = len(ks)
        # the attachment itself (k >= 2) seen at least twice: k = 0, 1 alone are other words
        if n_seen >= min_members and sum(k >= 2 for k in ks) >= 2:
            cands.append((n_seen, p, x, s))
    cands.sort(key=lambda c: (-c[0], len(c[2]), len(c[1]) + len(c[3])))
    return cands


def _pattern_text(prefix, block, suffix, var="k"):
    body = f"{block[0]}^{var}" if len(block) == 1 else "(" + ", ".join(map(str, block)) + f")^{var}"
    return "(" + ", ".join([*map(str, prefix), body, *map(str, suffix), "0^inf"]) + ")"


def cascades(e, u, *, samples=2000, words=None, min_members=4, block_max=4, k_max=100, max_iter=1000,
             resolution=128, lines=3):
    """cascades(e, u, *, samples=2000, words=None, min_members=4, block_max=4, k_max=100, max_iter=1000, resolution=128, lines=3) -> pandas.DataFrame

    The families of words on a line of the plane, found by block attachment and
    then located exactly with :func:`cascade`; with both ``e`` and ``u`` ranges,
    the families of a window at two levels of nesting (below, "A window").

    The words seen on the line (``sliding_word`` at ``samples`` evenly spaced
    points, or ``words``: texts or :class:`stairbounce.Word`, e.g. a
    :func:`stairbounce.word_table`'s ``text``) are split every way as
    ``P + X^m + S`` with a primitive block ``X`` of at most ``block_max``
    letters repeated ``m >= 2`` times; each ``(P, X, S)`` is a candidate
    family ``(P, X^k, S, 0^inf)``, kept when at least ``min_members`` of the
    words seen are members (any k, two of them with k >= 2).  Each is then
    passed to :func:`cascade` on the line; families with fewer than
    ``min_members`` members found, or with the same members as one listed
    before, are left out.  Returns one row per family, most members first: ``pattern``,
    ``seen`` (members among the words seen), ``members`` (found exactly),
    ``k_first``, ``k_last``, ``stop``, ``law`` (kind), ``exponent`` and
    ``exponent_lo``/``exponent_hi``, ``ratio`` and ``ratio_lo``/``ratio_hi``
    (:func:`cascade_law` on the last 8 members), ``limit_lo``/``limit_hi``
    (the enclosure of the accumulation point, to rounding) and ``limit_name``.
    The candidates depend on the words seen (a sampled line); the members
    listed do not.

    A window (``e`` and ``u`` both ranges): the words are those of a scan of
    ``resolution`` x ``resolution`` pixel centres (the words of
    :func:`stairbounce.word_table` without its border points); each
    candidate family is located exactly with :func:`cascade` on up to
    ``lines`` lines e = const through the pixel columns where its members
    were seen (``e_line`` the one with most members, whose law is given;
    ``limit_curve`` the accumulation enclosures ``(e, lo, hi)`` on all of
    them: the accumulation point as a curve over e).  ``level`` is 1 for
    these; families of families are then found among them (level 2): the
    patterns whose run lengths differ by one free count ``n`` (e.g.
    ``((1^n, 0)^k, 1^(n+1), 0^inf)`` for n = 1, 2, 3, ..., at least three n
    seen); the level-1 family of every n = 1..8, seen or not, is then
    located on one line (that of the first family seen), and the row lists
    the n whose family has members and an accumulation enclosure there
    (``n_values``, ``members``), those enclosures (``limit_curve``), and the
    law of the accumulation points against n (:func:`cascade_law` on the
    gaps between consecutive ones, at least 5 of them; ``limit_lo`` /
    ``limit_hi`` the extrapolated accumulation of the accumulation points).
    Members' regions: :meth:`Cascade.regions`.

    Parameters
    ----------
    e, u : float, or (lo, hi)
        The line, as in :func:`cascade`.
    samples : int >= 2, default 2000
    words : iterable of str or Word, optional
    min_members : int >= 2, default 4
    block_max : int >= 1, default 4
    k_max, max_iter : as in :func:`cascade`.
    resolution : int >= 8, default 128
        A window only: pixels per side of the scan whose words are split.
    lines : int >= 1, default 3
        A window only: lines e = const each family is located on.
    """
    import pandas as pd

    from .symbolic import parse_word

    if _is_pair(e) and _is_pair(u):  # a window: its families at two levels (cascade_families)
        from .cascade_families import window_families

        if words is not None:
            raise ValueError("words: only for a line (one of e and u a number); a window's words "
                             "are those of its scan (resolution)")

        return window_families(e, u, min_members=min_members, block_max=block_max, k_max=k_max,
                               max_iter=max_iter, resolution=resolution, lines=lines)
    axis, name, lo, hi, fixed = _line_args(e, u)
    samples = check_count("samples", samples, 2, 10**6)
    min_members = check_count("min_members", min_members, 2)
    block_max = check_count("block_max", block_max, 1, 64)
    line = (lo, hi)
    if words is None:
        seen = set()
        for x in np.linspace(lo, hi, samples):
            w = sliding_word(*((float(x), fixed) if axis == 0 else (fixed, float(x))), max_iter)
            if w is not None:
                seen.add(w.letters)
    else:
        seen = {(w if isinstance(w, Word) else parse_word(w)).letters for w in words}
    rows, done = [], set()
    for n_seen, p, x, s in _candidates(seen, min_members, block_max):
        text = _pattern_text(p, x, s)
        c = cascade(text, **({"e": line, "u": fixed} if axis == 0 else {"e": fixed, "u": line}),
                    k_max=k_max, max_iter=max_iter)
        key = frozenset(c.members.word)
        if len(key) < min_members or key in done:
            continue
        done.add(key)
        law, enc = c.law, c.limit_enclosure
        rows.append({"pattern": text, "seen": n_seen, "members": len(c.members),
                     "k_first": int(c.members.k.iloc[0]), "k_last": int(c.members.k.iloc[-1]),
                     "stop": c.stop, "law": law.kind, "exponent": law.exponent,
                     "exponent_lo": law.exponent_interval[0], "exponent_hi": law.exponent_interval[1],
                     "ratio": law.ratio, "ratio_lo": law.ratio_interval[0], "ratio_hi": law.ratio_interval[1],
                     "limit_lo": enc[0] if enc else math.nan, "limit_hi": enc[1] if enc else math.nan,
                     "limit_name": c.limit_name})
    cols = ["pattern", "seen", "members", "k_first", "k_last", "stop", "law", "exponent", "exponent_lo",
            "exponent_hi", "ratio", "ratio_lo", "ratio_hi", "limit_lo", "limit_hi", "limit_name"]
    out = pd.DataFrame(rows, columns=cols)
    return out.sort_values(["members", "seen"], ascending=False, kind="stable").reset_index(drop=True)


# --------------------------------------------------------------------------- #
# The family of one word                                                      #
# --------------------------------------------------------------------------- #


class Family(tuple):
    """``(pattern, k)``: a word's family as :func:`family_of` names it."""

    __slots__ = ()

    def __new__(cls, pattern: str, k: int):
        return super().__new__(cls, (pattern, k))

    @property
    def pattern(self) -> str:
        return self[0]

    @property
    def k(self) -> int:
        return self[1]

    def __repr__(self) -> str:
        return f"Family(pattern={self[0]!r}, k={self[1]})"


def family_of(word) -> Family | None:
    """family_of(word) -> Family(pattern, k) or None

    The family a word belongs to by its form, written as a pattern that
    :func:`cascade` reads: the word's letters ``P + X^k + S`` with the run
    ``X^k`` of a repeated block chosen by the rule below, as
    ``"(P, X^k, S, 0^inf)"`` in the paper's notation; ``k`` is the word's
    exponent, so the word is member ``k`` of the family.

    The rule (a definition of the word's form, not a measurement): among the
    runs ``X^m`` of the letters with ``m >= 2``, ``X`` primitive (no power of a
    shorter block) and with a jump (a block of zeros would raise the impacts
    of one step, not a cascade of steps), each run taken from its first
    letter as far as it repeats (the attachments :func:`cascades` finds
    families by), the one covering the most letters (``m * len(X)``); among
    equal ones the shorter block, then the run that starts first.  ``None``
    when no such block repeats.

    Examples: ``(1, 1, 1, 0^inf)`` -> ``("(1^k, 0^inf)", 3)``;
    ``((1, 0), (1, 0), 1, 1, 0^inf)``, the letters (1, 0, 1, 0, 1, 1) ->
    ``("((1, 0)^k, 1, 1, 0^inf)", 2)`` (the run (1, 0)^2 covers four letters,
    1^2 two); ``(2, 0^inf)`` -> None.

    Parameters
    ----------
    word : Word, a sequence of letters or its text (``"(1, 1, 1, 0^inf)"``)

    Returns
    -------
    Family or None
        A named pair: ``pattern`` (str) and ``k`` (int >= 2).
    """
    from .structure.regions import _as_word

    letters = tuple(int(a) for a in _as_word(word).letters)
    runs = _attachments(letters, len(letters) // 2)
    if not runs:
        return None
    (prefix, block, suffix), m = max(runs, key=lambda r: (r[1] * len(r[0][1]), -len(r[0][1]), -len(r[0][0])))
    return Family(_pattern_text(prefix, block, suffix), m)
