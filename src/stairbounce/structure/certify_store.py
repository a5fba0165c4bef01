"""A certified atlas streamed to a Zarr store tile by tile (issue 44):
:func:`certify_to_zarr`, its memory bounded by a tile, not by the depth.

Every box of :func:`stairbounce.certify`'s quadtree is computed from its integer
position ``(level, i, j)`` in the window's quadtree alone (``certify._run_tile``,
``_kernel._box_edges``).  So the quadtree can be cut: the coarse levels, from
``certify._START_LEVEL`` (3) to ``tile_level - 1``, are computed here in memory (few
boxes); their final boxes are tile 0, and the undecided boxes of level
``tile_level - 1``, split into their level-``tile_level`` children, are cut, in the
order of (j, i), into batches of ``tile_boxes`` boxes: tiles 1, 2, ...  Each tile runs
the quadtree below its boxes down to ``depth`` (``certify._run_tile``), makes its own
table (``_box_table``, ``_atlas_dataset``), and with ``classes`` / ``trap`` the
class-level proofs (``classes.mark_atlas``) and trapping regions
(``trapping.trap_atlas``, re-checked by the independent checker) on its own boxes:
each of those is box by box, so a tile's boxes are those of the whole run.  The
tiles merged (``_store_read.read_store``: sorted by level, then j, then i, the
itineraries and regions renumbered) are :func:`certify`'s table, bit for bit.

Layout of a store::

    atlas.zarr/
      zarr.json              attrs: kind, format, window, depth, max_iter, form, trap,
                             classes, tile_level, tile_boxes, n_tiles
      tiles/done, tiles/crc  done flag and checksum per tile (attrs: format, token)
      summary/               attrs: the tiles' summaries combined (written at the end)
      boxes/000000 ...       one group per tile: its atlas table as CertifiedAtlas.save
                             writes a .zarr (word_code/reason_code and names lists),
                             its summary (proven area bounds by status, reason, word)

Store discipline as :func:`stairbounce.atlas.scan_to_zarr`'s: one writer (the
store's lock, ``_io.store_lock``; every tile, on a Dask worker too, checks that the
lock still holds its run's token and that the store is the one its run opened before
it writes); a tile is written under a temporary name and renamed into place, then its
checksum (CRC-32 seeded with the store's token and the tile's index), and only then its
done flag: an interrupted tile is never counted done.  A re-run with the same
arguments reads every tile marked done, checks it against its checksum (a damaged one
is said, ``RuntimeWarning``, and computed again) and computes only the missing ones;
other arguments on an existing store are refused by name.

Derived numbers without loading the boxes: each tile's proven area bounds (sums of the
boxes' exact areas rounded outward, ``tiling.area_bounds``) by status, undecided
reason and word are summed over the tiles (``math.fsum`` of the tiles' lower bounds
moved one float down, of the upper bounds one up) into the ``summary`` group's
attribute: :class:`CertifiedStore`'s :meth:`~CertifiedStore.fraction` and
:meth:`~CertifiedStore.word_area_bounds`.  They may be a float or two wider than the
in-memory atlas's (summed in another order), and still proven.

Dask and distributed are imported inside the functions that need them.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import uuid
import warnings
from pathlib import Path

import numpy as np

from ..model import check_count
from . import _kernel as K
from . import _store_read as R
from ._store_read import encode as _encode
from ._store_read import factorize as _factorize
from .certificate import STATUSES
from .certify import (_START_LEVEL, UNDECIDED_REASONS, CertifiedAtlas, _atlas_dataset, _box_table, _check_request,
                      _recheck_regions, _run_tile, _SlideCache)

__all__ = ["certify_to_zarr", "CertifiedStore", "TILE_LEVEL", "TILE_BOXES"]

TILE_LEVEL = 7
"""The default tile level, ``min(depth, max(TILE_LEVEL, depth - TILE_SPAN))``: at most
``4^TILE_SPAN`` boxes of the deepest level below a tile's box (about ``3^TILE_SPAN``
on the paper's windows)."""
TILE_SPAN = 6
TILE_BOXES = 256
"""Boxes of the tile level per tile (the last tile holds the rest)."""
CHECKSUM = "crc32 of the tile's arrays and its summary and names lists, seeded with the store's token and tile index"


