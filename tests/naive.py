"""Slow, obviously-correct references: no closed form of the paper in here.

One step is simulated impact by impact: the flight to the floor is the root of
``y + v t - t^2/2 = 0``, every bounce with take-off speed ``w`` lasts ``2 w`` and
leaves with ``e w``.  Impacts "accumulate" when the bounce speed has fallen
below ``REST * (impact speed)``, which is where float64 can no longer tell a
bounce from rest; states that close to the sliding boundary are excluded from
exact comparisons by the tests.
"""

from __future__ import annotations

import math

SLIDING = -1
REST = 1e-13


def step(y, v, e, u, max_impacts=10_000_000):
    """One step edge to edge, impact by impact: ``(y_next, v_next, impacts)``."""
    T = 1.0 / u
    speed = math.sqrt(v * v + 2.0 * y)
    t = v + speed  # time when y + v t - t^2/2 reaches the floor
    if t > T:
        return y + v * T - 0.5 * T * T + 1.0, v - T, 0
    w = e * speed  # take-off speed after the impact
    k = 1
    while k < max_impacts:
        if w <= REST * speed:
            return 1.0, 0.0, SLIDING
        if t + 2.0 * w > T:
            d = T - t
            return w * d - 0.5 * d * d + 1.0, w - d, k
        t += 2.0 * w
        w *= e
        k += 1
    return 1.0, 0.0, SLIDING


def accumulation_time(y, v, e):
    """Time at which impacts on the first step would accumulate, summed term by
    term (used only to measure how close a state is to the sliding boundary)."""
    speed = math.sqrt(v * v + 2.0 * y)
    t = v + speed
    w = e * speed
    while w > 1e-17 * speed:
        t += 2.0 * w
        w *= e
    return t


def orbit_until_slide(y, v, e, u, max_steps):
    """Impact numbers of the steps up to the first slide (inclusive), or None."""
    ks = []
    for _ in range(max_steps):
        y, v, k = step(y, v, e, u)
        ks.append(k)
        if k == SLIDING:
            return ks
    return None


def word(e, u, max_steps=1000):
    """Letters of the periodic sliding solution through (1, 0) (docs/design.md), or None."""
    ks = orbit_until_slide(1.0, 0.0, e, u, max_steps)
    if ks is None:
        return None
    letters, jump = [], 0
    for k in ks:
        jump += 1
        if k == 0:
            continue
        letters.append(jump)
        jump = 0
        if k != SLIDING:
            letters.extend([0] * (k - 1))
    return tuple(letters)


def box_count(image, s, oy=0, ox=0):
    """Boxes of side ``s`` (grid corners at ``(k s - oy, l s - ox)``, boxes cut
    by the image edge included) holding a nonzero pixel, one box at a time."""
    h, w = len(image), len(image[0])
    count = 0
    for top in range(-oy, h, s):
        for left in range(-ox, w, s):
            rows = range(max(top, 0), min(top + s, h))
            cols = range(max(left, 0), min(left + s, w))
            if any(image[i][j] for i in rows for j in cols):
                count += 1
    return count


def border_pixels(mask):
    """Pixels of ``mask`` with a 4-neighbour inside the image and outside the mask."""
    h, w = len(mask), len(mask[0])
    out = [[False] * w for _ in range(h)]
    for i in range(h):
        for j in range(w):
            if mask[i][j]:
                for a, b in ((i - 1, j), (i + 1, j), (i, j - 1), (i, j + 1)):
                    if 0 <= a < h and 0 <= b < w and not mask[a][b]:
                        out[i][j] = True
    return out


def impacts_in_window(e, u, y0, v0, start, stop, max_events=10_000_000):
    """Impacts with horizontal position in ``[start, stop)`` steps, event by event.

    No Poincare map: the ball is followed from impact to impact in the plane.
    It leaves the edge ``x = 0`` at height ``y0`` above the floor of step 0
    (floor of step j at height -j) with vertical velocity ``v0`` and
    horizontal speed ``u``.  From a take-off at ``(x, h)`` with vertical
    velocity ``w`` the landing step is found by trying the steps in turn: it
    lands on step j at ``t = w + sqrt(w^2 + 2 (h + j))`` if ``x + u t < j + 1``.
    Returns the impact count, or None if the impacts accumulate (bounce speed
    below ``REST`` times the impact speed) before ``stop``.
    """
    x, h, w = 0.0, y0, v0
    count = 0
    for _ in range(max_events):
        j = math.floor(x) if x > 0.0 else 0
        if x >= j + 1.0:  # pragma: no cover - floor guards this
            j += 1
        while True:
            t = w + math.sqrt(w * w + 2.0 * (h + j))
            if x + u * t < j + 1.0:
                break
            j += 1
        speed = t - w  # |vertical velocity| at the landing
        x += u * t
        if x >= stop:
            return count
        if x >= start:
            count += 1
        h = -float(j)
        w = e * speed
        if w <= REST * speed:
            return None
    return None  # pragma: no cover


# --------------------------------------------------------------------------- #
# High-precision reference (60 significant digits, mpmath)                     #
# --------------------------------------------------------------------------- #

DIGITS = 60
# past this many impacts the reference sums the geometric series of the bounce
# durations in closed form instead of one bounce at a time; with 60 digits the
# sum loses log10(1/(1-e)) <= 16 digits to cancellation, leaving 44
COUNT_LIMIT = 20_000


