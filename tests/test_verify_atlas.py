"""The checker verifies the atlas, not only its boxes (issue 43, items 1, 2 and 6).

A saved atlas tampered with in every way the reports found (edited or reversed
word names, swapped word codes, reason codes, duplicated boxes, boxes from
another window, permuted quadtree places, a widened window, removed boxes) is
rejected, or its derived numbers are said to be of the covered part; every
genuine atlas (with and without trapping regions, .nc, .zarr, in memory)
verifies; the derived numbers enclose exact areas.
"""

from fractions import Fraction

import mpmath
import numpy as np
import pytest

import stairbounce as sb
from stairbounce.structure.certificate import STATUSES, decode_atlas, read_atlas_file

# the issue's window: one word over the whole window at depth 4
ONE_WORD = dict(e=(0.01, 0.02), u=(0.3, 0.31), depth=4)
TRAPPED = dict(e=(0.2, 0.4), u=(0.3, 0.5), depth=5, trap=True)
PLAIN = dict(e=(0.155, 0.2138), u=(0.6, 0.658), depth=5)


@pytest.fixture(scope="module")
def plain():
    return sb.certify(**PLAIN)


@pytest.fixture(scope="module")
def trapped():
    a = sb.certify(**TRAPPED)
    assert (a.boxes["reason"].values == "trapping").sum() > 10
    return a


def _exact_area(ds, sel):
    """The exact rational area of the float boxes ``sel``."""
    F = Fraction
    return sum(((F(float(b)) - F(float(a))) * (F(float(d)) - F(float(c)))
                for a, b, c, d in zip(*(ds[k].values[sel] for k in ("e0", "e1", "u0", "u1")))), F(0))


def _raw(atlas, tmp_path, suffix):
    """The table as the file stores it (a Zarr store's codes and names lists)."""
    path = tmp_path / f"genuine{suffix}"
    atlas.save(path)
    return read_atlas_file(path)


def _write(ds, tmp_path, suffix, name="tampered"):
    path = tmp_path / f"{name}{suffix}"
    ds = ds.copy()
    ds.attrs = {k: (list(v) if isinstance(v, tuple) else v) for k, v in ds.attrs.items()}
    if suffix == ".zarr":
        ds.to_zarr(path, mode="w", consolidated=False)
    else:
        ds.to_netcdf(path, engine="netcdf4")
    return path


# --------------------------------------------------------------- genuine atlases


@pytest.mark.parametrize("which", ["plain", "trapped"])
@pytest.mark.parametrize("form", ["memory", ".nc", ".zarr"])
def test_every_genuine_atlas_verifies_in_every_format(which, form, plain, trapped, tmp_path):
    atlas = {"plain": plain, "trapped": trapped}[which]
    if form == "memory":
        v = sb.verify(atlas)
    else:
        path = tmp_path / f"a{form}"
        atlas.save(path)
        v = sb.verify(path)
        loaded = sb.CertifiedAtlas.load(path)
        for k in ("status", "word", "reason", "e0", "u1", "level"):
            assert (loaded.boxes[k].values == atlas.boxes[k].values).all(), k
    assert v.ok and v.atlas and v.complete and v.rejected == 0, v.message
    assert v.checked == atlas.boxes.sizes["box"]
    # the verdict's numbers are the atlas's own proven bounds
    assert v.numbers["of"] == "the window"
    assert v.numbers["status"] == atlas.fraction(bound="both")
    for w in atlas.words()["word"]:
        assert v.numbers["words"][w] == atlas.word_area_bounds(w)


def test_certify_with_trapping_rechecks_its_regions(monkeypatch):
    # a region spoiled before the re-check: certify refuses to return the atlas
    from stairbounce.structure import trapping

    real = trapping.trap_atlas

    def spoiled(ds, progress=None, **kw):
        out = real(ds, progress, **kw)
        cells = out["trap_cells"].values.copy()
        cells[:] = 0  # every region reduced to one cell: no longer invariant
        return out.assign(trap_cells=(out["trap_cells"].dims, cells))

    monkeypatch.setattr(trapping, "trap_atlas", spoiled)
    with pytest.raises(RuntimeError, match="failed the independent check"):
        sb.certify(**TRAPPED)


