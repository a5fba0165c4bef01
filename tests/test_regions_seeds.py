"""Regions smaller than a seed pixel, found from the corners of their neighbours
(``window_regions(from_corners=True)``), and traced areas against pixel counts
at 4096 x 4096 (issue 22).

Known answers: the regions traced from a finer seed scan (the same margins,
walked from pixels instead of corners) and the pixel counts of a 4096 x 4096
scan with the map itself (``model._step`` through ``structure.itinerary._words_grid``).
"""

import math

import numpy as np
import pytest

import stairbounce as sb
from stairbounce import structure
from stairbounce.structure import regions
from tests._cli import run_cli
from tests.test_regions import _pixel_area


def _key(word):
    ks = regions.itinerary_of_word(word)
    return tuple(int(h) for h in structure.itinerary._hash_itinerary(ks, ks.size))


def test_corners_find_regions_smaller_than_a_seed_pixel():
    # near the tip of tongue 3: an 8 x 8 seed scan sees 14 words; a 64 x 64 one
    # (pixels 64 times smaller) sees the regions between them, e.g. (3, 0, 3, 0^inf),
    # 0.64 of a coarse pixel, which contains no coarse pixel centre
    e, u = (0.08, 0.12), (0.98, 1.02)
    coarse = sb.window_regions(e, u, resolution=8)
    corners = sb.window_regions(e, u, resolution=8, from_corners=True)
    fine = sb.window_regions(e, u, resolution=64)
    pixel = (0.04 / 8) ** 2
    seen = {r.word.letters for r in coarse}
    found = {r.word.letters: r for r in corners}
    assert (3, 0, 3) not in seen and (3, 0, 3) in found
    assert seen < set(found)
    # every word of the fine run of at least 1/10 of a coarse pixel that the coarse scan
    # missed is found from corners (measured: the smallest one missed is 0.045 pixel),
    # with the same area: the same region, walked from a corner instead of a pixel
    small = [r for r in fine if r.word.letters not in seen and r.area >= 0.1 * pixel]
    assert len(small) >= 15
    for r in small:
        assert r.word.letters in found, r
        c = found[r.word.letters]
        assert c.complete and len(c.components) == len(r.components) == 1
        assert c.area == pytest.approx(r.area, rel=1e-9)
    # no component twice, and every region inside the sliding set: the total lies
    # below the pixels touching a sliding pixel at 512 x 512
    for r in corners:
        areas = [round(c.area, 18) for c in r.components]
        assert len(set(areas)) == len(areas), r
    res = 512
    es, us = regions._grid(e, u, res)
    _, _, steps = regions._label_grid(es, us, 1000, 1.0, 0.0)
    _, hi = _pixel_area(steps > 0, (0.04 / res) ** 2)
    assert sum(r.area for r in corners) <= hi
    assert sum(not r.complete for r in corners) <= 0.05 * len(corners)
    with pytest.raises(ValueError, match="from_corners must be True or False"):
        sb.window_regions(e, u, resolution=8, from_corners="yes")


def test_corner_rings_surround_every_corner():
    # one ring per corner of each component of at least 1/16 pixel, at a quarter of
    # the seed spacing along each axis, with the bisectors of the corner's sectors
    e, u = (0.0, 0.3), (0.9, 1.3)
    r = sb.word_region((3,), e, u, resolution=32)
    pixel = (0.3 / 32, 0.4 / 32)
    C, P = regions._corner_rings([r], pixel)
    corners = r.corners
    assert len(C) == len(corners) >= 3
    for c in corners:
        assert np.min(np.hypot(C[:, 0] - c.e, C[:, 1] - c.u)) == 0.0
    d = (P - C[:, None, None, :]) / np.array(pixel)
    np.testing.assert_allclose(np.hypot(d[..., 0], d[..., 1]), regions._CORNER_RADII[0], rtol=1e-9)
    # the tip of tongue 3 (graze x chatter): the ring sees the tongue, the region above
    # the graze line, and the words beyond the tip
    tip = [i for i, c in enumerate(corners) if {k for k, _ in c.events} == {"graze", "chatter"}][0]
    buf = np.empty(1000, np.int64)
    words = set()
    for p in P[tip, 0]:
        n = structure.itinerary._itinerary_of(p[0], p[1], 1.0, 0.0, 1000, buf)
        words.add(tuple(buf[:n]) if n > 0 else None)
    assert tuple(regions.itinerary_of_word((3,))) in words and len(words) >= 3
    assert regions._corner_rings([], pixel)[0].shape == (0, 2)


# a window around three regions next to the chatter border of tongue 2, where
# every pixel of these words slides within five steps (max_iter 50 is plenty)
SMALL = ((0.095, 0.105), (0.81, 0.83))


@pytest.fixture(scope="module")
def labels_4096():
    res = 4096
    es, us = regions._grid(*SMALL, res)
    h1, h2, _ = regions._label_grid(es, us, 50, 1.0, 0.0)
    return res, h1, h2


@pytest.mark.parametrize("word", [(2,), (2, 0, 2), (2, 0, 2, 2)])
def test_region_area_against_pixel_counts_at_4096(labels_4096, word):
    res, h1, h2 = labels_4096
    r = sb.word_region(word, *SMALL, resolution=64, max_iter=50)
    assert r.complete and r.area > 0.05 * 0.01 * 0.02
    a, b = _key(word)
    mask = (h1 == a) & (h2 == b)
    de, du = 0.01 / res, 0.02 / res
    cell = de * du
    lo, hi = _pixel_area(mask, cell)
    # the pixels surely inside <= the traced area <= the pixels touching the region
    assert lo <= r.area <= hi
    # the pixel-boundary error: a pixel centre decides a pixel crossed by the border,
    # i.e. at most (L_e du + L_u de) of area for a border of total variation L_e in e
    # and L_u in u; half of it, as the counts' errors along the border largely cancel
    L_e = L_u = 0.0
    for comp in r.components:
        for k in [None] + list(range(len(comp.holes))):
            pe, pu = comp.polygon(k)
            L_e += np.abs(np.diff(pe)).sum()
            L_u += np.abs(np.diff(pu)).sum()
    bound = 0.5 * (L_e * du + L_u * de)
    diff = abs(r.area - mask.sum() * cell)
    assert diff <= bound
    assert diff <= 0.5 * (hi - lo)
    assert math.isclose(bound, 0.5 * (hi - lo), rel_tol=0.5)
    # and tighter: the n pixels along the border err by up to half a cell each, in
    # both directions, so the sum stays within a few sqrt(n) cells (measured: the
    # relative differences are 1.8e-6, 1.8e-6 and 9.2e-6, diff / bound <= 0.003)
    n = (hi - lo) / cell
    assert diff <= 3.0 * math.sqrt(n) * cell


def test_cli_words_regions_from_corners(tmp_path, capsys):
    def run(args):
        return run_cli(args, capsys)

    e, u = (0.08, 0.12), (0.98, 1.02)
    window = ["words", "--e", "0.08:0.12", "--u", "0.98:1.02", "--size", "8x8", "--regions"]
    code, text, err = run(window + ["--from-corners", "--out", str(tmp_path / "c.geojson")])
    assert code == 0, err
    ref = sb.window_regions(e, u, resolution=8, from_corners=True)
    assert len(ref) > 10 * len(sb.window_regions(e, u, resolution=8))
    assert f"{len(ref)} words in" in text
    assert "(3, 0, 3, 0^inf)" in (tmp_path / "c.geojson").read_text()
    code, _, err = run(["words", "--from-corners"])
    assert code == 2 and "--from-corners goes with --regions" in err and "Traceback" not in err
