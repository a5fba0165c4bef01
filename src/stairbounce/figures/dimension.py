"""Borders and dimension: Figs. 6 and 7 (the border of the sliding region and
its box counting), the slicing estimator computed in the run, and the
dimension study's shipped result (:func:`load_border_dimension`)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .proven import _border_bracket_row, _certified_atlas, _proven_area_row
from .rows import Result, Row, _compare
from .settings import DIMENSION_WINDOWS, Settings, _save, _scan


STUDY_FILE = Path(__file__).parent.parent / "data" / "border_dimension.json"
"""The dimension study's best estimate per window (written by the study of
the border's dimension; see docs/guide/dimension-study.md)."""


def load_border_dimension(path=None):
    """load_border_dimension(path=None) -> dict or None

    The dimension study's result, ``{"fig6": {"dimension": D, "ci95": [lo,
    hi], "method": str, "details": str, "systematic": s, "interval": [lo - s,
    hi + s]}, "fig7": {...}}`` (``systematic``: the drift of the estimate
    across its scales, 0 when the file has none; ``uncertainty_by_max_iter`` and
    ``max_iter_check``, its max_iter check, when the file has them), read from ``path``
    (default :data:`STUDY_FILE`); None when the file is absent, so that a
    figure says "no study result" rather than show a number nobody measured.

    Raises ValueError naming the file when it is malformed.
    """
    path = STUDY_FILE if path is None else Path(path)
    if not path.exists():
        return None
    from ..dimension import border_dimension_estimates

    try:
        data = border_dimension_estimates(path)
        out = {}
        for name, entry in data.items():
            if not isinstance(entry, dict):  # "generated_by", "date": provenance, not a window
                continue
            lo, hi = (float(x) for x in entry["ci95"])
            d = float(entry["dimension"])
            if not (math.isfinite(d) and lo <= hi):
                raise ValueError("dimension must be finite and ci95 = [lo, hi] with lo <= hi")
            sys_ = float(entry.get("systematic", 0.0))
            if not (math.isfinite(sys_) and sys_ >= 0):
                raise ValueError("systematic must be a finite number >= 0")
            out[name] = {"dimension": d, "ci95": [lo, hi], "method": str(entry["method"]),
                         "details": str(entry.get("details", "")), "systematic": sys_,
                         "interval": [lo - sys_, hi + sys_]}
            for key in ("uncertainty_by_max_iter", "max_iter_check"):  # its max_iter check, if any
                if isinstance(entry.get(key), dict):
                    out[name][key] = entry[key]
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise ValueError(f"border_dimension: {path} is not a dimension study result "
                         f"({type(exc).__name__}: {exc})") from None
    return out


_FIT_WHY = ("every power-of-two box from 1 px to an eighth of the picture: our reading of the "
            "paper's 'standard box-counting algorithm on the pictures' (it states no range); "
            "it includes the pixel scale")


_FIT_WHY_SHORT = (
    "every power-of-two box from 1 px to an eighth of the picture:",
    "our reading of the paper's 'standard box-counting algorithm' (it states no range); "
    "it includes the pixel scale.",
)