@pytest.mark.parametrize("which", ["plain", "trapped"])
def test_to_dataframe_has_one_row_per_box(which, plain, trapped):
    atlas = {"plain": plain, "trapped": trapped}[which]
    df = atlas.to_dataframe()
    n = atlas.boxes.sizes["box"]
    assert len(df) == n and set(df["status"]) <= set(STATUSES)
    assert (df["e0"].to_numpy() == atlas.boxes["e0"].values).all()
    assert (df["reason"] == "trapping").sum() == (atlas.boxes["reason"].values == "trapping").sum()


# ------------------------------------------------------------- tampered files


def _other_word(atlas):
    ws = atlas.words()["word"].tolist()
    assert len(ws) >= 2
    return ws


def _tamper(kind, raw, suffix, atlas):
    """The raw table ``raw`` (as stored with ``suffix``) changed in one way."""
    ds = raw.copy(deep=True)
    ds.attrs = dict(raw.attrs)
    st = ds["status"].values
    n = st.size
    zarr = suffix == ".zarr"
    if kind == "edited word_names":
        ws = _other_word(atlas)
        if zarr:
            names = list(ds.attrs["word_names"])
            k = names.index(ws[0])
            names[k] = ws[1]
            ds.attrs["word_names"] = names
        else:
            w = ds["word"].values.astype(object)
            w[w == ws[0]] = ws[1]
            ds["word"] = ("box", w.astype(str))
    elif kind == "reversed word_names":
        _reverse_names(ds, "word", zarr)
    elif kind == "swapped word_code":
        key = "word_code" if zarr else "word"
        w = ds[key].values.copy()
        a = int(np.flatnonzero(w == w[st == 0][0])[0])
        b = int(np.flatnonzero((st == 0) & (w != w[a]))[0])
        w[a], w[b] = w[b], w[a]
        ds[key] = ("box", w)
    elif kind == "reason codes":
        key = "reason_code" if zarr else "reason"
        r = ds[key].values.copy()
        text = np.array(ds.attrs["reason_names"], dtype=object)[r] if zarr else r.astype(str)
        blank = np.flatnonzero(text == "")[0]
        trapped = np.flatnonzero(text == "trapping")
        r[trapped] = r[blank]  # the trapping boxes lose their reason: Corollary 2.1 is checked instead
        ds[key] = ("box", r)
    elif kind == "reason_names reversed":
        _reverse_names(ds, "reason", zarr)
    elif kind == "duplicated boxes":
        idx = np.concatenate([np.arange(n), np.flatnonzero(st == 0)[:3]])
        ds = _take_boxes(ds, idx)
    elif kind == "boxes from another window":
        other = sb.certify(e=(0.16, 0.2), u=(0.61, 0.65), depth=4, max_iter=int(ds.attrs["max_iter"]))
        o = _raw_like(other, ds, suffix)
        ds = _replace_boxes(ds, o, np.flatnonzero(st == 0)[:5], np.flatnonzero(o["status"].values == 0)[:5])
    elif kind == "permuted level/i/j":
        i = ds["i"].values.copy()
        j = ds["j"].values.copy()
        sel = np.flatnonzero(i != j)[:4]
        i[sel], j[sel] = j[sel], i[sel]
        ds["i"] = ("box", i)
        ds["j"] = ("box", j)
    elif kind == "widened e_range":
        e = list(ds.attrs["e_range"])
        ds.attrs["e_range"] = [e[0], e[1] + (e[1] - e[0])]
    elif kind == "removed boxes":
        ds = _take_boxes(ds, np.flatnonzero(np.arange(n) % 7 != 3))
    else:
        raise AssertionError(kind)
    return ds


def _reverse_names(ds, key, zarr):
    """The texts ``key`` mapped to the reversed list of names (in place)."""
    if zarr:
        ds.attrs[f"{key}_names"] = list(ds.attrs[f"{key}_names"])[::-1]
    else:
        text = ds[key].values.astype(str)
        names = sorted(set(text))
        back = dict(zip(names, names[::-1]))
        ds[key] = ("box", np.array([back[x] for x in text]))


