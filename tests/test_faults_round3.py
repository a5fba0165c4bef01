"""The third fault campaign's findings, part A (issue 38; report
``reliability-round3.md``): R1, R3, R5, R9, R10, R11 and the Dask
observation, each with the case that broke (part B: test_faults_round3_b.py).

Every expected answer comes from a documented promise (the explorer's slice
bound, "resume verifies every tile", one-line errors, "estimated before it
starts", one writer per store, the cache's key), not from the code's output.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from stairbounce import plane, structure
from stairbounce.structure import borders, regions
from stairbounce.explorer import overlays, render
from stairbounce.explorer import view as V

# --------------------------------------------------------------------------- #
# R1: every slice of the explorer's worker is bounded in map steps            #
# --------------------------------------------------------------------------- #

# the report's link, small enough for a test: e 0.1:0.3, u 0.4:0.7 at a high
# max_iter for its size; the slice bound is lowered so that today's one-slice
# jobs are far over it
R1_VIEW = V.View(0.1, 0.3, 0.4, 0.7, 24, 20, max_iter=3000, overlays=("borders",))
R1_SLICE = 200_000


# a pair's trials: at most about 56 halvings of a bracket of two neighbouring
# pixel centres, at least one every third trial, and a few resets
# (test_r1_pair_work_bounds_the_trials_the_kernel_counts checks the kernel's own counts)
TRIALS = 192


def _pairs_bound(period, a, b, max_iter):
    """Map steps of the pairs in the border kernel: each trial follows the
    sliding end's word (its period p_c), then the other end up to max_iter."""
    pa, pb = period[a], period[b]
    pc = np.where(pa == 0, pb, np.where(pb == 0, pa, np.minimum(pa, pb)))
    return int(np.where(pc == 0, 0, TRIALS * pc + max_iter).sum())


class Meter:
    """Potential map steps, counted at the kernels' entries from their
    arguments (not from the code's own accounting): a scan runs at most
    ``max_iter`` steps per pixel, a pair at most :func:`borders.pair_work`,
    the words of points their periods, a seed scan ``max_iter`` per seed, a
    word beside an arc ``max_iter``."""

    def __init__(self):
        self.work = 0
        self.traced_words = 0

    def install(self, monkeypatch):
        def count(mod, name, cost):
            orig = getattr(mod, name)

            def wrapped(*a, **k):
                self.work += int(cost(*a))
                return orig(*a, **k)

            monkeypatch.setattr(mod, name, wrapped)

        count(plane, "_run", lambda es, us, grid, max_iter, *r: (es.size * us.size if grid else es.size) * max_iter)
        count(borders, "_border_kernel", lambda es, us, period, a, b, axis, max_iter, *r: _pairs_bound(period, a, b, max_iter))
        count(structure.words, "_fill_impacts", lambda e, u, periods, *r: periods.sum())
        count(regions, "_words_grid", lambda es, us, y0, v0, max_iter, *r: es.size * us.size * max_iter)
        count(overlays, "_word_at", lambda e, u, window, max_iter, *r: max_iter)
        orig = regions._trace_word

        def traced(*a, **k):  # the documented exception: one traced word, one slice
            self.traced_words += 1
            return orig(*a, **k)

        monkeypatch.setattr(regions, "_trace_word", traced)


def _slices(gen, meter):
    """Run ``gen`` one ``next()`` at a time: the work of each slice (None for a
    slice that traced a word), and the return value."""
    works = []
    while True:
        meter.work, meter.traced_words = 0, 0
        try:
            next(gen)
        except StopIteration as stop:
            works.append(None if meter.traced_words else meter.work)
            return works, stop.value
        works.append(None if meter.traced_words else meter.work)


@pytest.fixture
def meter(monkeypatch):
    # compile what the meter wraps before wrapping it (numba reads globals when it compiles)
    V.traced_overlay(R1_VIEW, regions.window_regions((0.2, 0.21), (0.5, 0.51), resolution=4, max_iter=50),
                     V.view_border_points(V.View(0.2, 0.21, 0.5, 0.51, 16, 16, max_iter=50)))
    for mod in (V, render, overlays):  # the modules that read SLICE_WORK (view re-exports it)
        monkeypatch.setattr(mod, "SLICE_WORK", R1_SLICE)
    m = Meter()
    m.install(monkeypatch)
    return m


