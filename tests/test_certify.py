"""Certified boxes (issue 36, items 1-3): sb.certify_box and sb.certify.

What is proven over a box is checked against the paper's theorems (the
Theorem 3.1 tongues, Corollary 2.1) and against the float map at random points
inside every proven box; the outward rounding against numpy's nextafter."""

import math

import numba
import numpy as np
import pytest

import stairbounce as sb
from stairbounce.structure import _kernel as K
from stairbounce.structure.certificate import STATUSES

from ._cli import run_cli as _cli

FIG7 = dict(e=(0.155, 0.2138), u=(0.6, 0.658))


@pytest.fixture(scope="module")
def atlas():
    return sb.certify(depth=6, **FIG7)


# ---- the outward rounding ---------------------------------------------------


@numba.njit
def _both(x):
    return K._dn(x), K._up(x)


def test_outward_steps_are_nextafter():
    specials = [0.0, -0.0, 5e-324, -5e-324, 2.0**-1022, -(2.0**-1022), 1.0, -1.0, 1.5, -1.5,
                1.7976931348623157e308, -1.7976931348623157e308]
    rng = np.random.default_rng(3)
    xs = specials + list(rng.standard_normal(500) * 10.0 ** rng.integers(-300, 300, 500))
    for x in xs:
        lo, hi = _both(x)
        with np.errstate(over="ignore"):
            assert lo == np.nextafter(x, -np.inf) and hi == np.nextafter(x, np.inf), x
    # no bound past the largest float: NaN, which no decision reads as a bound
    big = np.finfo(np.float64).max
    assert _both(np.inf)[0] == big and math.isnan(_both(np.inf)[1])
    assert math.isnan(_both(-np.inf)[0]) and _both(-np.inf)[1] == -big
    assert all(math.isnan(x) for x in _both(np.nan))


def test_numba_contracts_no_multiply_add_without_fastmath():
    # the argument of docs/design.md counts one rounding per operation: a fused
    # a*b+c would round once.  numba compiles with fastmath off (no "contract"
    # flag), so LLVM keeps a*b+c as two operations even on a CPU with FMA; the
    # same function with fastmath gets the fused instruction (the test can see it)
    def f(a, b, c):
        return a * b + c

    plain = numba.njit(f)
    fast = numba.njit(fastmath=True)(f)
    plain(1.0, 2.0, 3.0)
    fast(1.0, 2.0, 3.0)
    asm_plain = "\n".join(plain.inspect_asm().values()).lower()
    asm_fast = "\n".join(fast.inspect_asm().values()).lower()
    assert "fma" not in asm_plain
    import llvmlite.binding as ll

    if "+fma" in ll.get_host_cpu_features().flatten():
        assert "fma" in asm_fast
    assert plain(0.1, 0.3, -0.03) == 0.1 * 0.3 - 0.03


# ---- one box ----------------------------------------------------------------


def _tip(n):
    r = math.sqrt((n - 1) / n)
    return (1 - r) / (1 + r)


@pytest.mark.parametrize("n", range(1, 9))
def test_a_box_inside_a_tongue_is_proven_its_word(n):
    # Theorem 3.1: (n, 0^inf) exactly where sqrt((n-1)/2) < u <= sqrt(n/2) (1-e)/(1+e)
    tip = 0.5 if n == 1 else _tip(n)
    e0, e1 = 0.3 * tip, 0.31 * tip
    lo, hi = math.sqrt((n - 1) / 2), math.sqrt(n / 2) * (1 - e1) / (1 + e1)
    width = hi - lo
    c = sb.certify_box(e=(e0, e1), u=(lo + 0.25 * width, hi - 0.25 * width))
    assert c.status == "word" and c.word == sb.Word((n,))
    assert c.itinerary == (0,) * (n - 1) + (-1,)
    # points are boxes too
    p = sb.certify_box(e=(e0, e0), u=(lo + 0.5 * width, lo + 0.5 * width))
    assert p.status == "word" and p.word == sb.Word((n,))


@pytest.mark.parametrize("n", range(1, 9))
@pytest.mark.parametrize("h", [1e-3, 1e-7, 1e-12])
def test_a_box_straddling_a_tongue_border_is_never_proven(n, h):
    tip = 0.5 if n == 1 else _tip(n)
    e = 0.3 * tip
    hi = math.sqrt(n / 2) * (1 - e) / (1 + e)
    for u in ([hi] if n == 1 else [hi, math.sqrt((n - 1) / 2)]):
        c = sb.certify_box(e=(e, e + h * 1e-3), u=(u - h, u + h))
        assert c.status == "undecided" and not c.proven
        assert c.reason in ("graze", "edge", "chatter")


