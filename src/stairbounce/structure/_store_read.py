"""Reading a streamed certified atlas (``structure/certify_store.py``): its tiles,
each checked against its checksum, merged into the table :func:`stairbounce.certify`
returns (the same rows in the same order: by level, then j, then i).

Kept apart from ``certify_store`` (which imports the certifier) so that the readers
of atlas files (``certificate.read_atlas_file``, hence ``CertifiedAtlas.load`` and
``sb.verify``) can read a store without an import circle; numpy, xarray and zarr only (and
one compiled loop, :func:`_copy_rows`; pandas for :func:`encode`, the tile's form as
written, which the store's writer and ``focus.py``'s rounds share).
"""

from __future__ import annotations

import json
import os

import numpy as np
from numba import njit

STORE_KIND = "stairbounce certified atlas store"
STORE_FORMAT = "stairbounce-certify-store-1"
RECORD = "tiles"   # the tile record: done flags and checksums (attrs: format, token)
SUMMARY = "summary"  # a group whose attribute "summary" holds the tiles' numbers combined
BOXES = "boxes"    # one group per tile: BOXES/00000 (the coarse levels), 00001, ...

# the dimensions of an atlas table's variables (certify._atlas_dataset, trapping.trap_atlas)
DIMS = {"offsets": ("offset",), "itinerary": ("itinerary_step",), "trap_box": ("trap",),
        "trap_grid": ("trap", "trap_grid_field"), "trap_cell_offsets": ("trap_offset",),
        "trap_cells": ("trap_cell",)}
# attributes a tile carries that are not the atlas's (or are summed over the tiles)
TILE_ATTRS = ("summary", "word_names", "reason_names", "trap_tried", "trap_seconds", "trap_failures")


def tile_name(k):
    return f"{int(k):06d}"


def is_store(path):
    """Whether ``path`` is a folder holding a streamed certified atlas (its root
    group's ``kind``): read without zarr, from the root's metadata file."""
    try:
        with open(os.path.join(os.fspath(path), "zarr.json"), "rb") as f:
            meta = json.loads(f.read(16 << 20))
        return meta.get("attributes", {}).get("kind") == STORE_KIND
    except (OSError, ValueError, AttributeError):
        return False


def tile_seed(token, k):
    """What tile ``k``'s checksum is seeded with: the store's token and the tile's index
    (a tile copied to another index or store does not match there)."""
    return f"stairbounce certified store;token={token};tile={int(k)}"


def tile_values(arrays, attrs):
    """The checksummed content of a tile: its arrays, and its texts' names lists and
    summary as arrays (the attributes the rows need)."""
    values = dict(arrays)
    for key in ("word_names", "reason_names", "summary"):
        text = json.dumps(attrs.get(key), sort_keys=True)
        values[f"attr:{key}"] = np.frombuffer(text.encode(), np.uint8)
    return values


def read_tile(path, k):
    """``(arrays, attrs)`` of tile ``k`` as stored (codes not decoded)."""
    import zarr

    g = zarr.open_group(os.path.join(os.fspath(path), BOXES, tile_name(k)), mode="r")
    arrays = {name: np.asarray(arr[...]) for name, arr in g.arrays()}
    return arrays, dict(g.attrs)


def tile_level(root, depth):
    """The level the store's tiles are cut at (its root attribute ``tile_level``), or
    ``depth`` when that is missing or not an int in ``[0, depth]``: the cut the verdict's
    overlap argument and the streamed border counts rest on."""
    level = root.get("tile_level")
    return level if isinstance(level, int) and 0 <= level <= depth else depth


def store_state(path):
    """``(root attrs, record attrs, done flags, checksums)`` of a store."""
    import zarr

    root = zarr.open_group(os.fspath(path), mode="r")
    record = root[RECORD]
    return dict(root.attrs), dict(record.attrs), np.asarray(record["done"][...]), np.asarray(record["crc"][...])


def check_tile(path, k, token, crc):
    """Tile ``k``'s arrays and attributes, or None when it cannot be read or does not
    match its checksum ``crc`` (a chunk deleted, truncated or garbled)."""
    from ..atlas import _checksum

    try:
        arrays, attrs = read_tile(path, k)
        ok = _checksum(tile_values(arrays, attrs), tile_seed(token, k)) == int(crc)
    except Exception:  # noqa: BLE001 - any read or decoding error of a chunk is damage
        return None
    return (arrays, attrs) if ok else None


