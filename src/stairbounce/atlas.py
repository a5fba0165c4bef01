"""Tiled, resumable scans of the (e, u) plane, written to Zarr, locally or on Dask.

A scan too large for one sitting (a deep zoom, a 32768 x 32768 atlas at a high
``max_iter``) is cut into square tiles.  Every tile is computed with
:func:`stairbounce.plane.scan_coords` on its slice of the
:func:`stairbounce.plane.pixel_centres` grid, so the assembled store is the same,
bit for bit, as :func:`stairbounce.plane.scan` on the whole window, and it has
the same variables, coordinates and attributes.

Layout of a store (Zarr, one chunk per tile and variable)::

    atlas.zarr/
      status, word_length, jumps, period, impacts   (u, e), chunks tile x tile
      e, u                                           pixel centres
      tiles/done                                     bool per tile, chunks 1 x 1
      tiles (group attributes)                       tile size, format

The root group holds what :func:`stairbounce.plane.save` writes, chunked by
tile (the tile record lives in a sub-group that xarray does not read), so
:func:`stairbounce.plane.load` and ``xarray.open_zarr`` read an atlas like any
saved scan.

Resuming: the store is created up front (atomically: it exists complete with
its coordinates and attributes, or not at all), then each tile writes its data,
then the checksum of that data (``tiles/crc``), and only afterwards sets its
``tiles/done`` flag.  Chunk files are replaced atomically by Zarr's local
store, so an interrupted tile is either absent or whole per variable, and in
any case unmarked: a re-run computes it again.  A re-run also reads every tile
marked done and compares it with its checksum: a deleted, truncated or garbled
chunk is found, said (a ``RuntimeWarning``) and the tile computed again.  A
chunk never written reads as :data:`stairbounce.plane.FILL_VALUES` (status
255, counts -1), never as a result.  The coordinates (outside the tiles'
checksums) are compared with the pixel centres of the window and rewritten
when wrong; a done flag or checksum that cannot be read counts as a damaged
tile.  Where no lock can be taken (a read-only file system) a complete,
intact store opens read-only.

One writer at a time: a scan holds the store's lock
(:func:`stairbounce._io.store_lock`, a lock file beside the store with the
owner's host, pid and a token) from before it creates the store until it
returns; a second scan on the same path is refused with the holder's name.
Every tile, wherever it runs, checks that the lock still holds the token of
the scan that handed it out before it writes, so only the client holding the
lock ever writes into the store.  The lock is that of the store a path leads
to (symlinks resolved) and of its folder by device and inode (a bind mount
of it under another name), and every tile also checks, before and after it
writes, that the store at the path is still the one its scan opened (its
token): a store replaced under a running scan stops it with an error.

Dask and Numba threads: each tile runs the parallel numba kernel of
:mod:`stairbounce.plane`, which releases the GIL.  On a Dask worker a tile uses
one numba thread and the worker's Dask threads run tiles side by side, so a
worker never keeps more cores busy than it has threads, whether it is started
as ``--nworkers 1 --nthreads 16`` or ``--nworkers 16 --nthreads 1``, and many
small single-threaded tiles balance the very uneven cost of the plane better
than one tile split over all cores.  Without Dask the calling process does
the same with a pool of as many threads as numba has.  numba's ``workqueue``
layer cannot take launches from two threads at once: under it (and until the
layer is known) tiles of one process launch one at a time.

Dask and distributed are imported inside the functions that need them: they
are the optional extra ``stairbounce[dask]``.  Nothing here imports
matplotlib, Typer or the web stack.
"""

from __future__ import annotations

import contextlib
import math
import os
import threading
import time
import uuid
import warnings
import zlib
from pathlib import Path

import numpy as np

from . import _validate as _v
from ._io import lock_store_folder, store_lock
from .model import check_count
from .units import Staircase, staircase_of, with_speed

__all__ = ["scan_to_zarr", "tile_slices", "tiles_done", "downsample", "DamagedStoreError"]

# version 2: fill values that are no result, a checksum per tile, a lock
FORMAT = "stairbounce-atlas-2"
TILES_GROUP = "tiles"

# Kernel launches one at a time per process where the threading layer needs it.
_KERNEL_LOCK = threading.Lock()


# --------------------------------------------------------------------------- #
# Tiles                                                                       #
# --------------------------------------------------------------------------- #