def _app_jobs(view):
    """The jobs a page of ``view`` queues, on a scheduler that runs nothing by itself."""
    pytest.importorskip("panel", reason="panel is in the web extra")
    from stairbounce.explorer.app import Explorer
    from stairbounce.explorer.scheduler import Scheduler

    sched = Scheduler(thread=False)
    app = Explorer(view, scheduler=sched)
    app.start()
    return app, sched


def _run_jobs(sched, meter):
    """Every slice the scheduler runs, by job kind: its work (None: a traced word)."""
    by_kind: dict = {}
    while True:
        job = sched._pick()
        if job is None:
            return by_kind
        meter.work, meter.traced_words = 0, 0
        sched.run_slice(job)
        by_kind.setdefault(job.kind, []).append(None if meter.traced_words else meter.work)


@pytest.mark.parametrize("overlays, point", [(("borders",), None), (("traced",), None),
                                             ((), (0.21, 0.41))])
def test_r1_every_slice_of_every_job_kind_is_bounded_in_map_steps(meter, overlays, point):
    """The report's three routes (the exact borders, the traced overlay, a tap's
    word-table row) each ran as one slice of the view's whole grid at its
    max_iter; every slice of every job must stay within the slice bound
    (a traced word, the documented exception, aside)."""
    from dataclasses import replace

    view = replace(R1_VIEW, overlays=overlays, point=point)
    if "traced" in overlays:  # fewer words to trace (each a slice of its own); seeds 48 x 48 x 300 steps
        view = V.View(0.2, 0.3, 0.6, 0.7, 24, 20, max_iter=300, overlays=overlays)
    app, sched = _app_jobs(view)
    if point is not None:
        app._request_point(*point)
    by_kind = _run_jobs(sched, meter)
    heavy = "point" if point is not None else "borders"
    assert heavy in by_kind and "failed" not in app.status.object
    for kind, works in by_kind.items():
        counted = [w for w in works if w is not None]
        assert max(counted) <= R1_SLICE, (kind, works)
    # the heavy job did its work (over many slices), not nothing
    assert sum(w for w in by_kind[heavy] if w is not None) > 3 * R1_SLICE
    if point is not None:
        assert app._word_table is not None  # the row was computed


def test_r1_sliced_results_equal_the_one_call_results(meter):
    """The slices change no answer: the border points, the word row, the
    traced overlay and a render equal their one-call versions."""
    works, pts = _slices(V.border_point_slices(R1_VIEW), meter)
    assert len(works) > 5 and max(works) <= R1_SLICE
    ref = borders.border_points(*V.border_grid(R1_VIEW), max_iter=R1_VIEW.max_iter)
    assert pts.sizes["point"] > 10 and pts.equals(ref)
    text = str(pts["word_low"].values[0])
    if text == structure.words.NONE_WORD:
        text = str(pts["word_high"].values[0])
    works, row = _slices(V.word_row_slices(R1_VIEW, text), meter)
    assert max(works) <= R1_SLICE
    tab = borders.word_table(*V.border_grid(R1_VIEW), max_iter=R1_VIEW.max_iter)
    assert row["table"].equals(tab) and row["row"] is not None and row["row"]["text"] == text
    # a render whose single row is over the bound comes in pieces of rows, bit for bit the scan
    wide = V.View(0.1, 0.3, 0.4, 0.7, 200, 16, max_iter=3000)
    works, ds = _slices(V.render_slices(wide, slice_work=R1_SLICE), meter)
    assert max(works) <= R1_SLICE and len(works) > 16
    ref = plane.scan(e=(0.1, 0.3, 200), u=(0.4, 0.7, 16), max_iter=3000)
    for k in ("status", "period", "word_length"):
        assert np.array_equal(ds[k].values, ref[k].values)


