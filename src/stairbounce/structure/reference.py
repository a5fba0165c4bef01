"""The reference certifier: one box, with Arb balls (python-flint), slowly and plainly.

``reference_certificate(e=(e0, e1), u=(u0, u1), max_iter=1000)`` decides the
statement of ``structure/certificate.py`` for the box ``[e0, e1] x [u0, u1]``
with python-flint's ``arb`` balls (midpoint-radius intervals whose every
operation returns a ball containing the exact result, Johansson, *Arb*, IEEE
Trans. Computers 66 (2017)).  It shares no code with the fast kernel nor with
``stairbounce.model``: it is the slow implementation the others are checked by.

The maths (the paper's Section 2; T = 1/u, ``ratio = (1+e)/(1-e)``):

* From the edge state ``(y, v)`` let ``s = sqrt(v^2 + 2y)``.  The impact times
  on the step below are (eq. (2.2)) ``t_1 = v + s`` and
  ``t_{j+1} = t_j + 2 e^j s``; the ball leaves the j-th impact with
  ``v_j = e^j s``.
* Slide test (Prop. 2.1, eq. (2.4)): the impacts accumulate before the edge iff
  ``v + ratio s <= T``; margin ``T - (v + ratio s)``.
* Impact j happens on the step iff ``t_j <= T``; margin ``T - t_j``.  The
  impact number k of a non-sliding step is the last j with ``t_j <= T``
  (Prop. 2.2).
* Prop. 2.3: after a fly-over (k = 0) ``y' = y + vT - T^2/2 + 1``,
  ``v' = v - T``; after k >= 1 impacts, with ``d = T - t_k``,
  ``y' = 1 - d^2/2 + v_k d``, ``v' = v_k - d``; after a slide ``(1, 0)``.

The state is carried as ``(v, s)`` rather than ``(y, v)``: the new speed
``s' = sqrt(v'^2 + 2y')`` follows from Prop. 2.3 by algebra (energy
conservation over the flight), ``s'^2 = s^2 + 2`` after a fly-over and
``s'^2 = v_k^2 + 2`` after k impacts.  These are identities of real numbers, so
the enclosures stay rigorous; they avoid the dependency between ``d`` and
``v_k`` that makes ball arithmetic on the literal ``y'`` blow up over a few
steps.  ``y'`` itself is never needed (only ``s`` enters the decisions).  Along
a fixed itinerary every margin decreases with e and with u
(``structure/verify.py``), so these balls are the exact ranges up to rounding
and a second-order term (a ball product ``(m1 +- r1)(m2 +- r2)`` has radius
``|m1| r2 + |m2| r1 + r1 r2``, ``2 r1 r2`` wider than the range of the product
of two positive intervals); measured on 300 boxes up to 1e-4 wide in the Fig. 7
window, the margins' balls reach at most 6e-7 beyond the corner values.

The orbit starts at ``(y, v) = (1, 0)`` (``s = sqrt 2``).  Decisions and
statuses as in ``structure/certificate.py``: equality counts as the event, a
decision is proven when the enclosure ``[lo, hi]`` of its margin has
``lo >= 0`` (happens on the whole box) or ``hi < 0`` (nowhere).  ``no_sliding``
is Corollary 2.1 over the whole box: ``u0 > (1-e0) / (2 sqrt(2 e0))``, which
bounds ``(1-e)/(2 sqrt(2e))`` for every e >= e0 since that bound decreases in
e.
"""

from __future__ import annotations

import math

import numpy as np

from .. import _validate as _v
from ..symbolic import word_from_impacts
from .certificate import Certificate

__all__ = ["reference_certificate", "check_box"]

SLIDING = -1
# impact decisions tried on one step before the step is called undecided
# ("edge"): the j-th margin's enclosure tends to the slide margin's as
# e^j -> 0, so a step whose slide margin is proven negative ends long before
MAX_IMPACTS = 100_000
# working precision of the balls, in bits (Arb's default, that of float64)
PREC = 53


def _flint():
    try:
        import flint
    except ImportError:  # pragma: no cover - the test extra installs it
        raise ImportError(
            "the reference certifier needs python-flint (pip install 'python-flint>=0.6', "
            "or the package's [test] extra)"
        ) from None
    return flint


def check_box(e, u):
    """check_box(e, u) -> (e0, e1, u0, u1)

    The box ``[e0, e1] x [u0, u1]`` as floats, or a ``ValueError`` naming the
    parameter: ``0 < e0 <= e1 < 1`` and ``1e-150 <= u0 <= u1 <= 1e150`` (the
    package's valid range of u), every bound finite.  A point is a box.
    """
    out = []
    for name, pair in (("e", e), ("u", u)):
        if isinstance(pair, (str, bytes)) or not hasattr(pair, "__len__") or len(pair) != 2:
            raise ValueError(f"{name} must be a pair ({name}0, {name}1) of real numbers, got {pair!r}")
        lo, hi = (_v.real(f"{name}{i}", x) for i, x in enumerate(pair))
        if lo > hi:
            raise ValueError(f"{name} must be an interval with {name}0 <= {name}1, got ({lo!r}, {hi!r})")
        out += [lo, hi]
    e0, e1, u0, u1 = out
    if not 0.0 < e0 or not e1 < 1.0:
        raise ValueError(f"e (restitution coefficient) must lie in (0, 1): 0 < e0 <= e1 < 1, got ({e0!r}, {e1!r})")
    if not _v.U_MIN <= u0 or not u1 <= _v.U_MAX:
        raise ValueError(
            f"u (horizontal speed) must lie in [{_v.U_MIN:g}, {_v.U_MAX:g}], got ({u0!r}, {u1!r})")
    return e0, e1, u0, u1


