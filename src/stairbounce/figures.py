"""The paper's Figures 1-9 as named recipes, and the report that sets each
beside what the paper states.

Every recipe uses only the public API (``trajectory``, ``scan``, ``fractal``,
``orbits`` and the ``plot`` renderers) and returns a :class:`Result`: the files
it wrote, rows of "paper says / we measured" for the report, its parameters
and how long it took.  :func:`make_figures` runs a selection, keeps going when
one fails, and caches the expensive datasets on disk keyed by their inputs;
:func:`write_report` writes ``report.md``, ``report.html`` and
``manifest.json``.
"""

from __future__ import annotations

import contextlib
import hashlib
import html
import json
import math
import os
import time
import traceback
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from . import __version__
from ._io import atomic_path

__all__ = ["FIGURES", "Settings", "Result", "make_figures", "write_report", "BLOWUPS"]

# Figure 5 of the paper: a) .. e)
BLOWUPS = {
    "fig5a": ((0.0, 0.3), (0.3, 0.7)),
    "fig5b": ((0.0, 0.2), (0.7, 1.0)),
    "fig5c": ((0.0, 0.1), (1.0, 1.22)),
    "fig5d": ((0.0, 0.1), (0.9, 1.0)),
    "fig5e": ((0.04, 0.065), (0.92, 0.945)),
}


@dataclass
class Settings:
    """What every recipe needs: where to write, how, and how big."""

    out: Path
    fmt: str = "png"
    dpi: int = 150
    scale: float = 1.0
    max_iter: int = 1000
    cache_dir: Path | None = None  # None: no cache
    # replace existing files that are not from an earlier run into this folder
    overwrite: bool = False

    def px(self, n):
        """A pixel count of the default set, scaled (at least 16)."""
        return max(16, int(round(n * self.scale)))


@dataclass
class Row:
    """One line of the report: a quantity, the paper's statement, ours."""

    quantity: str
    paper: str
    measured: str
    agrees: bool | None = None  # None: nothing to compare


@dataclass
class Result:
    name: str
    title: str
    files: list[str] = field(default_factory=list)
    rows: list[Row] = field(default_factory=list)
    params: dict = field(default_factory=dict)
    seconds: float = 0.0
    error: str | None = None


# --------------------------------------------------------------------------- #
# helpers                                                                     #
# --------------------------------------------------------------------------- #


def _cached(settings, kind, inputs, compute):
    """``compute()`` -> xarray.Dataset, cached as netCDF under a hash of the inputs."""
    import xarray as xr

    if settings.cache_dir is None:
        return compute()
    key = json.dumps({"kind": kind, "version": __version__, **inputs}, sort_keys=True)
    path = Path(settings.cache_dir) / f"{kind}-{hashlib.sha256(key.encode()).hexdigest()[:20]}.nc"
    if path.exists():
        try:
            with xr.open_dataset(path) as ds:
                return ds.load()
        except (OSError, ValueError, RuntimeError):
            with contextlib.suppress(OSError):
                path.unlink()  # a damaged cache entry is recomputed
    ds = compute()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(path, overwrite=True) as tmp:  # our own cache
            ds.to_netcdf(tmp)
    except (OSError, ValueError) as exc:
        # an unwritable or full cache costs time, never a figure
        _cache_warning(settings.cache_dir, exc)
    return ds


_CACHE_WARNED = set()


def _cache_warning(cache_dir, exc):
    import warnings

    key = str(cache_dir)
    if key not in _CACHE_WARNED:
        _CACHE_WARNED.add(key)
        reason = " ".join(str(exc).split())
        warnings.warn(f"cannot write the cache {cache_dir} ({reason}): computing without it",
                      RuntimeWarning, stacklevel=3)


def _scan(settings, e, u, n_e, n_u):
    from .plane import scan

    inputs = {"e": list(e), "u": list(u), "n_e": n_e, "n_u": n_u, "max_iter": settings.max_iter}
    return _cached(
        settings, "scan", inputs,
        lambda: scan(e=(e[0], e[1], n_e), u=(u[0], u[1], n_u), max_iter=settings.max_iter),
    )


def _replaceable(settings):
    """Whether files in the output folder may be replaced: asked for, or the
    folder holds the manifest of an earlier run (its files are ours)."""
    if settings.overwrite:
        return True
    try:
        manifest = json.loads((Path(settings.out) / "manifest.json").read_text())
    except (OSError, ValueError):
        return False
    return isinstance(manifest, dict) and "stairbounce_version" in manifest


