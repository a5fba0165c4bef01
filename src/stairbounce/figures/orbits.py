"""Orbits and cascades: Figs. 1 and 2 (a real orbit drawn as the paper's
schematics), the orbit diagrams of Figs. 8 and 9 with their bifurcations,
and the cascades of words marked on them and measured in the report."""

from __future__ import annotations

import math

import numpy as np

from .motion import ZERO_EFOLDS
from .rows import Result, Row, _ours_tested
from .settings import Settings, _cached, _save, _subplots


_SCHEMATIC = ("The paper's Figs. 1 and 2 are schematics; here they are drawn from a real "
              "orbit computed exactly (ours).")


def fig1(s: Settings) -> Result:
    """Fig. 1: the staircase and a trajectory with impacts, accumulation, slide."""
    from ..model import SLIDING, iterate
    from ..plot import plot_trajectory
    from ..symbolic import sliding_word
    from ..trajectory import trajectory

    # one period of a periodic sliding solution whose slide is long enough to see
    e, u = 0.1, 0.65
    word = sliding_word(e, u)
    steps = word.period
    traj = trajectory(e, u, 1.0, 0.0, steps)
    fig, ax = _subplots(s, figsize=(9, 6))
    plot_trajectory(traj, ax=ax)
    ax.set_title(f"Fig. 1: e = {e}, u = {u}: one period of the periodic sliding solution "
                 f"${_math_word(word)}$", fontsize="medium")
    fig.tight_layout()
    ys, vs, ks = iterate(1.0, 0.0, e, u, steps)
    back = (ys[-1], vs[-1]) == (1.0, 0.0) and ks[-1] == SLIDING and not (ks[1:-1] == SLIDING).any()
    # the same statement proven at the point (e, u) by interval arithmetic, re-verified
    import stairbounce as sb

    cert = sb.certify_box(e=(e, e), u=(u, u), max_iter=s.max_iter)
    proven = cert.status == "word" and cert.word == word and bool(sb.verify(cert))
    contradicted = cert.status != "undecided" and not (cert.status == "word" and cert.word == word)
    rows = [
        Row("the drawn solution is periodic", "a periodic sliding solution returns to (1, 0) "
            "by sliding (Section 3)",
            f"{word}: from (1, 0), the first slide is on step {steps}, back at "
            f"({ys[-1]:g}, {vs[-1]:g}); certify_box at the point: {cert.status}"
            + (f" {cert.word}" if cert.word is not None else f" ({cert.reason})"),
            verdict="agrees" if back and not contradicted else "differs",
            why=("exactly (1, 0) after one period" if back else "it does not return")
            + ("; the certificate states another outcome" if contradicted else ""),
            basis="proven" if proven else "numerical",
            proof=(f"interval arithmetic at the point (e, u) = ({e}, {u}); {len(cert.itinerary)} "
                   f"steps decided, the certificate re-verified by sb.verify") if proven else ""),
    ]
    acc = traj.accumulations[0] if traj.accumulations else None
    if acc is not None:
        # the series of eq. (2.2) from the first impact on that step, summed in closed form
        first = next(i for i in traj.impacts if i.step == acc.step)
        w = first.v_after
        t_sum = first.time + 2.0 * w / (1.0 - e)
        gap = abs(t_sum - acc.time)
        rows.append(Row("accumulation time (eq. 2.2)", "the impacts accumulate in finite time",
                        f"t = {acc.time:.12g} on step {acc.step}; first impact + "
                        f"2w/(1-e) = {t_sum:.12g}", verdict="agrees" if gap < 1e-12 else "differs",
                        why=f"the two differ by {gap:.1e}"))
    caption = (f"{_SCHEMATIC} The ball (blue) leaves an edge at (1, 0), bounces (red dots), its "
               f"impacts accumulate (star) and it slides (green) to the next edge; grey: the "
               f"staircase, step height = step length = 1. e = {e}, u = {u} are ours, chosen "
               f"for a slide long enough to see.")
    return Result("fig1", "The staircase model", [_save(fig, s, "fig1")], rows,
                  {"e": e, "u": u, "y0": 1.0, "v0": 0.0, "steps": steps}, caption=caption)