def test_boxes_above_the_corollary_curve_are_no_sliding():
    rng = np.random.default_rng(5)
    for _ in range(200):
        e0 = rng.uniform(0.01, 0.95)
        e1 = e0 + rng.uniform(0, 0.04)
        bound = sb.no_sliding_bound(e0)
        u0 = bound * (1 + rng.uniform(1e-6, 1.0))
        c = sb.certify_box(e=(e0, min(e1, 0.99)), u=(u0, u0 * 1.1))
        assert c.status == "no_sliding" and c.decisions == () and c.proven
    # on the curve itself (equality in (2.4) slides): not by Corollary 2.1
    e = 0.2
    u = sb.no_sliding_bound(e)
    assert sb.certify_box(e=(e, e), u=(u * (1 - 1e-12), u * (1 - 1e-12))).status != "no_sliding"


def test_the_certificate_lists_every_decision_of_its_itinerary():
    c = sb.certify_box(e=(0.18, 0.1801), u=(0.62, 0.6201))
    assert c.status == "word"
    assert sb.sliding_word(0.18005, 0.62005) == c.word
    rows = iter(zip(c.decisions, c.margins))
    for k in c.itinerary:
        name, (lo, hi) = next(rows)
        assert name == "slide" and lo <= hi
        if k == -1:
            assert lo >= 0
            break
        assert hi < 0
        for j in range(1, k + 2):
            name, (lo, hi) = next(rows)
            assert name == f"impact {j}"
            assert (lo >= 0) if j <= k else (hi < 0)
    assert next(rows, None) is None
    assert c.margins.shape == (len(c.decisions), 2)


def test_a_certificate_round_trips_through_json():
    import json

    c = sb.certify_box(e=(0.18, 0.1801), u=(0.62, 0.6201))
    back = sb.Certificate.from_dict(json.loads(json.dumps(c.to_dict())))
    assert (back.e, back.u, back.status, back.word, back.itinerary, back.decisions) == \
        (c.e, c.u, c.status, c.word, c.itinerary, c.decisions)
    np.testing.assert_array_equal(back.margins, c.margins)


def _non_sliding_point():
    """A point of the Fig. 7 window below the Corollary 2.1 curve whose float orbit does
    not slide within 2000 steps (the first such of a seeded sample)."""
    rng = np.random.default_rng(2)
    while True:
        e, u = rng.uniform(*FIG7["e"]), rng.uniform(*FIG7["u"])
        if u < sb.no_sliding_bound(e) and sb.sliding_word(e, u, 2000) is None:
            return e, u


def test_no_slide_within_is_a_finite_claim():
    # a non-sliding point below the Corollary 2.1 curve, followed for a few steps
    e, u = _non_sliding_point()
    c = sb.certify_box(e=(e, e), u=(u, u), max_iter=5)
    assert c.status == "no_slide_within" and len(c.itinerary) == 5 and -1 not in c.itinerary


def test_the_naive_form_proves_less_and_never_otherwise():
    rng = np.random.default_rng(11)
    more = 0
    for _ in range(300):
        e0 = rng.uniform(*FIG7["e"])
        u0 = rng.uniform(*FIG7["u"])
        h = 10.0 ** rng.uniform(-6, -3)
        a = sb.certify_box(e=(e0, e0 + h), u=(u0, u0 + h), form="mean-value")
        b = sb.certify_box(e=(e0, e0 + h), u=(u0, u0 + h), form="naive")
        if b.proven:
            assert (a.status, a.word) == (b.status, b.word)
        more += a.proven and not b.proven
    assert more > 0


@pytest.mark.parametrize("kw, match", [
    (dict(e=(0.3, 0.2), u=(0.5, 0.6)), "reversed"),
    (dict(e=(0.2, 1.0), u=(0.5, 0.6)), "e must be a pair"),
    (dict(e=(-0.1, 0.2), u=(0.5, 0.6)), "e must be a pair"),
    (dict(e=(1e-20, 0.2), u=(0.5, 0.6)), "2\\^-53"),
    (dict(e=(0.1, 0.2), u=(0.0, 0.6)), "u must be a pair"),
    (dict(e=(0.1, 0.2), u=(0.6, 0.5)), "reversed"),
    (dict(e=(0.1, float("nan")), u=(0.5, 0.6)), "e1 must be finite"),
    (dict(e=(0.1, 0.2), u=(0.5, float("inf"))), "u1 must be finite"),
    (dict(e=0.1, u=(0.5, 0.6)), "e must be a pair"),
    (dict(e=("a", 0.2), u=(0.5, 0.6)), "e0 must be a real number"),
    (dict(e=(0.1, 0.2), u=(0.5, 0.6, 0.7)), "u must be a pair"),
    (dict(e=(0.1, 0.2), u=(0.5, 0.6), max_iter=0), "max_iter"),
    (dict(e=(0.1, 0.2), u=(0.5, 0.6), form="exact"), "form"),
])
def test_bad_boxes_are_refused_by_name(kw, match):
    with pytest.raises(ValueError, match=match):
        sb.certify_box(**kw)


