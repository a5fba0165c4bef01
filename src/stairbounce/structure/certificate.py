"""The certificate of one parameter box: what is proven over it, and its evidence.

A box ``B = [e0, e1] x [u0, u1]`` of the (e, u) plane (a point when ``e0 == e1``
and ``u0 == u1``).  Because a slide resets the state exactly to the edge state
``(1, 0)``, "the periodic sliding solution through (1, 0) has word W at every
point of B" is a finite list of sign decisions over B; a certificate lists them.

Decisions, per step of the Poincare map from ``(y, v)`` (``s = sqrt(v^2 + 2y)``,
``T = 1/u``, ``ratio = (1+e)/(1-e)``), each a *margin* ``m`` whose sign is the
decision (``m >= 0``: the event happens; equality counts as happening, the
convention of the map, docs/design.md):

* ``"slide"``:  ``m = T - (v + ratio * s)``; ``m >= 0``: the impacts accumulate
  before the edge (Prop. 2.1, test (2.4)); the step's impact number is SLIDING.
* ``"impact"`` number j (j = 1, 2, ...): ``m = T - t_j`` with ``t_1 = v + s``,
  ``t_{j+1} = t_j + 2 e^j s`` (eq. (2.2)); ``m >= 0``: the j-th impact is on the
  step.  A step with impact number k (0 <= k) has the slide decision < 0, the
  impact decisions 1..k >= 0 and the impact decision k+1 < 0.

A decision is *proven* when the enclosure ``[lo, hi]`` of its margin over the
whole box has ``lo >= 0`` (happens everywhere) or ``hi < 0`` (nowhere).

The itinerary is the list of impact numbers of the decided steps, in order
(0: flies over, k >= 1: k impacts, -1 = SLIDING: the step ends in a slide).

Array form (what atlases store and what the batch checker reads), for N boxes:
``e0, e1, u0, u1`` (float64, N), ``status`` (int8, N: index into STATUSES),
``max_iter`` (int), ``itinerary`` (int64, flat: all boxes' itineraries one
after the other) and ``offsets`` (int64, N + 1: box i's itinerary is
``itinerary[offsets[i]:offsets[i+1]]``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

STATUSES = ("word", "no_sliding", "no_slide_within", "undecided")
"""What a certificate states about its box (index = the status code in arrays).

* ``word``: every point of the box has the periodic sliding solution through
  (1, 0) with ``word``: the itinerary ends with the slide (-1), and every
  decision on the way is proven.
* ``no_sliding``: no periodic sliding solution at any point of the box, proven
  either by Corollary 2.1 over the whole box (``u0 > (1 - e0) / (2 sqrt(2
  e0))``, enclosed: no state with ``y >= 1`` slides at all; ``reason`` None) or,
  with ``reason == "trapping"``, by a trapping region
  (``structure/trapping.py``: the orbit of (1, 0) never slides, so no
  periodic sliding solution; ``itinerary`` is the entry, ``region`` the
  region).
* ``no_slide_within``: proven that the orbit of (1, 0) does not slide in the
  first ``max_iter`` steps anywhere in the box (a finite claim): the itinerary
  has ``max_iter`` entries, none -1.
* ``undecided``: ``reason`` says which decision could not be proven at
  ``step`` (1-based): ``"chatter"`` (the slide test), ``"graze"`` (the first
  impact, margin of impact 1), ``"edge"`` (a later impact), or another reason
  (documented where it is produced).
