"""Safe file output: nothing replaced without asking, nothing half-written, no stray temporaries.

Every file or store the package writes goes through :func:`atomic_path`:

- It is written under a hidden temporary name beside the target and renamed
  when complete, so the target is either the old one or the whole new one.
  The temporary name carries this host and process
  (``.NAME.sb<host>p<pid>r<random>.part.SUFFIX``), so a later run can tell
  the temporaries of a killed process (the owner is dead on this host) from
  those of a live one, and removes only the former, only ours.
- An existing target is replaced only with ``overwrite=True`` (``--force``
  on the command line); a folder is replaced only when it is one of our own
  outputs (a Zarr store carrying ``stairbounce_version`` or the tile format
  marker), never any other folder, and never a store another process holds
  the lock of.

:func:`store_lock` is the exclusive lock of a store: a lock file created with
``O_EXCL`` beside it, holding the owner's host, pid and a token.  A lock whose
owner is dead on this host is stale and is taken over; any other lock is a
refusal naming the holder.  The store folder itself is locked too, by its
device and inode (``flock`` on the folder): every name of it (a bind mount, a
symlink, a hard link) is the same inode, so a second writer is refused
whatever name it uses (report round 3, R11).

Nothing here imports more than the standard library (but :func:`read_dataset`,
which imports xarray when called).
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import re
import secrets
import shutil
import socket
import time
import zlib
from pathlib import Path

__all__ = [
    "atomic_path",
    "check_output",
    "is_our_output",
    "store_lock",
    "lock_holder",
    "OutputExistsError",
    "StoreLockedError",
    "StoreReplacedError",
    "clean_stale_temporaries",
    "check_input",
    "read_dataset",
    "suffix_of",
]


class OutputExistsError(ValueError):
    """The output path exists and replacing it was not asked for (or is not allowed)."""


class StoreLockedError(ValueError):
    """Another live process holds the lock of a store."""


class StoreReplacedError(ValueError):
    """The store a writer opened is no longer the one at its path."""


FORCE_HINT = "give --force (overwrite=True in Python) to replace it"


def _host_tag(host=None):
    # a hostname may hold dots and dashes: the temporary names carry a hash
    return format(zlib.crc32((host or socket.gethostname()).encode()), "08x")


_TEMP = re.compile(r"^\.(?P<name>.+)\.sb(?P<host>[0-9a-f]{8})p(?P<pid>\d+)r[0-9a-z]+\.part(\.[^./]*)?$")


def _temp_path(path, kind="new"):
    path = Path(path)
    suffix = path.suffix
    rand = secrets.token_hex(4) + ("o" if kind == "old" else "")
    return path.with_name(f".{path.name}.sb{_host_tag()}p{os.getpid()}r{rand}.part{suffix}")


def _pid_alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # alive, another user's
        return True
    except OverflowError:
        return False
    return True


def _process_start(pid):
    """Start time (epoch seconds) of a process, None where it cannot be told."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        ticks = int(fields[19])  # field 22 of stat, counted after the command name
        with open("/proc/stat") as f:
            boot = next(int(line.split()[1]) for line in f if line.startswith("btime"))
        return boot + ticks / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError, StopIteration):
        return None


def _owner_gone(host, pid, since):
    """Whether the process ``pid`` on ``host`` that made something at time
    ``since`` is certainly gone: only decidable on this host."""
    if host != _host_tag():
        return False
    if pid == os.getpid():
        return False
    if not _pid_alive(pid):
        return True
    start = _process_start(pid)
    # the pid was reused by a process started after the thing was made
    return start is not None and since is not None and start > since + 1.0


def scan_folder(folder):
    """scan_folder(folder) -> list of os.DirEntry

    The entries of ``folder`` (:func:`os.scandir`), none where it cannot be
    read (missing, not a folder, no permission).
    """
    try:
        return list(os.scandir(folder))
    except OSError:
        return []


