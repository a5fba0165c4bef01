"""The report's cascade rows (issue 39, item 6): the laws found between tongues 1
and 2 at e = 0.02, claims of ours with a verdict that fails when the law does;
the members marked on the orbit diagrams of Figs. 8 and 9."""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import numpy as np
import pytest

import stairbounce as sb
from stairbounce import figures as F

C = sys.modules["stairbounce.cascades"]  # the module (sb.cascades is its function)


def _settings(tmp_path):
    return F.Settings(out=Path(tmp_path), scale=0.05)


@pytest.fixture(scope="module")
def rows(tmp_path_factory):
    return F.orbits._cascade_rows(_settings(tmp_path_factory.mktemp("cascade_rows")))


def test_rows_are_ours_numerical_with_verdict_and_criterion(rows):
    assert len(rows) == 3
    for row in rows:
        assert row.quantity.startswith("ours: ") and row.paper == "-"
        assert row.verdict == "agrees", row
        assert row.basis == "numerical" and "float decisions" in row.basis_text()
        assert row.why.startswith("a claim of ours, passes: ")
    widths, accumulation, nested = rows
    assert "3 times smaller" in widths.why and "k = 5..12" in widths.why
    assert "contains u*" in accumulation.why and "within 0.1 of 1" in accumulation.why
    assert "lies in the enclosure" in nested.why


def test_rows_state_the_computed_numbers(rows):
    """Recomputed independently: the cascade's own law on k = 5..12 (sb.cascade's
    law_k), the neutral family from sb.one_impact_family."""
    widths, accumulation, nested = rows
    c = sb.cascade("(1^k, 0^inf)", e=0.02, u=(0.6, 0.75), law_k=(5, 12))
    assert f"members k = 1..{c.last} located exactly" in widths.measured
    assert f"algebraic, exponent {c.law.exponent:.3g} in [{c.law.exponent_interval[0]:.3g}, " in widths.measured
    u1 = sb.one_impact_family(1, 0.02)
    assert f"u* = {u1:.10g}" in accumulation.measured
    lo, hi, n = c.limit_enclosure
    assert lo <= u1 <= hi and f"enclosure [{lo:.9g}, {hi:.9g}] (first {n} steps" in accumulation.measured
    assert f"exponent {c.law.approach:.3g}" in accumulation.measured  # the right edges face u*
    d = sb.cascade("((1, 0)^k, 1, 1, 0^inf)", e=0.02, u=(0.6, 0.75), k_max=F.orbits.CASCADE_K_MAX)
    assert f"exponent {d.law.exponent:.4g}" in nested.measured and "k = 93..100" in nested.measured
    assert f"{d.law.limit:.9g}" in nested.measured


def _wrong_law(monkeypatch, **changes):
    real = C.cascade_law

    def wrong(*args, **kwargs):
        return dataclasses.replace(real(*args, **kwargs), **changes)

    monkeypatch.setattr(C, "cascade_law", wrong)


def test_a_wrong_law_makes_the_rows_differ(tmp_path, monkeypatch):
    _wrong_law(monkeypatch, kind="geometric")
    widths, _, nested = F.orbits._cascade_rows(_settings(tmp_path))
    for row in (widths, nested):
        assert row.verdict == "differs" and "FAILS" in row.why, row
        assert "geometric, exponent" in row.measured


def test_an_approach_not_like_1_over_k_differs(tmp_path, monkeypatch):
    _wrong_law(monkeypatch, approach_interval=(1.5, 1.7))
    widths, accumulation, _ = F.orbits._cascade_rows(_settings(tmp_path))
    assert widths.verdict == "agrees"
    assert accumulation.verdict == "differs" and "[1.5, 1.7]" in accumulation.measured


def test_an_accumulation_off_the_closed_form_differs(tmp_path, monkeypatch):
    """The enclosure moved off u* (and off the extrapolated limit): both
    accumulation rows fail their criterion."""
    real = C.cascade

    def shifted(*args, **kwargs):
        c = real(*args, **kwargs)
        lo, hi, n = c.limit_enclosure
        return dataclasses.replace(c, limit_enclosure=(lo + 0.01, hi + 0.01, n))

    monkeypatch.setattr(C, "cascade", shifted)
    _, accumulation, nested = F.orbits._cascade_rows(_settings(tmp_path))
    assert accumulation.verdict == nested.verdict == "differs"