def _mark_folder(settings):
    """Write a provisional manifest (replaced by :func:`write_report`), so that
    a run cut short (Ctrl-C, a kill) leaves a folder recognisably ours: the
    rerun replaces its figures without --force."""
    path = Path(settings.out) / "manifest.json"
    if path.exists() and not _replaceable(settings):
        return  # not ours: the figures' own writes refuse to replace anything
    with atomic_path(path, overwrite=True) as tmp:
        tmp.write_text(json.dumps({"stairbounce_version": __version__, "complete": False, "figures": []}))


def output_files(settings, names):
    """The files :func:`make_figures` and :func:`write_report` write for ``names``."""
    out = Path(settings.out)
    return [out / f"{n}.{settings.fmt}" for n in names] + [
        out / "report.md", out / "report.html", out / "manifest.json"]


def check_outputs(settings, names):
    """Refuse, before any figure is made, a folder where an existing file
    would be replaced without ``overwrite`` (and not from an earlier run), or
    where a target is a folder stairbounce did not write."""
    from ._io import check_output

    out = Path(settings.out)
    if not out.exists():
        if not out.parent.is_dir() and str(out.parent):
            raise ValueError(f"cannot write {out}: folder {out.parent} does not exist")
        return
    replace = _replaceable(settings)
    for path in output_files(settings, names):
        check_output(path, overwrite=replace)


def _save(fig, settings, name):
    import matplotlib.pyplot as plt

    path = Path(settings.out) / f"{name}.{settings.fmt}"
    with atomic_path(path, overwrite=_replaceable(settings)) as tmp:
        fig.savefig(tmp, dpi=settings.dpi, format=settings.fmt)
    plt.close(fig)
    return path.name


def _subplots(*args, **kwargs):
    import matplotlib.pyplot as plt

    return plt.subplots(*args, **kwargs)


# --------------------------------------------------------------------------- #
# recipes                                                                     #
# --------------------------------------------------------------------------- #


def fig1(s: Settings) -> Result:
    """Fig. 1: the staircase and a trajectory with impacts, accumulation, slide."""
    from .plot import plot_trajectory
    from .symbolic import sliding_word
    from .trajectory import trajectory

    # one period of a periodic sliding solution whose slide is long enough to see
    e, u = 0.1, 0.65
    word = sliding_word(e, u)
    steps = word.period
    traj = trajectory(e, u, 1.0, 0.0, steps)
    fig, ax = _subplots(figsize=(9, 6))
    plot_trajectory(traj, ax=ax)
    ax.set_title(f"Fig. 1: e = {e}, u = {u}, the periodic sliding solution {word}")
    acc = traj.accumulations[0] if traj.accumulations else None
    rows = [
        Row("model", "a ball bouncing down a staircase under gravity (1.3)-(1.4)",
            f"{len(traj.impacts)} impacts drawn, {len(traj.accumulations)} accumulation, "
            f"{len(traj.slides)} slide over {steps} steps"),
        Row("word of the solution drawn", "-", f"{word} (period {word.period}, "
            f"{word.impacts} finite impacts)"),
    ]
    if acc is not None:
        rows.append(Row("accumulation time (sum of the series of eq. 2.2)", "finite",
                        f"t = {acc.time:.12g} on step {acc.step}"))
    return Result("fig1", "The staircase model", [_save(fig, s, "fig1")], rows,
                  {"e": e, "u": u, "y0": 1.0, "v0": 0.0, "steps": steps})


def fig2(s: Settings) -> Result:
    """Fig. 2: the Poincare map, as the section of a long orbit."""
    from .model import iterate
    from .plot import plot_poincare_section

    e, u, y0, v0, steps = 0.1, 0.9, 1.0, 0.0, 3000
    ys, vs, ks = iterate(y0, v0, e, u, steps)
    fig, ax = _subplots(figsize=(7, 5))
    plot_poincare_section(ys, vs, ks, ax=ax)
    ax.set_title(f"Fig. 2: Poincare section, e = {e}, u = {u}, {steps} steps from ({y0}, {v0})")
    rows = [
        Row("domain of P", "[1, +inf) x R", f"min y over {steps} iterates = {ys[1:].min():.6f}",
            bool(ys[1:].min() >= 1.0)),
        Row("sliding from (1, 0)", "-",
            "never (quasi-periodic orbit)" if not (ks == -1).any() else "slides"),
    ]
    return Result("fig2", "The Poincare map", [_save(fig, s, "fig2")], rows,
                  {"e": e, "u": u, "y0": y0, "v0": v0, "steps": steps})


