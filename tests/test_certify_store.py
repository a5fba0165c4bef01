"""The streamed certified atlas (issue 44): sb.certify_to_zarr writes the same boxes as
sb.certify, bit for bit, tile by tile into a resumable Zarr store."""

import importlib
import warnings

import pytest

import stairbounce as sb

from ._cli import run_cli as _cli

C = importlib.import_module("stairbounce.structure.certify")
S = importlib.import_module("stairbounce.structure.certify_store")

FIG7 = dict(e=(0.155, 0.2138), u=(0.6, 0.658))
OTHER = dict(e=(0.3, 0.45), u=(0.45, 0.6))
_REFS = {}


def reference(**kw):
    key = tuple(sorted((k, str(v)) for k, v in kw.items()))
    if key not in _REFS:
        _REFS[key] = sb.certify(**kw).boxes
    return _REFS[key]


def assert_same_atlas(got, ref):
    assert list(got.variables) == list(ref.variables)
    for name in ref.variables:
        a, b = ref[name].values, got[name].values
        assert ref[name].dims == got[name].dims, name
        if a.dtype.kind in "OU":
            assert b.dtype.kind in "OU", name
            assert a.astype(str).tolist() == b.astype(str).tolist(), name
        else:
            assert a.dtype == b.dtype, name
            # bit for bit (floats compared by their bytes)
            assert a.shape == b.shape and a.tobytes() == b.tobytes(), name
    skip = {"trap_seconds"}  # a time, summed over the tiles
    assert {k: v for k, v in got.attrs.items() if k not in skip} == \
        {k: v for k, v in ref.attrs.items() if k not in skip}


@pytest.mark.parametrize("kw, tiling", [
    (dict(FIG7, depth=7), dict(tile_level=5, tile_boxes=40)),
    (dict(FIG7, depth=6), dict()),                                   # the default tile level: the last level
    (dict(OTHER, depth=6, max_iter=300), dict(tile_level=3, tile_boxes=7)),
    (dict(FIG7, depth=6, trap=True), dict(tile_level=4, tile_boxes=20)),
    (dict(FIG7, depth=6, trap="fine"), dict(tile_level=4, tile_boxes=20)),
    (dict(OTHER, depth=6, classes=True), dict(tile_level=4, tile_boxes=30)),
])
def test_the_store_holds_the_in_memory_boxes_bit_for_bit(tmp_path, kw, tiling):
    st = sb.certify_to_zarr(tmp_path / "a.zarr", **kw, **tiling)
    ref = reference(**kw)
    assert_same_atlas(sb.CertifiedAtlas.load(tmp_path / "a.zarr").boxes, ref)
    assert st.boxes == ref.sizes["box"]
    # the streamed proven numbers: bounds as the in-memory atlas's, within a few floats
    atlas = sb.CertifiedAtlas(ref)
    for by in ("status", "reason", "word"):
        mine, theirs = st.fraction(by, "both"), atlas.fraction(by, "both")
        assert set(mine) == set(theirs)
        for k, (lo, hi) in theirs.items():
            assert lo <= hi and mine[k][0] <= mine[k][1]
            assert mine[k][0] == pytest.approx(lo, rel=1e-13, abs=1e-300)
            assert mine[k][1] == pytest.approx(hi, rel=1e-13, abs=1e-300)
    for w in list(atlas.fraction("word"))[:3]:
        assert st.word_area_bounds(w) == pytest.approx(atlas.word_area_bounds(w), rel=1e-13)
    # the perimeter's box counts taken tile by tile: the loaded atlas's, integer for integer
    # (with the proven points inside undecided boxes: a cell coarser than the tile level
    # spans tiles, where each tile proves its own, so the store proves at least as many)
    streamed, loaded = st.border_box_counts(), atlas.border_box_counts()
    assert streamed.equals(loaded)
    drop = lambda a: {k: v for k, v in a.items() if not k.startswith("witnesses")}  # noqa: E731
    assert drop(streamed.attrs) == drop(loaded.attrs)
    assert streamed.attrs["witnesses"] >= loaded.attrs["witnesses"]
    assert loaded["upper"].iloc[-1] > 0
    # without them, the counts of the boxes alone, equal too and never above
    bare = st.border_box_counts(witnesses=False)
    assert bare.equals(atlas.border_box_counts(witnesses=False))
    assert (bare["lower"] <= loaded["lower"]).all() and (loaded["lower"] <= loaded["upper"]).all()
    assert bare.attrs["witnesses"] == 0