"""

REASONS = ("graze", "edge", "chatter")
"""The border events (the labels of ``sb.border_points``) an undecided box can stop at."""


class Decisions(Sequence):
    """The names of a certificate's decisions, kept as codes and named on demand.

    ``codes`` (int64, read-only): 0 for ``"slide"``, ``j >= 1`` for
    ``"impact j"`` (the certifier's record, :func:`stairbounce.certify_box`).
    A sequence of str like the tuple it stands for: ``len``, indexing (a slice
    gives a ``Decisions``), iteration, and ``==`` with another ``Decisions``
    or any sequence of the same names.  A certificate of a million steps keeps
    one array, not some four million strings.
    """

    __slots__ = ("codes",)

    def __init__(self, codes):
        codes = np.array(codes, dtype=np.int64).ravel()
        if codes.size and codes.min() < 0:
            raise ValueError(f"decision codes must be >= 0 (0: slide, j: impact j), got {int(codes.min())}")
        codes.setflags(write=False)
        self.codes = codes

    @staticmethod
    def name(code: int) -> str:
        """The name of one decision code."""
        return "slide" if code == 0 else f"impact {int(code)}"

    def __len__(self) -> int:
        return int(self.codes.size)

    def __getitem__(self, i):
        if isinstance(i, slice):
            return Decisions(self.codes[i])
        return self.name(int(self.codes[i]))

    def __iter__(self):
        return (self.name(c) for c in self.codes.tolist())

    def __eq__(self, other) -> bool:
        if isinstance(other, Decisions):
            return bool(np.array_equal(self.codes, other.codes))
        if isinstance(other, Sequence) and not isinstance(other, (str, bytes)):
            return len(other) == len(self) and all(a == b for a, b in zip(self, other))
        return NotImplemented

    __hash__ = None

    def __repr__(self) -> str:
        head = ", ".join(repr(x) for x in self[:4])
        return f"Decisions({len(self)}: {head}{', ...' if len(self) > 4 else ''})"


@dataclass(frozen=True)
class Certificate:
    """What is proven over one box of the (e, u) plane, with the evidence.

    ``margins`` has one row ``(lo, hi)`` per decision taken, in order, and
    ``decisions`` names each (``"slide"`` or ``"impact j"``), so that a reader
    sees every sign that was decided and by how much: a tuple of str, or (from
    :func:`stairbounce.certify_box`) a :class:`Decisions`, the same names kept
    as an int array and spelled out when read.
    """

    e: tuple[float, float]
    u: tuple[float, float]
    max_iter: int
    status: str
    word: object | None = None  # stairbounce.Word when status == "word"
    reason: str | None = None  # when status == "undecided"
    step: int | None = None  # the undecided step (1-based)
    itinerary: tuple[int, ...] = ()
    decisions: tuple[str, ...] | Decisions = ()
    margins: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    region: object | None = None  # structure.trapping.TrappingRegion when reason == "trapping"

    @property
    def proven(self) -> bool:
        """Whether the certificate states a theorem (every status but ``undecided``)."""
        return self.status != "undecided"

    def to_dict(self) -> dict:
        """The certificate as plain JSON types (floats written exactly by ``json``'s repr).

        Decisions held as codes (:class:`Decisions`) are written as
        ``"decision_codes"`` (ints), others as ``"decisions"`` (names);
        :meth:`from_dict` reads either."""
        coded = isinstance(self.decisions, Decisions)
        return {
            "e": [float(self.e[0]), float(self.e[1])], "u": [float(self.u[0]), float(self.u[1])],
            "max_iter": int(self.max_iter), "status": self.status,
            "word": None if self.word is None else [int(a) for a in getattr(self.word, "letters")],
            "reason": self.reason, "step": self.step,
            "itinerary": [int(k) for k in self.itinerary],
            **({"decision_codes": self.decisions.codes.tolist()} if coded else {"decisions": list(self.decisions)}),
            "margins": [[float(lo), float(hi)] for lo, hi in np.asarray(self.margins).reshape(-1, 2)],
            **({"region": getattr(self.region, "to_dict")()} if self.region is not None else {}),
        }

    @classmethod
    def from_dict(cls, d: dict) -> Certificate:
        """The certificate of :meth:`to_dict` (nothing is re-checked: see the checker)."""
        from ..symbolic import Word

        return cls(
            e=(float(d["e"][0]), float(d["e"][1])), u=(float(d["u"][0]), float(d["u"][1])),
            max_iter=int(d["max_iter"]), status=str(d["status"]),
            word=None if d.get("word") is None else Word(tuple(d["word"])),
            reason=d.get("reason"), step=d.get("step"),
            itinerary=tuple(int(k) for k in d.get("itinerary", ())),
            decisions=(Decisions(d["decision_codes"]) if "decision_codes" in d else tuple(d.get("decisions", ()))),
            margins=np.array(d.get("margins", []), dtype=np.float64).reshape(-1, 2),
            region=_region(d.get("region")),
        )


def _region(d):
    if d is None:
        return None
    from .trapping import TrappingRegion

    return TrappingRegion.from_dict(d)
