"""The compiled checker (structure/_check_kernel.py, issue 43 item 3, issue 44 item 5).

It must give the verdicts of the numpy checker it replaced (kept in
tests/_verify_numpy.py as the reference), check and step for check and step, on
genuine and tampered certificates and atlases and on trapping regions; verify a
long certificate in a bounded time; refuse work beyond its stated limit by
name; and certify_box must keep its decisions as codes that read as names.
"""

from __future__ import annotations

import dataclasses
import json
import time

import numpy as np
import pytest

import stairbounce as sb
from stairbounce.structure import verify as checker
from stairbounce.structure.certificate import STATUSES, Certificate, Decisions
from stairbounce.structure.reference import reference_certificate
from stairbounce.structure.verify import verify_codes
from stairbounce.structure.verify_trapping import verify_region

from . import _verify_numpy as numpy_checker

FIG7 = ((0.155, 0.2138), (0.6, 0.658))
# a box whose orbit of (1, 0) does not slide: no_slide_within at any max_iter (reliability round 4)
WITHIN = ((0.2995, 0.2995 + 3e-16), (0.4135, 0.4135 + 3e-16))


def _arrays(e0, e1, u0, u1, status, max_iter, itins):
    lengths = [len(k) for k in itins]
    return (np.asarray(e0, float), np.asarray(e1, float), np.asarray(u0, float), np.asarray(u1, float),
            np.asarray(status, np.int64), max_iter,
            np.concatenate([np.asarray(k, np.int64) for k in itins] + [np.zeros(0, np.int64)]),
            np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64))


def _both(arrays):
    fast = verify_codes(*arrays)
    slow = numpy_checker.verify_codes(*(a.copy() if isinstance(a, np.ndarray) else a for a in arrays))
    return fast, slow


@pytest.fixture(scope="module")
def claims():
    """Genuine certificates of the Fig. 7 window (the Arb reference; boxes of 1e-6 and
    1e-4, so that many are undecided at some step) and tampered ones: boxes widened,
    impact numbers changed, itineraries cut or lengthened, statuses swapped."""
    rng = np.random.default_rng(43)
    (ea, eb), (ua, ub) = FIG7
    certs = []
    for w in (1e-6, 1e-4, 3e-3):
        for _ in range(250):
            e, u = rng.uniform(ea, eb), rng.uniform(ua, ub)
            certs.append(reference_certificate((e, e + w), (u, u + w)))
    rows = [(c.e[0], c.e[1], c.u[0], c.u[1], STATUSES.index(c.status), list(c.itinerary)) for c in certs]
    tampered = []
    for e0, e1, u0, u1, st, it in rows[:500]:
        kind = rng.integers(5)
        it = list(it)
        if kind == 0:  # widened
            f = 10.0 ** rng.uniform(0, 3)
            tampered.append((e0, e0 + (e1 - e0) * f, u0, u0 + (u1 - u0) * f, st, it))
        elif kind == 1 and it:  # one impact number changed
            j = rng.integers(len(it))
            it[j] = max(it[j] + int(rng.choice([-1, 1, 2])), 0) if it[j] >= 0 else 1
            tampered.append((e0, e1, u0, u1, st, it))
        elif kind == 2 and len(it) > 1:  # the slide moved earlier, or a fly-over added in front
            tampered.append((e0, e1, u0, u1, st, [0] + it))
        elif kind == 3:  # another status
            tampered.append((e0, e1, u0, u1, int(rng.integers(4)), it))
        else:  # moved to another place of the window
            de, du = rng.uniform(-0.02, 0.02, 2)
            tampered.append((e0 + de, e1 + de, u0 + du, u1 + du, st, it))
    return rows + tampered


def test_the_compiled_checker_gives_the_numpy_checker_s_verdicts(claims):
    e0, e1, u0, u1, st, it = zip(*claims)
    (code, step), (code0, step0) = _both(_arrays(e0, e1, u0, u1, st, 1000, it))
    # the set is worth comparing: accepted claims and every failing check of the dynamics
    found = set(np.unique(code).tolist())
    assert {0, checker._SLIDE, checker._IMPACT, checker._NOIMPACT, checker._COR} <= found
    assert 0.2 < (code == 0).mean() < 0.9
    np.testing.assert_array_equal(code, code0)
    np.testing.assert_array_equal(step, step0)