@pytest.mark.parametrize("kw, match", [
    (dict(e=(0.2, 0.2), u=(0.5, 0.6)), "empty"),
    (dict(e=(0.1, 0.2), u=(0.5, 0.5)), "empty"),
    (dict(e=(0.1, 0.2), u=(0.5, 0.6), depth=-1), "depth"),
    (dict(e=(0.1, 0.2), u=(0.5, 0.6), depth=40), "depth"),
    (dict(e=(0.1, 0.2), u=(0.5, 0.6), depth=2, tiles=8), "tiles"),
    (dict(e=(0.1, 0.2), u=(0.5, 0.6), tiles=3), "tiles"),
    (dict(e=(0.1, 0.2), u=(0.5, 0.6), progress=3), "progress"),
])
def test_bad_windows_are_refused_by_name(kw, match):
    with pytest.raises(ValueError, match=match):
        sb.certify(**kw)


# ---- the atlas --------------------------------------------------------------


def test_every_proven_box_agrees_with_the_float_map_inside(atlas):
    ds = atlas.boxes
    st = ds["status"].values
    proven = np.flatnonzero(st != K.UNDECIDED)
    assert proven.size > 100
    rng = np.random.default_rng(7)
    picks = rng.choice(proven, 3000)
    for b in picks:
        e = rng.uniform(ds["e0"].values[b], ds["e1"].values[b])
        u = rng.uniform(ds["u0"].values[b], ds["u1"].values[b])
        w = sb.sliding_word(e, u, atlas.max_iter)
        if st[b] == K.WORD:
            assert w is not None and w.format(ascii=True) == ds["word"].values[b], (e, u)
        else:
            assert w is None, (e, u, STATUSES[st[b]])


def test_the_boxes_tile_the_window(atlas):
    ds = atlas.boxes
    area = ((ds.e1 - ds.e0) * (ds.u1 - ds.u0)).sum().item()
    (a, b), (c, d) = atlas.window
    assert area == pytest.approx((b - a) * (d - c), rel=1e-12)
    f = atlas.fraction()
    assert set(f) == set(STATUSES) and sum(f.values()) == pytest.approx(1.0)
    assert f["word"] > 0.4 and f["no_sliding"] > 0.1
    r = atlas.fraction("reason")
    assert sum(r.values()) == pytest.approx(f["undecided"])
    assert r["nonsliding"] > 0  # the non-sliding motion is told apart from borders


@pytest.mark.parametrize("form", ["corners", "mean-value"])
def test_threads_and_tiles_give_the_same_boxes(form):
    kw = dict(e=(0.16, 0.19), u=(0.6, 0.63), depth=6, form=form)
    threads = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = sb.certify(**kw).boxes
        numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
        two = sb.certify(**kw).boxes
    finally:
        numba.set_num_threads(threads)
    tiled = sb.certify(tiles=4, **kw).boxes
    assert one.attrs["form"] == form
    one.attrs.pop("stairbounce_version")
    for other in (two, tiled):
        other.attrs.pop("stairbounce_version")
        assert one.identical(other)


def test_words_and_their_area_bounds(atlas):
    words = atlas.words()
    assert len(words) > 5 and (words["area"] > 0).all()
    assert sum(words.attrs["by_period"].values()) == len(words)
    top = words["word"][0]
    lo, hi = atlas.word_area_bounds(top)
    assert lo == pytest.approx(words["area"][0]) and lo <= hi <= lo + atlas.fraction()["undecided"] * 1
    (a, b), (c, d) = atlas.window
    assert hi <= (b - a) * (d - c)


def test_border_box_counts_bracket(atlas):
    df = atlas.border_box_counts(border="words")  # all borders: each word its own class
    assert list(df["k"]) == list(range(atlas.depth + 1))
    assert (df["lower"] <= df["upper"]).all()
    assert (df["upper"] <= 4.0 ** df["k"]).all()
    # a cell of the finest scale holds one box: two classes only from coarser scales on
    assert df["lower"].iloc[-1] == 0 and df["lower"].iloc[-3] > 0
    lo, hi = atlas.slope_bracket(3, 6, border="words")
    assert lo <= hi


def test_certificates_of_the_atlas_restate_its_boxes(atlas):
    ds = atlas.boxes
    proven = np.flatnonzero(ds["status"].values != K.UNDECIDED)
    certs = atlas.certificates()
    for b, c in zip(proven[:200], certs):
        assert c.e == (ds["e0"].values[b], ds["e1"].values[b])
        assert STATUSES.index(c.status) == ds["status"].values[b]
        o = ds["offsets"].values
        assert c.itinerary == tuple(ds["itinerary"].values[o[b]:o[b + 1]])
        if c.status == "word":
            assert c.word.format(ascii=True) == ds["word"].values[b]


@pytest.mark.parametrize("suffix", [".nc", ".zarr"])
def test_save_and_load_round_trip(atlas, tmp_path, suffix):
    path = tmp_path / f"atlas{suffix}"
    atlas.save(path)
    back = sb.CertifiedAtlas.load(path)
    for k in atlas.boxes.variables:
        np.testing.assert_array_equal(back.boxes[k].values, atlas.boxes[k].values)
    assert back.window == atlas.window and back.max_iter == atlas.max_iter
    assert back.fraction() == atlas.fraction()
    with pytest.raises(ValueError, match="exists"):
        atlas.save(path)
    atlas.save(path, overwrite=True)


