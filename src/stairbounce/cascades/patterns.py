"""Patterns: a family of words written with one block raised to a free exponent, the
impact numbers its letters describe, their lexicographic order, and the form of a word
(the block attachments that name its family).  Moved verbatim from ``cascades.py``."""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..model import SLIDING
from ..symbolic import Word

__all__ = ["Family", "family_of", "word_impacts"]

# longest pattern text read, and most letters a pattern may write: every item, nested
# groups expanded, the free block once (memory and time grow with them; a million
# letters is far beyond any cascade on a line; issue 45 item 2: on the whole pattern,
# not per item)
_MAX_PATTERN_TEXT = 1000
_MAX_LETTERS = 10**6
# most work one call may do, in steps followed by its searches: each search bisects a
# line (about 60 trials), every trial following the member's steps and impacts, so one
# unit is one step of a member searched once (about 2 microseconds on one core: the
# limit is about a minute at worst); estimated before the work starts (_check_work)
_MAX_WORK = 3 * 10**7
# most letters the decompositions of the words seen may copy (memory: 8 bytes each)
_MAX_COPIES = 5 * 10**7
# impact number standing for "slides" in the lexicographic order
_SLIDE_RANK = np.iinfo(np.int64).max


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

    @cached_property
    def costs(self) -> tuple[int, int]:
        """:func:`_cost` of the prefix and suffix together, and of the block."""
        return _cost(self.prefix) + _cost(self.suffix), _cost(self.block)

    @cached_property
    def k_first(self) -> int:
        """The first exponent whose letters make a word: 0, or 1 where member 0
        has no letters or a leading zero (as :meth:`word` decides, without
        building it)."""
        fixed = self.prefix + self.suffix
        return 0 if fixed and fixed[0] >= 1 else 1

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


_TOKEN = re.compile(r"\s*(?:([0-9]+)|(inf|\u221e)|([A-Za-z_]\w*)|([(),^]))", re.ASCII)


def _parse_pattern(text) -> _Pattern:
    """Read a pattern such as ``((1, 0)^k, 1, 1, 0^inf)``; ValueError otherwise.
    A :class:`_Pattern` (the families' candidates, whose text may pass
    ``_MAX_PATTERN_TEXT``) is returned as it is."""
    if isinstance(text, _Pattern):
        return text
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
                letters = _expand_all(seq(False), text, rule)
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
    block = items[i][0]
    _letter_count(items[:i] + [(block, 1)] + items[i + 1:], text)  # the whole pattern, before expanding
    prefix = _expand_all(items[:i], text, rule)
    suffix = _expand_all(items[i + 1:], text, rule)
    if not block:
        raise ValueError(f"{rule}: the raised block is empty, got {text!r}")
    return _Pattern(text.strip(), items[i][1], prefix, block, suffix)


def _letter_count(items, text):
    """The letters ``items`` ((letters, exponent) pairs) write, refused above
    ``_MAX_LETTERS`` before anything is expanded."""
    n = sum(len(letters) * exp for letters, exp in items if not isinstance(exp, str))
    if n > _MAX_LETTERS:
        shown = text if len(text) <= 80 else text[:77] + "..."
        raise ValueError(f"pattern must write at most {_MAX_LETTERS} letters in all (every item, nested "
                         f"groups expanded, the free block once), got {n} in {shown!r}")
    return n


def _expand_all(items, text, rule):
    """The letters of ``items``, one tuple, after the whole count is checked."""
    for _, exp in items:
        if isinstance(exp, str):
            raise ValueError(f"{rule}: exactly one free exponent, at the top level, got {text!r}")
    _letter_count(items, text)
    return tuple(a for letters, exp in items for a in letters * exp)


def _cost(letters) -> int:
    """Steps and impacts a trial follows along ``letters``: a jump ``a`` flies over
    ``a`` steps, a zero adds one impact."""
    return sum(max(int(a), 1) for a in letters)