def clean_stale_temporaries(folder):
    """clean_stale_temporaries(folder) -> list of Path

    Remove the temporaries (``.NAME.sb<host>p<pid>r<random>.part.SUFFIX``) in
    ``folder`` that a killed process of this host left behind: the owner pid is
    dead, or was reused by a process started after the temporary was last
    written.  Temporaries of other hosts and of live processes are kept; so is
    everything whose name is not ours.  Returns what was removed.
    """
    removed = []
    for entry in scan_folder(folder):
        m = _TEMP.match(entry.name)
        if m is None:
            continue
        try:
            since = entry.stat(follow_symlinks=False).st_mtime
        except OSError:
            continue
        if not _owner_gone(m["host"], int(m["pid"]), since):
            continue
        try:
            if entry.is_dir(follow_symlinks=False):
                shutil.rmtree(entry.path)
            else:
                os.unlink(entry.path)
            removed.append(Path(entry.path))
        except OSError:
            pass  # another cleaner got there first, or we may not: leave it
    return removed


# --------------------------------------------------------------------------- #
# What is ours                                                                #
# --------------------------------------------------------------------------- #


def _json(path):
    try:
        with open(path, "rb") as f:
            return json.loads(f.read(1 << 20))
    except (OSError, ValueError):
        return None


def is_our_output(path):
    """is_our_output(path) -> bool

    Whether the folder ``path`` is a store this package wrote: a Zarr group
    (format 3 ``zarr.json`` or format 2 ``.zattrs``) whose attributes carry
    ``stairbounce_version``, or a tiled store (its ``tiles`` group carries a
    ``stairbounce-atlas`` format marker).
    """
    path = Path(path)
    if not path.is_dir() or path.is_symlink():
        return False
    root = _json(path / "zarr.json")
    attrs = (root or {}).get("attributes") if isinstance(root, dict) else None
    if attrs is None:
        attrs = _json(path / ".zattrs")
    if isinstance(attrs, dict) and "stairbounce_version" in attrs:
        return True
    tiles = _json(path / "tiles" / "zarr.json") or {}
    marker = tiles.get("attributes", {}).get("format", "") if isinstance(tiles, dict) else ""
    return isinstance(marker, str) and marker.startswith("stairbounce-atlas")


def check_store_metadata(path, what="a scan"):
    """check_store_metadata(path, what="a scan") -> None

    Refuse a Zarr store folder whose arrays or groups have lost their
    metadata: a sub-folder (not hidden) of the store or of one of its groups
    without ``zarr.json`` (or format 2's ``.zarray``/``.zgroup``).  Zarr
    and xarray skip such a folder silently, so its variable was missing
    further on, a traceback (report round 3, R9: ``status/zarr.json``
    deleted).  ``ValueError`` names the store and the array.  Every reader
    of a store calls this first (:func:`stairbounce.plane.load`, ``render``,
    :func:`stairbounce.atlas.scan_to_zarr` on resume).
    """
    root = Path(path)
    if not root.is_dir():
        return
    todo = [root]
    while todo:
        folder = todo.pop()
        try:
            entries = sorted(os.scandir(folder), key=lambda d: d.name)
        except OSError:
            return  # unreadable: the reader says why
        for d in entries:
            if d.name.startswith(".") or not d.is_dir():
                continue
            sub = Path(d.path)
            meta = _json(sub / "zarr.json")
            if meta is None and not ((sub / ".zarray").exists() or (sub / ".zgroup").exists()):
                name = sub.relative_to(root).as_posix()
                raise ValueError(
                    f"cannot read {path} as {what}: the store is damaged, its array {name!r} has lost "
                    f"its metadata ({name}/zarr.json is missing or unreadable); write it again to a new path"
                )
            if isinstance(meta, dict) and meta.get("node_type") == "group":
                todo.append(sub)  # an array's folder holds its chunks (c/...): not looked into


# --------------------------------------------------------------------------- #
# Names and inputs                                                            #
# --------------------------------------------------------------------------- #


