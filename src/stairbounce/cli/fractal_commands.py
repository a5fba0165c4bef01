"""``stairbounce dimension``: fractal dimension of a border (Figs. 6 and 7), by slicing, the
uncertainty exponent or box counting of a scan, a picture or a tiled store."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import typer

from ._app import (FORCE_HELP, CLIError, app, check_dpi, check_outputs, parse_range, perimeter_lines, progress_bar,
                   save_figure)

# Scans with more pixel-steps than this show a progress bar.
_PROGRESS_WORK = 2e8


def _parse_fit_range(text):
    if text is None:
        return None
    lo, hi = parse_range("fit-range", text)
    if lo < 1:
        raise CLIError(f"--fit-range must be box sides in pixels MIN:MAX with MIN >= 1, got {text!r}")
    return lo, hi


def _read_region(path: Path, region: str) -> np.ndarray:
    """The region of a black-and-white picture: pixels darker than mid grey
    (``region="black"``) or not (``"white"``), rows from the top."""
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(path) as im:
            grey = np.asarray(im.convert("L"), dtype=np.uint8)
    except FileNotFoundError:
        raise CLIError(f"--image: no such file: {path}") from None
    except (UnidentifiedImageError, OSError, ValueError, Image.DecompressionBombError) as exc:
        raise CLIError(f"--image: cannot read {path} as an image ({exc})") from None
    dark = grey < 128
    return dark if region == "black" else ~dark


def _scan_with_progress(kwargs):
    from ..dimension import perimeter_dimension

    n = kwargs["resolution"]
    if n * n * kwargs["max_iter"] < _PROGRESS_WORK:
        return perimeter_dimension(**kwargs)
    from rich.console import Console

    with progress_bar(Console(stderr=True), "scanning", n, unit="rows") as (bar, task):
        return perimeter_dimension(**kwargs, progress=lambda done, total: bar.update(task, completed=done))


def _parse_eps(text):
    parts = text.split(":")
    try:
        lo, hi, n = float(parts[0]), float(parts[1]), int(parts[2])
        if len(parts) != 3:
            raise ValueError
    except (ValueError, IndexError):
        raise CLIError(f"--eps must be MIN:MAX:N (N values log-spaced), got {text!r}") from None
    if not (0 < lo < hi < 1) or n < 3:
        raise CLIError(f"--eps must have 0 < MIN < MAX < 1 (fractions of the window) and N >= 3, got {text!r}")
    return np.logspace(np.log10(lo), np.log10(hi), n)


def _bar(label):
    """``(bar, task)``: the commands' progress bar on stderr (lines off a terminal)."""
    from rich.console import Console

    return progress_bar(Console(stderr=True), label, None)


def _uncertainty_with_progress(kwargs, work):
    from ..dimension import perimeter_dimension

    if work < _PROGRESS_WORK:
        return perimeter_dimension(**kwargs)
    with _bar("classifying") as (bar, task):
        return perimeter_dimension(
            **kwargs, progress=lambda done, total: bar.update(task, completed=done, total=total))


def _print_estimate(result):
    """The scale-resolved view first (local dimension against scale, with
    its 95% band where the estimator has one), then D with the interval that
    covers the drift, the scales and max_iter, and the one-line warning."""
    mid, dl, half = result.local_band()
    typer.echo(f"local dimension against scale ({result.scale_unit}), drawn on 1 .. 2 "
               "(*: the local dimension, -: its 95% band, |: D):")
    lo, hi = result.scales
    for m, d, h in zip(mid, dl, half):
        band = f"  +- {h:.4f}" if np.isfinite(h) else "          "
        inside = "fitted" if lo <= m <= hi else "      "
        typer.echo(f"  {m:10.3g}  {d:8.4f}{band}  {inside}  {_strip(d, h, result.dimension)}")
    typer.echo(f"D = {result.dimension:.4f}")
    ilo, ihi = result.interval
    typer.echo(f"interval = [{ilo:.4f}, {ihi:.4f}]  (95% statistical +-{result.statistical:.4f}, "
               f"systematic +-{result.systematic:.4f}: {result.halves[0]:.4f} over the finer, "
               f"{result.halves[1]:.4f} over the coarser half of the scales)")
    clo, chi = result.ci
    typer.echo(f"95% CI = [{clo:.4f}, {chi:.4f}]  (statistical only, stderr {result.stderr:.4f})")
    mi = "" if result.max_iter is None else f", max_iter {result.max_iter}"
    typer.echo(f"scales: {result.scales_text()}{mi}")
    warn = result.warning()
    if warn:
        typer.echo(warn)