def test_r1_pair_work_bounds_the_trials_the_kernel_counts():
    """pair_work is a bound: every pair's trials (the kernel's own count) stay
    under PAIR_TRIALS, and its trial steps under PAIR_TRIALS * p_c."""
    e, u = (0.0, 1.0, 60), (0.0, 1.5, 45)
    ds = plane.scan(e=e, u=u, max_iter=1000)
    es, us, period, max_iter = borders._grid_input(ds)
    a, b, axis = borders._pairs(period, us.size, es.size)
    found, out = borders._run_pairs(es, us, period, a, b, axis, max_iter, None)
    pa, pb = period[a][found], period[b][found]
    pc = np.where(pa == 0, pb, np.where(pb == 0, pa, np.minimum(pa, pb)))
    assert found.sum() > 100
    assert borders.PAIR_TRIALS == TRIALS
    assert out[found, 9].max() <= TRIALS
    assert np.all(out[found, 10] <= TRIALS * pc)
    assert np.array_equal(borders.pair_work(period, a, b, max_iter)[found], TRIALS * pc + max_iter)


# --------------------------------------------------------------------------- #
# R3: a tile's checksum is bound to the tile and the store                    #
# --------------------------------------------------------------------------- #

R3_WINDOW = dict(e=(0.05, 0.95, 45), u=(0.1, 1.4, 38), max_iter=400)
R3_OTHER = dict(e=(0.1, 0.6, 45), u=(0.3, 1.2, 38), max_iter=400)  # the same layout, other pixels
R3_TILE = 16  # 3 x 3 tiles
R3_VARS = ("status", "word_length", "jumps", "period", "impacts")


def _copy_tile(src, src_ij, dst, dst_ij):
    """A tile's five data chunks and its checksum chunk, copied as files."""
    import shutil

    for rel in [*R3_VARS, "tiles/crc"]:
        a = Path(src, rel, "c", *map(str, src_ij))
        b = Path(dst, rel, "c", *map(str, dst_ij))
        shutil.copyfile(a, b)


def _resume(path, window=R3_WINDOW):
    """Resume a store; the warnings it gives."""
    import warnings

    from stairbounce.atlas import scan_to_zarr

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ds = scan_to_zarr(path, tile=R3_TILE, **window)
    return ds, [str(w.message) for w in caught if issubclass(w.category, RuntimeWarning)]


@pytest.mark.parametrize("source", ["another tile", "another store", "the same tile of a twin store"])
def test_r3_a_tile_and_its_checksum_copied_from_elsewhere_fail_and_are_recomputed(tmp_path, source):
    """The report's cases (tile (0,0) replaced by tile (1,1) of the same store,
    or by tile (0,0) of another store of the same layout, data and checksum
    both) passed resume as complete; the pixels then differed from the scan.
    A variant: a twin store of the same window (the same bytes), its
    checksum copied: the store's token still tells it apart."""
    from stairbounce.atlas import scan_to_zarr

    path = tmp_path / "a.zarr"
    scan_to_zarr(path, tile=R3_TILE, **R3_WINDOW)
    if source == "another tile":
        _copy_tile(path, (1, 1), path, (0, 0))
    else:
        other = tmp_path / "other.zarr"
        scan_to_zarr(other, tile=R3_TILE, **(R3_OTHER if source == "another store" else R3_WINDOW))
        _copy_tile(other, (0, 0), path, (0, 0))
    ds, warned = _resume(path)
    assert any("no longer match their checksum" in w and "(0, 0)" in w for w in warned), warned
    ref = plane.scan(**R3_WINDOW)
    for k in R3_VARS:
        assert np.array_equal(ds[k].values, ref[k].values), k


def test_r3_a_store_of_before_keeps_resuming_and_its_checksums_are_bound_from_then_on(tmp_path):
    """A store written before the fix (checksums of the bytes only, no
    ``checksum`` attribute) resumes without recomputing its intact tiles;
    its checksums are then rewritten bound, so a copied tile is found next time."""
    import zarr

    from stairbounce import atlas

    path = tmp_path / "old.zarr"
    atlas.scan_to_zarr(path, tile=R3_TILE, **R3_WINDOW)
    g = zarr.open_group(str(path), mode="r+")
    rec = g["tiles"]
    del rec.attrs["checksum"]  # as written before
    rows, cols = atlas.tile_slices(38, R3_TILE), atlas.tile_slices(45, R3_TILE)
    for i, j in np.ndindex(3, 3):
        rec["crc"][i, j] = atlas._checksum({k: g[k][rows[i], cols[j]] for k in R3_VARS})
    calls = []
    orig = atlas._run_tile
    atlas._run_tile = lambda *a: calls.append(a) or orig(*a)
    try:
        ds, warned = _resume(path)
    finally:
        atlas._run_tile = orig
    assert warned == [] and calls == []  # intact: nothing recomputed
    assert zarr.open_group(str(path), mode="r")["tiles"].attrs["checksum"] == atlas.CHECKSUM
    _copy_tile(path, (2, 1), path, (1, 2))
    ds, warned = _resume(path)
    assert any("(1, 2)" in w for w in warned), warned
    ref = plane.scan(**R3_WINDOW)
    assert all(np.array_equal(ds[k].values, ref[k].values) for k in R3_VARS)


