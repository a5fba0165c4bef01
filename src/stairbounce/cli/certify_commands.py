"""``stairbounce certify``: a certified atlas of a window of the (e, u) plane
(:func:`stairbounce.certify`), its summary, files and picture; ``--verify FILE``
re-checks a saved atlas with the independent checker."""

from __future__ import annotations

from pathlib import Path

import typer

from ._app import (FORCE_HELP, CLIError, app, check_dpi, check_outputs, parse_range, perimeter_lines, progress_bar,
                   save_figure)

_FIGURE_SUFFIXES = (".png", ".pdf", ".svg")


def _pct(x: float, digits: int, down: bool = True) -> str:
    """``100 x`` in percent with ``digits`` decimals, rounded down (a lower bound stays
    one) or up, exactly (decimal arithmetic on the float's exact value)."""
    from decimal import ROUND_CEILING, ROUND_FLOOR, Decimal

    q = Decimal(1).scaleb(-digits)
    return str((Decimal(x) * 100).quantize(q, rounding=ROUND_FLOOR if down else ROUND_CEILING))


# the proven statuses the summaries list (with --classes, "sliding": some word, which of a few)
_PROVEN = {False: ("word", "no_sliding", "no_slide_within"), True: ("word", "sliding", "no_sliding", "no_slide_within")}


def _verify(path: Path, perimeter: bool = False) -> None:
    try:
        from ..structure.verdict import verify
    except ImportError:
        raise CLIError("--verify is not available: this stairbounce has no independent checker "
                       "(stairbounce.structure.verdict)") from None
    try:
        v = verify(path)
    except ValueError as exc:
        raise CLIError(str(exc)) from None
    typer.echo(f"{path}: {v.checked} certificates checked, {v.rejected} rejected: {v.message}")
    if v.numbers:
        n = v.numbers
        typer.echo(f"the checker's numbers ({n['basis']}), shares of {n['of']}:")
        typer.echo("  " + ", ".join(f"{k} [{_pct(lo, 4)}%, {_pct(hi, 4, down=False)}%]"
                                    for k, (lo, hi) in n["status"].items()))
        if not v.complete:
            lo, hi = n["uncovered_area"]
            typer.echo(f"  uncovered area in [{lo:.6g}, {hi:.6g}] (the atlas does not cover its window)")
        words = sorted(n["words"].items(), key=lambda p: (-p[1][0], p[0]))
        typer.echo(f"  proven words: {len(words)} (at least that many words in {n['of']})")
        for w, (lo, hi) in words[:10]:
            typer.echo(f"  {w:<32} area in [{lo:.6g}, {hi:.6g}]")
    if perimeter:
        _perimeter(path, v)
    if not v.ok:
        raise typer.Exit(1)


def _perimeter(path: Path, verdict) -> None:
    """The proven box counts of the sliding region's border of the file just verified
    (``verdict``: basis proven only when it passed): a store's tile by tile, an atlas
    file's loaded."""
    from ..structure._store_read import is_store
    from ..structure.certify import CertifiedAtlas, _scales, counted_depth, perimeter_result
    from ..structure.certify_store import CertifiedStore

    try:
        if is_store(path):
            st = CertifiedStore(path)

            def count(progress, phase):
                phase("border counts, tile by tile")
                return st.border_box_counts(progress=progress)

            df = _with_phases(count)
            attrs = st.attrs
        else:
            atlas = CertifiedAtlas.load(path)
            df, attrs = atlas.border_box_counts(), atlas.boxes.attrs
        k1, k2 = _scales(None, None, counted_depth(attrs))  # a --focus store: the scales k <= focus
        r = perimeter_result(df, k1, k2, int(attrs["depth"]), int(attrs["max_iter"]), verdict, attrs.get("focus"))
    except ValueError as exc:
        raise CLIError(f"--perimeter: {exc}") from None
    for line in perimeter_lines(r):
        typer.echo(line)