def test_members_are_marked_on_their_branches(tmp_path):
    """Each tick sits at a member's centre, at heights that the orbit diagram's
    column there holds (the diagram, from (0.1, 0) after 2000 steps, is on
    the member's periodic orbit)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from stairbounce.plot import plot_orbit_diagram

    e, window = 0.1, (0.58, 0.64)
    od = sb.orbit_diagram(e, np.linspace(*window, 121), y0=0.1, v0=0.0, transient=2000, keep=50)
    fig, ax = plt.subplots()
    plot_orbit_diagram(od, ax=ax, colorbar=False)
    view = (ax.get_xlim(), ax.get_ylim())
    (c,) = F.orbits._cascade_marks(_settings(tmp_path), ax, e, window, [("(1^k, 0^inf)", (2, 5))], first=2)
    assert (ax.get_xlim(), ax.get_ylim()) == view  # the marks never move the view
    members = c.members[c.members.k.between(2, 5)]
    assert list(members.k) == [2, 3, 4, 5]
    (ticks,) = [ln for ln in ax.lines if ln.get_marker() == "|"]  # one line per cascade
    x, y = np.asarray(ticks.get_xdata()), np.asarray(ticks.get_ydata())
    # the diagram's own columns at the members' centres hold the ticks' heights
    at = sb.orbit_diagram(e, 0.5 * (members.lo.values + members.hi.values), y0=0.1, v0=0.0,
                          transient=2000, keep=50)
    assert len(x) == members.period.sum()  # one tick per branch
    for m, col in zip(members.itertuples(), at.y.values):
        mine = y[x == 0.5 * (m.lo + m.hi)]
        assert len(mine) == m.period
        assert np.allclose(np.sort(mine), np.unique(np.round(col, 9)), atol=1e-8), m.k
    bands = [p for p in ax.collections if len(p.get_paths()) == 4]
    assert len(bands) == 1  # one band per member, in one collection
    for path, m in zip(bands[0].get_paths(), members.itertuples()):
        assert path.vertices[:, 0].min() == pytest.approx(m.lo, abs=1e-15)
        assert path.vertices[:, 0].max() == pytest.approx(m.hi, abs=1e-15)
    labels = [t.get_text() for t in ax.texts]
    assert labels == ["k=2", "k=3"]
    legend = [a for a in ax.artists if a.get_title().get_text() == "cascade members (sb.cascade)"]
    assert len(legend) == 1 and "k = 2..5 (4 members, exact)" in legend[0].get_texts()[0].get_text()
    assert "0^{\\infty}" in legend[0].get_texts()[0].get_text()
    plt.close(fig)


def test_the_renderers_refuse_what_is_not_a_cascade_and_draw_the_law():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from stairbounce.plot import plot_cascade_law, plot_cascade_members

    with pytest.raises(ValueError, match="Cascade objects"):
        plot_cascade_members([object()])
    c = sb.cascade("(1^k, 0^inf)", e=0.02, u=(0.6, 0.75), law_k=(5, 12))
    with pytest.raises(ValueError, match="one mapping per cascade"):
        plot_cascade_members(c, heights=[{}, {}])
    ax = plot_cascade_law(c)
    assert ax.get_title().endswith("algebraic on k = 5..12")
    points, alg, geo = ax.lines
    assert list(points.get_xdata()) == list(range(2, 26))  # k = 1 is cut by the range
    # the algebraic line is the fitted power law: its slope on log axes is -gamma (the straight
    # line's, exponent_fit, whose residual decides the law; not the asymptotic extrapolation)
    x, y = alg.get_xdata(), alg.get_ydata()
    slope = np.log(y[-1] / y[0]) / np.log(x[-1] / x[0])
    assert slope == pytest.approx(-c.law.exponent_fit)
    assert x[0] == 5 and x[-1] == 12
    plt.close("all")
