"""How the cascades are organised: the families on a line or in a window (at two
levels of nesting) and the organising centres.  Moved verbatim from ``cascades.py``
and ``cascade_families.py`` (whose module docstring follows).

How the cascades are organised (issue 39, items 3-5): the families of a
window at two levels of nesting, the Farey / Stern-Brocot test of the order of
words along lines, the number of members of a family against e, and the
organising centres (the corners where most border arcs meet, beside the
accumulation curves of the cascades).

Everything here is built on :mod:`stairbounce.cascades`: members and edges
are located exactly (to rounding) on lines of the plane by the lexicographic
order of itineraries; what is sampled (the words a scan sees, the points of a
line between two words) only proposes candidates, and the module says where a
statement depends on it.  Laws and verdicts are numerical, each with its
criterion.
"""

from __future__ import annotations

import math

import numpy as np

from ..model import check_count
from ..symbolic import Word, sliding_word
from .laws import cascade_law
from .members import _cascade_work, cascade
from .patterns import (_MAX_LETTERS, _Pattern, _candidates, _check_work, _lower_k, _parse_pattern,
                       _pattern_text)
from .search import _centres, _is_pair, _line_args, _window, _words_at

__all__ = ["cascades", "organising_centres", "window_families"]


def _check_families_work(cands, k_max, lines):
    """Refuse, before any search, candidate families whose cascades (each on
    ``lines`` lines, up to ``k_max``) would together pass ``_MAX_WORK``."""
    pats = [_Pattern("", "k", p, x, s) for _, p, x, s in cands]
    work = lines * sum(_cascade_work(pat, k_max) for pat in pats)
    _check_work(f"the {len(pats)} candidate families with k_max = {k_max}"
                + (f" on {lines} lines each" if lines > 1 else ""), work,
                lambda: _lower_k(lambda k: lines * sum(_cascade_work(q, k) for q in pats), " or give fewer words"))