def test_geojson_merges_the_proven_boxes_per_word(atlas, tmp_path):
    shapely = pytest.importorskip("shapely")
    from shapely.geometry import shape

    gj = atlas.geojson()
    words = atlas.fraction("word")
    feats = {f["properties"]["word"]: f for f in gj["features"] if f["properties"]["word"]}
    assert set(feats) == set(words)
    (a, b), (c, d) = atlas.window
    for w, f in feats.items():
        g = shape(f["geometry"])
        assert g.is_valid
        assert g.area == pytest.approx(words[w] * (b - a) * (d - c), rel=1e-9)
    atlas.save(tmp_path / "a.geojson")
    assert (tmp_path / "a.geojson").stat().st_size > 0
    assert shapely is not None


def test_progress_reports_every_level():
    calls = []
    sb.certify(e=(0.16, 0.19), u=(0.6, 0.63), depth=4, progress=lambda d, t: calls.append((d, t)))
    assert calls[0] == (0, 2) and calls[-1] == (2, 2)


def test_the_paper_plane_edges_are_undecided_by_range():
    a = sb.certify(e=(0.0, 1.0), u=(0.0, 1.5), depth=4)
    r = a.fraction("reason")
    assert r["range"] > 0
    ds = a.boxes
    edge = (ds["e1"].values == 1.0) | (ds["u0"].values == 0.0)
    assert (ds["reason"].values[edge] == "range").all()
    assert (ds["reason"].values[~edge] != "range").all()
    # split to the last level: a strip one box wide along the two edges e = 1 and u = 0
    # (e = 0 is inside the model: its boxes are certified, test_boxes_touching_e_zero...)
    assert (ds["level"].values[edge] == 4).all()
    assert r["range"] == pytest.approx((2 * 16 - 1) / 256)


# ---- the command line -------------------------------------------------------


def test_cli_certify_prints_the_summary_and_writes(tmp_path, capsys):
    out = tmp_path / "a.nc"
    code, text, err = _cli(["certify", "--e", "0.16:0.19", "--u", "0.6:0.63", "--depth", "5",
                            "--out", str(out), "--top", "3"], capsys)
    assert code == 0, err
    atlas = sb.CertifiedAtlas.load(out)
    f = atlas.fraction()
    assert f"word {100 * f['word']:.2f}%" in text
    assert f"proven words: {len(atlas.words())}" in text
    assert atlas.words()["word"][0] in text


@pytest.mark.parametrize("args, message", [
    (["--e", "0.3:0.2"], "--e"),
    (["--depth", "40"], "--depth"),
    (["--max-iter", "0"], "--max-iter"),
    (["--out", "x.txt"], "--out"),
    (["--e", "0.5:1.5"], "e must be a pair"),
])
def test_cli_certify_refuses_bad_input_with_status_2(args, message, capsys):
    code, text, err = _cli(["certify", *args], capsys)
    assert code == 2 and message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_cli_verify_needs_the_checker(tmp_path, capsys):
    try:
        import stairbounce.structure.verify  # noqa: F401
    except ImportError:
        code, text, err = _cli(["certify", "--verify", str(tmp_path / "a.nc")], capsys)
        assert code == 2 and "not available" in err
    else:  # the checker is there: a missing file is still one line and status 2
        code, text, err = _cli(["certify", "--verify", str(tmp_path / "missing.nc")], capsys)
        assert code == 2


def test_long_itineraries_are_stored_whole():
    # itineraries longer than the level kernel keeps (no_slide_within: max_iter entries)
    e, u = _non_sliding_point()
    a = sb.certify(e=(e, e + 1e-9), u=(u, u + 1e-9), depth=3, max_iter=40)
    ds = a.boxes
    o = ds["offsets"].values
    long_ = np.flatnonzero(ds["status"].values == K.NO_SLIDE_WITHIN)
    assert long_.size and (np.diff(o)[long_] == 40).all()
    for c in a.certificates():
        b = np.flatnonzero((ds["e0"].values == c.e[0]) & (ds["u0"].values == c.u[0]))[0]
        assert c.itinerary == tuple(ds["itinerary"].values[o[b]:o[b + 1]])


# ---- the corners form ---------------------------------------------------------
# Along a frozen itinerary every margin is non-increasing in e and u (structure/
# certify.py, certify_box): two outward-rounded point evaluations, at (e1, u1) and
# (e0, u0), decide a box.  Checked against the mean-value form (it must prove at
# least as much), the float map, the independent checker and the Arb reference.

WINDOWS = {"fig7": FIG7, "fig5e": dict(e=(0.04, 0.065), u=(0.92, 0.945)),
           "fig6": dict(e=(0.0, 0.333), u=(0.4, 0.733))}


