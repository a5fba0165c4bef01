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

from .. import _validate as _v

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

    __hash__ = None  # type: ignore[assignment]  # mutable-looking equality: not hashable

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
        decisions = ({"decision_codes": self.decisions.codes.tolist()} if isinstance(self.decisions, Decisions)
                     else {"decisions": list(self.decisions)})
        return {
            "e": [float(self.e[0]), float(self.e[1])], "u": [float(self.u[0]), float(self.u[1])],
            "max_iter": int(self.max_iter), "status": self.status,
            "word": None if self.word is None else [int(a) for a in getattr(self.word, "letters")],
            "reason": self.reason, "step": self.step,
            "itinerary": [int(k) for k in self.itinerary],
            **decisions,
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
            e=_field_pair("e", d["e"]), u=_field_pair("u", d["u"]),
            max_iter=_integer("max_iter", d["max_iter"]), status=_text("status", d["status"]),
            word=word, reason=d.get("reason"), step=d.get("step"),
            itinerary=_integers("itinerary", d.get("itinerary", ())),
            decisions=(Decisions(d["decision_codes"]) if "decision_codes" in d else tuple(d.get("decisions", ()))),
            margins=_margins(d.get("margins", [])),
            region=_region(d.get("region")),
        )


def _field_pair(name, v):
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
    _field_pair("e", cert.e)
    _field_pair("u", cert.u)
    _integer("max_iter", cert.max_iter)
    _text("status", cert.status)


def _region(d):
    if d is None:
        return None
    return TrappingRegion.from_dict(d)


def _cell_edge(lo, width, hi, i, n):
    """The ``i``-th of the ``n + 1`` edges of a grid axis ``[lo, hi]``."""
    if i >= n:
        return hi
    return lo + width * (float(i) * (1.0 / n))


@dataclass(frozen=True)
class TrappingRegion:
    """A proven trapping region of the box ``e x u`` (:func:`trapping_region`).

    ``itinerary``: the entry, the impact numbers of the decided steps of the
    orbit of (1, 0) before it is in the region; ``grid = (v_lo, v_hi, nv,
    s_lo, s_hi, ns)``: the rectangle of the ``(v, s)`` plane cut into
    ``nv x ns`` cells, cell ``(i, j)`` being ``[edge_v(i), edge_v(i+1)] x
    [edge_s(j), edge_s(j+1)]`` with ``edge(i) = lo + (hi - lo) * (i * (1/n))``
    (``hi`` for ``i = n``), floats; ``cells``: the region, the cells' indices
    ``j * nv + i``, sorted; ``entry``: the enclosure ``(v0, v1, s0, s1)`` of the
    state after the entry.
    """

    e: tuple[float, float]
    u: tuple[float, float]
    itinerary: tuple[int, ...]
    grid: tuple[float, float, int, float, float, int]
    cells: np.ndarray
    entry: tuple[float, float, float, float]

    def boxes(self):
        """The region's cells as an ``(n, 4)`` array of ``(v0, v1, s0, s1)``."""
        v_lo, v_hi, nv, s_lo, s_hi, ns = self.grid
        i = self.cells % nv
        j = self.cells // nv
        ev = np.array([_cell_edge(v_lo, v_hi - v_lo, v_hi, k, nv) for k in range(nv + 1)])
        es = np.array([_cell_edge(s_lo, s_hi - s_lo, s_hi, k, ns) for k in range(ns + 1)])
        return np.stack([ev[i], ev[i + 1], es[j], es[j + 1]], axis=1)

    def to_dict(self):
        """The region as plain JSON types (floats exact by ``json``'s repr)."""
        return {"e": list(map(float, self.e)), "u": list(map(float, self.u)),
                "itinerary": [int(k) for k in self.itinerary],
                "grid": [float(self.grid[0]), float(self.grid[1]), int(self.grid[2]),
                         float(self.grid[3]), float(self.grid[4]), int(self.grid[5])],
                "cells": [int(c) for c in self.cells], "entry": list(map(float, self.entry))}

    @classmethod
    def from_dict(cls, d):
        """The region of :meth:`to_dict` (nothing re-checked: see ``sb.verify``)."""
        g = d["grid"]
        return cls(e=(float(d["e"][0]), float(d["e"][1])), u=(float(d["u"][0]), float(d["u"][1])),
                   itinerary=tuple(int(k) for k in d["itinerary"]),
                   grid=(float(g[0]), float(g[1]), int(g[2]), float(g[3]), float(g[4]), int(g[5])),
                   cells=np.asarray(d["cells"], dtype=np.int64), entry=tuple(map(float, d["entry"])))