def fig3(s: Settings) -> Result:
    """Fig. 3: the (n, 0^inf) tongues of Theorem 3.1 and the Corollary 2.1 curve."""
    from .model import no_sliding_bound, tongue
    from .plot import plot_tongues

    n_max = 12
    fig, ax = _subplots(figsize=(7, 5.5))
    plot_tongues(n_max=n_max, e=(0.0, 1.0), u=(0.0, 1.5), ax=ax)
    ax.set_title("Fig. 3: the (n, 0^\u221e) sliding tongues (Theorem 3.1)")
    # the tongues end on the Corollary 2.1 curve: at the tip u_low = u_high
    gaps = []
    for n in range(2, n_max + 1):
        c = math.sqrt((n - 1) / n)
        e_tip = (1 - c) / (1 + c)
        gaps.append(abs(tongue(n, e_tip)[1] - no_sliding_bound(e_tip)))
    worst = max(gaps)
    rows = [
        Row("tongue tips on the Corollary 2.1 curve", "the tongues finish on u = (1-e)/(2 sqrt(2e))",
            f"largest gap between tip and curve, n = 2..{n_max}: {worst:.1e}", worst < 1e-12),
    ]
    return Result("fig3", "The (n, 0^inf)-sliding tongues", [_save(fig, s, "fig3")], rows,
                  {"n_max": n_max})


def fig4(s: Settings) -> Result:
    """Fig. 4: the fractal pattern coloured by word length, tongues overlaid."""
    from .plot import plot_scan
    from .plane import no_sliding_curve, tongue_mask

    e, u = (0.0, 1.0), (0.0, 1.5)
    n_e, n_u = s.px(500), s.px(350)
    ds = _scan(s, e, u, n_e, n_u)
    fig, ax = _subplots(figsize=(8, 6))
    plot_scan(ds, field="word_length", ax=ax, overlay=("tongues", "bound"))
    ax.set_title(f"Fig. 4: word length of the periodic sliding solution ({n_e} x {n_u})")
    E, U = np.meshgrid(ds.e.values, ds.u.values)
    wl1 = ds.word_length.values == 1
    inside = tongue_mask(E, U, 200)
    frac_in = wl1[inside].mean() if inside.any() else float("nan")
    frac_wl1 = inside[wl1].mean() if wl1.any() else float("nan")
    sliding = ds.status.values == 0
    above = sliding & (U >= no_sliding_curve(E))
    rows = [
        Row("word length 1 = the tongues of Fig. 3", "the black region coincides with Figure 3",
            f"{100 * frac_wl1:.2f}% of word-length-1 pixels lie inside the analytic tongues; "
            f"{100 * frac_in:.2f}% of tongue pixels have word length 1",
            bool(frac_wl1 > 0.99 and frac_in > 0.99)),
        Row("no sliding above Corollary 2.1", "u >= (1-e)/(2 sqrt(2e)): no sliding solutions",
            f"{int(above.sum())} sliding pixels above the curve", bool(above.sum() == 0)),
        Row("periodic sliding solutions", "-",
            f"{100 * sliding.mean():.1f}% of pixels; word lengths 1..{int(ds.word_length.max())}"),
    ]
    return Result("fig4", "The fractal pattern in the (e, u) plane", [_save(fig, s, "fig4")], rows,
                  {"e": e, "u": u, "size": [n_e, n_u], "max_iter": s.max_iter})


