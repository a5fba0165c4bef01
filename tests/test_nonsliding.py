"""stairbounce.nonsliding: <k>, Lyapunov exponents and the one-impact families (issue 13).

The references are independent of the kernels: finite differences of the
Poincare map, NumPy QR on maps with known exponents, an event-by-event
simulation in the plane (tests/naive.py, no Poincare map) and identities
derived in stairbounce/motion.py's docstring from the flow, the impact law and
the balance of energy and momentum.
"""

import math

import numba
import numpy as np
import pytest

from stairbounce import model
from stairbounce.nonsliding import (
    MOTION_FIELDS,
    _gram_schmidt,
    _log_norm,
    _product_exponents,
    _tangent_step,
    lyapunov_exponents,
    motion,
    motion_coords,
    motion_scan,
    one_impact_family,
    one_impact_state,
    k_mean_bound,
    speed_spread,
    step_jacobian,
)
from stairbounce.plane import pixel_centres

from . import naive


def _random_non_sliding_points(n, seed):
    """(e, u) above Cor. 2.1's curve, where no orbit slides."""
    rng = np.random.default_rng(seed)
    pts = []
    while len(pts) < n:
        e = rng.uniform(0.05, 0.95)
        u = rng.uniform(0.0, 1.5)
        if u > model.no_sliding_bound(e) * 1.05:
            pts.append((e, u))
    return pts


# --------------------------------------------------------------------------- #
# The Lyapunov algorithm on maps with known exponents                         #
# --------------------------------------------------------------------------- #

CAT = np.array([[2.0, 1.0], [1.0, 1.0]])
CAT_EXPONENT = math.log((3.0 + math.sqrt(5.0)) / 2.0)  # eigenvalues (3 +- sqrt 5)/2


@pytest.mark.parametrize("exponents", [lyapunov_exponents, _product_exponents])
def test_lyapunov_of_the_cat_map_is_log_of_its_eigenvalues(exponents):
    # Arnold's cat map: a constant Jacobian with eigenvalues (3 +- sqrt 5)/2
    l1, l2 = exponents(np.repeat(CAT[None], 400, axis=0))
    assert l1 == pytest.approx(CAT_EXPONENT, abs=1e-2)
    assert l2 == pytest.approx(-CAT_EXPONENT, abs=1e-2)
    assert l1 + l2 == pytest.approx(0.0, abs=1e-12)  # det = 1


@pytest.mark.parametrize("exponents", [lyapunov_exponents, _product_exponents])
def test_lyapunov_of_linear_maps_with_known_spectrum(exponents):
    # a non-normal triangular map (eigenvalues 3 and 0.25), a rotation scaled by
    # 0.7 (complex eigenvalues of modulus 0.7: both exponents log 0.7), and a
    # shear (both eigenvalues 1: exponents 0, converging like log(N)/N)
    c, s = math.cos(1.0), math.sin(1.0)
    cases = [
        (np.array([[3.0, 5.0], [0.0, 0.25]]), math.log(3.0), math.log(0.25), 1e-2),
        (0.7 * np.array([[c, -s], [s, c]]), math.log(0.7), math.log(0.7), 1e-9),
        (np.array([[1.0, 1.0], [0.0, 1.0]]), 0.0, 0.0, 2e-2),
    ]
    for J, e1, e2, tol in cases:
        l1, l2 = exponents(np.repeat(J[None], 2000, axis=0))
        assert l1 == pytest.approx(e1, abs=tol)
        assert l2 == pytest.approx(e2, abs=tol)


def test_lyapunov_of_a_random_product_matches_between_the_two_implementations():
    # the kernel's primitives (power-of-two rescaling, Gram-Schmidt) against NumPy QR
    rng = np.random.default_rng(3)
    Js = rng.normal(size=(3000, 2, 2))
    a = lyapunov_exponents(Js)
    b = _product_exponents(Js)
    assert b[0] == pytest.approx(a[0], abs=1e-10)
    assert b[1] == pytest.approx(a[1], abs=1e-10)


