"""The motion when the ball does not slide (issue 13): <k> over the plane,
the convergence of lambda_1, and a cut at fixed u."""

from __future__ import annotations

import numpy as np

from .rows import Result, Row, _ours
from .settings import Settings, _cached, _save, _scan, _subplots


# orbit lengths of the motion figures (the benchmark's: 1000 + 1000 steps)
MOTION_STEPS = 1000
MOTION_TRANSIENT = 1000
# a finite-N lambda_1 of a quasi-periodic orbit is a log-norm ratio over N:
# "compatible with 0" allows that many e-folds on top of the halves' difference
ZERO_EFOLDS = 5.0


def _motion(settings, e, u, n_e, n_u):
    from ..nonsliding import motion_scan

    inputs = {"e": list(e), "u": list(u), "n_e": n_e, "n_u": n_u,
              "steps": MOTION_STEPS, "transient": MOTION_TRANSIENT}
    return _cached(
        settings, "motion", inputs,
        lambda: motion_scan(e=(e[0], e[1], n_e), u=(u[0], u[1], n_u),
                            steps=MOTION_STEPS, transient=MOTION_TRANSIENT),
    )


# a pixel whose mean energy lost at impacts per step is not within this fraction
# of the height descended (1) is still transient: unconverged
ENERGY_TOL = 0.05


def _result(s, fig, name, title, rows, params, caption):
    """How each motion recipe ends: its one figure saved as ``name``, in a Result."""
    return Result(name, title, [_save(fig, s, name)], rows, params, caption=caption)


def _unconverged(ds):
    """Non-sliding pixels still transient: energy balance off by ENERGY_TOL or more."""
    return (ds.slide_step.values == 0) & ~(np.abs(ds.dissipation.values - 1.0) < ENERGY_TOL)


def _motion_plane(s: Settings, fields, unconverged=None):
    from ..plot.motion import plot_motion

    e, u = (0.0, 1.0), (0.0, 1.5)
    n_e, n_u = s.px(500), s.px(350)
    ds = _motion(s, e, u, n_e, n_u)
    sliding = _scan(s, "motion", e, u, n_e, n_u)
    fig, axes = _subplots(s, 1, len(fields), figsize=(9 * len(fields), 6.5), squeeze=False)
    mask = None if unconverged is None else unconverged(ds)
    for ax, name in zip(axes[0], fields):
        plot_motion(ds, field=name, ax=ax, sliding=sliding, unconverged=mask)
    fig.tight_layout()
    return ds, fig, {"e": e, "u": u, "size": [n_e, n_u], "steps": MOTION_STEPS,
                     "transient": MOTION_TRANSIENT}


def motion_k(s: Settings) -> Result:
    """<k> (impacts per step) over the paper's plane, families and Cor. 2.1 overlaid."""
    from ..nonsliding import k_mean_bound, speed_spread

    ds, fig, params = _motion_plane(s, ("k_mean", "speed_spread"), unconverged=_unconverged)
    ok = ds.slide_step.values == 0
    k = ds.k_mean.values[ok]
    d = ds.dissipation.values[ok]
    E, U = np.meshgrid(ds.e.values, ds.u.values)
    ratio = k / k_mean_bound(E[ok], U[ok])
    spread = speed_spread(k, ds.impulse.values[ok], ds.dissipation.values[ok], E[ok])
    near = np.abs(d - 1) < ENERGY_TOL
    rows = [
        _ours("non-sliding pixels: three quarters of Fig. 4 are white (our README's sentence)",
              f"{100 * ok.mean():.1f}% of pixels: the orbit of (1, 0) does not slide within "
              f"{MOTION_TRANSIENT + MOTION_STEPS} steps", 0.7 <= ok.mean() <= 0.8,
              "three quarters read as 70% to 80%"),
        Row("<k> over them", "-", f"{k.min():.3g} .. {k.max():.3g} impacts per step, median {np.median(k):.3g}",
            verdict="not comparable", why="the paper does not study the non-sliding motion"),
        Row("<k> against its bound (1-e)/(2(1+e)u^2)", "-",
            f"<k>/<k>_0: median {np.median(ratio):.4f}, 90th percentile {np.percentile(ratio, 90):.3f}, "
            f"max {ratio.max():.1f}; below 1 - 1% at {100 * np.mean(ratio < 0.99):.2f}% "
            "(finite orbits; the finite-N bound holds exactly, tests/test_nonsliding.py)",
            verdict="not comparable", why="a bound derived here (stairbounce.nonsliding); the paper has none"),
        Row("spread of the impact speeds Var/mean^2", "-",
            f"median {np.median(spread):.2e}, 90th percentile {np.percentile(spread, 90):.2e}; "
            f"below 1e-3 at {100 * np.mean(spread < 1e-3):.1f}% of pixels (0 on the one-impact families)",
            verdict="not comparable", why="the paper does not study the non-sliding motion"),
        _ours("energy balance", "mean energy lost at impacts per step within 5% of the height "
              f"descended (1) at {100 * near.mean():.1f}% of pixels; the others (median e "
              f"{np.median(E[ok][~near]) if (~near).any() else float('nan'):.3f}) are still gaining "
              "energy after the transient: masked in the maps", near.mean() > 0.9,
              "an identity every stationary orbit obeys; more than 90% of pixels within 5% "
              "counts as holding"),
    ]
    caption = ("Left: <k>, the mean number of impacts per step over the kept steps of the orbit "
               f"of (1, 0) ({MOTION_TRANSIENT} transient + {MOTION_STEPS} kept steps, ours), on the "
               "paper's plane e in (0, 1), u in (0, 1.5); right: the relative spread of the impact "
               "speeds. Sliding pixels in greys by word length, as Fig. 4; curves: the one-impact "
               "families u_n(e) (<k> = 1/n on them) and the Corollary 2.1 curve (dashed). "
               f"Magenta: unconverged pixels, whose mean energy lost per step is not within "
               f"{100 * ENERGY_TOL:g}% of the height descended (still transient), not coloured by "
               "a value they have not reached.")
    return _result(s, fig, "motion_k", "Non-sliding motion: impacts per step <k>", rows, params, caption)