def tile_slices(n, tile):
    """tile_slices(n, tile) -> list of slice

    The slices ``[0, tile), [tile, 2 tile), ...`` covering ``range(n)``; the
    last one is shorter when ``tile`` does not divide ``n``.
    """
    n = check_count("n", n, 1)
    tile = check_count("tile", tile, 1)
    # about 100 bytes a slice object and its list entry (report D12: 10**12 hung)
    _v.check_memory(f"n = {n} in tiles of {tile}", 100 * (-(-n // tile)))
    return [slice(a, min(a + tile, n)) for a in range(0, n, tile)]


def _tile_record(path):
    import zarr

    return zarr.open_group(str(path), mode="r")[TILES_GROUP]


def _root_attrs(path):
    import zarr

    return dict(zarr.open_group(str(path), mode="r").attrs)


class DamagedStoreError(ValueError):
    """A chunk of a store's tile record or coordinates cannot be read or does
    not match the store's window: running its scan again repairs it."""


def tiles_done(path):
    """tiles_done(path) -> np.ndarray of bool, shape (tiles along u, tiles along e)

    Which tiles of the store at ``path`` are complete.  A done flag that
    cannot be read (a garbled chunk) raises :class:`DamagedStoreError` (a
    ``ValueError``); running the store's scan again repairs it.
    """
    try:
        flags = _tile_record(path)["done"]
    except (KeyError, FileNotFoundError):
        raise ValueError(f"{path} is not a tiled scan store (no tile record)") from None
    done, bad = _read_record(flags, False)
    if bad:
        raise DamagedStoreError(
            f"the tile record of {path} is damaged (the done flag of tile {bad[0]} cannot be read): "
            "run its scan again to repair it"
        )
    return done.astype(bool)


def _read_record(arr, unreadable):
    """A tile record array (chunks 1 x 1) and the tiles whose chunk cannot be
    read (report N5: a garbled chunk was a Zstd traceback): read whole when it
    can be, else chunk by chunk, an unreadable chunk reading as ``unreadable``."""
    try:
        return np.asarray(arr[...]), []
    except Exception:  # noqa: BLE001 - any decoding error of a chunk is damage
        pass
    out = np.full(arr.shape, unreadable, dtype=arr.dtype)
    bad = []
    for i, j in np.ndindex(*arr.shape):
        try:
            out[i, j] = arr[i, j]
        except Exception:  # noqa: BLE001
            bad.append((i, j))
    return out, bad


def _store_token(path):
    """The token of the store now at ``path`` (None: not a tile store): read
    from its tile record's metadata file, a few hundred bytes."""
    from ._io import _json

    record = _json(os.path.join(path, TILES_GROUP, "zarr.json"))
    try:
        return record["attributes"]["token"]
    except (TypeError, KeyError):
        return None


def _check_same_store(path, token):
    """Refuse to write into a store other than the one the scan opened (report
    N3: a store replaced under a running scan received its tiles)."""
    from ._io import StoreReplacedError

    if _store_token(path) != token:
        raise StoreReplacedError(
            f"the store {path} was replaced while the scan was running: its tiles were not "
            "written into the new one; run the scan again (to a new path, or with the same "
            "one to resume the new store if it is this scan's)"
        )


def _run_tile(path, token, owner, i, j, su, se, e_values, u_values, max_iter, y0, v0, prune, numba_threads,
              identity=None):
    """Compute tile (i, j) and write it into its region of the store, then its
    checksum (bound to the tile and the store by ``identity``,
    :func:`_identity`; None: a store of before issue 38), then mark it done.

    Runs in the calling process (local scans) or on a Dask worker; writes only
    while the store's lock holds ``owner``, the token of the scan that handed
    the tile out.
    """
    from ._io import holds_lock

    import numba

    from .plane import scan_coords

    # one thread by default: tiles run side by side (module docstring)
    threads = max(1, min(numba_threads or 1, numba.config.NUMBA_NUM_THREADS))
    with _KERNEL_LOCK if _serial_launches() else contextlib.nullcontext():
        before = numba.get_num_threads()
        numba.set_num_threads(threads)  # numba's count is per calling thread
        try:
            ds = scan_coords(e_values, u_values, max_iter, y0, v0, prune=prune)
        finally:
            numba.set_num_threads(before)
    if not holds_lock(path, owner):
        raise RuntimeError(f"the scan that handed out this tile no longer holds the lock of {path}")
    _check_same_store(path, token)
    arrays, crc, done = _open_store(path, token)
    values = {name: var.values for name, var in ds.data_vars.items()}
    for name, a in values.items():
        arrays[name][su, se] = a
    crc[i, j] = _checksum(values, _tile_seed(identity, i, j))
    # the store replaced while the data was written: no done flag into the new one
    _check_same_store(path, token)
    # only now: a tile killed above is recomputed on the next run
    done[i, j] = True
    return i, j


CHECKSUM = "crc32, seeded with the tile's index and the store's identity"
"""The ``checksum`` attribute of a tile record whose checksums are bound to
their tile and store (issue 38, R3).  A store without it (written before)
has checksums of the bytes only: resume verifies it so, then rewrites the
checksums of its intact tiles bound and sets the attribute."""

# the attributes of the store that its tiles' checksums are bound to, with its token
_IDENTITY_KEYS = ("e_min", "e_max", "n_e", "u_min", "u_max", "n_u", "max_iter", "y0", "v0")


def _identity(root_attrs, record_attrs):
    """The store's identity as its checksums are seeded with it: its window,
    ``max_iter``, start and token (drawn when it was made); None for a store
    whose checksums are of the bytes only (no :data:`CHECKSUM` attribute)."""
    if record_attrs.get("checksum") != CHECKSUM:
        return None
    parts = [f"{k}={root_attrs.get(k)!r}" for k in _IDENTITY_KEYS]
    return ";".join(parts + [f"token={record_attrs.get('token')}"])


def _tile_seed(identity, i, j):
    """What tile (i, j)'s checksum is seeded with (None: unseeded)."""
    return None if identity is None else f"{identity};tile={int(i)},{int(j)}"


def _checksum(values, seed=None):
    """CRC-32 of a tile's variables (by name, C order), starting from the
    CRC of ``seed`` (:func:`_tile_seed`: the tile's index and the store's
    identity, so that a tile's data and checksum copied to another tile or
    store do not match there): checked on resume."""
    c = 0 if seed is None else zlib.crc32(seed.encode())
    for name in sorted(values):
        a = np.ascontiguousarray(values[name])
        c = zlib.crc32(f"{name}{a.dtype.str}{a.shape}".encode(), c)
        c = zlib.crc32(a.tobytes(), c)
    return c


# Opened arrays per store, kept by each process for the tiles that follow (opening
# costs more than writing a small tile).  The token, drawn when the store is
# created, tells a store apart from another one later made at the same path.
_OPEN_STORES: dict[tuple[str, str], tuple] = {}


def _open_store(path, token):
    key = (path, token)
    hit = _OPEN_STORES.get(key)
    if hit is None:
        import zarr

        root = zarr.open_group(path, mode="r+")
        record = root[TILES_GROUP]
        if record.attrs.get("token") != token:
            _check_same_store(path, token)
        hit = ({name: arr for name, arr in root.arrays() if arr.ndim == 2}, record["crc"], record["done"])
        if len(_OPEN_STORES) > 16:
            _OPEN_STORES.clear()
        _OPEN_STORES[key] = hit
    return hit


def _serial_launches():
    """Whether kernel launches must take turns: numba's workqueue layer is not
    thread-safe, and the layer is only known after the first launch."""
    import numba

    try:
        return numba.threading_layer() == "workqueue"
    except ValueError:
        return True


# --------------------------------------------------------------------------- #
# The store                                                                   #
# --------------------------------------------------------------------------- #


def _check_path(path):
    given = Path(os.path.abspath(os.fspath(path)))
    if given.suffix != ".zarr":
        raise ValueError(f"path must end in .zarr, got {str(given)!r}")
    # the store the name leads to: one lock and one store whatever the name (report N3)
    path = Path(os.path.realpath(given))
    if not path.parent.is_dir():
        raise ValueError(f"cannot write {path}: folder {path.parent} does not exist")
    return path


def _writable(folder):
    """Whether a file can be created in ``folder`` (tried: root ignores mode bits)."""
    return _unwritable_reason(folder) is None


def _unwritable_reason(folder):
    from ._io import _probe_writable

    return _probe_writable(folder)


def _template(probe, es, us, tile):
    """The dataset of the store, lazy zeros, with the attributes of ``probe``."""
    import dask.array as da
    import xarray as xr

    n_e, n_u = es.size, us.size
    chunks = (min(tile, n_u), min(tile, n_e))
    data_vars = {}
    for name, var in probe.data_vars.items():
        if var.dims != ("u", "e"):  # pragma: no cover - a change in scan's layout
            raise RuntimeError(f"scan variable {name} has dims {var.dims}, expected ('u', 'e')")
        data_vars[name] = (var.dims, da.zeros((n_u, n_e), dtype=var.dtype, chunks=chunks), var.attrs)
    coords = {
        "e": ("e", es, probe["e"].attrs),
        "u": ("u", us, probe["u"].attrs),
    }
    attrs = dict(probe.attrs)
    attrs.update(n_e=n_e, n_u=n_u)
    ds = with_speed(xr.Dataset(data_vars, coords=coords, attrs=attrs), Staircase.from_attrs(attrs))
    from .plane import FILL_VALUES

    encoding = {name: {"chunks": chunks} for name in data_vars}
    for name in encoding:
        if name in FILL_VALUES:
            # a chunk never written (or deleted) reads as no valid result
            encoding[name]["fill_value"] = FILL_VALUES[name]
    return ds, encoding


def _create(path, template, encoding, shape_tiles, tile):
    import zarr

    from ._io import atomic_path

    try:
        with atomic_path(path) as tmp:
            template.to_zarr(tmp, mode="w", compute=False, encoding=encoding, consolidated=False)
            record = zarr.open_group(str(tmp), mode="r+").create_group(TILES_GROUP)
            record.attrs.update(format=FORMAT, tile=tile, token=uuid.uuid4().hex, checksum=CHECKSUM)
            record.zeros(name="done", shape=shape_tiles, chunks=(1, 1), dtype=bool)
            record.full(name="crc", shape=shape_tiles, chunks=(1, 1), dtype=np.int64, fill_value=-1)
    except PermissionError as exc:
        raise ValueError(f"cannot write {path}: {exc.strerror.lower()} ({path.parent})") from None


def _verify(path, rows, cols, done, repair=True):
    """Tiles marked done whose data no longer matches their checksum (a chunk
    deleted, truncated or garbled, or copied with its checksum from another
    tile or store): unmarked (with ``repair``), so that they are computed
    again.  Returns their indices.  A store whose checksums are of the bytes
    only (before issue 38) is verified so; with ``repair`` the checksums of
    its intact tiles are then rewritten bound (:data:`CHECKSUM`)."""
    import zarr

    root = zarr.open_group(str(path), mode="r+" if repair else "r")
    record = root[TILES_GROUP]
    arrays = {name: arr for name, arr in root.arrays() if arr.ndim == 2}
    crc, _ = _read_record(record["crc"], -2)  # -2: no checksum, an unreadable chunk is damage
    identity = _identity(dict(root.attrs), dict(record.attrs))
    upgrade = repair and identity is None
    if upgrade:
        bound = _identity(dict(root.attrs), {**record.attrs, "checksum": CHECKSUM})
        rewrite = {}
    damaged = []
    for i, j in zip(*np.nonzero(done)):
        try:
            values = {name: arr[rows[i], cols[j]] for name, arr in arrays.items()}
            ok = _checksum(values, _tile_seed(identity, i, j)) == int(crc[i, j])
        except Exception:  # noqa: BLE001 - any read error of a chunk is damage
            ok = False
        if not ok:
            damaged.append((int(i), int(j)))
        elif upgrade:
            rewrite[i, j] = _checksum(values, _tile_seed(bound, i, j))
    if repair:
        for i, j in damaged:
            record["done"][i, j] = False
            record["crc"][i, j] = -1
    if upgrade:  # the checksums first: interrupted here, the old ones fail and their tiles are recomputed
        for (i, j), c in rewrite.items():
            record["crc"][i, j] = c
        record.attrs["checksum"] = CHECKSUM
    return damaged


def _check_existing(path, attrs, tile, variables=()):
    """Refuse an existing store made for another scan, or one whose arrays
    lost their metadata or are missing (report round 3, R9); never mix two scans."""
    import zarr

    from ._io import check_store_metadata

    check_store_metadata(path, "a tiled scan store")
    try:
        root = zarr.open_group(str(path), mode="r")
        record = root[TILES_GROUP]
    except Exception:
        raise ValueError(
            f"{path} exists and is not a tiled scan store: choose another path or remove it"
        ) from None
    if record.attrs.get("format") != FORMAT:
        raise ValueError(
            f"{path} is a tile store of another format ({record.attrs.get('format')!r}, this version "
            f"writes {FORMAT!r}): it can be read and drawn, but not resumed; write to a new path"
        )
    if "crc" not in record or "done" not in record:
        raise ValueError(f"{path} is a damaged tile store (its tile record is incomplete): write to a new path")
    missing = [name for name in variables if name not in root]
    if missing:
        raise ValueError(f"{path} is a damaged tile store (its array {missing[0]!r} is missing): write to a new path")
    differ = []
    if record.attrs.get("tile") != tile:
        differ.append(f"tile: store {record.attrs.get('tile')!r}, asked {tile!r}")
    stored = dict(root.attrs)
    for key in attrs:
        if key not in stored or _differs(stored[key], attrs[key]):
            differ.append(f"{key}: store {stored.get(key)!r}, asked {attrs[key]!r}")
    if differ:
        raise ValueError(
            f"{path} holds a different scan ({'; '.join(differ)}): resume it with its own "
            "parameters, or write to a new path"
        )


def _check_coords(path, es, us, repair):
    """The coordinate arrays of the store against the pixel centres of its
    window (report N2: they are outside the checksum; a deleted ``e`` chunk
    read as nan, a rewritten one as another window, and passed as complete).
    Wrong or unreadable ones are rewritten (said, ``RuntimeWarning``) with
    ``repair``, else refused.  Returns the names rewritten."""
    import zarr

    root = zarr.open_group(str(path), mode="r+" if repair else "r")
    fixed = []
    for name, want in (("e", es), ("u", us)):
        try:
            arr = root[name]
        except Exception:  # noqa: BLE001 - its metadata garbled: not ours to rebuild
            raise DamagedStoreError(f"{path} is damaged (its {name} coordinate array cannot be read): "
                                    "write to a new path") from None
        try:
            ok = arr.shape == want.shape and np.array_equal(arr[...], want)
        except Exception:  # noqa: BLE001 - a garbled chunk
            ok = False
        if ok:
            continue
        if not repair:
            raise DamagedStoreError(
                f"the {name} coordinates of {path} are damaged (they do not match its window) and "
                "the store cannot be written here: run its scan again where it can be written"
            )
        arr[...] = want
        fixed.append(name)
    if fixed:
        warnings.warn(
            f"the coordinate {' and '.join(fixed)} of {path} did not match the store's window "
            "(a chunk deleted or damaged): rewritten", RuntimeWarning, stacklevel=3,
        )
    return fixed


def _differs(a, b):
    if isinstance(b, float) or isinstance(a, float):
        try:
            return float(a) != float(b)
        except (TypeError, ValueError):
            return True
    return a != b


# --------------------------------------------------------------------------- #
# Public API                                                                  #
# --------------------------------------------------------------------------- #


def scan_to_zarr(
    path,
    e=(0.0, 1.0, 500),
    u=(0.0, 1.5, 350),
    max_iter=1000,
    y0=1.0,
    v0=0.0,
    tile=1024,
    client=None,
    progress=None,
    numba_threads=None,
    prune=True,
    verify=True,
):
    """scan_to_zarr(path, e=(e_min, e_max, n_e), u=(u_min, u_max, n_u), max_iter=1000, y0=1.0, v0=0.0, tile=1024, client=None, progress=None, numba_threads=None, prune=True, verify=True) -> xarray.Dataset

    :func:`stairbounce.plane.scan` cut into tiles, computed locally or on Dask, written to Zarr.

    The ``n_u x n_e`` grid of pixel centres is cut into ``tile x tile`` blocks
    (shorter at the far edges).  Each block is computed by
    :func:`stairbounce.plane.scan_coords` on its slice of the grid (so the
    result equals the whole :func:`~stairbounce.plane.scan`, bit for bit) and
    written into its own region, one Zarr chunk per variable, of a store
    created up front with the full coordinates and attributes.  A tile is
    marked complete only after its data is written; running the same call
    again skips complete tiles, so an interrupted scan resumes where it
    stopped.  An existing store made with another window, ``max_iter``,
    ``y0``, ``v0``, ``tile`` or store format is refused, never mixed; a store
    another scan is writing (its lock is held) is refused, naming the holder.

    Parameters
    ----------
    path : str or path-like ending in ``.zarr``
        The store.  Its folder must exist and be writable; with a Dask
        cluster it must be on a file system every worker sees at the same path.
    e, u, max_iter, y0, v0, prune :
        As in :func:`stairbounce.plane.scan` (same defaults, same checks;
        ``prune`` changes no value, so a store may be resumed either way).
    tile : int >= 1, default 1024
        Tile edge in pixels; also the chunk edge of the store.
    client : None, ``dask.distributed.Client`` or str, default None
        None: compute the tiles in this process, in a pool of threads.  A client, or a scheduler address such as
        ``"tcp://10.0.0.1:8786"`` (connected for this call and closed): every
        tile is a task; the worker computes it and writes its region itself.
    progress : callable ``progress(done, total)`` or None
        Called with the number of complete tiles: once before any work
        (counting tiles found complete), then after each tile.  An exception
        raised there stops the scan (tiles already complete stay complete).
    numba_threads : int >= 1 or None, default None (1)
        Numba threads per tile.  Locally, ``numba.get_num_threads() //
        numba_threads`` tiles run at once; on a Dask worker as many as it has
        Dask threads (keep their product at most the worker's cores).
    verify : bool, default True
        Before resuming, read every tile marked complete and compare it with
        the checksum written with it; damaged tiles are said (``RuntimeWarning``)
        and computed again.  False skips the read (a large complete store).

    Returns
    -------
    xarray.Dataset
        The store, opened lazily (dask arrays chunked ``tile x tile``).

    Raises
    ------
    ValueError
        A bad parameter (naming it), a path that does not end in ``.zarr``,
        whose folder is missing or read-only, an existing store made for a
        different scan, a store locked by another scan
        (:class:`stairbounce._io.StoreLockedError`), or a scheduler that cannot
        be reached (before the store is created).

    Reference: Section 3 of the paper (the scan behind Figures 4 and 5).
    """
    import xarray as xr

    from .plane import _windows, pixel_centres, scan

    path = _check_path(path)
    tile = check_count("tile", tile, 1)
    if numba_threads is not None:
        numba_threads = check_count("numba_threads", numba_threads, 1)
    _check_client(client)
    # one pixel through the public scan: validates everything as scan does and
    # gives its variables and attributes, whatever scan records
    (e_lo, e_hi, n_e), (u_lo, u_hi, n_u) = _windows(e, u)
    # a window of speeds in m/s (Staircase.speed(lo, hi, n)): the store records the
    # staircase (its attributes, checked on resume) and the coordinate speed
    stairs = staircase_of(u)
    u_probe = (u_lo, u_hi, 1) if stairs is None else stairs.speed(*u.metres_per_second, 1)
    probe = scan(e=(e_lo, e_hi, 1), u=u_probe, max_iter=max_iter, y0=y0, v0=v0)
    n_e = check_count("n_e", n_e, 1)
    n_u = check_count("n_u", n_u, 1)
    a = probe.attrs
    es = pixel_centres(a["e_min"], a["e_max"], n_e)
    us = pixel_centres(a["u_min"], a["u_max"], n_u)
    template, encoding = _template(probe, es, us, tile)
    rows, cols = tile_slices(n_u, tile), tile_slices(n_e, tile)
    reason = _unwritable_reason(path.parent)
    if reason is not None and path.exists():
        # no lock can be taken here: a complete store opens read-only (report N9)
        return _open_read_only(path, template.attrs, tile, es, us, rows, cols, verify, progress, reason,
                               list(template.data_vars))
    if reason is not None:
        raise ValueError(f"cannot write {path}: folder {path.parent} is not writable ({reason})")

    with _connected_and_locked(path, client) as (client, owner):
        if path.exists():
            _check_existing(path, template.attrs, tile, list(template.data_vars))
            _check_coords(path, es, us, repair=True)
        else:
            _create(path, template, encoding, (len(rows), len(cols)), tile)
            lock_store_folder(path, owner)  # its device and inode, whatever name it gets

        done, unreadable = _read_record(_tile_record(path)["done"], False)
        if unreadable:
            warnings.warn(
                f"the done flag of {len(unreadable)} tile(s) of {path} cannot be read (a chunk "
                f"damaged), e.g. tile {unreadable[0]}: computed again", RuntimeWarning, stacklevel=2,
            )
        todo = [(i, j) for i in range(len(rows)) for j in range(len(cols)) if not done[i, j]]
        if todo and not _writable(path):
            raise ValueError(f"cannot resume {path}: the store is not writable")
        if verify and done.any():
            damaged = _verify(path, rows, cols, done)
            if damaged:
                warnings.warn(
                    f"{len(damaged)} complete tile(s) of {path} no longer match their checksum "
                    f"(a chunk deleted or damaged), e.g. tile {damaged[0]}: computed again",
                    RuntimeWarning, stacklevel=2,
                )
                todo = sorted(set(todo) | set(damaged))
        total = done.size
        if progress is not None:
            progress(total - len(todo), total)

        record = _tile_record(path)
        token = record.attrs["token"]
        identity = _identity(_root_attrs(path), dict(record.attrs))
        args = [
            (str(path), token, owner, i, j, rows[i], cols[j], es[cols[j]], us[rows[i]],
             a["max_iter"], a["y0"], a["v0"], bool(prune), numba_threads, identity)
            for i, j in todo
        ]
        if client is None:
            _run_here(args, numba_threads, total - len(todo), total, progress)
        else:
            _run_on_dask(client, args, total - len(todo), total, progress)
        _check_same_store(path, token)
    return xr.open_zarr(str(path), consolidated=False)


def _open_read_only(path, attrs, tile, es, us, rows, cols, verify, progress, reason, variables=()):
    """A store whose folder cannot be written (no lock can be taken there):
    opened read-only when it is this scan's, complete and intact, else refused."""
    import xarray as xr

    _check_existing(path, attrs, tile, variables)
    _check_coords(path, es, us, repair=False)
    done = tiles_done(path)
    missing = int((~done).sum())
    if missing:
        raise ValueError(f"cannot resume {path}: its folder is not writable ({reason}) and "
                         f"{missing} of {done.size} tiles are not computed yet")
    if verify:
        damaged = _verify(path, rows, cols, done, repair=False)
        if damaged:
            raise DamagedStoreError(
                f"{len(damaged)} tile(s) of {path} no longer match their checksum, e.g. tile "
                f"{damaged[0]}, and its folder is not writable ({reason}): run its scan again "
                "where it can be written"
            )
    if progress is not None:
        progress(done.size, done.size)
    return xr.open_zarr(str(path), consolidated=False)


@contextlib.contextmanager
def _connected_and_locked(path, client):
    """``(client, owner)`` for a tiled writer (``scan_to_zarr``,
    ``certify_to_zarr``): a scheduler address is connected to before the store
    exists (an unreachable scheduler leaves nothing), then the store's lock is
    taken (``owner``, ``_io.store_lock``); a client connected here is closed on
    the way out, whatever happened."""
    own = isinstance(client, str)
    if own:  # connect before the store exists: an unreachable scheduler leaves nothing
        client = _connect(client)
    try:
        with store_lock(path) as owner:
            yield client, owner
    finally:
        if own:
            client.close()


def _connect(address):
    """A client of the scheduler at ``address``; a closed port fails at once
    (a plain TCP connection is tried first), anything else within Dask's
    connect timeout."""
    import socket
    from urllib.parse import urlsplit

    from distributed import Client

    parts = urlsplit(address)
    if parts.scheme in ("tcp", "tls") and parts.hostname and parts.port:
        try:
            socket.create_connection((parts.hostname, parts.port), timeout=10).close()
        except OSError as exc:
            reason = (exc.strerror or str(exc) or type(exc).__name__).lower()
            raise ValueError(f"cannot reach the Dask scheduler at {address}: {reason}") from None
    try:
        return Client(address)
    except (OSError, TimeoutError) as exc:
        raise ValueError(f"cannot reach the Dask scheduler at {address}: {exc}") from None


def _run_here(args, numba_threads, n_done, total, progress):
    """The tiles in this process: side by side in a pool of threads."""
    import numba
    from concurrent.futures import ThreadPoolExecutor, as_completed

    args = [arg[:13] + (numba_threads or 1,) + arg[14:] for arg in args]  # arg[13]: numba_threads
    side_by_side = max(1, numba.get_num_threads() // (numba_threads or 1))
    if side_by_side == 1 or len(args) == 1:
        for arg in args:
            _run_tile(*arg)
            n_done += 1
            if progress is not None:
                progress(n_done, total)
        return
    with ThreadPoolExecutor(side_by_side, thread_name_prefix="stairbounce-tile") as pool:
        futures = [pool.submit(_run_tile, *arg) for arg in args]
        try:
            for future in as_completed(futures):
                future.result()
                n_done += 1
                if progress is not None:
                    progress(n_done, total)
        finally:
            # on an error or an interrupt: tiles not started are dropped, the
            # running ones finish (and are marked) before this returns
            for future in futures:
                future.cancel()


def _check_client(client) -> None:
    """``client`` as the tiled functions take it: None (here), a
    ``dask.distributed.Client`` or a scheduler address (see :func:`_connect`)."""
    if client is not None and not isinstance(client, str) and not hasattr(client, "submit"):
        raise ValueError(
            f"client must be None, a dask.distributed.Client or a scheduler address, got {client!r}"
        )


def _dask_each(client, fn, args, each, wait_cancelled=False) -> None:
    """Run ``fn(*a)`` on the cluster for every ``a`` in ``args`` and call
    ``each(result)`` here as they finish.  On the way out (an error, Ctrl-C)
    what has not finished is cancelled; with ``wait_cancelled``, waited for
    (up to 5 s) until it has stopped."""
    from distributed import as_completed

    from distributed.client import FutureCancelledError
    from distributed.comm.core import CommClosedError

    futures = []
    try:
        futures = [client.submit(fn, *a, pure=False) for a in args]
        done = as_completed(futures)
        last = noted = time.monotonic()
        while not done.is_empty():
            if done.has_ready():
                future = next(done)
                each(future.result())
                future.release()
                last = noted = time.monotonic()
                continue
            time.sleep(0.05)  # Ctrl-C is seen here at once
            now = time.monotonic()
            if now - noted >= WAIT_NOTE:  # no tile finished for a while: say why, if the cluster knows
                note = _cluster_note(client, now - last)
                noted = time.monotonic()
                if note is not None:
                    warnings.warn(note, RuntimeWarning, stacklevel=2)
    except (FutureCancelledError, CommClosedError) as exc:
        # the scheduler is gone (report N7: a 30-line traceback): what is
        # complete stays complete, the same call resumes
        reason = " ".join(str(exc).split())[:200] or type(exc).__name__
        raise ValueError(
            f"lost the Dask scheduler {getattr(client.scheduler, 'address', '')} ({type(exc).__name__}: "
            f"{reason}); the complete tiles are kept: run the same command again to resume"
        ) from None
    finally:
        pending = [f for f in futures if not f.done()]
        if pending:
            with contextlib.suppress(Exception):  # a scheduler that is gone takes no cancel
                client.cancel(pending)
            if wait_cancelled:
                with contextlib.suppress(Exception):
                    from distributed import wait

                    wait(pending, timeout=5)


WAIT_NOTE = 30.0
"""Seconds without a finished tile after which a Dask scan asks its scheduler
how many workers it has, and says so when none is connected or the scheduler
does not answer (then again every as many seconds); report round 3: a scan
whose workers were all killed, or whose scheduler was stopped, waited silently."""


def _cluster_note(client, waited):
    """What a Dask scan waits for, or None when workers are connected: the
    scheduler asked for its workers, within 5 s."""
    address = getattr(getattr(client, "scheduler", None), "address", "") or "?"
    try:
        workers = client.nthreads(callback_timeout=5)
    except Exception:  # noqa: BLE001 - no answer: stopped, or gone (then the scan fails on its own)
        return (f"waiting for the Dask scheduler {address}: it does not answer (no tile finished for "
                f"{waited:.0f} s); Ctrl-C stops, the complete tiles are kept")
    if not workers:
        return (f"waiting for workers: none connected to the Dask scheduler {address} (no tile finished "
                f"for {waited:.0f} s); start workers, or Ctrl-C stops and the complete tiles are kept")
    return None


def _run_on_dask(client, args, n_done, total, progress):
    def each(_):
        nonlocal n_done
        n_done += 1
        if progress is not None:
            progress(n_done, total)

    # the lock is released when the caller returns: tiles still running must
    # not write after that (they check the lock, and a cancelled one that
    # already checked writes a whole, unmarked tile), hence the wait
    _dask_each(client, _run_tile, args, each, wait_cancelled=True)


def downsample(ds, max_pixels, method="mode"):
    """downsample(ds, max_pixels, method="mode") -> xarray.Dataset

    A scan reduced to at most ``max_pixels`` pixels by blocks of ``f x f``.

    ``f = ceil(sqrt(n_u n_e / max_pixels))``; pixels beyond a whole number of
    blocks at the far edges are dropped.  The variables are categorical (word
    lengths, periods), so blocks are never averaged:

    - ``"mode"``: the most frequent value of the block (ties: the smallest),
    - ``"max"``: the largest value,
    - ``"stride"``: the first pixel of the block (a sample, no reduction).

    Coordinates become the block centres.  Works lazily on dask-backed
    datasets (an opened store): only the reduced result is held in memory
    when it is computed.  ``f = 1`` returns ``ds`` unchanged.
    """
    import xarray as xr

    max_pixels = check_count("max_pixels", max_pixels, 1)
    if method not in ("mode", "max", "stride"):
        raise ValueError(f"method must be one of 'mode', 'max', 'stride', got {method!r}")
    n = ds.sizes["u"] * ds.sizes["e"]
    f = math.ceil(math.sqrt(n / max_pixels))
    while f > 1 and (ds.sizes["u"] // f) * (ds.sizes["e"] // f) > max_pixels:
        f += 1  # pragma: no cover - float rounding of the square root
    f = max(1, min(f, ds.sizes["u"], ds.sizes["e"]))
    if f == 1:
        return ds
    window = {"u": f, "e": f}
    if method == "stride":
        nu, ne = (ds.sizes["u"] // f) * f, (ds.sizes["e"] // f) * f
        out = ds.isel(u=slice(0, nu, f), e=slice(0, ne, f))
        centres = ds[["u", "e"]].coarsen(window, boundary="trim").mean()
        out = out.assign_coords(u=centres["u"].values, e=centres["e"].values)
    elif method == "max":
        out = ds.coarsen(window, boundary="trim").max()
    else:
        blocks = ds.coarsen(window, boundary="trim").construct(u=("u", "u_in"), e=("e", "e_in"))
        out = xr.apply_ufunc(
            _block_mode,
            blocks,
            input_core_dims=[["u_in", "e_in"]],
            dask="parallelized",
            keep_attrs=True,
        )
        centres = ds[["u", "e"]].coarsen(window, boundary="trim").mean()
        out = out.assign_coords(u=centres["u"].values, e=centres["e"].values)
    for name in out.variables:
        out[name].attrs = ds[name].attrs
    out.attrs = dict(ds.attrs, downsampled=f, downsample_method=method)
    return out


def _block_mode(x):
    """Most frequent value over the last two axes (ties: the smallest)."""
    shape = x.shape[:-2]
    flat = np.sort(x.reshape(-1, x.shape[-2] * x.shape[-1]), axis=1)
    k = flat.shape[1]
    idx = np.broadcast_to(np.arange(k), flat.shape)
    starts = np.where(np.diff(flat, axis=1, prepend=flat[:, :1] - 1) != 0, idx, 0)
    run = idx - np.maximum.accumulate(starts, axis=1) + 1
    best = np.argmax(run, axis=1)
    return flat[np.arange(flat.shape[0]), best].reshape(shape)