def test_the_store_s_perimeter_bracket_is_the_loaded_atlas_s(tmp_path):
    """Issue 44 items 1 and 4: CertifiedStore.perimeter_bracket (counts tile by tile, the
    checker on the store tile by tile) gives the dict of the loaded atlas's, basis
    "proven"; lower counts > 0 at several scales, so the comparison could differ."""
    kw = dict(e=(0.0, 0.333), u=(0.4, 0.733), depth=8, classes=True, trap=True)
    st = sb.certify_to_zarr(tmp_path / "a.zarr", **kw, tile_level=5, tile_boxes=64)
    seen = []
    got = st.perimeter_bracket(progress=lambda d, t: seen.append((d, t)))
    want = st.load().perimeter_bracket()
    # the same dict but the number of proven points (a store proves those of a cell
    # coarser than its tile level in each tile the cell spans)
    drop = lambda r: {k: v for k, v in r.items() if not k.startswith("witnesses")}  # noqa: E731
    assert drop(got) == drop(want) and got["basis"] == "proven" and sum(x > 0 for x in got["lower"]) >= 3
    assert got["witnesses"] >= want["witnesses"] > 0
    assert seen[-1][0] == seen[-1][1] == len(seen) > 2
    assert drop(st.perimeter_bracket(2, 6, verify=False)) == drop(st.load().perimeter_bracket(2, 6, verify=False))
    with pytest.raises(ValueError, match="border must be sliding"):
        st.border_box_counts(border="words")
    with pytest.raises(ValueError, match="verify must be True or False"):
        st.perimeter_bracket(verify="yes")
    with pytest.raises(ValueError, match="k2"):
        st.perimeter_bracket(3, 3)


def test_streamed_counts_refuse_a_store_cut_elsewhere_and_an_uncovered_window(tmp_path):
    """The per-tile lower counts rest on each level-T cell's boxes lying in one tile: a
    store whose stated tile level is coarser than its cut is refused, by name; boxes
    that do not add up to the window give no counts."""
    import zarr

    B = importlib.import_module("stairbounce.structure.border_counts")
    sb.certify_to_zarr(tmp_path / "a.zarr", **FIG7, depth=6, tile_level=5, tile_boxes=20)
    root = zarr.open_group(str(tmp_path / "a.zarr"), mode="r+")
    root.attrs["tile_level"] = 3
    with pytest.raises(ValueError, match="not cut at its tile level 3"):
        S.CertifiedStore(tmp_path / "a.zarr").border_box_counts()
    np = pytest.importorskip("numpy")
    acc = B.StreamedCounts(((0.0, 1.0), (0.0, 1.0)), 2, 2, 1)
    acc.add(0, np.array([1, 1, 1]), np.array([0, 1, 0]), np.array([0, 0, 1]), np.array([0, 3, 1], np.int8))
    with pytest.raises(ValueError, match="do not cover the window"):
        acc.rows()
    acc.add(1, np.array([1]), np.array([1]), np.array([1]), np.array([3], np.int8))
    # the window in four level-1 boxes: (i, j) = (0, 0) a word, (0, 1) not sliding, (1, 0) and
    # (1, 1) undecided.  k = 0: one cell with both classes; k = 1: each cell one box, every
    # cell touching an undecided box; k = 2: the 4 x 4 cells of i >= 1 (i = 1 meets the
    # undecided boxes' closure at their side), 12
    rows = acc.rows()
    assert [r["lower"] for r in rows] == [1, 0, 0] and [r["upper"] for r in rows] == [1, 4, 12]


def test_the_default_tile_level():
    assert [S._default_tile_level(d) for d in (0, 3, 7, 8, 13, 14, 16)] == [0, 3, 7, 7, 7, 8, 10]


