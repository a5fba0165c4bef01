"""A store refined only where the perimeter's counts can change (issue 44 item 4):
``certify_to_zarr(focus=K)`` and ``structure/focus.py``, and the trapping pass that
carries an earlier pass's failed tries one level further (``trap_atlas(tried=...)``)."""

import importlib

import numpy as np
import pytest

import stairbounce as sb

from ._cli import run_cli as _cli

F = importlib.import_module("stairbounce.structure.focus")
R = importlib.import_module("stairbounce.structure._store_read")
T = importlib.import_module("stairbounce.structure.trapping")
S = importlib.import_module("stairbounce.structure.certify_store")

FIG7 = dict(e=(0.155, 0.2138), u=(0.6, 0.658))
FIG6 = dict(e=(0.0, 0.333), u=(0.4, 0.733))


@pytest.fixture(scope="module")
def stores(tmp_path_factory):
    """Fig. 7's window with class-level proofs and trapping regions: refined for k <= 6
    down to depth 8, and the plain stores of depths 6 and 8."""
    d = tmp_path_factory.mktemp("focus")
    kw = dict(FIG7, max_iter=1000, classes=True, trap=True, tile_level=5, tile_boxes=64)
    return {name: sb.certify_to_zarr(d / f"{name}.zarr", **kw, **extra)
            for name, extra in (("focus", dict(depth=8, focus=6)), ("d6", dict(depth=6)), ("d8", dict(depth=8)))}


def test_a_refined_store_brackets_its_scales_as_the_full_depth_with_fewer_boxes(stores):
    """At k <= focus the refined store's upper counts are at most the full depth-8
    store's: a box left alone is next to cells holding proven points of both classes
    (so the border meets them and the full store counts them too), a box taken up is
    certified again as the full store's quadtree below it, and a box proven early (a
    trapping region on a box the full quadtree splits) only removes cells.  Its
    bracket is at least as narrow as its round 0's (the depth-6 store) at every scale,
    the store is re-verified box by box (basis proven), and it holds far fewer boxes.
    The lower counts use witnesses sampled in other boxes than the full store's, so
    they are compared with the round 0's only."""
    got = stores["focus"].perimeter_bracket()
    full = stores["d8"].perimeter_bracket(k2=6)
    base = stores["d6"].perimeter_bracket()
    assert got["basis"] == full["basis"] == "proven" and got["focus"] == 6 and got["depth"] == 8
    assert got["k"] == full["k"] == base["k"] == [3, 4, 5, 6]
    assert all(a <= b for a, b in zip(got["upper"], full["upper"]))
    assert sum(full["upper"]) - sum(got["upper"]) <= 0.01 * sum(full["upper"])  # the same cells but a few
    assert got["upper"] != base["upper"]  # the rounds changed something: the comparisons could differ
    assert all(lo >= b for lo, b in zip(got["lower"], base["lower"]))
    assert all(up <= b for up, b in zip(got["upper"], base["upper"]))
    assert stores["focus"].boxes < 0.8 * stores["d8"].boxes
    assert "refined below depth 6 only where the counts at k <= 6 can change" in got["proof"]


def test_a_refined_store_counts_tile_by_tile_as_loaded_whole(stores):
    """The store's counts tile by tile are the loaded atlas's (both at the scales
    0 .. focus: its attribute ``focus``), and its boxes tile the window at depth 8."""
    st = stores["focus"]
    atlas = st.load()
    assert atlas.boxes.attrs["focus"] == 6 and atlas.depth == 8
    assert int(atlas.boxes["level"].values.max()) > 6  # refined below the focus
    a = st.border_box_counts()
    b = atlas.border_box_counts()
    assert list(a["k"]) == list(b["k"]) == list(range(7))
    assert list(a["upper"]) == list(b["upper"]) and list(a["lower"]) == list(b["lower"])
    v = sb.verify(st.path)
    assert v.ok and v.complete and v.rejected == 0


def test_focus_at_the_depth_is_the_plain_store(tmp_path):
    """focus == depth: no round after round 0, the boxes of the plain store bit for bit."""
    kw = dict(FIG6, depth=5, classes=True, trap=True, tile_level=4, tile_boxes=30)
    a = sb.certify_to_zarr(tmp_path / "a.zarr", **kw, focus=5).load().boxes
    b = sb.certify_to_zarr(tmp_path / "b.zarr", **kw).load().boxes
    assert a.attrs.pop("focus") == 5 and "focus" not in b.attrs
    for name in b.variables:
        assert a[name].values.tobytes() == b[name].values.tobytes() if a[name].dtype.kind not in "OU" else \
            a[name].values.tolist() == b[name].values.tolist(), name