# --------------------------------------------------------------------------- #
# R9: a store whose array lost its metadata; R11: one writer per folder       #
# --------------------------------------------------------------------------- #


from .test_faults import run as _run_cli  # noqa: E402  (the CLI in process: exit status, out, err)
from .test_faults_round2 import kernel_changed  # noqa: E402
from .test_faults_round2 import one_line_error as _one_line_error  # noqa: E402


R3_SCAN = ["scan", "--e", "0.05:0.95", "--u", "0.1:1.4", "--size", "45x38", "--max-iter", "400"]


@pytest.mark.parametrize("damage", ["status/zarr.json", "word_length/zarr.json", "tiles/done/zarr.json", "status"])
def test_r9_a_store_whose_array_lost_its_metadata_is_one_line_everywhere(tmp_path, capsys, damage):
    """Report R9: ``rm s.zarr/status/zarr.json`` gave a 57-line ``KeyError:
    'status'`` traceback in ``render`` and in resume.  Now ``render``, resume
    (CLI and API) and ``load`` refuse it in one line naming the store; the
    variants: another array's metadata, the tile record's, a whole array gone."""
    import shutil

    from stairbounce.atlas import scan_to_zarr

    path = tmp_path / "s.zarr"
    scan_to_zarr(path, tile=R3_TILE, **R3_WINDOW)
    target = path / damage
    shutil.rmtree(target) if target.is_dir() else target.unlink()
    code, _, err = _run_cli(["render", path, "--png", tmp_path / "s.png"], capsys)
    assert code == 2 and _one_line_error(err) and str(path) in err, err
    assert not (tmp_path / "s.png").exists()
    code, _, err = _run_cli(R3_SCAN + ["--tile", R3_TILE, "--out", path], capsys)
    assert code == 2 and _one_line_error(err) and str(path) in err, err
    with pytest.raises(ValueError, match="s.zarr"):
        scan_to_zarr(path, tile=R3_TILE, **R3_WINDOW)
    if damage != "status":  # a whole variable gone is still a readable dataset for load
        with pytest.raises(ValueError, match="lost its metadata"):
            plane.load(path)


def test_r9_a_saved_scan_whose_array_lost_its_metadata_is_refused_by_load(tmp_path, capsys):
    path = tmp_path / "p.zarr"
    plane.save(plane.scan(e=(0.1, 0.9, 20), u=(0.2, 1.2, 16), max_iter=100), path)
    (path / "period" / "zarr.json").unlink()
    with pytest.raises(ValueError, match=r"p\.zarr.*'period'"):
        plane.load(path)
    code, _, err = _run_cli(["render", path, "--png", tmp_path / "p.png", "--field", "status"], capsys)
    assert code == 2 and _one_line_error(err), err


@pytest.fixture
def bind_alias(tmp_path):
    """The folder of a store mounted under another name (root only)."""
    import os
    import subprocess

    real = tmp_path / "d6" / "real.zarr"
    other = tmp_path / "d6other" / "other.zarr"
    real.mkdir(parents=True)
    other.mkdir(parents=True)
    if os.geteuid() != 0:
        pytest.skip("a bind mount needs root")
    r = subprocess.run(["mount", "--bind", str(real), str(other)], capture_output=True, text=True)
    if r.returncode != 0:
        pytest.skip(f"cannot bind-mount here: {r.stderr.strip()}")
    yield real, other
    subprocess.run(["umount", str(other)], capture_output=True)


