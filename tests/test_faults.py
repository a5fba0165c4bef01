"""Faults a careful user and a hostile input cause: the fast cases of the
reliability campaign (issue 17; the long runs are ``scripts/campaign_faults.py``).

- nothing the program did not write is ever deleted, nothing existing is
  replaced without ``--force`` / ``overwrite=True`` (campaign D1),
- two writers on one store: one wins, the other is refused, nothing is mixed (D2),
- a damaged store is found, said and repaired on resume; a garbled chunk is one
  line, never a traceback (D8),
- unwritable or full destinations, huge dpi or images, a closed pipe: one line,
  exit 2 (or a quiet exit), never a traceback (D7, D14),
- Ctrl-C: exit 130 even where Python loses the interrupt (D9),
- temporaries of killed processes are cleaned by the next run (D11).

Every expected answer here comes from the contract stated in
docs/guide/robustness.md ("Files, stores and interruptions: what is guaranteed"), not from the code's output.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import zarr

from stairbounce import _io, atlas
from stairbounce.atlas import scan_to_zarr, tiles_done
from stairbounce.plane import FILL_VALUES, load, save, scan

from ._cli import run_cli as run
from ._stores import StopAfter, stop_after

pytestmark = pytest.mark.filterwarnings("ignore:Port 8787 is already in use")

WINDOW = dict(e=(0.05, 0.95, 45), u=(0.1, 1.4, 38), max_iter=400)
TILE = 16  # 3 x 3 tiles
SCAN = ["scan", "--e", "0.05:0.95", "--u", "0.1:1.4", "--size", "45x38", "--max-iter", "400"]
EXE = str(Path(sys.executable).with_name("stairbounce"))


@pytest.fixture(scope="module")
def reference():
    return scan(**WINDOW)


def one_line_error(err):
    lines = err.strip().splitlines()
    return len(lines) == 1 and lines[0].startswith("stairbounce: error:") and "Traceback" not in err


def precious(folder):
    """A folder of the user's at an output path, with a file inside."""
    folder.mkdir(parents=True)
    (folder / "sub").mkdir()
    (folder / "sub" / "keep.txt").write_text("important")
    return folder


def intact(folder):
    return (folder / "sub" / "keep.txt").read_text() == "important"


def leftovers(folder):
    return sorted(p.name for p in Path(folder).iterdir() if ".part" in p.name or p.name.endswith(".lock"))


# --------------------------------------------------------------------------- #
# 1. Never delete what the program did not write; replace only with --force    #
# --------------------------------------------------------------------------- #

WRITERS = {
    # command line, the output path given as {path}
    "scan --out": ["scan", "--size", "12x8", "--max-iter", "50", "--out", "{path}"],
    "scan --png": ["scan", "--size", "12x8", "--max-iter", "50", "--png", "{path}"],
    "trajectory --out": ["trajectory", "--e", "0.05", "--u", "0.93", "--steps", "2", "--dpi", "20", "--out", "{path}"],
    "trajectory --animate": ["trajectory", "--e", "0.05", "--u", "0.93", "--steps", "1", "--dpi", "20",
                             "--out", "{dir}/t.png", "--animate", "{path}"],
    "orbit-diagram --out": ["orbit-diagram", "--e", "0.1", "--u", "0.3:1", "--n", "10", "--transient", "10",
                            "--keep", "5", "--out", "{path}"],
    "orbit-diagram --png": ["orbit-diagram", "--e", "0.1", "--u", "0.3:1", "--n", "10", "--transient", "10",
                            "--keep", "5", "--dpi", "20", "--png", "{path}"],
    "dimension --png": ["dimension", "--resolution", "32", "--max-iter", "50", "--dpi", "20", "--png", "{path}"],
}
SUFFIX = {"scan --out": ".zarr", "trajectory --animate": ".gif", "orbit-diagram --out": ".zarr"}


def _args(name, path):
    return [a.replace("{path}", str(path)).replace("{dir}", str(path.parent)) for a in WRITERS[name]]


