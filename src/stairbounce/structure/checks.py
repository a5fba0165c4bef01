"""The exact borders checked against the paper, as the report prints them:
the tongues of Theorem 3.1 (:func:`tongue_distances`, :data:`TONGUE_WINDOW`),
Corollary 2.1 (:func:`above_no_sliding_curve`), the pixels' sides
(:func:`side_agreement`) and the self-similarity of the bands of Figs. 5a-c
on traced regions (:func:`band_similarity`).
"""

from __future__ import annotations

import math

import numpy as np

from ..model import check_count
from .borders import _grid_input
from .regions import word_region
from .words import _words

__all__ = ["band_similarity"]


# --------------------------------------------------------------------------- #
# Checks the report can print                                                 #
# --------------------------------------------------------------------------- #

TONGUE_WINDOW = ((0.0, 0.25), (0.05, 2.05))
"""A window holding the tongues n = 1..8 of Theorem 3.1 (and their tips)."""


def tongue_distances(points, n_max=8):
    """tongue_distances(points, n_max=8) -> dict

    The border points of the words ``(n, 0^inf)``, n = 1..n_max, against
    Theorem 3.1: their lower border is the graze curve ``u^2 = (n-1)/2``,
    their upper border the chatter curve ``u^2 = n/2 ((1-e)/(1+e))^2``.
    Returns ``points`` (how many), ``wrong_kind`` (neither graze on the lower
    curve nor chatter on the upper one), ``max_relative`` (the largest
    relative distance in u of a bracket to its curve: for a bracket along u,
    ``|u - u_curve(e)| / u_curve`` with the nearer end; along e, the nearer
    of its two ends), ``kinds`` (n -> set of kinds seen).
    """
    word = points["word_low"].values
    high = points["word_high"].values
    kind = points["kind"].values
    e, u, w = points["e"].values, points["u"].values, points["width"].values
    along_u = points["axis"].values == "u"
    worst, count, wrong, kinds = 0.0, 0, 0, {}
    for n in range(1, n_max + 1):
        text = f"({n}, 0^inf)"
        for i in np.flatnonzero((word == text) | (high == text)):
            count += 1
            kinds.setdefault(n, set()).add(kind[i])
            ends_e = (e[i], e[i]) if along_u[i] else (e[i], e[i] + w[i])
            ends_u = (u[i], u[i] + w[i]) if along_u[i] else (u[i], u[i])
            if kind[i] == "graze" and n >= 2:
                target = [math.sqrt((n - 1) / 2.0)] * 2
            elif kind[i] == "chatter":
                target = [math.sqrt(n / 2.0) * (1.0 - x) / (1.0 + x) for x in ends_e]
            else:
                wrong += 1
                continue
            d = min(abs(a - b) / b for a, b in zip(ends_u, target))
            worst = max(worst, d)
    return {"points": count, "wrong_kind": wrong, "max_relative": worst, "kinds": kinds}


def above_no_sliding_curve(points):
    """above_no_sliding_curve(points) -> int

    Corollary 2.1: the border points strictly above ``u = (1-e)/(2 sqrt(2e))``
    (none can be there: no solution slides above the curve, so no two sides
    differ)."""
    e, u = points["e"].values, points["u"].values
    with np.errstate(divide="ignore"):
        bound = (1.0 - e) / (2.0 * np.sqrt(2.0 * e))
    return int(np.sum(u > bound))


def side_agreement(points, scan, radius=0.5):
    """side_agreement(points, scan, radius=0.5) -> (float, int)

    The share of the pixel centres of ``scan`` whose word equals the word on
    their side of the nearest border point (distances in pixels; the side is
    taken along the point's axis), among the pixels within ``radius`` pixels
    of a border point (every point lies on a segment between two pixel
    centres; farther pixels are inside a region, where the nearest point
    says nothing), and how many pixels that is.  A pixel disagrees where a
    region narrower than a pixel lies between it and its neighbour: its
    side of the border found is that region's.  NaN when no pixel is near."""
    from scipy.spatial import cKDTree

    es, us, period, _ = _grid_input(scan)
    E, U = np.meshgrid(es, us)
    E, U = E.ravel(), U.ravel()
    de = (es[-1] - es[0]) / max(es.size - 1, 1) or 1.0
    du = (us[-1] - us[0]) / max(us.size - 1, 1) or 1.0
    if points.sizes.get("point", 0) == 0:
        return math.nan, 0
    tree = cKDTree(np.column_stack([points["e"].values / de, points["u"].values / du]))
    dist, k = tree.query(np.column_stack([E / de, U / du]))
    near = dist <= radius
    if not near.any():
        return math.nan, 0
    words = _words(E[near], U[near], period[near])
    k = k[near]
    along_e = points["axis"].values[k] == "e"
    x = np.where(along_e, E[near], U[near])
    low = x < np.where(along_e, points["e"].values[k], points["u"].values[k])
    side = np.where(low, points["word_low"].values[k], points["word_high"].values[k])
    return float(np.mean(side == words)), int(near.sum())


# --------------------------------------------------------------------------- #
# Self-similarity on the exact borders                                        #
# --------------------------------------------------------------------------- #


def band_similarity(n=(2, 3, 4, 5, 6), repeats=(2, 3), *, resolution=256):
    """band_similarity(n=(2, ..., 6), repeats=(2, 3), *, resolution=256) -> dict

    Self-similarity between the bands ``sqrt((n-1)/2) < u <= sqrt(n/2)`` of
    Figs. 5a-c, measured on exact borders: in band n, the region of the word
    ``(n, ..., n)`` (``m`` letters, m in ``repeats``; the first members of the
    family the band shows), its area and its corner of largest e (its tip),
    and the ratios of both between consecutive bands.  A constant scale factor
    would make each row of ratios constant.

    Returns a dict ``{m: {"n": [...], "area": [...], "tip_e": [...],
    "tip_u": [...], "area_ratio": [...], "tip_ratio": [...]}}`` and
    ``"tongue_tip_ratio"``, the ratio e_{n+1}/e_n of Theorem 3.1's tips.
    """
    ns = [check_count("n", k, 2, 50) for k in n]
    out = {}
    for m in repeats:
        m = check_count("repeats", m, 1, 20)
        rows = {"n": [], "area": [], "area_error": [], "tip_e": [], "tip_u": []}
        for k in ns:
            lo, hi = math.sqrt((k - 1) / 2.0), math.sqrt(k / 2.0)
            tip = (math.sqrt(k) - math.sqrt(k - 1)) ** 2
            r = word_region((k,) * m, e=(1e-9, min(0.999, 2.0 * tip)), u=(lo, hi),
                            resolution=resolution, max_iter=max(1000, 2 * k * m))
            xs = [(c.e, c.u) for c in r.corners if c.events[0][0] != "window" or
                  c.events[1][0] != "window"]
            te, tu = max(xs) if xs else (math.nan, math.nan)
            rows["n"].append(k)
            rows["area"].append(r.area)
            rows["area_error"].append(r.area_error)
            rows["tip_e"].append(te)
            rows["tip_u"].append(tu)
        rows["area_ratio"] = [b / a if a else math.nan for a, b in zip(rows["area"], rows["area"][1:])]
        rows["tip_ratio"] = [b / a if a else math.nan for a, b in zip(rows["tip_e"], rows["tip_e"][1:])]
        out[m] = rows
    tips = [(math.sqrt(k) - math.sqrt(k - 1)) ** 2 for k in ns]
    out["tongue_tip_ratio"] = [b / a for a, b in zip(tips, tips[1:])]
    return out