def test_r11_a_store_bind_mounted_under_another_name_has_one_writer(bind_alias, tmp_path, capsys):
    """Report R11: the store folder bind-mounted under another name got a
    second writer (the lock file beside each name differed).  Now the folder
    is locked by its device and inode: a writer under either name refuses
    the other, through the API and the command line."""
    import os
    import shutil

    from stairbounce import _io
    from stairbounce.atlas import scan_to_zarr

    real, other = bind_alias
    build = tmp_path / "build.zarr"
    scan_to_zarr(build, tile=R3_TILE, **R3_WINDOW)
    for item in build.iterdir():
        (shutil.copytree if item.is_dir() else shutil.copyfile)(item, real / item.name)
    assert os.stat(real).st_ino == os.stat(other).st_ino and (other / "tiles").is_dir()
    with _io.store_lock(real):
        with pytest.raises(_io.StoreLockedError, match="inode"):
            scan_to_zarr(other, tile=R3_TILE, **R3_WINDOW)
        assert _io.lock_holder(other) is not None
        code, _, err = _run_cli(R3_SCAN + ["--tile", R3_TILE, "--out", other], capsys)
        assert code == 2 and _one_line_error(err) and "another stairbounce process" in err, err
        code, _, err = _run_cli(["scan", "--size", "16x16", "--max-iter", "20", "--out", other, "--force"], capsys)
        assert code == 2 and _one_line_error(err), err
    with _io.store_lock(other):  # the other way round
        with pytest.raises(_io.StoreLockedError):
            scan_to_zarr(real, tile=R3_TILE, **R3_WINDOW)
    ds = scan_to_zarr(other, tile=R3_TILE, **R3_WINDOW)  # free again
    assert np.array_equal(ds["period"].values, plane.scan(**R3_WINDOW)["period"].values)


# --------------------------------------------------------------------------- #
# R10: the figures' cache hits for every kind, and follows the code of each   #
# --------------------------------------------------------------------------- #


def _figures_cached(cache, kind, inputs, compute):
    from stairbounce import figures as F

    return F.settings._cached(F.Settings(out=cache, cache_dir=cache), kind, dict(inputs), compute)


BIF_INPUTS = {"e": 0.5, "u": [0.3, 1.0], "n": 40, "y0": 0.1, "v0": 0.0, "transient": 300, "keep": 50}


def _bifurcations():
    return structure.bifurcations.bifurcations(0.5, np.linspace(0.3, 1.0, 40), y0=0.1, v0=0.0, transient=300, keep=50)


def test_r10_a_bifurcations_entry_is_used_the_second_time(tmp_path):
    """Report R10 (d): a "bifurcations" entry never hit (its string variables
    read back as ``<U``, the checksum was of ``object`` arrays): every run
    recomputed it.  A variant: a dataset with a ``<U`` variable from the start."""
    import xarray as xr

    first = _figures_cached(tmp_path, "bifurcations", BIF_INPUTS, _bifurcations)
    assert first.sizes["bifurcation"] > 0 and any(first[k].dtype == object for k in first.variables)
    calls = []
    again = _figures_cached(tmp_path, "bifurcations", BIF_INPUTS, lambda: calls.append(1) or _bifurcations())
    assert calls == []
    for k in first.variables:
        assert np.array_equal(np.asarray(first[k].values, dtype=str if first[k].dtype == object else None),
                              np.asarray(again[k].values, dtype=str if first[k].dtype == object else None)), k
    texts = xr.Dataset({"w": ("i", np.array(["(1, 0^inf)", "(2, 0, 1, 0^inf)"]))})
    _figures_cached(tmp_path, "scan", {"x": 1}, lambda: texts)
    calls = []
    _figures_cached(tmp_path, "scan", {"x": 1}, lambda: calls.append(1) or texts)
    assert calls == []