def test_rescaling_by_powers_of_two_keeps_the_log_norm():
    assert _log_norm(2.0**500, 0.0, 100) == pytest.approx(600 * math.log(2.0))
    qa, qb, r = _gram_schmidt(3.0, 4.0, 1.0, 0.0)
    assert r == pytest.approx(0.8) and qa * 3.0 + qb * 4.0 == pytest.approx(0.0, abs=1e-15)


# --------------------------------------------------------------------------- #
# The Jacobian of one step                                                     #
# --------------------------------------------------------------------------- #


def _random_states(n, seed):
    """Edge states and parameters; one in two with a slow ball and e near 1, where
    steps with many impacts (and the closed form past 8 of them) are common."""
    rng = np.random.default_rng(seed)
    for i in range(n):
        if i % 2:
            yield (rng.uniform(1.0, 6.0), rng.uniform(-4.0, 4.0), rng.uniform(0.02, 0.98),
                   rng.uniform(0.1, 2.0))
        else:
            yield (rng.uniform(1.0, 3.0), rng.uniform(-2.0, 2.0), rng.uniform(0.7, 0.97),
                   rng.uniform(0.02, 0.3))


def test_tangent_step_is_model_step_bit_for_bit():
    # the motion kernels iterate the same map as plane/orbits
    for y, v, e, u in _random_states(3000, 1):
        T, ratio = model._constants(e, u)
        assert _tangent_step(y, v, e, T, ratio)[:3] == model._step(y, v, e, T, ratio)


def test_step_jacobian_matches_finite_differences_on_non_grazing_states():
    # central differences of poincare_map; states whose impact number changes
    # within the stencil (grazing: the map is discontinuous there) are skipped
    checked = {0: 0, 1: 0, 2: 0, "3-7": 0, "closed form": 0}
    h = 1e-6
    for y, v, e, u in _random_states(4000, 2):
        J, k = step_jacobian(y, v, e, u)
        if k == model.SLIDING:
            assert not J.any()  # the image is the constant (1, 0)
            continue
        cols = []
        ok = True
        for dy, dv in ((h, 0.0), (0.0, h)):
            p = model.poincare_map(y + dy, v + dv, e, u)
            m = model.poincare_map(y - dy, v - dv, e, u)
            if p[2] != k or m[2] != k:
                ok = False
                break
            cols.append(((p[0] - m[0]) / (2 * h), (p[1] - m[1]) / (2 * h)))
        if not ok:
            continue
        fd = np.array(cols).T
        assert np.allclose(J, fd, rtol=1e-5, atol=1e-5 * max(1.0, np.abs(J).max())), (y, v, e, u, k)
        checked[k if k <= 2 else ("3-7" if k < 8 else "closed form")] += 1
    assert min(checked.values()) >= 50, checked  # every kind of step was exercised


def test_determinant_of_a_step_with_k_impacts_is_e_to_the_2k():
    # flights preserve area; each impact's saltation matrix has determinant e^2
    for y, v, e, u in _random_states(2000, 4):
        J, k = step_jacobian(y, v, e, u)
        if k == model.SLIDING:
            continue
        assert np.linalg.det(J) == pytest.approx(e ** (2 * k), rel=1e-8, abs=1e-300)


def test_tangent_map_carries_the_vertical_field_so_lambda_1_is_zero():
    # horizontal translation of a trajectory is a symmetry away from grazing:
    # J (v, -1) = (v', -1) (motion.py docstring), hence lambda_1 = 0 exactly
    n = 0
    for y, v, e, u in _random_states(2000, 6):
        J, k = step_jacobian(y, v, e, u)
        if k == model.SLIDING:
            continue
        yn, vn, _ = model.poincare_map(y, v, e, u)
        assert J @ np.array([v, -1.0]) == pytest.approx(np.array([vn, -1.0]), rel=1e-12, abs=1e-12)
        n += 1
    assert n > 1000