def test_an_interrupted_store_resumes_with_only_the_missing_tiles(tmp_path, monkeypatch):
    kw = dict(FIG7, depth=7, tile_level=5, tile_boxes=40)
    path = tmp_path / "a.zarr"

    def stop(done, total):
        if done >= 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        sb.certify_to_zarr(path, progress=stop, **kw)
    with pytest.raises(ValueError, match="incomplete"):
        sb.CertifiedAtlas.load(path)
    computed, seen = [], []
    original = S._compute_tile
    monkeypatch.setattr(S, "_compute_tile", lambda *a, **k: computed.append(1) or original(*a, **k))
    st = sb.certify_to_zarr(path, progress=lambda d, t: seen.append((d, t)), **kw)
    total = st.attrs["n_tiles"]
    assert seen[0] == (3, total) and seen[-1] == (total, total)
    assert len(computed) == total - 3
    assert_same_atlas(sb.CertifiedAtlas.load(path).boxes, reference(**FIG7, depth=7))


def test_other_arguments_on_an_existing_store_are_refused_by_name(tmp_path):
    path = tmp_path / "a.zarr"
    sb.certify_to_zarr(path, **FIG7, depth=5)
    with pytest.raises(ValueError, match="max_iter: store 1000, asked 500"):
        sb.certify_to_zarr(path, **FIG7, depth=5, max_iter=500)
    with pytest.raises(ValueError, match="trap"):
        sb.certify_to_zarr(path, **FIG7, depth=5, trap=True)
    sb.certify_to_zarr(tmp_path / "t.zarr", **FIG7, depth=5, trap=True)
    with pytest.raises(ValueError, match="trap: store True, asked 'fine'"):
        sb.certify_to_zarr(tmp_path / "t.zarr", **FIG7, depth=5, trap="fine")
    (tmp_path / "b.zarr").mkdir()
    with pytest.raises(ValueError, match="not a certified atlas store"):
        sb.certify_to_zarr(tmp_path / "b.zarr", **FIG7, depth=5)


@pytest.mark.parametrize("kw, match", [
    (dict(depth=27), "depth"), (dict(max_iter=0), "max_iter"), (dict(form="x"), "form"),
    (dict(tile_level=2, depth=6), "tile_level"), (dict(tile_boxes=0), "tile_boxes"), (dict(trap=1), "trap"),
    (dict(client=3), "client"),
])
def test_bad_arguments_are_refused_by_name(tmp_path, kw, match):
    with pytest.raises(ValueError, match=match):
        sb.certify_to_zarr(tmp_path / "a.zarr", **{**FIG7, "depth": 5, **kw})
    assert not (tmp_path / "a.zarr").exists()
    with pytest.raises(ValueError, match="zarr"):
        sb.certify_to_zarr(tmp_path / "a.nc", **FIG7, depth=5)


def test_a_damaged_tile_is_found_by_its_checksum_and_computed_again(tmp_path):
    kw = dict(FIG7, depth=6, tile_level=4, tile_boxes=20)
    path = tmp_path / "a.zarr"
    sb.certify_to_zarr(path, **kw)
    chunk = next(p for p in (path / "boxes" / "000002" / "e0").rglob("*") if p.is_file() and p.name != "zarr.json")
    chunk.write_bytes(chunk.read_bytes()[:-3] + b"xyz")
    with pytest.raises(ValueError, match="tile 2 .* checksum"):
        sb.CertifiedAtlas.load(path)
    with pytest.raises(ValueError, match="tile 2"):
        sb.verify(path)
    with pytest.warns(RuntimeWarning, match="1 complete tile.* tile 2"):
        sb.certify_to_zarr(path, **kw)
    assert_same_atlas(sb.CertifiedAtlas.load(path).boxes, reference(**FIG7, depth=6))


