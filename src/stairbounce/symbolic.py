"""Words of periodic sliding solutions (Section 3 of the paper, docs/design.md).

A word lists the jump numbers between consecutive impacts, starting from the
ball's departure at ``(1, 0)`` (it has just slid off an edge).  Landing on the
step right below is a jump of 1; a step with ``k >= 1`` impacts contributes its
jump and then ``k - 1`` zeros; the step where the impacts accumulate contributes
its jump and the accumulation tail ``0^inf``, which is not a letter.
"""

from __future__ import annotations

import math
import re
import sys
import warnings
from dataclasses import dataclass

import numpy as np
from numba import njit

from . import _validate as _v
from .model import SLIDING, _constants, _step, check_count, check_e, check_u, no_sliding_bound

__all__ = ["SlidingAnswer", "Word", "sliding_answer", "sliding_word", "parse_word"]

INFINITY = "\u221e"
# longest word text parse_word reads: a million characters (regular expression
# and integer conversion stay linear and fast)
_MAX_WORD_TEXT = 10**6
# steps iterated per call of the compiled kernel in sliding_word: the steps'
# impact numbers are kept only up to the slide, and a long search can be
# interrupted between blocks
_BLOCK = 1 << 16


@dataclass(frozen=True)
class Word:
    """The word of a periodic sliding solution, tail ``0^inf`` left out.

    ``letters`` are the jump numbers; ``period`` (steps per period) is their
    sum and ``impacts`` (finite impacts per period) is ``len(word) - 1``: every
    letter but the last one ends in an impact, the last one in the accumulation.
    """

    letters: tuple[int, ...]

    def __post_init__(self):
        if isinstance(self.letters, (str, bytes)) or not isinstance(self.letters, (tuple, list, np.ndarray)):
            raise ValueError(f"letters must be a tuple of integer jump numbers, got {self.letters!r}")
        letters = tuple(self.letters)
        if not all(type(a) is int and 0 <= a <= _v._INT64_MAX for a in letters):
            # the general check (numpy integers, integral floats; names the bad letter)
            letters = tuple(check_count(f"letters[{i}]", a, 0) for i, a in enumerate(letters))
        if not letters or letters[0] < 1 or letters[-1] < 1 or min(letters) < 0:
            raise ValueError(
                "letters must be non-negative jump numbers, the first and last >= 1, "
                f"got {letters}"
            )
        object.__setattr__(self, "letters", letters)

    @property
    def period(self) -> int:
        """Steps per period: the sum of the jump numbers."""
        return sum(self.letters)

    @property
    def impacts(self) -> int:
        """Finite impacts per period (the accumulation not counted)."""
        return len(self.letters) - 1

    @property
    def jumps(self) -> int:
        """Non-zero letters: the steps of a period on which the ball lands."""
        return sum(1 for a in self.letters if a)

    def __len__(self) -> int:
        return len(self.letters)

    def format(self, ascii: bool = False) -> str:
        """``(2, 0, 3, 1, 0^inf)``, with the infinity sign unless ``ascii``."""
        tail = "0^inf" if ascii else "0^" + INFINITY
        return "(" + ", ".join([*map(str, self.letters), tail]) + ")"

    def __str__(self) -> str:
        return self.format()


def parse_word(text: str) -> Word:
    """Read a word written as in the paper, ``(2, 0, 3, 1, 0^inf)`` (or with the
    infinity sign), or its letters alone, ``(2, 0, 3, 1)`` (the tail left out,
    as :class:`Word` keeps them); both give the same :class:`Word`."""
    if not isinstance(text, str):
        raise ValueError(f"word must be a string like (2, 0, 3, 1, 0^inf), got {text!r}")
    if len(text) > _MAX_WORD_TEXT:
        raise ValueError(f"word must be at most {_MAX_WORD_TEXT} characters long, got {len(text)}")
    m = (re.fullmatch(r"\s*\(\s*((?:\d+\s*,\s*)+)0\^(?:inf|\u221e)\s*\)\s*", text)
         or re.fullmatch(r"\s*\(\s*(\d+(?:\s*,\s*\d+)*)\s*,?\s*\)\s*", text))
    if not m:
        raise ValueError(f"word must look like (2, 0, 3, 1, 0^inf) or (2, 0, 3, 1), got {text!r}")
    letters = [a.strip() for a in m.group(1).split(",") if a.strip()]
    if any(len(a) > 18 for a in letters):  # int64, as the scan stores them
        raise ValueError(f"word letters must be below 10^18, got {text[:60]!r}...")
    return Word(tuple(int(a) for a in letters))