def test_r10_the_kernel_hash_covers_every_module_that_computes_a_cached_entry(monkeypatch, tmp_path):
    """Report R10: the kernel hash left out borders.py, which computes the
    bifurcation entries (a change of it would reuse stale entries once they
    hit).  Every function whose result figures/ caches is in a hashed
    module, and a change of borders.py makes a new entry.  Since issue 36
    item 9 the bifurcations live in structure/bifurcations.py and the border
    kernels they call in structure/borders.py and structure/itinerary.py:
    every module of the structure package they import is hashed."""
    import re

    from stairbounce import _cache, figures, nonsliding, orbits

    sources = "".join(p.read_text() for p in Path(figures.__file__).parent.glob("*.py"))
    kinds = set(re.findall(r'_cached\(\s*settings, "([a-z_]+)"', sources))
    computed_by = {"scan": plane.scan, "orbits": orbits.orbit_diagram,
                   "bifurcations": structure.bifurcations.bifurcations,
                   "motion": nonsliding.motion_scan}
    assert kinds == set(computed_by)  # a new cached kind: name the function that computes it here
    hashed = {name for name, _ in _cache._kernel_sources()}
    for fn in computed_by.values():
        rel = Path(fn.__code__.co_filename).resolve().relative_to(Path(_cache.__file__).resolve().parent)
        assert rel.as_posix() in hashed, rel
    # not listed: followed from the modules that import them
    assert {"structure/regions.py", "structure/borders.py", "structure/itinerary.py", "structure/words.py"} <= hashed
    assert not {"borders.py", "regions.py", "_region_export.py"} & hashed  # the old paths' shims compute nothing
    _figures_cached(tmp_path, "bifurcations", BIF_INPUTS, _bifurcations)
    with kernel_changed(monkeypatch, "structure/borders.py"):
        calls = []
        _figures_cached(tmp_path, "bifurcations", BIF_INPUTS, lambda: calls.append(1) or _bifurcations())
        assert calls == [1]


# --------------------------------------------------------------------------- #
# R5: itinerary estimated up front, streamed by the command line              #
# --------------------------------------------------------------------------- #

NEAR_ONE = dict(e=0.9999999999999999, u=0.01768)  # the report's orbit: no slide for 2.5e8 steps and more


def test_r5_itinerary_refuses_a_max_iter_over_the_memory_before_it_starts(monkeypatch):
    """Report R5: ``itinerary(max_iter=2**31 - 1)`` near e = 1 grew to half the
    machine's memory (checked block by block against what was left) before it
    refused.  Now the estimate comes first, naming max_iter; nothing is
    computed.  The variants: another available memory, the largest max_iter."""
    from stairbounce import _validate

    calls = []
    orig = structure.itinerary._itinerary_block
    monkeypatch.setattr(structure.itinerary, "_itinerary_block", lambda *a: calls.append(1) or orig(*a))
    for avail, max_iter in [(64 << 20, 2_000_000), (1 << 30, 2**31 - 1)]:
        monkeypatch.setattr(_validate, "available_memory", lambda avail=avail: avail)
        with pytest.raises(ValueError, match=f"max_iter = {max_iter}.*memory"):
            structure.itinerary.itinerary(max_iter=max_iter, **NEAR_ONE)
        assert calls == []
    monkeypatch.setattr(_validate, "available_memory", lambda: 64 << 20)
    assert structure.itinerary.itinerary(0.02, 0.7, max_iter=100_000).sizes["step"] == 4  # a small one still runs


def _itinerary_peak(tmp_path, max_iter):
    """Peak resident memory (kB) of ``stairbounce itinerary --csv`` near e = 1
    in a process of its own, and its CSV's data rows."""
    import subprocess
    import sys

    code = ("import sys\nfrom stairbounce.cli import main\ntry:\n    main(sys.argv[1:])\n"
            "except SystemExit as exc:\n    assert exc.code in (0, None), exc.code\n"
            "sys.stderr.write('HWM ' + open('/proc/self/status').read().split('VmHWM:')[1].split()[0])")
    out = tmp_path / f"it{max_iter}.csv"
    with open(out, "w") as f:
        r = subprocess.run([sys.executable, "-c", code, "itinerary", "--e", repr(NEAR_ONE["e"]), "--u",
                            repr(NEAR_ONE["u"]), "--max-iter", str(max_iter), "--csv"], stdout=f,
                           stderr=subprocess.PIPE, text=True, env={**__import__("os").environ, "PYTHONPATH": SRC})
    assert r.returncode == 0, r.stderr
    rows = sum(1 for _ in open(out)) - 1
    return int(r.stderr.rsplit("HWM ", 1)[1]), rows


SRC = str(Path(__file__).resolve().parents[1] / "src")