def cascades(e, u, *, samples=2000, words=None, min_members=4, block_max=4, k_max=100, max_iter=1000,
             resolution=128, lines=3):
    """cascades(e, u, *, samples=2000, words=None, min_members=4, block_max=4, k_max=100, max_iter=1000, resolution=128, lines=3) -> pandas.DataFrame

    The families of words on a line of the plane, found by block attachment and
    then located exactly with :func:`cascade`; with both ``e`` and ``u`` ranges,
    the families of a window at two levels of nesting (below, "A window").

    The words seen on the line (``sliding_word`` at ``samples`` evenly spaced
    points, or ``words``: texts or :class:`stairbounce.Word`, e.g. a
    :func:`stairbounce.word_table`'s ``text``) are split every way as
    ``P + X^m + S`` with a primitive block ``X`` of at most ``block_max``
    letters repeated ``m >= 2`` times; each ``(P, X, S)`` is a candidate
    family ``(P, X^k, S, 0^inf)``, kept when at least ``min_members`` of the
    words seen are members (any k, two of them with k >= 2).  Each is then
    passed to :func:`cascade` on the line; families with fewer than
    ``min_members`` members found, or with the same members as one listed
    before, are left out.  Returns one row per family, most members first: ``pattern``,
    ``seen`` (members among the words seen), ``members`` (found exactly),
    ``k_first``, ``k_last``, ``stop``, ``law`` (kind), ``exponent`` and
    ``exponent_lo``/``exponent_hi``, ``ratio`` and ``ratio_lo``/``ratio_hi``
    (:func:`cascade_law` on the last 8 members), ``limit_lo``/``limit_hi``
    (the enclosure of the accumulation point, to rounding) and ``limit_name``.
    The candidates depend on the words seen (a sampled line); the members
    listed do not.

    A window (``e`` and ``u`` both ranges): the words are those of a scan of
    ``resolution`` x ``resolution`` pixel centres (the words of
    :func:`stairbounce.word_table` without its border points); each
    candidate family is located exactly with :func:`cascade` on up to
    ``lines`` lines e = const through the pixel columns where its members
    were seen (``e_line`` the one with most members, whose law is given;
    ``limit_curve`` the accumulation enclosures ``(e, lo, hi)`` on all of
    them: the accumulation point as a curve over e).  ``level`` is 1 for
    these; families of families are then found among them (level 2): the
    patterns whose run lengths differ by one free count ``n`` (e.g.
    ``((1^n, 0)^k, 1^(n+1), 0^inf)`` for n = 1, 2, 3, ..., at least three n
    seen); the level-1 family of every n = 1..8, seen or not, is then
    located on one line (that of the first family seen), and the row lists
    the n whose family has members and an accumulation enclosure there
    (``n_values``, ``members``), those enclosures (``limit_curve``), and the
    law of the accumulation points against n (:func:`cascade_law` on the
    gaps between consecutive ones, at least 5 of them; ``limit_lo`` /
    ``limit_hi`` the extrapolated accumulation of the accumulation points).
    Members' regions: :meth:`Cascade.regions`.

    Parameters
    ----------
    e, u : float, or (lo, hi)
        The line, as in :func:`cascade`.
    samples : int >= 2, default 2000
    words : iterable of str or Word, optional
    min_members : int >= 2, default 4
    block_max : int >= 1, default 4
    k_max, max_iter : as in :func:`cascade`.
    resolution : int >= 8, default 128
        A window only: pixels per side of the scan whose words are split.
    lines : int >= 1, default 3
        A window only: lines e = const each family is located on.
    """
    import pandas as pd

    from ..symbolic import parse_word

    if _is_pair(e) and _is_pair(u):  # a window: its families at two levels (window_families)
        if words is not None:
            raise ValueError("words: only for a line (one of e and u a number); a window's words "
                             "are those of its scan (resolution)")

        return window_families(e, u, min_members=min_members, block_max=block_max, k_max=k_max,
                               max_iter=max_iter, resolution=resolution, lines=lines)
    axis, name, lo, hi, fixed = _line_args(e, u)
    samples = check_count("samples", samples, 2, 10**6)
    min_members = check_count("min_members", min_members, 2)
    block_max = check_count("block_max", block_max, 1, 64)
    line = (lo, hi)
    if words is None:
        seen = set()
        for x in np.linspace(lo, hi, samples):
            w = sliding_word(*((float(x), fixed) if axis == 0 else (fixed, float(x))), max_iter)
            if w is not None:
                seen.add(w.letters)
    else:
        seen = {(w if isinstance(w, Word) else parse_word(w)).letters for w in words}
        longest = max(map(len, seen), default=0)
        if longest > _MAX_LETTERS:
            raise ValueError(f"words must have at most {_MAX_LETTERS} letters each, got one of {longest}")
    rows, done = [], set()
    cands = _candidates(seen, min_members, block_max)
    _check_families_work(cands, k_max, 1)
    for n_seen, p, x, s in cands:
        text = _pattern_text(p, x, s)
        c = cascade(_Pattern(text, "k", p, x, s), **({"e": line, "u": fixed} if axis == 0 else {"e": fixed, "u": line}),
                    k_max=k_max, max_iter=max_iter)
        key = frozenset(c.members.word)
        if len(key) < min_members or key in done:
            continue
        done.add(key)
        law, enc = c.law, c.limit_enclosure
        rows.append({"pattern": text, "seen": n_seen, "members": len(c.members),
                     "k_first": int(c.members.k.iloc[0]), "k_last": int(c.members.k.iloc[-1]),
                     "stop": c.stop, "law": law.kind, "exponent": law.exponent,
                     "exponent_lo": law.exponent_interval[0], "exponent_hi": law.exponent_interval[1],
                     "ratio": law.ratio, "ratio_lo": law.ratio_interval[0], "ratio_hi": law.ratio_interval[1],
                     "limit_lo": enc[0] if enc else math.nan, "limit_hi": enc[1] if enc else math.nan,
                     "limit_name": c.limit_name})
    cols = ["pattern", "seen", "members", "k_first", "k_last", "stop", "law", "exponent", "exponent_lo",
            "exponent_hi", "ratio", "ratio_lo", "ratio_hi", "limit_lo", "limit_hi", "limit_name"]
    out = pd.DataFrame(rows, columns=cols)
    return out.sort_values(["members", "seen"], ascending=False, kind="stable").reset_index(drop=True)