@pytest.mark.parametrize("force", [False, True])
@pytest.mark.parametrize("name", list(WRITERS))
def test_a_folder_at_an_output_path_is_never_replaced(name, force, tmp_path, capsys):
    """Campaign D1, cases 56, 62, 112, 121, 196, 199: the folder and its
    contents survive, even with --force; one line, exit 2, nothing left."""
    target = precious(tmp_path / ("out" + SUFFIX.get(name, ".png")))
    code, _, err = run(_args(name, target) + (["--force"] if force else []), capsys)
    assert code == 2 and one_line_error(err), err
    assert "stairbounce did not write" in err and "never replaced" in err
    assert intact(target)
    assert leftovers(tmp_path) == []


@pytest.mark.parametrize("name", ["scan --out", "scan --png", "orbit-diagram --out", "dimension --png"])
def test_an_existing_file_is_replaced_only_with_force(name, tmp_path, capsys):
    suffix = {"scan --out": ".nc", "orbit-diagram --out": ".csv"}.get(name, ".png")
    target = tmp_path / ("old" + suffix)
    target.write_bytes(b"the user's old result")
    code, _, err = run(_args(name, target), capsys)
    assert code == 2 and one_line_error(err) and "exists: not replaced" in err and "--force" in err
    assert target.read_bytes() == b"the user's old result"
    code, out, err = run(_args(name, target) + ["--force"], capsys)
    assert code == 0, err
    assert target.read_bytes() != b"the user's old result"
    assert leftovers(tmp_path) == []


def test_refused_before_any_work(tmp_path, capsys, monkeypatch):
    """The output is checked before the scan runs (not after hours of it)."""
    from stairbounce import plane

    target = tmp_path / "old.nc"
    target.write_text("x")

    def no_scan(*a, **k):
        raise AssertionError("computed although the output was refused")

    monkeypatch.setattr(plane, "scan", no_scan)
    code, _, err = run(["scan", "--size", "12x8", "--out", target], capsys)
    assert code == 2 and "exists" in err


def test_scan_draws_its_picture_only_where_asked(tmp_path, capsys, monkeypatch):
    """scan.png is the default picture only when nothing else is asked for."""
    monkeypatch.chdir(tmp_path)
    assert run(["scan", "--size", "12x8", "--max-iter", "50", "--out", "a.nc"], capsys)[0] == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.nc"]
    assert run(["scan", "--size", "12x8", "--max-iter", "50"], capsys)[0] == 0
    assert (tmp_path / "scan.png").exists()
    code, _, err = run(["scan", "--size", "12x8", "--max-iter", "50"], capsys)
    assert code == 2 and "scan.png exists" in err


def test_a_tiled_atlas_is_not_replaced_by_a_forgotten_tile(tmp_path, capsys, reference):
    """Campaign 4.3 last row: `scan --out atlas.zarr` without --tile onto a
    finished atlas replaced it; now refused, and with --force only because
    the atlas is our own store."""
    store = tmp_path / "atlas.zarr"
    scan_to_zarr(store, tile=TILE, **WINDOW)
    code, _, err = run(["scan", "--size", "8x8", "--max-iter", "50", "--out", store], capsys)
    assert code == 2 and "exists: not replaced" in err
    xr.testing.assert_identical(load(store), reference)


def test_api_save_needs_overwrite_and_never_replaces_a_foreign_folder(tmp_path, reference):
    small = reference.isel(e=slice(0, 5))
    path = tmp_path / "s.zarr"
    save(small, path)
    with pytest.raises(_io.OutputExistsError, match="overwrite=True"):
        save(reference, path)
    assert load(path).sizes["e"] == 5
    save(reference, path, overwrite=True)  # our own store: replaced when asked
    assert load(path).sizes["e"] == 45
    mine = precious(tmp_path / "mine.zarr")
    with pytest.raises(ValueError, match="never replaced"):
        save(reference, mine, overwrite=True)
    assert intact(mine)
    assert leftovers(tmp_path) == []


