"""Tiled, resumable scans written to Zarr (stairbounce.atlas), locally and on Dask."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import distributed
import numpy as np
import pytest
import xarray as xr
import zarr

from stairbounce import atlas
from stairbounce.atlas import downsample, scan_to_zarr, tile_slices, tiles_done
from stairbounce.plane import load, save, scan

from ._cli import run_cli as run
from ._stores import StopAfter, stop_after

# the scheduler's HTTP server (no dashboard) falls back to a free port when 8787 is taken
pytestmark = pytest.mark.filterwarnings("ignore:Port 8787 is already in use")

# a window crossing tongues, the fractal part and the non-sliding region; 45 x 38
# pixels in tiles of 16: 3 x 3 tiles, the last row and column shorter
WINDOW = dict(e=(0.05, 0.95, 45), u=(0.1, 1.4, 38), max_iter=400)
TILE = 16


@pytest.fixture(scope="module")
def reference():
    return scan(**WINDOW)


@pytest.fixture(scope="module")
def client():
    # two workers in this process: fast to start, and the tasks really go
    # through the scheduler, serialisation and worker-side region writes
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as c:
        yield c


def assert_store_is_scan(ds, reference):
    assert ds["word_length"].chunks is not None  # lazy, dask-backed
    xr.testing.assert_identical(ds.compute(), reference)
    for name in reference.data_vars:
        assert ds[name].dtype == reference[name].dtype


# --------------------------------------------------------------------------- #
# Equal to the in-memory scan                                                  #
# --------------------------------------------------------------------------- #


def test_core_import_needs_no_dask_plotting_or_cli():
    code = (
        "import sys, stairbounce, stairbounce.atlas; "
        "print(sorted(m for m in ('dask', 'distributed', 'matplotlib', 'typer') if m in sys.modules))"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert r.stdout.strip() == "[]"


def test_tile_slices_cover_the_range_once():
    s = tile_slices(45, 16)
    assert [(t.start, t.stop) for t in s] == [(0, 16), (16, 32), (32, 45)]
    assert tile_slices(5, 16) == [slice(0, 5)]


def test_local_scan_equals_scan_bit_for_bit(tmp_path, reference):
    seen = []
    ds = scan_to_zarr(tmp_path / "a.zarr", tile=TILE, progress=lambda d, t: seen.append((d, t)), **WINDOW)
    assert_store_is_scan(ds, reference)
    assert ds["status"].chunks == ((16, 16, 6), (16, 16, 13))
    assert seen == [(k, 9) for k in range(10)]
    assert tiles_done(tmp_path / "a.zarr").all()


def test_transient_from_another_state_equals_scan(tmp_path):
    kw = dict(e=(0.2, 0.8, 20), u=(0.3, 1.0, 17), max_iter=300, y0=2.5, v0=-0.7)
    ds = scan_to_zarr(tmp_path / "a.zarr", tile=7, **kw)
    xr.testing.assert_identical(ds.load(), scan(**kw))


def test_dask_cluster_scan_equals_scan_bit_for_bit(tmp_path, client, reference):
    seen = []
    ds = scan_to_zarr(
        tmp_path / "a.zarr", tile=TILE, client=client, progress=lambda d, t: seen.append(d), **WINDOW
    )
    assert_store_is_scan(ds, reference)
    assert seen == list(range(10))


def test_scheduler_address_string(tmp_path, client, reference):
    ds = scan_to_zarr(tmp_path / "a.zarr", tile=TILE, client=client.scheduler_info()["address"], **WINDOW)
    assert_store_is_scan(ds, reference)


@pytest.mark.slow
def test_worker_processes_write_their_own_tiles(tmp_path, reference):
    # real worker processes (spawned): the client never touches tile data
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as c:
        ds = scan_to_zarr(tmp_path / "a.zarr", tile=TILE, client=c, **WINDOW)
        pids = set(c.run(os.getpid).values())
    assert os.getpid() not in pids
    assert_store_is_scan(ds, reference)


def test_store_reads_like_a_saved_scan(tmp_path, reference):
    scan_to_zarr(tmp_path / "a.zarr", tile=TILE, **WINDOW)
    xr.testing.assert_identical(load(tmp_path / "a.zarr"), reference)


def concurrency(monkeypatch, expected):
    """Wrap the tile kernel: the first ``expected`` tiles must run at the same
    time (a barrier), and the most tiles seen running at once is recorded."""
    import threading

    import stairbounce.plane

    original = stairbounce.plane.scan_coords
    state = {"now": 0, "max": 0, "calls": 0}
    lock = threading.Lock()
    barrier = threading.Barrier(expected, timeout=20)

    def wrapped(*a, **k):
        if len(a[0]) == 1 and len(a[1]) == 1:
            return original(*a, **k)  # the one-pixel probe of the attributes
        with lock:
            state["calls"] += 1
            first = state["calls"] <= expected
            state["now"] += 1
            state["max"] = max(state["max"], state["now"])
        try:
            if first and expected > 1:
                barrier.wait()
            return original(*a, **k)
        finally:
            with lock:
                state["now"] -= 1

    monkeypatch.setattr(stairbounce.plane, "scan_coords", wrapped)
    return state


def test_local_tiles_run_side_by_side_one_numba_thread_each(tmp_path, reference, monkeypatch):
    import numba

    cores = numba.get_num_threads()
    seen = concurrency(monkeypatch, cores)
    ds = scan_to_zarr(tmp_path / "a.zarr", tile=TILE, **WINDOW)
    assert seen["max"] == cores
    assert numba.get_num_threads() == cores
    assert_store_is_scan(ds, reference)


def test_local_tiles_one_at_a_time_on_all_numba_threads(tmp_path, reference, monkeypatch):
    import numba

    seen = concurrency(monkeypatch, 1)
    ds = scan_to_zarr(tmp_path / "a.zarr", tile=TILE, numba_threads=numba.get_num_threads(), **WINDOW)
    assert seen["max"] == 1
    assert_store_is_scan(ds, reference)


def test_two_tiles_at_once_in_one_process_equal_the_scan(tmp_path, reference):
    # one worker, two threads: concurrent kernel launches in one process
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as c:
        ds = scan_to_zarr(tmp_path / "a.zarr", tile=8, client=c, **WINDOW)
    assert_store_is_scan(ds, reference)


# --------------------------------------------------------------------------- #
# Interrupt and resume                                                         #
# --------------------------------------------------------------------------- #


def test_interrupted_local_scan_resumes_to_the_same_store(tmp_path, reference):
    path = tmp_path / "a.zarr"
    with pytest.raises(StopAfter):
        scan_to_zarr(path, tile=TILE, progress=stop_after(4), **WINDOW)
    done = tiles_done(path)
    # the tiles running when the scan stopped are finished, not started ones
    k = int(done.sum())
    assert 4 <= k < 9
    first = []
    ds = scan_to_zarr(path, tile=TILE, progress=lambda d, t: first.append(d), **WINDOW)
    assert first == list(range(k, 10))  # the complete tiles were skipped
    assert_store_is_scan(ds, reference)


def test_interrupted_dask_scan_resumes_to_the_same_store(tmp_path, client, reference):
    path = tmp_path / "a.zarr"
    with pytest.raises(StopAfter):
        scan_to_zarr(path, tile=TILE, client=client, progress=stop_after(3), **WINDOW)
    # at least the 3 reported tiles are in the store; tiles already running on the workers
    # when the run stops may finish and write themselves (the workers write their own
    # tiles), up to all 9 on a busy machine (seen in a CI run): what matters is that the
    # resumed run computes only what is missing and gives the scan
    done = int(tiles_done(path).sum())
    assert 3 <= done <= 9
    seen = []
    ds = scan_to_zarr(path, tile=TILE, client=client, progress=lambda d, t: seen.append(d), **WINDOW)
    # one call per tile computed again, ending at 9 of 9: at most the 6 not reported before
    # the stop (a tile that was finishing may have written itself since it was counted)
    assert seen[-1] == 9 and seen == sorted(seen) and len(seen) <= min(6, 9 - done + 1)
    assert_store_is_scan(ds, reference)


def test_complete_store_is_not_recomputed(tmp_path, reference, monkeypatch):
    path = tmp_path / "a.zarr"
    scan_to_zarr(path, tile=TILE, **WINDOW)

    def fail(*a, **k):
        raise AssertionError("a complete tile was computed again")

    monkeypatch.setattr(atlas, "_run_tile", fail)
    seen = []
    ds = scan_to_zarr(path, tile=TILE, progress=lambda d, t: seen.append(d), **WINDOW)
    assert seen == [9]
    xr.testing.assert_identical(ds.compute(), reference)


def test_tile_cut_off_while_writing_is_not_marked_and_is_recomputed(tmp_path, reference, monkeypatch):
    path = tmp_path / "a.zarr"
    with pytest.raises(StopAfter):  # creates the store, computes nothing
        scan_to_zarr(path, tile=TILE, progress=stop_after(0), **WINDOW)
    writes = {"n": 0}
    original = zarr.Array.__setitem__

    def setitem(self, key, value):
        # a tile is five variables then its flag: fail on the third variable of
        # the third tile, (0, 2)
        writes["n"] += 1
        if writes["n"] == 2 * 6 + 3:
            raise OSError("disk pulled out")
        return original(self, key, value)

    monkeypatch.setattr(zarr.Array, "__setitem__", setitem)
    import numba

    with pytest.raises(OSError, match="disk pulled out"):
        # one tile at a time, so that the writes come in tile order
        scan_to_zarr(path, tile=TILE, numba_threads=numba.get_num_threads(), **WINDOW)
    monkeypatch.setattr(zarr.Array, "__setitem__", original)
    done = tiles_done(path)
    assert done.sum() == 2 and not done[0, 2]  # tiles (0, 0), (0, 1) only
    # the half-written tile holds some new data and some zeros
    assert ds_region_differs(path, reference, slice(0, 16), slice(32, 45))
    ds = scan_to_zarr(path, tile=TILE, **WINDOW)
    assert_store_is_scan(ds, reference)


def ds_region_differs(path, reference, su, se):
    stored = xr.open_zarr(path, consolidated=False).isel(u=su, e=se).load()
    return not stored.identical(reference.isel(u=su, e=se))


def test_unmarked_garbage_is_overwritten(tmp_path, reference):
    path = tmp_path / "a.zarr"
    scan_to_zarr(path, tile=TILE, **WINDOW)
    root = zarr.open_group(str(path), mode="r+")
    root["word_length"][16:32, 0:16] = 12345
    root["tiles"]["done"][1, 0] = False
    ds = scan_to_zarr(path, tile=TILE, **WINDOW)
    assert_store_is_scan(ds, reference)


KILLED_SCAN = textwrap.dedent(
    """
    import sys, time
    import numba
    from stairbounce.atlas import scan_to_zarr
    # one tile at a time (all numba threads each), so that the sleep in
    # progress paces the tiles and the kill lands mid-scan even under load
    scan_to_zarr(sys.argv[1], e=(0.05, 0.95, 45), u=(0.1, 1.4, 38), max_iter=400, tile=8,
                 numba_threads=numba.get_num_threads(), progress=lambda done, total: time.sleep(0.3))
    """
)


@pytest.mark.slow
def test_killed_process_resumes_to_the_same_store(tmp_path):
    path = tmp_path / "a.zarr"
    proc = subprocess.Popen([sys.executable, "-c", KILLED_SCAN, str(path)])
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and proc.poll() is None:
            if path.exists() and tiles_done(path).sum() >= 3:
                break
            time.sleep(0.05)
        assert proc.poll() is None, "the scan finished (or failed) before it could be killed"
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    done = tiles_done(path)
    assert 3 <= done.sum() < done.size
    ds = scan_to_zarr(path, e=(0.05, 0.95, 45), u=(0.1, 1.4, 38), max_iter=400, tile=8)
    xr.testing.assert_identical(ds.load(), scan(**WINDOW))


@pytest.mark.slow
def test_killed_dask_worker_its_tiles_are_done_again(tmp_path):
    # long orbits (max_iter 1e5) so that tiles are still running when a worker
    # process is killed after the first tile; Dask reschedules its tasks
    kw = dict(e=(0.05, 0.95, 45), u=(0.1, 1.4, 38), max_iter=100_000)
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster, distributed.Client(cluster) as c:
        pids = list(c.run(os.getpid).values())
        killed = []

        def progress(done, total):
            if done >= 1 and not killed:
                os.kill(pids[0], signal.SIGKILL)
                killed.append(done)

        ds = scan_to_zarr(tmp_path / "a.zarr", tile=8, client=c, progress=progress, **kw)
        assert killed and killed[0] < 30
        assert pids[0] not in c.run(os.getpid).values()
    xr.testing.assert_identical(ds.compute(), scan(**kw))


# --------------------------------------------------------------------------- #
# Refusals and errors                                                          #
# --------------------------------------------------------------------------- #


@pytest.mark.parametrize(
    "change, word",
    [
        (dict(e=(0.05, 0.9, 45)), "e_max"),
        (dict(e=(0.05, 0.95, 46)), "n_e"),
        (dict(u=(0.2, 1.4, 38)), "u_min"),
        (dict(max_iter=401), "max_iter"),
        (dict(y0=1.5), "y0"),
        (dict(v0=0.25), "v0"),
        (dict(tile=8), "tile"),
    ],
)
def test_a_different_scan_on_an_existing_store_is_refused(tmp_path, change, word):
    path = tmp_path / "a.zarr"
    with pytest.raises(StopAfter):
        scan_to_zarr(path, tile=TILE, progress=stop_after(2), **WINDOW)
    before = tiles_done(path)
    kw = dict(WINDOW, tile=TILE)
    kw.update(change)
    with pytest.raises(ValueError, match=f"holds a different scan.*{word}"):
        scan_to_zarr(path, **kw)
    np.testing.assert_array_equal(tiles_done(path), before)  # untouched


def test_a_path_holding_something_else_is_refused(tmp_path, reference):
    other = tmp_path / "other.zarr"
    other.mkdir()
    (other / "notes.txt").write_text("mine")
    with pytest.raises(ValueError, match="not a tiled scan store"):
        scan_to_zarr(other, tile=TILE, **WINDOW)
    assert (other / "notes.txt").read_text() == "mine"
    saved = tmp_path / "saved.zarr"
    save(reference, saved)
    with pytest.raises(ValueError, match="not a tiled scan store"):
        scan_to_zarr(saved, tile=TILE, **WINDOW)


def test_missing_folder_is_a_clear_error(tmp_path):
    with pytest.raises(ValueError, match=r"folder .*nowhere does not exist"):
        scan_to_zarr(tmp_path / "nowhere" / "a.zarr", tile=TILE, **WINDOW)


@pytest.fixture
def read_only_dir(tmp_path):
    """A folder nobody can create files in, even root (chmod, else chattr +i)."""
    d = tmp_path / "ro"
    d.mkdir()
    os.chmod(d, 0o555)
    immutable = False
    if atlas._writable(d):
        immutable = subprocess.run(["chattr", "+i", str(d)], capture_output=True).returncode == 0
    try:
        if atlas._writable(d):
            pytest.skip("cannot make a read-only folder here (root without chattr)")
        yield d
    finally:
        if immutable:
            subprocess.run(["chattr", "-i", str(d)], check=True)
        os.chmod(d, 0o755)


def test_read_only_folder_is_a_clear_error(read_only_dir):
    with pytest.raises(ValueError, match="not writable"):
        scan_to_zarr(read_only_dir / "a.zarr", tile=TILE, **WINDOW)
    assert not (read_only_dir / "a.zarr").exists()


def test_unfinished_read_only_store_is_a_clear_error_finished_one_opens(tmp_path, reference):
    path = tmp_path / "a.zarr"
    with pytest.raises(StopAfter):
        scan_to_zarr(path, tile=TILE, progress=stop_after(2), **WINDOW)
    with read_only(path):
        with pytest.raises(ValueError, match="cannot resume .*not writable"):
            scan_to_zarr(path, tile=TILE, **WINDOW)
    scan_to_zarr(path, tile=TILE, **WINDOW)
    with read_only(path):
        xr.testing.assert_identical(scan_to_zarr(path, tile=TILE, **WINDOW).load(), reference)


class read_only:
    def __init__(self, path):
        self.path = path
        self.immutable = False

    def __enter__(self):
        os.chmod(self.path, 0o555)
        if atlas._writable(self.path):
            r = subprocess.run(["chattr", "+i", str(self.path)], capture_output=True)
            self.immutable = r.returncode == 0
        if atlas._writable(self.path):
            self.__exit__()
            pytest.skip("cannot make a read-only folder here (root without chattr)")

    def __exit__(self, *exc):
        if self.immutable:
            subprocess.run(["chattr", "-i", str(self.path)], check=True)
        os.chmod(self.path, 0o755)


@pytest.mark.parametrize(
    "kw, match",
    [
        (dict(tile=0), "tile must be an integer >= 1"),
        (dict(tile=2.5), "tile must be an integer >= 1"),
        (dict(e=(0.5, 0.2, 10)), "e_min must be < e_max"),
        (dict(e=(0.0, 1.0, 5, 5)), r"e must be a tuple \(e_min, e_max\) or \(e_min, e_max, n_e\)"),
        (dict(u=(0.1, 1.0, 0)), "n_u must be an integer >= 1"),
        (dict(max_iter=0), "max_iter must be an integer >= 1"),
        (dict(y0=-1.0), "y0"),
        (dict(numba_threads=0), "numba_threads must be an integer >= 1"),
        (dict(client=42), "client must be None, a dask.distributed.Client or a scheduler address"),
    ],
)
def test_bad_input_names_the_parameter(tmp_path, kw, match):
    args = dict(e=(0.1, 0.9, 10), u=(0.1, 1.0, 10), max_iter=10, tile=4)
    args.update(kw)
    with pytest.raises(ValueError, match=match):
        scan_to_zarr(tmp_path / "a.zarr", **args)
    assert not (tmp_path / "a.zarr").exists()


def test_path_must_be_a_zarr_store(tmp_path):
    with pytest.raises(ValueError, match=r"path must end in \.zarr"):
        scan_to_zarr(tmp_path / "a.nc", e=(0.1, 0.9, 4), u=(0.1, 1.0, 4), tile=2)


# --------------------------------------------------------------------------- #
# Downsampling for rendering                                                   #
# --------------------------------------------------------------------------- #


def naive_mode(block):
    values, counts = np.unique(block, return_counts=True)
    return values[np.argmax(counts)]  # np.unique sorts: ties go to the smallest


def test_block_mode_against_a_plain_count():
    rng = np.random.default_rng(3)
    x = rng.integers(0, 4, size=(5, 7, 3, 3)).astype(np.int64)
    got = atlas._block_mode(x)
    want = np.array([[naive_mode(x[i, j]) for j in range(7)] for i in range(5)])
    np.testing.assert_array_equal(got, want)
    u8 = rng.integers(0, 2, size=(4, 4, 2, 2)).astype(np.uint8)
    np.testing.assert_array_equal(
        atlas._block_mode(u8), [[naive_mode(u8[i, j]) for j in range(4)] for i in range(4)]
    )


@pytest.mark.parametrize("method", ["mode", "max", "stride"])
def test_downsample_reduces_blocks_lazily(tmp_path, reference, method):
    ds = scan_to_zarr(tmp_path / "a.zarr", tile=TILE, **WINDOW)
    small = downsample(ds, 200, method)
    f = small.attrs["downsampled"]
    assert f == 3 and small.sizes["u"] * small.sizes["e"] <= 200
    assert dict(small.sizes) == {"u": 38 // 3, "e": 45 // 3}
    assert small["word_length"].chunks is not None  # still lazy
    small = small.load()
    wl = reference["word_length"].values
    for i, j in [(0, 0), (4, 7), (11, 14), (6, 2)]:
        block = wl[f * i : f * i + f, f * j : f * j + f]
        want = {"mode": naive_mode(block), "max": block.max(), "stride": block[0, 0]}[method]
        assert small["word_length"].values[i, j] == want
    np.testing.assert_allclose(small["e"].values, reference["e"].values[:45].reshape(-1, 3).mean(1))
    assert small["word_length"].dtype == np.int64
    assert small["word_length"].attrs == reference["word_length"].attrs


def test_downsample_leaves_small_scans_alone(reference):
    assert downsample(reference, 45 * 38) is reference
    with pytest.raises(ValueError, match="method must be one of"):
        downsample(reference, 10, "mean")


# --------------------------------------------------------------------------- #
# Command line: scan --tile / --scheduler / --workers, render                  #
# --------------------------------------------------------------------------- #

SCAN_ARGS = ["scan", "--e", "0.05:0.95", "--u", "0.1:1.4", "--size", "45x38", "--max-iter", "400"]


def test_cli_tiled_scan_writes_the_store_and_resumes(tmp_path, capsys, reference):
    store, png = tmp_path / "atlas.zarr", tmp_path / "atlas.png"
    code, out, err = run(SCAN_ARGS + ["--tile", 16, "--out", store, "--png", png], capsys)
    assert code == 0, err
    assert f"wrote {store}: 45 x 38 pixels (e x u), 9 tiles of 16, computed in this process" in out
    xr.testing.assert_identical(xr.open_zarr(store, consolidated=False).compute(), reference)
    assert png.stat().st_size > 0
    # the store is resumed; the picture that exists is replaced only with --force
    code, out, err = run(SCAN_ARGS + ["--tile", 16, "--out", store, "--png", png], capsys)
    assert code == 2 and "exists: not replaced" in err
    code, out, err = run(SCAN_ARGS + ["--tile", 16, "--out", store, "--png", png, "--force"], capsys)
    assert code == 0 and "(9 already complete)" in out


def test_cli_tiled_scan_on_a_scheduler(tmp_path, capsys, client, reference):
    store = tmp_path / "atlas.zarr"
    address = client.scheduler_info()["address"]
    code, out, err = run(SCAN_ARGS + ["--scheduler", address, "--tile", 16, "--out", store], capsys)
    assert code == 0, err
    assert f"computed in scheduler {address}" in out
    xr.testing.assert_identical(xr.open_zarr(store, consolidated=False).compute(), reference)


@pytest.mark.slow
def test_console_script_with_local_workers(tmp_path, reference):
    # worker processes spawned from the installed console script
    store = tmp_path / "atlas.zarr"
    exe = os.path.join(os.path.dirname(sys.executable), "stairbounce")
    r = subprocess.run(
        [exe, *SCAN_ARGS, "--workers", "2", "--tile", "16", "--out", str(store), "--png", str(tmp_path / "a.png")],
        capture_output=True, text=True, timeout=300,
    )
    assert r.returncode == 0, r.stderr
    assert "computed in 2 local workers" in r.stdout
    xr.testing.assert_identical(xr.open_zarr(store, consolidated=False).compute(), reference)


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--tile", 16], "needs --out STORE.zarr"),
        (["--tile", 16, "--out", "{tmp}/a.nc"], "--out must be a .zarr store for a tiled scan"),
        (["--tile", 0, "--out", "{tmp}/a.zarr"], "--tile must be an integer >= 1"),
        (["--workers", 0, "--out", "{tmp}/a.zarr"], "--workers must be an integer >= 1"),
        (["--workers", 2, "--scheduler", "tcp://h:8786", "--out", "{tmp}/a.zarr"], "not both"),
        (["--scheduler", "somewhere", "--out", "{tmp}/a.zarr"], "--scheduler must be an address"),
        (["--tile", 16, "--out", "{tmp}/missing/a.zarr"], "does not exist"),
    ],
)
def test_cli_tiled_scan_bad_input_exits_2(tmp_path, capsys, extra, message):
    args = SCAN_ARGS + [str(a).replace("{tmp}", str(tmp_path)) for a in extra] + ["--png", tmp_path / "p.png"]
    code, out, err = run(args, capsys)
    assert code == 2
    assert err.startswith("stairbounce: error:") and message in err
    assert len(err.strip().splitlines()) == 1


def test_cli_refuses_a_different_scan_on_the_store(tmp_path, capsys):
    store = tmp_path / "atlas.zarr"
    assert run(SCAN_ARGS + ["--tile", 16, "--out", store, "--png", tmp_path / "p.png"], capsys)[0] == 0
    args = SCAN_ARGS[:-1] + ["500", "--tile", 16, "--out", store, "--png", tmp_path / "p2.png"]
    code, _, err = run(args, capsys)
    assert code == 2 and "holds a different scan (max_iter: store 400, asked 500)" in err


def test_cli_unreachable_scheduler_exits_2(tmp_path, capsys):
    import dask

    with dask.config.set({"distributed.comm.timeouts.connect": "1s"}):
        code, _, err = run(
            SCAN_ARGS + ["--scheduler", "tcp://127.0.0.1:9", "--out", tmp_path / "a.zarr", "--png", tmp_path / "p.png"],
            capsys,
        )
    assert code == 2 and "cannot reach the Dask scheduler at tcp://127.0.0.1:9" in err


@pytest.fixture(scope="module")
def store(tmp_path_factory, reference):
    path = tmp_path_factory.mktemp("render") / "atlas.zarr"
    scan_to_zarr(path, tile=TILE, **WINDOW)
    return path


def png_size(path):
    from PIL import Image

    with Image.open(path) as im:
        return im.format, im.size


def test_cli_render_whole_store(tmp_path, capsys, store):
    png = tmp_path / "r.png"
    code, out, err = run(["render", store, "--png", png, "--dpi", 50], capsys)
    assert code == 0, err
    assert out.strip() == f"wrote {png}: word_length, 45 x 38 pixels"
    assert png_size(png) == ("PNG", (400, 300))


def test_cli_render_reduces_large_stores_by_blocks(tmp_path, capsys, store):
    png = tmp_path / "r.png"
    code, out, err = run(["render", store, "--png", png, "--max-pixels", 200, "--field", "period"], capsys)
    assert code == 0, err
    assert "period, 15 x 12 pixels, blocks of 3 x 3 (mode)" in out
    code, out, _ = run(["render", store, "--png", png, "--max-pixels", 200, "--reduce", "stride", "--force"], capsys)
    assert code == 0 and "(stride)" in out


def test_cli_render_window(tmp_path, capsys, store, reference):
    png = tmp_path / "r.png"
    code, out, err = run(["render", store, "--png", png, "--window", "0.3:0.8,0.2:0.7", "--field", "status"], capsys)
    assert code == 0, err
    e, u = reference["e"].values, reference["u"].values
    n_e = int(((e >= 0.3) & (e <= 0.8)).sum())
    n_u = int(((u >= 0.2) & (u <= 0.7)).sum())
    assert f"status, {n_e} x {n_u} pixels" in out


def test_cli_render_warns_about_missing_tiles(tmp_path, capsys):
    path = tmp_path / "part.zarr"
    with pytest.raises(StopAfter):
        scan_to_zarr(path, tile=TILE, progress=stop_after(4), **WINDOW)
    missing = int((~tiles_done(path)).sum())
    assert missing > 0
    code, _, err = run(["render", path, "--png", tmp_path / "r.png"], capsys)
    assert code == 0 and f"warning: {missing} of 9 tiles" in err


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--png", "{tmp}/r.jpg"], "--png must end in .png"),
        (["--png", "{tmp}/r.png", "--field", "colour"], "--field must be one of"),
        (["--png", "{tmp}/r.png", "--max-pixels", 0], "--max-pixels must be an integer >= 1"),
        (["--png", "{tmp}/r.png", "--reduce", "mean"], "--reduce must be mode, max or stride"),
        (["--png", "{tmp}/r.png", "--window", "0:1"], "--window must be E0:E1,U0:U1"),
        (["--png", "{tmp}/r.png", "--window", "0:1,2:1"], "--window must have MIN < MAX"),
        (["--png", "{tmp}/r.png", "--window", "0:1,2:3"], "holds no pixel"),
        (["--png", "{tmp}/nowhere/r.png"], "does not exist"),
    ],
)
def test_cli_render_bad_input_exits_2(tmp_path, capsys, store, extra, message):
    args = ["render", store] + [str(a).replace("{tmp}", str(tmp_path)) for a in extra]
    code, _, err = run(args, capsys)
    assert code == 2 and message in err, err
    assert len(err.strip().splitlines()) == 1


def test_cli_render_missing_or_unreadable_store_exits_2(tmp_path, capsys):
    code, _, err = run(["render", tmp_path / "none.zarr", "--png", tmp_path / "r.png"], capsys)
    assert code == 2 and "no such store" in err
    bad = tmp_path / "bad.zarr"
    bad.mkdir()
    code, _, err = run(["render", bad, "--png", tmp_path / "r.png"], capsys)
    assert code == 2 and "cannot read" in err