def _decode(arrays, attrs, key):
    """The texts of a tile's ``{key}_code`` from its names list; a code outside the list
    (a negative one too, which numpy's indexing would take from the end) refused with
    ValueError naming the row of the tile."""
    names = list(attrs.get(f"{key}_names") or [])
    table = np.array(names + [""], dtype=object)[:-1] if names else np.zeros(0, dtype=object)
    if f"{key}_code" not in arrays:
        raise ValueError(f"a tile's {key}_code is missing: the store is damaged")
    codes = np.asarray(arrays.pop(f"{key}_code"))
    integer = codes.dtype.kind in "iu"
    bad = np.flatnonzero((codes < 0) | (codes >= len(names))) if integer else np.arange(codes.size)
    if bad.size:
        raise ValueError(f"{key}_code {codes[bad[0]].item()!r} at row {int(bad[0])} of a tile is outside its "
                         f"names list {key}_names ({len(names)} names)")
    return table[codes]


def encode(ds):
    """A tile's table as written: word and reason as int32 codes into names lists kept in
    attributes (CertifiedAtlas.save's .zarr form; :func:`_decode` reads them back)."""
    ds = ds.copy()
    ds.attrs = {k: (list(v) if isinstance(v, tuple) else v) for k, v in ds.attrs.items()}
    for k in ("word", "reason"):
        codes, names = factorize(ds[k].values)
        ds = ds.drop_vars(k).assign({f"{k}_code": ("box", codes.astype(np.int32))})
        ds.attrs[f"{k}_names"] = names
    return ds


def factorize(values):
    """``(codes, names)``: the distinct texts of ``values`` (sorted) and each value's index
    among them, by hashing (no fixed-width copy of the texts: a word can be hundreds of
    letters, and a ``<U`` copy of a tile's words took 170 MiB at depth 12)."""
    import pandas as pd

    v = np.asarray(values)
    codes, uniques = pd.factorize(v if v.dtype.kind == "O" else v.astype(object))
    names = [str(x) for x in uniques]
    order = sorted(range(len(names)), key=names.__getitem__)
    remap = np.empty(len(names), np.int64)
    remap[order] = np.arange(len(names))
    return remap[codes] if len(names) else codes.astype(np.int64), [names[k] for k in order]


def store_sizes(path):
    """``(boxes, itinerary steps, trapping cells)`` of a complete store, from its summary
    (the checker's work estimated before the boxes are read); None without a summary."""
    try:
        s = read_summary(path)
        return int(s["boxes"]), int(s["itinerary"]), int(s.get("trap_cells", 0))
    except Exception:  # noqa: BLE001 - incomplete or damaged: read_store says which
        return None


def read_summary(path):
    """The store's combined summary (dict), or None when the run has not finished."""
    import zarr

    try:
        g = zarr.open_group(os.path.join(os.fspath(path), SUMMARY), mode="r")
    except Exception:  # noqa: BLE001 - not written yet
        return None
    text = g.attrs.get("summary")
    return None if text is None else json.loads(text)


def complete_state(path):
    """``(root attrs, token, checksums)`` of a complete store; an unreadable, damaged or
    incomplete one refused with ValueError saying which."""
    try:
        root, record, done, crc = store_state(path)
    except Exception as exc:  # noqa: BLE001
        raise ValueError(f"cannot read {path} as a certified atlas store: {exc}") from None
    n = int(root.get("n_tiles", -1))
    if done.shape != (n,) or crc.shape != (n,):
        raise ValueError(f"{path} is a damaged certified atlas store (its tile record has {done.size} "
                         f"entries, the store {n} tiles)")
    if not done.all():
        raise ValueError(f"{path} is incomplete: {int(done.sum())} of {n} tiles computed; run "
                         "certify_to_zarr (stairbounce certify --store) again with the same arguments to finish it")
    return root, record.get("token"), crc