def _dimension(name):
    def recipe(s: Settings) -> Result:
        from ..dimension import boundary, box_dimension
        from ..plot import plot_border, plot_box_counts

        (e, u), paper = DIMENSION_WINDOWS[name]
        res = s.px(500)
        # perimeter_dimension's steps, on the cached scan: the border of the
        # sliding region (status 0), the window's frame not counted
        ds = _scan(s, name, e, u, res, res)
        region = ds.status.transpose("u", "e").values == 0
        s.note(f"{name}: box counting")
        border = boundary(region)
        fit_range = (1, max(4, 2 ** round(math.log2(res / 8))))
        est = box_dimension(border, fit_range=fit_range)
        auto = box_dimension(border)
        # the same picture at SLICING_CHECK x max_iter: the fits cut to the box
        # sizes where it does not move the local slope
        from dataclasses import replace

        more = SLICING_CHECK * s.max_iter
        again = boundary(_scan(replace(s, max_iter=more), name, e, u, res, res)
                         .status.transpose("u", "e").values == 0)
        checked = [_box_checked(fit, box_dimension(again, fit_range=fit.fit_range), s.max_iter, more)
                   for fit in (est, auto)]
        est, auto = (fit for fit, _, _ in checked)
        study = load_border_dimension(s.border_dimension)
        best = None if study is None else study.get(name)
        # fixed panels: the border's panel square (the window is square), and at
        # least as many screen pixels as the picture has, at the file's dpi
        import matplotlib.pyplot as plt

        width, height, side = 13.0, 7.6, 4.4
        fig = plt.figure(figsize=(width, height), dpi=s.dpi)
        ax0 = fig.add_axes((0.07, 0.27, side / width, side / height))
        ax1 = fig.add_axes((0.55, 0.27, 0.42, side / height))
        plot_border(border, e, u, ax=ax0, title=f"border of the sliding region, {res} x {res} px")
        plot_box_counts(est, ax=ax1)
        fig.suptitle(f"Fig. {name[-1]}: border of the sliding region in "
                     f"[{e[0]:g}, {e[1]:g}] x [{u[0]:g}, {u[1]:g}] and its box counting")
        lo, hi = est.interval
        if best is not None:
            study_line = (f"dimension study (best estimate, shipped, not recomputed): D = "
                          f"{best['dimension']:.3f} [{best['interval'][0]:.3f}, "
                          f"{best['interval'][1]:.3f}] with its drift, {best['method']}")
        else:
            study_line = "dimension study (best estimate): no study result"
        lines = [
            f"fit range: boxes {fit_range[0]}-{fit_range[1]} px, {_FIT_WHY_SHORT[0]}",
            _FIT_WHY_SHORT[1],
            f"paper: D = {paper}    this fit: D = {est.dimension:.3f} [{lo:.3f}, {hi:.3f}] "
            f"(with the drift of the local slope), max_iter {s.max_iter}",
            f"automatic range ({auto.fit_range[0]}-{auto.fit_range[1]} px, excludes the pixel "
            f"scale): D = {auto.dimension:.3f} [{auto.interval[0]:.3f}, {auto.interval[1]:.3f}]",
            study_line,
        ]
        fig.text(0.07, 0.05, "\n".join(lines), fontsize=9, va="bottom", ha="left")
        v1, w1 = _compare(est.dimension, paper, est.interval)
        v2, w2 = _compare(auto.dimension, paper, auto.interval)
        if v1 != "not comparable" and est.r <= 0.99:
            v1, w1 = "differs", w1 + f"; r = {est.r:.4f} <= 0.99, the paper's r > 0.99"
        if not checked[0][2]:
            v1, w1 = "not comparable", f"max_iter {s.max_iter} is not converged over enough box sizes to fit"
        if not checked[1][2]:
            v2, w2 = "not comparable", f"max_iter {s.max_iter} is not converged over enough box sizes to fit"
        rows = [
            Row(f"box-counting dimension, boxes {fit_range[0]}..{fit_range[1]} px",
                f"D = {paper}, r > 0.99", _dimension_text(est, res, s.max_iter) + checked[0][1],
                verdict=v1, why=w1),
            Row("box-counting dimension, automatic linear range (heuristic)", f"D = {paper}",
                _dimension_text(auto, res, s.max_iter) + checked[1][1],
                verdict=v2, why=w2 + "; this range leaves out the pixel scale the paper's "
                "fit includes (docs/guide/dimension-study.md)"),
        ]
        rows.append(_slicing_row(s, name, e, u, paper))
        rows.append(_study_row(name, paper, best))
        certified = _certified_atlas(s, name, e, u, perimeter=True)
        if name == "fig7":
            rows.append(_proven_area_row(s, name, e, u, ds, certified))
        rows.append(_border_bracket_row(s, name, certified, est))
        if best is not None:
            from types import SimpleNamespace

            from ..dimension import disagree

            study_est = SimpleNamespace(dimension=best["dimension"], interval=best["interval"])
            warn = disagree(auto, study_est)
            if warn:  # one line, on the row of the picture's estimate
                rows[1].measured += f". {warn[0].upper()}{warn[1:]} (this picture's automatic fit, the study)"
        caption = (f"Left: the border of the region with a periodic sliding solution (status 0, "
                   f"max_iter = {s.max_iter}) in the paper's window [{e[0]:g}, {e[1]:g}] x "
                   f"[{u[0]:g}, {u[1]:g}] at the paper's 500 px (here {res} px), black on white, "
                   f"square pixels. Right: log N(s) against log(1/s); filled: the fitted box "
                   f"sizes, hollow: not fitted, shaded: the fit range {fit_range[0]}-"
                   f"{fit_range[1]} px ({_FIT_WHY}); red: the fitted line. Under the panels: the "
                   f"paper's D, this fit, the automatic range, and the dimension study's best "
                   f"estimate.")
        return Result(name, f"Box-counting dimension of the border (Fig. {name[-1]})",
                      [_save(fig, s, name)], rows,
                      {"e": e, "u": u, "resolution": res, "max_iter": s.max_iter,
                       "fit_range": fit_range, "D": est.dimension, "r": est.r,
                       "ci": list(est.ci), "interval": list(est.interval),
                       "systematic": est.systematic, "D_auto": auto.dimension,
                       "D_study": None if best is None else best["dimension"]},
                      caption=caption)

    recipe.__name__ = name
    recipe.__doc__ = f"Fig. {name[-1]}: border and box counting of {DIMENSION_WINDOWS[name][0]}."
    return recipe