def _math_word(word):
    """A word as mathtext: ``(1, 1, 2, 0^{\\infty})``."""
    return "(" + ", ".join([*map(str, word.letters), r"0^{\infty}"]) + ")"


def _min_pair_distance(points, chunk=512):
    """The least distance between two of ``points`` (rows), in chunks of rows."""
    best = math.inf
    for i in range(0, len(points), chunk):
        block = points[i:i + chunk]
        d = np.sqrt(((block[:, None, :] - points[None, :, :]) ** 2).sum(axis=-1))
        later = np.arange(i, i + len(block))[:, None] < np.arange(len(points))[None, :]
        if later.any():
            best = min(best, float(d[later].min()))
    return best


def fig2(s: Settings) -> Result:
    """Fig. 2: the Poincare map, as the section of a long orbit."""
    from ..model import SLIDING, iterate
    from ..plot import plot_poincare_section

    e, u, y0, v0, steps, skip = 0.1, 0.9, 1.0, 0.0, 3000, 100
    ys, vs, ks = iterate(y0, v0, e, u, steps)
    fig, ax = _subplots(s, figsize=(8, 5))
    plot_poincare_section(ys, vs, ks, ax=ax)
    ax.plot([y0], [v0], "s", ms=6, color="C3", mec="k", mew=0.5, zorder=4,
            label=f"start ({y0:g}, {v0:g})")
    ax.legend(loc="center", fontsize="small")
    ax.set_title(f"Fig. 2: Poincare section, e = {e}, u = {u}, {steps} steps from ({y0}, {v0})",
                 fontsize="medium")
    fig.tight_layout()
    d = _min_pair_distance(np.stack([ys[skip:], vs[skip:]], axis=1))
    slides = int((ks[1:] == SLIDING).sum())
    from ..nonsliding import motion

    m = motion(e, u, steps=steps - skip, transient=skip, y0=y0, v0=v0)
    # "compatible with 0": within the halves' difference plus 5 e-folds over
    # the orbit, the criterion of the motion_lyap report row
    lyap_zero = abs(m["lyap1"]) <= m["lyap1_err"] + ZERO_EFOLDS / (steps - skip)
    quasi = d > 1e-9 and slides == 0 and lyap_zero
    rows = [
        Row("the orbit drawn does not return (quasi-periodic)", "- (the paper's Fig. 2 is a "
            "schematic of P)",
            f"{slides} slides in {steps} steps; least distance between two of iterates "
            f"{skip}..{steps}: {d:.2e} (> 1e-9: no return within {steps - skip} steps); "
            f"lambda_1 = {m['lyap1']:.1e} (halves differ by {m['lyap1_err']:.1e}), "
            f"compatible with 0" if quasi else
            f"{slides} slide{'' if slides == 1 else 's'}; least distance between two iterates {d:.2e}; "
            f"lambda_1 = {m['lyap1']:.1e}",
            verdict="not comparable",
            why="the paper names no orbit; the claim is ours, measured "
                + ("and holds" if quasi else "and FAILS")
                + " (no return to 1e-9, and lambda_1 within the halves' difference + "
                f"{ZERO_EFOLDS:g}/N of 0)"),
    ]
    caption = (f"{_SCHEMATIC} Each point is the state (y, v) at a step edge, coloured by its "
               f"index n (colour bar); dashed: y = 1, where the map's domain [1, inf) x R "
               f"begins; red square: the starting state (1, 0). e = {e}, u = {u}, {steps} steps are "
               f"ours.")
    return Result("fig2", "The Poincare map", [_save(fig, s, "fig2")], rows,
                  {"e": e, "u": u, "y0": y0, "v0": v0, "steps": steps,
                   "min_distance": d}, caption=caption)


# Figure 9 and its zooms: each window sits inside the previous one, at the
# right end of the gap between the n = 1 and n = 2 tongues for e = 0.1
FIG9_WINDOWS = [(0.3, 1.0), (0.57, 0.72), (0.578, 0.592), (0.5785, 0.5797)]


