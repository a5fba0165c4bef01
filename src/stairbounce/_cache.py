"""The figures' cache of computed datasets (``~/.cache/stairbounce``): what an
entry is, when it may be used, how big the cache may grow.

An entry is a netCDF file ``KIND-HASH.nc``.  ``HASH`` is a hash of the
request: the kind, the inputs the recipe asked for (window, pixels,
``max_iter``, start, ...) and :func:`kernel_hash`, a hash of the source of the
modules that compute the numbers, so a change of the kernels (not of the
version string, unchanged across the whole history, report N1) makes new
entries.  The file carries its request and a checksum of its data in two
global attributes; an entry is used only when both agree with what is asked
and with what it holds (and, for a grid, its shape and pixel centres),
otherwise it is removed and computed again (a stray file under a cached name,
another tool's file, a damaged or out-of-date entry).

Size: at most :data:`MAX_BYTES` (``$STAIRBOUNCE_CACHE_MAX_BYTES``, default
2 GiB); after each write the least recently used entries are removed until
the cache fits.  ``stairbounce cache info`` and ``stairbounce cache clear``
show and empty it.

Nothing here imports more than numpy at import time (xarray when an entry is read).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import json
import os
import re
import zlib
from pathlib import Path

import numpy as np

__all__ = ["kernel_hash", "entry_path", "read_entry", "write_entry", "entries", "clear", "max_bytes",
           "KERNEL_MODULES", "MAX_BYTES"]

# The modules whose code computes the entries the cache holds, as dotted names
# under stairbounce (a package covers all its modules): the scans (plane),
# orbit diagrams (orbits), bifurcations (structure.bifurcations, which imports
# the border kernels of structure.borders and structure.itinerary), motion
# fields (nonsliding).  The hash follows every
# stairbounce module they import, anywhere in their code, transitively
# (_kernel_files), so a helper they call is covered without being listed;
# tests/test_faults_round3.py checks that every function whose result
# figures/ caches is defined in a hashed module.
KERNEL_MODULES = ("model", "plane", "orbits", "nonsliding", "symbolic", "structure.bifurcations")
# never followed: drawing and interfaces compute no cached number
_NOT_KERNEL = ("plot", "cli", "explorer", "figures", "_cache")
MAX_BYTES = 2 << 30
REQUEST_ATTR = "stairbounce_cache_request"
CHECKSUM_ATTR = "stairbounce_cache_checksum"
_ENTRY = re.compile(r"^[a-z_]+-[0-9a-f]{20}\.nc$")


def _module_files(here, dotted):
    """The source files of the stairbounce module ``dotted`` (relative to the
    package, e.g. ``"plane"``; a package: all its modules), [] when there is none."""
    parts = dotted.split(".")
    if not parts[0] or parts[0] in _NOT_KERNEL:
        return []
    base = here.joinpath(*parts)
    if base.with_suffix(".py").is_file():
        return [base.with_suffix(".py")]
    if base.is_dir() and (base / "__init__.py").is_file():
        return sorted(base.rglob("*.py"))
    return []


def _imports(here, path):
    """The stairbounce modules (dotted, relative to the package) that the
    source file ``path`` imports, anywhere in its code."""
    import ast

    package = list(path.relative_to(here).parent.parts)
    found = []
    for node in ast.walk(ast.parse(path.read_bytes())):
        if isinstance(node, ast.Import):
            found += [a.name.split(".", 1)[1] for a in node.names if a.name.startswith("stairbounce.")]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - (node.level - 1)] if node.level > 1 else package
            elif (node.module or "").split(".")[0] == "stairbounce":
                base = []
            else:
                continue
            mod = (node.module or "")
            if not node.level:
                mod = mod.split(".", 1)[1] if "." in mod else ""
            prefix = base + (mod.split(".") if mod else [])
            if prefix:
                found.append(".".join(prefix))
            found += [".".join(prefix + [a.name]) for a in node.names]  # from . import plane
    return found


def _kernel_files():
    """The files of :data:`KERNEL_MODULES` and of every stairbounce module they
    import, transitively, in a fixed order."""
    here = Path(__file__).resolve().parent
    seen, todo = set(), [f for name in KERNEL_MODULES for f in _module_files(here, name)]
    missing = [name for name in KERNEL_MODULES if not _module_files(here, name)]
    if missing:  # a module moved: the list must follow it (or the cache would not)
        raise RuntimeError(f"_cache.KERNEL_MODULES names {missing}, not found in {here}")
    while todo:
        f = todo.pop()
        if f in seen:
            continue
        seen.add(f)
        for name in _imports(here, f):
            todo += [g for g in _module_files(here, name) if g not in seen]
    return here, sorted(seen)


def _kernel_sources():
    here, files = _kernel_files()
    return [(f.relative_to(here).as_posix(), f.read_bytes()) for f in files]


@functools.lru_cache(maxsize=1)
def kernel_hash() -> str:
    """SHA-256 (16 hex digits) of the source of :data:`KERNEL_MODULES` and of
    the stairbounce modules they import (:func:`_kernel_files`)."""
    h = hashlib.sha256()
    for name, text in _kernel_sources():
        h.update(name.encode() + b"\0" + text + b"\0")
    return h.hexdigest()[:16]


def max_bytes() -> int:
    """The size bound: ``$STAIRBOUNCE_CACHE_MAX_BYTES`` (bytes), default :data:`MAX_BYTES`."""
    try:
        n = int(os.environ.get("STAIRBOUNCE_CACHE_MAX_BYTES", MAX_BYTES))
    except ValueError:
        return MAX_BYTES
    return max(0, n)


def request(kind, inputs) -> str:
    """The request of an entry as canonical JSON: kind, inputs, kernel hash."""
    return json.dumps({"kind": kind, "kernel": kernel_hash(), **inputs}, sort_keys=True)


def entry_path(folder, kind, inputs) -> Path:
    """``folder/KIND-HASH.nc`` for the request."""
    key = request(kind, inputs)
    return Path(folder) / f"{kind}-{hashlib.sha256(key.encode()).hexdigest()[:20]}.nc"


def checksum(ds) -> str:
    """CRC-32 of every variable and coordinate (name, dtype, shape, bytes, by name).

    Text is hashed as text, whatever array type holds it: strings written as
    ``object`` read back from netCDF as ``<U`` (report round 3, R10: the
    bifurcation entries never matched, so they were computed every time).
    """
    c = 0
    for name in sorted(map(str, ds.variables)):
        a = np.ascontiguousarray(ds[name].values)
        if _is_text(a):
            c = zlib.crc32(f"{name}|text{a.shape}".encode(), c)
            c = zlib.crc32(json.dumps([str(x) for x in a.ravel().tolist()]).encode(), c)
            continue
        c = zlib.crc32(f"{name}{a.dtype.str}{a.shape}".encode(), c)
        c = zlib.crc32(a.tobytes() if a.dtype.kind != "O" else repr(a.tolist()).encode(), c)
    return format(c, "08x")


def _is_text(a) -> bool:
    """A string array (``<U``) or an object array of strings only."""
    if a.dtype.kind == "U":
        return True
    return a.dtype.kind == "O" and all(isinstance(x, str) for x in a.ravel().tolist())


def _grid_ok(ds, inputs) -> bool:
    """For a grid request (``e``, ``u``, ``n_e``, ``n_u``): its shape and pixel centres."""
    if not all(k in inputs for k in ("e", "u", "n_e", "n_u")):
        return True
    from .plane import pixel_centres

    try:
        for name in ("e", "u"):
            lo, hi = inputs[name]
            want = pixel_centres(lo, hi, inputs[f"n_{name}"])
            if ds.sizes.get(name) != want.size or not np.array_equal(ds[name].values, want):
                return False
    except (KeyError, TypeError, ValueError):
        return False
    return "max_iter" not in inputs or "max_iter" not in ds.attrs or ds.attrs["max_iter"] == inputs["max_iter"]


def _strip(ds):
    ds.attrs.pop(REQUEST_ATTR, None)
    ds.attrs.pop(CHECKSUM_ATTR, None)
    return ds


def read_entry(path, kind, inputs):
    """The dataset of the entry at ``path`` when it is the one asked for and
    intact, else None (the file, if any, is removed: it is recomputed)."""
    import xarray as xr

    path = Path(path)
    if not path.exists():
        return None
    try:
        with xr.open_dataset(path) as ds:
            ds = ds.load()
        ok = (ds.attrs.get(REQUEST_ATTR) == request(kind, inputs)
              and ds.attrs.get(CHECKSUM_ATTR) == checksum(ds)
              and _grid_ok(ds, inputs))
    except (OSError, ValueError, RuntimeError, KeyError, TypeError):
        ok = False
    if not ok:
        with contextlib.suppress(OSError):
            path.unlink()  # a damaged, foreign or out-of-date entry is recomputed
        return None
    with contextlib.suppress(OSError):
        os.utime(path)  # recently used: kept by the size bound
    return _strip(ds)


def write_entry(path, ds, kind, inputs):
    """Write ``ds`` as the entry at ``path`` (atomically), with its request
    and checksum; then keep the cache within :func:`max_bytes`.  Errors (a
    full or unwritable cache) propagate: the caller warns and goes on."""
    from ._io import atomic_path, write_shielded

    path = Path(path)
    stored = ds.copy(deep=False)
    stored.attrs = {**ds.attrs, REQUEST_ATTR: request(kind, inputs), CHECKSUM_ATTR: checksum(ds)}
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path, overwrite=True) as tmp:  # our own cache
        write_shielded(lambda: stored.to_netcdf(tmp), tmp)
    bound(path.parent, keep=path)


def entries(folder):
    """The entries in ``folder`` (``KIND-HASH.nc`` files), oldest use first: list of (Path, bytes)."""
    from ._io import scan_folder

    found = []
    for e in scan_folder(folder):
        if _ENTRY.match(e.name) and e.is_file(follow_symlinks=False):
            with contextlib.suppress(OSError):
                st = e.stat(follow_symlinks=False)
                found.append((st.st_mtime, Path(e.path), st.st_size))
    return [(p, n) for _, p, n in sorted(found)]


def bound(folder, keep=None, limit=None):
    """Remove the least recently used entries until the cache holds at most
    ``limit`` bytes (default :func:`max_bytes`); never ``keep``.  Returns the removed paths."""
    limit = max_bytes() if limit is None else limit
    found = entries(folder)
    total = sum(n for _, n in found)
    removed = []
    for p, n in found:
        if total <= limit:
            break
        if keep is not None and p == Path(keep):
            continue
        with contextlib.suppress(OSError):
            p.unlink()
            total -= n
            removed.append(p)
    return removed


def clear(folder):
    """Remove every entry of the cache in ``folder`` (and temporaries of killed
    writers); nothing else.  Returns (entries removed, bytes freed)."""
    from ._io import clean_stale_temporaries

    found = entries(folder)
    n = freed = 0
    for p, size in found:
        with contextlib.suppress(OSError):
            p.unlink()
            n += 1
            freed += size
    clean_stale_temporaries(folder)
    return n, freed