def test_verify_checks_a_store_as_a_whole_atlas(tmp_path, monkeypatch):
    path = tmp_path / "a.zarr"
    sb.certify_to_zarr(path, **FIG7, depth=6, tile_level=4, tile_boxes=20)
    v = sb.verify(path)
    assert v.ok and v.atlas and v.complete and v.checked == reference(**FIG7, depth=6).sizes["box"]

    verify_module = importlib.import_module("stairbounce.structure.verify")
    # the limit holds for each tile (a store is checked a tile at a time), not for the whole store
    sizes = []
    for k in range(int(S.CertifiedStore(path).attrs["n_tiles"])):
        arrays, _ = importlib.import_module("stairbounce.structure._store_read").read_tile(path, k)
        sizes.append(arrays["offsets"].size - 1 + arrays["itinerary"].size)
    monkeypatch.setattr(verify_module, "MAX_WORK", max(sizes))
    assert sum(sizes) > max(sizes) and sb.verify(path).ok  # the whole store is above the limit
    monkeypatch.setattr(verify_module, "MAX_WORK", max(sizes) - 1)
    worst = sizes.index(max(sizes))
    with pytest.raises(ValueError, match=f"tile {worst} of the atlas store .* units of checking work"):
        sb.verify(path)


def test_a_store_is_one_writer_at_a_time(tmp_path):
    from stairbounce._io import StoreLockedError, store_lock

    path = tmp_path / "a.zarr"
    with store_lock(path.resolve()):
        with pytest.raises(StoreLockedError):
            sb.certify_to_zarr(path, **FIG7, depth=5)


def test_a_level_beyond_the_machines_memory_is_refused_before_its_work(monkeypatch):
    monkeypatch.setattr(C, "_available_memory", lambda: 10_000)
    with pytest.raises(ValueError, match=r"certify: depth 6 needs about .* GiB at level \d, more than this "
                                         r"machine's 0.0 GiB available; use certify_to_zarr / --store"):
        sb.certify(**FIG7, depth=6)
    monkeypatch.setattr(C, "_available_memory", lambda: None)  # unknown: no refusal
    assert sb.certify(**FIG7, depth=4).boxes.sizes["box"] > 0


def test_dask_workers_write_the_same_tiles(tmp_path):
    distributed = pytest.importorskip("distributed")
    kw = dict(FIG7, depth=6, tile_level=4, tile_boxes=20)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                      dashboard_address=None) as cluster, distributed.Client(cluster) as c:
            sb.certify_to_zarr(tmp_path / "a.zarr", client=c, **kw)
    assert_same_atlas(sb.CertifiedAtlas.load(tmp_path / "a.zarr").boxes, reference(**FIG7, depth=6))


@pytest.mark.slow
def test_a_killed_dask_worker_s_tiles_are_computed_again(tmp_path):
    """Issue 44 item 2: a worker process killed (SIGKILL) while tiles are in flight; Dask
    reschedules its tasks on the worker left and the store ends equal to sb.certify's
    atlas, box for box (long orbits, max_iter 20000, so that tiles are still running)."""
    import os
    import signal

    distributed = pytest.importorskip("distributed")
    kw = dict(FIG7, depth=8, tile_level=5, tile_boxes=6, max_iter=20_000)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                      dashboard_address=None) as cluster, distributed.Client(cluster) as c:
            pids = list(c.run(os.getpid).values())
            killed, totals = [], []

            def progress(done, total):
                totals.append(total)
                if done >= 2 and not killed:  # tile 0 is computed here; one task has ended
                    os.kill(pids[0], signal.SIGKILL)
                    killed.append(done)

            sb.certify_to_zarr(tmp_path / "a.zarr", client=c, progress=progress, **kw)
            assert killed and killed[0] < totals[-1] - 2  # the kill came with tiles still to do
            assert pids[0] not in c.run(os.getpid).values()
    assert_same_atlas(sb.CertifiedAtlas.load(tmp_path / "a.zarr").boxes, reference(**FIG7, depth=8, max_iter=20_000))