def _orbits(settings, e, u_window, n):
    from ..orbits import orbit_diagram

    settings.note(f"orbit diagram e = {e:g}, u in [{u_window[0]:g}, {u_window[1]:g}], {n} values")
    inputs = {"e": e, "u": list(u_window), "n": n, "y0": 0.1, "v0": 0.0, "transient": 2000,
              "keep": 200}
    return _cached(
        settings, "orbits", inputs,
        lambda: orbit_diagram(e, np.linspace(u_window[0], u_window[1], n), y0=0.1, v0=0.0,
                              transient=2000, keep=200),
    )


def _bifurcation_marks(settings, e, u_window, n, ax):
    """Mark the discontinuity-induced bifurcations (sb.bifurcations, located to
    rounding and labelled graze / edge / chatter) found between ``n`` values of
    u on an orbit diagram's axes; returns their count."""
    from ..structure.bifurcations import bifurcations
    from ..plot import plot_bifurcations

    settings.note(f"bifurcations e = {e:g}, u in [{u_window[0]:g}, {u_window[1]:g}], {n} values")
    b = _cached(settings, "bifurcations", {"e": e, "u": list(u_window), "n": n, "y0": 0.1,
                                           "v0": 0.0, "transient": 2000, "keep": 200},
                lambda: bifurcations(e, np.linspace(u_window[0], u_window[1], n), y0=0.1, v0=0.0,
                                     transient=2000, keep=200))
    plot_bifurcations(b, ax=ax)
    return b.sizes["bifurcation"]


def _distinct(row):
    return np.unique(np.round(row, 9)).size


# --------------------------------------------------------------------------- #
# cascades of words (issue 39): the laws found between tongues 1 and 2 (report #
# rows of Fig. 9) and the members marked on Figs. 8 and 9                      #
# --------------------------------------------------------------------------- #

CASCADE_LINE = (0.02, (0.6, 0.75))
"""The line of the cascade rows: e = 0.02, u across the gap between tongues 1 and 2."""

CASCADE_LAW_K = (5, 12)
"""Members of ``(1^k, 0^inf)`` the law is fitted on: past the first few, before the
family's end (k = 25 at e = 0.02), where the widths fall faster than any law."""

CASCADE_K_MAX = 100
"""Members searched of ``((1, 0)^k, 1, 1, 0^inf)`` (it has more: the law is on the last 8)."""

APPROACH_TOL = 0.1
"""How far from 1 the local exponents of the edges' approach may be for "like C/k"."""

CASCADE_SAME_C = 0.01
"""How close k (u* - edge) must be for the two edges of the last member (one C)."""

CASCADE_NOTE = "edges and enclosures are float decisions, exact to rounding; the law is a fit"

# the cascades marked on Fig. 8 (each tongue's family, in the gap that follows it) and on
# each panel of Fig. 9: (pattern, members drawn); member k = 1 of (n^k, 0^inf) is tongue n
FIG8_CASCADES = [(f"({n}^k, 0^inf)", (2, 6)) for n in (1, 2, 3)]
FIG9_CASCADES = [
    [("(1^k, 0^inf)", (2, 20))],
    [("(1^k, 0^inf)", (2, 20))],
    [("((1, 0)^k, 0^inf)", (2, 20)), ("((1, 0)^k, 1, 1, 0^inf)", (1, 20))],
    [("((1, 0, 0)^k, 1, 0^inf)", (1, 20)), ("((1, 0, 0)^k, 1, 0, 1, 0^inf)", (1, 20))],
]