def _random_boxes(n, seed, sizes=(-3, -14)):
    """``n`` random boxes per window, of widths window * 2^k for k uniform in ``sizes``
    (the e and u widths drawn independently)."""
    rng = np.random.default_rng(seed)
    out = []
    for name, w in WINDOWS.items():
        (ea, eb), (ua, ub) = w["e"], w["u"]
        for _ in range(n):
            he = (eb - ea) * 2.0 ** rng.uniform(*sizes[::-1])
            hu = (ub - ua) * 2.0 ** rng.uniform(*sizes[::-1])
            e0 = max(rng.uniform(ea, eb - he), 1e-3)
            u0 = rng.uniform(ua, ub - hu)
            out.append((name, (e0, e0 + he), (u0, u0 + hu)))
    return out


@pytest.fixture(scope="module")
def corner_boxes():
    """(window, e, u, corners certificate, mean-value certificate) for 1200 boxes a window."""
    rows = []
    for name, e, u in _random_boxes(1200, seed=36):
        rows.append((name, e, u, sb.certify_box(e=e, u=u, form="corners"),
                     sb.certify_box(e=e, u=u, form="mean-value")))
    return rows


def test_corners_prove_every_box_the_mean_value_form_proves(corner_boxes):
    more = {name: 0 for name in WINDOWS}
    proven = {name: 0 for name in WINDOWS}
    for name, e, u, c, m in corner_boxes:
        if m.proven:
            assert c.proven, (name, e, u, m.status, m.word)
            assert (c.status, c.word, c.itinerary) == (m.status, m.word, m.itinerary), (name, e, u)
        # every step the mean-value form decided, the corners decided alike
        assert c.itinerary[:len(m.itinerary)] == m.itinerary, (name, e, u)
        more[name] += c.proven and not m.proven
        proven[name] += c.proven
    # the gain is real in every window (this could be false: it is measured)
    assert all(more[name] > 0 for name in WINDOWS), more
    assert all(proven[name] > 100 for name in WINDOWS), proven


def test_corners_proven_boxes_agree_with_the_float_map_inside(corner_boxes):
    rng = np.random.default_rng(8)
    checked = 0
    for name, e, u, c, _ in corner_boxes:
        if not c.proven:
            continue
        for _ in range(2):
            pe, pu = rng.uniform(*e), rng.uniform(*u)
            w = sb.sliding_word(pe, pu, c.max_iter)
            if c.status == "word":
                assert w == c.word, (name, pe, pu, c.word, w)
            else:
                assert w is None, (name, pe, pu, c.status)
            checked += 1
    assert checked > 1000


def test_the_checker_accepts_every_corners_certificate(corner_boxes):
    certs = [c for *_, c, _ in corner_boxes if c.proven]
    assert len(certs) > 300
    for c in certs[:300]:  # one by one, through sb.verify(certificate)
        v = sb.verify(c)
        assert v.ok, (c.e, c.u, v)
    # and thousands at once, as the atlas stores them
    atlas = sb.certify(depth=8, form="corners", **WINDOWS["fig5e"])
    proven = int((atlas.boxes["status"].values != K.UNDECIDED).sum())
    v = sb.verify(atlas)
    assert proven > 2000 and v.ok and v.checked == atlas.boxes.sizes["box"], v


def test_corners_margins_enclose_the_margins_at_points_inside(corner_boxes):
    # the recorded enclosure [lo at (e1, u1), hi at (e0, u0)] holds the margin of
    # every point of the box: it meets the Arb ball of the margin at a point inside
    from stairbounce.structure.reference import reference_certificate

    rng = np.random.default_rng(9)
    boxes = [r for r in corner_boxes if r[3].status == "word"][:200]
    assert len(boxes) == 200
    for name, e, u, c, _ in boxes:
        pe, pu = rng.uniform(*e), rng.uniform(*u)
        p = reference_certificate(e=(pe, pe), u=(pu, pu), max_iter=c.max_iter)
        assert p.itinerary == c.itinerary and p.decisions == c.decisions
        for (lo, hi), (plo, phi) in zip(c.margins, p.margins):
            assert lo <= hi and plo <= hi and phi >= lo, (name, pe, pu)


def test_the_reference_never_decides_otherwise_where_corners_decide():
    from stairbounce.structure.reference import reference_certificate

    both = 0
    for name, e, u in _random_boxes(500, seed=37, sizes=(-6, -20)):
        c = sb.certify_box(e=e, u=u, form="corners")
        r = reference_certificate(e=e, u=u, max_iter=c.max_iter)
        # every step both decided, they decided alike
        n = min(len(c.itinerary), len(r.itinerary))
        assert c.itinerary[:n] == r.itinerary[:n], (name, e, u)
        if c.proven and r.proven:
            assert (c.status, c.word, c.itinerary) == (r.status, r.word, r.itinerary), (name, e, u)
            both += 1
        if r.proven and r.status != "no_sliding":
            assert c.proven, (name, e, u, r.status)  # the exact range decides what the ball decides
    assert both > 300


