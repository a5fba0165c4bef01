"""The report's vocabulary: a :class:`Row` (paper says / we measured, a
verdict and a basis), a recipe's :class:`Result`, and the criteria stated in
the report's header."""

from __future__ import annotations

from dataclasses import dataclass, field



VERDICTS = ("agrees", "differs", "not comparable")
"""What a report row can conclude; "differs" says by how much and
"not comparable" says why, in :attr:`Row.why`."""

BASES = ("proven", "numerical")
"""What a report row's statement rests on (:attr:`Row.basis`): a proof, or
a floating-point computation (see :data:`BASIS_CRITERION`)."""


@dataclass
class Row:
    """One line of the report: a quantity, the paper's statement, ours, and the verdict.

    ``verdict`` is one of :data:`VERDICTS`; ``why`` says by how much a row
    differs, why it is not comparable, or on what margin it agrees.  Rows
    made with only ``agrees`` (True/False) get "agrees"/"differs"; a row with
    neither is printed as "no verdict", which the tests do not let through.
    ``basis`` is one of :data:`BASES`: "proven" (with ``proof`` saying by
    what) only where the row's statement is a theorem for every real point it
    speaks of (:data:`BASIS_CRITERION`); "numerical", the default, otherwise.
    """

    quantity: str
    paper: str
    measured: str
    agrees: bool | None = None
    verdict: str | None = None
    why: str = ""
    basis: str = "numerical"
    proof: str = ""

    def __post_init__(self):
        if self.basis not in BASES:
            raise ValueError(f"basis must be one of {', '.join(BASES)}, got {self.basis!r}")
        if self.basis == "proven" and not self.proof:
            raise ValueError("a proven row must say by what (proof)")
        if self.verdict is None and self.agrees is not None:
            self.verdict = "agrees" if self.agrees else "differs"
        if self.verdict is not None and self.verdict not in VERDICTS:
            raise ValueError(f"verdict must be one of {', '.join(VERDICTS)}, got {self.verdict!r}")
        if self.agrees is None and self.verdict in ("agrees", "differs"):
            self.agrees = self.verdict == "agrees"

    def verdict_text(self) -> str:
        if self.verdict is None:
            return "no verdict"
        return self.verdict + (f": {self.why}" if self.why else "")

    def basis_text(self) -> str:
        """``"proven: PROOF"`` or ``"numerical"`` (with its note, if any)."""
        return self.basis + (f": {self.proof}" if self.proof else "")


@dataclass
class Result:
    """What a recipe made: its files, caption, report rows and parameters."""

    name: str
    title: str
    files: list[str] = field(default_factory=list)
    rows: list[Row] = field(default_factory=list)
    params: dict = field(default_factory=dict)
    seconds: float = 0.0
    error: str | None = None
    caption: str = ""


CRITERION = (
    "A row **agrees** when the paper's number lies inside our interval (the row states the "
    "interval: for a fitted dimension the 95% interval of the fit widened by the drift of the "
    "local slope over the fitted scales), or, for an exact statement of the paper (a theorem, a "
    "corollary), when our measurement meets it to the tolerance the row states; it **differs** "
    "otherwise, by the amount the row states. It is **not comparable** when the paper gives "
    "nothing our measurement could contradict, or when our measurement cannot test the statement "
    "(a fit whose interval leaves [1, 2], a number that restates a theorem); the row says why. "
    "Rows whose quantity begins with 'ours:' are claims of ours, not the paper's: their paper "
    "column is '-' and the measurement says whether the claim holds; where the row tests the "
    "claim by a criterion it states (a fitted law's decision, a closed form) it **agrees** when "
    "the claim passes and **differs** when it fails, otherwise it is not comparable. 'Here' means computed in "
    "this run, except where the row says 'not recomputed'."
)
"""The report's verdict criterion, stated once in its header."""

BASIS_CRITERION = (
    "Every row is either **proven** or **numerical** (the basis column). A row is proven only "
    "when its statement holds at every real point it speaks of, by a proof the column names: "
    "every decision taken by outward-rounded interval arithmetic over whole boxes of (e, u) "
    "(stairbounce.certify_box / certify) and every certificate re-verified by the independent "
    "checker stairbounce.verify; a proven row whose certificates the checker rejects is "
    "numerical and differs. Everything else is numerical: floating-point computations (exact to "
    "rounding and checked against independent code, but a float decision near a border can fall "
    "on the wrong side), pixel samples, fits, and analytic facts evaluated in floats. Proven areas "
    "are rounded down and proven counts are lower or upper bounds, as the row says; a proven row "
    "agrees when its certificates are re-verified and the numerical measurement beside it does "
    "not contradict the proven bound."
)
"""The criterion of the report's basis column (:attr:`Row.basis`), stated in its header."""


def _compare(value, paper, ci, unit=""):
    """A verdict on a measured ``value`` with interval ``ci`` against the
    paper's ``paper``: "agrees" when ``paper`` lies inside ``ci``, else
    "differs" by ``value - paper``; "not comparable" when ``ci`` leaves the
    range [1, 2] a border's dimension can take (a failed fit)."""
    lo, hi = float(ci[0]), float(ci[1])
    delta = value - paper
    where = f"interval [{lo:.3f}, {hi:.3f}]"
    if not (1.0 <= lo and hi <= 2.0):
        return "not comparable", (f"a failed fit: its {where} reaches outside [1, 2], the "
                                  f"dimensions a border in the plane can have")
    ok = lo <= paper <= hi
    return (("agrees" if ok else "differs"),
            f"{delta:+.3f}{unit}: the paper's {paper:g} is {'inside' if ok else 'outside'} our {where}")


def _ours(quantity, measured, holds, criterion):
    """A row for a claim of ours (not the paper's): the paper column is '-',
    the measurement says whether the claim holds and by which criterion."""
    return Row(f"ours: {quantity}", "-",
               f"{measured}; {'holds' if holds else 'FAILS'} ({criterion})",
               verdict="not comparable", why="a claim of ours; the paper says nothing about it")


def _ours_tested(quantity, measured, holds, criterion, note=""):
    """A row for a claim of ours tested by a stated criterion: the paper column
    is '-', the verdict agrees when the claim passes and differs when it fails."""
    return Row(f"ours: {quantity}", "-", measured, verdict="agrees" if holds else "differs",
               why=f"a claim of ours, {'passes' if holds else 'FAILS'}: {criterion}", proof=note)