@pytest.mark.parametrize("e, u", _random_non_sliding_points(8, 7))
def test_lambda_1_is_the_growth_of_the_vertical_field(e, u):
    # after the transient the tangent vector is aligned with (v, -1) (the other
    # direction contracts like e^(2k)), so the finite-N estimate of lambda_1 is
    # log(|(v_N, -1)| / |(v_0, -1)|) / N, and it decays like 1/N
    N = 3000
    r = motion(e, u, steps=N, transient=2000)
    (_, v0), (_, vN) = r["state_start"], r["state_end"]
    # misalignment left after the transient: about exp(lambda_2 * transient)
    tol = 4.0 * math.exp(r["lyap2"] * 2000) / N + 1e-9
    assert r["lyap1"] == pytest.approx(0.5 * math.log((1 + vN * vN) / (1 + v0 * v0)) / N, abs=tol)
    assert abs(r["lyap1"]) * N < 10


def test_step_jacobian_of_a_flight_is_a_shear():
    J, k = step_jacobian(5.0, 3.0, 0.5, 2.0)  # t_1 = 3 + sqrt(19) > T = 0.5
    assert k == 0
    assert np.array_equal(J, [[1.0, 0.5], [0.0, 1.0]])


def test_grazing_is_a_jump_of_the_velocity():
    # y = 1, v = 0: the first impact is at t_1 = sqrt 2; with T = t_1 the ball
    # meets the floor exactly at the edge: P's velocity jumps from -sqrt 2
    # (just missing the floor) to e sqrt 2 (just hitting it), y' = 1 on both sides
    e = 0.5
    u = 1.0 / math.sqrt(2.0)
    below = model.poincare_map(1.0, 0.0, e, u * (1 + 1e-12))
    above = model.poincare_map(1.0, 0.0, e, u * (1 - 1e-12))
    assert below[2] == 0 and above[2] == 1
    assert below[0] == pytest.approx(1.0, abs=1e-9) and above[0] == pytest.approx(1.0, abs=1e-9)
    assert below[1] == pytest.approx(-math.sqrt(2.0), abs=1e-9)
    assert above[1] == pytest.approx(e * math.sqrt(2.0), abs=1e-9)


# --------------------------------------------------------------------------- #
# One point                                                                    #
# --------------------------------------------------------------------------- #


def test_motion_exponents_match_numpy_qr_on_the_product_of_step_jacobians():
    e, u, N = 0.6, 0.7, 1500
    r = motion(e, u, steps=N, transient=500)
    ys, vs, _ = model.iterate(1.0, 0.0, e, u, 500 + N)
    Js = [step_jacobian(ys[n], vs[n], e, u)[0] for n in range(500 + N)]
    # same start (first vector (1, 0)), NumPy QR over the whole orbit minus the
    # transient's logs: compare through the exponents of the kept part
    Q = np.eye(2)
    sums = np.zeros(2)
    for n, J in enumerate(Js):
        Q, R = np.linalg.qr(J @ Q)
        if n >= 500:
            sums += np.log(np.abs(np.diag(R)))
    assert r["lyap1"] == pytest.approx(sums[0] / N, abs=1e-9)
    assert r["lyap2"] == pytest.approx(sums[1] / N, abs=1e-9)


@pytest.mark.parametrize("e, u", _random_non_sliding_points(40, 5))
def test_identities_hold_on_long_orbits(e, u):
    # motion.py docstring: (1) lambda_1 + lambda_2 = 2 <k> log e;
    # (2) energy: dissipation = 1 + (E_0 - E_N)/N with E = v^2/2 + y;
    # (3) momentum/time: impulse = T + (v_N - v_0)/N
    N = 2000
    r = motion(e, u, steps=N, transient=500)
    assert not r["slides"]
    (y0, v0), (yN, vN) = r["state_start"], r["state_end"]
    assert r["lyap1"] + r["lyap2"] == pytest.approx(2 * r["k_mean"] * math.log(e), abs=1e-9)
    assert r["lyap2"] == pytest.approx(r["lyap2_identity"], abs=1e-9)
    E0, EN = 0.5 * v0 * v0 + y0, 0.5 * vN * vN + yN
    assert r["dissipation"] == pytest.approx(1.0 + (E0 - EN) / N, abs=1e-10)
    assert r["impulse"] == pytest.approx(1.0 / u + (vN - v0) / N, rel=1e-10)
    # and the consequences for the averages themselves
    assert r["k_mean"] * r["jump_mean"] >= 1.0 - 1e-12  # impacts per landing >= 1
    assert r["lyap1"] >= r["lyap2"]