def test_figures_never_replace_the_users_files(tmp_path, capsys):
    """Campaign case 246: a folder at f/fig3.png was deleted.  A file of the
    user's is kept without --force; the files of an earlier run (the folder
    holds its manifest) are replaced."""
    out = tmp_path / "f"
    precious(out / "fig3.png")
    code, _, err = run(["figures", "--only", "fig3", "--out", out, "--dpi", "20"], capsys)
    assert code == 2 and one_line_error(err) and intact(out / "fig3.png")
    code, _, err = run(["figures", "--only", "fig3", "--out", out, "--dpi", "20", "--force"], capsys)
    assert code == 2 and intact(out / "fig3.png")

    other = tmp_path / "g"
    other.mkdir()
    (other / "report.md").write_text("my notes")
    code, _, err = run(["figures", "--only", "fig3", "--out", other, "--dpi", "20"], capsys)
    assert code == 2 and "report.md exists" in err
    assert (other / "report.md").read_text() == "my notes"
    assert run(["figures", "--only", "fig3", "--out", other, "--dpi", "20", "--force"], capsys)[0] == 0
    # a rerun into a folder of our own needs no --force
    assert run(["figures", "--only", "fig3", "--out", other, "--dpi", "20"], capsys)[0] == 0


def test_is_our_output_reads_the_marker(tmp_path, reference):
    save(reference, tmp_path / "s.zarr")
    scan_to_zarr(tmp_path / "t.zarr", tile=TILE, **WINDOW)
    xr.Dataset({"x": ("a", np.arange(3))}).to_zarr(tmp_path / "foreign.zarr", consolidated=False)
    assert _io.is_our_output(tmp_path / "s.zarr")
    assert _io.is_our_output(tmp_path / "t.zarr")
    assert not _io.is_our_output(tmp_path / "foreign.zarr")
    assert not _io.is_our_output(precious(tmp_path / "p.zarr"))


# --------------------------------------------------------------------------- #
# 2. Two writers on one store                                                 #
# --------------------------------------------------------------------------- #


def test_a_live_lock_refuses_a_second_writer_naming_it(tmp_path):
    path = tmp_path / "a.zarr"
    with _io.store_lock(path) as owner:
        info = json.loads(_io.lock_file(path).read_text())
        assert info["pid"] == os.getpid() and info["owner"] == owner
        # another process of this host holds it (our parent is alive)
        info["pid"] = os.getppid()
        _io.lock_file(path).write_text(json.dumps(info))
        with pytest.raises(_io.StoreLockedError, match=rf"pid {os.getppid()} on host {socket.gethostname()}"):
            scan_to_zarr(path, tile=TILE, **WINDOW)
    assert not path.exists()


def dead_pid():
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


def test_a_stale_lock_is_taken_over_one_of_another_host_is_not(tmp_path, reference):
    path = tmp_path / "a.zarr"
    lock = _io.lock_file(path)
    stale = {"pid": dead_pid(), "host": _io._host_tag(), "hostname": socket.gethostname(),
             "since": time.time() - 60, "owner": "x"}
    lock.write_text(json.dumps(stale))
    ds = scan_to_zarr(path, tile=TILE, **WINDOW)
    xr.testing.assert_identical(ds.compute(), reference)
    assert not lock.exists()  # released
    remote = dict(stale, host=_io._host_tag("elsewhere"), hostname="elsewhere")
    lock.write_text(json.dumps(remote))
    with pytest.raises(_io.StoreLockedError, match="on host elsewhere"):
        scan_to_zarr(path, tile=TILE, **WINDOW)


def test_a_tile_writes_only_for_the_holder_of_the_lock(tmp_path):
    """On a cluster, a tile handed out by a scan that lost the lock (or by
    another client) does not write."""
    path = tmp_path / "a.zarr"
    with pytest.raises(StopAfter):
        scan_to_zarr(path, tile=TILE, progress=stop_after(0), **WINDOW)
    token = atlas._tile_record(path).attrs["token"]
    rows, cols = atlas.tile_slices(38, TILE), atlas.tile_slices(45, TILE)
    es = np.linspace(0, 0.5, 45)[cols[0]] + 0.01
    with _io.store_lock(path):
        with pytest.raises(RuntimeError, match="no longer holds the lock"):
            atlas._run_tile(str(path), token, "not-the-owner", 0, 0, rows[0], cols[0], es,
                            np.linspace(0.2, 1, 38)[rows[0]], 400, 1.0, 0.0, True, 1)
    assert not tiles_done(path).any()