def _member_cost(pat, k_max, *, one=False) -> int:
    """:func:`_cost` of members ``k_first..k_max`` of ``pat`` summed (of member
    ``k_max`` alone with ``one``), in closed form (a member's trailing zeros,
    dropped into the tail, are counted: an upper bound)."""
    c_fixed, c_block = pat.costs
    if one:
        return c_fixed + c_block * k_max
    k0 = pat.k_first
    if k_max < k0:
        return 0
    n = k_max - k0 + 1
    return n * c_fixed + c_block * (k0 + k_max) * n // 2


def _check_work(what, work, hint):
    """Refuse a call whose estimated work (steps followed by its searches,
    ``_MAX_WORK``) is above the limit, naming ``what`` (its arguments); ``hint``
    a callable giving what to change."""
    if work > _MAX_WORK:
        hint = hint()
        raise ValueError(f"{what}: its searches would follow about {work:.2g} steps (each member's steps "
                         f"and impacts once per search), more than the limit {_MAX_WORK:.0e} (about a "
                         f"minute); {hint}")
    return work


def _lower_k(work_of, other):
    """What to change: the largest k_max within the limit, or that none is."""
    k = _largest_k(work_of)
    return (f"lower k_max (at most {k} here){other}" if k >= 1 else
            f"no k_max >= 1 is within it: shorten the pattern's letters{other}")


def _largest_k(work_of) -> int:
    """The largest k_max (0: none) whose work ``work_of(k_max)`` (non-decreasing
    in k_max) stays within ``_MAX_WORK``, by bisection."""
    lo, hi = 0, 10**7
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if work_of(mid) <= _MAX_WORK:
            lo = mid
        else:
            hi = mid - 1
    return lo


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
# Families found                                                              #
# --------------------------------------------------------------------------- #


def _primitive(block) -> bool:
    """Whether ``block`` is no power of a shorter block."""
    b = len(block)
    return not any(b % d == 0 and block == block[:d] * (b // d) for d in range(1, b))


def _attachment_spans(letters, block_max):
    """``(i, b, m)`` of each run ``X^m`` (``X = letters[i:i + b]``) that
    :func:`_attachments` lists, without copying the letters."""
    out = []
    n = len(letters)
    for b in range(1, block_max + 1):
        i = 0
        while i + 2 * b <= n:
            x = letters[i:i + b]
            if not (_primitive(x) and any(x)):  # before counting the run: linear, not quadratic, in n
                i += 1
                continue
            m = 1
            while letters[i + m * b:i + (m + 1) * b] == x:
                m += 1
            if m >= 2:
                out.append((i, b, m))
                i += m * b
            else:
                i += 1
    return out


def _attachments(letters, block_max, spans=None):
    """The decompositions ``P + X^m + S`` of one word with ``m >= 2``, ``X``
    primitive with a jump, each run taken once (from its first letter)."""
    spans = _attachment_spans(letters, block_max) if spans is None else spans
    return [((letters[:i], letters[i:i + b], letters[i + m * b:]), m) for i, b, m in spans]


def _candidates(seen, min_members, block_max):
    """The candidate families ``(seen members, P, X, S)`` of a set of words
    (letter tuples) by block attachment, most members seen first."""
    families: dict = {}
    spans = {letters: _attachment_spans(letters, block_max) for letters in seen}
    # every decomposition copies its word's letters: the copies counted before they are made
    copies = sum(len(sp) * len(letters) for letters, sp in spans.items())
    if copies > _MAX_COPIES:
        raise ValueError(f"words: their decompositions P + X^m + S would copy {copies:.2g} letters, more "
                         f"than the limit {_MAX_COPIES:.0e}; give fewer or shorter words (or a smaller block_max)")
    for letters in seen:
        for key, m in _attachments(letters, block_max, spans[letters]):
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
    from ..structure.regions import _as_word

    letters = tuple(int(a) for a in _as_word(word).letters)
    runs = _attachments(letters, len(letters) // 2)
    if not runs:
        return None
    (prefix, block, suffix), m = max(runs, key=lambda r: (r[1] * len(r[0][1]), -len(r[0][1]), -len(r[0][0])))
    return Family(_pattern_text(prefix, block, suffix), m)