def _default_tile_level(depth):
    return min(depth, max(TILE_LEVEL, depth - TILE_SPAN))


# --------------------------------------------------------------------------- #
# Tiles                                                                       #
# --------------------------------------------------------------------------- #


def _coarse(win, depth, start, tile_level, max_iter, code, classes):
    """The coarse levels ``start .. tile_level - 1`` in memory: ``(parts, ti, tj)``, the
    final boxes of those levels (``_run_tile``'s tuples) and the positions of the
    level-``tile_level`` boxes below the undecided ones, sorted by (j, i)."""
    n = 1 << start
    gi, gj = np.meshgrid(np.arange(n), np.arange(n))
    ii, jj = gi.ravel().astype(np.int64), gj.ravel().astype(np.int64)
    parts = []
    points = _SlideCache(win, depth, max_iter)
    for level in range(start, tile_level):
        gen = _run_tile(win, depth, level, ii, jj, max_iter, code, parts, points, classes=classes)
        for _, level_done in gen:  # one level: the first kernel call completes it
            if level_done:
                break
        gen.close()
        fi, fj = parts[-1][1], parts[-1][2]
        split = ~np.isin((ii << 28) | jj, (fi << 28) | fj)
        i2, j2 = 2 * ii[split], 2 * jj[split]
        ii = np.concatenate([i2, i2 + 1, i2, i2 + 1])
        jj = np.concatenate([j2, j2, j2 + 1, j2 + 1])
    order = np.argsort((jj << 28) | ii)
    return parts, ii[order], jj[order]


def _table(win, depth, max_iter, code, parts, classes, trap, root=False):
    """A tile's table from its final boxes, with the class-level proofs and trapping
    regions of :func:`certify` (box by box); with ``root`` the column ``focus.ROOT``
    (each row's quadtree box's level, which the trapping pass's pieces inherit)."""
    cols, kept, row = _box_table(parts)
    ds = _atlas_dataset(win, depth, max_iter, code, *cols, kept, row)
    if root:
        from .focus import ROOT

        ds[ROOT] = ds["level"].copy()
    if classes:
        from .classes import mark_atlas

        mark_atlas(ds)
    return _trapped(ds, trap) if trap else ds


def _trapped(ds, trap, tried=None):
    """``ds`` with the trapping pass of ``trap`` (True or "fine"; ``tried``: as
    :func:`trapping.trap_atlas`'s) and its regions re-checked by the independent checker."""
    from .trapping import trap_atlas

    ds = trap_atlas(ds, fine=trap == "fine", tried=tried)
    _recheck_regions(ds)
    return ds


def _empty_parts():
    z = np.zeros(0, np.int64)
    return [(np.zeros(0, np.int8), z, z, np.zeros(0, np.int8), np.zeros(0, np.int8), z, z,
             np.zeros((0, 32), np.int16))]


def _summary(ds):
    """A tile's proven area bounds (rounded outward) by status, undecided reason and
    word, and its counts."""
    from .tiling import area_bounds, _sum_bounds

    st = ds["status"].values
    lo, hi = area_bounds(*(ds[k].values for k in ("e0", "e1", "u0", "u1")))

    def groups(keys, mask):
        out = {}
        sel = np.flatnonzero(mask)
        if sel.size:
            inv, names = _factorize(np.asarray(keys)[sel])
            order = np.argsort(inv, kind="stable")
            cuts = np.searchsorted(inv[order], np.arange(len(names) + 1))
            for k, name in enumerate(names):
                m = sel[order[cuts[k]:cuts[k + 1]]]
                out[name] = list(_sum_bounds(lo[m], hi[m]))
        return out

    return {"boxes": int(st.size), "itinerary": int(ds["itinerary"].size),
            "trap_cells": int(ds["trap_cells"].size) if "trap_cells" in ds.variables else 0,
            "status": {name: list(_sum_bounds(lo[st == k], hi[st == k])) for k, name in enumerate(STATUSES)},
            "reason": groups(ds["reason"].values, st == K.UNDECIDED),
            "word": groups(ds["word"].values, st == K.WORD),
            "trapping": list(_sum_bounds(*(x[(st == K.NO_SLIDING) & (ds["reason"].values == "trapping")]
                                           for x in (lo, hi))))}


