"""Trapping regions: the orbit of (1, 0) proven never to slide (issue 36, item 7).

Known answers: the box below proven by a region must not slide in the float map
at any point inside it (checked for 10^5 steps at random points); above the
Corollary 2.1 curve nothing changes (the theorem decides those boxes first);
inside the (1, 0^inf) tongue of Theorem 3.1 every point slides, so no region can
exist; and the independent checker must reject a region that lost a cell or a
certificate whose box was moved.
"""

import dataclasses
import re
from fractions import Fraction

import numpy as np
import pytest

import stairbounce as sb
from stairbounce.model import _constants, _slide_or_steps
from stairbounce.structure.certificate import Certificate
from stairbounce.structure.verify_trapping import verify_region

BOX = ((0.299, 0.30), (0.413, 0.414))  # below the curve, numerically non-sliding (Fig. 4)


@pytest.fixture(scope="module")
def region():
    r = sb.trapping_region(*BOX)
    assert r is not None
    return r


def test_region_is_proven_and_agrees_with_long_float_orbits(region):
    (e0, e1), (u0, u1) = BOX
    assert u1 < (1 - e1) / (2 * np.sqrt(2 * e1))  # below Corollary 2.1: no theorem there
    assert sb.certify_box(*BOX).status == "undecided"  # no finite itinerary proves it
    assert verify_region(e0, e1, u0, u1, 1000, region.itinerary, region.grid, region.cells) == "ok"
    rng = np.random.default_rng(7)
    for e, u in zip(rng.uniform(e0, e1, 12), rng.uniform(u0, u1, 12)):
        T, ratio = _constants(e, u)
        assert _slide_or_steps(1.0, 0.0, e, T, ratio, 100_000)[0] == 0  # no slide within 10^5 steps


def test_region_cells_and_dict_round_trip(region):
    b = region.boxes()
    assert b.shape == (region.cells.size, 4) and np.all(b[:, 0] < b[:, 1]) and np.all(b[:, 2] < b[:, 3])
    again = type(region).from_dict(region.to_dict())
    assert again.grid == region.grid and np.array_equal(again.cells, region.cells)


def test_tampered_regions_are_rejected(region):
    (e0, e1), (u0, u1) = BOX
    args = (region.itinerary, region.grid)
    assert verify_region(e0, e1, u0, u1, 1000, *args, region.cells[1:]) != "ok"  # a cell less
    assert verify_region(e0, e1, u0, u1, 1000, *args, region.cells[:-1]) != "ok"
    assert verify_region(e0, e1 + 0.01, u0, u1, 1000, *args, region.cells) != "ok"  # a wider box
    assert verify_region(e0, e1, u0 - 0.01, u1, 1000, *args, region.cells) != "ok"
    assert verify_region(0.1, 0.101, 0.3, 0.301, 1000, *args, region.cells) != "ok"  # a sliding box


def test_certificate_verdicts(region):
    from stairbounce.structure.trapping import certificate_of

    c = certificate_of(region, 1000)
    assert c.status == "no_sliding" and c.reason == "trapping" and sb.verify(c)
    assert sb.verify(Certificate.from_dict(c.to_dict()))
    shrunk = dataclasses.replace(c, region=dataclasses.replace(region, cells=region.cells[1:]))
    assert not sb.verify(shrunk) and sb.verify(shrunk).check == "trapping"
    moved = dataclasses.replace(c, u=(0.40, 0.401), region=dataclasses.replace(region, u=(0.40, 0.401)))
    assert not sb.verify(moved)
    assert not sb.verify(dataclasses.replace(c, u=(0.40, 0.401)))  # the region's box differs


