"""The registry of every recipe, in the paper's order (:data:`FIGURES`), and
:func:`make_figures`, which runs a selection of them."""

from __future__ import annotations

import math
import time
import traceback
from pathlib import Path

from .dimension import _dimension
from .motion import motion_cut, motion_k, motion_lyap
from .orbits import fig1, fig2, fig8, fig9
from .plane import _blowup, fig3, fig4
from .rows import Result
from .settings import BLOWUPS, DIMENSION_WINDOWS, Settings, _mark_folder


FIGURES = {
    "fig1": fig1,
    "fig2": fig2,
    "fig3": fig3,
    "fig4": fig4,
    **{name: _blowup(name) for name in BLOWUPS},
    **{name: _dimension(name) for name in DIMENSION_WINDOWS},
    "fig8": fig8,
    "fig9": fig9,
}
"""Recipe of every figure, in the paper's order."""

FIGURES.update({"motion_k": motion_k, "motion_lyap": motion_lyap, "motion_cut": motion_cut})


def select(only=None):
    """The recipe names for ``only`` (names or prefixes such as ``fig5``), in order."""
    if not only:
        return list(FIGURES)
    wanted = []
    for item in only:
        item = item.strip()
        names = [n for n in FIGURES if n == item or (n.startswith(item) and item == n[:4])]
        if not names:
            raise ValueError(f"only: unknown figure {item!r}; choose from {', '.join(FIGURES)}")
        wanted += [n for n in names if n not in wanted]
    return [n for n in FIGURES if n in wanted]


def make_figures(settings: Settings, only=None, on_start=None, on_done=None) -> list[Result]:
    """make_figures(settings, only=None, on_start=None, on_done=None) -> list[Result]

    Run the recipes named in ``only`` (all by default) into ``settings.out``.

    A recipe that raises is reported in its :class:`Result` (``error``) and
    the others still run; ``KeyboardInterrupt`` stops at once (no file is left
    half-written: every file is written under a temporary name).
    """
    import matplotlib

    matplotlib.use("Agg")
    if settings.fmt not in ("png", "pdf", "svg"):
        raise ValueError(f"format must be one of png, pdf, svg, got {settings.fmt!r}")
    if not (isinstance(settings.dpi, int) and 10 <= settings.dpi <= 1200):
        raise ValueError(f"dpi must be an integer in [10, 1200], got {settings.dpi!r}")
    if not (math.isfinite(settings.scale) and 0.01 <= settings.scale <= 16):
        raise ValueError(f"scale must be in [0.01, 16], got {settings.scale!r}")
    names = select(only)
    Path(settings.out).mkdir(parents=True, exist_ok=True)
    _mark_folder(settings)
    results = []
    for name in names:
        if on_start:
            on_start(name)
        t0 = time.perf_counter()
        try:
            res = FIGURES[name](settings)
        except KeyboardInterrupt:
            raise
        except Exception as exc:  # one failing figure must not stop the others
            res = Result(name, name, error=f"{type(exc).__name__}: {exc}")
            res.params["traceback"] = traceback.format_exc(limit=6)
        res.seconds = time.perf_counter() - t0
        results.append(res)
        if on_done:
            on_done(res)
    return results