def test_the_two_checkers_agree_on_an_atlas_and_its_tampered_copy():
    atlas = sb.certify(e=FIG7[0], u=FIG7[1], depth=7)
    b = atlas.boxes
    arrays = _arrays(b["e0"].values, b["e1"].values, b["u0"].values, b["u1"].values, b["status"].values,
                     atlas.max_iter, [])
    itin, off = np.asarray(b["itinerary"].values, np.int64), np.asarray(b["offsets"].values, np.int64)
    arrays = arrays[:6] + (itin, off)
    (code, step), (code0, step0) = _both(arrays)
    assert (code == 0).all()
    np.testing.assert_array_equal(step, step0)
    # tampered: every 7th box's u range moved up by a third of the window, every 11th
    # box's first step made a fly-over
    rng = np.random.default_rng(1)
    u0, u1 = arrays[2].copy(), arrays[3].copy()
    u0[::7] += 0.02
    u1[::7] += 0.02
    itin = itin.copy()
    long = np.flatnonzero(np.diff(off) > 1)
    pick = rng.choice(long, size=len(long) // 11, replace=False)
    itin[off[pick]] = np.where(itin[off[pick]] == 0, 1, 0)
    tampered = arrays[:2] + (u0, u1) + arrays[4:6] + (itin, off)
    (code, step), (code0, step0) = _both(tampered)
    assert 0 < (code != 0).sum() < len(code)
    np.testing.assert_array_equal(code, code0)
    np.testing.assert_array_equal(step, step0)


def test_a_long_certificate_is_verified_quickly_and_its_tampering_found_at_its_step():
    n = 100_000
    c = sb.certify_box(*WITHIN, max_iter=n)
    assert c.status == "no_slide_within" and len(c.itinerary) == n
    t = time.perf_counter()
    assert sb.verify(c)
    assert time.perf_counter() - t < 2.0  # the numpy checker: 10.9 s for 1e5 steps (reliability round 4)
    it = list(c.itinerary)
    j = 77_777
    it[j] = it[j] + 1
    bad = sb.verify(dataclasses.replace(c, itinerary=tuple(it)))
    assert not bad and bad.step == j + 1 and bad.check in ("impact", "no impact")
    # the numpy reference on a shorter piece: the same check at the same step
    m = 3000
    it = list(c.itinerary[:m])
    it[2500] += 1
    a = _arrays([c.e[0]], [c.e[1]], [c.u[0]], [c.u[1]], [2], m, [it])
    (code, step), (code0, step0) = _both(a)
    assert code[0] != 0 and (code[0], step[0]) == (code0[0], step0[0]) == (code[0], 2501)


@pytest.fixture(scope="module")
def region():
    r = sb.trapping_region((0.299, 0.30), (0.413, 0.414))
    assert r is not None
    return r


def test_trapping_regions_get_the_numpy_checker_s_verdicts(region):
    (e0, e1), (u0, u1) = region.e, region.u
    it, grid, cells = region.itinerary, region.grid, np.asarray(region.cells)
    rng = np.random.default_rng(3)
    cases = [((e0, e1, u0, u1), it, grid, cells)]
    for c in rng.choice(len(cells), size=12, replace=False):  # a cell less
        cases.append(((e0, e1, u0, u1), it, grid, np.delete(cells, c)))
    for f in (1.001, 1.05, 1.5, 3.0):  # wider boxes
        cases.append(((e0, e0 + (e1 - e0) * f, u0, u1), it, grid, cells))
        cases.append(((e0, e1, u1 - (u1 - u0) * f, u1), it, grid, cells))
    cases.append(((0.1, 0.101, 0.3, 0.301), it, grid, cells))  # a sliding box
    v_lo, v_hi, nv, s_lo, s_hi, ns = grid
    cases.append(((e0, e1, u0, u1), it, (v_lo + 0.01, v_hi + 0.01, nv, s_lo, s_hi, ns), cells))  # shifted grid
    cases.append(((e0, e1, u0, u1), list(it)[:-1], grid, cells))  # another entry
    verdicts = []
    for (a, b, c, d), i, g, cl in cases:
        new = verify_region(a, b, c, d, 1000, i, g, cl)
        assert new == numpy_checker.verify_region(a, b, c, d, 1000, i, g, cl)
        verdicts.append(new)
    assert verdicts[0] == "ok" and {"invariant", "slide"} & set(verdicts) and verdicts.count("ok") < len(cases)


def test_the_coverage_rule_gives_the_prefix_sum_s_answers():
    """``_check_kernel.covered`` reads a region by its sorted cells and their row
    runs (memory and time of the region's cells, not of the grid rectangle
    holding them); its answers are the numpy checker's prefix sum over the whole
    grid: on rings, scattered cells and holes, with runs ending at a row's last
    column (the next cell index is the next row's first), rectangles at and
    beyond the grid's edges, one cell wide, empty and NaN."""
    from stairbounce.structure._check_kernel import covered, edges, runs

    rng = np.random.default_rng(44)
    answers = []
    for trial in range(60):
        nv, ns = int(rng.integers(1, 40)), int(rng.integers(1, 40))
        ev, es = edges(-1.0, 2.0, nv), edges(0.5, 3.0, ns)
        jj, ii = np.mgrid[0:ns, 0:nv]
        kind = trial % 3
        if kind == 0:  # a ring: a rectangle less a smaller one
            flags = ((ii >= nv // 5) & (ii <= nv - 1) & (jj >= ns // 6)
                     & ~((ii > nv // 2) & (ii < nv - 2) & (jj > ns // 3) & (jj < ns - 3)))
        elif kind == 1:  # dense with holes
            flags = rng.random((ns, nv)) < 0.93
        else:  # scattered
            flags = rng.random((ns, nv)) < 0.3
        cells = np.flatnonzero(flags.ravel()).astype(np.int64)
        if not cells.size:
            continue
        cells = np.concatenate([cells, cells[: cells.size // 4]])  # repeats change nothing
        rng.shuffle(cells)
        s, last = runs(cells, nv)
        a, b = rng.uniform(-1.4, 2.4, 400), rng.uniform(0.2, 3.3, 400)
        w, h = rng.exponential(0.3, 400), rng.exponential(0.3, 400)
        a0, a1, b0, b1 = a, a + w, b, b + h
        # on the edges, one cell, empty and NaN rectangles
        k = rng.integers(0, nv, 40)
        m = rng.integers(0, ns, 40)
        a0 = np.concatenate([a0, ev[k], ev[k], [ev[0], ev[0], np.nan, 0.5]])
        a1 = np.concatenate([a1, ev[k + 1], ev[k], [ev[-1], ev[0] - 1e-12, 0.6, np.nan]])
        b0 = np.concatenate([b0, es[m], es[m], [es[0], es[0], 1.0, 1.0]])
        b1 = np.concatenate([b1, es[m + 1], es[m], [es[-1], es[-1], 1.1, 1.1]])
        want = numpy_checker._covered(flags.ravel().astype(np.int64), ev, es, a0, a1, b0, b1)
        got = np.array([covered(s, last, ev, es, *r) for r in zip(a0, a1, b0, b1)])
        assert np.array_equal(got, want), (trial, np.flatnonzero(got != want)[:5])
        answers.append(want)
    answers = np.concatenate(answers)
    assert 0.05 < answers.mean() < 0.95  # both answers, many times


def test_work_beyond_the_limit_is_refused_by_name(monkeypatch, tmp_path):
    c = sb.certify_box(*WITHIN, max_iter=5000)
    monkeypatch.setattr(checker, "MAX_WORK", 4000)
    with pytest.raises(ValueError, match=r"5,000 itinerary entries.*limit of 4,000"):
        sb.verify(c)
    with pytest.raises(ValueError, match=r"limit of 4,000 \(stairbounce.structure.verify.MAX_WORK"):
        verify_codes([c.e[0]], [c.e[1]], [c.u[0]], [c.u[1]], [2], 5000, c.itinerary, [0, 5000])
    atlas = sb.certify(e=FIG7[0], u=FIG7[1], depth=5)
    path = tmp_path / "a.nc"
    atlas.save(path)
    steps = atlas.boxes.sizes[atlas.boxes["itinerary"].dims[0]]
    monkeypatch.setattr(checker, "MAX_WORK", steps)  # fewer than boxes + steps
    with pytest.raises(ValueError, match=rf"a.nc'.*{atlas.boxes.sizes['box']:,} boxes"):
        sb.verify(path)
    from stairbounce.cli import main

    with pytest.raises(SystemExit) as exit_:
        main(["certify", "--verify", str(path)])
    assert exit_.value.code == 2
    monkeypatch.setattr(checker, "MAX_WORK", 10**9)
    assert sb.verify(path) and sb.verify(c)


def test_certify_box_keeps_decisions_as_codes_read_as_names():
    c = sb.certify_box(e=(0.18, 0.1801), u=(0.62, 0.6201))
    assert isinstance(c.decisions, Decisions) and c.decisions.codes.dtype == np.int64
    names = list(c.decisions)
    assert len(names) == len(c.margins) and names[-1] == "slide" and c.decisions[-1] == "slide"
    assert names == ["slide" if k == 0 else f"impact {k}" for k in c.decisions.codes]
    assert c.decisions == tuple(names) and c.decisions != tuple(names[:-1])
    d = c.to_dict()
    assert "decisions" not in d and d["decision_codes"] == c.decisions.codes.tolist()
    back = Certificate.from_dict(json.loads(json.dumps(d)))
    assert back.decisions == c.decisions and isinstance(back.decisions, Decisions)
    # a certificate whose decisions are names (the reference's) keeps writing names
    r = reference_certificate(c.e, c.u)
    assert Certificate.from_dict(json.loads(json.dumps(r.to_dict()))).decisions == r.decisions
    with pytest.raises(ValueError, match="decision codes must be >= 0"):
        Decisions([0, -2])
    long = sb.certify_box(*WITHIN, max_iter=20_000)
    assert long.decisions.codes.size == len(long.decisions) > 3 * 20_000


def test_the_checker_s_outward_step_is_nextafter_float_for_float():
    """The checker's _up/_dn step the bits (libm's nextafter cost most of a 1000-step
    check): they must be np.nextafter towards +inf/-inf exactly, on zeros of both signs,
    subnormals, the largest floats, infinities, NaN and a spread of magnitudes."""
    from numba import njit

    from stairbounce.structure import _check_kernel as ck

    @njit
    def both(xs, up, dn):
        for i in range(xs.size):
            up[i] = ck._up(xs[i])
            dn[i] = ck._dn(xs[i])

    tiny, big = 5e-324, np.finfo(float).max
    special = [0.0, -0.0, tiny, -tiny, 2 * tiny, 2.2250738585072014e-308, -2.2250738585072014e-308,
               2.225073858507201e-308, 1.0, -1.0, 1.0 - 2**-53, big, -big, np.inf, -np.inf, np.nan, -np.nan]
    rng = np.random.default_rng(44)
    xs = np.concatenate([special, rng.standard_normal(20000) * 10.0 ** rng.integers(-310, 308, 20000)])
    up, dn = np.empty_like(xs), np.empty_like(xs)
    both(xs, up, dn)
    with np.errstate(over="ignore"):
        want_up, want_dn = np.nextafter(xs, np.inf), np.nextafter(xs, -np.inf)
    same = lambda a, b: (a.view(np.int64) == b.view(np.int64)) | (np.isnan(a) & np.isnan(b))  # noqa: E731
    assert same(up, want_up).all() and same(dn, want_dn).all()
    assert up[1] == tiny and dn[0] == -tiny and up[3] == 0.0 and np.signbit(up[3])  # -tiny steps up to -0