def test_cli_store_resume_verify_and_errors(tmp_path, capsys):
    store = str(tmp_path / "s.zarr")
    args = ["certify", "--depth", "5", "--top", "2"]
    code, out, err = _cli(args + ["--store", store], capsys)
    assert code == 0, err
    assert "wrote" in out and "proven words" in out
    assert _cli(args + ["--store", store], capsys)[0] == 0  # resumed: nothing to do
    code, out, err = _cli(["certify", "--verify", store], capsys)
    assert code == 0 and "0 rejected" in out
    for extra, message in ((["--store", store, "--depth", "6"], "depth: store 5, asked 6"),
                           (["--store", store, "--out", str(tmp_path / "a.nc")], "--store"),
                           (["--scheduler", "tcp://127.0.0.1:1"], "--scheduler needs --store"),
                           (["--store", str(tmp_path / "x.nc")], "--store must be a .zarr")):
        code, out, err = _cli(args + extra, capsys)
        assert code == 2, (extra, err)
        assert message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_cli_classes_and_the_perimeter_of_a_verified_store_or_file(tmp_path, capsys):
    """certify --classes (class-level proofs, in a store or in memory), then --verify
    --perimeter: the counts printed per scale are the API's (a store's tile by tile, a
    file's loaded), basis proven; --perimeter without --verify is one line, status 2."""
    import re

    store, nc = str(tmp_path / "s.zarr"), str(tmp_path / "a.nc")
    args = ["certify", "--depth", "6", "--classes", "--top", "1"]
    code, out, err = _cli(args + ["--store", store], capsys)
    assert code == 0 and "sliding " in out.split("proven: at least")[1].split("\n")[0], (out, err)
    assert _cli(args + ["--out", nc], capsys)[0] == 0
    for path in (store, nc):
        code, out, err = _cli(["certify", "--verify", path, "--perimeter"], capsys)
        assert code == 0, err
        r = (S.CertifiedStore(path) if path == store else sb.CertifiedAtlas.load(path)).perimeter_bracket()
        assert "proven box counts of the sliding border (basis: proven, certify depth 6" in out
        for k, lo, up in zip(r["k"], r["lower"], r["upper"]):
            assert re.search(rf"k = +{k}  window/{1 << k} +lower +{lo:,}  upper +{up:,}\n", out), (k, out)
        assert sum(r["lower"]) > 0 and f"slope {r['slope_text']}" in out and "not proven:" in out
    code, out, err = _cli(["certify", "--perimeter"], capsys)
    assert code == 2 and "--perimeter goes with --verify" in err and len(err.strip().splitlines()) == 1


def test_ragged_rows_are_taken_as_the_rows_concatenated():
    """_take_rows (a compiled loop) against the rows sliced and concatenated in Python:
    any order, empty rows, other dtypes; rows outside the values refused."""
    R = importlib.import_module("stairbounce.structure._store_read")
    np = pytest.importorskip("numpy")
    rng = np.random.default_rng(4)
    lengths = rng.integers(0, 5, 50)
    starts = np.cumsum(lengths) - lengths
    for values in (np.arange(int(lengths.sum())) * 3, rng.normal(size=int(lengths.sum())),
                   rng.integers(-9, 9, int(lengths.sum())).astype(np.int8)):
        for order in (rng.permutation(50), np.arange(50)[::-1], np.array([], np.int64)):
            want = (np.concatenate([values[starts[k]:starts[k] + lengths[k]] for k in order]) if order.size
                    else values[:0])
            got = R._take_rows(values, starts[order], lengths[order])
            assert got.dtype == values.dtype and np.array_equal(got, want)
    for s, n in (([0], [-1]), ([-1], [1]), ([int(lengths.sum())], [1])):
        with pytest.raises(ValueError, match="outside"):
            R._take_rows(np.arange(int(lengths.sum())), np.array(s), np.array(n))


# ------------------------------------------------- verify a store tile by tile

V = importlib.import_module("stairbounce.structure.verdict")
R = importlib.import_module("stairbounce.structure._store_read")


def _tva():
    """The tamperings of tests/test_verify_atlas.py (reused on a store's tiles)."""
    import importlib.util
    from pathlib import Path

    if "_tva" not in _REFS:
        spec = importlib.util.spec_from_file_location("_tamper_cases", Path(__file__).with_name("test_verify_atlas.py"))
        _REFS["_tva"] = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(_REFS["_tva"])
    return _REFS["_tva"]