def _members_law(c, k=None, edge=None):
    """sb.cascade_law on the members of ``c`` not cut by the range (those with k
    in ``k``; by default the last 8), with ``edge`` ("lo" or "hi"; by default
    the one facing the accumulation point) as the positions."""
    from ..cascades import cascade_law

    m = c.members
    m = m[(m.lo_kind != "range") & (m.hi_kind != "range") & (m.width > 0) & (m.k >= 1)]
    if k is not None:
        m = m[(m.k >= k[0]) & (m.k <= k[1])]
    if edge is None:
        edge = "hi" if len(m) < 2 or m.lo.iloc[-1] > m.lo.iloc[0] else "lo"
    tail = max(4, len(m)) if k is not None else 8
    return cascade_law(m.k.values.astype(float), m.width.values.astype(float),
                         m[edge].values.astype(float), tail=tail)


def _range_text(lo, hi, digits=4):
    return f"[{lo:.{digits}g}, {hi:.{digits}g}]"


def _cascade_rows(s):
    """The laws of two cascades between tongues 1 and 2 at e = 0.02, measured
    exactly (sb.cascade) and fitted (sb.cascade_law): three rows of ours."""
    from ..cascades import cascade

    e, u = CASCADE_LINE
    line = f"e = {e:g}, u in [{u[0]:g}, {u[1]:g}]"
    s.note(f"fig9: cascades between tongues 1 and 2 at e = {e:g}")
    ones = cascade("(1^k, 0^inf)", e=e, u=u, k_max=CASCADE_K_MAX)
    # the right edges face the accumulation point (the members move right with k)
    law = _members_law(ones, CASCADE_LAW_K, "hi")
    ks = ones.members.k
    k0, k1 = CASCADE_LAW_K
    rule = (f"sb.cascade_law decides algebraic when the RMS residual of log w against log k is "
            f"{law.threshold:g} times smaller than that of log w against k on k = {k0}..{k1}, "
            f"geometric for the reverse, undecided otherwise")
    rows = [_ours_tested(
        f"widths of the cascade (1^k, 0^inf) between tongues 1 and 2 ({line})",
        f"members k = {ks.iloc[0]}..{ks.iloc[-1]} located exactly (sb.cascade; stop: "
        f"{ones.stop.split(':')[0]}); widths on k = {k0}..{k1}: {law.kind}, exponent "
        f"{law.exponent:.3g} in {_range_text(*law.exponent_interval, 3)} (ratio {law.ratio:.3g}); "
        f"residuals algebraic {law.residual_algebraic:.2g}, geometric {law.residual_geometric:.2g}",
        law.kind == "algebraic", rule, CASCADE_NOTE)]

    # the accumulation point against the closed form of the neutral family, and the
    # approach of both edges: C/k with one C
    u_star = math.sqrt((1 - e) / (2 * (1 + e)))
    enc = ones.limit_enclosure
    inside = enc is not None and enc[0] <= u_star <= enc[1]
    beta = law.approach_interval
    like_1_over_k = (law.approach_kind == "algebraic"
                     and all(abs(b - 1) <= APPROACH_TOL for b in beta))
    left = _members_law(ones, CASCADE_LAW_K, "lo")
    whole = ones.members[(ones.members.lo_kind != "range") & (ones.members.hi_kind != "range")]
    first, last = whole.iloc[0], whole.iloc[-1]
    c_lo = [r.k * (u_star - r.lo) for r in (first, last)]
    c_hi = last.k * (u_star - last.hi)
    one_c = c_hi > 0 and abs(c_lo[1] / c_hi - 1) <= CASCADE_SAME_C
    enc_text = (f"enclosure {_range_text(enc[0], enc[1], 9)} (first {enc[2]} steps of 1, 1, 1, ...)"
                if enc is not None else "no enclosure")
    rows.append(_ours_tested(
        f"(1^k, 0^inf) accumulates on u* = sqrt((1-e)/(2(1+e))), its edges like C/k ({line})",
        f"u* = {u_star:.10g}; {enc_text}; right edges (facing u*) on k = {k0}..{k1} approach "
        f"{law.approach_kind}ally, exponent {law.approach:.3g} in {_range_text(*beta, 3)}, "
        f"extrapolated limit {law.limit:.9g} ({law.limit - u_star:+.1e} from u*); left edges: "
        f"local exponents {_range_text(*left.approach_interval, 3)} on k = {k0}..{k1}, "
        f"k (u* - u_lo) = {c_lo[0]:.4g} at k = {first.k}, {c_lo[1]:.4g} at k = {last.k}, against "
        f"k (u* - u_hi) = {c_hi:.4g} there",
        inside and like_1_over_k and one_c,
        f"the enclosure (the points that follow 1, 1, 1, ... for its first steps) contains u*; the "
        f"right edges' gaps are algebraic by sb.cascade_law's criterion with every local exponent "
        f"within {APPROACH_TOL:g} of 1; and at the last member k (u* - edge) is the same for both "
        f"edges within {100 * CASCADE_SAME_C:g}% (one C)", CASCADE_NOTE))

    nested = cascade("((1, 0)^k, 1, 1, 0^inf)", e=e, u=u, k_max=CASCADE_K_MAX)
    nlaw = _members_law(nested)
    nenc = nested.limit_enclosure
    agree = (nenc is not None and math.isfinite(nlaw.limit)
             and nenc[0] <= nlaw.limit <= nenc[1])
    nk = nlaw.ks_used
    rows.append(_ours_tested(
        f"widths and accumulation of the cascade ((1, 0)^k, 1, 1, 0^inf) ({line})",
        f"members k = {nested.members.k.iloc[0]}..{nested.members.k.iloc[-1]} (stop: "
        f"{nested.stop}); widths on k = {nk[0]}..{nk[-1]}: {nlaw.kind}, exponent "
        f"{nlaw.exponent:.4g} in {_range_text(*nlaw.exponent_interval, 4)}; extrapolated limit "
        f"{nlaw.limit:.9g}; "
        + (f"enclosure {_range_text(nenc[0], nenc[1], 9)} (first {nenc[2]} steps of the limit itinerary)"
           if nenc is not None else "no enclosure"),
        nlaw.kind == "algebraic" and agree,
        f"sb.cascade_law decides algebraic ({nlaw.threshold:g} times smaller residual, last "
        f"{len(nk)} members), and the limit extrapolated from the edges lies in the enclosure "
        f"found from the order of itineraries", CASCADE_NOTE))
    return rows