@pytest.mark.slow
@pytest.mark.parametrize("stagger", [0.0, 0.3])
def test_two_processes_racing_on_one_store(tmp_path, stagger):
    """Campaign D2 / section 7: A (max_iter 400) and B (max_iter 300) started
    together on a new store.  Exactly one succeeds, the other is refused in one
    line, and the store is exactly the winner's scan, bit for bit."""
    path = tmp_path / "S.zarr"
    base = [EXE, *SCAN[:-1]]
    slow = {**os.environ, "NUMBA_NUM_THREADS": "1"}
    a = subprocess.Popen(base + ["400", "--tile", "8", "--out", str(path)], env=slow,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(stagger)
    b = subprocess.Popen(base + ["300", "--tile", "8", "--out", str(path)], env=slow,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    (_, err_a), (_, err_b) = a.communicate(timeout=300), b.communicate(timeout=300)
    codes = sorted([a.returncode, b.returncode])
    assert codes == [0, 2], (err_a, err_b)
    loser = err_a if a.returncode == 2 else err_b
    assert one_line_error(loser)
    assert ("another stairbounce process writes it" in loser) or ("holds a different scan" in loser)
    winner = 400 if a.returncode == 0 else 300
    stored = xr.open_zarr(path, consolidated=False).compute()
    assert stored.attrs["max_iter"] == winner
    xr.testing.assert_identical(stored, scan(**dict(WINDOW, max_iter=winner)))
    assert tiles_done(path).all()
    assert leftovers(tmp_path) == []


def test_unreachable_scheduler_fails_before_the_store_exists(tmp_path, capsys):
    """Campaign D14: a closed port made the store, then failed after 30 s."""
    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    path = tmp_path / "a.zarr"
    code, _, err = run(SCAN + ["--scheduler", f"tcp://127.0.0.1:{port}", "--out", path], capsys)
    assert code == 2 and one_line_error(err) and "cannot reach the Dask scheduler" in err
    assert list(tmp_path.iterdir()) == []


# --------------------------------------------------------------------------- #
# 3. A damaged store                                                          #
# --------------------------------------------------------------------------- #


@pytest.fixture
def store(tmp_path):
    path = tmp_path / "a.zarr"
    scan_to_zarr(path, tile=TILE, **WINDOW)
    return path


def chunk(path, var, i, j):
    return Path(path) / var / "c" / str(i) / str(j)


def test_a_missing_chunk_reads_as_no_result_not_as_found(store, reference):
    """Campaign D8: a deleted status chunk read as 0, 'solution found'."""
    chunk(store, "status", 1, 2).unlink()
    back = load(store)
    region = back["status"].values[16:32, 32:45]
    assert (region == FILL_VALUES["status"]).all()
    assert not np.isin(FILL_VALUES["status"], [0, 1])  # neither 'found' nor 'not found'
    assert (back["status"].values[:16] == reference["status"].values[:16]).all()


def test_a_saved_zarr_scan_has_the_same_fill_values(tmp_path, reference):
    path = tmp_path / "s.zarr"
    save(reference, path, chunks=16)
    chunk(path, "word_length", 0, 0).unlink()
    assert (load(path)["word_length"].values[:16, :16] == -1).all()


@pytest.mark.parametrize("damage", ["delete", "truncate", "garble", "delete-flagged-data"])
def test_damaged_tiles_are_found_said_and_recomputed(store, reference, damage):
    if damage == "delete":
        chunk(store, "status", 1, 2).unlink()
    elif damage == "truncate":
        chunk(store, "word_length", 0, 1).write_bytes(b"")
    elif damage == "garble":
        c = chunk(store, "period", 2, 0)
        raw = bytearray(c.read_bytes())
        raw[len(raw) // 2:] = os.urandom(len(raw) - len(raw) // 2)
        c.write_bytes(bytes(raw))
    else:  # a chunk of a tile whose values differ but still decode
        z = zarr.open_group(str(store), mode="r+")
        z["impacts"][0:16, 0:16] = 7
    with pytest.warns(RuntimeWarning, match=r"1 complete tile\(s\) .* computed again"):
        ds = scan_to_zarr(store, tile=TILE, **WINDOW)
    xr.testing.assert_identical(ds.compute(), reference)


def test_garbled_chunk_is_one_line_in_load_and_render_and_the_rerun_repairs(store, tmp_path, capsys, reference):
    chunk(store, "word_length", 1, 1).write_bytes(b"\x28\xb5\x2f\xfd garbage")
    with pytest.raises(ValueError, match="cannot read .*a.zarr as a scan"):
        load(store)
    code, _, err = run(["render", store, "--png", tmp_path / "r.png"], capsys)
    assert code == 2 and one_line_error(err) and "damaged" in err, err
    code, out, err = run(SCAN + ["--tile", TILE, "--out", store], capsys)
    assert code == 0, err
    assert err.strip().splitlines() == [line for line in err.strip().splitlines() if line.startswith("stairbounce: warning:")]
    assert "1 complete tile(s)" in err and "(8 already complete)" in out
    xr.testing.assert_identical(load(store), reference)


def test_a_store_of_the_old_format_is_refused_not_mixed(store):
    z = zarr.open_group(str(store), mode="r+")
    z["tiles"].attrs["format"] = "stairbounce-atlas-1"
    with pytest.raises(ValueError, match="another format .* not resumed"):
        scan_to_zarr(store, tile=TILE, **WINDOW)


# --------------------------------------------------------------------------- #
# 8 and 14. One line, exit 2, never a traceback                                #
# --------------------------------------------------------------------------- #


@pytest.mark.parametrize(
    "args, needle",
    [
        (["scan", "--size", "12x8", "--png", "/proc/x.png"], "cannot write --png /proc/x.png"),
        (["scan", "--size", "12x8", "--out", "/proc/x.nc"], "cannot write --out /proc/x.nc"),
        (["trajectory", "--e", "0.05", "--u", "0.93", "--out", "/proc/x.png"], "cannot write --out"),
        (["orbit-diagram", "--e", "0.1", "--u", "0.3:1", "--out", "/proc/x.nc"], "cannot write --out"),
        (["dimension", "--resolution", "16", "--png", "/proc/x.png"], "cannot write --png"),
        (["render", "{store}", "--png", "/proc/x.png"], "cannot write --png"),
        (["figures", "--only", "fig3", "--out", "/proc/figs"], "/proc/figs"),
        (["trajectory", "--e", "0.05", "--u", "0.93", "--dpi", "5"], "--dpi must be in [10, 1200]"),
        (["trajectory", "--e", "0.05", "--u", "0.93", "--dpi", "100000"], "--dpi must be in [10, 1200]"),
        (["orbit-diagram", "--e", "0.1", "--u", "0.3:1", "--png", "x.png", "--dpi", "100000"], "--dpi must be in"),
        (["dimension", "--dpi", "100000"], "--dpi must be in"),
        (["figures", "--only", "fig4", "--max-iter", "3000000000"], "--max-iter must be an integer >= 1 and <= 2147483647"),
    ],
)
def test_unwritable_destinations_and_absurd_sizes_are_one_line(args, needle, tmp_path, capsys, monkeypatch, store):
    monkeypatch.chdir(tmp_path)
    code, _, err = run([a.replace("{store}", str(store)) for a in args], capsys)
    assert code == 2 and one_line_error(err), err
    assert needle in err
    assert leftovers(tmp_path) == []


def test_memory_error_and_os_error_are_one_line(tmp_path, capsys, monkeypatch):
    """Whatever command runs out of memory or space: one line, exit 2."""
    import errno

    from stairbounce.cli import model_commands

    def full(*a, **k):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(model_commands, "iterate", full)
    code, _, err = run(["map", "--e", "0.1", "--u", "0.9"], capsys)
    assert code == 2 and one_line_error(err) and "no space left on device" in err

    def huge(*a, **k):
        raise MemoryError("std::bad_alloc")

    monkeypatch.setattr(model_commands, "iterate", huge)
    code, _, err = run(["map", "--e", "0.1", "--u", "0.9"], capsys)
    assert code == 2 and one_line_error(err) and "not enough memory" in err


def test_a_decompression_bomb_is_one_line(tmp_path, capsys, monkeypatch):
    """Campaign case 227 (a 20000 x 20000 PNG), scaled down: PIL refuses an
    image over twice its pixel limit."""
    from PIL import Image

    Image.new("L", (100, 100)).save(tmp_path / "big.png")
    monkeypatch.setattr(Image, "MAX_IMAGE_PIXELS", 1000)
    code, _, err = run(["dimension", "--image", tmp_path / "big.png"], capsys)
    assert code == 2 and one_line_error(err) and "cannot read" in err


def test_closed_pipe_ends_quietly_full_stdout_is_one_line():
    """`map --csv | head -1` and `map > /dev/full` (campaign D14)."""
    p = subprocess.Popen([EXE, "map", "--e", "0.1", "--u", "0.9", "--steps", "20000", "--csv"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    p.stdout.readline()
    p.stdout.close()
    err = p.stderr.read().decode()
    p.wait(timeout=120)
    assert p.returncode == 141 and err == "", err
    if not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full on this system")
    with open("/dev/full", "w") as full:
        r = subprocess.run([EXE, "map", "--e", "0.1", "--u", "0.9"], stdout=full, stderr=subprocess.PIPE, text=True)
    assert r.returncode == 2 and one_line_error(r.stderr) and "no space left" in r.stderr, r.stderr


def test_unwritable_cache_computes_the_figures_with_one_warning(tmp_path, capsys):
    """Campaign cases 244/245: a cache that cannot be written failed fig4."""
    afile = tmp_path / "afile"
    afile.write_text("x")
    for cache in ("/proc/cache", afile):
        out = tmp_path / f"f{len(str(cache))}"
        code, _, err = run(["figures", "--only", "fig4", "--out", out, "--scale", "0.05", "--dpi", "20",
                            "--cache-dir", cache], capsys)
        assert code == 0, err
        warnings_ = [line for line in err.splitlines() if "warning" in line]
        assert len(warnings_) == 1 and "computing without it" in warnings_[0]
        assert (out / "fig4.png").exists()


@pytest.fixture(scope="module")
def tmpfs(tmp_path_factory):
    """A 1 MiB file system, where this machine lets us mount one (root)."""
    d = tmp_path_factory.mktemp("full")
    if os.geteuid() != 0:
        pytest.skip("mounting a small tmpfs needs root")
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m", "tmpfs", str(d)], capture_output=True, text=True)
    if r.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {r.stderr.strip()}")
    yield d
    subprocess.run(["umount", str(d)], check=False)


def test_full_disk_is_one_line_and_leaves_nothing(tmpfs, capsys):
    """Campaign 4.4: ENOSPC tracebacks; now one line and no partial file."""
    filler = tmpfs / "filler"
    with open(filler, "wb") as f:
        try:
            f.write(b"\0" * (2 << 20))
        except OSError:
            pass
    try:
        code, _, err = run(["scan", "--size", "300x200", "--max-iter", "20", "--png", tmpfs / "s.png"], capsys)
        assert code == 2 and one_line_error(err), err
        code, _, err = run(["scan", "--size", "300x200", "--max-iter", "20", "--out", tmpfs / "s.zarr"], capsys)
        assert code == 2 and one_line_error(err), err
        assert sorted(p.name for p in tmpfs.iterdir()) == ["filler"]
    finally:
        filler.unlink()


# --------------------------------------------------------------------------- #
# 9. Ctrl-C                                                                   #
# --------------------------------------------------------------------------- #


def test_an_interrupt_python_lost_still_exits_130(tmp_path, capsys, monkeypatch):
    """Campaign D9: a KeyboardInterrupt raised inside a weakref callback is
    swallowed by Python, and `figures` wrote everything and exited 0.  The
    Ctrl-C handler records the interrupt; the command stops at the next
    figure and exits 130."""
    from stairbounce import figures
    from stairbounce.cli import _app

    made = []
    real = figures.FIGURES["fig3"]

    def lost_interrupt(settings):
        _app.INTERRUPTED.set()  # what the handler does before raising ...
        made.append("fig3")
        return real(settings)  # ... and the KeyboardInterrupt is lost

    monkeypatch.setitem(figures.FIGURES, "fig3", lost_interrupt)
    code, _, err = run(["figures", "--only", "fig3,fig4", "--out", tmp_path / "f", "--dpi", "20",
                        "--scale", "0.05", "--no-cache"], capsys)
    assert code == 130 and "interrupted" in err
    assert made == ["fig3"] and not (tmp_path / "f" / "fig4.png").exists()


def test_an_interrupted_figures_run_is_rerun_without_force(tmp_path, capsys, monkeypatch):
    """The folder of a run cut short holds a provisional manifest: it is ours,
    and the same command run again replaces its figures (campaign 4.1 reruns)."""
    from stairbounce import figures

    def interrupted(settings):
        raise KeyboardInterrupt

    out = tmp_path / "f"
    with monkeypatch.context() as m:
        m.setitem(figures.FIGURES, "fig4", interrupted)
        code, _, _ = run(["figures", "--only", "fig3,fig4", "--out", out, "--dpi", "20"], capsys)
    assert code == 130 and (out / "fig3.png").exists() and not (out / "report.md").exists()
    code, _, err = run(["figures", "--only", "fig3,fig4", "--out", out, "--dpi", "20", "--scale", "0.05",
                        "--no-cache"], capsys)
    assert code == 0, err
    assert json.loads((out / "manifest.json").read_text())["figures"][0]["name"] == "fig3"


# --------------------------------------------------------------------------- #
# 11. Temporaries of killed processes                                         #
# --------------------------------------------------------------------------- #

KILLED_WRITER = textwrap.dedent(
    """
    import os, signal, sys
    from stairbounce._io import atomic_path
    with atomic_path(sys.argv[1]) as png, atomic_path(sys.argv[2]) as store:
        png.write_text("half")
        store.mkdir()
        (store / "x").write_text("half")
        os.kill(os.getpid(), signal.SIGKILL)
    """
)


def test_temporaries_of_a_killed_process_are_cleaned_by_the_next_run(tmp_path, capsys):
    """Campaign D11: a SIGKILL left `.fig5c.<random>.part.png` and
    `.<name>.<random>.part.zarr` that reruns never removed."""
    r = subprocess.run([sys.executable, "-c", KILLED_WRITER, str(tmp_path / "p.png"), str(tmp_path / "s.zarr")])
    assert r.returncode == -signal.SIGKILL
    assert len(leftovers(tmp_path)) == 2
    # not ours by name, and a live process's temporary: both kept
    (tmp_path / ".notes.part.png").write_text("mine")
    live = tmp_path / f".q.png.sb{_io._host_tag()}p{os.getppid()}rabcd.part.png"
    live.write_text("being written")
    code, _, err = run(["scan", "--size", "8x8", "--max-iter", "20", "--png", tmp_path / "p.png"], capsys)
    assert code == 0, err
    assert leftovers(tmp_path) == sorted([".notes.part.png", live.name])


# --------------------------------------------------------------------------- #
# 9. Ctrl-C inside long numba kernels                                          #
# --------------------------------------------------------------------------- #


def test_sliced_orbit_kernel_is_bit_identical_to_the_plain_iteration():
    """The transient runs in slices of 2**16 steps that check the halt flag;
    the iterates are those of model.iterate (one _step after another), bit for
    bit, across slice boundaries and a remainder."""
    from stairbounce import orbits
    from stairbounce.model import iterate

    transient = 2 * orbits._SLICE + 17
    us = np.array([0.31, 0.62, 0.93])
    ds = orbits.orbit_diagram(0.1, us, y0=0.1, v0=0.0, transient=transient, keep=5)
    warm = orbits.orbit_diagram(0.1, us, y0=0.1, v0=0.0, transient=transient, keep=5, warm_start=True)
    y, v = 0.1, 0.0
    for i, u in enumerate(us):
        ys, vs, _ = iterate(0.1, 0.0, 0.1, u, transient + 5)
        np.testing.assert_array_equal(ds.y.values[i], ys[transient + 1:])
        np.testing.assert_array_equal(ds.v.values[i], vs[transient + 1:])
        ys, vs, _ = iterate(y, v, 0.1, u, transient + 5)
        np.testing.assert_array_equal(warm.y.values[i], ys[transient + 1:])
        y, v = ys[-1], vs[-1]


def test_kernels_return_at_once_when_halted_and_agree_when_not(reference):
    """A set halt flag stops the scan kernel before any pixel is written; a
    clear one changes nothing (the scan through the helper thread equals the
    kernel called in place)."""
    from stairbounce import plane

    # writeable copies: a coordinate's .values is read-only, and the kernel called with a
    # read-only array is another signature, compiled again (about 15 s)
    es, us = np.array(reference.e.values), np.array(reference.u.values)
    chunk, units = plane._chunking(es.size * us.size, 2)
    names = ("status", "word_length", "jumps", "period", "impacts")
    # pruned or not: a segment's listing answers pixels (pruned ones, those whose
    # first step slides), so the flag is read before the first listing
    for prune in (False, True):
        outs = [np.full(us.size * es.size, 99, dtype=reference[k].dtype) for k in names]
        plane._scan_fast(es, us, True, 400, 1.0, 0.0, prune, units, chunk, *outs, np.ones(1, np.int64))
        assert all((o == 99).all() for o in outs)
    for prune in (False, True):
        plane._scan_fast(es, us, True, 400, 1.0, 0.0, prune, units, chunk, *outs, np.zeros(1, np.int64))
        for o, k in zip(outs, names):
            np.testing.assert_array_equal(o.reshape(us.size, es.size), reference[k].values)


LONG_RUNS = {
    "orbit-diagram": ["orbit-diagram", "--e", "0.1", "--u", "0.3:1", "--n", "50",
                      "--transient", "1000000000000", "--png", "x.png"],
    # below the Corollary 2.1 curve, 796 of 4096 pixels never slide: 2e9 steps each, hours
    # (the window e 0.999:1, u 0:0.001 used here before is pruned or slides at once: it
    # finished in about 2 s once the kernel got faster, sometimes before the Ctrl-C)
    "scan": ["scan", "--e", "0.46:0.47", "--u", "0.25:0.26", "--size", "64x64",
             "--max-iter", "2000000000", "--png", "x.png"],
}


@pytest.mark.slow
@pytest.mark.parametrize("name", list(LONG_RUNS))
def test_ctrl_c_stops_a_long_kernel_with_130_and_no_file(name, tmp_path):
    """Campaign D9: both ran on 30 s after SIGINT.  Here SIGINT is sent once the
    kernel runs (its helper thread exists); the process must end with 130
    within a few seconds and leave nothing in the folder."""
    # Ctrl-C at its default in the child (an earlier test may leave it ignored
    # here, and a child inherits an ignored SIGINT)
    p = subprocess.Popen([EXE, *LONG_RUNS[name]], cwd=tmp_path, stderr=subprocess.PIPE, text=True,
                         start_new_session=True, preexec_fn=_default_sigint)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and p.poll() is None:
            if _kernel_thread_running(p.pid):
                break
            time.sleep(0.2)
        time.sleep(1.0)
        assert p.poll() is None, p.stderr.read()
        p.send_signal(signal.SIGINT)
        _, err = p.communicate(timeout=20)  # a kernel ignoring Ctrl-C runs for hours
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()
    assert p.returncode == 130, err
    assert "interrupted" in err and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []


def _default_sigint():
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _kernel_thread_running(pid):
    try:
        names = [Path(f"/proc/{pid}/task/{t}/comm").read_text().strip() for t in os.listdir(f"/proc/{pid}/task")]
    except OSError:
        return False
    return any(n.startswith("stairbounce-ker") for n in names)


def test_read_only_file_system_is_one_line_before_any_work(tmp_path, capsys):
    """Campaign cases 165, 194, 217, 242: OSError [Errno 30] tracebacks."""
    if os.geteuid() != 0:
        pytest.skip("mounting a read-only tmpfs needs root")
    ro = tmp_path / "ro"
    ro.mkdir()
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=1m", "tmpfs", str(ro)], capture_output=True, text=True)
    if r.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {r.stderr.strip()}")
    try:
        for args in (["scan", "--size", "12x8", "--out", ro / "x.nc"],
                     ["scan", "--size", "12x8", "--tile", "4", "--out", ro / "x.zarr"],
                     ["trajectory", "--e", "0.05", "--u", "0.93", "--out", ro / "t.png"],
                     ["figures", "--only", "fig3", "--out", ro / "f"]):
            code, _, err = run(args, capsys)
            assert code == 2 and one_line_error(err) and "read-only file system" in err, err
    finally:
        subprocess.run(["umount", str(ro)], check=False)