def _blowup(name):
    letter = name[-1]

    def recipe(s: Settings) -> Result:
        from .plot import plot_scan

        e, u = BLOWUPS[name]
        n = s.px(400)
        ds = _scan(s, e, u, n, n)
        fig, ax = _subplots(figsize=(6.5, 5.5))
        plot_scan(ds, field="word_length", ax=ax, overlay=("tongues",))
        ax.set_title(f"Fig. 5{letter}): [{e[0]}, {e[1]}] x [{u[0]}, {u[1]}]")
        sliding = ds.status.values == 0
        lengths = np.unique(ds.word_length.values[sliding])
        rows = [
            Row("self-similar structure", "the same complex structure repeated at smaller scales",
                f"{100 * sliding.mean():.1f}% sliding; {lengths.size} distinct word lengths "
                f"(up to {int(lengths.max()) if lengths.size else 0})"),
        ]
        return Result(name, f"Blow-up {letter})", [_save(fig, s, name)], rows,
                      {"e": e, "u": u, "size": [n, n], "max_iter": s.max_iter})

    recipe.__name__ = name
    recipe.__doc__ = f"Fig. 5{letter}): blow-up of {BLOWUPS[name]}."
    return recipe


# Figures 6 and 7: window, the paper's dimension
DIMENSION_WINDOWS = {
    "fig6": (((0.0, 0.333), (0.4, 0.733)), 1.324),
    "fig7": (((0.155, 0.2138), (0.6, 0.658)), 1.403),
}


def _dimension(name):
    def recipe(s: Settings) -> Result:
        from .fractal import box_dimension, boundary
        from .plot import plot_border, plot_box_counts

        (e, u), paper = DIMENSION_WINDOWS[name]
        res = s.px(500)
        # perimeter_dimension's steps, on the cached scan: the border of the
        # sliding region (status 0), the window's frame not counted
        region = _scan(s, e, u, res, res).status.transpose("u", "e").values == 0
        border = boundary(region)
        # the paper fits every box size of its 500 px picture up to an eighth of it;
        # the automatic linear-region choice is reported beside it (a heuristic)
        fit_range = (1, max(4, 2 ** round(math.log2(res / 8))))
        est = box_dimension(border, fit_range=fit_range)
        auto = box_dimension(border)
        fig, axes = _subplots(1, 2, figsize=(12, 5.2))
        plot_border(border, e, u, ax=axes[0],
                    title=f"border of the sliding region, {res} x {res} px")
        plot_box_counts(est, ax=axes[1])
        fig.suptitle(f"Fig. {name[-1]}: border of the sliding region in "
                     f"[{e[0]}, {e[1]}] x [{u[0]}, {u[1]}] and its box counting")
        fig.tight_layout()
        lo, hi = est.ci
        rows = [
            Row(f"box-counting dimension, boxes {fit_range[0]}..{fit_range[1]} px",
                f"D = {paper}, r > 0.99",
                f"D = {est.dimension:.3f} (95% CI {lo:.3f}..{hi:.3f}), r = {est.r:.4f}",
                bool(abs(est.dimension - paper) < 0.08 and est.r > 0.99)),
            Row("box-counting dimension, automatic linear range (heuristic)", f"D = {paper}",
                f"D = {auto.dimension:.3f} (95% CI {auto.ci[0]:.3f}..{auto.ci[1]:.3f}), "
                f"r = {auto.r:.4f}, boxes {auto.fit_range[0]}..{auto.fit_range[1]} px"),
        ]
        return Result(name, f"Box-counting dimension of the border (Fig. {name[-1]})",
                      [_save(fig, s, name)], rows,
                      {"e": e, "u": u, "resolution": res, "max_iter": s.max_iter,
                       "fit_range": fit_range, "D": est.dimension, "r": est.r,
                       "ci": list(est.ci), "D_auto": auto.dimension})

    recipe.__name__ = name
    recipe.__doc__ = f"Fig. {name[-1]}: border and box counting of {DIMENSION_WINDOWS[name][0]}."
    return recipe


# Figure 9 and its zooms: each window sits inside the previous one, at the
# right end of the gap between the n = 1 and n = 2 tongues for e = 0.1
FIG9_WINDOWS = [(0.3, 1.0), (0.57, 0.72), (0.578, 0.592), (0.5785, 0.5797)]


def _orbits(settings, e, u_window, n):
    from .orbits import orbit_diagram

    inputs = {"e": e, "u": list(u_window), "n": n, "y0": 0.1, "v0": 0.0, "transient": 2000,
              "keep": 200}
    return _cached(
        settings, "orbits", inputs,
        lambda: orbit_diagram(e, np.linspace(u_window[0], u_window[1], n), y0=0.1, v0=0.0,
                              transient=2000, keep=200),
    )


def _distinct(row):
    return np.unique(np.round(row, 9)).size