def _bounds(m):
    """Float bounds ``(lo, hi)`` of the ball ``m``, rounded outward."""
    flint = _flint()
    lo, hi = m.lower(), m.upper()
    flo, fhi = float(lo), float(hi)
    if flint.arb(flo) > lo:
        flo = math.nextafter(flo, -math.inf)
    if flint.arb(fhi) < hi:
        fhi = math.nextafter(fhi, math.inf)
    return flo, fhi


def _sign(m):
    """+1 when the ball ``m`` is proven >= 0, -1 when proven < 0, 0 when undecided."""
    if m.lower() >= 0:
        return 1
    if m.upper() < 0:
        return -1
    return 0


def reference_certificate(e, u, max_iter=1000):
    """reference_certificate(e=(e0, e1), u=(u0, u1), max_iter=1000) -> Certificate

    What the orbit of the edge state (1, 0) does over the whole box, decided
    with Arb balls (the slow reference of the certifier).

    The box is entered as balls containing ``[e0, e1]`` and ``[u0, u1]`` (their
    radii rounded up), and the Poincare map (Prop. 2.3, eqs. (2.2), (2.4)) is
    iterated on balls from ``(y, v) = (1, 0)``: per step the slide decision
    ``T - (v + ratio s)``, then the impact decisions ``T - t_j``, j = 1, 2, ...
    until one is proven negative (see the module's docstring for the
    formulas).  Every statement it makes is proven by ball arithmetic; a
    decision it cannot prove stops it with status ``undecided``.

    Parameters
    ----------
    e : (float, float), 0 < e0 <= e1 < 1
    u : (float, float), 1e-150 <= u0 <= u1 <= 1e150
    max_iter : int >= 1, default 1000
        Steps followed before the finite claim ``no_slide_within``.

    Returns
    -------
    Certificate
        ``no_sliding`` (Corollary 2.1 over the box), ``word`` (the itinerary
        ends with the slide), ``no_slide_within`` (``max_iter`` proven steps
        without a slide) or ``undecided`` with ``reason`` ``"chatter"`` (the
        slide decision), ``"graze"`` (impact 1) or ``"edge"`` (a later impact)
        and the 1-based ``step``.  ``margins`` hold the outward-rounded float
        bounds of every decision's ball, the undecided one last.
    """
    e0, e1, u0, u1 = check_box(e, u)
    max_iter = _v.count("max_iter", max_iter, 1)
    flint = _flint()
    arb = flint.arb
    old_prec = flint.ctx.prec
    flint.ctx.prec = PREC
    try:
        E = arb(e0).union(arb(e1))
        U = arb(u0).union(arb(u1))
        base = dict(e=(e0, e1), u=(u0, u1), max_iter=max_iter)
        # Corollary 2.1 over the box: u0 - (1 - e0) / (2 sqrt(2 e0)) > 0
        e0b = arb(e0)
        cor = arb(u0) - (1 - e0b) / (2 * (2 * e0b).sqrt())
        if cor.lower() > 0:
            return Certificate(**base, status="no_sliding", decisions=("corollary 2.1",),
                               margins=np.array([_bounds(cor)]))
        T = 1 / U
        ratio = (1 + E) / (1 - E)
        v, s = arb(0), arb(2).sqrt()
        itinerary, decisions, margins = [], [], []

        def stop(reason, step):
            return Certificate(**base, status="undecided", reason=reason, step=step,
                               itinerary=tuple(itinerary), decisions=tuple(decisions),
                               margins=np.array(margins, dtype=float).reshape(-1, 2))

        for step in range(1, max_iter + 1):
            m = T - (v + ratio * s)  # (2.4)
            decisions.append("slide")
            margins.append(_bounds(m))
            sign = _sign(m)
            if sign == 0:
                return stop("chatter", step)
            if sign > 0:
                itinerary.append(SLIDING)
                its = tuple(itinerary)
                return Certificate(**base, status="word", word=word_from_impacts(its), itinerary=its,
                                   decisions=tuple(decisions), margins=np.array(margins, dtype=float))
            t, ej, j = v + s, arb(1), 1  # t_1, e^0
            while True:
                m = T - t  # impact j happens iff t_j <= T
                decisions.append(f"impact {j}")
                margins.append(_bounds(m))
                sign = _sign(m)
                if sign == 0 or j > MAX_IMPACTS:
                    return stop("graze" if j == 1 else "edge", step)
                if sign < 0:
                    break
                ej = ej * E  # e^j
                t_last, t = t, t + 2 * ej * s  # t_{j+1} = t_j + 2 e^j s
                j += 1
            k = j - 1
            itinerary.append(k)
            if k == 0:  # fly-over: v' = v - T, s'^2 = s^2 + 2
                v, s = v - T, (s * s + 2).sqrt()
            else:  # k impacts: v_k = e^k s, d = T - t_k, v' = v_k - d, s'^2 = v_k^2 + 2
                vk = ej * s
                v, s = vk - (T - t_last), (vk * vk + 2).sqrt()
        return Certificate(**base, status="no_slide_within", itinerary=tuple(itinerary),
                           decisions=tuple(decisions), margins=np.array(margins, dtype=float))
    finally:
        flint.ctx.prec = old_prec