def _compute_tile(win, depth, tile_level, gi, gj, max_iter, code, classes, trap, parts=None, focus=None):
    """A tile's table: the quadtree below the level-``tile_level`` boxes ``(gi, gj)``,
    or the given final boxes ``parts`` (tile 0); with ``focus``, to depth ``focus``,
    then refined to ``depth`` where the counts at the scales ``k <= focus`` can change
    (:func:`focus.refine`)."""
    top = depth if focus is None else focus
    if parts is None:
        parts = _quadtree(win, top, tile_level, gi, gj, max_iter, code, classes)
    ds = _table(win, top, max_iter, code, parts or _empty_parts(), classes, trap, root=focus is not None)
    if focus is None:
        return ds
    from .focus import refine

    def rerun(level, ii, jj, d):
        return _table(win, d, max_iter, code, _quadtree(win, d, level, ii, jj, max_iter, code, classes) or
                      _empty_parts(), classes, trap, root=True)

    def deeper(table, tried):
        return _trapped(table, trap, tried)

    return refine(ds, depth, focus, tile_level, rerun, deeper if trap else None, classes)


def _quadtree(win, depth, level, ii, jj, max_iter, code, classes):
    """The final boxes (``_run_tile``'s tuples) of the quadtree to ``depth`` below the
    level-``level`` boxes ``(ii, jj)``."""
    parts = []
    points = _SlideCache(win, depth, max_iter)
    for _ in _run_tile(win, depth, level, ii, jj, max_iter, code, parts, points, classes=classes):
        pass
    return parts


def _write_tile(path, token, owner, k, ds):
    """Write tile ``k`` (renamed into place whole), then its checksum, then its done flag,
    while the store's lock holds ``owner`` and the store is the one of ``token``."""
    import zarr

    from .._io import holds_lock
    from ..atlas import _check_same_store, _checksum

    enc = _encode(ds)
    enc.attrs["summary"] = json.dumps(_summary(ds), sort_keys=True)
    if not holds_lock(path, owner):
        raise RuntimeError(f"the run that handed out this tile no longer holds the lock of {path}")
    _check_same_store(path, token)
    folder = os.path.join(path, R.BOXES)
    final = os.path.join(folder, R.tile_name(k))
    tmp = os.path.join(folder, f".tmp-{R.tile_name(k)}-{uuid.uuid4().hex[:8]}")
    try:
        enc.to_zarr(tmp, mode="w", consolidated=False, zarr_format=3)
        if os.path.lexists(final):  # an earlier, unmarked or damaged write of this tile
            shutil.rmtree(final)
        os.rename(tmp, final)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    arrays, attrs = R.read_tile(path, k)
    record = zarr.open_group(path, mode="r+")[R.RECORD]
    record["crc"][k] = _checksum(R.tile_values(arrays, attrs), R.tile_seed(token, k))
    _check_same_store(path, token)
    record["done"][k] = True  # only now: a tile stopped above is computed again on the next run
    return json.loads(attrs["summary"])


def _tile_task(path, token, owner, k, win, depth, tile_level, gi, gj, max_iter, code, classes, trap, focus,
               numba_threads=None):
    """Compute and write tile ``k`` (here or on a Dask worker): returns ``(k, summary)``."""
    ds = _tile_table(win, depth, tile_level, gi, gj, max_iter, code, classes, trap, focus, numba_threads)
    return k, _write_tile(path, token, owner, k, ds)


def _tile_table(win, depth, tile_level, gi, gj, max_iter, code, classes, trap, focus, numba_threads):
    """Tile ``(gi, gj)``'s table computed with ``numba_threads`` threads (None: numba's)."""
    import numba

    before = numba.get_num_threads()
    if numba_threads is not None:
        numba.set_num_threads(max(1, min(numba_threads, numba.config.NUMBA_NUM_THREADS)))
    try:
        return _compute_tile(win, depth, tile_level, gi, gj, max_iter, code, classes, trap, focus=focus)
    finally:
        numba.set_num_threads(before)


