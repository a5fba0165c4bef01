"""Proven rows: the certifier (stairbounce.certify_box / certify), re-verified
by the independent checker (stairbounce.verify), on the windows of Figs. 5e,
6 and 7."""

from __future__ import annotations

import math

import numpy as np

from ..structure.certificate import STATUSES
from .rows import Row
from .settings import DIMENSION_WINDOWS


CERTIFY_DEPTH = 9
"""Depth of the certified atlases of the report's windows at scale 1 (boxes of
window/256); each halving of ``Settings.scale`` takes one level off (4..12)."""


def _certify_depth(s):
    """The atlas depth for the settings' scale: CERTIFY_DEPTH at scale 1, one
    level less per halving of the scale, within 4..12."""
    return int(min(12, max(4, CERTIFY_DEPTH + round(math.log2(s.scale)))))


def _rejections(verdicts):
    """``(checked, rejected, first message)`` over stairbounce.verify's verdicts."""
    checked = sum(v.checked for v in verdicts)
    rejected = sum(0 if v.ok else max(v.rejected, 1) for v in verdicts)
    first = next((v.message for v in verdicts if not v.ok), "")
    return checked, rejected, first


def _proof(n_certs, rejected, first):
    """(basis, proof, verdict override or None) of a row resting on
    ``n_certs`` certificates of which the checker ``rejected`` some."""
    if rejected:
        return ("numerical", f"NOT proven: sb.verify rejected {rejected} of {n_certs} certificates "
                f"({first})", ("differs", f"the independent checker rejected {rejected} certificates"))
    return ("proven", f"interval arithmetic; {n_certs} certificates re-verified by sb.verify", None)


def _certified_atlas(s, name, e, u, perimeter=False):
    """The certified atlas of a window at :func:`_certify_depth` and the
    checker's verdict on it: ``(atlas, depth, n_proven, basis, proof, override)``.
    A window from e = 0 is certified as it is: its boxes touching e = 0 are
    certified like the others (the corners form's bounds hold on [0, e1]; e = 0 is
    the perfectly plastic impact) and re-verified by the checker.
    ``perimeter``: with class-level proofs and the fine trapping pass
    (``certify(classes=True, trap="fine")``), for the proven box counts of the
    sliding region's border."""
    import stairbounce as sb

    depth = _certify_depth(s)
    s.note(f"{name}: certified atlas, depth {depth}"
           + (", class-level proofs, trapping regions (fine)" if perimeter else ""))
    atlas = sb.certify(e=e, u=u, depth=depth, max_iter=s.max_iter, classes=perimeter,
                       trap="fine" if perimeter else False)
    n_proven = int((atlas.boxes["status"].values != _undecided_code()).sum())
    v = sb.verify(atlas)
    rejected = 0 if v.ok else max(v.rejected, 1)
    basis, proof, override = _proof(n_proven, rejected, v.message)
    return atlas, depth, n_proven, basis, proof, override


def _undecided_code():
    from ..structure.certificate import STATUSES

    return STATUSES.index("undecided")


def _window_text(e, u):
    return f"[{e[0]:.3g}, {e[1]:g}] x [{u[0]:g}, {u[1]:g}]"


def _pixels_in_proven_boxes(atlas, ds):
    """The scan's pixel centres that lie in a box the atlas proves a word or
    no sliding: ``(pixels, mismatches)``, a mismatch being a pixel whose float
    status, period or jump count is not the proven one."""
    from ..symbolic import parse_word

    b = atlas.boxes
    (e_lo, e_hi), (u_lo, u_hi) = atlas.window
    depth = atlas.depth
    E, U = np.meshgrid(ds.e.values, ds.u.values, indexing="ij")
    stat = ds.status.transpose("e", "u").values
    period = ds.period.transpose("e", "u").values
    jumps = ds.jumps.transpose("e", "u").values
    n = 1 << depth
    fi = np.floor((E - e_lo) / (e_hi - e_lo) * n).astype(np.int64)
    fj = np.floor((U - u_lo) / (u_hi - u_lo) * n).astype(np.int64)
    inside = (fi >= 0) & (fi < n) & (fj >= 0) & (fj < n)
    st = b["status"].values
    # one word, or proven not to slide (a "sliding" box of the class-level proofs has
    # several possible words: its pixels are not checked against one)
    keep = (st != _undecided_code()) & (st != STATUSES.index("sliding"))
    level, ii, jj = (b[k].values.astype(np.int64)[keep] for k in ("level", "i", "j"))
    words, st = b["word"].values[keep], st[keep]
    # the proven word's period and jump count per box (-1: proven not sliding)
    names, inv = np.unique(words, return_inverse=True)
    parsed = [parse_word(str(w)) if w else None for w in names]
    per = np.array([-1 if w is None else w.period for w in parsed], dtype=np.int64)[inv]
    jmp = np.array([-1 if w is None else sum(a > 0 for a in w.letters) for w in parsed], dtype=np.int64)[inv]
    per[st != 0] = jmp[st != 0] = -1
    key = (level << 50) | (ii << 25) | jj
    order = np.argsort(key)
    key = key[order]
    pixels = mismatches = 0
    fi, fj = fi[inside], fj[inside]
    stat, period, jumps = stat[inside], period[inside], jumps[inside]
    for lv in range(depth + 1):
        if not key.size:
            break
        q = (np.int64(lv) << 50) | ((fi >> (depth - lv)) << 25) | (fj >> (depth - lv))
        pos = np.minimum(np.searchsorted(key, q), key.size - 1)
        hit = key[pos] == q
        box = order[pos[hit]]
        sliding = per[box] >= 0
        good = np.where(sliding, (stat[hit] == 0) & (period[hit] == per[box]) & (jumps[hit] == jmp[box]),
                        stat[hit] != 0)
        pixels += int(hit.sum())
        mismatches += int((~good).sum())
    return pixels, mismatches