STUDY_RECOMPUTE = {
    # the study's fine-scale protocol (data/border_dimension.json, "details"), as one command;
    # 2 x 10^4 points of it took 15 s on a 2-core machine, so 2 x 10^6 take about 20 minutes
    name: (f"stairbounce dimension --e {e[0]:g}:{e[1]:g} --u {u[0]:g}:{u[1]:g} "
           f"--points 2000000 --max-iter 16000 --eps 1e-9:1e-3:13", 20)
    for name, ((e, u), _) in DIMENSION_WINDOWS.items()
}
"""Per window: the command that recomputes the dimension study's best
estimate, and about how many minutes it takes on a 2-core machine."""


# slicing in the report: scales where max_iter 1000 is converged (docs/guide/dimension.md)
SLICING_SCALES = (1e-6, 1e-2)
SLICING_LINES = 64
# the slicing row is measured again at this many times the run's max_iter
SLICING_CHECK = 4


def _slicing_row(s, name, e, u, paper):
    """The third estimator, computed in this run: slicing along random lines
    (seed 0) over SLICING_SCALES of the window, at the run's max_iter and
    again at SLICING_CHECK x max_iter on the same lines; the fit is cut to the
    scales where the larger max_iter does not move the local dimension, and
    the verdict is the cut fit's."""
    from ..dimension import max_iter_check, sliding_classifier, slicing_dimension

    lines = max(8, int(round(SLICING_LINES * min(s.scale, 1.0))))
    more = SLICING_CHECK * s.max_iter
    s.note(f"{name}: slicing along {lines} lines, max_iter {s.max_iter} and {more}")
    est, again = (slicing_dimension(sliding_classifier(max_iter=m), (e, u), n_lines=lines,
                                    scale_min=SLICING_SCALES[0], scale_max=SLICING_SCALES[1], seed=0)
                  for m in (s.max_iter, more))
    check = max_iter_check(est, again)
    cut = check.cut(est.scales)
    what = ("dimension by slicing (crossings along random lines), computed in this run, "
            f"checked at max_iter {more}")
    setup = f"{lines} lines, seed 0, max_iter {s.max_iter}"
    if check.converged:
        conv = (f"max_iter {s.max_iter} -> {more}: converged at scales "
                f"{est.scales[0]:.2g}..{est.scales[1]:.2g}")
    else:
        bad = check.not_converged
        conv = (f"max_iter {s.max_iter} -> {more}: "
                + ("no scale measured at both" if bad is None
                   else f"not converged at scales {bad[0]:.2g}..{bad[1]:.2g} (local dimensions)")
                + ": fitted range cut to ")
        try:
            est = est.refit(cut) if cut is not None else None
        except ValueError:  # fewer than 3 converged levels
            est = None
        if est is None:
            return Row(what, f"D = {paper}", f"{conv}fewer than 3 converged levels, no fit ({setup})",
                       verdict="not comparable",
                       why=f"max_iter {s.max_iter} is not converged over enough scales to fit")
        conv += f"{est.scales[0]:.2g}..{est.scales[1]:.2g}"
    v, w = _compare(est.dimension, paper, est.interval)
    lo, hi = est.interval
    warn = est.warning()
    return Row(what, f"D = {paper}",
               f"D = {est.dimension:.3f}, interval [{lo:.3f}, {hi:.3f}] (95% statistical "
               f"+-{est.statistical:.3f}, drift +-{est.systematic:.3f}), scales "
               f"{est.scales[0]:.2g}..{est.scales[1]:.2g} of the window, {setup}; {conv}; "
               "biased low by 0.01-0.04 (Weierstrass validation)"
               + (f". {warn[0].upper()}{warn[1:]}" if warn else ""), verdict=v, why=w)


def _box_checked(est, again, max_iter, more):
    """A box-counting fit checked against the same picture at ``more``
    iterations: ``(fit, text, ok)``, the fit cut to the box sizes whose local
    slopes do not move (``est`` itself when none moves); with fewer than 3
    converged sizes ``est`` as it was and ``ok`` False (no verdict)."""
    from ..dimension import box_dimension_from_counts, max_iter_check

    check = max_iter_check(est, again)
    a, b = est.fit_range
    head = f"; max_iter {max_iter} -> {more}: "
    if check.converged:
        return est, head + f"converged at boxes {a}..{b} px", True
    bad = check.not_converged
    moved = ("no box size measured at both" if bad is None
             else f"not converged at the local slopes of boxes {bad[0]:.3g}..{bad[1]:.3g} px")
    cut = check.cut(est.fit_range)
    sizes = np.asarray(est.sizes)[est.usable]
    mids = est.local_dimensions[0]  # between sizes[k] and sizes[k + 1], as the check's scales
    if cut is not None:
        k = np.flatnonzero((mids >= cut[0]) & (mids <= cut[1]))
        try:
            fit = box_dimension_from_counts(est.sizes, est.counts,
                                            fit_range=(sizes[k[0]], sizes[k[-1] + 1]))
            return (fit, head + f"{moved}: fitted range cut to boxes {fit.fit_range[0]}.."
                    f"{fit.fit_range[1]} px", True)
        except ValueError:  # fewer than 3 sizes
            pass
    return est, head + f"{moved}: fewer than 3 converged box sizes, no fit", False