def _whole(path):
    """Today's whole-atlas verdict: the store merged in memory, then checked."""
    return V._verify_dataset(R.read_store(path))


def _bits(x):
    """A verdict's fields with every float as its bits (0.0 and -0.0 differ)."""
    if isinstance(x, float):
        return x.hex()
    if isinstance(x, dict):
        return {k: _bits(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_bits(v) for v in x]
    return x


def assert_same_verdict(got, want):
    fields = ("ok", "check", "step", "message", "checked", "rejected", "atlas", "complete", "numbers")
    assert {f: _bits(getattr(got, f)) for f in fields} == {f: _bits(getattr(want, f)) for f in fields}


@pytest.mark.parametrize("kw, tiling", [
    (dict(FIG7, depth=7), dict(tile_level=5, tile_boxes=40)),
    (dict(FIG7, depth=6, trap=True), dict(tile_level=4, tile_boxes=20)),
    (dict(OTHER, depth=6, classes=True), dict(tile_level=3, tile_boxes=7)),
])
def test_a_store_verified_tile_by_tile_gives_the_whole_atlas_s_verdict(tmp_path, kw, tiling, monkeypatch):
    path = tmp_path / "a.zarr"
    st = sb.certify_to_zarr(path, **kw, **tiling)
    assert st.attrs["n_tiles"] > 2
    merged = []
    monkeypatch.setattr(R, "read_store", lambda p: merged.append(p))  # sb.verify never holds the whole table
    v = sb.verify(path)
    monkeypatch.undo()
    assert not merged
    assert v.ok and v.complete and v.checked == reference(**kw).sizes["box"]
    assert v.numbers["of"] == "the window"
    assert set(v.numbers["words"]) == set(sb.CertifiedAtlas(reference(**kw)).fraction("word"))
    assert_same_verdict(v, _whole(path))
    assert_same_verdict(v, sb.verify(sb.CertifiedAtlas.load(path)))  # and the in-memory atlas's


def test_exact_sums_are_fsum_s_floats():
    np = pytest.importorskip("numpy")
    import math

    rng = np.random.default_rng(44)
    for n in (1, 2, 7, 1000):
        for scale in (1e-3, 1e-300, 1e300, 5e-324):
            x = rng.random(n) * scale
            x[: n // 3] = np.float64(scale)  # repeated values: sums on the ties of rounding
            areas = V._ExactAreas()
            half = n // 2
            areas.add(np.zeros(half, np.int64), ["g"], x[:half], x[:half])
            areas.add(np.zeros(n - half, np.int64), ["g"], x[half:], x[half:])
            _, lo, hi = areas.sums["g"]
            assert lo / (1 << 1126) == math.fsum(x.tolist()) and lo == hi
    # halfway between two floats: ties to even, as fsum
    for parts in ([1.0, 2.0 ** -53], [1.0, 3 * 2.0 ** -53], [1.0 + 2.0 ** -52, 2.0 ** -53], [1e16, 1.0, 1e-16]):
        areas = V._ExactAreas()
        areas.add(np.zeros(len(parts), np.int64), ["g"], np.array(parts), np.array(parts))
        assert areas.sums["g"][1] / (1 << 1126) == math.fsum(parts)


def _rewrite_tile(path, k, change):
    """Tile ``k`` of a store replaced by ``change(raw table)``, with a new checksum (as a
    writer could forge it): what reaches the checker."""
    import os
    import shutil

    import numpy as np
    import xarray as xr
    import zarr

    from stairbounce.atlas import _checksum

    arrays, attrs = R.read_tile(path, k)
    ds = xr.Dataset({name: (R.DIMS.get(name, ("box",)), a) for name, a in arrays.items()}, attrs=attrs)
    ds = change(ds)
    ds.attrs = {a: (list(v) if isinstance(v, tuple) else v) for a, v in ds.attrs.items()}
    folder = os.path.join(path, R.BOXES, R.tile_name(k))
    shutil.rmtree(folder)
    ds.to_zarr(folder, mode="w", consolidated=False, zarr_format=3)
    arrays, attrs = R.read_tile(path, k)
    record = zarr.open_group(str(path), mode="r+")[R.RECORD]
    record["crc"][k] = _checksum(R.tile_values(arrays, attrs), R.tile_seed(record.attrs["token"], k))
    assert np.asarray(record["done"][...]).all()


@pytest.fixture(scope="module")
def plain_store(tmp_path_factory):
    path = tmp_path_factory.mktemp("store") / "plain.zarr"
    sb.certify_to_zarr(path, **FIG7, depth=7, tile_level=5, tile_boxes=40)
    return path


@pytest.fixture(scope="module")
def trapped_store(tmp_path_factory):
    path = tmp_path_factory.mktemp("store") / "trapped.zarr"
    sb.certify_to_zarr(path, e=(0.2, 0.4), u=(0.3, 0.5), depth=5, trap=True, tile_level=4, tile_boxes=8)
    return path


def _copy(store, tmp_path):
    import shutil

    shutil.copytree(store, tmp_path / "t.zarr")
    return tmp_path / "t.zarr"


def _tile_atlas(path, k):
    arrays, attrs = R.read_tile(path, k)
    return sb.CertifiedAtlas(R.merge_tiles([(arrays, attrs)], arrays["offsets"].size - 1, arrays["itinerary"].size))


TILE = 2  # a tile of the plain store's with several words


@pytest.mark.parametrize("kind", ["edited word_names", "reversed word_names", "swapped word_code", "duplicated boxes",
                                  "boxes from another window", "permuted level/i/j", "removed boxes"])
def test_a_store_tampered_within_a_tile_is_judged_as_the_whole_atlas(kind, plain_store, tmp_path):
    tva = _tva()
    path = _copy(plain_store, tmp_path)
    atlas = _tile_atlas(path, TILE)
    _rewrite_tile(path, TILE, lambda ds: tva._tamper(kind, ds, ".zarr", atlas))
    v = sb.verify(path)
    assert_same_verdict(v, _whole(path))
    if kind == "removed boxes":
        assert v.ok and v.complete is False and "do not cover the window" in v.message
        assert v.numbers["of"] == "the covered part"
    else:
        assert not v and v.rejected >= 1 and v.numbers is None, v.message
        assert v.check in ("word", "place", "overlap"), v.check


def test_a_widened_window_in_tile_0_rejects_every_tile_s_boxes(plain_store, tmp_path):
    tva = _tva()
    path = _copy(plain_store, tmp_path)
    _rewrite_tile(path, 0, lambda ds: tva._tamper("widened e_range", ds, ".zarr", None))
    v = sb.verify(path)
    assert_same_verdict(v, _whole(path))
    assert not v and v.check == "place" and v.rejected == v.checked


def _move(src, dst, rows, keep):
    """Tamperings across tiles: boxes ``rows`` of tile ``src`` appended to tile ``dst``
    (``keep``: left in ``src`` too, a duplicate; else moved)."""
    import numpy as np

    def change(path):
        arrays, attrs = R.read_tile(path, src)
        moved = {}
        for name in ("e0", "e1", "u0", "u1", "status", "step", "level", "i", "j", "word_code", "reason_code"):
            moved[name] = arrays[name][rows]
        moved["words"] = np.array(attrs["word_names"] + [""], dtype=object)[:-1][arrays["word_code"][rows]]
        moved["reasons"] = np.array(attrs["reason_names"] + [""], dtype=object)[:-1][arrays["reason_code"][rows]]
        off = arrays["offsets"]
        moved["pieces"] = [arrays["itinerary"][off[r]:off[r + 1]] for r in rows]
        tva = _tva()

        def add(ds):
            n = ds.sizes["box"]
            names = {key: list(ds.attrs[f"{key}_names"]) for key in ("word", "reason")}
            out = ds.drop_vars(["offsets", "itinerary"])
            cols = {}
            for name in ("e0", "e1", "u0", "u1", "status", "step", "level", "i", "j"):
                cols[name] = np.concatenate([ds[name].values, moved[name]])
            for key, texts in (("word", moved["words"]), ("reason", moved["reasons"])):
                for t in texts:
                    if t not in names[key]:
                        names[key].append(t)
                codes = np.array([names[key].index(t) for t in texts], np.int32)
                cols[f"{key}_code"] = np.concatenate([ds[f"{key}_code"].values, codes])
                out.attrs[f"{key}_names"] = names[key]
            out = out.drop_vars(list(cols)).assign({k: ("box", v) for k, v in cols.items()})
            off = ds["offsets"].values
            pieces = [ds["itinerary"].values[off[b]:off[b + 1]] for b in range(n)] + moved["pieces"]
            lengths = np.array([p.size for p in pieces], np.int64)
            return out.assign(offsets=("offset", np.concatenate([[0], np.cumsum(lengths)])),
                              itinerary=("itinerary_step", np.concatenate(pieces)))

        _rewrite_tile(path, dst, add)
        if not keep:
            _rewrite_tile(path, src, lambda ds: tva._take_boxes(ds, np.setdiff1d(np.arange(ds.sizes["box"]), rows)))
    return change


@pytest.mark.parametrize("how", ["duplicate", "moved"])
def test_boxes_across_tiles_overlap_exactly_when_they_do(how, plain_store, tmp_path):
    import numpy as np

    path = _copy(plain_store, tmp_path)
    rows = np.array([0, 3, 17])
    _move(4, 1, rows, keep=how == "duplicate")(path)
    v = sb.verify(path)
    assert_same_verdict(v, _whole(path))
    if how == "duplicate":  # the copies in tile 1 overlap their originals in tile 4
        assert not v and v.check == "overlap" and v.rejected == rows.size, v.message
    else:  # the same boxes cut into other tiles: still the atlas, verified
        assert v.ok and v.complete, v.message
        assert_same_verdict(v, sb.verify(plain_store))


@pytest.mark.parametrize("kind", ["reason codes", "reason_names reversed"])
def test_tampered_reasons_in_a_tile_of_a_trapped_store_are_rejected(kind, trapped_store, tmp_path):
    import numpy as np

    tva = _tva()
    path = _copy(trapped_store, tmp_path)
    k = next(k for k in range(1, sb.CertifiedStore(path).attrs["n_tiles"])
             if (_tile_atlas(path, k).boxes["reason"].values == "trapping").any()
             and (_tile_atlas(path, k).boxes["reason"].values == "").any())
    _rewrite_tile(path, k, lambda ds: tva._tamper(kind, ds, ".zarr", None))
    v = sb.verify(path)
    assert_same_verdict(v, _whole(path))
    assert not v and v.rejected >= 1 and v.check in ("reason", "corollary", "trapping"), v.message
    assert np.all(np.isfinite([v.checked, v.rejected]))


def test_a_code_outside_a_tile_s_names_list_is_refused_naming_the_tile(plain_store, tmp_path):
    path = _copy(plain_store, tmp_path)

    def negative(ds):
        c = ds["word_code"].values.copy()
        c[1] = -1  # numpy would take the last name
        return ds.assign(word_code=("box", c))

    _rewrite_tile(path, 3, negative)
    for f in (sb.verify, sb.CertifiedAtlas.load):
        with pytest.raises(ValueError, match="tile 3: word_code -1 at row 1 of a tile is outside its names list"):
            f(path)


def test_a_store_s_tiles_checked_in_two_processes_give_the_same_verdict(plain_store, tmp_path):
    assert_same_verdict(sb.verify(plain_store, workers=2), sb.verify(plain_store))
    with pytest.raises(ValueError, match="workers"):
        sb.verify(plain_store, workers=0)
    path = _copy(plain_store, tmp_path)
    atlas = _tile_atlas(path, TILE)
    _rewrite_tile(path, TILE, lambda ds: _tva()._tamper("swapped word_code", ds, ".zarr", atlas))
    v = V._verify_store(path, workers=2)
    assert not v and v.check == "word"
    assert_same_verdict(v, sb.verify(path))