def test_cell_range_is_the_cells_by_their_edges():
    # the definition, cell by cell: i0 the cell whose lower edge is <= a below the next
    # one's, i1 the last cell whose lower edge is < b (the search starts from a guess and
    # the axis's 1/n and n/width computed once; the answer must not depend on either)
    from stairbounce.structure.certificate import _cell_edge  # the regions' edges, as the checker reads them
    from stairbounce.structure.trapping import _cell_range

    rng = np.random.default_rng(44)
    for n in (1, 3, 48, 64, 100, 512):
        for lo, hi in ((0.0, 1.0), (-2.5, 7.0), (1.0, 1.0 + 2.0 ** -40), (-1e-300, 1e-300)):
            edges = np.array([_cell_edge(lo, hi - lo, hi, i, n) for i in range(n + 1)])
            pts = np.concatenate([edges, np.nextafter(edges, np.inf), np.nextafter(edges, -np.inf),
                                  rng.uniform(lo, hi, 40)])
            pts = pts[(pts >= lo) & (pts <= hi)]
            for a, b in zip(rng.choice(pts, 150), rng.choice(pts, 150)):
                a, b = min(a, b), max(a, b)
                want0 = int(np.flatnonzero(edges[:n] <= a)[-1])
                want1 = max(int(np.flatnonzero(edges[:n] < b)[-1]) if (edges[:n] < b).any() else 0, want0)
                assert _cell_range(a, b, lo, hi, n) == (want0, want1), (n, lo, hi, a, b)
            assert _cell_range(lo - 1.0, hi, lo, hi, n) == (-1, -1)
            assert _cell_range(lo, hi + 1.0, lo, hi, n) == (-1, -1)
            assert _cell_range(np.nan, hi, lo, hi, n) == (-1, -1)


def test_a_grid_whose_side_is_not_a_power_of_two_closes_and_verifies():
    # the regions' search finds a cell's (i, j) by a mask and a shift when the side is a
    # power of two, by a division otherwise: both kinds of grid close over BOX, and the
    # independent checker accepts each region
    from stairbounce.structure.trapping import _try

    (e0, e1), (u0, u1) = BOX
    for cells in (64, 96):
        r, why = _try(e0, e1, u0, u1, 1000, tries=((cells, 0.3),))
        assert why == "ok" and r.grid[2] == r.grid[5] == cells
        assert verify_region(e0, e1, u0, u1, 1000, r.itinerary, r.grid, r.cells) == "ok"
        assert verify_region(e0, e1, u0, u1, 1000, r.itinerary, r.grid, r.cells[:-1]) != "ok"


def test_no_region_where_every_point_slides():
    # inside the (1, 0^inf) tongue of Theorem 3.1 (u^2 <= (1/2)((1-e)/(1+e))^2)
    assert sb.trapping_region((0.1, 0.101), (0.3, 0.301)) is None


def _rows(ds):
    """``{(level, i, j): row}`` of an atlas table."""
    return {(int(L), int(i), int(j)): r for r, (L, i, j) in
            enumerate(zip(ds["level"].values, ds["i"].values, ds["j"].values))}


def _split_from(key, rows):
    """The box of ``rows`` that ``key`` (level, i, j) lies in, or None."""
    L, i, j = key
    for up in range(0, L + 1):
        k = (L - up, i >> up, j >> up)
        if k in rows:
            return k
    return None


def _assert_agree(ds0, ds):
    """Every box of the trapped table ``ds`` is a box of the plain table ``ds0``,
    unchanged or (was "nonsliding") trapped, or a piece of a split "nonsliding"
    box, trapped or keeping its label."""
    trapped = ds["reason"].values == "trapping"
    assert trapped.any() and np.all(ds["status"].values[trapped] == 1)
    rows0, rows = _rows(ds0), _rows(ds)
    for key, r in rows.items():
        if key in rows0:  # a box not split: unchanged, or a "nonsliding" box now trapped
            r0 = rows0[key]
            if trapped[r]:
                assert ds0["reason"].values[r0] == "nonsliding"
            else:
                for k in ("status", "reason", "step", "word", "e0", "e1", "u0", "u1"):
                    assert ds[k].values[r] == ds0[k].values[r0], k
        else:  # a piece of a split "nonsliding" box, trapped or keeping its label
            r0 = rows0[_split_from(key, rows0)]
            assert ds0["reason"].values[r0] == "nonsliding"
            assert trapped[r] or (ds["reason"].values[r] == "nonsliding" and ds["status"].values[r] == 3)
    return trapped


def test_atlas_with_trap():
    win = dict(e=(0.29, 0.31), u=(0.40, 0.42), depth=3, max_iter=300)
    plain = sb.certify(**win)
    atlas = sb.certify(**win, trap=True)
    ds = atlas.boxes
    trapped = _assert_agree(plain.boxes, ds)
    assert sb.verify(atlas)
    certs = [c for c in atlas.certificates() if c.reason == "trapping"]
    assert len(certs) == trapped.sum() and all(sb.verify(c) for c in certs[:3])
    bad = ds.copy()
    cells = bad["trap_cells"].values.copy()
    off = bad["trap_cell_offsets"].values
    cells[off[0]] = cells[off[0] + 1]  # the first region loses a cell
    bad["trap_cells"] = ("trap_cell", cells)
    assert not sb.verify(bad)