def _print_accounting(result, ew, uw, at_defaults, checked, which):
    """The interval widened for the estimator's known bias, what it leaves
    out, and in a window of the dimension study its shipped number, labelled,
    with the command that recomputes it (issue 37)."""
    blo, bhi = result.known_bias
    lo, hi = result.bias_interval
    where = ("measured at these settings" if at_defaults else
             "measured at the default settings, not at these: a different bias may apply")
    typer.echo(f"with the estimator's bias: [{lo:.4f}, {hi:.4f}]  (the interval above corrected for a "
               f"bias of {blo:+.3f}..{bhi:+.3f} on sets of known dimension, {where}; "
               "benchmarks/dimension_bias.py, docs/guide/dimension.md)")
    if not checked:
        typer.echo("left out: the effect of max_iter (--check-max-iter measures it at 4 x max_iter)")
    study = _study_entry(ew, uw) if which == "sliding" else None
    if study is not None:
        name, entry, command = study
        slo, shi = entry["ci95"][0] - entry.get("systematic", 0.0), entry["ci95"][1] + entry.get("systematic", 0.0)
        typer.echo(f"the dimension study's number for this window ({name}, shipped with the package, not "
                   f"recomputed here; {entry['method']}): D = {entry['dimension']:.4f} interval "
                   f"[{slo:.4f}, {shi:.4f}] (noise and drift only{_study_bias(entry)}); recomputed by: {command}")


def _study_bias(entry):
    """``"; the uncertainty exponent's measured bias ... is not in it"`` for the study's estimator."""
    from ..dimension.result import KNOWN_BIAS

    key = next((k for k in KNOWN_BIAS if str(entry.get("method", "")).startswith(k)), None)
    if key is None:
        return ""
    blo, bhi = KNOWN_BIAS[key]
    return f"; the {key} estimator's measured bias {blo:+.3f}..{bhi:+.3f} is not in it"


def _study_entry(ew, uw):
    """``(name, entry, command)`` of the shipped dimension study when the
    window is one of its windows, else None."""
    from ..dimension import border_dimension_estimates
    from ..figures import DIMENSION_WINDOWS

    for name, ((e, u), _) in DIMENSION_WINDOWS.items():
        if np.allclose([*ew, *uw], [*e, *u], rtol=0, atol=1e-12):
            try:
                study = border_dimension_estimates()
            except (OSError, ValueError):
                return None
            if name in study:
                return name, study[name], study.get("generated_by", "benchmarks/dimension_study.py")
    return None


def _strip(d, half, dim, width=41):
    """One row of the local-dimension curve as text: the range 1..2 in
    ``width`` characters, ``*`` at ``d``, ``-`` over ``d -+ half``, ``|`` at ``dim``."""
    def at(x):
        return int(round((min(max(x, 1.0), 2.0) - 1.0) * (width - 1)))

    row = [" "] * width
    if np.isfinite(half):
        for k in range(at(d - half), at(d + half) + 1):
            row[k] = "-"
    row[at(dim)] = "|"
    if np.isfinite(d):
        row[at(d)] = "*"
    return "[" + "".join(row) + "]"


def _print_result(result, ew, uw, at_defaults, checked, which):
    """The estimator's table, its estimate (:func:`_print_estimate`) and the
    accounting of the interval (:func:`_print_accounting`)."""
    typer.echo(result.table())
    _print_estimate(result)
    _print_accounting(result, ew, uw, at_defaults, checked, which)


def _measure_again(result, run, max_iter):
    """``run(4 * max_iter)``, compared scale by scale with ``result``; returns
    the ``compare`` argument of :func:`stairbounce.plot.plot_local_dimension`."""
    again = run(4 * max_iter)
    _check_max_iter(result, again, max_iter)
    return ((again, f"max_iter {4 * max_iter}"),)


