"""Box counting of the border in a tiled atlas store, tile by tile (Section 3, Figs. 6-7).

A store written by :func:`stairbounce.atlas.scan_to_zarr` can be far larger
than memory (32768 x 32768 pixels are 27 GB of scan variables).  Its border is
measured here without ever holding more than one tile and its halo:

- each tile reads its ``status`` (and ``word_length`` for the borders between
  words) with a one-pixel halo from the neighbouring tiles, so that its border
  pixels are exactly those of :func:`stairbounce.dimension.boundary` (or
  :func:`~stairbounce.dimension.label_boundary`) of the whole image: a pixel's
  neighbours across a tile edge are read, and at the image edge the same
  edge rule applies (``image_edge="ignore"``);
- box sides ``s`` that divide the tile size: the boxes of the image grid never
  cross a tile edge, so ``N(s)`` is the sum over tiles of the tile's count;
- every other box side: each tile also returns its border OR-reduced by
  ``G x G`` blocks, ``G`` the greatest common divisor of the tile size and
  those sides; the reduced tiles form a ``ceil(n_u/G) x ceil(n_e/G)`` image
  whose box counts at side ``s / G`` are ``N(s)`` (a box holds a border pixel
  exactly when one of its blocks does).

The counts equal, count for count, :func:`stairbounce.dimension.box_counts` of
the whole border in memory (``tests/test_atlas_boxes.py``).  Tiles run in a
pool of threads of this process or as tasks of a Dask cluster (the one that
made the store, say), like the scan itself.

Core module: nothing here imports matplotlib, Typer or the web stack at
import time; zarr is imported where a store is read, dask only for a
cluster.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from .atlas import _check_client, _connect, _dask_each, tile_slices, tiles_done
from .dimension.borders import boundary, label_boundary
from .dimension.boxes import _check_sizes, box_counts, box_dimension_from_counts
from .dimension.classifier import _WHICH

__all__ = ["store_box_counts", "store_box_dimension", "store_info"]

# The OR-reduced image of the box sides that do not divide the tile is held by
# the caller: refuse sides that would make it as large as the store.
_MAX_REDUCED_PIXELS = 1 << 26


def _open(path):
    """The store's root group, refused unless every tile is complete."""
    import zarr

    p = Path(os.fspath(path))
    if not p.exists():
        raise ValueError(f"no such store: {p}")
    done = tiles_done(p)  # ValueError for anything but a tiled scan store
    if not done.all():
        missing = int(done.size - done.sum())
        raise ValueError(
            f"the store {p} is not complete: {missing} of {done.size} tiles are missing; "
            "finish it first (run the same scan_to_zarr / 'stairbounce scan --tile' again, it resumes)"
        )
    root = zarr.open_group(str(p), mode="r")
    tile = int(root["tiles"].attrs["tile"])
    return root, tile


def store_info(path):
    """store_info(path) -> dict

    The scan attributes of a finished atlas store (window ``e_min``,
    ``e_max``, ``u_min``, ``u_max``, sizes ``n_e``, ``n_u``, ``max_iter``,
    ...) and its ``tile`` size.  Raises ``ValueError`` for a path that is not
    a tiled scan store or a store with missing tiles.
    """
    root, tile = _open(path)
    return dict(root.attrs, tile=tile)


def _check_args(which, connectivity):
    if which not in _WHICH:
        raise ValueError(f"which must be one of {_WHICH}, got {which!r}")
    if connectivity not in (4, 8):
        raise ValueError(f"connectivity must be 4 or 8, got {connectivity!r}")


def _tile_border(root, rows, cols, which, connectivity):
    """The border pixels of one tile, from the tile and its one-pixel halo."""
    n_u, n_e = root["status"].shape
    r0, r1 = max(rows.start - 1, 0), min(rows.stop + 1, n_u)
    c0, c1 = max(cols.start - 1, 0), min(cols.stop + 1, n_e)
    region = root["status"][r0:r1, c0:c1] == 0
    if which == "sliding":
        # where the halo stops at the image edge, boundary's edge padding is
        # the image's: the border of the block is the image's border there
        b = boundary(region, connectivity=connectivity)
    else:
        labels = np.where(region, root["word_length"][r0:r1, c0:c1], -1).astype(np.int64)
        b = label_boundary(labels, connectivity=connectivity)
    i, j = rows.start - r0, cols.start - c0
    return b[i : i + rows.stop - rows.start, j : j + cols.stop - cols.start]