def _take_boxes(ds, idx):
    """The table with the boxes ``idx`` (in that order), their itineraries kept."""
    off = ds["offsets"].values
    pieces = [ds["itinerary"].values[off[b]:off[b + 1]] for b in idx]
    lengths = np.array([p.size for p in pieces], np.int64)
    offsets = np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)
    box_vars = [k for k, v in ds.data_vars.items() if v.dims == ("box",)]
    out = ds.drop_vars(["offsets", "itinerary"]).isel(box=idx)
    out = out.assign(offsets=("offset", offsets), itinerary=("itinerary_step", np.concatenate(pieces)))
    if "trap_box" in ds:  # the regions follow their boxes
        where = {int(b): k for k, b in enumerate(idx)}
        out["trap_box"] = ("trap", np.array([where.get(int(b), -1) for b in ds["trap_box"].values], np.int64))
    assert all(out[k].sizes["box"] == len(idx) for k in box_vars)
    return out


def _raw_like(atlas, like, suffix):
    ds = atlas.boxes
    if suffix == ".zarr":  # codes into the first table's names lists
        for k in ("word", "reason"):
            names = list(like.attrs[f"{k}_names"])
            for x in np.unique(ds[k].values):
                if x not in names:
                    names.append(str(x))
            like.attrs[f"{k}_names"] = names
            ds = ds.drop_vars(k).assign({f"{k}_code": ("box", np.array([names.index(x) for x in ds[k].values],
                                                                       np.int32))})
    return ds


def _replace_boxes(ds, other, mine, theirs):
    """``ds`` with its boxes ``mine`` replaced by the boxes ``theirs`` of ``other``
    (edges, status, word, place and itinerary)."""
    off, o_off = ds["offsets"].values, other["offsets"].values
    take = dict(zip(mine.tolist(), theirs.tolist()))
    pieces = [other["itinerary"].values[o_off[take[b]]:o_off[take[b] + 1]] if b in take
              else ds["itinerary"].values[off[b]:off[b + 1]] for b in range(ds.sizes["box"])]
    out = ds.copy(deep=True)
    for k, v in ds.data_vars.items():
        if v.dims == ("box",) and k in other:
            col = out[k].values.copy()
            col[mine] = other[k].values[theirs]
            out[k] = ("box", col)
    lengths = np.array([p.size for p in pieces], np.int64)
    return out.drop_vars(["offsets", "itinerary"]).assign(
        offsets=("offset", np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)),
        itinerary=("itinerary_step", np.concatenate(pieces)))


TAMPERINGS = ["edited word_names", "reversed word_names", "swapped word_code", "duplicated boxes",
              "boxes from another window", "permuted level/i/j", "widened e_range"]


@pytest.mark.parametrize("suffix", [".nc", ".zarr"])
@pytest.mark.parametrize("kind", TAMPERINGS)
def test_a_tampered_atlas_file_is_rejected(kind, suffix, plain, tmp_path):
    raw = _raw(plain, tmp_path, suffix)
    path = _write(_tamper(kind, raw, suffix, plain), tmp_path, suffix)
    v = sb.verify(path)
    assert not v and v.rejected >= 1 and v.numbers is None, (kind, v.message)
    assert v.check in ("word", "place", "overlap"), v.check


@pytest.mark.parametrize("suffix", [".nc", ".zarr"])
@pytest.mark.parametrize("kind", ["reason codes", "reason_names reversed"])
def test_tampered_reasons_of_a_trapped_atlas_are_rejected(kind, suffix, trapped, tmp_path):
    raw = _raw(trapped, tmp_path, suffix)
    assert sb.verify(_write(raw, tmp_path, suffix, "copy")), "the untouched copy verifies"
    path = _write(_tamper(kind, raw, suffix, trapped), tmp_path, suffix)
    v = sb.verify(path)
    assert not v and v.rejected >= 1 and v.check in ("reason", "corollary", "trapping"), v.message


