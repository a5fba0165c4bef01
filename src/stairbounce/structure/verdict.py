"""The checker's verdict on a certificate, an atlas or an atlas file.

:func:`verify` re-verifies what a :class:`~stairbounce.Certificate`, a
:class:`~stairbounce.CertifiedAtlas` (or its Dataset) or a saved atlas (``.nc``,
``.zarr``) claims, with the independent checker: the boxes' claims by
``structure/verify.py`` (:func:`~stairbounce.structure.verify.verify_codes`), the
trapping regions by ``structure/verify_trapping.py``.  The layers: this module
imports those two, ``verify_trapping`` imports ``verify``, and neither imports
this one.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..symbolic import Word, parse_word, word_from_impacts
from ._store_read import row_key
from .certificate import ATLAS_REASONS, STATUSES, Certificate, check_certificate_fields, decode_atlas, read_atlas_file
from .tiling import AreaBook, deepest_level, tiling, word_area_bounds
from .verify import _BRANCHES, _COR, _ITIN, _OK, _TRAP, _WORD, _WORD_S, CHECKS, check_work, verify_codes
from .verify_branches import check_atlas_branches
from .verify_trapping import check_atlas_regions, verify_certificate_region

__all__ = ["Verdict", "verify", "verify_file", "read_atlas_arrays"]

# the checks of a whole table beyond verify.CHECKS (codes after its own)
_REASON, _PLACE, _OVERLAP = len(CHECKS), len(CHECKS) + 1, len(CHECKS) + 2


@dataclass(frozen=True)
class Verdict:
    """The checker's answer: ``ok``, and else which check failed, at which step.

    For an atlas or a file, ``checked`` and ``rejected`` count its boxes and
    ``check``/``step`` describe the first rejected one.  True in a boolean
    context exactly when ``ok``.

    ``atlas``: the table is an atlas (its attribute ``kind``), so its boxes were
    also checked as the quadtree of its window (checks ``place``: a box is not the
    box ``(level, i, j)`` of the window at the depth, edges bit for bit;
    ``overlap``: it shares area with another box); ``complete``: they cover the
    window.  ``numbers``: for an atlas whose every box is verified, the derived
    numbers, proven from the verified boxes by outward rounding
    (``structure/tiling.py``), each a ``(lower, upper)`` pair: ``status`` and
    ``reason`` (the undecided boxes' reasons) area shares, ``words`` each proven
    word's area bounds (:meth:`CertifiedAtlas.word_area_bounds`), ``window_area``,
    ``covered_area``, ``uncovered_area``, ``of`` ("the window", or "the covered
    part" when the boxes do not cover it: the shares are then of the covered part)
    and ``basis``.
    """

    ok: bool
    check: str | None = None
    step: int | None = None
    message: str = ""
    checked: int = 1
    rejected: int = 0
    atlas: bool = False
    complete: bool | None = None
    numbers: dict | None = None

    def __bool__(self) -> bool:
        return self.ok


def _arrays_of_certificate(cert):
    itin = np.asarray(cert.itinerary, dtype=np.int64).ravel()
    status = STATUSES.index(cert.status) if cert.status in STATUSES else -1
    return (np.array([cert.e[0]], dtype=float), np.array([cert.e[1]], dtype=float),
            np.array([cert.u[0]], dtype=float), np.array([cert.u[1]], dtype=float),
            np.array([status]), cert.max_iter, itin, np.array([0, len(itin)]))


def _verify_certificate(cert):
    check_work(1, len(cert.itinerary), what="the certificate")
    if cert.status == "no_sliding" and cert.reason == "trapping":  # a trapping region (verify_trapping.py)
        return verify_certificate_region(cert, Verdict)
    try:
        arrays = _arrays_of_certificate(cert)
        code, step = verify_codes(*arrays)
    except (ValueError, TypeError) as exc:
        return Verdict(False, "box", None, f"malformed certificate: {exc}")
    c, st = int(code[0]), int(step[0])
    if c == _OK and cert.status == "word":
        try:
            spelled = word_from_impacts(cert.itinerary)
        except ValueError:
            spelled = None
        if not isinstance(cert.word, Word) or cert.word != spelled:
            return Verdict(False, "word", None,
                           f"the itinerary spells {spelled}, the certificate states {cert.word}")
    if c == _OK and cert.status != "word" and cert.word is not None:
        return Verdict(False, "word", None, f"a {cert.status} certificate states a word ({cert.word})")
    if c == _OK:
        return Verdict(True, None, None, f"{cert.status}: re-verified")
    where = f" at step {st}" if st else ""
    return Verdict(False, CHECKS[c], st or None, f"{cert.status}: check '{CHECKS[c]}' failed{where}")


def read_atlas_arrays(data):
    """read_atlas_arrays(data) -> dict of the array form (and ``word`` if stored)

    From an xarray Dataset with dimension ``box`` and variables ``e0, e1, u0,
    u1, status`` (int8 codes into STATUSES, or strings), ``itinerary`` (its own
    dimension), ``offsets`` (box + 1) and the attribute ``max_iter``; texts and
    codes decoded by :func:`~stairbounce.structure.certificate.decode_atlas`.
    """
    _need(data)
    return _arrays(decode_atlas(data))


_NEED = ("e0", "e1", "u0", "u1", "status", "itinerary", "offsets")


def _need(data):
    """The variables and attribute the array form needs, or ValueError naming the missing."""
    missing = [name for name in _NEED if name not in data.variables]
    if missing or "max_iter" not in data.attrs:
        raise ValueError(f"atlas must hold the variables {', '.join(_NEED)} and the attribute max_iter; "
                         f"missing: {', '.join(missing + ([] if 'max_iter' in data.attrs else ['max_iter']))}")


def _arrays(data):
    """:func:`read_atlas_arrays` of a decoded table."""
    out = {name: np.asarray(data[name].values) for name in _NEED}
    m = data.attrs["max_iter"]
    m = m.item() if isinstance(m, np.ndarray) and m.size == 1 else m
    if isinstance(m, (bool, np.bool_)) or not isinstance(m, (int, np.integer, float, np.floating)) \
            or not np.isfinite(m) or m != int(m):
        raise ValueError(f"atlas: the attribute max_iter must be an integer >= 1, got {m!r}")
    out["max_iter"] = int(m)
    for key in ("word", "reason"):
        if key in data.variables:
            out[key] = np.asarray(data[key].values)
    return out


def _check_words(arrays, code, cache=None):
    """Where a stored word text disagrees with the word its itinerary spells, or a box
    that is not proven ``word`` states a word.  ``cache``: three dicts kept between
    calls (a store's tiles), of the itineraries spelled, texts parsed and pairs compared."""
    words = arrays.get("word")
    if words is None:
        return
    is_word = np.asarray(arrays["status"]) == _WORD_S
    itin, off = np.asarray(arrays["itinerary"], dtype=np.int64), np.asarray(arrays["offsets"], dtype=np.int64)
    spelled, parsed, same = cache or ({}, {}, {})  # each itinerary spelled once, each text parsed once
    for i in np.flatnonzero(is_word & (code == _OK)):
        key = (itin[off[i]:off[i + 1]].tobytes(), words[i])
        if key not in same:
            if key[0] not in spelled:
                try:
                    spelled[key[0]] = word_from_impacts(itin[off[i]:off[i + 1]])
                except ValueError:
                    spelled[key[0]] = None
            text = str(words[i])
            if text not in parsed:
                try:
                    parsed[text] = parse_word(text)
                except ValueError:
                    parsed[text] = None
            same[key] = spelled[key[0]] is not None and parsed[text] == spelled[key[0]]
        if not same[key]:
            code[i] = _WORD
    # object texts: a fixed-width copy of 13.6 million words of up to 493 letters is 25 GiB
    texts = words.astype(str) if words.dtype.kind != "O" else np.array([str(w) for w in words], dtype=object)
    # a ``sliding`` box states its possible words (checked by verify_branches.py)
    states = is_word | (np.asarray(arrays["status"]) == STATUSES.index("sliding"))
    code[(code == _OK) & ~states & (texts != "")] = _WORD


# what reasons each status may carry in an atlas ("" for a proven box; trapping: a region)
# branches: a class-level proof (structure/classes.py); a ``sliding`` box lists its words
_REASONS_OF = {"word": {""}, "no_sliding": {"", "trapping"}, "no_slide_within": {"", "branches"},
               "undecided": set(ATLAS_REASONS) - {"", "trapping", "branches"}, "sliding": {""}}


def _check_reasons(arrays, code):
    """Where a box's reason does not go with its status (:data:`_REASONS_OF`)."""
    reasons = arrays.get("reason")
    if reasons is None:
        return
    status = np.asarray(arrays["status"])
    texts = np.array([str(r) for r in reasons], dtype=object)
    for k, name in enumerate(STATUSES):
        sel = (status == k) & (code == _OK)
        if sel.any():
            fits = np.isin(texts[sel], sorted(_REASONS_OF[name]))
            code[np.flatnonzero(sel)[~fits]] = _REASON


def _check_trap_layout(data):
    """The trapping regions' variables laid out as ``trap_atlas`` writes them (else
    ValueError naming the variable): ``trap_box`` rows of the table, each once;
    ``trap_grid`` six numbers a region, its cell counts whole and >= 1;
    ``trap_cell_offsets`` from 0 to ``len(trap_cells)``, never decreasing."""
    names = ("trap_box", "trap_grid", "trap_cell_offsets", "trap_cells")
    have = [k for k in names if k in data.variables]
    if not have:
        return
    if len(have) < len(names):
        raise ValueError(f"atlas: the trapping regions need {', '.join(names)}; missing: "
                         f"{', '.join(k for k in names if k not in have)}")
    n = data.sizes.get("box", 0)
    box = np.asarray(data["trap_box"].values)
    grid = np.asarray(data["trap_grid"].values)
    off = np.asarray(data["trap_cell_offsets"].values)
    cells = np.asarray(data["trap_cells"].values)
    if box.dtype.kind not in "iu" or np.any((box < 0) | (box >= n)) or np.unique(box).size != box.size:
        raise ValueError(f"atlas: trap_box must hold distinct rows of the table (0 to {n - 1})")
    if grid.shape != (box.size, 6) or grid.dtype.kind != "f":
        raise ValueError(f"atlas: trap_grid must hold six numbers (v_lo, v_hi, nv, s_lo, s_hi, ns) for each of the "
                         f"{box.size} regions, got shape {grid.shape}")
    counts = grid[:, [2, 5]] if grid.size else np.ones((0, 2))
    if not (np.all(np.isfinite(counts)) and np.all(counts >= 1) and np.all(counts == np.floor(counts))):
        raise ValueError("atlas: trap_grid's cell counts nv and ns must be whole numbers >= 1")
    if (off.dtype.kind not in "iu" or off.shape != (box.size + 1,) or off[0] != 0 or off[-1] != cells.size
            or np.any(np.diff(off) < 0)):
        raise ValueError(f"atlas: trap_cell_offsets must run from 0 to len(trap_cells) = {cells.size}, one entry per "
                         "region plus one, never decreasing")
    if cells.dtype.kind not in "iu":
        raise ValueError(f"atlas: trap_cells must hold integers, got dtype {cells.dtype}")


def _window(data):
    """An atlas's window and deepest level (its depth, plus the levels its trapping
    pass split boxes below it: ``trap_split``) from its attributes, refused by name."""
    for key in ("e_range", "u_range", "depth"):
        if key not in data.attrs:
            raise ValueError(f"atlas: the attribute {key} is missing (a certified atlas states its window and depth)")
    for key in ("level", "i", "j"):
        if key not in data.variables:
            raise ValueError(f"atlas: the variable {key} is missing (each box's place in the window's quadtree)")
    pairs = []
    for key in ("e_range", "u_range"):
        v = np.atleast_1d(np.asarray(data.attrs[key], dtype=np.float64))
        if v.size != 2:
            raise ValueError(f"atlas: the attribute {key} must be a pair (lo, hi), got {data.attrs[key]!r}")
        pairs.append((float(v[0]), float(v[1])))
    depth = data.attrs["depth"]
    if isinstance(depth, np.ndarray) and depth.size == 1:
        depth = depth.item()
    if not isinstance(depth, (int, np.integer)):
        raise ValueError(f"atlas: the attribute depth must be an int, got {depth!r}")
    # boxes may lie below the depth where the trapping pass split them (trap_split levels)
    return tuple(pairs), deepest_level(int(depth), data.attrs)


def _numbers(data, arrays, window, complete):
    """The derived numbers of a verified atlas (:class:`Verdict`'s ``numbers``)."""
    from ..symbolic import parse_word

    book = AreaBook(arrays["e0"], arrays["e1"], arrays["u0"], arrays["u1"], window, complete)
    status = np.asarray(arrays["status"])
    reasons = np.array([str(r) for r in arrays.get("reason", np.full(status.size, ""))], dtype=object)
    words = arrays.get("word")
    if words is None:  # no texts stored: each verified word box's word as its itinerary spells it
        words = np.full(status.size, "", dtype=object)
        itin, off, spelled = arrays["itinerary"], arrays["offsets"], {}
        for b in np.flatnonzero(status == _WORD_S):
            key = itin[off[b]:off[b + 1]].tobytes()
            if key not in spelled:
                spelled[key] = word_from_impacts(itin[off[b]:off[b + 1]]).format(ascii=True)
            words[b] = spelled[key]
    words = np.array([str(w) for w in words], dtype=object)
    undecided = status == STATUSES.index("undecided")
    return _numbers_dict(book, complete, {name: book.share(status == k) for k, name in enumerate(STATUSES)},
                         {r: book._ratio(*a) for r, a in book.groups(reasons, undecided).items()},
                         book.word_bounds(status, words, arrays["max_iter"], lambda w: parse_word(w).period))


def _numbers_dict(book, complete, status, reason, words):
    """:class:`Verdict`'s ``numbers`` from an :class:`~stairbounce.structure.tiling.AreaBook`
    and the shares by status and reason and the words' area bounds."""
    wlo, whi = book.window
    clo, chi = book.covered
    return {
        "basis": "proven: sums of the verified boxes' exact areas, rounded outward (structure/tiling.py)",
        "of": book.of,
        "window_area": book.window, "covered_area": book.covered,
        "uncovered_area": (0.0, 0.0) if complete else (max(float(np.nextafter(wlo - chi, -np.inf)), 0.0),
                                                       float(np.nextafter(whi - clo, np.inf))),
        "status": status, "reason": reason, "words": words,
    }


def _check_boxes(data, cache=None):
    """Every check of a table box by box: ``(decoded table, arrays, code, step)``, the
    code per box (``_OK`` or the first failed check) before the quadtree checks
    (``cache``: :func:`_check_words`'s)."""
    _need(data)
    data = decode_atlas(data)
    arrays = _arrays(data)
    code, step = verify_codes(arrays["e0"], arrays["e1"], arrays["u0"], arrays["u1"], arrays["status"],
                              arrays["max_iter"], arrays["itinerary"], arrays["offsets"])
    _check_words(arrays, code, cache)
    _check_reasons(arrays, code)
    _check_trap_layout(data)
    if "reason" in data.variables:  # no_sliding boxes proven by trapping regions (verify_trapping.py)
        # a region stands in for Corollary 2.1 only: a box that failed another check stays rejected
        prior = code.copy()
        check_atlas_regions(data, arrays, code, _TRAP)
        keep = (prior != _OK) & (prior != _COR)
        code[keep] = prior[keep]
    # class-level proofs (structure/classes.py) have no single itinerary: the branch
    # checker stands in for the itinerary check only, as a region does for Corollary 2.1
    prior = code.copy()
    check_atlas_branches(data, arrays, code, _BRANCHES)
    keep = (prior != _OK) & (prior != _ITIN)
    code[keep] = prior[keep]
    return data, arrays, code, step


_NAMES = CHECKS + ("reason", "place", "overlap")
_ATLAS_KIND = "stairbounce certified atlas"


def _place(data, arrays, code, step, window, depth):
    """The quadtree checks of an atlas's boxes (``tiling``), written into ``code`` and
    ``step``: returns the :class:`~stairbounce.structure.tiling.Tiling`."""
    t = tiling(window, depth, data["level"].values, data["i"].values, data["j"].values,
               arrays["e0"], arrays["e1"], arrays["u0"], arrays["u1"])
    code[~t.placed] = _PLACE
    code[t.overlapping & t.placed] = _OVERLAP
    step[~t.placed | t.overlapping] = 0
    return t


def _rejected(n, n_bad, first, check, st, is_atlas, complete):
    return Verdict(False, _NAMES[check], st or None,
                   f"{n_bad} of {n} boxes rejected; the first, box {first}, failed check '{_NAMES[check]}'"
                   + (f" at step {st}" if st else ""), checked=n, rejected=n_bad, atlas=is_atlas,
                   complete=complete)


def _not_atlas(n):
    return Verdict(True, None, None, f"{n} boxes re-verified (a table of certificates, not an atlas: no "
                   "window stated, no derived numbers)", checked=n, rejected=0)


def _accepted(n, depth, numbers, complete, missing):
    cover = ("they cover the window" if complete else
             f"they do not cover the window ({missing} of {4 ** depth} cells of the deepest level missing, "
             f"uncovered area in [{numbers['uncovered_area'][0]:.6g}, {numbers['uncovered_area'][1]:.6g}]); "
             "every derived number is of the covered part")
    return Verdict(True, None, None, f"{n} boxes re-verified, each the quadtree box of the window it states, "
                   f"none overlapping; {cover}", checked=n, rejected=0, atlas=True, complete=complete,
                   numbers=numbers)


def _verify_dataset(data):
    data, arrays, code, step = _check_boxes(data)
    is_atlas = data.attrs.get("kind") == _ATLAS_KIND
    complete = None
    if is_atlas:
        window, depth = _window(data)
        t = _place(data, arrays, code, step, window, depth)
        complete = t.complete
    bad = np.flatnonzero(code != _OK)
    n = len(code)
    if len(bad):
        i = int(bad[0])
        return _rejected(n, len(bad), i, int(code[i]), int(step[i]), is_atlas, complete)
    if not is_atlas:
        return _not_atlas(n)
    return _accepted(n, depth, _numbers(data, arrays, window, complete), complete, t.missing)


# --------------------------------------------------------------------------- #
# A streamed atlas (certify_to_zarr's store), verified tile by tile            #
# --------------------------------------------------------------------------- #


def _units(x):
    """The exact values of the finite floats ``x`` as integers ``M`` and offsets ``s``:
    ``x = M * 2^(s - 1126)`` with ``|M| < 2^53`` and ``0 <= s < 4096``."""
    m, e = np.frexp(np.asarray(x, dtype=np.float64))
    return (m * 2.0 ** 53).astype(np.int64), (e - 53 + 1126).astype(np.int64)


class _ExactAreas:
    """Exact sums of the boxes' area bounds (``tiling.area_bounds``) by group, added tile
    by tile: each sum a Python integer in units of ``2^-1126`` (below the smallest
    float), so that the sum of all the tiles is the exact sum of all the boxes' bounds,
    in any order.  ``bounds(key)`` is then what ``tiling._sum_bounds`` gives on all the
    boxes of the group at once: ``math.fsum`` is the correctly rounded exact sum, and
    so is the integer division of the exact sum by ``2^1126`` (Python rounds both to
    nearest, ties to even)."""

    def __init__(self):
        self.sums = {}  # key: [boxes, exact sum of the lower bounds, of the upper bounds]
        self.max_iter = None  # the atlas's (a word's upper bound depends on it)

    def add(self, inv, names, lo, hi):
        """Add the boxes' bounds ``lo``, ``hi`` to the groups ``names[inv]`` (``inv``: an
        index into the list of keys ``names``, one a box)."""
        inv = np.asarray(inv, np.int64)
        if not inv.size:
            return
        for col, bounds in ((1, lo), (2, hi)):
            m, s = _units(bounds)
            group = inv * 4096 + s
            order = np.argsort(group, kind="stable")
            g = group[order]
            starts = np.flatnonzero(np.r_[True, g[1:] != g[:-1]])
            mo = m[order]
            high = np.add.reduceat(mo >> 26, starts)   # |M >> 26| < 2^27: no int64 overflow below 2^36 boxes
            low = np.add.reduceat(mo & ((1 << 26) - 1), starts)
            for gk, h, lw in zip(g[starts].tolist(), high.tolist(), low.tolist()):
                entry = self.sums.setdefault(names[gk >> 12], [0, 0, 0])
                entry[col] += ((h << 26) + lw) << (gk & 4095)
        counts = np.bincount(inv, minlength=len(names))
        for k, name in enumerate(names):
            if counts[k]:
                self.sums.setdefault(name, [0, 0, 0])[0] += int(counts[k])

    def merge(self, other):
        """Add the sums of another :class:`_ExactAreas` (another tile's)."""
        self.max_iter = other.max_iter
        for key, (n, lo, hi) in other.sums.items():
            entry = self.sums.setdefault(key, [0, 0, 0])
            entry[0] += n
            entry[1] += lo
            entry[2] += hi

    def bounds(self, key):
        """``(lower, upper)`` on the exact area of the group ``key`` (``(0, 0)`` if empty)."""
        n, lo, hi = self.sums.get(key, (0, 0, 0))
        if not n:
            return 0.0, 0.0
        scale = 1 << 1126
        return max(float(np.nextafter(lo / scale, -np.inf)), 0.0), float(np.nextafter(hi / scale, np.inf))

    def names(self, kind):
        return sorted(k[1] for k in self.sums if k[0] == kind)


def _tile_areas(areas, arrays, status):
    """Add a verified tile's boxes to the exact sums by status, undecided reason and word."""
    from .tiling import area_bounds

    import pandas as pd

    lo, hi = area_bounds(arrays["e0"], arrays["e1"], arrays["u0"], arrays["u1"])
    n = status.size
    areas.add(np.zeros(n, np.int64), [("all", 0)], lo, hi)
    areas.add(status.astype(np.int64), [("status", k) for k in range(len(STATUSES))], lo, hi)

    def texts(kind, sel, values):
        values = np.asarray(values)  # decode_atlas's Python strings (one object per distinct text)
        codes, names = pd.factorize(values if values.dtype.kind == "O" else values.astype(str).astype(object))
        areas.add(codes, [(kind, str(x)) for x in names], lo[sel], hi[sel])

    sel = np.flatnonzero(status == STATUSES.index("undecided"))
    reasons = arrays.get("reason")
    texts("reason", sel, reasons[sel] if reasons is not None else [""] * sel.size)
    sel = np.flatnonzero(status == _WORD_S)
    words = arrays.get("word")
    if words is None:  # no texts stored: the word its itinerary spells (as _numbers)
        itin, off = arrays["itinerary"], arrays["offsets"]
        texts("word", sel, [word_from_impacts(itin[off[b]:off[b + 1]]).format(ascii=True) for b in sel])
    else:
        texts("word", sel, words[sel])


def _numbers_of_sums(areas, window, complete):
    """:func:`_numbers` from the exact sums of the tiles (the same floats, bit for bit)."""
    empty = np.zeros(0)
    book = AreaBook(empty, empty, empty, empty, window, complete)
    if not complete:
        book.covered = areas.bounds(("all", 0))
    words = word_area_bounds({w: areas.bounds(("word", w)) for w in areas.names("word")},
                             areas.bounds(("status", _WORD_S))[0],
                             areas.bounds(("status", STATUSES.index("no_sliding")))[0],
                             areas.bounds(("status", STATUSES.index("no_slide_within")))[0],
                             book.covered[1], areas.max_iter, lambda w: parse_word(w).period)
    return _numbers_dict(book, complete,
                         {name: book._ratio(*areas.bounds(("status", k))) for k, name in enumerate(STATUSES)},
                         {r: book._ratio(*areas.bounds(("reason", r))) for r in areas.names("reason")}, words)


def _runs(depth, level, i, j):
    """The Morton runs ``[start, end)`` of the deepest level's cells of boxes ``(level, i, j)``
    (placed ones: ``tiling``'s module docstring)."""
    from .tiling import _spread

    level = np.asarray(level, np.int64)
    shift = 2 * (depth - level)
    start = ((_spread(np.asarray(i, np.int64)) | (_spread(np.asarray(j, np.int64)) << np.uint64(1)))
             .astype(np.int64)) << shift
    return start, start + (np.int64(1) << shift)


def _cells(start, end, shift):
    """The cells of level ``depth - shift / 2`` that the runs meet, as sorted disjoint
    intervals ``(lo, hi)``."""
    if not start.size:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    lo, hi = start >> shift, ((end - 1) >> shift) + 1
    order = np.argsort(lo, kind="stable")
    lo, hi = lo[order], np.maximum.accumulate(hi[order])
    new = np.r_[True, lo[1:] > hi[:-1]]  # an interval starts where it does not touch the ones before
    first = np.flatnonzero(new)
    return lo[first], np.maximum.reduceat(hi, first)


def _store_tile(path, k, token, crc, base_attrs):
    """Tile ``k`` of a store, checked against its checksum, as the rows it holds of the
    whole atlas's table (its rows in the atlas's order, its regions renumbered) with the
    atlas's attributes (those of tile 0, as ``read_store`` gives the whole table)."""
    from . import _store_read as R

    got = R.check_tile(path, k, token, crc)
    if got is None:
        raise ValueError(f"tile {k} of {path} does not match its checksum (a chunk deleted or damaged): "
                         "run certify_to_zarr with the same arguments to compute it again")
    arrays, attrs = got
    try:
        n_boxes, n_steps = arrays["offsets"].size - 1, arrays["itinerary"].size
    except KeyError as exc:
        raise ValueError(f"tile {k} of {path} lacks its variable {exc}: the store is damaged") from None
    from .verify import check_work

    # the limit of one call, held by each tile: a store is checked a tile at a time
    check_work(n_boxes, n_steps, arrays["trap_cells"].size if "trap_cells" in arrays else 0,
               what=f"tile {k} of the atlas store {str(path)!r}")
    ds = R.merge_tiles([(arrays, attrs)], n_boxes, n_steps, first=k)
    if base_attrs is not None:
        ds.attrs = dict(base_attrs)
    return ds


def _verify_store(path, workers=None):
    """The verdict on a streamed atlas (:func:`stairbounce.certify_to_zarr`), read one
    tile at a time: the same :class:`Verdict`, field for field and float for float, as
    :func:`verify` of the whole table ``read_store`` merges (``CertifiedAtlas.load``),
    with the memory of a tile.

    Every tile is read and checked against its checksum, then checked as today's
    whole table is, box by box (``_check_boxes``: the claims, words, reasons, trapping
    regions, branches) with the atlas's attributes (tile 0's, as the merged table has
    them), and each of its boxes placed (``tiling``: the quadtree box ``(level, i, j)``
    of the stated window at the stated depth, edges bit for bit, inside the window; no
    two of the tile's boxes overlapping).  What is left is the atlas as a whole:

    * Overlap across tiles.  A box is a run of Morton codes of the deepest level's
      cells (``tiling``); cut the window at a level ``T`` (the store's tile level): a box
      of a level ``>= T`` lies in one level-``T`` cell, a coarser one covers whole
      level-``T`` cells.  Each tile's placed boxes give the set of level-``T`` cells they
      meet (kept as sorted intervals, a few integers a tile).  Two boxes of different
      tiles that overlap share a cell of the deepest level, hence a level-``T`` cell met
      by both tiles.  So when no level-``T`` cell is met by two tiles (the quadtree cut
      as ``certify_to_zarr`` cuts it: a tile's boxes are below its own level-``T`` boxes,
      tile 0's coarse boxes cover the cells of no other tile) no boxes of different tiles
      overlap; otherwise the boxes meeting the shared cells are read again and every
      pair of them from different tiles compared, exactly (so a store cut otherwise,
      but a genuine atlas, still verifies).  A box is marked ``overlap`` as ``tiling``
      marks it in the whole table: when a box before it in the order of Morton start,
      then of the table's rows, overlaps it.
    * Coverage.  Without overlaps, the boxes cover the window exactly when every box is
      placed and their runs add up to ``4^depth`` cells (a Python integer summed over
      the tiles).
    * Derived numbers.  The boxes' area bounds (``tiling.area_bounds``, per box) summed
      exactly by status, undecided reason and word (:class:`_ExactAreas`), so that each
      bound is the float ``math.fsum`` gives on the whole table: the numbers equal the
      whole table's bit for bit.
    * The first rejected box is numbered as in the whole table (its rows ordered by
      level, then j, then i, then tile): a second pass reads the ``level, i, j`` of every
      tile, only when a box is rejected.
    """
    try:
        return _verify_tiles(path, workers)
    finally:
        for cache in _WORDS_CACHE:  # this process's (a worker's goes with it)
            cache.clear()


def _verify_tiles(path, workers):
    from . import _store_read as R

    root, token, crc = R.complete_state(path)
    n_tiles = crc.size
    ds = _store_tile(path, 0, token, crc[0], None)
    base = dict(ds.attrs)
    is_atlas = base.get("kind") == _ATLAS_KIND
    window, depth, shift = None, 0, 0
    if is_atlas:
        window, depth = _window(ds)
        shift = 2 * (depth - R.tile_level(root, depth))
    job = (str(path), token, base, is_atlas, window, depth, shift)
    first_tile = _check_tile(job, 0, crc[0], ds)
    del ds
    areas = _ExactAreas()
    n = n_bad = 0
    first = None               # (key, tile, row, code, step) of the first rejected box so far
    bad_of = {}                # tile: the rows of its rejected boxes
    cells = []                 # per tile: the level-T cells its placed boxes meet, (lo, hi)
    covered, all_placed, clash = 0, True, False
    for k, r in enumerate(_each_tile(job, crc, first_tile, workers)):
        n += r["n"]
        if r["bad"].size:
            bad_of[k] = r["bad"]
            n_bad += r["bad"].size
            first = r["first"] if first is None or r["first"][:3] < first[:3] else first
        elif not n_bad:
            areas.merge(r["areas"])
        if is_atlas:
            all_placed &= r["placed"]
            clash |= r["clash"]
            covered += r["covered"]
            cells.append(r["cells"])
    complete = None
    if is_atlas:
        for key, k, row in _overlaps_across_tiles(path, token, crc, base, cells, shift, window, depth):
            clash = True
            rows = bad_of.get(k, np.zeros(0, np.int64))
            at = np.searchsorted(rows, row)
            if not (at < rows.size and rows[at] == row):
                n_bad += 1
            if first is None or (key, k, row) < first[:3] or first[1:3] == (k, row):
                first = (key, k, row, _OVERLAP, 0)
        complete = all_placed and not clash and covered == 4 ** depth
    if n_bad:
        return _rejected(n, n_bad, _row_in_atlas(path, n_tiles, first), first[3], first[4], is_atlas, complete)
    if not is_atlas:
        return _not_atlas(n)
    return _accepted(n, depth, _numbers_of_sums(areas, window, complete), complete, 4 ** depth - covered)


_WORDS_CACHE: tuple[dict, dict, dict] = ({}, {}, {})  # _check_words's, kept over the tiles a process checks


def _check_tile(job, k, crc, ds=None):
    """Tile ``k`` checked as a part of the whole table (``_verify_store``): what the
    whole verdict needs of it, a few numbers and small arrays (picklable: run in a
    worker process too)."""
    path, token, base, is_atlas, window, depth, shift = job
    if ds is None:
        ds = _store_tile(path, k, token, crc, base)
    data, arrays, code, step = _check_boxes(ds, _WORDS_CACHE)
    del ds
    out = {"n": int(code.size)}
    if is_atlas:
        t = _place(data, arrays, code, step, window, depth)
        sel = np.flatnonzero(t.placed)
        start, end = _runs(depth, data["level"].values[sel], data["i"].values[sel], data["j"].values[sel])
        out.update(placed=bool(t.placed.all()), clash=bool(t.overlapping.any()), covered=int((end - start).sum()),
                   cells=_cells(start, end, shift))
    bad = np.flatnonzero(code != _OK)
    out["bad"] = bad
    if bad.size:
        key = int(row_key(*(data[v].values[bad[:1]] for v in ("level", "i", "j")))[0])
        out["first"] = (key, k, int(bad[0]), int(code[bad[0]]), int(step[bad[0]]))
    else:
        out["areas"] = areas = _ExactAreas()
        areas.max_iter = arrays["max_iter"]
        _tile_areas(areas, arrays, np.asarray(arrays["status"]))
    return out


def _check_tile_task(job, k_crc):
    return _check_tile(job, *k_crc)


def _each_tile(job, crc, first, workers):
    """The tiles' results in their order: tile 0's ``first``, then the others, checked
    here one after another or, with ``workers`` > 1, in that many processes (tiles are
    independent; their results are combined in the tiles' order, so the verdict is the
    same)."""
    yield first
    rest = range(1, crc.size)
    if workers is None or workers <= 1 or crc.size <= 2:
        for k in rest:
            yield _check_tile(job, k, crc[k])
        return
    import functools
    import multiprocessing

    # spawned, not forked: numba's thread pools are not safe to fork; the workers leave
    # Ctrl-C to this process, which stops them at once (terminate) and raises it
    pool = multiprocessing.get_context("spawn").Pool(min(workers, crc.size - 1), initializer=_ignore_sigint)
    finished = False
    try:
        yield from pool.imap(functools.partial(_check_tile_task, job), [(k, crc[k]) for k in rest])
        finished = True
    finally:
        if finished:
            pool.close()
        else:
            pool.terminate()
        pool.join()


def _ignore_sigint():
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _overlaps_across_tiles(path, token, crc, base, cells, shift, window, depth):
    """``[(key, tile, row)]``: the boxes that overlap a box of another tile before them in
    the whole table's order of Morton start, then rows (``_verify_store``'s docstring)."""
    if len(cells) < 2:
        return []
    lo = np.concatenate([c[0] for c in cells])
    hi = np.concatenate([c[1] for c in cells])
    order = np.argsort(lo, kind="stable")
    lo, hi = lo[order], hi[order]
    before = np.r_[np.int64(-1), np.maximum.accumulate(hi)[:-1]] if hi.size else hi
    met = lo < before  # a tile's intervals are disjoint: this one meets another tile's
    if not met.any():
        return []
    shared = _cells(lo[met], np.minimum(hi[met], before[met]), 0)  # the cells met by two tiles (or more)
    s_lo, s_hi = shared[0] << shift, shared[1] << shift  # as runs of the deepest level
    boxes = []  # (start, key, tile, row, end) of the boxes meeting a shared cell
    for k, (c_lo, c_hi) in enumerate(cells):
        at = np.searchsorted(shared[0], c_hi, side="left") - 1
        if not np.any((at >= 0) & (shared[1][np.maximum(at, 0)] > c_lo)):
            continue
        ds = _store_tile(path, k, token, crc[k], base)
        data = decode_atlas(ds)
        arrays = _arrays(data)
        t = tiling(window, depth, data["level"].values, data["i"].values, data["j"].values,
                   arrays["e0"], arrays["e1"], arrays["u0"], arrays["u1"])
        sel = np.flatnonzero(t.placed)
        lv, ii, jj = (data[v].values[sel] for v in ("level", "i", "j"))
        start, end = _runs(depth, lv, ii, jj)
        at = np.searchsorted(s_lo, end, side="left") - 1
        meet = (at >= 0) & (s_hi[np.maximum(at, 0)] > start)
        keys = row_key(lv, ii, jj)
        boxes += [(int(a), int(b), k, int(r), int(e)) for a, b, r, e in
                  zip(start[meet], keys[meet], sel[meet], end[meet])]
    boxes.sort()
    out = []
    best_end, best_tile, second_end = -1, -1, -1  # the furthest end so far, its tile; the furthest of other tiles
    for start, key, k, row, end in boxes:
        other = best_end if best_tile != k else second_end
        if start < other:
            out.append((key, k, row))
        if k == best_tile:
            best_end = max(best_end, end)
        elif end > best_end:
            best_end, best_tile, second_end = end, k, best_end
        elif end > second_end:
            second_end = end
    return out


def _row_in_atlas(path, n_tiles, first):
    """The row of the whole table (``read_store``'s) of tile ``first[1]``'s row ``first[2]``
    (key ``first[0]``): the rows of all the tiles with a smaller key, of the tiles before
    with the same key, and of its own tile before it with the same key."""
    import zarr

    from . import _store_read as R

    key, tile, row = first[:3]
    before = 0
    for k in range(n_tiles):
        g = zarr.open_group(str(Path(path) / R.BOXES / R.tile_name(k)), mode="r")
        keys = np.sort(row_key(*(np.asarray(g[v][...]) for v in ("level", "i", "j"))))
        if k < tile:
            before += int(np.searchsorted(keys, key, side="right"))
        elif k == tile:
            before += row
        else:
            before += int(np.searchsorted(keys, key, side="left"))
    return before


def _read_checked(path):
    """The atlas file, read after its work (``verify.MAX_WORK``) is estimated
    from its variables' sizes, opened lazily; for a streamed atlas's store its sizes
    from its summary (None when it has none) instead: :func:`_verify_store` reads it a
    tile at a time, and the limit holds for each tile (:func:`_store_tile`)."""
    import xarray as xr

    from .._io import check_input

    from ._store_read import is_store, store_sizes

    s = str(path)
    check_input(path, (".nc", ".zarr"))  # a FIFO or device would block the opening below forever
    if is_store(path):  # a streamed atlas (certify_to_zarr): checked a tile at a time, the
        # work limit held by each tile (_store_tile), as its memory is
        return store_sizes(path)
    try:
        f = xr.open_zarr(s, consolidated=False) if s.endswith(".zarr") else xr.open_dataset(s, engine="netcdf4")
    except Exception:  # noqa: BLE001 - read_atlas_file names what is wrong with the file
        f = None
    if f is not None:
        with f:
            sizes = [f[name].size if name in f.variables else 0 for name in ("e0", "itinerary", "trap_cells")]
        check_work(*sizes, what=f"the atlas file {s!r}")
    return read_atlas_file(path)


def verify_file(path):
    """verify_file(path) -> (n_checked, n_rejected)

    Re-verify every box of an atlas file (``.nc`` or ``.zarr``, the layout of
    :func:`read_atlas_arrays`) with :func:`verify_arrays`; a stored ``word``
    text must be the word its itinerary spells.
    """
    verdict = _verify_path(path)
    return verdict.checked, verdict.rejected


def _verify_path(path, workers=None):
    data = _read_checked(path)
    if data is None or isinstance(data, tuple):  # a store: its sizes (or None, incomplete)
        return _verify_store(path, workers)
    return _verify_dataset(data)


def verify(obj, *, workers=None):
    """verify(cert_or_atlas_or_path, *, workers=None) -> Verdict

    Re-verify a claim with the independent checker: a :class:`Certificate`
    (from its box, status, max_iter and itinerary alone; a ``word`` status
    also needs the stated word to be the itinerary's), an atlas (an object
    whose ``boxes`` is the Dataset of :func:`read_atlas_arrays`, or that
    Dataset) or the path of an atlas file.  The verdict is true when every
    claim is re-verified, and says otherwise which check failed first.

    An atlas (a table whose attribute ``kind`` says so) is verified as a whole
    too: its texts decoded by :func:`~stairbounce.structure.certificate.decode_atlas`
    (a code out of range or a missing names list: ValueError), each stored word the
    one its itinerary spells, each reason one its status may carry, each trapping
    region re-verified, each box the quadtree box ``(level, i, j)`` of the stated
    window at the stated depth (edges bit for bit) and inside it, no two boxes
    overlapping (``structure/tiling.py``); the verdict says whether they cover the
    window and carries the derived numbers proven from the verified boxes
    (:class:`Verdict`'s ``numbers``, of the covered part when they do not).  A streamed
    atlas's store (:func:`stairbounce.certify_to_zarr`) is checked tile by tile, with the
    memory of a tile, to the same verdict (``_verify_store``); with ``workers`` (an int
    >= 2) its tiles are checked in that many processes (spawned: a script that calls
    this needs Python's ``if __name__ == "__main__":`` guard), each holding a tile
    (about 0.6 GiB at depth 14), the results combined in the tiles' order: the same
    verdict (the checker's compiled loop runs on one core: 2 processes took 42 s for
    depth 14's store where one took 66 s).  Other objects ignore ``workers``.
    """
    if workers is not None:
        from ..model import check_count

        workers = check_count("workers", workers, 1)
    if isinstance(obj, Certificate):
        check_certificate_fields(obj)
        return _verify_certificate(obj)
    if isinstance(obj, (str, Path)):
        return _verify_path(obj, workers)
    data = getattr(obj, "boxes", obj)
    if hasattr(data, "variables") and hasattr(data, "attrs"):
        return _verify_dataset(data)
    raise ValueError(f"verify needs a Certificate, an atlas (with boxes) or a path, got {type(obj).__name__}")