def _check_max_iter(result, again, max_iter):
    """Scale by scale: does 4 x max_iter move the local dimension?  The same
    random points at both (same seed): the band is the two bands combined
    (:func:`stairbounce.dimension.convergence.max_iter_check`)."""
    from ..dimension.convergence import NO_NOISE_MODEL_BAND, max_iter_check

    check = max_iter_check(result, again)
    typer.echo(f"max_iter check: local dimension at max_iter {max_iter} and {4 * max_iter} "
               "(difference, and the band it is held to: the two 95% bands combined and widened "
               f"for the scales compared, or {NO_NOISE_MODEL_BAND:g} where the estimator has no "
               "noise model)")
    for (mid, d1, d2, diff, tol, flag), cut in zip(check.rows(), check.truncated):
        mark = "  moved" if cut else ("  moved (a chance flag: every finer scale agrees)" if flag else "")
        typer.echo(f"  {mid:10.3g}  {d1:8.4f}  {d2:8.4f}  {diff:+.4f} +- {tol:.4f}{mark}")
    bad = check.not_converged
    if bad is not None:
        typer.echo(f"warning: max_iter {max_iter} is not converged at scales {bad[0]:.3g}..{bad[1]:.3g}: "
                   f"the local dimension moves with max_iter {4 * max_iter} there; fit scales above "
                   f"{bad[1]:.3g} (--fit-range) or raise --max-iter")
    else:
        typer.echo(f"max_iter {max_iter} converged at every scale measured (within the band)")