@pytest.mark.parametrize("suffix", [".nc", ".zarr"])
def test_removed_boxes_leave_numbers_of_the_covered_part(suffix, plain, tmp_path):
    raw = _raw(plain, tmp_path, suffix)
    path = _write(_tamper("removed boxes", raw, suffix, plain), tmp_path, suffix)
    v = sb.verify(path)
    assert v.ok and v.atlas and v.complete is False
    assert "do not cover the window" in v.message and "covered part" in v.message
    nums = v.numbers
    assert nums["of"] == "the covered part"
    lo, hi = nums["uncovered_area"]
    ds = decode_atlas(read_atlas_file(path))
    kept = _exact_area(ds, np.ones(ds.sizes["box"], bool))
    (a, b), (c, d) = plain.window
    missing = (Fraction(b) - Fraction(a)) * (Fraction(d) - Fraction(c)) - kept
    assert missing > 0 and Fraction(lo) <= missing <= Fraction(hi)
    # the shares are of the covered part: they add up to 1 within their bounds
    shares = nums["status"].values()
    assert sum(s[0] for s in shares) <= 1 <= sum(s[1] for s in shares)
    loaded = sb.CertifiedAtlas.load(path)
    assert "covered part" in loaded.area_basis()


@pytest.mark.parametrize("suffix", [".nc", ".zarr"])
def test_codes_out_of_range_and_missing_names_are_refused_by_name(suffix, plain, tmp_path):
    raw = _raw(plain, tmp_path, suffix)
    bad = raw.copy(deep=True)
    st = bad["status"].values.copy()
    st[2] = 7
    bad["status"] = ("box", st)
    with pytest.raises(ValueError, match="status code 7 at box 2"):
        sb.verify(_write(bad, tmp_path, suffix, "status"))
    if suffix == ".zarr":
        bad = raw.copy(deep=True)
        c = bad["word_code"].values.copy()
        c[5] = len(raw.attrs["word_names"])
        bad["word_code"] = ("box", c)
        path = _write(bad, tmp_path, suffix, "code")
        for f in (sb.verify, sb.CertifiedAtlas.load):
            with pytest.raises(ValueError, match="word_code .* outside its names list word_names"):
                f(path)
        bad = raw.copy()
        bad.attrs = {k: v for k, v in raw.attrs.items() if k != "reason_names"}
        path = _write(bad, tmp_path, suffix, "names")
        for f in (sb.verify, sb.CertifiedAtlas.load):
            with pytest.raises(ValueError, match="reason_code is stored without its names list"):
                f(path)


# ------------------------------------------------------- derived numbers proven


def test_the_issue_s_word_area_bounds_enclose_the_exact_area():
    a = sb.certify(**ONE_WORD)
    ds = a.boxes
    assert set(ds["status"].values) == {0} and len(set(ds["word"].values)) == 1
    word = str(ds["word"].values[0])
    exact = _exact_area(ds, np.ones(ds.sizes["box"], bool))
    (e0, e1), (u0, u1) = a.window  # the boxes tile the window: the same exact area
    assert exact == (Fraction(e1) - Fraction(e0)) * (Fraction(u1) - Fraction(u0))
    assert float(exact).hex() == "0x1.a36e2eb1c4333p-14"
    lo, hi = a.word_area_bounds(word)
    assert Fraction(lo) <= exact <= Fraction(hi)
    assert lo < float(exact) < hi and (hi - lo) < 1e-14 * lo
    assert Fraction(a.words()["area"][0]) <= exact
    flo, fhi = a.fraction("word", bound="both")[word]
    assert flo <= 1.0 <= fhi and a.fraction()["word"] == flo
    v = sb.verify(a)
    assert v.numbers["words"][word] == (lo, hi)