def _local_tiles(args, each):
    """The tiles ``args`` (``_tile_task``'s arguments) here, each computed while the one
    before is written by a writer thread: the kernels use every core, the writing
    (coding, compressing, the read back and checksum: about a fifth of a tile's time at
    depth 14, on one core) then overlaps the next tile's kernels.  Two tiles are held at
    a time.  The tiles are the same (computed as before, one after another; only their
    writing moved), and written, marked done and counted (``each``, in this thread) in
    their order.  On an exception (Ctrl-C) the write under way is finished (a tile
    takes well under a second to write) before it is raised, while the store is still
    locked; the tiles not written are computed again on the next run."""
    from concurrent.futures import ThreadPoolExecutor

    writer = ThreadPoolExecutor(1, thread_name_prefix="stairbounce-tile-writer")
    pending = None
    try:
        for path, token, owner, k, *rest in args:
            ds = _tile_table(*rest)
            if pending is not None:
                each(pending.result())
            pending = writer.submit(_write_tile, path, token, owner, k, ds)
            del ds
        if pending is not None:
            each(pending.result())
            pending = None
    finally:
        writer.shutdown(wait=True, cancel_futures=True)


# --------------------------------------------------------------------------- #
# The store                                                                   #
# --------------------------------------------------------------------------- #


def _store_attrs(win, depth, max_iter, form, trap, classes, tile_level, tile_boxes, n_tiles, positions, focus=None):
    from .._version import __version__

    return {"kind": R.STORE_KIND, "format": R.STORE_FORMAT, "e_range": [float(win[0]), float(win[1])],
            "u_range": [float(win[2]), float(win[3])], "depth": int(depth), "max_iter": int(max_iter),
            "form": form, "trap": trap, "classes": bool(classes), "tile_level": int(tile_level),
            "tile_boxes": int(tile_boxes), "n_tiles": int(n_tiles), "tiles_crc": positions,
            "impact_cap": int(K.IMPACT_CAP), "focus": None if focus is None else int(focus),
            "stairbounce_version": __version__}


# what an existing store must agree on (the version may differ: the same boxes by design)
_SAME = ("format", "e_range", "u_range", "depth", "max_iter", "form", "trap", "classes", "tile_level",
         "tile_boxes", "n_tiles", "tiles_crc", "impact_cap", "focus")


def _create(path, attrs, n_tiles):
    import zarr

    from .._io import atomic_path

    try:
        with atomic_path(path) as tmp:
            root = zarr.open_group(str(tmp), mode="w", zarr_format=3)
            root.attrs.update(attrs)
            record = root.create_group(R.RECORD)
            record.attrs.update(format=R.STORE_FORMAT, token=uuid.uuid4().hex, checksum=CHECKSUM)
            record.zeros(name="done", shape=(n_tiles,), chunks=(1,), dtype=bool)
            record.full(name="crc", shape=(n_tiles,), chunks=(1,), dtype=np.int64, fill_value=-1)
            root.create_group(R.BOXES)
    except PermissionError as exc:
        raise ValueError(f"cannot write {path}: {exc.strerror.lower()} ({path.parent})") from None


def _check_existing(path, attrs):
    """Refuse an existing path that is not a store of this run, naming what differs."""
    if not R.is_store(path):
        raise ValueError(f"{path} exists and is not a certified atlas store: choose another path or remove it")
    try:
        stored, record, _, _ = R.store_state(path)
    except Exception:  # noqa: BLE001
        raise ValueError(f"{path} is a damaged certified atlas store (its tile record cannot be read): "
                         "write to a new path") from None
    differ = [f"{k}: store {stored.get(k)!r}, asked {attrs[k]!r}" for k in _SAME
              if k != "tiles_crc" and stored.get(k) != attrs[k]]
    if not differ and stored.get("tiles_crc") != attrs["tiles_crc"]:
        differ.append("the tiles' boxes differ")
    if differ:
        raise ValueError(f"{path} holds a different certified atlas ({'; '.join(differ)}): resume it with its "
                         "own arguments, or write to a new path")


def _clean_temporaries(path):
    folder = Path(path) / R.BOXES
    for p in folder.glob(".tmp-*"):
        shutil.rmtree(p, ignore_errors=True)