def _store_dimension(store, which, connectivity, fit_range, scheduler):
    """Box counting of a finished atlas store, tile by tile."""
    from ..atlas_boxes import store_box_dimension, store_info

    if not store.exists():
        raise CLIError(f"--store: no such store: {store}")
    try:
        attrs = store_info(store)  # before the progress bar: a refusal is one line
    except ValueError as exc:
        raise CLIError(f"--store: {exc}") from None
    n = min(int(attrs.get("n_e", 0)), int(attrs.get("n_u", 0)))
    if fit_range is None:
        # the study's range: away from the pixel scale (1-2 px see the raster
        # staircase), below the sizes dominated by the window's extent
        if n // 32 >= 64:
            fit_range = (16, n // 32)
        elif n // 16 >= 16:
            fit_range = (4, n // 16)
            typer.echo(f"{store}: {n} px: the documented range, 16 px to 1/32 of the picture "
                       f"(= {n // 32} px), holds fewer than the 3 box sizes a fit needs; fitting "
                       f"4..{n // 16} px instead (still clear of the 1-2 px pixel scale)")
        else:
            typer.echo(f"{store}: {n} px is too small for a fit clear of the pixel scale; using the "
                       "automatic range (it may include the pixel scale)")
    with _bar("counting tiles") as (bar, task):
        result = store_box_dimension(
            store, which=which, connectivity=connectivity, fit_range=fit_range, client=scheduler,
            progress=lambda done, total: bar.update(task, completed=done, total=total),
        )
    what = "sliding region" if which == "sliding" else "word-length regions"
    typer.echo(
        f"{store}: border of the {what} in [{attrs.get('e_min'):g}, {attrs.get('e_max'):g}] x "
        f"[{attrs.get('u_min'):g}, {attrs.get('u_max'):g}], {attrs.get('n_e')} x {attrs.get('n_u')} px, "
        f"max_iter {attrs.get('max_iter')}, counted tile by tile"
    )
    return result, fit_range


@app.command(short_help="Fractal dimension of the sliding border (Figs 6, 7).")
def dimension(
    e: str = typer.Option("0:0.333", "--e", help="Window along e, MIN:MAX (default: the paper's Fig. 6)."),
    u: str = typer.Option("0.4:0.733", "--u", help="Window along u, MIN:MAX (default: the paper's Fig. 6)."),
    method: str = typer.Option(
        None, "--method",
        help="'slicing', 'uncertainty' or 'boxes'. Default: slicing for a window of the model (crossings of the "
             "border along --lines random lines refined down to 1e-8 of the window, --scales: of the three, the "
             "smallest bias on sets of known dimension, docs/guide/dimension.md; before 0.4 the default was "
             "uncertainty), boxes for --image and --store (pictures can only be box-counted). 'uncertainty': the "
             "uncertainty exponent of random points (reads high where thin tongues abound). 'boxes' on a window "
             "scans a --resolution picture: the paper's method (--resolution 500 --fit-range 1:64 --max-iter 1000 "
             "gives its numbers). Each prints its interval widened for the estimator's measured bias."),
    resolution: int = typer.Option(None, "--resolution", help="Boxes: pixels along each axis of the scan (>= 8; default 2048, fitted over boxes of 4..64 px unless --fit-range; before 0.4: 512 with the automatic range)."),
    max_iter: int = typer.Option(None, "--max-iter", help="Steps before a point counts as non-sliding (>= 1; default 4000 for uncertainty and slicing, 1000 for boxes; before 0.4: 1000)."),
    points: int = typer.Option(None, "--points", help="Uncertainty: random points (>= 100; default 300000; before 0.4: 100000)."),
    eps: str = typer.Option(None, "--eps", help="Uncertainty: perturbations MIN:MAX:N, log-spaced fractions of the window (default 1e-8:1e-4:9; before 0.4: 1e-6:0.1:11)."),
    seed: int = typer.Option(0, "--seed", help="Uncertainty, slicing: seed of the random points or lines (same seed, same answer)."),
    lines: int = typer.Option(None, "--lines", help="Slicing: random lines (>= 1; default 128; before 0.4: 64)."),
    scales: str = typer.Option(None, "--scales", help="Slicing: smallest and largest box length along the lines, MIN:MAX fractions of the window (default 1e-8:1e-2, fitted over 1e-8..1e-4 unless --fit-range; before 0.4: 1e-10:1e-2, every level fitted)."),
    check_max_iter: bool = typer.Option(False, "--check-max-iter", help="A window of the model, any method: measure again at 4 x --max-iter and show, scale by scale, whether the local dimension moves (and where not to fit)."),
    image: Path = typer.Option(None, "--image", help="Measure the border of the region of this black-and-white picture instead of scanning."),
    store: Path = typer.Option(None, "--store", help="Measure the border in a finished tiled store (stairbounce scan --tile ... --out X.zarr), tile by tile: no memory limit."),
    scheduler: str = typer.Option(None, "--scheduler", help="With --store: count the tiles on this Dask scheduler (tcp://host:port)."),
    region: str = typer.Option("black", "--region", help="With --image: which colour is the region, black (darker than mid grey) or white."),
    pixels: bool = typer.Option(False, "--pixels", help="With --image: measure the region's pixels as they are (a line drawing), not its border."),
    which: str = typer.Option("sliding", "--which", help="'sliding' (border of the sliding region) or 'words' (borders between word lengths)."),
    fit_range: str = typer.Option(None, "--fit-range", help="Boxes: box sides to fit, MIN:MAX pixels (default: largest linear region, a heuristic; with --store 16 px to 1/32 of the picture). The paper's numbers: 1:64 at 500 px. Uncertainty: eps to fit, MIN:MAX (default: all with >= 25 uncertain points)."),
    offsets: int = typer.Option(1, "--offsets", help="Boxes: grid shifts per axis, counts averaged over them (>= 1)."),
    connectivity: int = typer.Option(4, "--connectivity", help="Boxes: neighbours that define the border: 4 or 8."),
    proven_depth: int = typer.Option(None, "--proven-depth", help="A window of the model with --which sliding: also print proven box counts of the sliding region's border (the paper's perimeter), lower/upper per scale window/2^k and the slope bracket, from a certified atlas of this depth at --max-iter (class-level proofs and the fine trapping pass, every box re-verified by sb.verify), beside the numerical D. 0: off. Default 8: about 9 s more on the Fig. 7 window on 2 cores (18 s in all); 9: about 14-25 s more; each level about 3x more."),
    png: Path = typer.Option(None, "--png", help="Draw the result (border and log-log plot, or f(eps) and local dimensions) to this file (.png, .pdf, .svg)."),
    dpi: int = typer.Option(120, "--dpi", help="Resolution of raster output (10-1200)."),
    force: bool = typer.Option(False, "--force", help=FORCE_HELP),
):
    """Fractal dimension of the border of the sliding region (Figs. 6 and 7), of a picture or of a tiled store."""
    from ..dimension import boundary, box_dimension

    if png is not None and png.suffix.lower() not in {".png", ".pdf", ".svg"}:
        raise CLIError(f"--png must end in .png, .pdf or .svg, got {str(png)!r}")
    if region not in ("black", "white"):
        raise CLIError(f"--region must be black or white, got {region!r}")
    if which not in ("sliding", "words"):
        raise CLIError(f"--which must be sliding or words, got {which!r}")
    if connectivity not in (4, 8):
        raise CLIError(f"--connectivity must be 4 or 8, got {connectivity}")
    if offsets < 1:
        raise CLIError(f"--offsets must be an integer >= 1, got {offsets}")
    if image is not None and store is not None:
        raise CLIError("--image and --store: give one of them")
    if scheduler is not None and store is None:
        raise CLIError("--scheduler counts the tiles of a --store: give --store too")
    proven_depth = _check_proven_depth(proven_depth, image is not None or store is not None, which)
    if method is None:
        # the options of one method select it; none: slicing (issue 37; before, the uncertainty exponent)
        if image is not None or store is not None or resolution is not None:
            method = "boxes"
        elif points is not None or eps is not None:
            method = "uncertainty"
        else:
            method = "slicing"
    if method not in ("boxes", "uncertainty", "slicing"):
        raise CLIError(f"--method must be boxes, uncertainty or slicing, got {method!r}")
    # the defaults for a window of the model: the package's best answer in about a minute
    from ..dimension.perimeter import MODEL_DEFAULTS

    best = MODEL_DEFAULTS[method]
    at_defaults = fit_range is None and max_iter is None and {
        "uncertainty": points is None and eps is None,
        "slicing": lines is None and scales is None,
        "boxes": resolution is None and offsets == 1 and connectivity == 4}[method]
    default_fit = fit_range is None and (scales is None if method == "slicing" else resolution is None)
    max_iter = best["max_iter"] if max_iter is None else max_iter
    points = MODEL_DEFAULTS["uncertainty"]["n_points"] if points is None else points
    lines = MODEL_DEFAULTS["slicing"]["n_lines"] if lines is None else lines
    if method == "boxes" and image is None and store is None and default_fit:
        fit_range = "{}:{}".format(*best["fit_range"])
    if method == "slicing" and default_fit:
        fit_range = "{}:{}".format(*best["fit_range"])
    if resolution is None:
        resolution = MODEL_DEFAULTS["boxes"]["resolution"]
    if scales is None:
        scales = "{}:{}".format(*MODEL_DEFAULTS["slicing"]["scales"])
    if method in ("uncertainty", "slicing") and (image is not None or store is not None):
        raise CLIError(f"--method {method} classifies points of the model: give a window (--e, --u), "
                       "not --image or --store")
    if check_max_iter and (image is not None or store is not None):
        raise CLIError("--check-max-iter measures a window of the model again: not with --image or --store")
    check_dpi(dpi)
    check_outputs(force, png=png)

    if method in ("uncertainty", "slicing"):
        if max_iter < 1:
            raise CLIError(f"--max-iter must be an integer >= 1, got {max_iter}")
        if seed < 0:
            raise CLIError(f"--seed must be an integer >= 0, got {seed}")
    if method == "uncertainty":
        if points < 100:
            raise CLIError(f"--points must be an integer >= 100, got {points}")
        eps_values = np.asarray(MODEL_DEFAULTS["uncertainty"]["eps"]) if eps is None else _parse_eps(eps)
        fr = None
        if fit_range is not None:
            fr = parse_range("fit-range", fit_range)
            if not (0 < fr[0] and fr[1] < 1):
                raise CLIError(f"--fit-range with --method uncertainty is eps MIN:MAX in (0, 1), got {fit_range!r}")
        ew, uw = parse_range("e", e), parse_range("u", u)

        def run(mi):
            return _uncertainty_with_progress(
                dict(e=ew, u=uw, max_iter=mi, which=which, method="uncertainty", n_points=points,
                     eps=eps_values, seed=seed, fit_range=fr),
                points * (1 + 2 * eps_values.size) * mi,
            )

        result = run(max_iter)
        what = "sliding region" if which == "sliding" else "word-length regions"
        typer.echo(
            f"border of the {what} in [{ew[0]:g}, {ew[1]:g}] x [{uw[0]:g}, {uw[1]:g}], max_iter {max_iter}: "
            f"uncertainty exponent of {points} random points (seed {seed}, random directions)"
        )
        _print_result(result, ew, uw, at_defaults, check_max_iter, which)
        _print_proven_counts(ew, uw, proven_depth, max_iter, result.dimension)
        typer.echo(f"r = {result.r:.5f}; fit: eps {result.fit_range[0]:.3g}..{result.fit_range[1]:.3g} of the "
                   f"window, {result.fit.n} values, alpha = {result.alpha:.4f}, D = 2 - alpha (stderr "
                   f"binomial {result.stderr_binomial:.4f}, scatter about the line {result.stderr_fit:.4f})")
        # the same seed: the same points
        compare = _measure_again(result, run, max_iter) if check_max_iter else ()
        if png is not None:
            _draw(png, dpi, force, lambda: _plot_uncertainty(result, ew, uw, compare))
        return

    if method == "slicing":
        if lines < 1:
            raise CLIError(f"--lines must be an integer >= 1, got {lines}")
        smin, smax = parse_range("scales", scales)
        if not (1e-13 <= smin and smax <= 0.25):
            raise CLIError(f"--scales must lie in [1e-13, 0.25] (fractions of the window), got {scales!r}")
        fr = None
        if fit_range is not None:
            fr = parse_range("fit-range", fit_range)
            if not (0 < fr[0] and fr[1] <= 0.25):
                raise CLIError(f"--fit-range with --method slicing is box lengths MIN:MAX in (0, 0.25] "
                               f"(fractions of the window), got {fit_range!r}")
        ew, uw = parse_range("e", e), parse_range("u", u)

        from ..dimension import sliding_classifier, slicing_dimension

        what = "sliding region" if which == "sliding" else "word-length regions"

        def run(mi):
            try:
                return _with_bar("refining levels", lambda progress: slicing_dimension(
                    sliding_classifier(max_iter=mi, which=which), (ew, uw), n_lines=lines,
                    scale_min=smin, scale_max=smax, seed=seed, fit_range=fr, progress=progress,
                    label=f"border of the {what}, max_iter {mi}"))
            except ValueError as exc:
                raise CLIError(str(exc)) from None

        result = run(max_iter)
        typer.echo(
            f"border of the {what} in [{ew[0]:g}, {ew[1]:g}] x [{uw[0]:g}, {uw[1]:g}], max_iter {max_iter}: "
            f"slicing, {lines} random lines (seed {seed}), {result.evaluations} points classified"
        )
        _print_result(result, ew, uw, at_defaults, check_max_iter, which)
        _print_proven_counts(ew, uw, proven_depth, max_iter, result.dimension)
        # the same seed: the same lines
        compare = _measure_again(result, run, max_iter) if check_max_iter else ()
        if png is not None:
            def make():
                import matplotlib.pyplot as plt
                from ..plot import plot_local_dimension

                fig, ax = plt.subplots(figsize=(8, 5))
                plot_local_dimension(result, ax=ax, compare=compare, label=f"slicing, max_iter {max_iter}",
                                     title=f"slicing of the border in [{ew[0]:g}, {ew[1]:g}] x "
                                           f"[{uw[0]:g}, {uw[1]:g}]")
                fig.tight_layout()
                return fig

            _draw(png, dpi, force, make)
        return

    fr = _parse_fit_range(fit_range)
    if store is not None:
        if png is not None:
            raise CLIError("--png draws a picture in memory; a store is measured tile by tile "
                           "(use 'stairbounce render' to see it)")
        result, used = _store_dimension(store, which, connectivity, fr, scheduler)
        plot_image = None
    elif image is not None:
        mask = _read_region(image, region)
        if not mask.any():
            raise CLIError(f"--image: {image} has no {region} pixel (threshold at mid grey): the region is empty")
        if mask.all() and not pixels:
            raise CLIError(f"--image: {image} is all {region} (threshold at mid grey): the region has no border")
        measured = mask if pixels else boundary(mask, connectivity=connectivity)
        try:
            result = box_dimension(measured, offsets=offsets, fit_range=fr)
        except ValueError as exc:
            raise CLIError(f"--image: {image}: {exc}") from None
        what = f"{region} pixels" if pixels else f"border of the {region} region"
        typer.echo(f"{image}: {what}, {mask.shape[1]} x {mask.shape[0]} px")
        plot_image = measured[::-1]  # drawn with rows upwards: flip to look like the file
        used = fr
    else:
        if resolution < 8:
            raise CLIError(f"--resolution must be an integer >= 8, got {resolution}")
        if max_iter < 1:
            raise CLIError(f"--max-iter must be an integer >= 1, got {max_iter}")
        ew, uw = parse_range("e", e), parse_range("u", u)
        def scan_boxes(mi):
            return _scan_with_progress(dict(
                e=ew, u=uw, method="boxes", resolution=resolution, max_iter=mi, which=which,
                connectivity=connectivity, offsets=offsets, fit_range=fr,
            ))

        result = scan_boxes(max_iter)
        what = "sliding region" if which == "sliding" else "word-length regions"
        typer.echo(
            f"border of the {what} in [{ew[0]:g}, {ew[1]:g}] x [{uw[0]:g}, {uw[1]:g}], "
            f"{resolution} x {resolution} px, max_iter {max_iter} "
            f"(sliding region: {100 * result.region_fraction:.1f}% of the window)"
        )
        plot_image = None
        used = fr

    _print_estimate(result)
    if image is None and store is None:
        _print_accounting(result, ew, uw, at_defaults, check_max_iter, which)
    typer.echo(f"r = {result.r:.5f}")
    auto = " (automatic: largest linear region, a heuristic)" if used is None else ""
    typer.echo(f"fit: boxes of {result.fit_range[0]}..{result.fit_range[1]} px, {result.fit.n} sizes{auto}")
    typer.echo("sizes:  " + " ".join(f"{int(s)}" for s in result.sizes))
    typer.echo("counts: " + " ".join(f"{c:g}" for c in np.asarray(result.counts, dtype=float)))
    if image is None and store is None:
        _print_proven_counts(ew, uw, proven_depth, max_iter, result.dimension)

    if check_max_iter:
        # the same picture at 4 x max_iter; box counts have no per-size band,
        # so a move of more than 0.03 in a local slope counts as a change
        _measure_again(result, scan_boxes, max_iter)
    if png is not None:
        from ..plot import plot_box_dimension

        _draw(png, dpi, force, lambda: plot_box_dimension(
            result, image=plot_image, title=str(image) if image is not None else None))


PROVEN_DEPTH = 8
"""``stairbounce dimension --proven-depth``'s default: the certified atlas of the
proven box counts (about 9 s more on the Fig. 7 window on 2 cores, 18 s in all with the
default slicing; benchmarks/README.md)."""


def _check_proven_depth(depth, picture, which):
    """The depth of the proven box counts (0: none): the default for a window of
    the model and the sliding border, refused by name where it cannot apply."""
    if depth is None:
        return 0 if picture or which != "sliding" else PROVEN_DEPTH
    if depth < 0 or depth > 16:
        raise CLIError(f"--proven-depth must be an integer in [0, 16] (0: off), got {depth}")
    if depth and picture:
        raise CLIError("--proven-depth certifies a window of the model: not with --image or --store")
    if depth and which != "sliding":
        raise CLIError("--proven-depth counts the border of the sliding region: not with --which words")
    return depth


def _print_proven_counts(ew, uw, depth, max_iter, dimension):
    """Proven lower/upper box counts of the sliding region's border (the paper's
    perimeter) and the slope bracket, from a certified atlas of ``depth`` (class-level
    proofs and the fine trapping pass: fewer undecided boxes below the Corollary 2.1
    curve, lower upper counts) whose boxes the independent checker re-verifies (its
    basis says whether it did), beside the numerical ``dimension``."""
    if not depth:
        return
    import stairbounce as sb
    from ..structure.certify import slope_verdict

    try:
        atlas = _with_bar(f"certifying (depth {depth})", lambda progress: sb.certify(
            e=ew, u=uw, depth=depth, max_iter=max_iter, classes=True, trap="fine", progress=progress))
        r = atlas.perimeter_bracket(0 if depth == 1 else None)
    except ValueError as exc:
        raise CLIError(f"--proven-depth: {exc}") from None
    verdict, why = slope_verdict(dimension, r["across"])
    for line in perimeter_lines(r, [f"  beside the numerical D = {dimension:.4f}: {verdict} ({why})"]):
        typer.echo(line)


def _plot_uncertainty(result, ew, uw, compare=()):
    from ..plot import plot_local_dimension, plot_uncertainty

    fig = plot_uncertainty(
        result, title=f"uncertainty exponent of the border in [{ew[0]:g}, {ew[1]:g}] x [{uw[0]:g}, {uw[1]:g}]")
    if compare:
        ax = fig.axes[1]
        ax.clear()
        plot_local_dimension(result, ax=ax, compare=compare, label=f"max_iter {result.max_iter}")
    return fig


def _with_bar(label, call):
    with _bar(label) as (bar, task):
        return call(lambda done, total: bar.update(task, completed=done, total=total))


def _draw(png, dpi, force, make):
    import matplotlib

    matplotlib.use("Agg")
    save_figure(make(), png, dpi, force)
    typer.echo(f"wrote {png}")