def _tongue_area(n, window):
    """The exact area of the (n, 0^inf) tongue of Theorem 3.1 in the window (mpmath,
    60 digits): u between sqrt((n-1)/2) and sqrt(n/2)(1-e)/(1+e) (sb.tongue)."""
    (ea, eb), (ua, ub) = window
    mpmath.mp.dps = 60
    low = mpmath.sqrt(mpmath.mpf(n - 1) / 2)

    def height(e):
        high = mpmath.sqrt(mpmath.mpf(n) / 2) * (1 - e) / (1 + e)
        return max(mpmath.mpf(0), min(mpmath.mpf(ub), high) - max(mpmath.mpf(ua), low))

    # the kinks: where the upper curve crosses u = ub and u = ua
    kinks = []
    for level in (ub, ua):
        r = mpmath.mpf(level) / mpmath.sqrt(mpmath.mpf(n) / 2)  # (1-e)/(1+e) = r
        e = (1 - r) / (1 + r)
        if ea < e < eb:
            kinks.append(e)
    points = [mpmath.mpf(ea)] + sorted(kinks) + [mpmath.mpf(eb)]
    for e in (ea, (ea + eb) / 2, eb):  # the curves are the package's
        lo_, hi_ = sb.tongue(n, e)
        assert abs(lo_ - float(low)) < 1e-15 and abs(hi_ - float(mpmath.sqrt(mpmath.mpf(n) / 2) * (1 - e) / (1 + e))) < 1e-15
    return mpmath.quad(height, points)


@pytest.mark.parametrize("n, window", [(2, ((0.1, 0.2), (0.72, 0.85))), (3, ((0.05, 0.15), (1.0, 1.2)))])
def test_tongue_area_bounds_enclose_theorem_3_1_s_integral(n, window):
    a = sb.certify(e=window[0], u=window[1], depth=7)
    exact = _tongue_area(n, window)
    lo, hi = a.word_area_bounds(sb.Word((n,)))
    assert 0 < lo <= exact <= hi, (lo, float(exact), hi)
    (ea, eb), (ua, ub) = window
    assert hi < 0.5 * (eb - ea) * (ub - ua) and lo > 0.5 * exact  # the bounds say something
    v = sb.verify(a)
    assert v.numbers["words"][sb.Word((n,)).format(ascii=True)] == (lo, hi)


def test_shares_are_outward_bounds_of_the_exact_shares(plain):
    ds = plain.boxes
    (a, b), (c, d) = plain.window
    window = (Fraction(b) - Fraction(a)) * (Fraction(d) - Fraction(c))
    both = plain.fraction(bound="both")
    for k, name in enumerate(STATUSES):
        exact = _exact_area(ds, ds["status"].values == k) / window
        lo, hi = both[name]
        assert Fraction(lo) <= exact <= Fraction(hi), name
    for w, (lo, hi) in plain.fraction("word", bound="both").items():
        exact = _exact_area(ds, (ds["status"].values == 0) & (ds["word"].values == w)) / window
        assert Fraction(lo) <= exact <= Fraction(hi), w
    df = plain.border_box_counts(border="words")  # all borders (the default before issue 44)
    assert df.attrs["of"] == "the window"
    lower, upper = df["lower"].to_numpy(float), df["upper"].to_numpy(float)
    ok = lower[1:] > 0  # a level whose lower count is 0 has no slope bound to check (log2(0))
    assert ok.any()
    slope = np.log2(lower[1:][ok] / upper[:-1][ok])
    assert (df["slope_lo"].to_numpy()[1:][ok] < slope).all()


def test_malformed_trapping_variables_and_max_iter_are_refused_by_name(trapped, tmp_path):
    raw = _raw(trapped, tmp_path, ".nc")
    off = raw["trap_cell_offsets"].values.copy()
    off[-1] += 5  # past the end of trap_cells: a region would silently lose cells
    bad = raw.assign(trap_cell_offsets=(raw["trap_cell_offsets"].dims, off))
    with pytest.raises(ValueError, match="trap_cell_offsets must run from 0 to len"):
        sb.verify(_write(bad, tmp_path, ".nc", "off"))
    grid = raw["trap_grid"].values.copy()
    grid[0, 2] = np.nan
    bad = raw.assign(trap_grid=(raw["trap_grid"].dims, grid))
    with pytest.raises(ValueError, match="trap_grid's cell counts"):
        sb.verify(_write(bad, tmp_path, ".nc", "grid"))
    bad = raw.copy()
    bad.attrs = dict(raw.attrs, max_iter="abc")
    with pytest.raises(ValueError, match="the attribute max_iter must be an integer"):
        sb.verify(_write(bad, tmp_path, ".nc", "mi"))