# --------------------------------------------------------------------------- #
# The arguments of a box and of a window                                      #
# --------------------------------------------------------------------------- #


def _pair(name, value):
    if isinstance(value, (str, bytes)) or not isinstance(value, (tuple, list, np.ndarray)) or len(value) != 2:
        raise ValueError(f"{name} must be a pair ({name}0, {name}1) of real numbers, got {_v._show(value)}")
    return _v.real(f"{name}0", value[0]), _v.real(f"{name}1", value[1])


def _check_e(e, window=False, zero=False):
    """``(e0, e1)`` with ``0 < e0 <= e1 < 1`` (a box; ``0 <= e0`` with ``zero``, a box
    the corners form certifies) or ``0 <= e0 < e1 <= 1`` (a window, whose boxes
    touching e = 1 are undecided "range", and those touching e = 0 too for a form
    other than the corners), each 0 or >= 2^-53."""
    e0, e1 = _pair("e", e)
    zero = zero or window  # may e0 be 0
    top = "<= 1" if window else "< 1"
    rule = f"e must be a pair (e0, e1) with 0 {'<=' if zero else '<'} e0 {'<' if window else '<='} e1 {top}"
    if not ((0.0 <= e0 if zero else 0.0 < e0) and (e1 <= 1.0 if window else e1 < 1.0)):
        raise ValueError(f"{rule} (restitution coefficients), got ({e0}, {e1})")
    if not (e0 < e1 if window else e0 <= e1):
        raise ValueError(f"{rule}: {'an empty' if e0 == e1 else 'a reversed'} range, got ({e0}, {e1})")
    for x in (e0, e1):
        if _v.e_too_small(x):
            raise ValueError(f"{_v.E_TINY_RULE}, got {x} in e = ({e0}, {e1})")
    return e0, e1


def _check_u(u, window=False):
    """``(u0, u1)`` within ``[1e-150, 1e150]`` (``u0 = 0`` allowed for a window)."""
    u0, u1 = _pair("u", u)
    low = 0.0 if window else _v.U_MIN
    rule = (f"u must be a pair (u0, u1) with {'0 <=' if window else f'{_v.U_MIN:g} <='} u0 "
            f"{'<' if window else '<='} u1 <= {_v.U_MAX:g} (horizontal speeds, the valid numeric range)")
    if not (u0 >= low and u1 <= _v.U_MAX and (u0 > 0.0 or window)):
        raise ValueError(f"{rule}, got ({u0}, {u1})")
    if window and 0.0 < u0 < _v.U_MIN:
        raise ValueError(f"{rule}, got ({u0}, {u1})")
    if not (u0 < u1 if window else u0 <= u1):
        raise ValueError(f"{rule}: {'an empty' if u0 == u1 else 'a reversed'} range, got ({u0}, {u1})")
    return u0, u1


# --------------------------------------------------------------------------- #
# An atlas's table, decoded                                                   #
# --------------------------------------------------------------------------- #

ATLAS_REASONS = ("", "graze", "edge", "chatter", "impacts", "nonsliding", "range", "trapping", "branches")
"""The reasons an atlas's box may carry: ``""`` (a proven box), the undecided
reasons (``structure/certify.py``, ``UNDECIDED_REASONS``) and ``"trapping"`` (a
``no_sliding`` box proven by a trapping region)."""


def _names(ds, key):
    """The names list ``{key}_names`` of a Zarr store's ``{key}_code`` (save)."""
    if f"{key}_names" not in ds.attrs:
        raise ValueError(f"atlas: {key}_code is stored without its names list (the attribute {key}_names)")
    names = ds.attrs[f"{key}_names"]
    names = [names] if isinstance(names, str) else list(np.atleast_1d(names))
    if not all(isinstance(x, str) for x in names):
        raise ValueError(f"atlas: {key}_names must be a list of texts, got {names!r}")
    return names


def _codes(name, codes, what, n):
    """Integer ``codes`` each in ``[0, n)`` (indices into ``what``), else ValueError."""
    codes = np.asarray(codes)
    if codes.dtype.kind not in "iu":
        raise ValueError(f"atlas: {name} must hold integers, got dtype {codes.dtype}")
    bad = (codes < 0) | (codes >= n)
    if bad.any():
        raise ValueError(f"atlas: {name} {int(codes[bad][0])} at box {int(np.flatnonzero(bad)[0])} is outside "
                         f"{what} (0 to {n - 1})")
    return codes