def test_the_atlas_form_is_stored_and_its_certificates_follow_it(tmp_path):
    kw = dict(e=(0.16, 0.19), u=(0.6, 0.63), depth=5)
    for form in ("corners", "mean-value", "naive"):
        a = sb.certify(form=form, **kw)
        assert a.boxes.attrs["form"] == form
        a.save(tmp_path / f"{form}.nc")
        back = sb.CertifiedAtlas.load(tmp_path / f"{form}.nc")
        assert back.boxes.attrs["form"] == form
        ds = a.boxes
        for c, b in zip(back.certificates(), np.flatnonzero(ds["status"].values != K.UNDECIDED)):
            ref = sb.certify_box(e=c.e, u=c.u, max_iter=c.max_iter, form=form)
            assert (c.status, c.itinerary) == (ref.status, ref.itinerary)
            np.testing.assert_array_equal(c.margins, ref.margins)
    assert sb.certify(**kw).boxes.attrs["form"] == "corners"  # the default


def test_boxes_touching_e_zero_are_certified_by_the_corners_form():
    # e = 0 is the perfectly plastic impact (docs/design.md): a ball that lands before
    # the edge slides, eq. (2.4) with ratio 1; the corners form's coefficients increase
    # with e on [0, 1), so a box [0, e1] x [u0, u1] is bounded by its two corners.
    # Known answer: at e = 0 the orbit of (1, 0) flies over the steps while
    # sqrt(v^2 + 2y) + v > 1/u and slides on the first landing, so u < 1/sqrt(2)
    # slides on step 1, (1, 0^inf) (also Theorem 3.1's first tongue as e -> 0).
    from . import naive

    c = sb.certify_box(e=(0.0, 0.01), u=(0.6, 0.61))
    assert c.status == "word" and str(c.word) == "(1, 0^∞)" and sb.verify(c)
    for form in ("naive", "mean-value"):  # their enclosures are not argued on [0, e1]
        with pytest.raises(ValueError, match=r"^e0 = 0 is certified by form='corners' only"):
            sb.certify_box(e=(0.0, 0.01), u=(0.6, 0.61), form=form)
    with pytest.raises(ValueError, match=r"^e must be"):
        sb.certify_box(e=(-1e-3, 0.01), u=(0.6, 0.61))
    atlas = sb.certify(e=(0.0, 0.333), u=(0.4, 0.733), depth=6)
    b = atlas.boxes
    at_zero = np.flatnonzero(b.e0.values == 0.0)
    assert "range" not in set(b.reason.values.tolist())
    words = b.status.values[at_zero] == sb.structure.certificate.STATUSES.index("word")
    assert words.sum() >= 8 and {"(1, 0^inf)", "(2, 0^inf)"} <= set(b.word.values[at_zero][words].tolist())
    assert sb.verify(atlas).ok
    rng = np.random.default_rng(0)
    for k in at_zero[words]:
        e1, u0, u1 = (float(b[v].values[k]) for v in ("e1", "u0", "u1"))
        want = tuple(int(x) for x in str(b.word.values[k]).strip("()").replace(", 0^inf", "").split(", "))
        es = [0.0, e1, *rng.uniform(2.0 ** -50, e1, 4)]
        us = [u0, u1, *rng.uniform(u0, u1, 4)]
        for e, u in zip(es, us):
            assert naive.word(e, u) == want, (k, e, u)
    # the checker rejects a wrong claim there: a (1, 0^inf) box claimed to fly over first
    from stairbounce.structure.certificate import Certificate

    k = int(at_zero[words & (b.word.values[at_zero] == "(1, 0^inf)")][0])
    cert = sb.certify_box(e=(0.0, float(b.e1.values[k])), u=(float(b.u0.values[k]), float(b.u1.values[k])))
    assert cert.status == "word" and list(cert.itinerary) == [-1] and sb.verify(cert)
    forged = Certificate.from_dict({**cert.to_dict(), "word": [2], "itinerary": [0, -1]})
    assert not sb.verify(forged)
    # the forms other than the corners leave them undecided "range", which claims nothing
    naive_atlas = sb.certify(e=(0.0, 0.333), u=(0.4, 0.733), depth=6, form="naive")
    nb = naive_atlas.boxes
    assert set(nb.reason.values[nb.e0.values == 0.0].tolist()) == {"range"} and sb.verify(naive_atlas).ok


# ---- the shared "nonsliding" check ----------------------------------------------
# certify takes the float map's "nonsliding" verdict for all the undecided boxes of a
# level at once (the scan's lane kernel, each box corner once); the reference takes
# it box by box in the level kernel (_kernel._any_slides, short-circuiting at the
# first point that slides), the algorithm before.  The boxes must be the same, bit
# for bit: a speed-up never changes an answer.


