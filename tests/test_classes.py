"""Class-level proofs (structure/classes.py): boxes where every point slides within
max_iter with one of several words, re-verified by the checker's own branch
following (structure/verify_branches.py) and compared with the float map."""

import numpy as np
import pytest

import stairbounce as sb
from stairbounce.structure.certificate import STATUSES

FIG7 = dict(e=(0.155, 0.2138), u=(0.6, 0.658))
SLIDING = STATUSES.index("sliding")


@pytest.fixture(scope="module")
def atlas():
    return sb.certify(depth=6, classes=True, **FIG7)


def test_sliding_boxes_are_reverified_and_slide_at_random_points(atlas):
    b = atlas.boxes
    st = b["status"].values
    sl = np.flatnonzero(st == SLIDING)
    assert sl.size > 20
    assert sb.verify(atlas).ok
    # the claim at random points of the boxes: the float map slides, with a listed word
    rng = np.random.default_rng(3)
    for i in rng.choice(sl, 40, replace=False):
        words = set(str(b["word"].values[i]).split(" | "))
        assert len(words) >= 2
        for _ in range(5):
            e = rng.uniform(b["e0"].values[i], b["e1"].values[i])
            u = rng.uniform(b["u0"].values[i], b["u1"].values[i])
            w = sb.sliding_word(e, u, max_iter=atlas.max_iter)
            assert w is not None and w.format(ascii=True) in words


def test_the_checker_rejects_a_shortened_word_list(atlas):
    b = atlas.boxes.copy(deep=True)
    i = np.flatnonzero(b["status"].values == SLIDING)[0]
    w = b["word"].values.copy()
    w[i] = w[i].split(" | ")[0]
    b["word"] = ("box", w)
    v = sb.verify(b)
    assert not v.ok and v.check == "branches" and v.rejected == 1


def test_a_sliding_status_with_an_itinerary_alone_is_refused():
    # the array checker never accepts status sliding: it has no single itinerary
    from stairbounce.structure.verify import verify_arrays

    ok = verify_arrays([0.18], [0.1801], [0.62], [0.6201], [SLIDING], 1000, [1, 1, 1, 2, -1], [0, 5])
    assert not ok[0]


def test_the_sliding_border_counts_fewer_cells_than_all_borders(atlas):
    s = atlas.border_box_counts(border="sliding")
    w = atlas.border_box_counts(border="words")
    assert (s["lower"] <= s["upper"]).all() and (w["lower"] <= w["upper"]).all()
    # "sliding" boxes are undecided between words but proven for the sliding region
    assert (s["upper"] <= w["upper"]).all() and (s["upper"] < w["upper"]).any()
    with pytest.raises(ValueError, match="border must be one of sliding, words"):
        atlas.border_box_counts(border="all")


def test_classes_must_be_a_bool():
    with pytest.raises(ValueError, match="classes must be True or False"):
        sb.certify(depth=2, classes="yes", **FIG7)


def test_the_perimeter_bracket_is_the_sliding_counts(atlas):
    r = atlas.perimeter_bracket(2, 5)
    s = atlas.border_box_counts(border="sliding")
    assert r["basis"] == "proven" and r["lower"] == list(s["lower"][2:6]) and r["upper"] == list(s["upper"][2:6])
    assert r["slope"] == atlas.slope_bracket(2, 5, border="sliding")
    assert "max_iter -> infinity" in r["not_proven"]


@pytest.mark.parametrize("ext", ["nc", "zarr"])
def test_a_saved_atlas_with_class_proofs_verifies(atlas, tmp_path, ext):
    path = tmp_path / f"a.{ext}"
    atlas.save(path)
    v = sb.verify(path)
    assert v.ok, v
    back = sb.CertifiedAtlas.load(path).boxes
    assert (back["status"].values == SLIDING).sum() == (atlas.boxes["status"].values == SLIDING).sum()


def test_the_branch_checker_keeps_word_texts_as_python_strings():
    # a fixed-width copy of the words takes the longest one's width for every row: at depth
    # 12 of Fig. 7 a 34,733-character word list made it 191 GiB and the checker failed
    import xarray as xr

    from stairbounce.structure.verify_branches import _texts

    long = " | ".join(["(1, 1, 2, 0^inf)"] * 3000)
    for values in (np.array([long, "(2, 0^inf)"], dtype=object), np.array([long, "(2, 0^inf)"])):
        got = _texts(xr.Dataset({"word": ("box", values)}), "word")
        assert got.dtype == object and got[0] == long and got[1] == "(2, 0^inf)"
    coded = xr.Dataset({"word_code": ("box", np.array([1, 0, 1]))}, attrs={"word_names": ["", long]})
    got = _texts(coded, "word")
    assert got.dtype == object and list(got) == [long, "", long]


@pytest.mark.parametrize("max_live, max_leaves", [(None, None), (1, 64), (2, 1), (8, 2)])
def test_the_compiled_branch_follower_is_the_python_rule_box_for_box(atlas, max_live, max_leaves):
    """``_check_kernel.follow_boxes`` (what ``sb.verify`` runs) against
    ``verify_branches.follow`` (the rule in Python): the same claim and the same
    words on boxes of every status, with the atlas's limits and with small ones
    that force merges (max_live 1, 2) and the leaf cap (max_leaves 1, 2)."""
    from stairbounce.structure._check_kernel import follow_boxes
    from stairbounce.structure.verify_branches import _word_text, follow

    b = atlas.boxes
    live = int(b.attrs["branch_max_live"]) if max_live is None else max_live
    leaves = int(b.attrs["branch_max_leaves"]) if max_leaves is None else max_leaves
    rng = np.random.default_rng(11)
    rows = rng.choice(b.sizes["box"], 300, replace=False)
    rows = np.union1d(rows, np.flatnonzero(b["status"].values == SLIDING)[:200])
    e0, e1, u0, u1 = (b[k].values[rows].astype(np.float64) for k in ("e0", "e1", "u0", "u1"))
    claims, leaf_off, it_off, impacts = follow_boxes(e0, e1, u0, u1, atlas.max_iter, live, leaves, 4096)
    names = {0: None, 1: "sliding", 2: "no_slide_within"}
    seen = set()
    for n in range(rows.size):
        claim, words = follow(e0[n], e1[n], u0[n], u1[n], atlas.max_iter, live, leaves)
        got = {_word_text(tuple(impacts[it_off[q]:it_off[q + 1]].tolist())) for q in range(leaf_off[n], leaf_off[n + 1])}
        assert (names[int(claims[n])], got if claims[n] == 1 else set()) == (claim, words), rows[n]
        seen.add(claim)
    assert "sliding" in seen and None in seen  # both outcomes were compared