# --------------------------------------------------------------------------- #
# Families of a window, two levels                                           #
# --------------------------------------------------------------------------- #


def _runs(letters):
    """Run-length code ``[(letter, count), ...]``."""
    out = []
    for a in letters:
        if out and out[-1][0] == a:
            out[-1][1] += 1
        else:
            out.append([a, 1])
    return [tuple(r) for r in out]


def _free_count_text(runs, var_runs, base):
    """Letters of runs with the counts of ``var_runs`` written as n + offset."""
    parts = []
    for i, (a, c) in enumerate(runs):
        if i in var_runs:
            off = c - base
            exp = "n" if off == 0 else f"(n{off:+d})"
            parts.append(f"{a}^{exp}")
        else:
            parts.extend([str(a)] * c)
    return parts


def _level2(fams):
    """Families of families: level-1 patterns ``(P, X, S)`` whose run-length
    codes have the same letters and whose counts differ by one free ``n`` on
    a fixed set of runs.  Returns ``[(text, [(n, index into fams), ...]), ...]``
    with at least 3 distinct n."""
    groups: dict = {}
    for idx, (p, x, s) in enumerate(fams):
        parts = [_runs(p), _runs(x), _runs(s)]
        flat = [c for part in parts for (_, c) in part]
        shape = tuple(tuple(a for a, _ in part) for part in parts)
        groups.setdefault(shape, []).append((idx, parts, flat))
    out, used = [], set()
    for shape, mem in groups.items():
        if len(mem) < 3:
            continue
        size = len(mem[0][2])
        # every mask of runs that vary together (the one free count n), from pairwise differences
        masks = set()
        for i in range(len(mem)):
            for j in range(i + 1, len(mem)):
                d = [b - a for a, b in zip(mem[i][2], mem[j][2])]
                nz = [t for t in range(size) if d[t] != 0]
                if nz and len({d[t] for t in nz}) == 1:
                    masks.add(tuple(nz))
        for mask in sorted(masks, key=len):
            fam: dict = {}
            for idx, parts, flat in mem:
                n = flat[mask[0]]
                key = (tuple(flat[t] for t in range(size) if t not in mask),
                       tuple(flat[t] - n for t in mask))
                fam.setdefault(key, {}).setdefault(n, idx)
            for key, by_n in fam.items():
                if len(by_n) < 3 or frozenset(by_n.values()) in used:
                    continue
                used.add(frozenset(by_n.values()))
                n0 = min(by_n)
                idx0 = by_n[n0]
                parts = [_runs(t) for t in fams[idx0]]
                # the free runs' texts, offsets relative to n
                sizes = [len(pt) for pt in parts]
                texts, at = [], 0
                for pt, sz in zip(parts, sizes):
                    var = {t - at for t in mask if at <= t < at + sz}
                    texts.append(_free_count_text(pt, var, n0))
                    at += sz
                block = texts[1]
                body = (f"{block[0]}^k" if len(block) == 1 and "^" not in block[0]
                        else "(" + ", ".join(block) + ")^k")
                text = "(" + ", ".join([*texts[0], body, *texts[2], "0^inf"]) + ")"
                out.append((text, sorted(by_n.items()), _member_maker(parts, set(mask), n0)))
    return out


