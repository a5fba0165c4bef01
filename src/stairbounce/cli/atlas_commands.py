"""Tiled scans to Zarr (``stairbounce scan ... --tile``) and ``stairbounce render``.

``scan`` itself lives in :mod:`.scan_commands`; with ``--tile``, ``--scheduler``
or ``--workers`` it hands over to :func:`run_tiled_scan` here, which runs
:func:`stairbounce.atlas.scan_to_zarr` locally, on a new local Dask cluster or
on a running scheduler, with a progress bar over tiles.
"""

from __future__ import annotations

import sys
import warnings
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import typer

from ._app import FORCE_HELP, CLIError, app, check_dpi, check_outputs, draw_scan, parse_range, plural

DEFAULT_TILE = 1024
FIELDS = ("word_length", "period", "jumps", "impacts", "status")


def run_tiled_scan(out, e, u, max_iter=1000, y0=1.0, v0=0.0, tile=None, scheduler=None, workers=None):
    """Run a tiled, resumable scan into the store ``out`` and print what was done.

    ``e`` and ``u`` are ``(min, max, n)``; ``tile`` None means
    :data:`DEFAULT_TILE`; at most one of ``scheduler`` (an address such as
    ``tcp://host:8786``) and ``workers`` (worker processes of a local Dask
    cluster, one thread each) may be given, neither runs in this process.
    Returns the opened (lazy) dataset.
    """
    from ..atlas import scan_to_zarr

    out = Path(out)
    if out.suffix != ".zarr":
        raise CLIError(f"--out must be a .zarr store for a tiled scan, got {str(out)!r}")
    tile = DEFAULT_TILE if tile is None else tile
    if tile < 1:
        raise CLIError(f"--tile must be an integer >= 1, got {tile}")
    if scheduler is not None and workers is not None:
        raise CLIError("give --scheduler or --workers, not both")
    if workers is not None and workers < 1:
        raise CLIError(f"--workers must be an integer >= 1, got {workers}")
    if scheduler is not None and "://" not in scheduler:
        raise CLIError(f"--scheduler must be an address such as tcp://HOST:8786, got {scheduler!r}")

    from rich.console import Console

    from .._progress import make_display

    console = Console(stderr=True)
    counts = {}
    cluster = client = None
    try:
        with warnings.catch_warnings(), _quiet_dask_logs(scheduler is not None or workers is not None):
            # a local cluster's HTTP server moves to a free port when 8787 is taken
            warnings.filterwarnings("ignore", message="Port .* is already in use")
            if workers is not None:
                cluster, client = _local_cluster(workers)
            # a bar in a terminal, a line every 10 s elsewhere (as every command)
            bar, task = make_display("tiles", None, "", console)

            def progress(done, total):
                if not counts:  # the store is ready: bad input has been reported by now
                    bar.start()
                counts.setdefault("skipped", done)
                counts["total"] = total
                bar.update(task, completed=done, total=total)

            try:
                # damaged tiles found on resume are a RuntimeWarning: one line (cli.main)
                ds = scan_to_zarr(
                    out, e=e, u=u, max_iter=max_iter, y0=y0, v0=v0, tile=tile,
                    client=scheduler if scheduler is not None else client, progress=progress,
                )
            finally:
                if counts:
                    bar.stop()
    except KeyboardInterrupt:
        print(f"stairbounce: the complete tiles are kept in {out}; run the same command to resume",
              file=sys.stderr)
        raise
    finally:
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
    where = f"scheduler {scheduler}" if scheduler else (plural(workers, "local worker") if workers else "this process")
    skipped = counts.get("skipped", 0)
    resumed = f" ({skipped} already complete)" if skipped else ""
    typer.echo(
        f"wrote {out}: {ds.sizes['e']} x {ds.sizes['u']} pixels (e x u), "
        f"{plural(counts.get('total', 0), 'tile')} of {tile}{resumed}, computed in {where}"
    )
    return ds


@contextmanager
def _quiet_dask_logs(active=True):
    """Dask's client logs a lost scheduler as tracebacks on stderr, also while
    the command reports it and ends; the command says it in one line (report
    N7).  Its loggers are quiet while the scan runs, and stay so after an
    error (the command is ending)."""
    import logging

    if not active:
        yield
        return
    try:
        import distributed  # noqa: F401  (its import configures its loggers: first)
    except ImportError:
        pass
    names = ["distributed"] + [n for n in logging.root.manager.loggerDict if n.startswith("distributed.")]
    levels = {n: logging.getLogger(n).level for n in names}
    for n in names:
        logging.getLogger(n).setLevel(logging.CRITICAL + 1)
    yield
    for n, level in levels.items():
        logging.getLogger(n).setLevel(level)


def _local_cluster(workers):
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise CLIError("--workers needs Dask: pip install 'stairbounce[dask]'") from None
    # one thread per worker process: numba then runs one thread per tile, so
    # N workers keep N cores busy
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
    try:
        return cluster, Client(cluster)
    except BaseException:
        cluster.close()
        raise


