"""What a tap shows at one point of the plane: the pixel it falls in
(:func:`pixel_of`), the word, orbit and motion there (:func:`point_details`)
and the orbit diagram along u (:func:`orbit_along_u`).

Pure Python, no Panel or Bokeh; :mod:`stairbounce.explorer.view` re-exports
everything here.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .. import orbits, plane
from ..cascades import family_of
from ..model import check_e, check_u
from ..symbolic import sliding_answer
from ..trajectory import trajectory
from .window import View


def pixel_of(view: View, e: float, u: float) -> tuple[int, int] | None:
    """Indices ``(row along u, column along e)`` of the pixel containing ``(e, u)``,
    or ``None`` outside the window."""
    if not (view.e_lo <= e <= view.e_hi and view.u_lo <= u <= view.u_hi):
        return None
    j = min(view.width - 1, int((e - view.e_lo) / (view.e_hi - view.e_lo) * view.width))
    i = min(view.height - 1, int((u - view.u_lo) / (view.u_hi - view.u_lo) * view.height))
    return i, j


# --------------------------------------------------------------------------- #


def point_details(e: float, u: float, max_iter: int, steps: int | None = None,
                  max_steps: int = 2000) -> dict:
    """point_details(e, u, max_iter, steps=None, max_steps=2000) -> dict

    What a tap on ``(e, u)`` shows: the word of the periodic sliding solution
    through (1, 0) (:func:`stairbounce.sliding_word`, ``None`` when it does
    not slide within ``max_iter`` steps) and ``"answer"``, the
    :class:`stairbounce.SlidingAnswer` saying whether Corollary 2.1 proves
    that it never slides, for a point that does not slide its
    motion (:func:`stairbounce.nonsliding.motion`, ``max_iter`` transient and kept
    steps: <k>, exponents) and last Poincare iterates (``"motion"``,
    ``"section"``; ``None`` otherwise), and the exact trajectory from (1, 0)
    over ``steps`` steps (default: one full period and two more steps, at
    least 4 and at most ``max_steps``; 12 when it does not slide) sampled for
    drawing (at most about 40 000 points), with its impacts, accumulation
    points and slides; ``"family"``: the word's family by its form
    (:func:`stairbounce.family_of`, ``None`` without a repeated block or a word).
    """
    e, u = check_e(e), check_u(u)
    answer = sliding_answer(e, u, max_iter=max_iter)
    w = answer.word
    mo, section = _point_motion(e, u, max_iter) if w is None else (None, None)
    if steps is None:
        steps = 12 if w is None else int(min(max_steps, max(4, w.period + 2)))
    traj = trajectory(e, u, 1.0, 0.0, steps)
    per_step = max(10, min(200, 40_000 // steps))
    t = np.linspace(0.0, traj.duration, per_step * steps + 1)
    t = np.union1d(t, [i.time for i in traj.impacts if i.time <= traj.duration])
    x, y = traj.position(t)
    return {
        "e": e,
        "u": u,
        "word": w,
        "answer": answer,
        "steps": steps,
        "path": (x, y),
        "impacts": (np.array([i.x for i in traj.impacts]), np.array([i.y for i in traj.impacts])),
        "accumulations": (
            np.array([a.x for a in traj.accumulations]),
            np.array([a.y for a in traj.accumulations]),
        ),
        "slides": [(s.x_start, s.x_end, s.y) for s in traj.slides],
        "motion": mo,
        "section": section,
        "family": None if w is None else family_of(w),
    }


# Points of the Poincare section sent to the page after a tap
_SECTION_POINTS = 2000


def _point_motion(e, u, max_iter):
    """:func:`stairbounce.nonsliding.motion` of a non-sliding point (``max_iter``
    transient and kept steps), and the last kept Poincare iterates ``(y, v)``."""
    from ..model import iterate
    from ..nonsliding import motion

    steps = max(2, max_iter)
    r = motion(e, u, steps=steps, transient=max_iter)
    if r["slides"]:
        return r, None
    ys, vs, _ = iterate(1.0, 0.0, e, u, max_iter + steps)
    keep = min(steps, _SECTION_POINTS)
    return r, (ys[-keep:], vs[-keep:])


def orbit_along_u(e: float, u_lo: float, u_hi: float, n: int = 300, transient: int = 2000,
                  keep: int = 200) -> xr.Dataset:
    """orbit_along_u(e, u_lo, u_hi, n=300, transient=2000, keep=200) -> xarray.Dataset

    The orbit diagram of Section 4 (Figs. 8, 9) at restitution ``e`` over ``n``
    pixel centres of ``[u_lo, u_hi]``: :func:`stairbounce.orbits.orbit_diagram`
    from the paper's ``(y0, v0) = (0.1, 0)``.
    """
    us = plane.pixel_centres(u_lo, u_hi, n)
    return orbits.orbit_diagram(e, us, y0=0.1, v0=0.0, transient=transient, keep=keep)