def suffix_of(path, allowed, name="path"):
    """suffix_of(path, allowed, name="path") -> str

    The suffix of ``path`` among ``allowed`` (lower-case, with the dot), case
    ignored (``X.GEOJSON`` is ``.geojson``; a trailing ``/`` of a store folder
    ignored): the one rule of every writer and reader that picks its format by
    the name, checked before any work.  ``ValueError`` naming ``name`` and the
    suffixes allowed otherwise.
    """
    suffix = Path(str(path).rstrip("/") or str(path)).suffix.lower()
    if suffix not in allowed:
        choices = ", ".join(allowed[:-1]) + f" or {allowed[-1]}" if len(allowed) > 1 else allowed[0]
        raise ValueError(f"{name} must end in {choices}, got {str(path)!r}")
    return suffix


def check_input(path, allowed, name="path"):
    """check_input(path, allowed, name="path") -> str: the suffix

    Refuse, before opening it, an input that cannot be read as its suffix
    says (:func:`suffix_of`): a missing path, anything that is not a regular
    file or a folder (a FIFO would block the reader forever, a device read
    without end), a folder named as a file format (``.nc``) or a file named
    as a store (``.zarr``).  ``ValueError`` naming the path and the reason.
    """
    import stat

    suffix = suffix_of(path, allowed, name)
    try:
        mode = os.stat(path).st_mode
    except OSError as exc:
        raise ValueError(f"cannot read {path}: {(exc.strerror or str(exc)).lower()}") from None
    if not (stat.S_ISREG(mode) or stat.S_ISDIR(mode)):
        raise ValueError(f"cannot read {path}: not a regular file or a folder")
    if suffix == ".zarr" and not stat.S_ISDIR(mode):
        raise ValueError(f"cannot read {path}: a file, not a Zarr store (a folder)")
    if suffix != ".zarr" and stat.S_ISDIR(mode):
        raise ValueError(f"cannot read {path}: a folder, not a {suffix} file")
    return suffix