def _dimension_text(est, res, max_iter):
    """A box-counting estimate as a report cell: D, its drift-covering
    interval with the two terms apart, the scales, r, the picture, max_iter
    and the one-line warning when the drift exceeds the statistical interval."""
    lo, hi = est.interval
    a, b = est.fit_range
    warn = est.warning()
    return (f"D = {est.dimension:.3f}, interval [{lo:.3f}, {hi:.3f}] (95% fit +-{est.statistical:.3f}, "
            f"drift +-{est.systematic:.3f}: {est.halves[0]:.3f} over the finer, "
            f"{est.halves[1]:.3f} over the coarser half), boxes {a}..{b} px of {res} "
            f"({a / res:.3g}..{b / res:.3g} of the window), r = {est.r:.4f}, max_iter {max_iter}"
            + (f". {warn[0].upper()}{warn[1:]}" if warn else ""))


def _study_row(name, paper, best):
    """The report row of the dimension study's best estimate for window
    ``name`` (``best``: its entry of :func:`load_border_dimension`, or None)
    against the paper's ``paper``, with the tiled box count beside it.  The
    number is shipped data, not recomputed: the row says so and how to."""
    quantity = "dimension study, best estimate (shipped, not recomputed in this run)"
    if best is None:
        return Row(quantity, f"D = {paper}", "no study result",
                   verdict="not comparable", why="stairbounce/data/border_dimension.json is absent")
    command, minutes = STUDY_RECOMPUTE.get(name, ("benchmarks/dimension_study.py", 60))
    v, w = _compare(best["dimension"], paper, best["interval"])
    iv = best["interval"]
    return Row(quantity, f"D = {paper}",
               f"D = {best['dimension']:.3f}, interval [{iv[0]:.3f}, {iv[1]:.3f}] (95% statistical "
               f"[{best['ci95'][0]:.3f}, {best['ci95'][1]:.3f}], drift +-{best['systematic']:.3f}; "
               f"{best['method']}, eps 1e-9..1e-3 of the window, max_iter 16000){_same_scales(name)}; "
               f"from the dimension study, not "
               f"recomputed: `{command}` recomputes it in about {minutes} minutes"
               f"{_study_max_iter_text(best)}",
               verdict=v, why=w)


def _study_max_iter_text(best):
    """The max_iter check of the study's estimate, as measured (shipped with it):
    the uncertainty exponent at max_iter 1000/4000/16000 over its default scales, and
    slicing at 4000 and 16000 over the fine scales the best estimate covers."""
    parts = []
    by = best.get("uncertainty_by_max_iter") or {}
    if by:
        ds = [f"{by[k]['sliding']['dimension']:.3f}" for k in sorted(by, key=int)]
        parts.append(f"max_iter {'/'.join(sorted(by, key=int))} move the default-scale estimate "
                     f"(eps 1e-6..1e-1): {'/'.join(ds)}")
    chk = best.get("max_iter_check")
    if chk:
        a, b = chk["max_iter"]
        da, db = chk["dimension"]
        parts.append(f"slicing at max_iter {a} and {b} over {chk['scales'][0]:g}..{chk['scales'][1]:g}: "
                     f"{da:.3f} and {db:.3f}, converged down to about {chk['converged_down_to']:g} of the "
                     f"window; {chk['finest_decade']}")
    return ("; max_iter check (measured with the study, not in this run): " + "; ".join(parts)) if parts else ""


def _same_scales(name):
    """The tiled box count beside the best estimate, at the scales both
    estimators measure (benchmarks/dimension_study.py;
    docs/guide/dimension-study.md), or "" when the packaged study has none."""
    from ..dimension import border_dimension_estimates

    try:
        boxes = border_dimension_estimates()[name]["same_scales"]["boxes"]
    except (FileNotFoundError, KeyError):
        return ""
    lo, hi = boxes["ci95"]
    a, b = boxes["fit_range_px"]
    return (f"; box counting {boxes['resolution']}^2 px, boxes {a}..{b} px: "
            f"{boxes['dimension']:.3f} (95% CI {lo:.3f}..{hi:.3f})")