def _reduce(border, g):
    """OR over ``g x g`` blocks (the last ones clipped by the tile's edge)."""
    h, w = border.shape
    hb, wb = -(-h // g), -(-w // g)
    if g == 1:
        return border.copy()
    padded = np.zeros((hb * g, wb * g), dtype=bool)
    padded[:h, :w] = border
    return padded.reshape(hb, g, wb, g).any(axis=(1, 3))


def _tile_counts(path, rows, cols, which, connectivity, small, g):
    """Counts of one tile at the sides in ``small`` and its ``g``-reduced
    border (None when no side needs it).  Runs here or on a Dask worker."""
    import zarr

    root = zarr.open_group(str(path), mode="r")
    border = _tile_border(root, rows, cols, which, connectivity)
    counts = box_counts(border, sizes=small)[1] if len(small) else np.zeros(0, dtype=np.int64)
    reduced = _reduce(border, g) if g else None
    return rows, cols, np.asarray(counts, dtype=np.int64), reduced


def _plan(sizes, tile):
    small = [int(s) for s in sizes if tile % int(s) == 0]
    rest = [int(s) for s in sizes if tile % int(s) != 0]
    g = math.gcd(tile, *rest) if rest else 0
    return small, rest, g


def store_box_counts(path, which="sliding", connectivity=4, sizes=None, client=None, progress=None, threads=None):
    """store_box_counts(path, which="sliding", connectivity=4, sizes=None, client=None, progress=None, threads=None) -> (sizes, counts)

    :func:`stairbounce.dimension.box_counts` of the border of a finished atlas
    store, computed tile by tile.

    ``N(s)`` = number of boxes of side ``s`` pixels of the image grid
    (rows along u, columns along e, origin at the first pixel; boxes
    clipped by the image edge count) holding a border pixel, where the
    border is ``boundary(status == 0)`` (``which="sliding"``, the perimeter
    of Figs. 6-7) or ``label_boundary`` of the word lengths with -1 where
    nothing slides (``which="words"``), exactly as
    :func:`stairbounce.dimension.perimeter_dimension` takes it from a scan.

    Parameters
    ----------
    path : str or path-like
        A store of :func:`stairbounce.atlas.scan_to_zarr` with every tile
        complete.
    which : "sliding" or "words", default "sliding"
    connectivity : 4 or 8, default 4
    sizes : sequence of int >= 1, default None
        Box sides in pixels; default the powers of two up to the shorter side
        of the image.  Sides that divide the tile size are summed over tiles;
        the others are counted on the border reduced by the greatest common
        divisor ``G`` of the tile size and those sides, an image of
        ``(n_u / G) x (n_e / G)`` pixels that must stay under 2^26 (with a
        power-of-two tile and the default sides, ``G`` is the tile size).
    client : None, ``dask.distributed.Client`` or str, default None
        None: tiles in a pool of ``threads`` threads of this process.  A client
        or a scheduler address (connected for this call): one task per tile.
    progress : callable(done, total) or None
        Called with the number of tiles counted, once before the first; an
        exception raised there stops the count.
    threads : int >= 1 or None, default None (numba's thread count)
        Local tiles at once.

    Returns
    -------
    sizes : int64 array, counts : int64 array

    Raises
    ------
    ValueError
        A path that is not a tiled scan store, a store with missing tiles,
        or a bad parameter (naming it).

    Memory: one tile with its halo per task (status, and word_length for
    ``"words"``), plus the reduced image in the caller.
    """
    from .model import check_count

    _check_args(which, connectivity)
    root, tile = _open(path)
    n_u, n_e = root["status"].shape
    s = _check_sizes(sizes, (n_u, n_e))
    small, rest, g = _plan(s, tile)
    if rest and (-(-n_u // g)) * (-(-n_e // g)) > _MAX_REDUCED_PIXELS:
        raise ValueError(
            f"sizes {rest} share only a factor {g} with the tile size {tile}: their counts would need "
            f"the border reduced to {-(-n_u // g)} x {-(-n_e // g)} pixels; use box sides that divide "
            "the tile size or are multiples of a large divisor of it"
        )
    threads = None if threads is None else check_count("threads", threads, 1)
    tasks = [(str(path), rows, cols, which, connectivity, small, g)
             for rows in tile_slices(n_u, tile) for cols in tile_slices(n_e, tile)]
    summed = np.zeros(len(small), dtype=np.int64)
    reduced = np.zeros((-(-n_u // g), -(-n_e // g)), dtype=bool) if g else None

    def collect(result):
        nonlocal summed
        rows, cols, counts, red = result
        summed += counts
        if red is not None:
            i, j = rows.start // g, cols.start // g
            reduced[i : i + red.shape[0], j : j + red.shape[1]] = red

    if client is None:
        _run_here(tasks, threads, collect, progress)
    else:
        _run_on_dask(client, tasks, collect, progress)

    counts = np.zeros(len(s), dtype=np.int64)
    where = {int(v): k for k, v in enumerate(s)}
    for size, c in zip(small, summed):
        counts[where[size]] = c
    if rest:
        _, big = box_counts(reduced, sizes=[r // g for r in rest])
        for size, c in zip(rest, big):
            counts[where[size]] = c
    return s, counts


def _run_here(tasks, threads, collect, progress):
    import numba
    from concurrent.futures import ThreadPoolExecutor, as_completed

    total = len(tasks)
    if progress is not None:
        progress(0, total)
    workers = threads or numba.get_num_threads()
    if workers == 1 or total == 1:
        for k, t in enumerate(tasks, 1):
            collect(_tile_counts(*t))
            if progress is not None:
                progress(k, total)
        return
    # zarr's decompression and numpy's array operations release the GIL, so
    # tiles overlap in threads; a bounded window of submitted tiles keeps the
    # memory to a few tiles whatever the store's size
    with ThreadPoolExecutor(workers, thread_name_prefix="stairbounce-boxes") as pool:
        pending, it, done = set(), iter(tasks), 0
        try:
            for t in it:
                pending.add(pool.submit(_tile_counts, *t))
                if len(pending) >= 2 * workers:
                    finished = next(as_completed(pending))
                    pending.discard(finished)
                    collect(finished.result())
                    done += 1
                    if progress is not None:
                        progress(done, total)
            for finished in as_completed(pending):
                collect(finished.result())
                done += 1
                if progress is not None:
                    progress(done, total)
            pending = set()
        finally:
            for f in pending:
                f.cancel()


def _run_on_dask(client, tasks, collect, progress):
    _check_client(client)
    own = isinstance(client, str)
    if own:
        client = _connect(client)
    total, done = len(tasks), 0

    def each(result):
        nonlocal done
        collect(result)
        done += 1
        if progress is not None:
            progress(done, total)

    try:
        if progress is not None:
            progress(0, total)
        _dask_each(client, _tile_counts, tasks, each)
    finally:
        if own:
            client.close()


def store_box_dimension(
    path, which="sliding", connectivity=4, sizes=None, fit_range=None, tol=0.1, min_boxes=32,
    client=None, progress=None, threads=None,
):
    """store_box_dimension(path, which="sliding", connectivity=4, sizes=None, fit_range=None, tol=0.1, min_boxes=32, client=None, progress=None, threads=None) -> BoxDimension

    The box-counting dimension of the border in a finished atlas store:
    :func:`store_box_counts` then
    :func:`stairbounce.dimension.box_dimension_from_counts` (the fit of
    :func:`stairbounce.dimension.box_dimension`, same ``fit_range``, ``tol``,
    ``min_boxes``).  For the perimeter, choose a ``fit_range`` away from
    the pixel scale (boxes of 1-2 px see the raster staircase of the border,
    docs/guide/dimension-study.md).

    The paper's numbers for its Figs. 6 and 7 windows: 1.324 and 1.403
    (Section 3).
    """
    s, counts = store_box_counts(path, which=which, connectivity=connectivity, sizes=sizes,
                                 client=client, progress=progress, threads=threads)
    return box_dimension_from_counts(s, counts, fit_range=fit_range, tol=tol, min_boxes=min_boxes)