@pytest.fixture(scope="module")
def split_atlas():
    """A window below the Corollary 2.1 curve (Fig. 4) at depth 6, trapped with
    boxes split one level below the depth, and without trapping."""
    win = dict(e=(0.28, 0.32), u=(0.38, 0.42), depth=6, max_iter=1000)
    return sb.certify(**win), sb.certify(**win, trap=True)


def test_split_boxes_are_quadtree_children_and_verify(split_atlas):
    from stairbounce.structure.trapping import SPLIT_LEVELS

    plain, atlas = split_atlas
    ds = atlas.boxes
    _assert_agree(plain.boxes, ds)  # the boxes not split are the plain atlas's
    level, reason = ds["level"].values, ds["reason"].values
    assert reason.dtype == plain.boxes["reason"].values.dtype == object  # one object per distinct text
    assert ds.attrs["trap_split"] == SPLIT_LEVELS >= 1
    below = level > atlas.depth
    assert (below & (reason == "trapping")).any()  # boxes proven only below the depth
    assert level.max() <= atlas.depth + SPLIT_LEVELS
    v = sb.verify(atlas)
    assert v and v.rejected == 0 and v.complete and v.checked == ds.sizes["box"]
    # the trapped area grew against the boxes tried whole only (split=0 keeps them at the depth)
    from stairbounce.structure.trapping import trap_atlas

    whole = trap_atlas(plain.boxes, split=0)
    assert whole["level"].values.max() <= atlas.depth

    def area(d):
        t = d["reason"].values == "trapping"
        return float(((d["e1"].values - d["e0"].values) * (d["u1"].values - d["u0"].values))[t].sum())

    assert area(ds) > area(whole) > 0
    # the boxes of the depth none of whose pieces was proven stay whole, as without trapping
    rows0 = _rows(plain.boxes)
    assert all(_split_from(k, rows0) is not None for k in _rows(ds))


def test_split_beyond_the_stated_levels_is_rejected(split_atlas):
    _, atlas = split_atlas
    ds = atlas.boxes.copy()
    ds.attrs["trap_split"] = 0  # the split boxes now lie below the deepest level stated
    v = sb.verify(ds)
    assert not v and v.check == "place"
    ds.attrs["trap_split"] = 9  # more than MAX_TRAP_SPLIT: refused by name
    with pytest.raises(ValueError, match="trap_split"):
        sb.verify(ds)


def test_tampered_split_region_is_rejected(split_atlas):
    _, atlas = split_atlas
    ds = atlas.boxes
    below = np.flatnonzero((ds["level"].values > atlas.depth) & (ds["reason"].values == "trapping"))
    r = int(np.flatnonzero(ds["trap_box"].values == below[0])[0])
    bad = ds.copy(deep=True)
    cells = bad["trap_cells"].values.copy()
    off = bad["trap_cell_offsets"].values
    cells[off[r]:off[r + 1] - 1] = cells[off[r] + 1:off[r + 1]]  # the region loses a cell (its last repeated)
    bad["trap_cells"] = ("trap_cell", cells)
    v = sb.verify(bad)
    assert not v and v.check == "trapping" and v.rejected == 1
    moved = ds.copy(deep=True)  # the sub-box's region claimed for its sibling
    tb = moved["trap_box"].values.copy()
    sib = [k for k in np.flatnonzero(moved["level"].values == moved["level"].values[below[0]])
           if moved["reason"].values[k] != "trapping"]
    if sib:
        st = moved["status"].values.copy()
        rs = moved["reason"].values.astype(object).copy()
        st[sib[0]], rs[sib[0]] = 1, "trapping"
        tb[r] = sib[0]
        moved["status"] = ("box", st)
        moved["reason"] = ("box", rs.astype(str))
        moved["trap_box"] = ("trap", tb)
        assert not sb.verify(moved)


def test_points_of_newly_trapped_boxes_never_slide(split_atlas):
    """Random float points inside boxes proven only by the split (below the depth)
    never slide under the float map from (1, 0) within 10^5 steps."""
    _, atlas = split_atlas
    ds = atlas.boxes
    sel = np.flatnonzero((ds["level"].values > atlas.depth) & (ds["reason"].values == "trapping"))
    rng = np.random.default_rng(11)
    for b in rng.choice(sel, min(8, sel.size), replace=False):
        e0, e1, u0, u1 = (float(ds[k].values[b]) for k in ("e0", "e1", "u0", "u1"))
        for e, u in zip(rng.uniform(e0, e1, 3), rng.uniform(u0, u1, 3)):
            T, ratio = _constants(e, u)
            assert _slide_or_steps(1.0, 0.0, e, T, ratio, 100_000)[0] == 0