def test_the_selection_is_the_undecided_boxes_next_to_a_cell_not_in_lower():
    """selected(): a box whose closure's scale-K cells are all in ``lower`` is left; one
    touching a cell outside it (a neighbour across its side, or a cell it holds) is
    taken, and a ``nonsliding`` box of the last levels goes to the trapping tries."""
    import xarray as xr

    K = 3  # cells 8 x 8, code ci * 8 + cj
    # boxes at level 5 (4 x 4 a cell): (9, 9), (10, 10), (10, 9) inside cell (2, 2); (8, 9) on its left side
    level = np.array([5, 5, 5, 5, 2], np.int8)
    ii = np.array([9, 8, 10, 10, 1])
    jj = np.array([9, 9, 10, 9, 1])
    status = np.array([3, 3, 0, 3, 3], np.int8)  # undecided but the third (a word)
    reason = np.array(["edge", "edge", "", "nonsliding", "edge"], dtype=object)
    ds = xr.Dataset({"level": ("box", level), "i": ("box", ii), "j": ("box", jj), "status": ("box", status),
                     "reason": ("box", reason)})
    lower = np.array([2 * 8 + 2])
    again, deeper = F.selected(ds, K, lower, depth=7)
    assert again.tolist() == [False, True, False, False, True]  # (8, 9) touches cell (1, 2); the level-2 box
    assert deeper.tolist() == [False] * 5  # the nonsliding one's cells are all in lower
    again, deeper = F.selected(ds, K, np.array([], np.int64), depth=7)
    assert again.tolist() == [True, True, False, False, True] and deeper.tolist() == [False, False, False, True, False]
    # the level-2 box covers 4 cells and touches the ring around them: all must be in lower
    ring = np.array([a * 8 + c for a in range(1, 5) for c in range(1, 5)])
    assert F.selected(ds, K, ring, depth=7)[0][4] == False  # noqa: E712
    assert F.selected(ds, K, ring[1:], depth=7)[0][4] == True  # noqa: E712


def test_trapping_carried_one_level_further_is_the_deeper_pass(tmp_path):
    """trap_atlas(tried=...): a pass to depth 6 (tries to level 7), then its unproven
    nonsliding rows carried to depth 7 (only the level-8 tries made) give the rows and
    regions of one pass to depth 7, whose tree holds the same tries (each try depends
    on its box alone)."""
    ds = sb.certify(**FIG7, depth=7).boxes
    direct = T.trap_atlas(ds)
    first = T.trap_atlas(ds.assign_attrs(depth=6))
    st, rs = first["status"].values, first["reason"].values
    again = (st == 3) & (rs == "nonsliding")
    rows = F.without(first, again)
    rest = F.without(first, ~again)
    sub = R.merge_tiles([rest], rest[0]["offsets"].size - 1, rest[0]["itinerary"].size)
    second = T.trap_atlas(sub.assign_attrs(depth=7), tried=np.full(sub.sizes["box"], 7))
    parts = [rows, F._tile_form(second)]
    both = R.merge_tiles(parts, sum(a["offsets"].size - 1 for a, _ in parts),
                         sum(a["itinerary"].size for a, _ in parts))
    assert int(((direct["reason"].values == "trapping")).sum()) > int((rs == "trapping").sum())  # level 8 proved more
    for name in ("level", "i", "j", "status", "reason", "e0", "u1", "offsets", "itinerary", "trap_box", "trap_grid",
                 "trap_cell_offsets", "trap_cells"):
        assert np.array_equal(np.asarray(both[name].values, dtype=direct[name].dtype), direct[name].values), name
    assert second.attrs["trap_tried"] < direct.attrs["trap_tried"]  # the earlier tries not made again
    with pytest.raises(ValueError, match="tried must hold one level a row"):
        T.trap_atlas(sub, tried=np.zeros(2))


@pytest.mark.parametrize("kw, match", [
    (dict(depth=6, focus=7), "focus"),
    (dict(depth=6, focus=2), "focus"),
    (dict(depth=8, focus=5, tile_level=6), "tile_level"),
])
def test_bad_focus_is_refused_by_name(tmp_path, kw, match):
    with pytest.raises(ValueError, match=match):
        sb.certify_to_zarr(tmp_path / "a.zarr", **FIG7, **kw)


def test_a_store_of_another_focus_is_refused(tmp_path, stores):
    with pytest.raises(ValueError, match="focus: store 6, asked None"):
        sb.certify_to_zarr(stores["focus"].path, **FIG7, max_iter=1000, classes=True, trap=True, tile_level=5,
                           tile_boxes=64, depth=8)


def test_cli_focus_store_and_its_perimeter(tmp_path, capsys):
    store = str(tmp_path / "f.zarr")
    args = ["certify", "--depth", "6", "--classes", "--top", "1", "--focus", "5"]
    code, out, err = _cli(args + ["--store", store], capsys)
    assert code == 0, err
    code, out, err = _cli(["certify", "--verify", store, "--perimeter"], capsys)
    assert code == 0 and "certify depth 6 refined for k <= 5" in out and "k =  5" in out and "k =  6" not in out
    code, out, err = _cli(args, capsys)
    assert code == 2 and "--focus needs --store" in err and len(err.strip().splitlines()) == 1
    code, out, err = _cli(["certify", "--depth", "6", "--focus", "9", "--store", str(tmp_path / "g.zarr")], capsys)
    assert code == 2 and "--focus" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_dask_workers_write_the_local_refined_store(tmp_path):
    """The rounds run inside a tile's task: a Dask run (one numba thread a worker) writes
    the local run's boxes, bit for bit."""
    import warnings

    distributed = pytest.importorskip("distributed")
    kw = dict(FIG6, depth=7, focus=5, classes=True, trap=True, tile_level=4, tile_boxes=16)
    local = sb.certify_to_zarr(tmp_path / "a.zarr", **kw).load().boxes
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                      dashboard_address=None) as cluster, distributed.Client(cluster) as c:
            sb.certify_to_zarr(tmp_path / "b.zarr", client=c, **kw)
    got = sb.CertifiedAtlas.load(tmp_path / "b.zarr").boxes
    assert int(got["level"].values.max()) > 5
    for name in local.variables:
        a, b = local[name].values, got[name].values
        assert (a.tolist() == b.tolist()) if a.dtype.kind in "OU" else (a.tobytes() == b.tobytes()), name
