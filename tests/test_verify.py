"""The reference certifier (Arb balls) and the independent checker (numpy intervals), issue 36.

The reference is checked against Theorem 3.1 (an analytic theorem), Corollary 2.1
and the float package at points inside its proven boxes; the checker against the
reference (on genuine and tampered certificates) and against a third, pure-Python
implementation on mpmath's ``iv`` intervals written here from the paper's
formulas as printed (Prop. 2.3 on ``(y, v)``, eq. (2.2) in closed form).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import xarray as xr

import stairbounce as sb
from stairbounce.structure.certificate import STATUSES, Certificate
from stairbounce.structure.reference import reference_certificate
from stairbounce.structure.verdict import read_atlas_arrays, verify, verify_file
from stairbounce.structure.verify import CHECKS, verify_arrays, verify_codes

FIG5E = ((0.04, 0.065), (0.92, 0.945))
FIG7 = ((0.155, 0.2138), (0.6, 0.658))
WIDTH = 1e-6


def _box_at(e, u, w=WIDTH):
    return (e, e + w), (u, u + w)


def _random_certificates(window, n, seed, w=WIDTH):
    rng = np.random.default_rng(seed)
    (ea, eb), (ua, ub) = window
    return [reference_certificate(*_box_at(rng.uniform(ea, eb), rng.uniform(ua, ub), w)) for _ in range(n)]


def _arrays(certs):
    """The array form of structure/certificate.py built from certificates."""
    lengths = [len(c.itinerary) for c in certs]
    itin = np.concatenate([np.asarray(c.itinerary, dtype=np.int64) for c in certs] + [np.zeros(0, np.int64)])
    return dict(
        e0=np.array([c.e[0] for c in certs]), e1=np.array([c.e[1] for c in certs]),
        u0=np.array([c.u[0] for c in certs]), u1=np.array([c.u[1] for c in certs]),
        status=np.array([STATUSES.index(c.status) for c in certs], dtype=np.int8),
        max_iter=certs[0].max_iter, itinerary=itin,
        offsets=np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64),
    )


def _accepted(arrays):
    return verify_arrays(**arrays)


def _atlas_dataset(certs, strings=False, words=False):
    """An atlas as the other half of issue 36 stores it: dimension ``box``, the
    ragged itinerary on its own dimension, max_iter as an attribute."""
    a = _arrays(certs)
    status = np.array([c.status for c in certs]) if strings else a["status"]
    data = {name: ("box", a[name]) for name in ("e0", "e1", "u0", "u1")}
    data["status"] = ("box", status)
    data["itinerary"] = ("step", a["itinerary"])
    data["offsets"] = ("box_edge", a["offsets"])
    if words:
        data["word"] = ("box", np.array([c.word.format(ascii=True) if c.word else "" for c in certs]))
    return xr.Dataset(data, attrs={"max_iter": a["max_iter"]})


@pytest.fixture(scope="module")
def fig7():
    return _random_certificates(FIG7, 2500, seed=7)


@pytest.fixture(scope="module")
def fig5e():
    return _random_certificates(FIG5E, 500, seed=5)


# ---------------------------------------------------------------- the reference


@pytest.mark.parametrize("n", range(1, 7))
def test_a_box_well_inside_a_tongue_is_proven_with_its_word(n):
    # Theorem 3.1: (n, 0^inf) iff (n-1)/2 < u^2 <= n/2 ((1-e)/(1+e))^2
    e0, e1 = 0.01, 0.02
    low = math.sqrt((n - 1) / 2)
    high = math.sqrt(n / 2) * (1 - e1) / (1 + e1)  # the least u_high over [e0, e1]
    gap = high - low
    cert = reference_certificate((e0, e1), (low + 0.25 * gap, low + 0.75 * gap))
    assert cert.status == "word" and cert.proven
    assert cert.word == sb.Word((n,))
    assert cert.itinerary == (0,) * (n - 1) + (-1,)
    assert verify(cert)


# the tongues of n = 1..6 at e where they are open (the n-th ends near e = 0.5 / n^1.3)
STRADDLE = [(n, e) for n in range(1, 7) for e in (0.02, 0.1, 0.2) if sb.tongue(n, e)[1] > sb.tongue(n, e)[0]]


@pytest.mark.parametrize("n, e", STRADDLE)
def test_a_box_straddling_a_tongue_border_is_never_proven(n, e):
    low, high = sb.tongue(n, e)
    d = 1e-7
    upper = reference_certificate((e - d, e + d), (high - d, high + d))
    # the upper border is the slide test (2.4) of the n-th step
    assert (upper.status, upper.reason, upper.step) == ("undecided", "chatter", n)
    assert not verify(dataclasses.replace(upper, status="word", word=sb.Word((n,)),
                                          itinerary=(0,) * (n - 1) + (-1,)))
    if n > 1:
        lower = reference_certificate((e - d, e + d), (low - d, low + d))
        # the lower border is the ball grazing the edge at the end of step n - 1
        assert (lower.status, lower.reason, lower.step) == ("undecided", "graze", n - 1)


def test_no_sliding_exactly_above_the_corollary_curve():
    for e in (0.05, 0.2, 0.5, 0.9):
        bound = (1 - e) / (2 * math.sqrt(2 * e))
        above = reference_certificate((e, e + 1e-3), (bound * (1 + 1e-9), bound * 1.1))
        assert above.status == "no_sliding"
        assert verify(above)
        # a box reaching below the curve at e0 is not proven by the corollary
        across = reference_certificate((e, e + 1e-3), (bound * (1 - 1e-9), bound * 1.1))
        assert across.status != "no_sliding"


@pytest.mark.parametrize("window", ["fig5e", "fig7"])
def test_proven_boxes_agree_with_the_float_package_at_points_inside(window, request):
    certs = request.getfixturevalue(window)
    rng = np.random.default_rng(11)
    proven = [c for c in certs if c.proven]
    assert len(proven) > 0.6 * len(certs)
    assert "word" in {c.status for c in proven}
    for c in proven[:400]:
        for _ in range(3):
            e = rng.uniform(*c.e)
            u = rng.uniform(*c.u)
            found = sb.sliding_word(e, u, max_iter=c.max_iter)
            if c.status == "word":
                assert found == c.word, (c.e, c.u, e, u)
            else:
                assert found is None, (c.e, c.u, e, u)


def test_a_point_is_a_box():
    cert = reference_certificate((0.18, 0.18), (0.63, 0.63))
    assert cert.status == "word" and cert.word == sb.sliding_word(0.18, 0.63)


@pytest.mark.parametrize("e, u, name", [
    ((0.2, 0.1), (0.6, 0.61), "e"),
    ((0.0, 0.1), (0.6, 0.61), "e"),
    ((0.5, 1.0), (0.6, 0.61), "e"),
    ((0.1, 0.2), (0.61, 0.6), "u"),
    ((0.1, 0.2), (0.0, 0.6), "u"),
    ((0.1, float("nan")), (0.6, 0.61), "e1"),
    ((0.1, 0.2), (0.6, float("inf")), "u1"),
    ((0.1, 0.2, 0.3), (0.6, 0.61), "e"),
    ("ab", (0.6, 0.61), "e"),
])
def test_bad_boxes_are_refused_by_name(e, u, name):
    with pytest.raises(ValueError, match=rf"^{name}\b"):
        reference_certificate(e, u)


def test_bad_max_iter_is_refused():
    with pytest.raises(ValueError, match=r"^max_iter"):
        reference_certificate((0.1, 0.2), (0.6, 0.61), max_iter=0)


# ------------------------------------------------------------------ the checker


def test_the_checker_accepts_thousands_of_reference_proven_boxes(fig7, fig5e):
    certs = fig7 + fig5e
    assert sum(c.status == "word" for c in certs) > 1500
    accepted = _accepted(_arrays(certs))
    assert accepted.all(), [(c.e, c.u, c.status) for c, ok in zip(certs, accepted) if not ok][:5]
    assert all(verify(c) for c in certs[:300] if len(c.itinerary) < 50)


def _tamper_letters(certs, rng):
    """Each word certificate with one impact number changed (by +-1, 0 <-> 1)."""
    out = []
    for c in certs:
        if c.status != "word" or len(c.itinerary) < 2:
            continue
        itin = list(c.itinerary)
        i = int(rng.integers(len(itin) - 1))
        itin[i] = itin[i] + 1 if (itin[i] == 0 or rng.random() < 0.5) else itin[i] - 1
        out.append(dataclasses.replace(c, itinerary=tuple(itin), word=sb.symbolic.word_from_impacts(itin)))
    return out


def _changed_claims(certs, tampered, rng, box):
    """The word certificates of ``certs``, each claimed on ``box(c, w)`` for a
    width w drawn from 1e-6 to 10**-2.5, then those of ``tampered`` with one
    impact number changed (_tamper_letters), all from ``rng`` in that order."""
    claims = [box(c, 10 ** rng.uniform(-6, -2.5)) for c in certs if c.status == "word"]
    return claims + _tamper_letters(tampered, rng)


def test_a_changed_impact_number_is_rejected(fig7):
    tampered = _tamper_letters(fig7, np.random.default_rng(3))
    assert len(tampered) > 500
    assert not _accepted(_arrays(tampered)).any()
    verdicts = [verify(c) for c in tampered[:50]]
    assert not any(verdicts)
    assert {v.check for v in verdicts} <= {"slide", "impact", "no impact"}


def test_a_word_that_the_itinerary_does_not_spell_is_rejected(fig7):
    c = next(c for c in fig7 if c.status == "word")
    wrong = sb.Word(c.word.letters + (1,))
    v = verify(dataclasses.replace(c, word=wrong))
    assert not v and v.check == "word"


def test_a_box_widened_across_a_border_is_rejected(fig7):
    rng = np.random.default_rng(4)
    widened = []
    for c in fig7:
        if c.status != "word":
            continue
        w = 10 ** rng.uniform(-4, -2)
        e0, e1 = c.e[0] - w * rng.random(), c.e[1] + w * rng.random()
        u0, u1 = c.u[0] - w * rng.random(), c.u[1] + w * rng.random()
        corners = {sb.sliding_word(e, u) for e in (e0, e1) for u in (u0, u1)}
        if len(corners) > 1:  # a border crosses the widened box: the claim is false there
            widened.append(dataclasses.replace(c, e=(e0, e1), u=(u0, u1)))
    assert len(widened) > 300
    assert not _accepted(_arrays(widened)).any()


def test_no_sliding_below_the_corollary_curve_is_rejected(fig7):
    below = [dataclasses.replace(c, status="no_sliding", word=None, itinerary=())
             for c in fig7 if c.status == "word"]
    assert all(c.u[0] < (1 - c.e[0]) / (2 * math.sqrt(2 * c.e[0])) for c in below)
    code, _ = verify_codes(**_arrays(below))
    assert (code == CHECKS.index("corollary")).all()


def test_a_truncated_itinerary_is_rejected(fig7):
    cut = [dataclasses.replace(c, itinerary=c.itinerary[:-1]) for c in fig7
           if c.status in ("word", "no_slide_within")]
    assert any(c.status == "no_slide_within" for c in cut)
    code, _ = verify_codes(**_arrays(cut))
    assert (code == CHECKS.index("itinerary")).all()
    # a claim of more steps than max_iter, or a slide in the middle
    c = next(c for c in fig7 if c.status == "word")
    assert not verify(dataclasses.replace(c, max_iter=len(c.itinerary) - 1))
    assert not verify(dataclasses.replace(c, itinerary=(-1,) + c.itinerary))


def test_the_checker_and_the_reference_agree_on_which_claims_hold(fig7):
    """A claim holds for the reference when it proves the same status and
    itinerary on the (possibly widened or changed) box."""
    rng = np.random.default_rng(8)
    claims = _changed_claims(fig7[:600], fig7[:200], rng, lambda c, w: dataclasses.replace(
        c, e=(c.e[0] - w * rng.random(), c.e[1] + w * rng.random()),
        u=(c.u[0] - w * rng.random(), c.u[1] + w * rng.random())))
    accepted = _accepted(_arrays(claims))
    held = np.array([
        (lambda r: r.status == c.status and r.itinerary == c.itinerary)(reference_certificate(c.e, c.u))
        for c in claims])
    assert 0.1 < held.mean() < 0.9  # both outcomes are represented
    assert np.array_equal(accepted, held)


def test_undecided_certificates_are_checked_up_to_their_step(fig7):
    und = [c for c in fig7 if c.status == "undecided" and c.itinerary]
    assert len(und) > 20 and verify_arrays(**_arrays(und)).all()
    assert all(verify(c) for c in und if len(c.itinerary) < 50)
    bad = dataclasses.replace(und[0], itinerary=und[0].itinerary[:-1] + (und[0].itinerary[-1] + 1,))
    assert not verify(bad)


def test_bad_arrays_are_refused():
    a = _arrays(_random_certificates(FIG7, 3, seed=1))
    with pytest.raises(ValueError, match="^offsets"):
        verify_arrays(**{**a, "offsets": a["offsets"][:-1]})
    with pytest.raises(ValueError, match="^max_iter"):
        verify_arrays(**{**a, "max_iter": 0})
    # a box outside the plane, or an unknown status, is a rejected claim
    code, _ = verify_codes(**{**a, "e1": np.array([0.2, 1.5, 0.2]), "status": np.array([0, 0, 9])})
    assert list(code[1:]) == [CHECKS.index("box"), CHECKS.index("status")]


@pytest.mark.parametrize("suffix", [".nc", ".zarr"])
def test_verify_file_reads_an_atlas_and_counts_the_rejected_boxes(tmp_path, fig7, suffix):
    certs = fig7[:400]
    good = _atlas_dataset(certs, words=True)
    path = tmp_path / f"atlas{suffix}"

    def write(ds, where):  # a store as the package writes one: no consolidated metadata
        ds.to_zarr(where, consolidated=False) if suffix == ".zarr" else ds.to_netcdf(where)

    write(good, path)
    assert verify_file(path) == (400, 0)
    assert verify(path) and verify(str(path)).checked == 400
    tampered = _tamper_letters(certs, np.random.default_rng(2))
    bad = _atlas_dataset(certs[:100] + tampered, strings=True)
    path2 = tmp_path / f"bad{suffix}"
    write(bad, path2)
    assert verify_file(path2) == (100 + len(tampered), len(tampered))
    v = verify(path2)
    assert not v and v.rejected == len(tampered)


def test_a_stored_word_must_be_the_itinerary_s(fig7):
    certs = [c for c in fig7 if c.status == "word"][:50]
    data = _atlas_dataset(certs, words=True)
    data["word"].values[3] = "(1, 2, 0^inf)" if certs[3].word != sb.Word((1, 2)) else "(2, 1, 0^inf)"
    v = verify(data)
    assert not v and v.rejected == 1 and v.check == "word"
    assert read_atlas_arrays(data)["max_iter"] == certs[0].max_iter
    with pytest.raises(ValueError, match="^atlas must hold"):
        verify(data.drop_vars("offsets"))


# ------------------------------------------- a third implementation: mpmath iv


def _iv_check(cert):
    """Re-decide ``cert`` with mpmath's interval arithmetic, on the paper's
    formulas as printed: (y, v) states (Prop. 2.3), t_k in closed form (2.2),
    the slide test (2.4), Corollary 2.1 with its square root."""
    from mpmath import iv

    iv.prec = 53

    def happens(m):  # proven >= 0
        return bool(m.a >= 0)

    def never(m):  # proven < 0
        return bool(m.b < 0)

    e, u = iv.mpf(list(cert.e)), iv.mpf(list(cert.u))
    if cert.status == "no_sliding":
        m = iv.mpf(cert.u[0]) - (1 - iv.mpf(cert.e[0])) / (2 * iv.sqrt(2 * iv.mpf(cert.e[0])))
        return bool(m.a > 0)
    T = 1 / u
    y, v = iv.mpf(1), iv.mpf(0)

    def t(k, s):  # eq. (2.2)
        return v + (1 + e - 2 * e**k) / (1 - e) * s

    for k in cert.itinerary:
        s = iv.sqrt(v * v + 2 * y)
        slide = T - (v + (1 + e) / (1 - e) * s)
        if k == -1:
            return happens(slide)
        if not never(slide):
            return False
        if k >= 1 and not happens(T - t(k, s)):
            return False
        if not never(T - t(k + 1, s)):
            return False
        if k == 0:
            y, v = y + v * T - T * T / 2 + 1, v - T
        else:
            d, vk = T - t(k, s), e**k * s
            y, v = 1 - d * d / 2 + vk * d, vk - d
    return cert.status != "word"


def test_mpmath_iv_re_verifies_the_short_certificates_and_rejects_tampered_ones(fig7):
    # the literal (y, v) form loses the dependency between d and v_k at every
    # step (its enclosures roughly double per step), so it re-verifies the
    # 1e-6 boxes only over a few steps; the checkers carry (v, s) instead
    short = [c for c in fig7 if c.status in ("word", "no_sliding") and len(c.itinerary) <= 5][:250]
    assert len(short) == 250
    assert all(_iv_check(c) for c in short)
    tampered = _tamper_letters(short, np.random.default_rng(5))[:100]
    assert len(tampered) > 50
    assert not any(_iv_check(c) for c in tampered)


def test_certificate_margins_enclose_the_decisions(fig7):
    c = next(c for c in fig7 if c.status == "word" and len(c.itinerary) > 3)
    assert isinstance(c, Certificate)
    assert len(c.decisions) == len(c.margins)
    lo, hi = c.margins[:, 0], c.margins[:, 1]
    assert np.all(lo <= hi)
    # every decision proven: lo >= 0 (happens) or hi < 0 (does not)
    assert np.all((lo >= 0) | (hi < 0))
    assert c.decisions[-1] == "slide" and lo[-1] >= 0


def test_a_claim_holds_on_a_box_exactly_when_it_holds_at_its_two_corners(fig7):
    """Along a fixed itinerary every margin decreases in e and in u (the
    docstring of structure/verify.py), so its range over the box is attained
    at the corners (e1, u1) and (e0, u0): the checker's enclosures are the
    exact ranges up to rounding, and it accepts a box exactly when it accepts
    both corners as point boxes."""
    rng = np.random.default_rng(9)
    claims = _changed_claims(fig7[:700], fig7[:150], rng,
                             lambda c, w: dataclasses.replace(c, e=(c.e[0], c.e[0] + w), u=(c.u[0], c.u[0] + w)))
    box = _accepted(_arrays(claims))
    low = _accepted(_arrays([dataclasses.replace(c, e=(c.e[0],) * 2, u=(c.u[0],) * 2) for c in claims]))
    high = _accepted(_arrays([dataclasses.replace(c, e=(c.e[1],) * 2, u=(c.u[1],) * 2) for c in claims]))
    assert 0.1 < box.mean() < 0.9
    assert np.array_equal(box, low & high)
