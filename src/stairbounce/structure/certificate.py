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

from dataclasses import dataclass, field

import numpy as np

STATUSES = ("word", "no_sliding", "no_slide_within", "undecided", "sliding")
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
* ``sliding`` (atlases with ``classes=True``, ``structure/classes.py``): every
  point of the box slides within ``max_iter`` steps, with one of the listed words
  (both sides of the undecided decisions followed); no single itinerary.
* ``undecided``: ``reason`` says which decision could not be proven at
  ``step`` (1-based): ``"chatter"`` (the slide test), ``"graze"`` (the first
  impact, margin of impact 1), ``"edge"`` (a later impact), or another reason
  (documented where it is produced).
"""

REASONS = ("graze", "edge", "chatter")
"""The border events (the labels of ``sb.border_points``) an undecided box can stop at."""


@dataclass(frozen=True)
class Certificate:
    """What is proven over one box of the (e, u) plane, with the evidence.

    ``margins`` has one row ``(lo, hi)`` per decision taken, in order, and
    ``decisions`` names each (``"slide"`` or ``"impact j"``), so that a reader
    sees every sign that was decided and by how much.
    """

    e: tuple[float, float]
    u: tuple[float, float]
    max_iter: int
    status: str
    word: object | None = None  # stairbounce.Word when status == "word"
    reason: str | None = None  # when status == "undecided"
    step: int | None = None  # the undecided step (1-based)
    itinerary: tuple[int, ...] = ()
    decisions: tuple[str, ...] = ()
    margins: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    region: object | None = None  # structure.trapping.TrappingRegion when reason == "trapping"

    @property
    def proven(self) -> bool:
        """Whether the certificate states a theorem (every status but ``undecided``)."""
        return self.status != "undecided"

    def to_dict(self) -> dict:
        """The certificate as plain JSON types (floats written exactly by ``json``'s repr)."""
        return {
            "e": [float(self.e[0]), float(self.e[1])], "u": [float(self.u[0]), float(self.u[1])],
            "max_iter": int(self.max_iter), "status": self.status,
            "word": None if self.word is None else [int(a) for a in getattr(self.word, "letters")],
            "reason": self.reason, "step": self.step,
            "itinerary": [int(k) for k in self.itinerary], "decisions": list(self.decisions),
            "margins": [[float(lo), float(hi)] for lo, hi in np.asarray(self.margins).reshape(-1, 2)],
            **({"region": getattr(self.region, "to_dict")()} if self.region is not None else {}),
        }

    @classmethod
    def from_dict(cls, d: dict) -> Certificate:
        """The certificate of :meth:`to_dict` (nothing is re-checked: see the
        checker).  ``ValueError`` naming the member that is missing or not of
        its form (``e``, ``u``: two numbers; ``max_iter``: an integer;
        ``status``: text; ``itinerary``: integers; ``margins``: pairs)."""
        from ..symbolic import Word

        if not isinstance(d, dict):
            raise ValueError(f"a certificate dict is needed, got {type(d).__name__}")
        missing = [k for k in ("e", "u", "max_iter", "status") if k not in d]
        if missing:
            raise ValueError(f"certificate dict lacks {', '.join(missing)} (needs e, u, max_iter, status)")
        try:
            word = None if d.get("word") is None else Word(tuple(d["word"]))
        except (TypeError, ValueError) as exc:
            raise ValueError(f"certificate word must be a list of impact counts, got {d['word']!r} ({exc})") from None
        return cls(
            e=_pair("e", d["e"]), u=_pair("u", d["u"]),
            max_iter=_integer("max_iter", d["max_iter"]), status=_text("status", d["status"]),
            word=word, reason=d.get("reason"), step=d.get("step"),
            itinerary=_integers("itinerary", d.get("itinerary", ())),
            decisions=tuple(d.get("decisions", ())),
            margins=_margins(d.get("margins", [])),
            region=_region(d.get("region")),
        )


def _pair(name, v):
    """``(lo, hi)``: two numbers (not text), or ValueError naming ``name``."""
    try:
        if isinstance(v, (str, bytes)) or len(v) != 2:
            raise TypeError
        lo, hi = (float(x) for x in v)
    except (TypeError, ValueError):
        raise ValueError(f"certificate {name} must be a pair (lo, hi) of numbers, got {v!r}") from None
    return (lo, hi)


def _integer(name, v):
    if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)):
        raise ValueError(f"certificate {name} must be an integer, got {v!r}")
    return int(v)


def _text(name, v):
    if not isinstance(v, str):
        raise ValueError(f"certificate {name} must be text, got {v!r}")
    return v


def _integers(name, v):
    try:
        a = np.asarray(v)
        if a.ndim != 1 or (a.size and a.dtype.kind not in "iu"):
            raise TypeError
    except (TypeError, ValueError):
        raise ValueError(f"certificate {name} must be a list of integers, got {str(v)[:80]}") from None
    return tuple(int(k) for k in a)


def _margins(v):
    try:
        return np.array(v, dtype=np.float64).reshape(-1, 2)
    except (TypeError, ValueError):
        raise ValueError(f"certificate margins must be pairs (lo, hi) of numbers, got {str(v)[:80]}") from None


def check_certificate_fields(cert) -> None:
    """check_certificate_fields(cert) -> None: ``ValueError`` naming the field of
    ``cert`` that is not of its form (``e``, ``u`` two numbers, ``max_iter`` an
    integer, ``status`` text): what the checker needs before it can judge the
    claim (a claim of the right form but false is a rejected verdict, not an
    error)."""
    _pair("e", cert.e)
    _pair("u", cert.u)
    _integer("max_iter", cert.max_iter)
    _text("status", cert.status)


def _region(d):
    if d is None:
        return None
    from .trapping import TrappingRegion

    return TrappingRegion.from_dict(d)