def _cascade_marks(settings, ax, e, window, cascades, offset=0.0, unit=1.0, first=4,
                   legend="upper right"):
    """Locate the members of ``cascades`` ((pattern, (k_lo, k_hi)) pairs) on the
    line e = const inside ``window`` (sb.cascade), and mark them on an orbit
    diagram's axes at the heights of their periodic orbits, drawn as
    ``(y - offset) / unit``; returns the cascades."""
    from ..cascades import cascade
    from ..model import iterate
    from ..plot import plot_cascade_members

    settings.note(f"cascades e = {e:g}, u in [{window[0]:g}, {window[1]:g}]")
    found, heights = [], []
    for pattern, (k_lo, k_hi) in cascades:
        c = cascade(pattern, e=e, u=window, k_max=k_hi)
        h = {}
        for r in c.members.itertuples():
            if k_lo <= r.k <= k_hi:
                ys, _, _ = iterate(1.0, 0.0, e, 0.5 * (r.lo + r.hi), int(r.period))
                h[int(r.k)] = (np.unique(np.round(ys[:-1], 12)) - offset) / unit
        found.append(c)
        heights.append(h)
    plot_cascade_members(found, ax=ax, heights=heights, k=[c[1] for c in cascades], first=first,
                         legend=legend)
    return found


