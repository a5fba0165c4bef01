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
from .certificate import STATUSES, Certificate
from .verify import _OK, _TRAP, _WORD, _WORD_S, CHECKS, verify_codes

__all__ = ["Verdict", "verify", "verify_file", "read_atlas_arrays"]


@dataclass(frozen=True)
class Verdict:
    """The checker's answer: ``ok``, and else which check failed, at which step.

    For an atlas or a file, ``checked`` and ``rejected`` count its boxes and
    ``check``/``step`` describe the first rejected one.  True in a boolean
    context exactly when ``ok``.
    """

    ok: bool
    check: str | None = None
    step: int | None = None
    message: str = ""
    checked: int = 1
    rejected: int = 0

    def __bool__(self) -> bool:
        return self.ok


def _arrays_of_certificate(cert):
    itin = np.asarray(cert.itinerary, dtype=np.int64).ravel()
    status = STATUSES.index(cert.status) if cert.status in STATUSES else -1
    return (np.array([cert.e[0]], dtype=float), np.array([cert.e[1]], dtype=float),
            np.array([cert.u[0]], dtype=float), np.array([cert.u[1]], dtype=float),
            np.array([status]), cert.max_iter, itin, np.array([0, len(itin)]))


def _verify_certificate(cert):
    if cert.status == "no_sliding" and cert.reason == "trapping":  # a trapping region (verify_trapping.py)
        from .verify_trapping import verify_certificate_region

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
    dimension), ``offsets`` (box + 1) and the attribute ``max_iter``.
    """
    need = ("e0", "e1", "u0", "u1", "status", "itinerary", "offsets")
    missing = [name for name in need if name not in data.variables]
    if missing or "max_iter" not in data.attrs:
        raise ValueError(f"atlas must hold the variables {', '.join(need)} and the attribute max_iter; "
                         f"missing: {', '.join(missing + ([] if 'max_iter' in data.attrs else ['max_iter']))}")
    out = {name: np.asarray(data[name].values) for name in need}
    out["max_iter"] = int(data.attrs["max_iter"])
    if "word" in data.variables:
        out["word"] = np.asarray(data["word"].values)
    return out


def _check_words(arrays, code):
    """Where a stored word text disagrees with the word its itinerary spells."""
    words = arrays.get("word")
    if words is None:
        return
    status = np.asarray(arrays["status"])
    if status.dtype.kind in "USO":
        is_word = np.array([str(s) == "word" for s in status])
    else:
        is_word = status == _WORD_S
    itin, off = np.asarray(arrays["itinerary"], dtype=np.int64), np.asarray(arrays["offsets"], dtype=np.int64)
    for i in np.flatnonzero(is_word & (code == _OK)):
        try:
            same = parse_word(str(words[i])) == word_from_impacts(itin[off[i]:off[i + 1]])
        except ValueError:
            same = False
        if not same:
            code[i] = _WORD


def _verify_dataset(data):
    arrays = read_atlas_arrays(data)
    code, step = verify_codes(arrays["e0"], arrays["e1"], arrays["u0"], arrays["u1"], arrays["status"],
                              arrays["max_iter"], arrays["itinerary"], arrays["offsets"])
    _check_words(arrays, code)
    if "reason" in data.variables:  # no_sliding boxes proven by trapping regions (verify_trapping.py)
        from .verify_trapping import check_atlas_regions

        check_atlas_regions(data, arrays, code, _TRAP)
    bad = np.flatnonzero(code != _OK)
    n = len(code)
    if not len(bad):
        return Verdict(True, None, None, f"{n} boxes re-verified", checked=n, rejected=0)
    i = int(bad[0])
    st = int(step[i])
    return Verdict(False, CHECKS[code[i]], st or None,
                   f"{len(bad)} of {n} boxes rejected; the first, box {i}, failed check '{CHECKS[code[i]]}'"
                   + (f" at step {st}" if st else ""), checked=n, rejected=len(bad))


def _open(path):
    import xarray as xr

    path = Path(path)
    if path.suffix == ".zarr":
        return xr.open_zarr(path)
    if path.suffix == ".nc":
        return xr.open_dataset(path)
    raise ValueError(f"path must be an atlas file ending in .nc or .zarr, got {str(path)!r}")


def verify_file(path):
    """verify_file(path) -> (n_checked, n_rejected)

    Re-verify every box of an atlas file (``.nc`` or ``.zarr``, the layout of
    :func:`read_atlas_arrays`) with :func:`verify_arrays`; a stored ``word``
    text must be the word its itinerary spells.
    """
    with _open(path) as data:
        verdict = _verify_dataset(data.load())
    return verdict.checked, verdict.rejected


def verify(obj):
    """verify(cert_or_atlas_or_path) -> Verdict

    Re-verify a claim with the independent checker: a :class:`Certificate`
    (from its box, status, max_iter and itinerary alone; a ``word`` status
    also needs the stated word to be the itinerary's), an atlas (an object
    whose ``boxes`` is the Dataset of :func:`read_atlas_arrays`, or that
    Dataset) or the path of an atlas file.  The verdict is true when every
    claim is re-verified, and says otherwise which check failed first.
    """
    if isinstance(obj, Certificate):
        return _verify_certificate(obj)
    if isinstance(obj, (str, Path)):
        with _open(obj) as data:
            return _verify_dataset(data.load())
    data = getattr(obj, "boxes", obj)
    if hasattr(data, "variables") and hasattr(data, "attrs"):
        return _verify_dataset(data)
    raise ValueError(f"verify needs a Certificate, an atlas (with boxes) or a path, got {type(obj).__name__}")