def certify_to_zarr(path, e=(0.155, 0.2138), u=(0.6, 0.658), depth=10, max_iter=1000, *, form="corners",
                    trap=False, classes=False, client=None, progress=None, phase=None, tile_level=None,
                    tile_boxes=TILE_BOXES, numba_threads=None, verify=True, focus=None) -> "CertifiedStore":
    """certify_to_zarr(path, e=(lo, hi), u=(lo, hi), depth=10, max_iter=1000, *, form="corners", trap=False, classes=False, client=None, progress=None, phase=None, tile_level=None, tile_boxes=256, numba_threads=None, verify=True, focus=None) -> CertifiedStore

    :func:`stairbounce.certify` streamed to a Zarr store tile by tile: the memory is
    bounded by a tile, not by the depth, and the boxes are the same, bit for bit.

    The coarse levels (3 .. ``tile_level - 1``) are computed in memory; the
    level-``tile_level`` boxes below their undecided boxes are cut into tiles of
    ``tile_boxes`` boxes, each computed down to ``depth`` and written as soon as it is
    done (the module's docstring gives the layout); locally, each tile is written by a
    writer thread while the next one is computed.  ``CertifiedAtlas.load(path)`` reads the
    store as the whole atlas (all its boxes in memory); ``sb.verify(path)`` and
    ``stairbounce certify --verify path`` check it tile by tile with the memory of a tile
    (the same verdict as on the whole atlas); the proven shares and word areas are read
    without the boxes from the returned :class:`CertifiedStore`.

    Running the same call again resumes: the tiles marked done are checked against
    their checksums and only the missing (or damaged) ones are computed.  An existing
    store made with other arguments is refused, naming what differs; a store another
    run is writing (its lock held) is refused, naming the holder.

    Parameters
    ----------
    path : str or path-like ending in ``.zarr``
        The store; its folder must exist and be writable (with a Dask cluster, seen by
        every worker at the same path).
    e, u, depth, max_iter, form, trap, classes :
        As in :func:`stairbounce.certify`.
    client : None, ``dask.distributed.Client`` or str, default None
        None: the tiles one after another in this process (each with numba's threads,
        written while the next is computed).
        A client or a scheduler address: every tile is a Dask task whose worker
        computes and writes it (one numba thread, as ``scan_to_zarr``).
    progress : callable ``progress(done, total)``, optional
        Complete tiles (tile 0, the coarse levels, included): once before the tiles
        (counting those found complete), then after each.  An exception raised there
        (Ctrl-C too) stops the run between tiles; the complete tiles stay complete.
    phase : callable ``phase(name)``, optional
        Called with ``"levels 3-6"`` (the coarse levels), ``"tiles of levels 7-14"``.
    tile_level : int in [min(3, depth), depth] or None
        The level cut into tiles; None: ``min(depth, max(7, depth - 6))``.
    tile_boxes : int >= 1, default 256
        Boxes of the tile level per tile.
    numba_threads : int >= 1 or None
        Numba threads per tile: None, all of them locally and one on a Dask worker.
    verify : bool, default True
        Check the tiles marked done against their checksums before resuming.
    focus : int in [tile_level, depth] or None, default None
        For the perimeter's proven box counts at the scales ``k <= focus``: each tile
        is certified to depth ``focus`` as without it, then deepened one level a round
        to ``depth`` only where those counts can still change (an undecided box with a
        cell of scale ``focus`` not yet holding proven points of both classes;
        :mod:`stairbounce.structure.focus`).  The boxes are certified boxes that tile
        the window, so ``sb.verify`` checks them as any store's; the counts are taken
        at ``k <= focus`` (the store's attribute ``focus``).  The tile level's default
        is then that of depth ``focus``.  None: every undecided box to ``depth``.

    Returns
    -------
    CertifiedStore

    Raises
    ------
    ValueError
        A bad parameter (naming it), a path not ending in ``.zarr`` or whose folder is
        missing or read-only, an existing store of other arguments, a store locked by
        another run, an unreachable scheduler.
    """
    from .._io import lock_store_folder
    from ..atlas import _check_client, _check_path, _connected_and_locked, _dask_each, _unwritable_reason

    path = _check_path(path)
    e_lo, e_hi, u_lo, u_hi, depth, max_iter, code = _check_request(e, u, depth, max_iter, form)
    from .trapping import check_trap

    trap = check_trap(trap)
    for name, flag in (("classes", classes), ("verify", verify)):
        if not isinstance(flag, (bool, np.bool_)):
            raise ValueError(f"{name} must be True or False, got {flag!r}")
    if progress is not None and not callable(progress):
        raise ValueError(f"progress must be None or a callable progress(done, total), got {progress!r}")
    if phase is not None and not callable(phase):
        raise ValueError(f"phase must be None or a callable phase(name), got {phase!r}")
    start = min(_START_LEVEL, depth)
    if focus is not None:
        focus = check_count("focus", focus, start, depth)
    top = depth if focus is None else focus  # the plain quadtree's depth (round 0 with focus)
    tile_level = _default_tile_level(top) if tile_level is None else check_count("tile_level", tile_level,
                                                                                   start, top)
    tile_boxes = check_count("tile_boxes", tile_boxes, 1)
    if numba_threads is not None:
        numba_threads = check_count("numba_threads", numba_threads, 1)
    _check_client(client)
    reason = _unwritable_reason(path.parent)
    if reason is not None:
        raise ValueError(f"cannot write {path}: folder {path.parent} is not writable ({reason})")
    win = np.array([e_lo, e_hi, u_lo, u_hi])

    if phase is not None:
        phase(f"levels {start}-{tile_level - 1}" if tile_level > start else f"level {start}")
    parts, ti, tj = _coarse(win, top, start, tile_level, max_iter, code, classes)
    cuts = list(range(0, ti.size, tile_boxes))
    n_tiles = 1 + len(cuts)
    positions = _positions_crc(ti, tj)
    attrs = _store_attrs(win, depth, max_iter, form, trap, classes, tile_level, tile_boxes, n_tiles, positions,
                         focus)

    with _connected_and_locked(path, client) as (client, owner):
        if path.exists():
            _check_existing(path, attrs)
            _clean_temporaries(path)
        else:
            _create(path, attrs, n_tiles)
            lock_store_folder(path, owner)
        stored, record, done, crc = R.store_state(path)
        token = record["token"]
        done = done.astype(bool)
        if verify and done.any():
            damaged = [k for k in np.flatnonzero(done) if R.check_tile(path, k, token, crc[k]) is None]
            if damaged:
                warnings.warn(f"{len(damaged)} complete tile(s) of {path} no longer match their checksum "
                              f"(a chunk deleted or damaged), e.g. tile {damaged[0]}: computed again",
                              RuntimeWarning, stacklevel=2)
                _unmark(path, damaged)
                done[damaged] = False
        n_done = int(done.sum())
        if progress is not None:
            progress(n_done, n_tiles)

        def each(result):
            nonlocal n_done
            n_done += 1
            if progress is not None:
                progress(n_done, n_tiles)

        if not done[0]:
            ds = _compute_tile(win, depth, tile_level, None, None, max_iter, code, classes, trap, parts, focus)
            each(_write_tile(str(path), token, owner, 0, ds))
            del ds
        del parts
        todo = [k for k in range(1, n_tiles) if not done[k]]
        if todo and phase is not None:
            phase(f"tiles of levels {tile_level}-{depth}")
        args = [(str(path), token, owner, k, win, depth, tile_level, ti[cuts[k - 1]:cuts[k - 1] + tile_boxes],
                 tj[cuts[k - 1]:cuts[k - 1] + tile_boxes], max_iter, code, bool(classes), trap, focus,
                 numba_threads if client is None else (numba_threads or 1))
                for k in todo]
        if client is None:
            _local_tiles(args, each)
        else:
            _dask_each(client, _tile_task, args, each, wait_cancelled=True)
        from ..atlas import _check_same_store

        _check_same_store(str(path), token)
        _write_summary(path)
    return CertifiedStore(path)