def terminal_can_print_infinity(stream=None) -> bool:
    """Whether ``stream`` (default stdout) can encode the infinity sign."""
    enc = getattr(stream or sys.stdout, "encoding", None) or "ascii"
    try:
        INFINITY.encode(enc)
    except (UnicodeEncodeError, LookupError):
        return False
    return True


@njit(cache=True)
def _impacts_until_slide(y, v, e, T, ratio, max_steps, ks):
    """Impact numbers of the steps from ``(y, v)`` up to the first slide.

    Fills ``ks[:n]`` and returns ``(n, y, v)``: ``n`` is the step count
    including the sliding step, or 0 when the orbit does not slide within
    ``max_steps`` steps, and ``(y, v)`` the state reached.
    """
    for n in range(max_steps):
        y, v, k = _step(y, v, e, T, ratio)
        ks[n] = k
        if k == SLIDING:
            return n + 1, y, v
    return 0, y, v


def word_from_impacts(impacts) -> Word:
    """The word of one period from the impact numbers of its steps, the last
    one ``SLIDING`` (docs/design.md's convention)."""
    letters = []
    jump = 0
    for k in impacts:
        jump += 1
        if k == 0:
            continue
        letters.append(jump)
        jump = 0
        if k == SLIDING:
            return Word(tuple(letters))
        letters.extend([0] * (int(k) - 1))
    raise ValueError("impacts must end with a sliding step (SLIDING)")


def sliding_word(e, u, max_iter=1000, *, max_steps=None):
    """sliding_word(e, u, max_iter=1000) -> Word | None

    The periodic sliding solution through ``(1, 0)``, as a word.

    Every sliding solution passes through ``(1, 0)`` (it slides off an edge
    with zero vertical velocity), so a periodic sliding solution exists exactly
    when the orbit of ``(1, 0)`` under the Poincare map (Prop. 2.3) slides
    again; the sliding test (2.3)/(2.4) is the stop criterion of Section 3.

    Parameters
    ----------
    e : float in [0, 1)
    u : float > 0
    max_iter : int >= 1, default 1000
        Steps to iterate before giving up (``max_steps``, its old name, is
        still read, with a DeprecationWarning).

    Returns
    -------
    Word or None
        ``None`` when the orbit does not slide within ``max_iter`` steps.
    """
    e = check_e(e)
    T, ratio = _constants(e, check_u(u))
    max_iter = check_count("max_iter", _v.renamed("max_steps", max_steps, "max_iter", max_iter, 1000), 1)
    # blocks of _BLOCK steps: memory grows with the period found, not with
    # max_iter, and Ctrl-C is seen between blocks
    block = np.empty(min(max_iter, _BLOCK), dtype=np.int64)
    done = []
    y, v, left = 1.0, 0.0, max_iter
    while left > 0:
        m = min(left, block.size)
        n, y, v = _impacts_until_slide(y, v, e, T, ratio, m, block)
        if n:
            return word_from_impacts(np.concatenate([*done, block[:n]]))
        done.append(block[:m].copy())
        left -= m
    return None