def decode_atlas(ds):
    """decode_atlas(ds) -> xarray.Dataset

    An atlas's table with its texts decoded, as :meth:`CertifiedAtlas.load` and the
    checker (``sb.verify``) read it, from an ``.nc`` file, a ``.zarr`` store or memory:
    ``status`` as int8 codes into :data:`STATUSES` (names are looked up), ``word`` and
    ``reason`` as Python strings (one object per distinct text), read from a Zarr
    store's ``word_code``/``reason_code`` and its ``word_names``/``reason_names``
    attributes.  Refused with ValueError, by name: a code without its names list, a
    code out of the list's range, a status name or code not in :data:`STATUSES`, a
    reason not in :data:`ATLAS_REASONS`, and a ``word_code`` or ``reason_code`` beside a
    ``word`` or ``reason`` (two answers).  Other variables are kept as they are.
    """
    import pandas as pd

    ds = ds.copy()
    ds.attrs = dict(ds.attrs)
    for key in ("word", "reason"):
        if f"{key}_code" in ds.variables:
            if key in ds.variables:
                raise ValueError(f"atlas: both {key} and {key}_code are stored; one of them must go")
            names = _names(ds, key)
            codes = _codes(f"{key}_code", ds[f"{key}_code"].values, f"its names list {key}_names", len(names))
            table = np.array(names + [""], dtype=object)[:-1] if names else np.zeros(0, dtype=object)
            ds[key] = (ds[f"{key}_code"].dims, table[codes])
            ds = ds.drop_vars(f"{key}_code")
            del ds.attrs[f"{key}_names"]
        elif f"{key}_names" in ds.attrs:
            raise ValueError(f"atlas: {key}_names is stored without {key}_code")
        if key in ds.variables:
            # one Python string per distinct text (8 bytes a box)
            v = np.asarray(ds[key].values)
            codes, names = pd.factorize(v if v.dtype.kind == "O" else v.astype(str).astype(object))
            names = np.array([str(x) for x in names] + [""], dtype=object)
            if codes.size and codes.min() < 0:
                raise ValueError(f"atlas: {key} holds a missing value at box {int(np.flatnonzero(codes < 0)[0])}")
            ds[key] = (ds[key].dims, names[codes])
    if "reason" in ds.variables:
        known = set(ATLAS_REASONS)
        strange = [r for r in np.unique(ds["reason"].values.astype(str)) if r not in known]
        if strange:
            raise ValueError(f"atlas: reason {strange[0]!r} is not one of {', '.join(map(repr, ATLAS_REASONS))}")
    if "statuses" in ds.attrs and str(ds.attrs["statuses"]) != ",".join(STATUSES):
        raise ValueError(f"atlas: its status names (attribute statuses) {ds.attrs['statuses']!r} are not "
                         f"{','.join(STATUSES)!r}")
    if "status" in ds.variables:
        st = np.asarray(ds["status"].values)
        if st.dtype.kind in "USO":
            index = {s: k for k, s in enumerate(STATUSES)}
            text = st.astype(str)
            bad = np.array([s not in index for s in text], dtype=bool)
            if bad.any():
                raise ValueError(f"atlas: status {text[bad][0]!r} at box {int(np.flatnonzero(bad)[0])} is not one "
                                 f"of {', '.join(STATUSES)}")
            ds["status"] = (ds["status"].dims, np.array([index[s] for s in text], dtype=np.int8))
        else:
            st = _codes("status code", st, f"the statuses ({', '.join(STATUSES)})", len(STATUSES))
            ds["status"] = (ds["status"].dims, st.astype(np.int8))
    return ds


def read_atlas_file(path):
    """read_atlas_file(path) -> xarray.Dataset: the table of an atlas file (``.nc`` or
    ``.zarr``, or a store of ``certify_to_zarr``, its tiles merged) read into memory as
    stored (:func:`decode_atlas` decodes it); a path of
    another kind, something that is not a regular file or a folder, or a file that
    cannot be read, refused with a one-line ValueError (:func:`stairbounce._io.read_dataset`)."""
    from .._io import read_dataset
    from ._store_read import is_store, read_store

    if is_store(path):  # a streamed atlas (certify_to_zarr): its tiles merged, each checked
        return read_store(path)
    return read_dataset(path, "a certified atlas")