def _proven_area_row(s, name, e, u, ds, certified):
    """The window's proven sliding area and proven number of distinct words
    (a lower bound), from its certified atlas, against the scan ``ds`` of the
    same window: the proven share must not exceed the pixels' sliding share,
    and every pixel centre in a proven box must have the proven word."""
    atlas, depth, n_proven, basis, proof, override = certified
    f = atlas.fraction()
    why_f = atlas.fraction(by="reason")
    words = atlas.words()
    by_period = words.attrs.get("by_period", {})
    pixel_share = float((ds.status.values == 0).mean())
    pixels, mismatches = _pixels_in_proven_boxes(atlas, ds)
    floor = math.floor(1000 * f["word"]) / 10  # rounded down: a proven lower bound
    ok = floor <= 100 * pixel_share and mismatches == 0
    verdict, why = ("agrees" if ok else "differs",
                    (f"the proven {floor:.1f}% <= the pixels' {100 * pixel_share:.1f}%, and all {pixels} "
                     f"pixel centres in proven boxes have the proven word" if ok else
                     f"proven {floor:.1f}% against the pixels' {100 * pixel_share:.1f}%; {mismatches} of "
                     f"{pixels} pixel centres in proven boxes disagree with their box"))
    if override:
        verdict, why = override
    und = ", ".join(f"{r} {100 * v:.1f}%" for r, v in why_f.items() if v > 0)
    return Row(f"proven sliding area and number of words (certified atlas, depth {depth})",
               "the paper's picture of the window (numerical evidence)",
               f"{_window_text(*atlas.window)}, boxes down to 1/{1 << depth} of the window: at least "
               f"{floor:.1f}% of the window proven to slide, with at least {len(words)} distinct words "
               f"(by period: {', '.join(f'{p}: {c}' for p, c in by_period.items())}); "
               + (f"{100 * f['sliding']:.1f}% proven to slide with one of several words (class-level proofs); "
                  if f["sliding"] > 0 else "") +
               f"{100 * (f['no_sliding'] + f['no_slide_within']):.1f}% proven not to slide; undecided "
               f"{100 * f['undecided']:.1f}% ({und}); the {ds.sizes['e']} x {ds.sizes['u']} pixel scan: "
               f"{100 * pixel_share:.1f}% sliding (numerical)",
               verdict=verdict, why=why, basis=basis, proof=proof + " (areas rounded down)")


def _border_bracket_row(s, name, certified, est):
    """The proven box counts of the sliding region's border (the paper's perimeter:
    ``CertifiedAtlas.perimeter_bracket``) and the slope bracket between the scales
    k = 3 .. depth, beside the numerical dimension ``est`` of this picture: it
    differs when the numerical D lies outside the bracket between the coarsest and
    the finest scale whose lower counts are > 0 (both of its ends finite: a zero
    lower count leaves an end open; ``across``, :func:`slope_verdict` says why not
    the narrowest), and is not comparable when there is no such bracket or when it
    holds all of [1, 2] (too wide to decide)."""
    from ..structure.certify import slope_verdict

    atlas, depth, n_proven, basis, proof, override = certified
    r = atlas.perimeter_bracket(verify=False)  # the checker's verdict is the certified one's
    verdict, why = slope_verdict(est.dimension, r["across"])
    if override:
        verdict, why = override
    table = "; ".join(f"k = {k}: {lo}..{up}" for k, lo, up in zip(r["k"], r["lower"], r["upper"]))
    classes = "class-level proofs, " if (atlas.boxes["status"].values == STATUSES.index("sliding")).any() else ""
    trapped = "trapping regions, " if "trap_grids" in atlas.boxes.attrs else ""  # the atlas had the pass
    return Row(f"proven box counts of the sliding region's border and their slope (certified atlas, depth "
               f"{depth}, {classes}{trapped}max_iter {atlas.max_iter})",
               f"D = {DIMENSION_WINDOWS[name][1]} (numerical, box counting on pictures)",
               f"{_window_text(*atlas.window)}: closed cells of side window/2^k meeting the border of the region "
               f"sliding within max_iter, proven lower..upper counts, {table}; slope {r['slope_text']}; narrowest "
               f"between two scales with lower counts > 0: {r['finite_text']}; "
               + (f"lower counts with {r['witnesses']} proven points inside undecided boxes; " if r["witnesses"] else "")
               + f"this picture's fit: D = {est.dimension:.3f} (numerical); not proven: {r['not_proven']}",
               verdict=verdict, why=why, basis=basis,
               proof=proof + " (the counts bound N(s); the slope brackets are rounded outward"
               + ("; the points inside undecided boxes that the lower counts use are each certified as a degenerate "
                  "box and re-verified by the checker)" if r["witnesses"] else ")"))