def fig8(s: Settings) -> Result:
    """Fig. 8: orbit diagram for e = 0.001: grazing bifurcations, one per tongue."""
    from ..model import tongue
    from ..plot import plot_orbit_diagram

    e, window, n = 0.001, (0.3, 2.0), s.px(3000)
    ds = _orbits(s, e, window, n)
    fig, ax = _subplots(s, figsize=(10, 5.8))
    # left of the first grazing at u = sqrt(1/2) there is one branch, at y = 1:
    # the legend goes above it, clear of the bifurcation and of the tongue numbers
    plot_orbit_diagram(ds, ax=ax, overlay=("tongues",), legend="center left")
    _bifurcation_marks(s, e, window, s.px(500), ax)
    # the legend sits above the first branches, clear of the tongue numbers
    _cascade_marks(s, ax, e, window, FIG8_CASCADES, first=0, legend=(0.2, 0.7))
    ax.set_title(f"Fig. 8: orbit diagram, e = {e} (iterates 2001-2200 from (0.1, 0))")
    fig.tight_layout()
    counts, ok = [], True
    for k in range(1, 7):
        lo, hi = tongue(k, e)
        i = int(np.argmin(np.abs(ds.u.values - 0.5 * (lo + hi))))
        c = _distinct(ds.y.values[i])
        counts.append(f"n={k}: {c}")
        ok &= c == k
    rows = [
        Row("branches inside the n-th tongue", "new branches arise when u enters a new "
            "(n, 0^inf) tongue (grazing bifurcations)",
            "distinct values at the tongue centres: " + ", ".join(counts),
            verdict="agrees" if ok else "differs",
            why="n branches in tongue n, n = 1..6" if ok else "a count is not n"),
    ]
    caption = (f"Heights y of the Poincare iterates 2001-2200 from (0.1, 0) at {n} values of u "
               f"(ours; the paper does not state its u range, start or counts), binned into "
               f"cells coloured by how many iterates fall in each (white: none). e = {e} is the "
               f"paper's. Dashed/dotted lines: where tongue n of Theorem 3.1 begins "
               f"(u = sqrt((n-1)/2), a grazing bifurcation) and ends; at this e the two nearly "
               f"coincide; each tongue is numbered at its middle. Ticks at the bottom: the "
               f"discontinuity-induced bifurcations found between {s.px(500)} values of u "
               f"(stairbounce.bifurcations: where the itinerary of iterates 2001-2200 changes, "
               f"located to rounding), coloured by their event. Ticks on the branches: the "
               f"members k = {FIG8_CASCADES[0][1][0]}..{FIG8_CASCADES[0][1][1]} of the cascades "
               f"(n^k, 0^inf), n = 1..{len(FIG8_CASCADES)} (ours, issue 39; k = 1 is tongue n), "
               f"each at the heights of its periodic orbit, at the centre of its u-interval "
               f"(stairbounce.cascade, edges located to rounding): at this e they fill the "
               f"narrow gap after tongue n, a few 1e-4 wide, and accumulate on the neutral "
               f"family u = sqrt(n(1-e)/(2(1+e))).")
    return Result("fig8", "Orbit diagram, e = 0.001", [_save(fig, s, "fig8")], rows,
                  {"e": e, "u": window, "n": n, "y0": 0.1, "v0": 0.0, "transient": 2000,
                   "keep": 200}, caption=caption)