def checksum(path):
    """checksum(path) -> str: the SHA-256 (hex) of a file, or of a folder's files
    (each one's path relative to the folder, then its bytes, in sorted order)."""
    import hashlib

    h = hashlib.sha256()
    path = Path(path)
    files = [path] if path.is_file() else sorted(p for p in path.rglob("*") if p.is_file())
    for f in files:
        if f != path:
            h.update(f.relative_to(path).as_posix().encode() + b"\0")
        with open(f, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                h.update(block)
    return h.hexdigest()


def read_dataset(path, what, allowed=(".nc", ".zarr")):
    """read_dataset(path, what, allowed=(".nc", ".zarr")) -> xarray.Dataset, loaded

    Read a netCDF file or a Zarr store whole (checked first by
    :func:`check_input`; a store's lost metadata by
    :func:`check_store_metadata`), the file closed again.  Every failure of
    the reading libraries (a truncated or flipped file, a garbled chunk,
    another format under the name) is a ``ValueError`` "cannot read PATH as
    WHAT: reason", one line: never "cannot write", never a traceback.
    """
    import xarray as xr

    suffix = check_input(path, allowed)
    if suffix == ".zarr":
        check_store_metadata(path, what)
    try:
        if suffix == ".zarr":
            with xr.open_zarr(path, consolidated=False) as f:
                return f.load()
        with xr.open_dataset(path, engine="netcdf4") as f:
            return f.load()
    except MemoryError:
        raise
    except Exception as exc:  # the libraries' own errors: OSError, RuntimeError (codecs), ValueError, KeyError
        reason = " ".join(str(exc).split())[:300] or type(exc).__name__
        raise ValueError(f"cannot read {path} as {what}: {reason}") from None


# --------------------------------------------------------------------------- #
# Checks before the work                                                      #
# --------------------------------------------------------------------------- #


def _folder(path):
    return path.parent if str(path.parent) else Path(".")


def _probe_writable(folder):
    """Create and remove a file in ``folder`` (root ignores mode bits): None or the reason."""
    probe = _temp_path(Path(folder) / "probe")
    try:
        fd = os.open(probe, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600)
    except OSError as exc:
        return (exc.strerror or str(exc)).lower()
    os.close(fd)
    with contextlib.suppress(OSError):
        os.unlink(probe)
    return None


def check_output(path, overwrite=False, option=None):
    """check_output(path, overwrite=False, option=None) -> Path

    Refuse, before any work, an output path that cannot or must not be written.

    The folder must exist and accept a new file (tried, not guessed from mode
    bits).  An existing file is replaced only with ``overwrite``; an existing
    folder only with ``overwrite`` and when it is one of our own stores
    (:func:`is_our_output`) that no live process holds (:func:`store_lock`).
    ``option`` (e.g. ``"--png"``) prefixes the messages.

    Raises
    ------
    ValueError
        Naming the path and the reason (:class:`OutputExistsError` when it
        exists, :class:`StoreLockedError` when another process writes it).
    """
    path = Path(path)
    where = f"{option} " if option else ""
    folder = _folder(path)
    if not folder.is_dir():
        raise ValueError(f"cannot write {where}{path}: folder {folder} does not exist")
    if os.path.lexists(path):
        if path.is_dir() and not is_our_output(os.path.realpath(path)):
            # a folder, or a symlink to one, that is not one of our stores
            link = " (a symlink to a folder)" if path.is_symlink() else ""
            raise OutputExistsError(
                f"{where}{path} is an existing folder{link} that stairbounce did not write: "
                "it is never replaced; choose another path"
            )
        if path.is_dir():  # a store, or a symlink to one: its writer's lock (resolved)
            holder = lock_holder(path)
            if holder is not None:
                raise StoreLockedError(f"cannot replace {path}: {_describe(holder)}")
        if not overwrite:
            raise OutputExistsError(f"{where}{path} exists: not replaced; {FORCE_HINT}")
    reason = _probe_writable(folder)
    if reason is not None:
        raise ValueError(f"cannot write {where}{path}: {reason} ({folder})")
    return path


@contextlib.contextmanager
def atomic_path(path, overwrite=False):
    """atomic_path(path, overwrite=False) -> context manager yielding a temporary Path

    Write ``path`` under a temporary name beside it (same suffix, so writers
    that infer the format from the name still do); on success rename it to
    ``path``, on any error or interrupt remove it.

    The target is checked first with :func:`check_output` (an existing file
    needs ``overwrite``; a folder must also be one of our own stores), and
    again just before the rename, so a target that appeared meanwhile is not
    replaced either.  Stale temporaries of killed processes in the same folder
    are removed (:func:`clean_stale_temporaries`).  Works for files and for
    folders (a ``.zarr`` store).
    """
    path = Path(path)
    check_output(path, overwrite)
    clean_stale_temporaries(_folder(path))
    tmp = _temp_path(path)
    try:
        try:
            yield tmp
        except OSError as exc:
            if exc.filename is None or str(exc.filename) == str(tmp):
                exc.filename = str(path)  # a full disk names the file asked for, not our temporary
            raise
        except RuntimeError as exc:
            if str(exc).startswith("NetCDF:"):  # netCDF4 reports a full disk so (report N5, N6)
                raise _netcdf_os_error(exc, path) from None
            raise
        if not os.path.lexists(tmp):
            raise FileNotFoundError(f"the writer of {path} left no file at {tmp}")
        if os.path.lexists(path):
            check_output(path, overwrite)
        _replace(tmp, path)
    except BaseException:
        _remove(tmp, settle=True)
        raise


def write_shielded(write, tmp):
    """Call ``write()``, which writes the temporary ``tmp`` of :func:`atomic_path`,
    so that Ctrl-C cannot land inside the writer
    (:func:`stairbounce._interrupt.run_shielded`): a file's writer is left behind
    at once and removes ``tmp`` when it ends; a folder's (Zarr) is waited for."""
    from ._interrupt import run_shielded

    folder = Path(tmp).suffix.lower() == ".zarr"
    return run_shielded(write, wait=folder, cleanup=lambda: _remove(tmp, settle=folder))


def _netcdf_os_error(exc, path):
    """The OSError behind a netCDF4 ``RuntimeError("NetCDF: HDF error")``: a
    full disk (ENOSPC, when under 1 MiB is left, the temporary still in
    place) or an input/output error naming the library's message."""
    try:
        st = os.statvfs(_folder(Path(path)))
        full = st.f_bavail * st.f_frsize < (1 << 20)
    except OSError:
        full = False
    if full:
        return OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
    return OSError(errno.EIO, f"the netCDF library could not write it ({exc})", str(path))


def _remove(p, settle=False):
    if os.path.isdir(p) and not os.path.islink(p):
        # after a failed write (``settle``) the writer's pending asynchronous
        # chunk writes (Zarr) may recreate the folder just after it is removed
        # (report N6): remove until it stays gone
        for _ in range(20 if settle else 1):
            shutil.rmtree(p, ignore_errors=True)
            if not settle:
                break
            time.sleep(0.05)
            if not os.path.lexists(p):
                break
    elif os.path.lexists(p):
        with contextlib.suppress(OSError):
            os.unlink(p)


def _replace(tmp, path):
    """Rename ``tmp`` to ``path``; a folder on either side is moved aside first
    (rename cannot replace it) and removed only once the new one is in place."""
    both_files = not os.path.isdir(tmp) and not (os.path.isdir(path) and not os.path.islink(path))
    if both_files or not os.path.lexists(path):
        os.replace(tmp, path)
        return
    old = _temp_path(path, kind="old")
    os.rename(path, old)
    try:
        os.rename(tmp, path)
    except BaseException:
        os.rename(old, path)
        raise
    _remove(old)


# --------------------------------------------------------------------------- #
# Exclusive lock of a store                                                   #
# --------------------------------------------------------------------------- #


def lock_file(path):
    """The lock file of the store ``path``: ``.NAME.lock`` beside the store
    the path names, symlinks resolved (report N3: a symlinked name took a
    lock of its own, so two writers ran at once)."""
    path = Path(os.path.realpath(path))
    return path.with_name(f".{path.name}.lock")


def _read_lock(lock):
    info = _json(lock)
    return info if isinstance(info, dict) else None


def _describe(info):
    since = info.get("since")
    when = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(since)) if isinstance(since, (int, float)) else "?"
    return (
        f"another stairbounce process writes it (pid {info.get('pid')} on host "
        f"{info.get('hostname')}, since {when}; lock {info.get('lock')})"
    )


