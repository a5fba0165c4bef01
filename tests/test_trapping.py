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


def test_no_region_where_every_point_slides():
    # inside the (1, 0^inf) tongue of Theorem 3.1 (u^2 <= (1/2)((1-e)/(1+e))^2)
    assert sb.trapping_region((0.1, 0.101), (0.3, 0.301)) is None


def test_atlas_with_trap():
    win = dict(e=(0.29, 0.31), u=(0.40, 0.42), depth=3, max_iter=300)
    plain = sb.certify(**win)
    atlas = sb.certify(**win, trap=True)
    ds, ds0 = atlas.boxes, plain.boxes
    trapped = ds["reason"].values == "trapping"
    assert trapped.any()
    # only undecided "nonsliding" boxes changed, to no_sliding
    assert np.all(ds0["reason"].values[trapped] == "nonsliding")
    assert np.all(ds["status"].values[trapped] == 1)
    assert np.array_equal(ds["status"].values[~trapped], ds0["status"].values[~trapped])
    assert sb.verify(atlas)
    certs = [c for c in atlas.certificates() if c.reason == "trapping"]
    assert len(certs) == trapped.sum() and all(sb.verify(c) for c in certs[:3])
    bad = ds.copy()
    cells = bad["trap_cells"].values.copy()
    off = bad["trap_cell_offsets"].values
    cells[off[0]] = cells[off[0] + 1]  # the first region loses a cell
    bad["trap_cells"] = ("trap_cell", cells)
    assert not sb.verify(bad)


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