def fig8(s: Settings) -> Result:
    """Fig. 8: orbit diagram for e = 0.001: grazing bifurcations, one per tongue."""
    from .model import tongue
    from .plot import plot_orbit_diagram

    e, window, n = 0.001, (0.3, 2.0), s.px(3000)
    ds = _orbits(s, e, window, n)
    fig, ax = _subplots(figsize=(9, 5.5))
    plot_orbit_diagram(ds, ax=ax, overlay=("tongues",))
    ax.set_title(f"Fig. 8: orbit diagram, e = {e} (iterates 2001-2200 from (0.1, 0))")
    counts, ok = [], True
    for k in range(1, 7):
        lo, hi = tongue(k, e)
        i = int(np.argmin(np.abs(ds.u.values - 0.5 * (lo + hi))))
        c = _distinct(ds.y.values[i])
        counts.append(f"n={k}: {c}")
        ok &= c == k
    rows = [
        Row("branches inside the n-th tongue", "new branches arise when u enters a new "
            "(n, 0^inf) tongue (grazing bifurcations)",
            "distinct values at the tongue centres: " + ", ".join(counts), bool(ok)),
    ]
    return Result("fig8", "Orbit diagram, e = 0.001", [_save(fig, s, "fig8")], rows,
                  {"e": e, "u": window, "n": n, "y0": 0.1, "v0": 0.0, "transient": 2000,
                   "keep": 200})


def fig9(s: Settings) -> Result:
    """Fig. 9: orbit diagram for e = 0.1 and three nested zooms (self-similarity)."""
    from .plot import plot_orbit_diagram

    e, n = 0.1, s.px(3000)
    fig, axes = _subplots(2, 2, figsize=(12, 8))
    heights = []
    for k, (window, ax) in enumerate(zip(FIG9_WINDOWS, axes.flat)):
        ds = _orbits(s, e, window, n)
        plot_orbit_diagram(ds, ax=ax, overlay=("tongues",) if k == 0 else ())
        ax.set_title("e = 0.1" if k == 0 else f"zoom {k}: u in [{window[0]}, {window[1]}]")
        if k:  # typical height of the branches above y = 1, in the gap below sqrt(1/2)
            gap = ds.u.values < math.sqrt(0.5)
            heights.append(float(np.median(ds.y.values[gap].max(axis=1) - 1.0)))
        if k < len(FIG9_WINDOWS) - 1:
            nxt = FIG9_WINDOWS[k + 1]
            ax.axvspan(nxt[0], nxt[1], color="C0", alpha=0.12, lw=0)
    fig.suptitle("Fig. 9: orbit diagrams for e = 0.1 (iterates 2001-2200); shaded: the next zoom")
    fig.tight_layout()
    ratios = [heights[i + 1] / heights[i] for i in range(len(heights) - 1) if heights[i] > 0]
    rows = [
        Row("self-similar scheme", "an autosimilar bifurcation diagram at smaller and smaller "
            "scales", "median height of the branches above y = 1 in zooms 1-3: "
            + ", ".join(f"{h:.2e}" for h in heights)
            + "; successive ratios " + ", ".join(f"{r:.4f}" for r in ratios)
            + f" (e^2 = {e * e:.4f}; the paper gives no ratio)"),
    ]
    return Result("fig9", "Orbit diagrams, e = 0.1, with zooms", [_save(fig, s, "fig9")], rows,
                  {"e": e, "windows": FIG9_WINDOWS, "n": n, "y0": 0.1, "v0": 0.0,
                   "transient": 2000, "keep": 200})


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


# --------------------------------------------------------------------------- #
# running and reporting                                                       #
# --------------------------------------------------------------------------- #


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


def _md_table(rows):
    lines = ["| quantity | paper | here | agrees |", "|---|---|---|---|"]
    for r in rows:
        ok = "" if r.agrees is None else ("yes" if r.agrees else "**no**")
        lines.append(f"| {r.quantity} | {r.paper} | {r.measured} | {ok} |")
    return lines


