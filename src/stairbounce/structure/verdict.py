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
from .certificate import ATLAS_REASONS, STATUSES, Certificate, check_certificate_fields, decode_atlas, read_atlas_file
from .tiling import AreaBook, deepest_level, tiling
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


def _check_words(arrays, code):
    """Where a stored word text disagrees with the word its itinerary spells, or a box
    that is not proven ``word`` states a word."""
    words = arrays.get("word")
    if words is None:
        return
    is_word = np.asarray(arrays["status"]) == _WORD_S
    itin, off = np.asarray(arrays["itinerary"], dtype=np.int64), np.asarray(arrays["offsets"], dtype=np.int64)
    spelled, parsed, same = {}, {}, {}  # each itinerary spelled once, each text parsed once
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
    wlo, whi = book.window
    clo, chi = book.covered
    return {
        "basis": "proven: sums of the verified boxes' exact areas, rounded outward (structure/tiling.py)",
        "of": book.of,
        "window_area": book.window, "covered_area": book.covered,
        "uncovered_area": (0.0, 0.0) if complete else (max(float(np.nextafter(wlo - chi, -np.inf)), 0.0),
                                                       float(np.nextafter(whi - clo, np.inf))),
        "status": {name: book.share(status == k) for k, name in enumerate(STATUSES)},
        "reason": {r: book._ratio(*a) for r, a in book.groups(reasons, undecided).items()},
        "words": book.word_bounds(status, words, arrays["max_iter"], lambda w: parse_word(w).period),
    }


def _verify_dataset(data):
    _need(data)
    data = decode_atlas(data)
    arrays = _arrays(data)
    code, step = verify_codes(arrays["e0"], arrays["e1"], arrays["u0"], arrays["u1"], arrays["status"],
                              arrays["max_iter"], arrays["itinerary"], arrays["offsets"])
    _check_words(arrays, code)
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
    is_atlas = data.attrs.get("kind") == "stairbounce certified atlas"
    complete = None
    names = CHECKS + ("reason", "place", "overlap")
    if is_atlas:
        window, depth = _window(data)
        t = tiling(window, depth, data["level"].values, data["i"].values, data["j"].values,
                   arrays["e0"], arrays["e1"], arrays["u0"], arrays["u1"])
        code[~t.placed] = _PLACE
        code[t.overlapping & t.placed] = _OVERLAP
        step[~t.placed | t.overlapping] = 0
        complete = t.complete
    bad = np.flatnonzero(code != _OK)
    n = len(code)
    if len(bad):
        i = int(bad[0])
        st = int(step[i])
        return Verdict(False, names[code[i]], st or None,
                       f"{len(bad)} of {n} boxes rejected; the first, box {i}, failed check '{names[code[i]]}'"
                       + (f" at step {st}" if st else ""), checked=n, rejected=len(bad), atlas=is_atlas,
                       complete=complete)
    if not is_atlas:
        return Verdict(True, None, None, f"{n} boxes re-verified (a table of certificates, not an atlas: no "
                       "window stated, no derived numbers)", checked=n, rejected=0)
    numbers = _numbers(data, arrays, window, complete)
    cover = ("they cover the window" if complete else
             f"they do not cover the window ({t.missing} of {4 ** depth} cells of the deepest level missing, "
             f"uncovered area in [{numbers['uncovered_area'][0]:.6g}, {numbers['uncovered_area'][1]:.6g}]); "
             "every derived number is of the covered part")
    return Verdict(True, None, None, f"{n} boxes re-verified, each the quadtree box of the window it states, "
                   f"none overlapping; {cover}", checked=n, rejected=0, atlas=True, complete=complete,
                   numbers=numbers)


def _read_checked(path):
    """The atlas file, read after its work (``verify.MAX_WORK``) is estimated
    from its variables' sizes, opened lazily."""
    import xarray as xr

    from .._io import check_input

    from ._store_read import is_store, store_sizes

    s = str(path)
    check_input(path, (".nc", ".zarr"))  # a FIFO or device would block the opening below forever
    if is_store(path):  # a streamed atlas (certify_to_zarr): its size from its summary
        sizes = store_sizes(path)
        if sizes is not None:
            check_work(*sizes, what=f"the atlas store {s!r}")
        return read_atlas_file(path)
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
    verdict = _verify_dataset(_read_checked(path))
    return verdict.checked, verdict.rejected


def verify(obj):
    """verify(cert_or_atlas_or_path) -> Verdict

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
    (:class:`Verdict`'s ``numbers``, of the covered part when they do not).
    """
    if isinstance(obj, Certificate):
        check_certificate_fields(obj)
        return _verify_certificate(obj)
    if isinstance(obj, (str, Path)):
        return _verify_dataset(_read_checked(obj))
    data = getattr(obj, "boxes", obj)
    if hasattr(data, "variables") and hasattr(data, "attrs"):
        return _verify_dataset(data)
    raise ValueError(f"verify needs a Certificate, an atlas (with boxes) or a path, got {type(obj).__name__}")