@pytest.mark.parametrize("name, depth, tiles", [("fig7", 8, 1), ("fig5e", 7, 2), ("fig6", 7, 1)])
def test_the_shared_nonsliding_check_gives_the_reference_boxes(name, depth, tiles):
    import importlib

    C = importlib.import_module("stairbounce.structure.certify")
    w = WINDOWS[name]
    fast = sb.certify(depth=depth, tiles=tiles, **w).boxes
    ref = C._certify(w["e"], w["u"], depth, 1000, None, tiles, "corners", reference=True).boxes
    assert fast.identical(ref)
    # the check decided something at both kinds of level: the leaves (centre) and above (centre, corners)
    ns = fast["reason"].values == "nonsliding"
    lv = fast["level"].values
    assert (ns & (lv == depth)).any() and (ns & (lv < depth)).any()
    # and it is not vacuous: some undecided boxes of those levels were kept from it (their
    # centre or a corner slides), or every box would be "nonsliding"
    und = fast["status"].values == K.UNDECIDED
    assert (und & ~ns & (lv >= depth - 4) & (fast["reason"].values != "range")).any()


def test_no_nonsliding_box_has_a_corner_or_centre_that_slides():
    # the label's promise, "the float map slides at none of the box's corners and centre",
    # at every level, the last included (it tested the centre alone there: 73.5 % of the
    # last level's boxes of Fig. 7 at depth 10 had a sliding corner)
    import importlib

    C = importlib.import_module("stairbounce.structure.certify")
    depth = 7
    b = sb.certify(depth=depth, **FIG7).boxes
    ns = np.flatnonzero(b["reason"].values == "nonsliding")
    lv = b["level"].values[ns]
    assert (lv == depth).sum() > 50 and (lv < depth).any()
    e0, e1, u0, u1 = (b[k].values[ns] for k in ("e0", "e1", "u0", "u1"))
    es = np.concatenate([e0, e1, e0, e1, 0.5 * (e0 + e1)])
    us = np.concatenate([u0, u0, u1, u1, 0.5 * (u0 + u1)])
    assert not C._slides_at(es, us, 1000).any()


def test_the_slide_cache_answers_each_corner_as_the_float_map():
    # the verdict at shared corners, looked up across levels, is the point's own
    import importlib

    from stairbounce.model import _constants, _slide_or_steps

    C = importlib.import_module("stairbounce.structure.certify")
    win = np.array([0.155, 0.2138, 0.6, 0.658])
    cache = C._SlideCache(win, 6, 300)
    rng = np.random.default_rng(5)
    for level in (4, 5, 6, 5):
        gi = rng.integers(0, (1 << level) + 1, 300)
        gj = rng.integers(0, (1 << level) + 1, 300)
        got = cache.corners(level, gi, gj)
        for a, b, g in zip(gi, gj, got):
            e = K._edge(win[0], win[1] - win[0], win[1], a, level)
            u = K._edge(win[2], win[3] - win[2], win[3], b, level)
            T, ratio = _constants(e, u)
            assert g == (_slide_or_steps(1.0, 0.0, e, T, ratio, 300)[0] > 0)
    assert 0 < cache.slid.sum() < cache.keys.size and np.all(np.diff(cache.keys) > 0)


def test_words_are_spelled_the_same_when_hashes_collide(monkeypatch):
    # the atlas tells itineraries apart by a hash; boxes whose hashes collide are told
    # apart by their itineraries' bytes: every hash equal gives the same words
    import importlib

    C = importlib.import_module("stairbounce.structure.certify")
    kw = dict(depth=5, **FIG7)
    good = sb.certify(**kw).boxes
    monkeypatch.setattr(K, "_itinerary_hashes", lambda itin, off, boxes, out: out.fill(7))
    bad = sb.certify(**kw).boxes
    assert len(set(good["word"].values.tolist())) > 5
    assert good.drop_attrs().identical(bad.drop_attrs())
    # and each word is the one its itinerary spells
    o, it = good["offsets"].values, good["itinerary"].values
    for b in np.flatnonzero(good["status"].values == K.WORD)[::7]:
        assert good["word"].values[b] == C.word_from_impacts(it[o[b]:o[b + 1]]).format(ascii=True)


# ---- the quadtree's order ------------------------------------------------------
# _run_tile makes each level's children in the atlas's order (by j, then i) when the
# parents are, so the table needs no sort and the shared corners' cache merges sorted
# runs (issue 44, depth 14's time); any order must give the same boxes.


def _old_children(ii, jj):
    i2, j2 = 2 * ii, 2 * jj
    return np.concatenate([i2, i2 + 1, i2, i2 + 1]), np.concatenate([j2, j2, j2 + 1, j2 + 1])