# the orbit lengths of the lambda_1 convergence diagnostic, and how many pixels it follows
LYAP_LENGTHS = (250, 500, 1000, 2000, 4000, 8000, 16000)
LYAP_PIXELS = 24


def _lyap_convergence(e_pts, u_pts):
    """N lambda_1 at each N of LYAP_LENGTHS for the orbits of (1, 0) at the
    points (after MOTION_TRANSIENT steps): rows = points, columns = N."""
    from ..nonsliding import motion

    return np.array([[n * motion(float(e), float(u), steps=n, transient=MOTION_TRANSIENT)["lyap1"]
                      for n in LYAP_LENGTHS] for e, u in zip(e_pts, u_pts)])


def motion_lyap(s: Settings) -> Result:
    """lambda_1 of the non-sliding motion: not a map (lambda_1 = 0 is proven, a
    finite-N map is moire) but the convergence diagnostic the proof allows,
    N lambda_1 against N, and the report row "chaotic or just complicated?"."""
    ds = _motion(s, (0.0, 1.0), (0.0, 1.5), s.px(500), s.px(350))
    ok = ds.slide_step.values == 0
    l1, err = ds.lyap1.values[ok], ds.lyap1_err.values[ok]
    N = MOTION_STEPS
    zero = np.abs(l1) <= err + ZERO_EFOLDS / N
    E, U = np.meshgrid(ds.e.values, ds.u.values)
    i = int(np.argmax(l1))
    e_max, u_max = float(E[ok][i]), float(U[ok][i])
    # the pixel of largest lambda_1 and LYAP_PIXELS - 1 others drawn at random (seed 0)
    pick = np.random.default_rng(0).choice(ok.sum(), size=min(LYAP_PIXELS - 1, ok.sum()),
                                           replace=False)
    e_pts = np.concatenate([[e_max], E[ok][pick]])
    u_pts = np.concatenate([[u_max], U[ok][pick]])
    s.note("motion_lyap: N lambda_1 against N")
    nl = _lyap_convergence(e_pts, u_pts)
    lengths = np.asarray(LYAP_LENGTHS, dtype=float)
    fig, (ax, bx) = _subplots(s, 1, 2, figsize=(13, 5.2))
    for k in range(len(e_pts)):
        style = dict(color="C3", lw=1.8, zorder=3, label=f"largest lambda_1 at N = {N}: "
                     f"(e, u) = ({e_max:.3f}, {u_max:.3f})") if k == 0 else dict(
                     color="0.45", lw=0.7, alpha=0.7,
                     label=f"{len(e_pts) - 1} random non-sliding pixels" if k == 1 else None)
        ax.plot(lengths, nl[k], marker=".", **style)
        bx.plot(lengths, np.abs(nl[k]) / lengths, marker=".", **style)
    ax.axhspan(-ZERO_EFOLDS, ZERO_EFOLDS, color="C0", alpha=0.12, lw=0,
               label=f"|N lambda_1| <= {ZERO_EFOLDS:g}")
    ax.axhline(0.0, color="0.3", lw=0.6)
    ax.set_xscale("log")
    ax.set_xlabel("N, kept steps (after a transient of 1000)")
    ax.set_ylabel("N lambda_1")
    ax.set_title("N lambda_1 stays bounded as N grows: lambda_1 = 0", fontsize="medium")
    ax.legend(fontsize="small", loc="upper left")
    bx.plot(lengths, ZERO_EFOLDS / lengths, "--", color="C0", label=f"{ZERO_EFOLDS:g}/N")
    bx.set_xscale("log")
    bx.set_yscale("log")
    bx.set_xlabel("N, kept steps")
    bx.set_ylabel("|lambda_1| (per step)")
    bx.set_title("|lambda_1| falls like 1/N", fontsize="medium")
    bx.legend(fontsize="small", loc="lower left")
    fig.tight_layout()
    bounded = np.abs(nl).max(axis=1)
    drift = np.abs(nl[:, -1] - nl[:, len(LYAP_LENGTHS) // 2])
    holds = bool(zero.mean() > 0.99 and bounded.max() <= 4 * ZERO_EFOLDS)
    rows = [
        _ours("chaotic or just complicated? (Gruiz, Meszena, Tel 2017: quasi-periodic, "
              "non-chaotic)",
              f"|lambda_1| <= (halves' difference) + {ZERO_EFOLDS:g}/N at {100 * zero.mean():.2f}% "
              f"of {ok.sum()} non-sliding pixels (N = {N}); largest lambda_1 {l1[i]:.2e} at (e, u) "
              f"= ({e_max:.4f}, {u_max:.4f}); over N = {LYAP_LENGTHS[0]}..{LYAP_LENGTHS[-1]} at "
              f"{len(e_pts)} pixels |N lambda_1| stays <= {bounded.max():.1f} (its change from "
              f"N = {LYAP_LENGTHS[len(LYAP_LENGTHS) // 2]} to {LYAP_LENGTHS[-1]}: at most "
              f"{drift.max():.1f}), so lambda_1 -> 0 like 1/N. Just complicated: J carries "
              "(v, -1), so lambda_1 = 0 exactly (stairbounce.nonsliding)", holds,
              f"more than 99% of pixels within the halves' difference + {ZERO_EFOLDS:g}/N, and "
              f"|N lambda_1| <= {4 * ZERO_EFOLDS:g} at every N drawn"),
        Row("lambda_1 range", "-", f"{l1.min():.2e} .. {l1.max():.2e} per step over N = {N}",
            verdict="not comparable", why="the paper does not study the non-sliding motion"),
    ]
    params = {"e": (0.0, 1.0), "u": (0.0, 1.5), "size": [s.px(500), s.px(350)], "steps": N,
              "transient": MOTION_TRANSIENT, "lengths": list(LYAP_LENGTHS),
              "pixels": [[float(a), float(b)] for a, b in zip(e_pts, u_pts)],
              "zero_criterion": f"|lambda_1| <= lyap1_err + {ZERO_EFOLDS:g}/N"}
    caption = ("lambda_1 of the Poincare map is 0 exactly (the tangent map carries (v, -1)), so a "
               "map of its finite-N value shows only moire; drawn instead is the convergence "
               "diagnostic the proof allows: N lambda_1 against the number N of kept steps (left) "
               "and |lambda_1| against N (right) for the orbit of (1, 0) at the pixel of largest "
               f"lambda_1 on the paper's plane (red) and {len(e_pts) - 1} non-sliding pixels drawn "
               f"at random (grey; seed 0), after a transient of {MOTION_TRANSIENT} steps (ours). "
               "Bounded N lambda_1, |lambda_1| on the 1/N line: lambda_1 = 0, no chaos.")
    return _result(s, fig, "motion_lyap", "Non-sliding motion: lambda_1 = 0, N lambda_1 against N", rows, params,
                   caption)


MOTION_CUT_U = 0.9


def motion_cut(s: Settings) -> Result:
    """<k> against e at u = 0.9: how complicated the dependence on e is."""
    from ..nonsliding import motion_coords
    from ..plane import pixel_centres
    from ..plot.motion import plot_motion_cut

    n = s.px(4000)
    es = pixel_centres(0.0, 1.0, n)
    ds = motion_coords(es, [MOTION_CUT_U], steps=MOTION_STEPS, transient=MOTION_TRANSIENT)
    fig, axes = _subplots(s, 3, 1, figsize=(9, 8), sharex=True, height_ratios=(3, 2, 1))
    plot_motion_cut(ds, axes=axes)
    fig.tight_layout()
    ok = ds.slide_step.values[0] == 0
    k = ds.k_mean.values[0][ok]
    jumps = np.abs(np.diff(k))
    rows = [
        Row(f"<k> along u = {MOTION_CUT_U}", "-",
            f"{ok.sum()} non-sliding values of e of {n}; {len(np.unique(k))} distinct <k>; "
            f"largest change between neighbouring e: {jumps.max():.3f}" if k.size > 1 else "-",
            verdict="not comparable",
            why="the paper does not study the non-sliding motion; Gruiz et al. (2017) describe "
                "a very complicated dependence on e in words, with no number to compare"),
    ]
    caption = (f"A cut of the plane at u = {MOTION_CUT_U} (ours), {n} values of e: top, <k> of the "
               f"orbit of (1, 0) ({MOTION_TRANSIENT} transient + {MOTION_STEPS} kept steps) with the "
               "one-impact families' values 1/n where they cross the cut (orange circles); middle, "
               "the relative spread of the impact speeds (0 on a family); bottom, N lambda_1, "
               "bounded because lambda_1 = 0. Sliding values of e are left out.")
    params = {"u": MOTION_CUT_U, "n_e": n, "steps": MOTION_STEPS, "transient": MOTION_TRANSIENT}
    return _result(s, fig, "motion_cut", f"<k> against e at u = {MOTION_CUT_U}", rows, params, caption)