def test_motion_k_mean_agrees_with_an_event_by_event_simulation():
    # tests/naive.impacts_in_window: impact to impact in the plane, no Poincare map
    N, tr = 2000, 1000
    for e, u in [(0.5, 0.8), (0.3, 1.2), (0.9, 0.3), (0.7, 0.5), (0.2, 1.4), (0.95, 0.9),
                 (0.45, 0.33), (0.8, 1.1)]:
        r = motion(e, u, steps=N, transient=tr)
        c = naive.impacts_in_window(e, u, 1.0, 0.0, tr, tr + N)
        assert c is not None and not r["slides"]
        assert abs(c / N - r["k_mean"]) <= max(r["k_err"], 1.0 / N), (e, u)


def test_motion_reports_sliding_with_the_step():
    # (e, u) = (0.1, 0.2): in the first (n, 0^inf) tongue of Theorem 3.1, the
    # orbit of (1, 0) slides on its first step
    r = motion(0.1, 0.2)
    assert r["slides"] and r["slide_step"] == 1
    assert math.isnan(r["k_mean"]) and r["lyap1"] == -math.inf
    ks = naive.orbit_until_slide(1.0, 0.0, 0.3, 0.45, 100)
    r = motion(0.3, 0.45, steps=50, transient=50)
    assert r["slide_step"] == (len(ks) if ks is not None else 0)


@pytest.mark.parametrize("kwargs, word", [
    (dict(e=1.0, u=1.0), r"e \(restitution"),
    (dict(e=0.5, u=0.0), r"u \(horizontal"),
    (dict(e=0.5, u=1.0, steps=1), "steps"),
    (dict(e=0.5, u=1.0, transient=-1), "transient"),
    (dict(e=0.5, u=1.0, y0=-1.0), "y0"),
])
def test_motion_rejects_bad_input_naming_the_parameter(kwargs, word):
    with pytest.raises(ValueError, match=word):
        motion(**kwargs)


# --------------------------------------------------------------------------- #
# One impact every n steps                                                     #
# --------------------------------------------------------------------------- #

FAMILIES = [(n, e) for n in (1, 2, 3, 5) for e in (0.15, 0.5, 0.85)]


@pytest.mark.parametrize("n, e", FAMILIES)
def test_one_impact_family_is_a_fixed_point_of_the_nth_iterate(n, e):
    # the closed form of one_impact_family checked against the map: P^n brings
    # the state back with exactly one impact, for several phases of the impact
    for phase in (0.1, 0.5, 0.9):
        u, y, v = one_impact_state(n, e, phase)
        assert u == one_impact_family(n, e)
        ys, vs, ks = model.iterate(y, v, e, u, n)
        assert list(ks[1:]) == [0] * (n - 1) + [1]
        assert ys[-1] == pytest.approx(y, abs=1e-12) and vs[-1] == pytest.approx(v, abs=1e-12)


@pytest.mark.parametrize("n, e", FAMILIES)
def test_k_mean_is_one_over_n_on_the_families(n, e):
    N = 600 * n
    u, y, v = one_impact_state(n, e)
    r = motion(e, u, steps=N, transient=0, y0=y, v0=v)
    assert r["k_mean"] == 1.0 / n and r["jump_mean"] == n
    # eigenvalues of P^n: 1 along the family, e^2 across it
    assert abs(r["lyap1"]) < 5.0 / N
    assert r["lyap2"] == pytest.approx(2.0 * math.log(e) / n, abs=5.0 / N)
    # the orbit of the paper's (1, 0) is attracted to the family
    r = motion(e, u, steps=N, transient=3000)
    assert r["k_mean"] == 1.0 / n