@pytest.mark.parametrize("shuffle", [False, True])
def test_children_are_the_four_of_each_box_in_the_atlas_order(shuffle):
    rng = np.random.default_rng(11)
    # distinct boxes of level 6, in the atlas's order (by j, then i) or shuffled
    key = np.unique(rng.integers(0, 64 * 64, 900))
    jj, ii = key // 64, key % 64
    if shuffle:
        p = rng.permutation(key.size)
        ii, jj = ii[p], jj[p]
    ci, cj = np.empty(4 * ii.size, np.int64), np.empty(4 * ii.size, np.int64)
    K._children(ii.astype(np.int64), jj.astype(np.int64), ci, cj)
    oi, oj = _old_children(ii, jj)
    got = cj * 128 + ci
    assert np.array_equal(np.sort(got), np.sort(oj * 128 + oi))  # the same children, each once
    assert np.unique(got).size == got.size
    if not shuffle:  # sorted parents give sorted children
        assert np.all(np.diff(got) > 0)
    else:  # shuffled ones do not (so the table's sort is exercised below)
        assert not np.all(np.diff(got) > 0)


def test_unique_runs_is_numpys_unique():
    import importlib

    C = importlib.import_module("stairbounce.structure.certify")
    rng = np.random.default_rng(3)
    runs = [np.sort(rng.integers(0, 500, 400)) for _ in range(4)]
    for keys in (np.concatenate(runs), rng.integers(0, 50, 1000), np.arange(7), np.zeros(0, np.int64)):
        keys = keys.astype(np.int64)
        want, inv = np.unique(keys, return_inverse=True)
        got, ginv = C._unique_runs(keys)
        assert np.array_equal(got, want) and np.array_equal(ginv, inv.ravel())
        assert np.array_equal(got[ginv], keys)


def test_the_table_is_the_same_whatever_order_the_boxes_come_in(monkeypatch):
    # the quadtree made with children in the old order (four runs: the table sorts them)
    # gives the table made in the atlas's order (no sort): the same boxes, bit for bit
    import importlib

    C = importlib.import_module("stairbounce.structure.certify")
    kw = dict(depth=7, **FIG7)
    fast = sb.certify(**kw).boxes

    def children(ii, jj, out_i, out_j):
        oi, oj = _old_children(ii, jj)
        out_i[:], out_j[:] = oi, oj

    seen = []
    real_table = C._box_table

    from stairbounce.structure._store_read import row_key

    def table(parts):
        key = np.concatenate([row_key(p[0], p[1], p[2]) for p in parts])
        seen.append(bool(np.all(np.diff(key) > 0)))
        return real_table(parts)

    monkeypatch.setattr(K, "_children", children)
    monkeypatch.setattr(C, "_box_table", table)
    slow = sb.certify(**kw).boxes
    assert seen == [False]  # the boxes did come unsorted
    assert fast.drop_attrs().identical(slow.drop_attrs())


@pytest.mark.parametrize("kept", [0, 4, 2000])
def test_itineraries_kept_or_computed_again_are_the_same(monkeypatch, kept):
    # the level kernel keeps itineraries of at most _KEPT steps; longer ones are computed
    # again into their place in the table: every mix gives the same table
    import importlib

    C = importlib.import_module("stairbounce.structure.certify")
    kw = dict(depth=6, max_iter=40, **FIG7)  # its no_slide_within boxes have 40 steps
    ref = sb.certify(**kw).boxes
    n = np.diff(ref["offsets"].values)
    assert (n > 32).sum() > 5 and ((n > 0) & (n <= 4)).sum() > 100  # both kinds at the default
    monkeypatch.setattr(C, "_KEPT", kept)
    assert sb.certify(**kw).boxes.drop_attrs().identical(ref.drop_attrs())


def test_the_kept_itineraries_copy_stops_when_halted_and_copies_when_not():
    # a Ctrl-C sets the halt flag: the copy (1.4 s at depth 14) returns at once, writing
    # nothing; a clear flag copies each kept row to its box's place (numpy's reference)
    rng = np.random.default_rng(2)
    n = 3 * K._COPY_CHUNK + 5
    lengths = rng.integers(0, 33, n)
    row = np.where(rng.random(n) < 0.7, 0, -1)
    lengths[row < 0] = rng.integers(0, 5, int((row < 0).sum()))  # boxes computed again elsewhere
    row[row >= 0] = np.arange(int((row >= 0).sum()))[::-1]  # rows in any order
    kept = rng.integers(-1, 4096, (int((row >= 0).sum()), 32)).astype(np.int16)
    offsets = np.zeros(n + 1, np.int64)
    np.cumsum(lengths, out=offsets[1:])
    out = np.full(int(offsets[-1]), -7, np.int64)
    K._kept_itineraries(out, offsets, kept, row, np.ones(1, np.int64))
    assert (out == -7).all()
    K._kept_itineraries(out, offsets, kept, row, np.zeros(1, np.int64))
    want = np.full(out.size, -7, np.int64)
    for b in np.flatnonzero(row >= 0):
        want[offsets[b]:offsets[b + 1]] = kept[row[b], :lengths[b]]
    np.testing.assert_array_equal(out, want)
    assert (out != -7).sum() > n  # something was copied