def test_r5_the_itinerary_command_streams_its_rows(tmp_path):
    """The command line writes the itinerary block by block: 400 000 steps
    (the whole itinerary: 19 MB in blocks, as much again joined) cost its
    process no more memory than 1000 steps, to a few MB."""
    base, n0 = _itinerary_peak(tmp_path, 1000)
    peak, n = _itinerary_peak(tmp_path, 400_000)
    assert (n0, n) == (1000, 400_000)
    assert peak - base < 12_000, (base, peak)  # kB


def test_r5_issue37_the_itinerary_command_says_its_convention_and_the_word(capsys):
    """Issue 37: the margins came without their sign convention and the word
    they spell was not printed."""
    from stairbounce.symbolic import sliding_word

    from .test_faults import run

    word = sliding_word(0.02, 0.7).format(ascii=True)
    code, out, err = run(["itinerary", "--e", "0.02", "--u", "0.7"], capsys)
    assert code == 0, err
    assert ">= 0: the event happens on the step" in out and "accumulation point (>= 0: the step slides" in out
    assert f"slides on step 4; the impact numbers spell the word {word}" in out
    code, out, err = run(["itinerary", "--e", "0.02", "--u", "0.7", "--csv"], capsys)
    assert code == 0 and len(out.strip().splitlines()) == 5  # the CSV alone on stdout
    assert word in err and ">= 0: the event happens" in err
    code, out, err = run(["itinerary", "--e", "0.3", "--u", "3", "--max-iter", "50"], capsys)
    assert code == 0 and "no slide within 50 steps (no word)" in out


# --------------------------------------------------------------------------- #
# Observation: a Dask scan without workers says so                            #
# --------------------------------------------------------------------------- #


@pytest.mark.filterwarnings("ignore:Port 8787 is already in use")
def test_observation_a_tiled_scan_without_workers_says_so_and_goes_on_when_they_come(tmp_path, capsys, monkeypatch):
    """Report (observations): when every Dask worker is gone the client waits
    silently.  Now the command line says "waiting for workers: none
    connected" after a while, and the scan goes on once a worker connects."""
    import threading

    distributed = pytest.importorskip("distributed")
    from stairbounce import atlas

    from .test_faults import run

    monkeypatch.setattr(atlas, "WAIT_NOTE", 1.0, raising=False)
    cluster = distributed.LocalCluster(n_workers=0, processes=False, dashboard_address=None)
    note = getattr(atlas, "_cluster_note", lambda client, waited: None)
    said = []
    fallback = threading.Timer(20.0, lambda: cluster.scale(1))  # a silent client: a worker comes anyway
    fallback.daemon = True
    fallback.start()

    def noted(client, waited):  # once it is said, a worker comes
        text = note(client, waited)
        if text is not None and not said:
            said.append(text)
            threading.Timer(0.5, lambda: cluster.scale(1)).start()
        return text

    monkeypatch.setattr(atlas, "_cluster_note", noted, raising=False)
    try:
        path = tmp_path / "s.zarr"
        code, out, err = run(R3_SCAN + ["--tile", R3_TILE, "--out", path, "--scheduler", cluster.scheduler_address],
                             capsys)
    finally:
        fallback.cancel()
        cluster.close()
    assert code in (0, None), err
    assert "stairbounce: warning: waiting for workers: none connected" in err, err
    assert f"wrote {path}" in out
    assert np.array_equal(plane.load(path)["period"].values, plane.scan(**R3_WINDOW)["period"].values)


def test_observation_a_scheduler_that_does_not_answer_is_said():
    """The stopped scheduler (SIGSTOP) of the report: it does not answer."""
    from types import SimpleNamespace

    from stairbounce import atlas

    def no_answer(callback_timeout=None):
        raise TimeoutError("timed out")

    client = SimpleNamespace(scheduler=SimpleNamespace(address="tcp://10.0.0.1:8786"), nthreads=no_answer)
    note = atlas._cluster_note(client, 42.0)
    assert "tcp://10.0.0.1:8786: it does not answer" in note and "42 s" in note
    busy = SimpleNamespace(scheduler=SimpleNamespace(address="x"), nthreads=lambda callback_timeout=None: {"w": 1})
    assert atlas._cluster_note(busy, 42.0) is None