def test_k_mean_varies_continuously_near_the_families():
    # off the curve the impact point drifts: <k> - 1/n changes sign across the
    # curve and shrinks with the distance (linearly, as measured)
    N = 6000
    for n, e in [(1, 0.5), (2, 0.3), (3, 0.6)]:
        un = one_impact_family(n, e)
        for d in (1e-3, 1e-2, 3e-2):
            lo = motion(e, un * (1 - d), steps=N, transient=3000)["k_mean"] - 1.0 / n
            hi = motion(e, un * (1 + d), steps=N, transient=3000)["k_mean"] - 1.0 / n
            assert 0.0 < lo <= 4.0 * d + 2.0 / N
            assert -4.0 * d - 2.0 / N <= hi < 0.0


def test_families_lie_above_the_tongues_and_reject_bad_input():
    e = np.linspace(0.05, 0.95, 19)
    for n in (1, 2, 7):
        edge = np.array([model.tongue(n, x)[1] for x in e])  # Theorem 3.1's upper edge
        assert np.all(one_impact_family(n, e) > edge)
    with pytest.raises(ValueError, match="n must"):
        one_impact_family(0, 0.5)
    with pytest.raises(ValueError, match="e \\(restitution"):
        one_impact_family(1, 1.0)
    with pytest.raises(ValueError, match="phase"):
        one_impact_state(1, 0.5, 1.5)


# --------------------------------------------------------------------------- #
# The scan                                                                     #
# --------------------------------------------------------------------------- #

GRID = dict(e=(0.0, 1.0, 37), u=(0.0, 1.5, 23), steps=300, transient=200)


@pytest.fixture(scope="module")
def grid_scan():
    return motion_scan(**GRID)


def _same(a, b):
    return all(np.array_equal(a[v].values, b[v].values, equal_nan=True) for v in MOTION_FIELDS)


def test_scan_fast_and_plain_kernels_agree_bit_for_bit(grid_scan):
    assert _same(grid_scan, motion_scan(**GRID, kernel="plain"))


def test_scan_pixels_are_motion_of_that_point(grid_scan):
    ds = grid_scan
    for i in range(0, ds.sizes["u"], 4):
        for j in range(0, ds.sizes["e"], 5):
            e, u = float(ds.e[j]), float(ds.u[i])
            r = dict(motion(e, u, steps=GRID["steps"], transient=GRID["transient"]))
            r["lyap2"] = r["lyap2_identity"]
            for f in MOTION_FIELDS:
                a, b = float(ds[f].values[i, j]), float(r[f])
                assert a == b or (math.isnan(a) and math.isnan(b)), (f, e, u, a, b)


def test_scan_is_the_same_in_tiles_and_on_one_thread(grid_scan):
    es = pixel_centres(*GRID["e"])
    us = pixel_centres(*GRID["u"])
    kw = dict(steps=GRID["steps"], transient=GRID["transient"])
    tile = motion_coords(es[5:30], us[3:17], **kw)
    assert _same(tile, grid_scan.isel(e=slice(5, 30), u=slice(3, 17)))
    threads = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = motion_scan(**GRID)
    finally:
        numba.set_num_threads(threads)
    assert _same(one, grid_scan)