@dataclass(frozen=True, repr=False)
class SlidingAnswer:
    """Whether a periodic sliding solution exists at ``(e, u)``, and why; see
    :func:`sliding_answer`.

    ``verdict`` is ``"found"`` (``word`` is its word), ``"impossible"``
    (proven by Corollary 2.1: ``u`` lies above ``bound``, so the orbit of
    ``(1, 0)`` never slides again; nothing was iterated) or ``"not found"``
    (below the bound, but the orbit did not slide within ``max_iter``
    steps: not a proof).  ``bound`` is the Corollary 2.1 speed
    ``(1-e)/(2 sqrt(2e))`` below which sliding is possible (``inf`` at
    ``e = 0``); ``speed_bound`` is the same in m/s when ``u`` was given as a
    :class:`stairbounce.Speed` on a staircase, else None.
    """

    e: float
    u: float
    max_iter: int
    verdict: str
    word: Word | None
    bound: float
    speed_bound: float | None = None

    @property
    def found(self) -> bool:
        return self.word is not None

    @property
    def max_steps(self) -> int:
        """The old name of ``max_iter`` (deprecated)."""
        warnings.warn("SlidingAnswer.max_steps is deprecated: use max_iter", DeprecationWarning, stacklevel=2)
        return self.max_iter

    def text(self, ascii: bool = False) -> str:
        """One sentence: the word, or the proof, or the search that failed."""
        if self.word is not None:
            return f"word {self.word.format(ascii=ascii)}: period {self.word.period}"
        need = (f"sliding needs U < {self.speed_bound:.4g} m/s" if self.speed_bound is not None
                else f"sliding needs u < {self.bound:.6g}")
        if self.verdict == "impossible":
            return f"impossible (Corollary 2.1: u >= {self.bound:.6g} at e = {self.e:g}); {need}"
        return (f"no periodic sliding solution found within {self.max_iter} steps (the orbit of "
                f"(1, 0) does not slide; "
                f"Corollary 2.1 does not exclude it: {need})")

    def __repr__(self) -> str:
        text = self.text(ascii=True)
        if self.word is not None and len(text) > 60:
            text = f"word of length {len(self.word)}, period {self.word.period}"
        return f"SlidingAnswer(e={self.e:g}, u={self.u:g}: {text})"


def sliding_answer(e, u, max_iter=1000, *, max_steps=None):
    """sliding_answer(e, u, max_iter=1000) -> SlidingAnswer

    :func:`sliding_word`, with what the paper proves when there is no word.

    Above the Corollary 2.1 curve (by the rounding margin of
    :func:`stairbounce.prunable`, the test a scan prunes on) no solution
    slides: the verdict is ``"impossible"`` and nothing is iterated.
    Otherwise the orbit of ``(1, 0)`` is iterated for up to ``max_iter``
    steps: ``"found"`` with its word, or ``"not found"`` (``max_steps``, the
    old name of ``max_iter``, is still read, with a DeprecationWarning).  Given a
    :class:`stairbounce.Speed` (``staircase.speed(U)``), the answer also
    carries the bound in m/s, ``speed_bound``: the speed below which sliding
    becomes possible.

    >>> import stairbounce as sb
    >>> sb.sliding_answer(0.7, 0.5).verdict
    'impossible'
    >>> stairs = sb.Staircase(0.17, 0.28)
    >>> print(sb.sliding_answer(0.7, stairs.speed(1.5)).text())
    impossible (Corollary 2.1: u >= 0.126773 at e = 0.7); sliding needs U < 0.2696 m/s
    """
    from .plane import prunable
    from .units import staircase_of

    e = check_e(e)
    stairs = staircase_of(u)
    u_value = check_u(u)
    max_iter = check_count("max_iter", _v.renamed("max_steps", max_steps, "max_iter", max_iter, 1000), 1)
    bound = no_sliding_bound(e)
    speed_bound = None
    if stairs is not None and math.isfinite(bound):
        speed_bound = bound * stairs.speed_unit
    if bool(prunable(e, u_value)):
        return SlidingAnswer(e, u_value, max_iter, "impossible", None, bound, speed_bound)
    w = sliding_word(e, u_value, max_iter)
    return SlidingAnswer(e, u_value, max_iter, "found" if w is not None else "not found", w, bound,
                         speed_bound)