@app.command(short_help="Draw a scan store block by block, never whole in memory.")
def render(
    store: Path = typer.Argument(..., help="A scan store (.zarr) or file (.nc), e.g. from 'scan --tile'."),
    png: Path = typer.Option(..., "--png", help="Image to write (.png)."),
    window: str = typer.Option(None, "--window", help="Part to draw, E0:E1,U0:U1 (default: all)."),
    field: str = typer.Option("word_length", "--field", help="Variable to draw: " + ", ".join(FIELDS) + "."),
    max_pixels: int = typer.Option(4_000_000, "--max-pixels", help="Largest image; bigger windows are reduced by blocks."),
    reduce: str = typer.Option("mode", "--reduce", help="Block reducer: mode (most frequent value), max or stride."),
    dpi: int = typer.Option(150, "--dpi", help="Resolution of the figure."),
    force: bool = typer.Option(False, "--force", help=FORCE_HELP),
):
    """Draw a scan store without loading it whole: large windows are reduced by blocks first."""
    import xarray as xr

    from .._io import check_store_metadata
    from ..atlas import DamagedStoreError, tiles_done
    from ..plane import _check_grid

    if png.suffix.lower() != ".png":
        raise CLIError(f"--png must end in .png, got {str(png)!r}")
    if field not in FIELDS:
        raise CLIError(f"--field must be one of {', '.join(FIELDS)}, got {field!r}")
    if max_pixels < 1:
        raise CLIError(f"--max-pixels must be an integer >= 1, got {max_pixels}")
    if reduce not in ("mode", "max", "stride"):
        raise CLIError(f"--reduce must be mode, max or stride, got {reduce!r}")
    check_dpi(dpi)
    if not store.exists():
        raise CLIError(f"no such store: {store}")
    check_outputs(force, png=png)
    try:
        if store.suffix == ".nc":
            ds = xr.open_dataset(store, engine="netcdf4", chunks={})
        else:
            check_store_metadata(store)
            ds = xr.open_zarr(store, consolidated=False)
    except Exception as exc:  # noqa: BLE001 - any reader error is bad input here
        raise CLIError(f"cannot read {store} as a scan: {' '.join(str(exc).split())}") from None
    for name in dict.fromkeys([field, "status"]):  # status: where nothing slides (draw_store)
        if name not in ds.data_vars or set(ds[name].dims) != {"u", "e"}:
            raise CLIError(f"{store} has no ({'u'}, {'e'}) variable {name!r}")
    _check_grid(ds, store)
    try:
        done = tiles_done(store)
    except DamagedStoreError:
        raise
    except ValueError:
        done = None  # a saved scan, complete by construction
    if done is not None and not done.all():
        print(
            f"stairbounce: warning: {int((~done).sum())} of {done.size} tiles of {store} are not "
            "computed yet; they are drawn blank",
            file=sys.stderr,
        )
    bounds = None
    if window:
        parts = window.split(",")
        if len(parts) != 2:
            raise CLIError(f"--window must be E0:E1,U0:U1, got {window!r}")
        bounds = (parse_range("window", parts[0]), parse_range("window", parts[1]))
    small = draw_store(ds, field, png, dpi, max_pixels=max_pixels, reduce=reduce, window=bounds,
                       overwrite=force, source=store)
    f = small.attrs.get("downsampled", 1)
    how = f", blocks of {f} x {f} ({reduce})" if f > 1 else ""
    typer.echo(f"wrote {png}: {field}, {small.sizes['e']} x {small.sizes['u']} pixels{how}")


def draw_store(ds, field, png, dpi, overlay=(), max_pixels=4_000_000, reduce="mode", window=None,
               overwrite=False, source=None):
    """Draw ``field`` of a (lazy) scan dataset into ``png`` with
    :func:`stairbounce.plot.plot_scan`, reduced by blocks to at most
    ``max_pixels`` first (:func:`stairbounce.atlas.downsample`), so that only
    the reduced image is ever in memory.  ``window``: ``((e0, e1), (u0, u1))``,
    the pixels whose centres lie inside are drawn.  Returns the reduced
    dataset that was drawn.  A chunk that cannot be read (damaged) is one
    line naming the store (``source``), not a traceback.
    """
    from ..atlas import downsample

    # status too: it tells where there is no periodic sliding solution
    ds = ds[list(dict.fromkeys([field, "status"]))]
    first = {"e": 0, "u": 0}
    if window is not None:
        for name, (lo, hi) in zip(("e", "u"), window):
            c = ds[name].values
            first[name] = int(np.searchsorted(c, lo, side="left"))
            last = int(np.searchsorted(c, hi, side="right"))
            if last <= first[name]:
                raise CLIError(f"--window {name} in [{lo:g}, {hi:g}] holds no pixel of the store")
            ds = ds.isel({name: slice(first[name], last)})
    try:
        small = downsample(ds, max_pixels, method=reduce).compute()
    except (RuntimeError, OSError, ValueError, KeyError) as exc:
        # a garbled or truncated chunk: the reader's error, in one line
        where = source if source is not None else "the store"
        raise CLIError(
            f"cannot read {where}: a chunk is damaged ({type(exc).__name__}: {' '.join(str(exc).split())}); "
            "a tiled store repairs itself when its scan is run again"
        ) from None
    f = small.attrs.get("downsampled", 1)
    for name in ("e", "u") if (window is not None or f > 1) else ():
        # the image edges are those of the pixels kept (blocks trim the far edge)
        a = small.attrs
        keys = (f"{name}_min", f"{name}_max", f"n_{name}")
        if all(k in a for k in keys):
            width = (a[keys[1]] - a[keys[0]]) / a[keys[2]]
            lo = a[keys[0]] + first[name] * width
            a[keys[0]], a[keys[1]] = lo, lo + small.sizes[name] * f * width
            a[keys[2]] = small.sizes[name] * f
        else:
            a.pop(keys[0], None), a.pop(keys[1], None)
    draw_scan(small, field, overlay, png, dpi, overwrite=overwrite)
    return small