def _picture(atlas, png: Path, dpi: int, force: bool) -> None:
    """Proven boxes coloured by their word's length in the scans' colours (one
    colour bar), no_sliding by Corollary 2.1 and by a trapping region apart,
    undecided boxes by reason; the window and the proven share in the title."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    from matplotlib.colors import BoundaryNorm, ListedColormap, to_rgba
    from matplotlib.patches import Patch

    from .._colours import KIND_COLOURS
    from ..plot.plane import class_bounds, color_key
    from ..structure import _kernel as K
    from ..symbolic import parse_word

    b = atlas.boxes
    n = 1 << min(atlas.depth, 11)
    shift = atlas.depth - min(atlas.depth, 11)
    img = np.ones((n, n, 4))
    lv = b["level"].values.astype(np.int64)
    st = b["status"].values
    rs = b["reason"].values
    reasons = [r for r, v in atlas.fraction("reason").items() if v > 0]
    key = color_key("word_length")
    bounds = class_bounds("word_length")
    lengths = {w: len(parse_word(w)) for w in np.unique(b["word"].values[st == K.WORD])}
    # fixed colours outside the word-length palette: Corollary 2.1 grey, trapping blue-grey,
    # no slide within dark grey, the border events as the borders picture and the explorer
    # colour them (violet, pink, dark green), nonsliding white
    fixed = {"cor": "#808080", "trap": "#7f9fcf", "within": "#404040", **KIND_COLOURS,
             "impacts": "#8b4513", "nonsliding": "#ffffff", "range": "#f0e68c"}
    for k in range(b.sizes["box"]):
        L = lv[k]
        if L <= atlas.depth - shift:
            f = 1 << (atlas.depth - shift - L)
            i0, j0 = int(b["i"].values[k]) * f, int(b["j"].values[k]) * f
            i1, j1 = i0 + f, j0 + f
        else:  # finer than a pixel: paint its pixel
            g = L - (atlas.depth - shift)
            i0, j0 = int(b["i"].values[k]) >> g, int(b["j"].values[k]) >> g
            i1, j1 = i0 + 1, j0 + 1
        if st[k] == K.WORD:
            c = key.colors[int(np.searchsorted(bounds, lengths[b["word"].values[k]], side="right")) - 1]
        elif st[k] == K.NO_SLIDING:
            c = fixed["trap" if rs[k] == "trapping" else "cor"]
        elif st[k] == K.NO_SLIDE_WITHIN:
            c = fixed["within"]
        else:
            c = fixed.get(str(rs[k]), "#ffffff")
        img[j0:j1, i0:i1] = to_rgba(c)
    fig, ax = plt.subplots(figsize=(8.5, 6.5))
    (e0, e1), (u0, u1) = atlas.window
    ax.imshow(img, origin="lower", extent=(e0, e1, u0, u1), aspect="auto", interpolation="nearest")
    f = atlas.fraction()
    trapped = (st == K.NO_SLIDING) & (rs == "trapping")
    handles = [Patch(color=fixed["cor"], label="no sliding (Cor. 2.1)")] if ((st == K.NO_SLIDING) & ~trapped).any() \
        else []
    if trapped.any():
        handles.append(Patch(color=fixed["trap"], label="no sliding (trapping region: never slides)"))
    if (st == K.NO_SLIDE_WITHIN).any():
        handles.append(Patch(color=fixed["within"], label="no slide within max_iter"))
    handles += [Patch(facecolor=fixed.get(r, "#ffffff"), edgecolor="0.6", label=f"undecided: {r}")
                for r in reasons if r != "trapping"]
    ax.legend(handles=handles, fontsize=7, loc="upper right")
    sm = plt.cm.ScalarMappable(cmap=ListedColormap(key.colors),
                               norm=BoundaryNorm(np.arange(len(key.colors) + 1) - 0.5, len(key.colors)))
    bar = fig.colorbar(sm, ax=ax, ticks=key.ticks)
    bar.ax.set_yticklabels([key.labels[i] for i in key.ticks], fontsize=7)
    bar.set_label("proven word's length (the scans' colours)")
    ax.set_xlabel("e (restitution coefficient)")
    ax.set_ylabel("u (normalised horizontal speed)")
    proven = 1.0 - f["undecided"]
    ax.set_title(f"certified atlas, e {e0:g}..{e1:g} x u {u0:g}..{u1:g}, depth {atlas.depth}: "
                 f"proven {100 * proven:.1f}% of the window (word {100 * f['word']:.1f}%)", fontsize=9)
    fig.tight_layout()
    save_figure(fig, png, dpi, force)


@app.command("certify", short_help="A certified atlas: words proven over boxes.")
def certify_(
    e: str = typer.Option("0.155:0.2138", "--e", help="Window along e, LO:HI, within [0, 1]. Default: Fig. 7's."),
    u: str = typer.Option("0.6:0.658", "--u", help="Window along u, LO:HI (normalised), LO >= 0. Default: Fig. 7's."),
    depth: int = typer.Option(10, "--depth", help="The smallest boxes are window/2^DEPTH a side (0-26)."),
    max_iter: int = typer.Option(1000, "--max-iter", help="Steps followed before 'no slide within' (>= 1)."),
    out: Path = typer.Option(None, "--out", help="The atlas: .nc or .zarr (every box, its itinerary), "
                             ".geojson (proven boxes merged per word)."),
    png: Path = typer.Option(None, "--png", help="Picture (.png, .pdf or .svg): proven words by length (the scans' "
                             "colours), trapping apart, undecided boxes by reason."),
    dpi: int = typer.Option(150, "--dpi", help="Resolution of raster output (10-1200)."),
    top: int = typer.Option(10, "--top", help="Proven words listed in the summary (largest proven area first)."),
    trap: bool = typer.Option(False, "--trap", help="Try a trapping region on every undecided 'nonsliding' box: "
                              "where one is proven, the orbit of (1, 0) never slides there (status no_sliding, "
                              "reason 'trapping'). Costs more than the atlas itself."),
    fine_trap: bool = typer.Option(False, "--fine-trap", help="--trap with more grids (those the default "
                                   "pass skips, and 1024 to 8192 cells a side) where the spread of T over a box is "
                                   "narrow: for the perimeter's counts; on the paper's plane 95 % of the "
                                   "non-sliding area below the Corollary 2.1 curve proven instead of 85 %, the "
                                   "pass about 7 times as long."),
    verify: Path = typer.Option(None, "--verify", help="Instead: re-check the certificates of a saved atlas "
                                "(.nc or .zarr, or a --store) with the independent checker."),
    classes: bool = typer.Option(False, "--classes", help="Class-level proofs: a border box where every point "
                                 "slides within --max-iter, with one of several words, is proven 'sliding', and "
                                 "one where none does 'no_slide_within'; what stays undecided is the sliding "
                                 "region's border (for the proven box counts of --verify --perimeter)."),
    perimeter: bool = typer.Option(False, "--perimeter", help="With --verify: also print the proven box counts "
                                   "of the sliding region's border (the paper's perimeter) per scale window/2^k "
                                   "and the slope brackets, from the verified boxes (a store: tile by tile, in the "
                                   "memory of a tile); proven only when the checker passed every box."),
    store: Path = typer.Option(None, "--store", help="Stream the atlas to this .zarr store tile by tile "
                               "(memory bounded by a tile, not the depth; the same boxes as in memory); "
                               "the same command resumes an interrupted store. Not with --out or --png "
                               "(they hold the atlas in memory: load the store for them)."),
    scheduler: str = typer.Option(None, "--scheduler", help="With --store: compute the tiles on the Dask "
                                  "scheduler at this address (tcp://HOST:8786); the workers write the store, "
                                  "which they must see at the same path."),
    focus: int = typer.Option(None, "--focus", help="With --store, for the perimeter's proven counts at the "
                              "scales k <= FOCUS: certify to depth FOCUS, then deepen to --depth only the "
                              "undecided boxes next to a window/2^FOCUS cell not yet holding proven points of "
                              "both classes (--verify --perimeter then counts k <= FOCUS)."),
    force: bool = typer.Option(False, "--force", help=FORCE_HELP),
):
    """Cover a window of the (e, u) plane with boxes on which interval arithmetic proves
    the periodic sliding solution's word, or no sliding (Corollary 2.1), or leaves the
    box undecided with its reason; print the proven area by status, the proven words and
    the undecided area by reason.

    Reasons of undecided boxes: graze (the first impact lands on the step at some points
    of the box, flies over at others), edge (a later impact, likewise), chatter (the
    slide test (2.4) differs across the box), impacts (over 4096 impacts on one step),
    nonsliding (every decision proven, but the float map does not slide within
    --max-iter: numerical; --trap tries to prove it), range (the box touches e = 1 or
    u = 0; a box touching e = 0 is certified like the others).  A box is the binary
    floats of the typed decimals; see docs/citing.md for citing a proven box."""
    import time

    from .._io import suffix_of
    from ..structure.certificate import STATUSES
    from ..structure.certify import ATLAS_SUFFIXES, certify

    mode: bool | str = "fine" if fine_trap else trap  # trapping.TRAP_MODES: "fine", the finer grids too
    if perimeter and verify is None:
        raise CLIError("--perimeter goes with --verify (the counts of a saved atlas or store, from its verified boxes)")
    if verify is not None:
        _verify(verify, perimeter)
        return
    e_lo, e_hi = parse_range("e", e)
    u_lo, u_hi = parse_range("u", u)
    if scheduler is not None and store is None:
        raise CLIError("--scheduler needs --store (the tiles of a streamed atlas)")
    if focus is not None and store is None:
        raise CLIError("--focus needs --store (a store refined for the perimeter's counts)")
    if store is not None:
        if out is not None or png is not None:
            raise CLIError("--store writes the atlas itself: give --out or --png without --store, or load the store")
        _streamed(store, scheduler, e_lo, e_hi, u_lo, u_hi, depth, max_iter, mode, classes, top, focus)
        return
    if out is not None:
        suffix_of(out, ATLAS_SUFFIXES, "--out")   # the rule of CertifiedAtlas.save, before the work
    if png is not None:
        suffix_of(png, _FIGURE_SUFFIXES, "--png")
    if top < 0:
        raise CLIError(f"--top must be >= 0, got {top}")
    check_dpi(dpi)
    check_outputs(force, out=out, png=png)
    t0 = time.perf_counter()
    try:
        atlas = _with_phases(lambda p, ph: certify(e=(e_lo, e_hi), u=(u_lo, u_hi), depth=depth,
                                                  max_iter=max_iter, progress=p, trap=mode, classes=classes,
                                                  phase=ph))
    except ValueError as exc:  # the library names its parameters; the options carry the same names
        raise CLIError(f"--{str(exc).replace('_', '-')}" if str(exc).split()[0] in ("depth", "max_iter")
                       else str(exc)) from None
    seconds = time.perf_counter() - t0
    if out is not None:
        atlas.save(out, overwrite=force)
        typer.echo(f"wrote {out}")
    if png is not None:
        _picture(atlas, png, dpi, force)
        typer.echo(f"wrote {png}")
    f = atlas.fraction()
    r = atlas.fraction("reason")
    words = atlas.words()
    n_box = atlas.boxes.sizes["box"]
    typer.echo(f"e in [{e_lo:g}, {e_hi:g}], u in [{u_lo:g}, {u_hi:g}], depth {depth} (boxes down to "
               f"window/{1 << depth}), max_iter {max_iter}: {n_box} boxes in {seconds:.2f} s")
    typer.echo("proven: at least " + ", ".join(f"{k} {_pct(f[k], 2)}%" for k in _PROVEN[classes])
               + " of the window's area (proven bounds: the boxes' exact areas summed, rounded down)")
    if mode:
        rs, st = atlas.boxes["reason"].values, atlas.boxes["status"].values
        book = atlas._book()
        trapped = book.share((st == STATUSES.index("no_sliding")) & (rs == "trapping"))[0]
        typer.echo(f"  of which no_sliding by a trapping region at least {_pct(trapped, 2)}% (proven: the orbit of "
                   "(1, 0) never slides there)")
    f_up = atlas.fraction(bound="upper")
    typer.echo(f"undecided at most {_pct(f_up['undecided'], 2, down=False)}%: "
               + ", ".join(f"{k} {_pct(v, 2, down=False)}%" for k, v in atlas.fraction("reason", "upper").items() if v > 0)
               + ("  (nonsliding: numerical, the float map does not slide there)" if r.get("nonsliding") else ""))
    by = ", ".join(f"{p}: {c}" for p, c in words.attrs["by_period"].items())
    typer.echo(f"proven words: {len(words)} (a proven lower bound on the window's words; by period {by})")
    shares = atlas.fraction("word")
    for row in words.head(top).itertuples():
        typer.echo(f"  {row.word:<32} period {row.period:>4}  area >= {_pct(shares[row.word], 3)}% "
                   f"({row.boxes} boxes)")


def _streamed(store, scheduler, e_lo, e_hi, u_lo, u_hi, depth, max_iter, trap, classes, top, focus=None):
    """``--store``: :func:`stairbounce.certify_to_zarr` behind a progress bar over its
    tiles, then the summary from the store's proven numbers (its boxes not loaded)."""
    import time

    from ..structure.certify_store import certify_to_zarr

    if scheduler is not None and "://" not in scheduler:
        raise CLIError(f"--scheduler must be an address such as tcp://HOST:8786, got {scheduler!r}")
    if store.suffix != ".zarr":
        raise CLIError(f"--store must be a .zarr store, got {str(store)!r}")
    t0 = time.perf_counter()
    try:
        st = _with_phases(lambda p, ph: certify_to_zarr(store, e=(e_lo, e_hi), u=(u_lo, u_hi), depth=depth,
                                                        max_iter=max_iter, trap=trap, classes=classes,
                                                        client=scheduler, progress=p, phase=ph, focus=focus))
    except KeyboardInterrupt:
        typer.echo(f"stairbounce: the complete tiles are kept in {store}; run the same command to resume", err=True)
        raise
    except ValueError as exc:
        raise CLIError(f"--{str(exc).replace('_', '-')}" if str(exc).split()[0] in ("depth", "max_iter", "focus")
                       else str(exc)) from None
    seconds = time.perf_counter() - t0
    f, f_up = st.fraction(), st.fraction(bound="upper")
    typer.echo(f"wrote {store}: e in [{e_lo:g}, {e_hi:g}], u in [{u_lo:g}, {u_hi:g}], depth {depth}, max_iter "
               f"{max_iter}: {st.boxes} boxes in {st.attrs['n_tiles']} tiles, {seconds:.2f} s")
    typer.echo("proven: at least " + ", ".join(f"{k} {_pct(f[k], 2)}%" for k in _PROVEN[classes])
               + " of the window's area (proven bounds, summed over the tiles and rounded outward)")
    typer.echo(f"undecided at most {_pct(f_up['undecided'], 2, down=False)}%: "
               + ", ".join(f"{k} {_pct(v, 2, down=False)}%" for k, v in st.fraction("reason", "upper").items() if v > 0))
    shares = st.fraction("word")
    typer.echo(f"proven words: {len(shares)} (a proven lower bound on the window's words)")
    for w, v in list(shares.items())[:top]:
        typer.echo(f"  {w:<32} area >= {_pct(v, 3)}%")
    typer.echo(f"check it with: stairbounce certify --verify {store}")


def _with_phases(run):
    """``run(progress, phase)`` behind one progress bar on stderr whose
    description names the pass being counted ("certify levels 3-14", then
    "certify trapping regions", ...), its count restarting with each pass."""
    from rich.console import Console

    with progress_bar(Console(stderr=True), "certify", 1) as (bar, task):
        def phase(name):
            bar.update(task, description=f"certify {name}", completed=0, total=1)

        return run(lambda done, total: bar.update(task, completed=done, total=max(total, 1)), phase)