def test_regions_checked_in_one_batch_as_one_by_one(split_atlas):
    """verify_regions (all regions at once) gives each region the verdict of
    verify_region; a region damaged in the batch fails there alone."""
    from stairbounce.structure.verify_trapping import TRAP_CHECKS, verify_regions

    _, atlas = split_atlas
    ds = atlas.boxes
    tb = ds["trap_box"].values
    off = ds["trap_cell_offsets"].values
    io = ds["offsets"].values
    cells = ds["trap_cells"].values.copy()
    cells[off[2]] = cells[off[2] + 1]  # region 2 loses a cell
    e = [ds[k].values[tb] for k in ("e0", "e1", "u0", "u1")]
    lengths = io[tb + 1] - io[tb]
    itin = np.concatenate([ds["itinerary"].values[io[b]:io[b + 1]] for b in tb])
    got = verify_regions(*e, 1000, itin, np.concatenate([[0], np.cumsum(lengths)]), ds["trap_grid"].values, off,
                         cells)
    one = [verify_region(*(x[r] for x in e), 1000, ds["itinerary"].values[io[b]:io[b + 1]], ds["trap_grid"].values[r],
                         cells[off[r]:off[r + 1]]) for r, b in enumerate(tb)]
    assert [TRAP_CHECKS[c] for c in got] == one
    assert one[2] != "ok" and one.count("ok") == len(one) - 1


def test_the_pass_in_threads_is_the_pass_in_one_bit_for_bit(split_atlas, monkeypatch):
    """The trapping pass's batches run in threads (_try_all, threads=2) and give the
    same codes, grids, entries and cells as in one thread, bit for bit; batches of 7
    boxes so that many run at once, and some boxes fail, some are proven."""
    import importlib

    T = importlib.import_module("stairbounce.structure.trapping")
    plain, _ = split_atlas
    ds = plain.boxes
    e0, e1, u0, u1 = (ds[k].values for k in ("e0", "e1", "u0", "u1"))
    monkeypatch.setattr(T, "_BATCH", 7)
    seen = []
    one = T._try_all(e0, e1, u0, u1, 1000, threads=1)
    two = T._try_all(e0, e1, u0, u1, 1000, lambda d, t: seen.append(d), 0, e0.size, threads=2)
    assert e0.size > 4 * 7
    for a, b in zip(one, two):
        assert a.dtype == b.dtype and a.shape == b.shape
        assert np.array_equal(a.view(np.uint8), b.view(np.uint8))
    codes = one[0]
    assert (codes == T.TRAP_OK).any() and (codes != T.TRAP_OK).any()
    assert seen == sorted(seen) and seen[-1] == e0.size


def test_cli_certify_trap_states_the_trapped_share(tmp_path, capsys):
    from stairbounce.cli import main

    win = ["--e", "0.29:0.31", "--u", "0.40:0.42", "--depth", "3", "--max-iter", "300"]
    out = tmp_path / "t.nc"
    with pytest.raises(SystemExit) as exit_:
        main(["certify", *win, "--trap", "--out", str(out)])
    text = capsys.readouterr().out
    assert exit_.value.code == 0
    atlas = sb.CertifiedAtlas.load(out)
    ds = atlas.boxes
    trapped = (ds["reason"].values == "trapping") & (ds["status"].values == 1)
    F = Fraction
    share = sum((F(float(b)) - F(float(a))) * (F(float(d)) - F(float(c))) for a, b, c, d in
                zip(*(ds[k].values[trapped] for k in ("e0", "e1", "u0", "u1")))) / ((F(0.31) - F(0.29)) * (F(0.42) - F(0.4)))
    # a proven lower bound, rounded down to 0.01 %: at most 0.01 % below the exact share
    shown = re.search(r"no_sliding by a trapping region at least ([0-9.]+)%", text)
    assert share > 0 and shown and 100 * share - F("0.01") < F(shown.group(1)) <= 100 * share
    assert sb.verify(atlas)
    with pytest.raises(SystemExit):  # without --trap: no trapped boxes, no such line
        main(["certify", *win])
    assert "trapping region" not in capsys.readouterr().out


