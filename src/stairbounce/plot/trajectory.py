"""The ball on the staircase (the paper's Fig. 1) and the Poincare section (Fig. 2)."""

from __future__ import annotations

import numpy as np

from ..model import SLIDING


def _axes(ax, **subplot_kw):
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(7, 4.5), **subplot_kw)
    return ax


def _staircase(steps):
    """Outline of steps -1..steps: edge at x = j, floor of step j at -j."""
    xs, ys = [], []
    for j in range(-1, steps + 1):
        xs += [j, j + 1]
        ys += [-j, -j]
    return np.array(xs, float), np.array(ys, float)


def plot_trajectory(traj, ax=None, samples_per_step=400, show_impacts=True):
    """Draw a :class:`~stairbounce.Trajectory` on the staircase (Fig. 1).

    Flights are drawn from ``traj.position`` on a fine time grid (plus every
    impact time, so the corners are sharp); impacts are dots, accumulation
    points stars, slides thick segments along the floor.  A trajectory
    computed from a speed in m/s (``staircase.speed(U)``) is drawn with its
    axes in metres and a clock in seconds on top.
    """
    ax = _axes(ax)
    sx, sy = _staircase(max(traj.steps, 1))
    ax.fill_between(sx, sy, sy.min() - 0.6, step=None, color="0.88", zorder=0)
    ax.plot(sx, sy, color="0.3", lw=1.2, zorder=1)
    t = np.linspace(0.0, traj.duration, max(2, samples_per_step * max(traj.steps, 1)))
    t = np.union1d(t, [i.time for i in traj.impacts if i.time <= traj.duration])
    x, y = traj.position(t)
    ax.plot(x, y, color="C0", lw=1.3, label="ball", zorder=2)
    if show_impacts and traj.impacts:
        ax.plot([i.x for i in traj.impacts], [i.y for i in traj.impacts], "o", ms=3.5,
                color="C3", label="impacts", zorder=3)
    for s in traj.slides:
        ax.plot([s.x_start, s.x_end], [s.y, s.y], color="C2", lw=3.5, solid_capstyle="butt",
                zorder=3)
    if traj.slides:
        ax.plot([], [], color="C2", lw=3.5, label="sliding")
    if traj.accumulations:
        ax.plot([a.x for a in traj.accumulations], [a.y for a in traj.accumulations], "*",
                ms=11, color="C1", mec="k", mew=0.5, label="accumulation of impacts", zorder=4)
    ax.set_xlabel("x (steps)")
    ax.set_ylabel("height")
    ax.set_title(f"e = {traj.e:g}, u = {traj.u:g}")
    ax.set_aspect("equal", adjustable="box")
    ax.legend(loc="lower left", fontsize="small")
    if getattr(traj, "staircase", None) is not None:  # computed from a speed in m/s
        from ._units import path_in_metres

        path_in_metres(ax, traj.staircase, traj.u)
    return ax


def plot_poincare_section(ys, vs, impacts=None, ax=None, colorbar=True, staircase=None):
    """plot_poincare_section(ys, vs, impacts=None, ax=None, colorbar=True, staircase=None) -> Axes

    Draw Poincare iterates ``(y_n, v_n)`` at consecutive step edges (Fig. 2),
    coloured by the index n (with a colour bar saying so).

    Iterates reached by sliding (``impacts == SLIDING``), which are all the
    point (1, 0), are drawn as a larger marker.  The dashed line ``y = 1`` is
    the edge of the map's domain ``[1, inf) x R``: the height of the step
    just left.

    ``staircase``, a :class:`~stairbounce.Staircase` or what carries one (a
    speed ``stairs.speed(U)``, or the :class:`~stairbounce.Trajectory`
    computed from it), draws the axes in metres and m/s: heights ``y a`` and
    vertical velocities ``v sqrt(a g)``, ticked at round values, and the edge
    is the step height ``a``.  The iterates stay in the paper's normalised
    units, which are the labels without a staircase.
    """
    from ._units import section_in_metres, staircase_given

    stairs = staircase_given(staircase)
    ax = _axes(ax)
    ys, vs = np.asarray(ys), np.asarray(vs)
    if len(ys) <= 40:  # the order of a few iterates helps; of many it is clutter
        ax.plot(ys, vs, color="0.7", lw=0.6, zorder=1)
    sc = ax.scatter(ys, vs, c=np.arange(len(ys)), cmap="viridis", s=10, lw=0, zorder=2)
    # the legend's marker in a neutral colour: the colour itself is the index
    ax.plot([], [], "o", ms=4, color="0.45", label="iterates (colour: index n)")
    if colorbar:
        cb = ax.figure.colorbar(sc, ax=ax, pad=0.02)
        cb.set_label("iterate index n")
    if impacts is not None:
        sl = np.asarray(impacts) == SLIDING
        if sl.any():
            ax.plot(ys[sl], vs[sl], "*", ms=12, color="C1", mec="k", mew=0.5,
                    label="after sliding (1, 0)", zorder=3)
    edge = "y = 1" if stairs is None else f"y = {stairs.step_height:g} m"
    ax.axvline(1.0, color="0.5", lw=0.8, ls="--", label=f"{edge}: edge of the domain of P")
    ax.set_xlabel("y (height at the edge)")
    ax.set_ylabel("v (vertical velocity at the edge)")
    ax.set_title("Poincare section")
    if stairs is not None:
        section_in_metres(ax, stairs)
    ax.legend(loc="best", fontsize="small")
    return ax


def animate_trajectory(traj, path, fps=30, seconds_per_step=0.6, progress=None):
    """animate_trajectory(traj, path, fps=30, seconds_per_step=0.6, progress=None)

    Write an animation of the ball (GIF through Pillow) to ``path``;
    ``progress(done, total)`` is told about every frame written."""
    import matplotlib.pyplot as plt
    from matplotlib.animation import FuncAnimation, PillowWriter

    fig, ax = plt.subplots(figsize=(6, 4))
    plot_trajectory(traj, ax=ax, show_impacts=False)
    frames = max(2, int(fps * seconds_per_step * max(traj.steps, 1)))
    times = np.linspace(0.0, traj.duration, frames)
    xs, ys = traj.position(times)
    (ball,) = ax.plot([xs[0]], [ys[0]], "o", ms=9, color="C3", zorder=5)

    def update(i):
        ball.set_data([xs[i]], [ys[i]])
        return (ball,)

    anim = FuncAnimation(fig, update, frames=frames, blit=True)
    anim.save(str(path), writer=PillowWriter(fps=fps),
              progress_callback=None if progress is None else (lambda i, n: progress(i + 1, n)))
    plt.close(fig)