def _positions_crc(ti, tj):
    """A checksum of the tile level's boxes (the tiles' cut): a store resumed with
    other tiles is refused."""
    import zlib

    return int(zlib.crc32(np.ascontiguousarray(np.stack([ti, tj]).astype(np.int64)).tobytes()))


def _unmark(path, tiles):
    import zarr

    record = zarr.open_group(str(path), mode="r+")[R.RECORD]
    for k in tiles:
        record["done"][int(k)] = False
        record["crc"][int(k)] = -1


def _combine(pairs):
    """Bounds on a sum of exact areas from the tiles' bounds: lower parts summed and
    moved one float down, upper parts one up."""
    if not pairs or all(p[1] == 0.0 for p in pairs):  # nothing, or only zeros: exactly 0
        return [0.0, 0.0]
    lo = max(float(np.nextafter(math.fsum(p[0] for p in pairs), -np.inf)), 0.0)
    hi = float(np.nextafter(math.fsum(p[1] for p in pairs), np.inf))
    return [lo, hi]


def _write_summary(path):
    """The tiles' summaries combined into the ``summary`` group's attribute (all tiles done)."""
    import zarr

    stored, record, done, _ = R.store_state(path)
    if not done.all():  # pragma: no cover - the run above completes every tile
        return
    summaries = []
    for k in range(done.size):
        g = zarr.open_group(os.path.join(str(path), R.BOXES, R.tile_name(k)), mode="r")
        summaries.append(json.loads(g.attrs["summary"]))
    total = {k: sum(s[k] for s in summaries) for k in ("boxes", "itinerary", "trap_cells")}
    total.update({
             "trapping": _combine([s["trapping"] for s in summaries])})
    for key in ("status", "reason", "word"):
        names = sorted({n for s in summaries for n in s[key]})
        total[key] = {n: _combine([s[key][n] for s in summaries if n in s[key]]) for n in names}
    # a group of its own: the root's metadata stays small (thousands of words at depth 15)
    group = zarr.open_group(os.path.join(str(path), R.SUMMARY), mode="a", zarr_format=3)
    group.attrs["summary"] = json.dumps(total, sort_keys=True)