def test_an_atlas_without_word_texts_has_its_words_spelled_by_the_checker(plain, tmp_path):
    raw = _raw(plain, tmp_path, ".nc").drop_vars("word")
    v = sb.verify(_write(raw, tmp_path, ".nc", "nowords"))
    assert v.ok and v.complete
    assert v.numbers["words"] == sb.verify(plain).numbers["words"]


def test_cli_verify_prints_the_checker_s_numbers_with_their_basis(plain, tmp_path, capsys):
    from stairbounce.cli import main

    path = tmp_path / "a.zarr"
    plain.save(path)
    with pytest.raises(SystemExit) as exit_:
        main(["certify", "--verify", str(path)])
    out = capsys.readouterr().out
    assert exit_.value.code == 0 and "0 rejected" in out and "they cover the window" in out
    assert "the checker's numbers (proven: sums of the verified boxes' exact areas, rounded outward" in out
    lo, hi = plain.fraction(bound="both")["word"]
    shown = out.split("word [")[1].split("]")[0].replace("%", "").split(", ")
    assert Fraction(shown[0]) <= 100 * Fraction(lo) and 100 * Fraction(hi) <= Fraction(shown[1])
    raw = _raw(plain, tmp_path, ".zarr")
    bad = _write(_tamper("reversed word_names", raw, ".zarr", plain), tmp_path, ".zarr")
    with pytest.raises(SystemExit) as exit_:
        main(["certify", "--verify", str(bad)])
    out = capsys.readouterr().out
    assert exit_.value.code == 1 and "failed check 'word'" in out and "checker's numbers" not in out
    c = raw.copy(deep=True)
    codes = c["word_code"].values.copy()
    codes[0] = -1
    c["word_code"] = ("box", codes)
    with pytest.raises(SystemExit) as exit_:
        main(["certify", "--verify", str(_write(c, tmp_path, ".zarr", "neg"))])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and "word_code -1 at box 0" in err and len(err.strip().splitlines()) == 1


def test_the_checker_s_edges_are_the_certifier_s_bit_for_bit():
    from stairbounce.structure import _kernel as K
    from stairbounce.structure.tiling import box_edges

    rng = np.random.default_rng(43)
    for _ in range(40):
        lo = float(rng.choice([0.0, rng.uniform(0, 1), rng.uniform(0, 1e-3), 1e-150]))
        hi = lo + float(rng.choice([1.0, rng.uniform(1e-12, 1.0), rng.uniform(0, 1e-9)])) * (1 - lo if lo < 1 else 1)
        if not hi > lo:
            continue
        level = rng.integers(0, 27, 500)
        k = (rng.random(500) * (2.0 ** level)).astype(np.int64)
        win = np.array([lo, hi, lo, hi])
        e0, e1, u0, u1 = (np.empty(500) for _ in range(4))
        K._box_edges(win, level, k, k, e0, e1, u0, u1)
        assert (box_edges(lo, hi, level, k).view(np.int64) == e0.view(np.int64)).all()
        assert (box_edges(lo, hi, level, k + 1).view(np.int64) == e1.view(np.int64)).all()
        assert (lo <= e0).all() and (e0 <= e1).all() and (e1 <= hi).all()


def test_an_atlas_whose_boxes_are_moved_has_its_numbers_refused(plain):
    # the newcomer's case: a box moved onto another box of the same word counted its area twice
    ds = plain.boxes.copy(deep=True)
    st, words = ds["status"].values, ds["word"].values
    i, j = np.flatnonzero((st == 0) & (words == words[np.flatnonzero(st == 0)[0]]))[:2]
    for k in ("e0", "e1", "u0", "u1"):
        x = ds[k].values.copy()
        x[i] = x[j]
        ds[k] = ("box", x)
    moved = sb.CertifiedAtlas(ds)
    v = sb.verify(moved)
    assert not v and v.check == "place" and v.numbers is None
    for f in (moved.fraction, moved.words, moved.border_box_counts, lambda: moved.word_area_bounds(words[i])):
        with pytest.raises(ValueError, match="not its window's quadtree"):
            f()
    assert "numbers refused" in repr(moved)