def precise_step(y, v, e, u, digits=DIGITS, count_limit=COUNT_LIMIT, T=None):
    """One step in ``digits``-digit arithmetic from the physics alone.

    Returns ``(y_next, v_next, k, v_k, d)`` as mpmath numbers (k an int):
    the state at the next edge, the impact number, the take-off speed of the
    last bounce and the time ``d`` spent on it before the edge (``d`` and
    ``v_k`` are None when the ball flies over or slides).  The inputs are the
    floats as given (converted exactly), ``T = 1/u`` is exact to ``digits``.

    The ball falls to the root ``t_1`` of ``y + v t - t^2/2 = 0`` with impact
    speed ``s = sqrt(v^2 + 2y)``; a bounce with take-off speed ``w`` lasts
    ``2w`` and the next leaves with ``e w``; the bounces sum to the
    accumulation time ``t_1 + 2 e s/(1-e)``; at or before ``T`` the ball slides
    off the edge at (1, 0) (Prop. 2.1).  Bounces are counted one by one up to
    ``count_limit``; past it the count is the exact solution of
    ``t_1 + 2 e s (1 - e^(k-1))/(1-e) <= T`` found with a logarithm and checked
    by evaluating both sides at k and k + 1.
    """
    import mpmath

    with mpmath.workdps(digits):
        return _precise_step(mpmath, y, v, e, u, count_limit, T)


def _precise_step(ctx, y, v, e, u, count_limit, T):
    y, v, e, u = (ctx.mpf(float(x)) for x in (y, v, e, u))
    T = 1 / u if T is None else ctx.mpf(T)
    s = ctx.sqrt(v * v + 2 * y)
    # the root without cancellation when v < 0 (v + s = 2y/(s - v))
    t = v + s if v >= 0 else (2 * y / (s - v) if s - v > 0 else ctx.mpf(0))
    if t > T:
        return y + v * T - T * T / 2 + 1, v - T, 0, None, None
    if e == 0 or t + 2 * e * s / (1 - e) <= T:
        return ctx.mpf(1), ctx.mpf(0), SLIDING, None, None
    w = e * s
    k = 1
    while k < count_limit:
        if t + 2 * w > T:
            d = T - t
            return w * d - d * d / 2 + 1, w - d, k, w, d
        t += 2 * w
        w *= e
        k += 1
    t1 = t - 2 * e * s * (1 - e ** (k - 1)) / (1 - e)  # back to the first impact

    def tk(n):
        return t1 + 2 * e * s * (1 - e ** (n - 1)) / (1 - e)

    # t_k <= T  <=>  e^(k-1) >= 1 - (T - t_1)(1-e)/(2 e s)
    k = int(ctx.floor(ctx.log(1 - (T - t1) * (1 - e) / (2 * e * s)) / ctx.log(e))) + 1
    while tk(k) > T:
        k -= 1
    while tk(k + 1) <= T:
        k += 1
    w = e**k * s
    d = T - tk(k)
    return w * d - d * d / 2 + 1, w - d, k, w, d


EPS = 2.0**-52


def classify(y, v, e, u, result, slack=64, count_limit=50):
    """Judge a float map ``result = (y_next, v_next, k)`` of ``(y, v, e, u)``
    against :func:`precise_step`: ``(verdict, error)``.

    ``"ok"``: the reference's impact number and state to ``tol = slack eps
    (T + |v| + s + 1)`` (the rounding of ``T = 1/u`` and of the impact times
    alone is eps T); ``"ok-conditioned"``: another k, but one the reference
    gives for an edge moved by ``tol`` (``T (1 -+ slack eps) -+ tol``), with the
    state on that bounce (its energy ``y - 1 + v^2/2 = v_k^2/2``);
    ``"k-mismatch"`` / ``"value-mismatch"`` otherwise.  ``error`` is the
    absolute error of the state (0 when k differs).
    """
    import mpmath

    yn, vn, k = result
    ry, rv, rk, rvk, rd = precise_step(y, v, e, u, count_limit=count_limit)
    T = 1.0 / u
    s = math.sqrt(v * v + 2 * y)
    tol = slack * EPS * (T + abs(v) + s + 1.0)
    if k == rk:
        err = max(abs(yn - float(ry)), abs(vn - float(rv)))
        # a flight's height y + v T - T^2/2 + 1 rounds like its largest term
        scale_y = (slack * EPS * (abs(y) + abs(v) * T + T * T + 1.0) if rk == 0
                   else tol * (1 + float(rvk or 0.0)))
        good = abs(vn - float(rv)) <= tol and abs(yn - float(ry)) <= scale_y
        if good:
            return "ok", err
        if rk <= 0 or 2 * float(rvk) > 4 * tol:
            return "value-mismatch", err
    lo = precise_step(y, v, e, u, count_limit=count_limit, T=mpmath.mpf(T) * (1 - slack * EPS) - tol)[2]
    hi = precise_step(y, v, e, u, count_limit=count_limit, T=mpmath.mpf(T) * (1 + slack * EPS) + tol)[2]
    within = (lo <= k <= hi) or (hi == SLIDING and k >= lo) or (k == SLIDING and SLIDING in (lo, hi))
    if not within:
        return "k-mismatch", 0.0
    if k > 0:
        with mpmath.workdps(30):
            vk = float(mpmath.mpf(e) ** k * mpmath.sqrt(mpmath.mpf(v) ** 2 + 2 * mpmath.mpf(y)))
        if not (yn >= 1.0 and abs(vn) <= vk * (1 + 1e-12)
                and abs((yn - 1.0) + 0.5 * vn * vn - 0.5 * vk * vk) <= 8 * tol * (1 + vk)):
            return "value-mismatch", 0.0
    return "ok-conditioned", 0.0