def test_scan_fields_are_consistent(grid_scan):
    ds = grid_scan
    slid = ds.slide_step.values > 0
    assert np.all(np.isnan(ds.k_mean.values[slid])) and np.all(ds.lyap1.values[slid] == -np.inf)
    ok = ~slid
    assert ok.sum() > 0.6 * ok.size  # most of the paper's plane does not slide
    assert np.all(ds.k_mean.values[ok] >= 0)
    # above Cor. 2.1's curve nothing slides
    E, U = np.meshgrid(ds.e.values, ds.u.values)
    above = U > (1 - E) / (2 * np.sqrt(2 * E))
    assert not slid[above].any()
    # lambda_2 is the determinant identity's
    k, l1, l2 = ds.k_mean.values[ok], ds.lyap1.values[ok], ds.lyap2.values[ok]
    assert np.allclose(l1 + l2, 2 * k * np.log(E[ok]), atol=1e-12)


def test_scan_progress_and_bad_input():
    calls = []
    ds = motion_scan((0.2, 0.8, 5), (0.5, 1.0, 4), 10, 10, progress=lambda d, t: calls.append((d, t)))
    assert calls[0] == (0, 4) and calls[-1] == (4, 4)
    assert _same(ds, motion_scan((0.2, 0.8, 5), (0.5, 1.0, 4), 10, 10))
    with pytest.raises(ValueError, match="e window"):
        motion_scan((0.0, 1.5, 5))
    with pytest.raises(ValueError, match="kernel"):
        motion_coords([0.5], [1.0], kernel="slow")


def test_k_mean_obeys_the_cauchy_schwarz_bound_exactly(grid_scan):
    # motion.py docstring: <k> >= impulse^2 (1-e) / (2 (1+e) dissipation) for
    # every finite orbit (the two balances and Cauchy-Schwarz on impact speeds)
    ds = grid_scan
    ok = ds.slide_step.values == 0
    E = np.broadcast_to(ds.e.values[None, :], ok.shape)[ok]
    k, P, D = ds.k_mean.values[ok], ds.impulse.values[ok], ds.dissipation.values[ok]
    assert np.all(k >= P * P * (1 - E) / (2 * (1 + E) * D) * (1 - 1e-12))
    for e, u in _random_non_sliding_points(10, 8):
        r = motion(e, u, steps=4000, transient=4000)
        assert r["k_mean"] >= r["impulse"] ** 2 * (1 - e) / (2 * (1 + e) * r["dissipation"]) * (1 - 1e-12)


@pytest.mark.parametrize("n, e", FAMILIES)
def test_k_mean_bound_is_attained_on_the_families(n, e):
    assert k_mean_bound(e, one_impact_family(n, e)) == pytest.approx(1.0 / n, rel=1e-14)


def test_speed_spread_is_the_relative_variance_of_the_impact_speeds():
    # counted directly from an impact-by-impact replay of the kept steps
    for e, u in [(0.5, 0.8), (0.3, 1.2), (0.8, 0.4)]:
        N, tr = 1500, 1000
        r = motion(e, u, steps=N, transient=tr)
        ys, vs, _ = model.iterate(1.0, 0.0, e, u, tr + N)
        speeds = []
        for n in range(tr, tr + N):
            s = math.sqrt(vs[n] ** 2 + 2 * ys[n])
            k = naive.step(ys[n], vs[n], e, u)[2]
            speeds += [s * e**j for j in range(k)]
        speeds = np.array(speeds)
        assert len(speeds) == round(r["k_mean"] * N)
        assert r["speed_spread"] == pytest.approx(speeds.var() / speeds.mean() ** 2, rel=1e-6, abs=1e-12)
    u, y, v = one_impact_state(2, 0.4)
    assert abs(motion(0.4, u, steps=600, transient=0, y0=y, v0=v)["speed_spread"]) < 1e-12
    assert math.isnan(speed_spread(math.nan, 1.0, 1.0, 0.5))