def read_store(path):
    """read_store(path) -> xarray.Dataset: the whole atlas table of a streamed store,
    in memory: every tile read, checked against its checksum, and the tiles merged in
    the atlas's order (by level, then j, then i), the itineraries and trapping regions
    renumbered.  The same rows, bit for bit, as :func:`stairbounce.certify`'s table
    with the store's arguments; ``trap_tried`` and ``trap_seconds`` summed over the
    tiles, ``trap_failures`` counted over them.  An incomplete or damaged store is
    refused with ValueError naming the tile."""
    root, token, crc = complete_state(path)
    n = crc.size
    sizes = [_tile_sizes(path, k) for k in range(n)]

    def tiles():  # one at a time: read, checked, copied into the table, let go
        for k in range(n):
            got = check_tile(path, k, token, crc[k])
            if got is None:
                raise ValueError(f"tile {k} of {path} does not match its checksum (a chunk deleted or damaged): "
                                 "run certify_to_zarr with the same arguments to compute it again")
            yield got

    return merge_tiles(tiles(), sum(b for b, _ in sizes), sum(t for _, t in sizes))


def _tile_sizes(path, k):
    """``(boxes, itinerary steps)`` of tile ``k`` from its arrays' metadata (no chunk read)."""
    try:
        shapes = []
        for name in ("e0", "itinerary"):
            with open(os.path.join(os.fspath(path), BOXES, tile_name(k), name, "zarr.json"), "rb") as f:
                shapes.append(int(json.loads(f.read())["shape"][0]))
        return tuple(shapes)
    except (OSError, ValueError, KeyError, IndexError, TypeError):
        raise ValueError(f"tile {k} of {path} does not match its checksum (its metadata cannot be read): "
                         "run certify_to_zarr with the same arguments to compute it again") from None


def row_key(level, i, j):
    """The atlas's order of rows as one int64 key a box: by level, then j, then i
    (``i, j < 2^27`` at depth <= 26); ``certify``'s table, the trapping pass's, a
    store's merge and the store's verification sort by it."""
    return ((np.asarray(level).astype(np.int64) << 56) | (np.asarray(j).astype(np.int64) << 28)
            | np.asarray(i).astype(np.int64))