def test_above_the_curve_unaffected():
    win = dict(e=(0.5, 0.6), u=(1.0, 1.2), depth=3, max_iter=100)
    a, b = sb.certify(**win), sb.certify(**win, trap=True)
    assert np.array_equal(a.boxes["status"].values, b.boxes["status"].values)
    assert np.all(a.boxes["status"].values == 1) and not (b.boxes["reason"].values == "trapping").any()


@pytest.mark.parametrize("bad", [dict(e=(0.3, 0.2)), dict(u=(0.0, 0.1)), dict(max_iter=0), dict(e=(0.1, 1.0))])
def test_bad_input(bad):
    kw = dict(e=(0.299, 0.30), u=(0.413, 0.414)) | bad
    with pytest.raises(ValueError):
        sb.trapping_region(**kw)
    if "max_iter" not in bad:
        return
    with pytest.raises(ValueError, match="trap"):
        sb.certify(e=(0.29, 0.31), u=(0.4, 0.42), depth=2, trap="yes")


def test_kernel_enclosures_against_arb(region):
    """The fast kernel's claims on the region's cells, against python-flint's Arb
    balls at random states of random cells and random (e, u) of the box: the state
    does not slide, its impact number is one the kernel followed, and its image lies
    in the kernel's enclosure of that branch."""
    flint = pytest.importorskip("flint")
    from stairbounce.structure.trapping import _branches

    arb = flint.arb
    (e0, e1), (u0, u1) = BOX
    boxes = region.boxes()
    Tl, Th = np.nextafter(1 / u1, 0), np.nextafter(1 / u0, 2)
    Rl = np.nextafter((1 + e0) / (1 - e0), 0)
    out = np.empty((4098, 5))
    rng = np.random.default_rng(3)
    for c in rng.integers(0, len(boxes), 60):
        v0, v1, s0, s1 = boxes[c]
        n = _branches(v0, v1, s0, s1, e0, e1, Tl, Th, Rl, out)
        assert n > 0
        enclosure = {int(out[r, 4]): out[r, :4].copy() for r in range(n)}
        e, u = arb(rng.uniform(e0, e1)), arb(rng.uniform(u0, u1))
        v, s = arb(rng.uniform(v0, v1)), arb(rng.uniform(s0, s1))
        T, ratio = 1 / u, (1 + e) / (1 - e)
        assert T - v - ratio * s < 0  # (2.4) false: no slide
        t, w, k = v + s, e * s, 0
        t_k, w_k = t, w
        while t <= T:  # impact k + 1 on the step (eq. 2.2), decided by the balls
            k += 1
            t_k, w_k = t, w
            t, w = t + 2 * w, e * w
        assert t > T  # the last comparison was decided too
        assert k in enclosure
        a0, a1, b0, b1 = enclosure[k]
        if k == 0:
            vn, sn = v - T, (s * s + 2).sqrt()
        else:  # after the k-th impact, at t_k with speed w_k
            vn, sn = w_k - (T - t_k), (w_k * w_k + 2).sqrt()
        assert a0 <= vn.lower() and vn.upper() <= a1
        assert b0 <= sn.lower() and sn.upper() <= b1


def test_streamed_store_holds_the_split_boxes(tmp_path, split_atlas):
    from .test_certify_store import assert_same_atlas

    _, atlas = split_atlas
    assert (atlas.boxes["level"].values > atlas.depth).any()
    sb.certify_to_zarr(tmp_path / "t.zarr", e=(0.28, 0.32), u=(0.38, 0.42), depth=6, max_iter=1000, trap=True,
                       tile_level=4, tile_boxes=20)
    assert_same_atlas(sb.CertifiedAtlas.load(tmp_path / "t.zarr").boxes, atlas.boxes)