class CertifiedStore:
    """A streamed certified atlas (:func:`certify_to_zarr`): its proven numbers read
    from the store's summary without its boxes, and the whole atlas by :meth:`load`.

    The shares are of the window: the store's boxes tile it by construction (the
    quadtree's), which ``sb.verify(path)`` checks on the boxes themselves.
    """

    def __init__(self, path):
        self.path = Path(path)
        if not R.is_store(self.path):
            raise ValueError(f"{path} is not a certified atlas store")
        self.attrs, _, self._done, _ = R.store_state(self.path)
        self.summary = R.read_summary(self.path)
        if self.summary is None or not self._done.all():
            raise ValueError(f"{path} is incomplete ({int(self._done.sum())} of {self._done.size} tiles "
                             "computed): run certify_to_zarr again with the same arguments to finish it")

    @property
    def window(self):
        return tuple(self.attrs["e_range"]), tuple(self.attrs["u_range"])

    @property
    def depth(self) -> int:
        return int(self.attrs["depth"])

    @property
    def max_iter(self) -> int:
        return int(self.attrs["max_iter"])

    @property
    def boxes(self) -> int:
        return int(self.summary["boxes"])

    def load(self) -> CertifiedAtlas:
        """load() -> CertifiedAtlas: every box in memory (``CertifiedAtlas.load``)."""
        return CertifiedAtlas.load(self.path)

    def _window_area(self):
        from .tiling import area_bounds

        (a, b), (c, d) = self.window
        lo, hi = area_bounds(np.array([a]), np.array([b]), np.array([c]), np.array([d]))
        return float(lo[0]), float(hi[0])

    def _ratio(self, lo, hi):
        clo, chi = self._window_area()
        return (max(float(np.nextafter(lo / chi, -np.inf)), 0.0), min(float(np.nextafter(hi / clo, np.inf)), 1.0))

    def area(self, by="status"):
        """area(by="status") -> dict: ``{name: (lower, upper)}`` proven bounds on the area
        of each status, undecided reason (``by="reason"``) or proven word (``by="word"``)."""
        if by not in ("status", "reason", "word"):
            raise ValueError(f"by must be one of status, reason, word, got {by!r}")
        got = {k: tuple(v) for k, v in self.summary[by].items()}
        if by == "status":
            return {name: got.get(name, (0.0, 0.0)) for name in STATUSES}
        if by == "reason":
            return {r: got.get(r, (0.0, 0.0)) for r in UNDECIDED_REASONS}
        return dict(sorted(got.items(), key=lambda p: (-p[1][0], p[0])))

    def fraction(self, by="status", bound="lower"):
        """fraction(by="status", bound="lower") -> dict: proven bounds on the window's
        share of each status, reason or word, as :meth:`CertifiedAtlas.fraction`
        (``bound``: ``"lower"``, ``"upper"`` or ``"both"``)."""
        if bound not in ("lower", "upper", "both"):
            raise ValueError(f"bound must be one of lower, upper, both, got {bound!r}")
        pairs = {k: self._ratio(*v) for k, v in self.area(by).items()}
        if bound == "both":
            return pairs
        return {k: v[0 if bound == "lower" else 1] for k, v in pairs.items()}

    def word_area_bounds(self, word):
        """word_area_bounds(word) -> (lower, upper): proven bounds on the area of the
        window's points with the periodic sliding solution ``word``, as
        :meth:`CertifiedAtlas.word_area_bounds` (lower: its proven boxes; upper: the
        window less every box proven to be something else)."""
        from ..symbolic import Word, parse_word

        w = word if isinstance(word, Word) else parse_word(word)
        text = w.format(ascii=True)
        st = self.area("status")
        lo, hi = tuple(self.summary["word"].get(text, (0.0, 0.0)))
        down = lambda x: float(np.nextafter(x, -np.inf))  # noqa: E731
        other = down(max(down(st["word"][0] - hi), 0.0) + st["no_sliding"][0])
        if w.period <= self.max_iter:
            other = down(other + st["no_slide_within"][0])
        return lo, float(np.nextafter(self._window_area()[1] - other, np.inf))

    def border_box_counts(self, border="sliding", progress=None, *, witnesses=True):
        """border_box_counts(border="sliding", progress=None, *, witnesses=True) -> pandas.DataFrame: the
        proven box counts of the sliding region's border (the paper's perimeter), as
        :meth:`CertifiedAtlas.border_box_counts` gives them on the loaded atlas, integer
        for integer, taken tile by tile (:mod:`stairbounce.structure.border_counts`):
        the memory of a tile and one bit per cell of each scale, not the whole atlas.

        ``border="words"`` (every border between words) needs the words of every box
        at once: load the atlas for it (ValueError here).  The counts are proven when
        the boxes are; :meth:`perimeter_bracket` runs the checker on the store.
        ``witnesses``: the proven points inside undecided boxes in the lower counts, as
        :meth:`CertifiedAtlas.border_box_counts` (found tile by tile, the same counts)."""
        from .border_counts import store_rows
        from .certify import _counts_frame

        if border != "sliding":
            raise ValueError(f"border must be sliding for a store (the words' borders need every box at once: "
                             f"CertifiedAtlas.load(path).border_box_counts(border={border!r})), got {border!r}")
        if witnesses not in (True, False):
            raise ValueError(f"witnesses must be True or False, got {witnesses!r}")
        rows, _, (found, tried) = store_rows(self.path, progress, witnesses)
        df = _counts_frame(rows, "the window", "sliding")
        df.attrs["witnesses"], df.attrs["witnesses_tried"] = int(found), int(tried)
        return df

    def perimeter_bracket(self, k1=None, k2=None, *, verify=True, progress=None):
        """perimeter_bracket(k1=None, k2=None, *, verify=True, progress=None) -> dict: the
        proven box counts of the paper's perimeter and the slope brackets, as
        :meth:`CertifiedAtlas.perimeter_bracket` gives them on the loaded atlas (the
        same dict), with the store's memory: the counts tile by tile
        (:meth:`border_box_counts`), and with ``verify`` the independent checker on the
        store tile by tile (``sb.verify(path)``); ``basis`` is ``"proven"`` only when
        it passes.  ``progress(done, total)``: after each tile counted."""
        from .certify import _scales, counted_depth, perimeter_result

        if verify not in (True, False):
            raise ValueError(f"verify must be True or False, got {verify!r}")
        k1, k2 = _scales(k1, k2, counted_depth(self.attrs))
        verdict = None
        if verify:
            from .verdict import verify as check

            verdict = check(self.path)
        df = self.border_box_counts("sliding", progress)
        return perimeter_result(df, k1, k2, self.depth, self.max_iter, verdict, self.attrs.get("focus"))

    def __repr__(self):
        f = self.fraction()
        parts = ", ".join(f"{k} {100 * v:.1f}%" for k, v in f.items())
        return f"CertifiedStore({self.path}, {self.boxes} boxes, depth {self.depth}: {parts})"