def test_motion_figures_answer_chaotic_or_just_complicated(tmp_path):
    # the report row of issue 13, on a coarse grid: lambda_1 compatible with 0
    # (|lambda_1| <= halves' difference + 5/N) on more than 99% of the pixels
    from stairbounce import figures as F

    res = F.make_figures(F.Settings(out=tmp_path, dpi=40, scale=0.1), only=["motion_lyap", "motion_cut"])
    assert [r.error for r in res] == [None, None]
    row = res[0].rows[0]
    # a claim of ours (issue 24): the paper column quotes only the paper
    assert row.quantity.startswith("ours: chaotic or just complicated?") and row.paper == "-"
    assert row.verdict == "not comparable" and "; holds (" in row.measured
    # the picture is the convergence diagnostic N lambda_1 against N, not a map of lambda_1
    assert res[0].params["lengths"] == list(F.motion.LYAP_LENGTHS)
    nl = F.motion._lyap_convergence([0.5], [1.0])
    assert nl.shape == (1, len(F.motion.LYAP_LENGTHS)) and np.abs(nl).max() <= 4 * F.motion.ZERO_EFOLDS
    assert (tmp_path / "motion_lyap.png").exists() and (tmp_path / "motion_cut.png").exists()


def test_motion_k_masks_unconverged_pixels(tmp_path):
    # issue 24: pixels still gaining energy after the transient get their own colour and key entry
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from stairbounce import figures as F
    from stairbounce.plot.motion import UNCONVERGED_COLOUR, plot_motion

    ds = motion_scan(e=(0.5, 0.999, 16), u=(0.5, 1.0, 8), steps=1000, transient=1000)
    mask = F.motion._unconverged(ds)
    assert mask.any() and not mask.all()
    fig, ax = plt.subplots()
    plot_motion(ds, field="k_mean", ax=ax, unconverged=mask)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any(t.startswith("unconverged") for t in labels)
    shown = ax.images[-2].get_array()  # the values: masked where unconverged
    assert np.ma.getmaskarray(shown)[mask].all()
    assert matplotlib.colors.to_hex(ax.images[-1].cmap(0.5)) == UNCONVERGED_COLOUR
    plt.close(fig)


def test_the_guide_page_examples_run():
    # docs/guide/motion.md's doctest fences, outside Sphinx
    import doctest
    import re
    from pathlib import Path

    text = (Path(__file__).parents[1] / "docs" / "guide" / "motion.md").read_text()
    blocks = re.findall(r"```\{doctest\}\n(.*?)```", text, re.S)
    assert len(blocks) >= 4
    for b in blocks:
        test = doctest.DocTestParser().get_doctest(b, {}, "motion.md", "motion.md", 0)
        runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
        runner.run(test)
        assert runner.failures == 0


def test_motion_scan_refuses_what_does_not_fit_in_memory():
    with pytest.raises(ValueError, match="reduce the size or scan tiles"):
        motion_scan((0.0, 1.0, 10**6), (0.0, 1.5, 10**6))


def test_motion_scan_round_trips_through_zarr_and_netcdf(grid_scan, tmp_path):
    # plane.save / plane.load write any dataset atomically; tiles of a motion
    # scan can go to a store the same way
    from stairbounce.plane import load, save

    for name in ("m.zarr", "m.nc"):
        save(grid_scan, tmp_path / name)
        assert _same(load(tmp_path / name), grid_scan)


@pytest.mark.parametrize("transient, steps", [(0, 3), (7, 101), (150, 2)])
def test_fast_and_plain_agree_on_random_coordinates_with_many_impacts(transient, steps):
    # e near 1 and small u: steps with many impacts (the closed form past 8),
    # grazing-prone slow balls, odd lengths and no transient
    rng = np.random.default_rng(transient + steps)
    es = np.concatenate([rng.uniform(0.9, 0.999, 40), rng.uniform(0.0, 1.0, 40)])
    us = np.concatenate([rng.uniform(0.01, 0.1, 20), rng.uniform(0.05, 3.0, 20)])
    a = motion_coords(es, us, steps=steps, transient=transient)
    b = motion_coords(es, us, steps=steps, transient=transient, kernel="plain")
    assert _same(a, b)
    for i, j in [(0, 0), (5, 3), (25, 60), (39, 79)]:
        r = motion(es[j], us[i], steps=steps, transient=transient)
        assert float(a.k_mean.values[i, j]) == r["k_mean"] or r["slides"]