def merge_tiles(tiles, n_boxes, n_steps, first=0):
    """The atlas table of tiles ``(arrays, attrs)`` (:func:`read_tile`, an iterable, taken
    one at a time) holding ``n_boxes`` boxes and ``n_steps`` itinerary steps in all: each
    tile copied into the table's columns, allocated once (a list of the tiles' parts,
    concatenated, left the freed parts in the heap: 6 GiB of resident memory for a
    2.2 GB table at depth 14).  ``first``: the index of the first tile (named in errors)."""
    import xarray as xr

    cols = {}
    lengths = np.empty(n_boxes, np.int64)
    itinerary = np.empty(n_steps, np.int64)
    traps = []
    trap = None
    first_attrs = None
    tried, seconds, failures = 0, 0.0, {}
    base = step = 0
    for k, (arrays, attrs) in enumerate(tiles, first):
        arrays = dict(arrays)
        if trap is None:
            trap, first_attrs = "trap_box" in arrays, attrs
        try:
            arrays["word"] = _decode(arrays, attrs, "word")
            arrays["reason"] = _decode(arrays, attrs, "reason")
        except ValueError as exc:
            raise ValueError(f"tile {k}: {exc}") from None
        off = arrays.pop("offsets")
        it = arrays.pop("itinerary")
        nb = off.size - 1
        if base + nb > n_boxes or step + it.size > n_steps:
            raise ValueError("a tile holds more boxes or steps than its metadata says: the store is damaged")
        lengths[base:base + nb] = np.diff(off)
        itinerary[step:step + it.size] = it
        if trap:
            traps.append((arrays.pop("trap_box") + base, arrays.pop("trap_grid").reshape(-1, 6),
                          arrays.pop("trap_cell_offsets"), arrays.pop("trap_cells")))
            tried += int(attrs.get("trap_tried", 0))
            seconds += float(attrs.get("trap_seconds", 0.0))
            for part in filter(None, str(attrs.get("trap_failures", "")).split(", ")):
                why, c = part.rsplit(" ", 1)
                failures[why] = failures.get(why, 0) + int(c)
        for name, a in arrays.items():
            if name not in cols:
                cols[name] = np.empty(n_boxes, a.dtype)
            cols[name][base:base + nb] = a
        base += nb
        step += it.size
        del arrays, it, off
    if base != n_boxes or step != n_steps or first_attrs is None:
        raise ValueError("the tiles hold fewer boxes or steps than their metadata says: the store is damaged")
    old_off = np.zeros(lengths.size + 1, np.int64)
    np.cumsum(lengths, out=old_off[1:])
    # the atlas's order: by level, then j, then i (certify._box_table's key)
    order = np.argsort(row_key(cols["level"], cols["i"], cols["j"]), kind="stable")
    for name in list(cols):  # one column at a time
        cols[name] = cols[name][order]
    new_len = lengths[order]
    offsets = np.zeros(order.size + 1, np.int64)
    np.cumsum(new_len, out=offsets[1:])
    itinerary = _take_rows(itinerary, old_off[:-1][order], new_len)
    data = {name: ("box", a) for name, a in cols.items()}
    data["offsets"] = ("offset", offsets)
    data["itinerary"] = ("itinerary_step", itinerary)
    if trap:
        rank = np.empty(order.size, np.int64)
        rank[order] = np.arange(order.size)
        boxes = rank[np.concatenate([t[0] for t in traps]).astype(np.int64)]
        grids = np.concatenate([t[1] for t in traps]).astype(np.float64).reshape(-1, 6)
        cell_len = np.concatenate([np.diff(t[2]) for t in traps]).astype(np.int64)
        cells = np.concatenate([t[3] for t in traps]).astype(np.int64)
        cell_off = np.zeros(cell_len.size + 1, np.int64)
        np.cumsum(cell_len, out=cell_off[1:])
        by = np.argsort(boxes, kind="stable")
        new_cell_len = cell_len[by]
        new_cell_off = np.zeros(by.size + 1, np.int64)
        np.cumsum(new_cell_len, out=new_cell_off[1:])
        data["trap_box"] = ("trap", boxes[by])
        data["trap_grid"] = (("trap", "trap_grid_field"), grids[by])
        data["trap_cell_offsets"] = ("trap_offset", new_cell_off)
        data["trap_cells"] = ("trap_cell", _take_rows(cells, cell_off[:-1][by], new_cell_len))
    order_names = ["e0", "e1", "u0", "u1", "status", "word", "reason", "step", "level", "i", "j"]
    ordered = {k: data[k] for k in order_names if k in data}
    ordered.update({k: v for k, v in data.items() if k not in ordered})
    attrs = {k: v for k, v in first_attrs.items() if k not in TILE_ATTRS}
    if trap:
        attrs.update(trap_tried=tried, trap_seconds=seconds,
                     trap_failures=", ".join(f"{k} {v}" for k, v in sorted(failures.items())))
    return xr.Dataset(ordered, attrs=attrs)


def _take_rows(values, starts, lengths):
    """The ragged rows ``values[starts[k]:starts[k] + lengths[k]]`` one after another (a
    copy, of ``values``' dtype), by one compiled loop: no index arrays (an index a value
    took three int64 arrays of 1.2 GB each for the 150 million itinerary steps of depth
    14; then blocks of rows cut them, and their building was most of the trapping
    pass's Python time)."""
    values = np.ascontiguousarray(values)
    starts = np.ascontiguousarray(starts, np.int64)
    lengths = np.ascontiguousarray(lengths, np.int64)
    if starts.shape != lengths.shape or starts.ndim != 1:
        raise ValueError(f"starts and lengths must be two 1-d arrays of one length, got {starts.shape}, "
                         f"{lengths.shape}")
    if lengths.size and (lengths.min() < 0 or starts.min() < 0 or (starts + lengths).max() > values.size):
        raise ValueError("a row of starts/lengths lies outside values")
    out = np.empty(int(lengths.sum()), values.dtype)
    _copy_rows(values, starts, lengths, out)
    return out


@njit(cache=True, nogil=True)
def _copy_rows(values, starts, lengths, out):
    """Row after row into ``out``; rows that follow each other in ``values`` (most of
    them, where a table keeps its rows in their order) are copied as one block."""
    at = 0
    k = 0
    n_rows = starts.size
    while k < n_rows:
        s, n = starts[k], lengths[k]
        k += 1
        while k < n_rows and starts[k] == s + n:
            n += lengths[k]
            k += 1
        out[at:at + n] = values[s:s + n]
        at += n