def fig9(s: Settings) -> Result:
    """Fig. 9: orbit diagram for e = 0.1 and three nested zooms (self-similarity)."""
    from ..plot import plot_orbit_diagram

    e, n = 0.1, s.px(3000)
    fig, axes = _subplots(s, 2, 2, figsize=(13, 8.6))
    data = [_orbits(s, e, window, n) for window in FIG9_WINDOWS]
    heights = []
    for k, ds in enumerate(data[1:], start=1):
        # typical height of the branches above y = 1, in the gap below sqrt(1/2)
        gap = ds.u.values < math.sqrt(0.5)
        heights.append(float(np.median(ds.y.values[gap].max(axis=1) - 1.0)))
    s.note("fig9: drawing")
    images = []
    for k, (window, ax, ds) in enumerate(zip(FIG9_WINDOWS, axes.flat, data)):
        if k == 0:
            plot_orbit_diagram(ds, ax=ax, overlay=("tongues",), colorbar=False, vmax=200,
                               legend="center left")
            ax.set_title(f"e = {e}, u in [{window[0]:g}, {window[1]:g}]", fontsize="medium")
        else:
            # zoom k in units of e^(2k): the branches' height shrinks by about e^2
            # per zoom (measured below), so the three zooms read alike
            unit = e ** (2 * k)
            plot_orbit_diagram(ds, ax=ax, colorbar=False, vmax=200, offset=1.0, unit=unit,
                               range=(1.0 - 0.1 * unit, 1.0 + 1.3 * unit),
                               label=f"(y - 1) / $10^{{-{2 * k}}}$")
            ax.set_title(f"zoom {k}: u in [{window[0]:g}, {window[1]:g}]", fontsize="medium")
        _bifurcation_marks(s, e, window, s.px(300), ax)
        # numbered: the first cascade of each panel (the second's first members sit
        # under the bifurcations' legend)
        _cascade_marks(s, ax, e, window, FIG9_CASCADES[k], offset=0.0 if k == 0 else 1.0,
                       unit=1.0 if k == 0 else e ** (2 * k), first=[4, 0][:len(FIG9_CASCADES[k])],
                       legend=(0.01, 0.74))
        images += ax.get_images()
        if k < len(FIG9_WINDOWS) - 1:
            nxt = FIG9_WINDOWS[k + 1]
            ax.axvspan(nxt[0], nxt[1], color="C0", alpha=0.12, lw=0)
    fig.suptitle("Fig. 9: orbit diagrams for e = 0.1 (iterates 2001-2200 from (0.1, 0)); "
                 "shaded: the next zoom")
    fig.tight_layout(rect=(0, 0, 0.92, 1))
    cax = fig.add_axes((0.93, 0.12, 0.015, 0.76))
    cb = fig.colorbar(images[0], cax=cax)
    cb.set_label("iterates per cell (all panels)")
    ratios = [heights[i + 1] / heights[i] for i in range(len(heights) - 1) if heights[i] > 0]
    same = len(ratios) == 2 and abs(ratios[1] / ratios[0] - 1) < 0.05
    rows = [
        Row("self-similar scheme", "an autosimilar bifurcation diagram at smaller and smaller "
            "scales", "median height of the branches above y = 1 in zooms 1-3: "
            + ", ".join(f"{h:.2e}" for h in heights)
            + "; measured scale factor between nested zooms " + ", ".join(f"{r:.4f}" for r in ratios)
            + f" (e^2 = {e * e:.4f})",
            verdict="agrees" if same else "differs",
            why=("one scale factor for both zoom steps, within "
                 f"{100 * abs(ratios[1] / ratios[0] - 1):.1f}%; the paper gives no number")
            if len(ratios) == 2 else "too few zooms measured"),
        *_cascade_rows(s),
    ]
    caption = (f"As Fig. 8 at the paper's e = {e}, {n} values of u per panel. The zoom windows "
               f"(ours: the paper gives none) sit inside each other, shaded in the panel "
               f"before; zoom k shows (y - 1) in units of 10^(-2k) = e^(2k), so that the three "
               f"read alike if the scheme is self-similar with factor e^2. One colour scale "
               f"(iterates per cell) for all four panels. Shaded bands and ticks (ours, issue "
               f"39): the members of the cascades in each panel, located exactly on the line "
               f"(stairbounce.cascade, edges to rounding), the ticks at the heights of each "
               f"member's periodic orbit (its branches), the first members numbered k: "
               f"(1^k, 0^inf) in the gap between tongues 1 and 2 (top panel, zoom 1), ((1, 0)^k, 0^inf) and "
               f"((1, 0)^k, 1, 1, 0^inf) on either side of their common accumulation point "
               f"(zoom 2), and one level down ((1, 0, 0)^k, 1, 0^inf) and "
               f"((1, 0, 0)^k, 1, 0, 1, 0^inf) (zoom 3). The report's cascade rows measure "
               f"their laws at e = {CASCADE_LINE[0]:g}.")
    return Result("fig9", "Orbit diagrams, e = 0.1, with zooms", [_save(fig, s, "fig9")], rows,
                  {"e": e, "windows": FIG9_WINDOWS, "n": n, "y0": 0.1, "v0": 0.0,
                   "transient": 2000, "keep": 200, "heights": heights}, caption=caption)
