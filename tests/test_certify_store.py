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
    monkeypatch.setattr(verify_module, "MAX_WORK", 10)  # the work estimated from the summary, before reading
    with pytest.raises(ValueError, match="the atlas store .* units of checking work"):
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


def test_ragged_rows_are_taken_block_by_block():
    R = importlib.import_module("stairbounce.structure._store_read")
    np = pytest.importorskip("numpy")
    rng = np.random.default_rng(4)
    lengths = rng.integers(0, 5, 50)
    values = np.arange(int(lengths.sum())) * 3
    starts = np.cumsum(lengths) - lengths
    order = rng.permutation(50)
    want = np.concatenate([values[starts[k]:starts[k] + lengths[k]] for k in order])
    for block in (1, 3, 7, 1 << 20):
        assert np.array_equal(R._take_rows(values, starts[order], lengths[order], block=block), want)