def test_fine_grids_prove_more_and_contain_the_default_pass():
    """``trap="fine"`` (the default pass's tries as it makes them, then, where the
    spread of T over the box is narrow, the grids its gates skipped and 1024 to 8192
    cells a side): its first tries are the default pass's, so every box the default
    pass proves lies in a box the fine pass proves (itself or an ancestor, one not
    split); the fine pass proves more area (with grids the default pass never makes),
    the independent checker accepts every box, and float orbits at random points of
    the boxes only the fine pass proves never slide within 10^5 steps."""
    win = dict(e=(0.155, 0.2138), u=(0.6, 0.658), depth=6, max_iter=1000)
    plain, fine = sb.certify(**win, trap=True).boxes, sb.certify(**win, trap="fine").boxes
    assert plain.attrs["trap_grids"] == [64, 128, 64, 256, 512]
    assert fine.attrs["trap_grids"] == [64, 128, 64, 256, 512, 128, 256, 512, 1024, 2048, 4096, 8192]
    assert plain["trap_grid"].values[:, 2].max() <= 512
    assert {1024, 2048, 4096, 8192} & set(fine["trap_grid"].values[:, 2].astype(int))

    def trapped(ds):
        t = np.flatnonzero(ds["reason"].values == "trapping")
        return t, {(int(ds["level"].values[b]), int(ds["i"].values[b]), int(ds["j"].values[b])) for b in t}

    def area(ds, rows):
        return sum((Fraction(float(ds["e1"].values[b])) - Fraction(float(ds["e0"].values[b])))
                   * (Fraction(float(ds["u1"].values[b])) - Fraction(float(ds["u0"].values[b]))) for b in rows)

    rows_p, keys_p = trapped(plain)
    rows_f, keys_f = trapped(fine)

    def covered_by(keys, L, i, j):
        return any((m, i >> (L - m), j >> (L - m)) in keys for m in range(L + 1))

    assert all(covered_by(keys_f, *k) for k in keys_p)
    assert area(fine, rows_f) > area(plain, rows_p) > 0
    v = sb.verify(sb.CertifiedAtlas(fine))
    assert v and v.rejected == 0 and v.complete and v.checked == fine.sizes["box"]
    only = [b for b in rows_f if not covered_by(keys_p, int(fine["level"].values[b]), int(fine["i"].values[b]),
                                                  int(fine["j"].values[b]))]
    assert only
    rng = np.random.default_rng(12)
    for b in rng.choice(only, min(6, len(only)), replace=False):
        e0, e1, u0, u1 = (float(fine[k].values[b]) for k in ("e0", "e1", "u0", "u1"))
        for e, u in zip(rng.uniform(e0, e1, 3), rng.uniform(u0, u1, 3)):
            T, ratio = _constants(e, u)
            assert _slide_or_steps(1.0, 0.0, e, T, ratio, 100_000)[0] == 0


def test_cli_fine_trap_and_bad_trap_values(tmp_path, capsys):
    from stairbounce.cli import main

    win = ["--e", "0.155:0.2138", "--u", "0.6:0.658", "--depth", "5"]
    out = tmp_path / "f.nc"
    with pytest.raises(SystemExit) as exit_:
        main(["certify", *win, "--fine-trap", "--out", str(out)])
    assert exit_.value.code == 0
    assert "no_sliding by a trapping region at least" in capsys.readouterr().out
    ds = sb.CertifiedAtlas.load(out).boxes
    assert list(ds.attrs["trap_grids"]) == [64, 128, 64, 256, 512, 128, 256, 512, 1024, 2048, 4096, 8192]
    for bad in (1, "yes", None, "Fine"):
        with pytest.raises(ValueError, match="trap must be True, False or 'fine'"):
            sb.certify(e=(0.155, 0.2138), u=(0.6, 0.658), depth=3, trap=bad)


def test_the_set_of_cells_is_a_set_and_empties_again():
    """The pass's set of cells (a hash table, so that a grid of 8192^2 cells costs no
    more than its region's cells): against Python's set on cells with many
    collisions (multiples of the table's size, neighbours, indices of a 8192^2
    grid), repeats not queued twice, a full queue refused (-1), and the table
    empty again after :func:`_forget` (the next try starts from nothing)."""
    from stairbounce.structure.trapping import _enqueue, _forget, _seen_table

    rng = np.random.default_rng(3)
    max_cells = 500
    seen = _seen_table(max_cells)
    assert seen.size >= 2 * max_cells and (seen.size & (seen.size - 1)) == 0 and (seen == -1).all()
    queue, slots = np.empty(max_cells, np.int64), np.empty(max_cells, np.int64)
    for _ in range(3):
        cells = np.concatenate([rng.integers(0, 8192 * 8192, 300), np.arange(40) * seen.size,
                                np.arange(1000, 1040), rng.integers(0, 64, 200)])
        rng.shuffle(cells)
        ref, tail = [], 0
        for c in cells:
            t = _enqueue(int(c), seen, queue, slots, tail)
            if int(c) in ref:
                assert t == tail
            elif len(ref) < max_cells:
                ref.append(int(c))
                assert t == tail + 1
            else:
                assert t == -1
                continue
            tail = t
        assert list(queue[:tail]) == ref
        assert sorted(seen[seen != -1]) == sorted(ref)
        _forget(seen, slots, tail)
        assert (seen == -1).all()