def _inode_lock(path):
    """An open descriptor of the folder ``path`` holding an exclusive
    ``flock`` on it (its device and inode, whatever its name), None where the
    folder does not exist or cannot be locked (no ``flock`` here); raises
    :class:`StoreLockedError` when another descriptor holds it."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not a POSIX system
        return None
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError:
        return None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        st = os.fstat(fd)
        os.close(fd)
        raise StoreLockedError(
            f"cannot write {path}: another stairbounce process writes this store (the folder of "
            f"device {st.st_dev}, inode {st.st_ino}), under this name or another one (a bind "
            "mount, symlink or hard link of it)"
        ) from None
    except OSError:  # a file system without flock: the lock file beside the store still holds
        os.close(fd)
        return None
    return fd


def _inode_held(path):
    """Whether another descriptor holds the folder lock of the store ``path``."""
    try:
        fd = _inode_lock(path)
    except StoreLockedError:
        return True
    if fd is not None:
        os.close(fd)  # closing releases the flock taken just now
    return False


# the folder locks taken for each owner token of store_lock (lock_store_folder)
_FOLDER_LOCKS: dict[str, list[int]] = {}


def lock_store_folder(path, owner):
    """Lock the folder of the store ``path`` by its device and inode for the
    holder ``owner`` of its :func:`store_lock` (done on entering when the
    store exists; a scan that creates it calls this once it is made); released
    when the ``store_lock`` block is left."""
    fd = _inode_lock(path)
    if fd is not None:
        _FOLDER_LOCKS.setdefault(owner, []).append(fd)


def lock_holder(path):
    """lock_holder(path) -> dict or None

    The live holder of the lock of the store ``path`` (``pid``, ``hostname``,
    ``since``, ``owner``, ``lock``), or None when it is free or stale.  The
    folder held under another name (device and inode) counts as held.
    """
    info = _named_holder(path)
    if info is None and os.path.isdir(path) and _inode_held(path):
        st = os.stat(path)
        return {"pid": "?", "hostname": "?", "since": None, "owner": None,
                "lock": f"the folder itself, device {st.st_dev}, inode {st.st_ino}, under another name"}
    return info


def _named_holder(path):
    """The live holder of the lock file beside the store ``path`` (:func:`lock_holder`)."""
    lock = lock_file(path)
    info = _read_lock(lock)
    if info is None:
        try:
            age = time.time() - os.stat(lock).st_mtime
        except OSError:
            return None
        if age > 10.0:
            return None  # garbage, or its writer was killed between create and write
        # being written this instant: count it as held
        return {"pid": "?", "hostname": "?", "since": None, "owner": None, "lock": str(lock)}
    try:
        pid = int(info.get("pid", -1))
    except (TypeError, ValueError):
        pid = -1
    if pid < 0 or _owner_gone(info.get("host"), pid, info.get("since")):
        return None
    info["lock"] = str(lock)
    return info


def _take_over_stale(lock, seen):
    """Remove the stale lock ``lock`` whose content was ``seen``; one process
    at a time (an O_EXCL breaker file), and only if it still holds ``seen``."""
    breaker = lock.with_name(lock.name + ".break")
    try:
        fd = os.open(breaker, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
    except FileExistsError:
        with contextlib.suppress(OSError):
            if time.time() - breaker.stat().st_mtime > 10.0:
                breaker.unlink()  # a breaker killed within its few microseconds
        return
    try:
        os.close(fd)
        if _read_lock(lock) == seen:
            lock.unlink()
    finally:
        with contextlib.suppress(OSError):
            breaker.unlink()


@contextlib.contextmanager
def store_lock(path):
    """store_lock(path) -> context manager yielding the lock's owner token (str)

    Hold the exclusive lock of the store ``path`` while the block runs.

    The lock file (``.NAME.lock`` beside the store) is created with
    ``O_CREAT | O_EXCL`` and holds this host, pid, start time and a fresh
    token; it is removed on leaving.  A lock left by a dead process of this
    host is taken over; a live one (or one of another host: whether it lives
    cannot be told from here) raises :class:`StoreLockedError` naming the holder.
    An existing store's folder is locked too, by its device and inode
    (:func:`lock_store_folder`): a writer under another name of the same
    folder (a bind mount) is refused.
    """
    path = Path(path)
    lock = lock_file(path)
    owner = secrets.token_hex(16)
    info = {
        "pid": os.getpid(),
        "host": _host_tag(),
        "hostname": socket.gethostname(),
        "since": time.time(),
        "owner": owner,
    }
    for _ in range(50):
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            seen = _read_lock(lock)
            if seen is None:
                time.sleep(0.02)  # the holder is writing it right now
                seen = _read_lock(lock)
            holder = lock_holder(path)
            if holder is not None:
                raise StoreLockedError(f"cannot write {path}: {_describe(holder)}") from None
            _take_over_stale(lock, seen)
            continue
        except OSError as exc:
            raise ValueError(f"cannot lock {path}: {(exc.strerror or str(exc)).lower()} ({lock})") from None
        with os.fdopen(fd, "w") as f:
            json.dump(info, f)
        break
    else:  # pragma: no cover - fifty takeovers lost in a row
        raise StoreLockedError(f"cannot write {path}: could not take its lock {lock}")
    try:
        lock_store_folder(path, owner)
        yield owner
    finally:
        for fd in _FOLDER_LOCKS.pop(owner, []):
            with contextlib.suppress(OSError):
                os.close(fd)
        if (_read_lock(lock) or {}).get("owner") == owner:
            with contextlib.suppress(OSError):
                lock.unlink()


def holds_lock(path, owner):
    """Whether the lock of the store ``path`` is held by the token ``owner``
    (checked by every tile before it writes: only the scan that holds the lock
    writes into the store)."""
    return (_read_lock(lock_file(path)) or {}).get("owner") == owner
