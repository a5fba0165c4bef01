"""``stairbounce borders`` and ``stairbounce words``: the plane's borders located
to rounding and labelled graze / edge / chatter, and the table of its words
(:mod:`stairbounce.structure.borders`)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer

from . import _staircase as st
from ._app import (
    CLIError,
    Dpi,
    Force,
    MaxIter,
    Size,
    app,
    check_dpi,
    check_outputs,
    DEFAULT_E,
    DEFAULT_U,
    parse_range,
    save_figure,
    window_size,
    with_row_progress,
)

_DATA_SUFFIXES = (".nc", ".csv")
_FIGURE_SUFFIXES = (".png", ".pdf", ".svg")
E_HELP = "Window along e, MIN:MAX: the image edges, within [0, 1]; default 0:1, Fig. 4's window."
U_HELP = "Window along u, MIN:MAX (normalised): the image edges, MIN >= 0. Or --speed with --step-height, --step-length."
SPEED_HELP = "Window along the ball's horizontal speed in m/s, MIN:MAX (instead of --u)."
# the window options of borders and words
WindowE = Annotated[Optional[str], typer.Option("--e", help=E_HELP)]
WindowU = Annotated[Optional[str], typer.Option("--u", help=U_HELP + " Default 0:1.5, Fig. 4's window.")]
WindowSpeed = Annotated[Optional[str], typer.Option("--speed", help=SPEED_HELP)]


def _window(e, u, speed, step_height, step_length, g, size, max_iter, out, png, dpi, force, outputs=True):
    """Parse and check everything before any work; returns the scan's window
    arguments and the staircase (None with --u).  ``outputs=False``: the
    caller checks its own outputs."""
    from .. import plane

    default_window = e is None and u is None and speed is None
    if u is None and speed is None:
        u = DEFAULT_U
    u, stairs = st.resolve_u_text(u, speed, step_height, step_length, g)
    if stairs is not None:
        typer.echo(f"speed {speed} m/s on {stairs.describe()}: u = {u}")
    e_lo, e_hi = parse_range("e", e or DEFAULT_E)
    u_lo, u_hi = parse_range("u", u)
    n_e, n_u = window_size(size, (e_lo, e_hi), (u_lo, u_hi), default_window)
    if max_iter < 1 or max_iter > 2**31 - 1:
        raise CLIError(f"--max-iter must be an integer in [1, 2**31 - 1], got {max_iter}")
    plane._window("e", (e_lo, e_hi, n_e), 0.0, 1.0, "[0, 1]")
    plane._window("u", (u_lo, u_hi, n_u), 0.0, float("inf"), "[0, inf)")
    plane._check_memory(n_e, n_u)
    if not outputs:
        return (e_lo, e_hi, n_e), (u_lo, u_hi, n_u)
    if out is not None and out.suffix.lower() not in _DATA_SUFFIXES:
        raise CLIError(f"--out must end in .nc or .csv, got {str(out)!r}")
    if png is not None and png.suffix.lower() not in _FIGURE_SUFFIXES:
        raise CLIError(f"--png must end in .png, .pdf or .svg, got {str(png)!r}")
    if out is None and png is None:
        raise CLIError("give --out FILE (.nc or .csv) and/or --png FILE: there is nothing to write")
    check_dpi(dpi)
    check_outputs(force, out=out, png=png)
    return (e_lo, e_hi, n_e), (u_lo, u_hi, n_u)


def _write(ds, path: Path, overwrite: bool, dim: str) -> None:
    """A labelled table to .nc (netCDF4, strings as variable-length text) or
    .csv (one row per entry of ``dim``), atomically."""
    from .._io import atomic_path, write_shielded

    with atomic_path(path, overwrite=overwrite) as tmp:
        if path.suffix.lower() == ".nc":
            write_shielded(lambda: ds.to_netcdf(tmp, engine="netcdf4"), tmp)
        else:
            ds.drop_dims([d for d in ds.dims if d != dim]).to_dataframe().to_csv(tmp)


def _figure(png, dpi, force, draw):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 6.5))
    draw(ax)
    fig.tight_layout()
    save_figure(fig, png, dpi, force)


@app.command("borders", short_help="Borders between pixels located to rounding, by event.")
def borders_(
    e: WindowE = None, u: WindowU = None, speed: WindowSpeed = None,
    step_height: st.StepHeight = None, step_length: st.StepLength = None, g: st.G = None,
    size: Size = None, max_iter: MaxIter = 1000,
    outcome: str = typer.Option("word", "--outcome", help="What the two sides differ in: word (every border) "
                                "or sliding (the border of the sliding region, one point per crossing)."),
    out: Path = typer.Option(None, "--out", help="The border points: .nc (netCDF) or .csv (one row per point)."),
    png: Path = typer.Option(None, "--png", help="Figure (.png, .pdf or .svg): the borders over the scan, coloured by kind."),
    dpi: Dpi = 150, force: Force = False,
):
    """Every border between neighbouring pixels located to rounding and labelled by its
    event at a step's edge: graze (first contact), edge (a later impact) or chatter
    (the accumulation point)."""
    from .. import plane
    from ..structure import borders
    from ..structure.itinerary import KINDS

    if outcome not in ("word", "sliding"):
        raise CLIError(f"--outcome must be word or sliding, got {outcome!r}")
    ew, uw = _window(e, u, speed, step_height, step_length, g, size, max_iter, out, png, dpi, force)
    ds = with_row_progress(description="scan rows", rows=1,
                           run=lambda p: plane.scan(e=ew, u=uw, max_iter=max_iter, progress=p))
    # outcome sliding on many crossings reports the bisection's rounds, not pairs
    pts = with_row_progress(description="border pairs" if outcome == "word" else "bisection",
                            rows=1, run=lambda p: borders.border_points(ds, outcome=outcome, progress=p))
    if out is not None:
        _write(pts, out, force, "point")
        typer.echo(f"wrote {out}")
    if png is not None:
        from ..plot import plot_borders

        _figure(png, dpi, force, lambda ax: plot_borders(pts, ax=ax, scan=ds))
        typer.echo(f"wrote {png}")
    kinds = pts.kind.values
    n = kinds.size
    shares = ", ".join(f"{k} {int((kinds == k).sum())}" for k in KINDS)
    typer.echo(f"{ew[2]} x {uw[2]} pixels, e in [{ew[0]:g}, {ew[1]:g}], u in [{uw[0]:g}, {uw[1]:g}], "
               f"max_iter {max_iter}: {n} border points ({shares}); "
               f"{int(pts.sliding_border.values.sum())} on the border of the sliding region")


_REGIONS_HELP = ("Trace every word's region as polygons (stairbounce.structure.regions; seeded by a scan of the "
                 "window at --size, 2 to 8192 pixels a side) and write them to --out .geojson or .svg.")
_FROM_CORNERS_HELP = ("With --regions: also trace the regions smaller than a seed pixel found around the corners "
                      "of their neighbours (several times slower).")
_PROVE_HELP = ("Prove each word by intervals at one of its pixel centres (stairbounce.structure.labels) and "
               "report the proven words, a proven lower bound on the distinct words, first.")
_TOLERANCE_HELP = ("With --regions: largest deviation of an exported chord from the traced curve (default 1e-6 "
                   "of the window's larger side).")


@app.command("words", short_help="The distinct words of a window and N(p), or regions.")
def words_(
    e: WindowE = None, u: WindowU = None, speed: WindowSpeed = None,
    step_height: st.StepHeight = None, step_length: st.StepLength = None, g: st.G = None,
    size: Size = None, max_iter: MaxIter = 1000,
    top: int = typer.Option(10, "--top", help="Rows of the table to print (>= 0)."),
    out: Path = typer.Option(None, "--out", help="The word table: .nc (with N(p)) or .csv (one row per word)."),
    png: Path = typer.Option(None, "--png", help="Figure (.png, .pdf or .svg): N(p), distinct words by period."),
    dpi: Dpi = 150, force: Force = False,
    regions: bool = typer.Option(False, "--regions", help=_REGIONS_HELP),
    from_corners: bool = typer.Option(False, "--from-corners", help=_FROM_CORNERS_HELP),
    prove: bool = typer.Option(False, "--prove", help=_PROVE_HELP),
    tolerance: float = typer.Option(None, "--tolerance", help=_TOLERANCE_HELP),
):
    """The distinct words of the periodic sliding solutions in a window: letters, period,
    pixels, area, a representative point, bounding box, border points by kind; and N(p)."""
    from .. import plane
    from ..structure import borders

    if top < 0:
        raise CLIError(f"--top must be >= 0, got {top}")
    if from_corners and not regions:
        raise CLIError("--from-corners goes with --regions")
    if regions and png is not None:
        raise CLIError("--png does not go with --regions: draw the traced regions with --out FILE.svg")
    if tolerance is not None and not regions:
        raise CLIError("--tolerance goes with --regions")
    if regions:
        return _regions(e, u, speed, step_height, step_length, g, size, max_iter, out, force, from_corners,
                        tolerance)
    ew, uw = _window(e, u, speed, step_height, step_length, g, size, max_iter, out, png, dpi, force)
    ds = with_row_progress(description="scan rows", rows=1,
                           run=lambda p: plane.scan(e=ew, u=uw, max_iter=max_iter, progress=p))
    tab = with_row_progress(description="border pairs", rows=1,
                            run=lambda p: borders.word_table(ds, progress=p, prove=prove))
    if out is not None:
        _write(tab, out, force, "word")
        typer.echo(f"wrote {out}")
    if png is not None:
        def draw(ax):
            ax.loglog(tab.p.values, tab.distinct_words.values, "o", ms=3)
            ax.set_xlabel("period p (steps)")
            ax.set_ylabel("N(p): distinct words of period p")
            ax.set_title(f"{tab.sizes['word']} words in e [{ew[0]:g}, {ew[1]:g}] x u [{uw[0]:g}, {uw[1]:g}]")

        _figure(png, dpi, force, draw)
        typer.echo(f"wrote {png}")
    if prove:
        typer.echo(f"{tab.attrs['proven_distinct_words']} proven distinct words (a proven lower bound; "
                   f"each proven by intervals at a pixel centre)")
    typer.echo(f"{tab.sizes['word']} distinct words on {tab.attrs['sliding_pixels']} of "
               f"{tab.attrs['pixels']} pixels (max_iter {max_iter})")
    for i in range(min(top, tab.sizes["word"])):
        r = tab.isel(word=i)
        typer.echo(f"{r.text.item():>30s}  period {int(r.period):5d}  {int(r.pixels):8d} px "
                   f"({100 * float(r.area_fraction):6.2f} %)  at e = {float(r.e_rep):.6g}, "
                   f"u = {float(r.u_rep):.6g}  borders: graze {int(r.graze)}, edge {int(r.edge)}, "
                   f"chatter {int(r.chatter)}")


@app.command("itinerary", short_help="Impact numbers and event margins, step by step.")
def itinerary_(
    e: st.E, u: st.U = None,
    speed: st.Speed = None, step_height: st.StepHeight = None, step_length: st.StepLength = None, g: st.G = None,
    max_iter: MaxIter = 1000, y0: st.Y0 = 1.0, v0: st.V0 = 0.0,
    as_csv: bool = typer.Option(False, "--csv", help="Write CSV to stdout instead of a table."),
):
    """Print the impact number of every step up to the slide, with the signed time margins
    (T - t; >= 0: the event happens on the step) of the first contact, the next impact and
    the accumulation point: the events whose crossing of 0 makes a border; then the word
    the impact numbers spell."""
    import csv
    import sys

    from ..structure.itinerary import _itinerary_args, _itinerary_blocks

    u, stairs = st.resolve_u(u, speed, step_height, step_length, g)
    try:
        e, u, max_iter, y0, v0 = _itinerary_args(e, u, max_iter, y0, v0)
    except ValueError as exc:
        raise CLIError(str(exc)) from None
    cols = ("impacts", "contact", "next_impact", "accumulation")
    # streamed block by block (report round 3, R5: the whole itinerary was kept in memory first)
    word, steps, slid = _WordSpelled(), 0, False
    if as_csv:
        w = csv.writer(sys.stdout, lineterminator="\n")
        w.writerow(["step", *cols])
    else:
        if stairs is not None:
            typer.echo(st.describe(u, stairs))
        typer.echo(ITINERARY_CONVENTION)
        typer.echo(f"{'step':>6}  {'impacts':>8}  {'contact':>14}  {'next impact':>14}  {'accumulation':>14}")
    for whole, slid in _itinerary_blocks(e, u, max_iter, y0, v0):
        for lo in range(0, whole["impacts"].size, 4096):  # rows as text a few thousand at a time
            block = {c: whole[c][lo:lo + 4096] for c in cols}
            ks = block["impacts"]
            word.add(ks)
            ns = range(steps + 1, steps + ks.size + 1)
            steps += ks.size
            margins = zip(*(block[c].tolist() for c in cols[1:]))
            if as_csv:
                w.writerows([n, k, *(repr(x) for x in m)] for n, k, m in zip(ns, ks.tolist(), margins))
                continue
            typer.echo("\n".join(f"{n:6d}  {'slides' if k == -1 else k:>8}  "
                                 + "  ".join(f"{x:14.6e}" for x in m) for n, k, m in zip(ns, ks.tolist(), margins)))
    end = (f"e = {e!r}, u = {u!r}: " + (f"slides on step {steps}; the impact numbers spell the word "
                                        f"{word.text()}" if slid else f"no slide within {max_iter} steps (no word)"))
    if as_csv:  # the CSV alone on stdout; its convention and word beside it
        print(f"stairbounce: {ITINERARY_CONVENTION}", file=sys.stderr)
        print(f"stairbounce: {end}", file=sys.stderr)
        return
    typer.echo(end)


ITINERARY_CONVENTION = (
    "margins are T - t (time units, T = 1/u the time of one step); >= 0: the event happens on the step. "
    "contact: the first contact (>= 0: the step has an impact; 0 is a graze border); next impact: the "
    "impact after the last one (< 0; 0 is an edge border; NaN on the sliding step); accumulation: the "
    "accumulation point (>= 0: the step slides; 0 is a chatter border)"
)


class _WordSpelled:
    """The word of a stream of impact numbers (``structure.words._word_text``'s letters:
    the steps from one impact to the next, a 0 for each further impact on a
    step), kept to its first ``keep`` letters and counted beyond."""

    def __init__(self, keep=200):
        self.keep, self.letters, self.count, self.jump = keep, [], 0, 0

    def add(self, ks):
        for k in ks.tolist():
            self.jump += 1
            if k == 0:
                continue
            new = [str(self.jump)] + (["0"] * (k - 1) if k > 1 else [])
            self.jump = 0
            self.count += len(new)
            self.letters.extend(new[: max(0, self.keep - len(self.letters))])

    def text(self):
        more = self.count - len(self.letters)
        return "(" + ", ".join(self.letters) + (f", ... ({self.count} letters)" if more else "") + ", 0^inf)"


def _regions(e, u, speed, step_height, step_length, g, size, max_iter, out, force, from_corners=False,
             tolerance=None):
    """``words --regions``: the window's regions traced (stairbounce.structure.regions) to GeoJSON or SVG."""
    import time

    from ..structure import export as _region_export
    from ..structure import regions as rg
    from ..structure.graph import border_graph

    if out is None or out.suffix.lower() not in (".geojson", ".json", ".svg"):
        raise CLIError(f"--regions needs --out ending in .geojson or .svg, got {str(out) if out else None!r}")
    ew, uw = _window(e, u, speed, step_height, step_length, g, size, max_iter, out, None, 150, force,
                     outputs=False)
    check_outputs(force, out=out)
    try:
        tolerance, _, _ = _region_export._export_options(tolerance, None, max_iter)
    except ValueError as err:
        raise CLIError(f"--{err}") from None
    if not (2 <= ew[2] <= 8192 and 2 <= uw[2] <= 8192):
        raise CLIError(f"--size with --regions must be 2 to 8192 pixels a side (the seed scan), got "
                       f"{ew[2]}x{uw[2]}")
    # the seed scan is the --size grid of the window (its edges, as a scan's);
    # e = 1 and u = 0 are traced just inside (stairbounce.word_region)
    regs = with_row_progress(description="words traced", rows=1, run=lambda p: rg.window_regions(
        ew, uw, max_iter=max_iter, progress=p, from_corners=from_corners))
    graph = border_graph(regs)  # before the file: nothing is written when it fails
    start = time.perf_counter()
    _, meta = _region_export.write(regs, out, force, tolerance, (ew[2], uw[2]), max_iter, graph=graph)
    took = time.perf_counter() - start
    c = graph.counts()
    arcs = ", ".join(f"{k} {n}" for k, n in sorted(c["arcs"].items())) or "none"
    incomplete = [r.word.format(ascii=True) for r in regs if not r.complete]
    typer.echo(f"wrote {out}")
    typer.echo(f"{c['words']} words in {c['components']} components, {len(graph.nodes)} corners, "
               f"arcs by kind: {arcs}; area traced {sum(r.area for r in regs):.6g} of "
               f"{(ew[1] - ew[0]) * (uw[1] - uw[0]):.6g}; "
               f"{len(incomplete)} words incomplete" + (" (a walk gave up; their traced components, "
                                                         "if any, are in the file):" if incomplete else ""))
    for text in incomplete:
        typer.echo(f"  {text}")
    cov = meta["coverage"]
    typer.echo(f"coverage: traced area {meta['traced_area']:.6g} of the {ew[2]}x{uw[2]} seed scan's sliding "
               f"area {meta['sliding_area']:.6g}" + (f" ({100 * cov:.2f} %)" if cov is not None else "")
               + f"; {len(meta['untraced'])} words seen beside traced arcs but not traced"
               + (" (listed in the file)" if out.suffix.lower() != ".svg" else "")
               + f"; exported in {took:.1f} s (tolerance {meta['tolerance']:.3g})")
