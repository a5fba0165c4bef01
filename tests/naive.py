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