def write_report(results, settings: Settings, total_seconds=None):
    """write_report(results, settings) -> list of paths

    ``report.md`` and ``report.html`` (figures linked by relative path, so the
    folder reads offline) and ``manifest.json`` (every input, the package
    version, timings), all written atomically.
    """
    out = Path(settings.out)
    replace = _replaceable(settings)
    summary = [Row(f"{r.name}: {x.quantity}", x.paper, x.measured, x.agrees)
               for r in results for x in r.rows]
    md = [
        "# stairbounce: the paper reproduced",
        "",
        f"Campos, Romero-Valles, Torres, *A fractal structure in a bouncing ball model*. "
        f"stairbounce {__version__}; format {settings.fmt}, dpi {settings.dpi}, "
        f"scale {settings.scale}, max_iter {settings.max_iter}.",
        "",
        "## Summary",
        "",
        *_md_table(summary),
        "",
    ]
    for r in results:
        md += [f"## {r.name}: {r.title}", ""]
        if r.error:
            md += [f"**failed**: {r.error}", ""]
        for f in r.files:
            md += [f"![{r.name}]({f})" if not f.endswith(".pdf") else f"[{f}]({f})", ""]
        md += _md_table(r.rows) + [""]
        params = {k: v for k, v in r.params.items() if k != "traceback"}
        md += [f"Parameters: `{json.dumps(params, default=_jsonable)}`; time {r.seconds:.2f} s.", ""]
    if total_seconds is not None:
        md += [f"Total time: {total_seconds:.1f} s.", ""]
    paths = []
    with atomic_path(out / "report.md", overwrite=replace) as tmp:
        tmp.write_text("\n".join(md))
    paths.append(out / "report.md")
    with atomic_path(out / "report.html", overwrite=replace) as tmp:
        tmp.write_text(_html(results, settings, summary, total_seconds))
    paths.append(out / "report.html")
    manifest = {
        "stairbounce_version": __version__,
        "settings": {k: str(v) if isinstance(v, Path) else v for k, v in asdict(settings).items()},
        "total_seconds": total_seconds,
        "figures": [
            {**{k: v for k, v in asdict(r).items() if k != "rows"},
             "rows": [asdict(x) for x in r.rows]}
            for r in results
        ],
    }
    with atomic_path(out / "manifest.json", overwrite=replace) as tmp:
        tmp.write_text(json.dumps(manifest, indent=2, default=_jsonable))
    paths.append(out / "manifest.json")
    return paths


def _jsonable(x):
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, (tuple, set)):
        return list(x)
    return str(x)


def _html(results, settings, summary, total_seconds):
    esc = html.escape

    def table(rows):
        cells = "".join(
            f"<tr><td>{esc(r.quantity)}</td><td>{esc(r.paper)}</td><td>{esc(r.measured)}</td>"
            f"<td>{'' if r.agrees is None else ('yes' if r.agrees else '<b>no</b>')}</td></tr>"
            for r in rows
        )
        return ("<table><tr><th>quantity</th><th>paper</th><th>here</th><th>agrees</th></tr>"
                f"{cells}</table>")

    parts = [
        "<!doctype html><html><head><meta charset='utf-8'><title>stairbounce report</title>",
        "<style>body{font-family:sans-serif;max-width:1100px;margin:auto;padding:1em}"
        "table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #ccc;padding:3px 6px;"
        "vertical-align:top}img{max-width:100%}</style></head><body>",
        "<h1>stairbounce: the paper reproduced</h1>",
        f"<p>stairbounce {esc(__version__)}; scale {settings.scale}, max_iter {settings.max_iter}.</p>",
        "<h2>Summary</h2>", table(summary),
    ]
    for r in results:
        parts.append(f"<h2>{esc(r.name)}: {esc(r.title)}</h2>")
        if r.error:
            parts.append(f"<p><b>failed</b>: {esc(r.error)}</p>")
        for f in r.files:
            if f.endswith(".pdf"):
                parts.append(f"<p><a href='{esc(f)}'>{esc(f)}</a></p>")
            else:
                parts.append(f"<img src='{esc(f)}' alt='{esc(r.name)}'>")
        parts.append(table(r.rows))
        params = {k: v for k, v in r.params.items() if k != "traceback"}
        parts.append(f"<p>Parameters: <code>{esc(json.dumps(params, default=_jsonable))}</code>; "
                     f"time {r.seconds:.2f} s.</p>")
    if total_seconds is not None:
        parts.append(f"<p>Total time: {total_seconds:.1f} s.</p>")
    parts.append("</body></html>")
    return "\n".join(parts)


def default_cache_dir() -> Path:
    """``$XDG_CACHE_HOME/stairbounce`` (``~/.cache/stairbounce``)."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "stairbounce"