def _member_maker(parts, mask, n0):
    """The level-1 pattern ``(P, X, S)`` of a family of families at any n: the
    runs in ``mask`` (flat indices) get count ``n + (c - n0)``; None where a
    count would be below 1."""

    def make(n):
        out, at = [], 0
        for pt in parts:
            letters = []
            for a, c in pt:
                c2 = n + (c - n0) if at in mask else c
                if c2 < 1:
                    return None
                letters.extend([a] * c2)
                at += 1
            out.append(tuple(letters))
        return tuple(out)

    return make


def window_families(e, u, *, resolution=128, lines=3, min_members=4, block_max=4, k_max=100, max_iter=1000,
                    n_max=8):
    """The families of a window, as :func:`stairbounce.cascades` with two ranges
    lists them (see there); here is the work."""
    import pandas as pd

    e_lo, e_hi = _window("e", e)
    u_lo, u_hi = _window("u", u)
    resolution = check_count("resolution", resolution, 8, 4096)
    lines = check_count("lines", lines, 1, 64)
    min_members = check_count("min_members", min_members, 2)
    block_max = check_count("block_max", block_max, 1, 64)
    es, us = _centres(e_lo, e_hi, resolution), _centres(u_lo, u_hi, resolution)
    E, U = np.meshgrid(es, us)
    ids, letters = _words_at(E.ravel(), U.ravel(), max_iter)
    cols = ids.reshape(U.shape)  # (u, e)
    # where (which e columns) each word was seen
    seen_cols: dict = {}
    for w, row in enumerate(letters):
        seen_cols[row] = np.flatnonzero((cols == w).any(axis=0))
    seen = set(letters)
    rows, done, fams, cascs = [], set(), [], []
    cands = _candidates(seen, min_members, block_max)
    _check_families_work(cands, k_max, lines)
    for n_seen, p, x, s in cands:
        pat = _Pattern("", "k", p, x, s)
        text = _pattern_text(p, x, s)
        # the e columns where members were seen, by how many members each shows
        count = np.zeros(resolution, int)
        for k in range(0, 2 + max(len(w) for w in seen) // len(x)):
            lt = pat.letters(k)
            if lt in seen_cols:
                count[seen_cols[lt]] += 1
        order = np.flatnonzero(count)
        if not order.size:
            continue
        main = int(order[np.argmax(count[order])])
        picks = [main] + [int(c) for c in order[np.linspace(0, order.size - 1, lines).round().astype(int)]
                          if int(c) != main]
        picks = list(dict.fromkeys(picks))[:lines]
        found, curve, first = set(), [], None
        for c in picks:
            cc = cascade(_Pattern(text, "k", p, x, s), e=float(es[c]), u=(u_lo, u_hi), k_max=k_max, max_iter=max_iter)
            found.update(cc.members.word)
            if first is None:
                first = cc
            if cc.limit_enclosure is not None:
                curve.append((float(es[c]), cc.limit_enclosure[0], cc.limit_enclosure[1]))
        key = frozenset(found)
        if len(key) < min_members or key in done:
            continue
        done.add(key)
        law, enc = first.law, first.limit_enclosure
        m = first.members
        rows.append({"pattern": text, "level": 1, "seen": n_seen, "members": len(key),
                     "k_first": int(m.k.iloc[0]) if len(m) else -1,
                     "k_last": int(m.k.iloc[-1]) if len(m) else -1,
                     "stop": first.stop, "law": law.kind, "exponent": law.exponent,
                     "exponent_lo": law.exponent_interval[0], "exponent_hi": law.exponent_interval[1],
                     "ratio": law.ratio, "ratio_lo": law.ratio_interval[0], "ratio_hi": law.ratio_interval[1],
                     "limit_lo": enc[0] if enc else math.nan, "limit_hi": enc[1] if enc else math.nan,
                     "limit_name": first.limit_name, "e_line": float(es[main]),
                     "limit_curve": tuple(sorted(curve)), "n_values": ()})
        fams.append((p, x, s))
        cascs.append(first)
    # level 2: families of families; the level-1 family of every n = 1..n_max located on one
    # line (the line of the first one seen), its accumulation points' law against n
    for text, members, make in _level2(fams):
        line = cascs[members[0][1]].fixed
        ns, pts, curve = [], [], []
        for n in range(1, n_max + 1):
            pxs = make(n)
            if pxs is None:
                continue
            c = cascade(_Pattern(_pattern_text(*pxs), "k", *pxs), e=line, u=(u_lo, u_hi), k_max=k_max, max_iter=max_iter)
            if c.limit_enclosure is not None and len(c.members):
                ns.append(n)
                pts.append(0.5 * (c.limit_enclosure[0] + c.limit_enclosure[1]))
                curve.append((line, c.limit_enclosure[0], c.limit_enclosure[1]))
        row = {"pattern": text, "level": 2, "seen": len(members), "members": len(ns),
               "k_first": ns[0] if ns else -1, "k_last": ns[-1] if ns else -1,
               "stop": f"n = 1..{n_max} tried on the line e = {line:.17g}", "law": "undecided",
               "exponent": math.nan, "exponent_lo": math.nan,
               "exponent_hi": math.nan, "ratio": math.nan, "ratio_lo": math.nan, "ratio_hi": math.nan,
               "limit_lo": math.nan, "limit_hi": math.nan, "limit_name": None, "e_line": line,
               "limit_curve": tuple(curve), "n_values": tuple(ns)}
        gaps = np.abs(np.diff(pts))
        ok = np.diff(ns) == 1
        if ok.sum() >= 4 and np.all(gaps[ok] > 0):
            kk = np.asarray(ns[:-1], float)[ok]
            law = cascade_law(kk, gaps[ok], np.asarray(pts[:-1])[ok], tail=int(ok.sum()))
            row.update({"law": law.kind, "exponent": law.exponent, "exponent_lo": law.exponent_interval[0],
                        "exponent_hi": law.exponent_interval[1], "ratio": law.ratio,
                        "ratio_lo": law.ratio_interval[0], "ratio_hi": law.ratio_interval[1],
                        "limit_lo": law.limit_interval[0], "limit_hi": law.limit_interval[1]})
        rows.append(row)
    cols_out = ["pattern", "level", "seen", "members", "k_first", "k_last", "stop", "law", "exponent",
                "exponent_lo", "exponent_hi", "ratio", "ratio_lo", "ratio_hi", "limit_lo", "limit_hi",
                "limit_name", "e_line", "limit_curve", "n_values"]
    out = pd.DataFrame(rows, columns=cols_out)
    return out.sort_values(["level", "members", "seen"], ascending=[True, False, False],
                           kind="stable").reset_index(drop=True)


# --------------------------------------------------------------------------- #
# Organising centres                                                          #
# --------------------------------------------------------------------------- #


def _node_degrees(graph):
    """Arcs (not the window's) that end at each node of a border graph."""
    deg = np.zeros(len(graph.nodes), int)
    for i, j, arc in graph.edges:
        if arc.kind == "window":
            continue
        deg[i] += 1
        if j != i:
            deg[j] += 1
    return deg


def organising_centres(e, u, patterns=(), *, resolution=64, top=8, lines=5, k_max=60, max_iter=1000,
                       regions=None):
    """organising_centres(e, u, patterns=(), *, resolution=64, top=8, lines=5, k_max=60, max_iter=1000, regions=None) -> pandas.DataFrame

    The corners of a window's border graph where the most arcs meet, each
    with its distance to the accumulation curves of the given cascades.

    The regions of the window (:func:`stairbounce.window_regions` at
    ``resolution``, or ``regions`` given) make a
    :func:`stairbounce.border_graph`; each node's degree is the number of
    border arcs (not the window's edges) that end there.  The ``top`` nodes
    of highest degree are listed: ``e``, ``u``, ``degree``, ``events`` (the
    pairs of events that meet); and for each pattern its accumulation curve,
    the enclosure of the accumulation point (:func:`stairbounce.cascade`) on
    ``lines`` lines e = const across the window, interpolated linearly in e
    at the corner: ``nearest`` (the pattern whose curve passes closest in u),
    ``distance`` (``abs(u - curve(e))``, NaN outside the curve's e span) and
    ``on_curve`` (the corner's u within the curve's enclosure interval,
    interpolated, widened by the interpolation's change between lines).
    Returns the corners table; ``attrs["curves"]`` holds each pattern's
    curve as ``[(e, lo, hi), ...]``.  Numerical (the corners are traced to
    rounding, the curves are enclosures on lines, the interpolation between
    lines is linear).

    Parameters
    ----------
    e, u : (lo, hi)
    patterns : iterable of str, as in :func:`stairbounce.cascade`
    resolution : int >= 2, default 64
    top : int >= 1, default 8
    lines : int >= 2, default 5
    k_max, max_iter : as in :func:`stairbounce.cascade`
    regions : list of Region, optional (from :func:`stairbounce.window_regions` of this window)
    """
    import pandas as pd

    from ..structure.graph import border_graph
    from ..structure.regions import window_regions

    e_lo, e_hi = _window("e", e)
    u_lo, u_hi = _window("u", u)
    top = check_count("top", top, 1)
    lines = check_count("lines", lines, 2, 1000)
    patterns = [str(p) for p in patterns]
    for p in patterns:
        _parse_pattern(p)
    if regions is None:
        resolution = check_count("resolution", resolution, 2, 4096)
        regions = window_regions((e_lo, e_hi), (u_lo, u_hi), resolution=resolution, max_iter=max_iter)
    graph = border_graph(regions)
    deg = _node_degrees(graph)
    curves = {}
    for p in patterns:
        pts = []
        for ev in np.linspace(e_lo, e_hi, lines):
            c = cascade(p, e=float(ev), u=(u_lo, u_hi), k_max=k_max, max_iter=max_iter)
            if c.limit_enclosure is not None:
                pts.append((float(ev), c.limit_enclosure[0], c.limit_enclosure[1]))
        curves[p] = pts
    # the corners inside the window (a node where an arc meets the window's edge is no corner)
    inner = [i for i, c in enumerate(graph.nodes) if all(ev[0] != "window" for ev in c.events)]
    order = sorted(inner, key=lambda i: -deg[i])[:top]
    rows = []
    for i in order:
        node = graph.nodes[int(i)]
        row = {"e": node.e, "u": node.u, "degree": int(deg[i]),
               "events": "; ".join(f"{k} {s}" for k, s in node.events), "nearest": None,
               "distance": math.nan, "on_curve": False}
        for p, pts in curves.items():
            if len(pts) < 2:
                continue
            es_ = np.array([q[0] for q in pts])
            if not es_[0] <= node.e <= es_[-1]:
                continue
            lo_ = np.interp(node.e, es_, [q[1] for q in pts])
            hi_ = np.interp(node.e, es_, [q[2] for q in pts])
            mid = 0.5 * (lo_ + hi_)
            d = abs(node.u - mid)
            if row["nearest"] is None or d < row["distance"]:
                slack = float(np.max(np.abs(np.diff([0.5 * (q[1] + q[2]) for q in pts])))) / 2
                row.update(nearest=p, distance=d, on_curve=bool(lo_ - slack <= node.u <= hi_ + slack))
        rows.append(row)
    out = pd.DataFrame(rows, columns=["e", "u", "degree", "events", "nearest", "distance", "on_curve"])
    out.attrs["curves"] = curves
    out.attrs["nodes"] = len(graph.nodes)
    out.attrs["corners"] = len(inner)
    return out
