"""Axes in metres and m/s for data computed on a real staircase.

The data stay in the paper's normalised units (so every overlay, drawn in
those units, stays where it belongs); only the ticks move: an axis drawn in
``u`` is ticked at round m/s (``U = u b / sqrt(a/g)``), heights at round
metres (``y a``), vertical velocities at round m/s (``v sqrt(a g)``).
"""

from __future__ import annotations

from ..units import Staircase


def scaled_axis(axis, factor):
    """Tick ``axis`` (drawn in normalised units) at round values of ``factor`` times them."""
    from matplotlib.ticker import FuncFormatter, Locator, MaxNLocator

    class ScaledLocator(Locator):
        def __init__(self):
            self._inner = MaxNLocator(nbins="auto", steps=[1, 2, 2.5, 5, 10])

        def set_axis(self, axis):
            super().set_axis(axis)
            self._inner.set_axis(axis)

        def __call__(self):
            lo, hi = self.axis.get_view_interval()
            return self.tick_values(lo, hi)

        def tick_values(self, vmin, vmax):
            return [t / factor for t in self._inner.tick_values(vmin * factor, vmax * factor)]

    axis.set_major_locator(ScaledLocator())
    axis.set_major_formatter(FuncFormatter(lambda x, _pos: f"{x * factor:.4g}"))


def staircase(ds) -> Staircase | None:
    """The staircase a dataset was computed on (its attributes), or None."""
    return Staircase.from_attrs(ds.attrs)


SPEED_LABEL = "U (horizontal speed, m/s)"


def speed_axis(axis, stairs: Staircase):
    """An axis drawn in ``u``, ticked and labelled in m/s."""
    scaled_axis(axis, stairs.speed_unit)
    axis.set_label_text(SPEED_LABEL)


def describe(stairs: Staircase) -> str:
    """``a = 0.17 m, b = 0.28 m`` (and g when it is not 9.81) for titles."""
    return (f"a = {stairs.step_height:g} m, b = {stairs.step_length:g} m"
            + ("" if stairs.g == 9.81 else f", g = {stairs.g:g} m/s^2"))


def path_in_metres(ax, stairs: Staircase, u: float):
    """The ball's path (Fig. 1, drawn in steps) ticked in metres (``x b``,
    ``y a``) with the staircase's true aspect, and a clock on the top axis:
    horizontal motion is uniform, ``t = x / u`` time units of ``sqrt(a/g)`` s."""
    a, b = stairs.step_height, stairs.step_length
    scaled_axis(ax.xaxis, b)
    scaled_axis(ax.yaxis, a)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("height (m)")
    ax.set_aspect(a / b, adjustable="box")
    seconds_per_x = stairs.time_unit / u
    top = ax.secondary_xaxis("top", functions=(lambda x: x * seconds_per_x, lambda t: t / seconds_per_x))
    top.set_xlabel("t (s)")
    ax.set_title(f"{ax.get_title()}  (U = {u * stairs.speed_unit:.3g} m/s, a = {a:g} m, "
                 f"b = {b:g} m)", fontsize="medium")


def staircase_given(obj, name="staircase") -> Staircase | None:
    """The staircase of a plot's ``staircase`` argument: a :class:`Staircase`,
    an object carrying one in its ``staircase`` attribute (a ``Speed``, a
    ``Trajectory``; None there means normalised units), or None."""
    stairs = getattr(obj, "staircase", obj) if not isinstance(obj, Staircase) else obj
    if stairs is None or isinstance(stairs, Staircase):
        return stairs
    raise ValueError(f"{name} must be a stairbounce.Staircase or an object carrying one (a speed made by "
                     f"Staircase.speed, a Trajectory), got {type(obj).__name__}")


def section_in_metres(ax, stairs: Staircase):
    """Tick a Poincare section (drawn in normalised y, v) in metres and m/s."""
    scaled_axis(ax.xaxis, stairs.step_height)
    scaled_axis(ax.yaxis, stairs.velocity_unit)
    ax.set_xlabel("height at the edge (m)")
    ax.set_ylabel("vertical velocity at the edge (m/s)")
    ax.set_title(f"{ax.get_title()} ({describe(stairs)})", fontsize="medium")


def frame_plane(ax, ds, e_lo, e_hi, u_lo, u_hi):
    """The frame of an (e, u) picture (the scan's and the motion's): limits,
    axis labels, and the physical speed axis when ``ds`` carries a staircase
    (:func:`staircase`); returns that staircase, or None."""
    ax.set_xlim(e_lo, e_hi)
    ax.set_ylim(u_lo, u_hi)
    ax.set_xlabel("e (restitution coefficient)")
    ax.set_ylabel("u (horizontal speed)")
    stairs = staircase(ds)
    if stairs is not None:
        speed_axis(ax.yaxis, stairs)
    return stairs
