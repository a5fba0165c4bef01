"""Orbit diagrams (often called bifurcation diagrams): Section 4 of the paper.

Fix one of the parameters ``e``, ``u``, sweep the other, iterate the Poincare
map of Prop. 2.3 from one initial state, throw away a transient and keep the
next iterates: the kept heights (or velocities) plotted against the swept
parameter show the attractor at each parameter value.  Inside the ``n``-th
sliding tongue of Theorem 3.1 the orbit settles on the period-``n`` sliding
solution ``(n, 0^inf)``, so the diagram has ``n`` branches there; the paper's
Fig. 8 (``e = 0.001``) and Fig. 9 (``e = 0.1``) are of this kind.

Layout (docs/design.md): a private numba kernel iterates all parameter values,
:func:`orbit_diagram` validates, allocates, calls it and labels the result as
an :class:`xarray.Dataset`; :func:`orbit_density` bins the kept points into a
2-D histogram so that millions of them render as an image.  Nothing here
plots.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr
from numba import get_num_threads, njit, prange

from ._version import __version__
from . import _validate as _v
from ._interrupt import halted
from .model import _constants, _step, check_count, check_state
from .units import SpeedWindow, staircase_of, with_speed

__all__ = ["orbit_diagram", "orbit_density"]

# Each parallel work item takes every _chunks-th parameter value, so every
# item samples the whole sweep and costs about the same even where the cost of
# a step varies along it (more impacts per step at low u); several items per
# thread let a thread that was delayed by other processes be caught up.
_ITEMS_PER_THREAD = 8

_LONG_NAMES = {
    "e": "restitution coefficient e",
    "u": "horizontal speed u",
    "y": "height y at the step edge",
    "v": "vertical velocity v at the step edge",
}


# --------------------------------------------------------------------------- #
# Kernels                                                                     #
# --------------------------------------------------------------------------- #


# The kernels read their halt flag (Ctrl-C, stairbounce._interrupt) once per
# slice of this many map steps: a few milliseconds of work.
_SLICE = 1 << 16


@njit(cache=True)
def _orbit_row(e, u, y, v, transient, keep, ys, vs, ks, i, halt):
    """Iterate one parameter pair: skip ``transient`` steps, store ``keep``.
    Returns early (row incomplete) once ``halt[0]`` is set."""
    T, ratio = _constants(e, u)
    done = 0
    while done < transient:  # in slices, each the same steps in the same order
        if halted(halt):
            return y, v
        for _ in range(min(_SLICE, transient - done)):
            y, v, k = _step(y, v, e, T, ratio)
        done += _SLICE
    for j in range(keep):
        if (j & (_SLICE - 1)) == 0 and halted(halt):
            return y, v
        y, v, k = _step(y, v, e, T, ratio)
        ys[i, j] = y
        vs[i, j] = v
        ks[i, j] = k
    return y, v


@njit(parallel=True, cache=True, nogil=True)
def _orbit_kernel(es, us, y0, v0, transient, keep, ys, vs, ks, items, halt):
    """Every parameter pair ``(es[i], us[i])`` from ``(y0, v0)``, in parallel.

    The pairs are independent; work item ``c`` takes pairs ``c, c + items,
    c + 2 items, ...`` (interleaved, so all items cost about the same).
    Stops early once ``halt[0]`` is set (the outputs are then dropped).
    """
    n = es.size
    for c in prange(items):
        for i in range(c, n, items):
            _orbit_row(es[i], us[i], y0, v0, transient, keep, ys, vs, ks, i, halt)


@njit(cache=True, nogil=True)
def _orbit_kernel_warm(es, us, y0, v0, transient, keep, ys, vs, ks, items, halt):
    """Like :func:`_orbit_kernel`, but pair ``i`` starts where pair ``i-1``
    ended, so the pairs are iterated one after the other (``items`` unused)."""
    y, v = y0, v0
    for i in range(es.size):
        if halted(halt):
            return
        y, v = _orbit_row(es[i], us[i], y, v, transient, keep, ys, vs, ks, i, halt)


# --------------------------------------------------------------------------- #
# Validation                                                                  #
# --------------------------------------------------------------------------- #


def _parameter(name, value):
    """``value`` as a float64 array and whether it was given as a 1-D array."""
    if isinstance(value, SpeedWindow):
        raise ValueError(f"{name} must be a speed or an array of speeds, got a scan window {value!r}: "
                         "pass staircase.speed(np.linspace(lo, hi, n))")
    a = np.asarray(_v.real_array(name, value))
    if a.ndim > 1:
        raise ValueError(f"{name} must be a real number or a 1-D array, got an array of shape {a.shape}")
    if a.ndim == 1 and a.size == 0:
        raise ValueError(f"{name} must be a non-empty 1-D array")
    bad = ~np.isfinite(a)
    if name == "e":
        tiny = _v.e_too_small(a)
        bad |= ~((a >= 0.0) & (a < 1.0)) | tiny
        rule = _v.E_TINY_RULE if np.any(tiny) else "e (restitution coefficient) must be in [0, 1)"
    else:
        bad |= ~((a >= _v.U_MIN) & (a <= _v.U_MAX))
        rule = f"u (horizontal speed) must be finite and > 0, in [{_v.U_MIN:g}, {_v.U_MAX:g}]"
    if np.any(bad):
        if a.ndim == 0:
            raise ValueError(f"{rule}, got {float(a)}")
        i = int(np.flatnonzero(bad)[0])
        raise ValueError(f"{rule}, got {a[i]} at index {i}")
    return a, a.ndim == 1


# --------------------------------------------------------------------------- #
# Public API                                                                  #
# --------------------------------------------------------------------------- #


def orbit_diagram(e, u, y0=0.1, v0=0.0, transient=2000, keep=200, warm_start=False):
    """orbit_diagram(e, u, y0=0.1, v0=0.0, transient=2000, keep=200, warm_start=False) -> xarray.Dataset

    Orbit diagram (bifurcation diagram) of the Poincare map over one parameter.

    For each value ``p`` of the swept parameter (``e`` or ``u``; the other is
    fixed), iterate ``x_{n+1} = P(x_n)`` with ``x_0 = (y0, v0)`` and the
    Poincare map ``P`` of Prop. 2.3, discard ``x_1 .. x_transient`` and keep
    ``x_{transient+1} .. x_{transient+keep}``.  Inside the ``n``-th tongue of
    Theorem 3.1, ``(n-1)/2 < u^2 <= n/2 ((1-e)/(1+e))^2``, the kept iterates
    are the ``n`` points of the sliding solution ``(n, 0^inf)``; new branches
    appear where ``u`` enters a new tongue (grazing bifurcations, Section 4).

    The paper's Figs. 8 and 9: ``e = 0.001`` and ``0.1``, ``u`` swept,
    ``(y0, v0) = (0.1, 0)``, iterates 2000 to 2200 of ``y`` (the defaults).

    Computed by the private numba kernel ``_orbit_kernel``, parallel over the
    parameter values (interleaved work items for load balance), with the fast
    map ``model._step``.  With ``warm_start=True`` the kernel is
    ``_orbit_kernel_warm``, which is necessarily sequential: each parameter
    value starts from the previous one's last state.

    Parameters
    ----------
    e : float in [0, 1), or 1-D array of them
        Restitution coefficient.
    u : float > 0, or 1-D array of them
        Horizontal speed.  Exactly one of ``e``, ``u`` is a 1-D array (in any
        order, repeats allowed): the swept parameter.
    y0 : float >= 0, default 0.1
        Initial height above the floor of the step being entered.
    v0 : float, default 0.0
        Initial vertical velocity.
    transient : int >= 0, default 2000
        Iterates discarded at each parameter value.
    keep : int >= 1, default 200
        Iterates kept at each parameter value.
    warm_start : bool, default False
        Start each parameter value (in the given order) from the last state of
        the previous one, as DynamicalSystems.jl's ``orbitdiagram`` does,
        instead of from ``(y0, v0)``; the transient is still discarded at every
        value.  This follows one attractor along the sweep.

    Returns
    -------
    xarray.Dataset
        Data variables ``y``, ``v`` (float64) and ``impacts`` (int32: impacts
        on the step that led to the iterate, 0 for a flight over the step,
        ``SLIDING`` = -1 when the impacts accumulated), dimensions
        ``(p, "iterate")`` where ``p`` is ``"e"`` or ``"u"``.  Coordinates:
        the swept values, ``iterate`` = ``transient+1 .. transient+keep`` (the
        power ``n`` of ``P^n``), and the fixed parameter as a scalar.
        Attributes record every input (``varied``, the fixed parameter,
        ``y0``, ``v0``, ``transient``, ``keep``, ``warm_start`` as 0/1) and
        ``stairbounce_version``.  The last state of a row is its last kept
        iterate.
    """
    ea, e_swept = _parameter("e", e)
    ua, u_swept = _parameter("u", u)
    if e_swept == u_swept:
        raise ValueError(
            "exactly one of e, u must be a 1-D array (the swept parameter) and the other "
            f"a float, got {'two arrays' if e_swept else 'two floats'}"
        )
    y0, v0 = check_state(y0, v0, "y0", "v0")
    transient = check_count("transient", transient, 0)
    keep = check_count("keep", keep, 1)
    warm_start = _v.flag("warm_start", warm_start)

    varied, fixed = ("e", "u") if e_swept else ("u", "e")
    values = ea if e_swept else ua
    fixed_value = float(ua if e_swept else ea)
    n = values.size
    # y and v (float64) and impacts (int32) for every kept iterate, and the coordinates
    _v.check_memory(f"keep = {keep} iterates of {n} parameter values", n * keep * 20 + 24 * n + 8 * keep)
    # copies, writeable: a view of broadcast_to is read-only, and a read-only array is
    # another signature of the kernel, compiled again (one a sweep's direction)
    es = np.array(np.broadcast_to(ea, (n,)), dtype=np.float64)
    us = np.array(np.broadcast_to(ua, (n,)), dtype=np.float64)
    ys = np.empty((n, keep))
    vs = np.empty((n, keep))
    ks = np.empty((n, keep), dtype=np.int32)
    kernel = _orbit_kernel_warm if warm_start else _orbit_kernel
    items = min(n, _ITEMS_PER_THREAD * get_num_threads())
    from ._interrupt import run_kernel

    # in a helper thread when called from the main thread: Ctrl-C stops it at once
    run_kernel(kernel, es, us, y0, v0, transient, keep, ys, vs, ks, items)


    dims = (varied, "iterate")
    ds = xr.Dataset(
        {
            "y": (dims, ys, {"long_name": _LONG_NAMES["y"]}),
            "v": (dims, vs, {"long_name": _LONG_NAMES["v"]}),
            "impacts": (
                dims,
                ks,
                {"long_name": "impacts on the step that led to the iterate (-1: sliding)"},
            ),
        },
        coords={
            varied: (varied, values.copy(), {"long_name": _LONG_NAMES[varied]}),
            "iterate": (
                "iterate",
                np.arange(transient + 1, transient + keep + 1),
                {"long_name": "n in P^n(y0, v0)"},
            ),
            fixed: ((), fixed_value, {"long_name": _LONG_NAMES[fixed]}),
        },
        attrs={
            "title": f"orbit diagram of the staircase Poincare map, {fixed} = {fixed_value:g}",
            "varied": varied,
            fixed: fixed_value,
            "y0": y0,
            "v0": v0,
            "transient": transient,
            "keep": keep,
            "warm_start": int(bool(warm_start)),
            "stairbounce_version": __version__,
        },
    )
    return with_speed(ds, staircase_of(u), "u")


def _varied(ds):
    """Name of the swept parameter of an :func:`orbit_diagram` dataset."""
    varied = ds.attrs.get("varied")
    if varied not in ("e", "u") or varied not in ds.dims:
        raise ValueError("ds must be a dataset returned by orbit_diagram (attribute varied = 'e' or 'u')")
    return varied


def _check_range(name, value):
    if not isinstance(value, (tuple, list, np.ndarray)) or len(value) != 2:
        raise ValueError(f"{name} must be a pair (min, max) of finite numbers, got {value!r}")
    lo, hi = (_v.real(name, x) for x in value)
    # hi - lo must be a float too: the bin edges are lo + i (hi - lo) / bins
    if not (lo < hi and math.isfinite(hi - lo)):
        raise ValueError(
            f"{name} must be a pair (min, max) of finite numbers with min < max and "
            f"max - min finite, got {value!r}"
        )
    return lo, hi


def _span(lo, hi, bins):
    """Bin edges for data spanning [lo, hi]; a single value gets a unit-wide
    range around it (numpy's convention), evenly spaced values one bin each
    when ``bins`` equals their number."""
    if lo == hi:
        return lo - 0.5, hi + 0.5
    if bins > 1:
        half = 0.5 * (hi - lo) / (bins - 1)
        return lo - half, hi + half
    return lo, hi


def orbit_density(ds, bins=400, component="y", range=None, param_bins=None):
    """orbit_density(ds, bins=400, component="y", range=None, param_bins=None) -> xarray.DataArray

    Two-dimensional histogram of an orbit diagram: how many kept iterates fall
    in each (parameter, component) cell.

    ``count[i, j] = #{(p, n) : p in parameter bin i, x_n(p) in value bin j}``
    with uniform bins, so millions of points render as one image (the
    datashader idea: aggregate first, shade separately).  Points outside the
    value range, and non-finite ones, are not counted; the attribute
    ``points_in_range`` says how many were.

    Parameters
    ----------
    ds : xarray.Dataset
        Output of :func:`orbit_diagram`.
    bins : int >= 1, default 400
        Bins along the component.
    component : "y" or "v", default "y"
        Which component of the iterates to bin (the paper plots ``y``).
    range : (float, float) or None, default None
        Value range ``(min, max)`` of the component; None: the range of the
        finite data.
    param_bins : int >= 1 or None, default None
        Bins along the swept parameter, spanning its values; None: one bin per
        parameter value (centred on them when they are evenly spaced).

    Returns
    -------
    xarray.DataArray
        int64 counts, dimensions ``(p, component)`` with the bin centres as
        coordinates; attributes ``component``, ``range``, ``param_range`` (the
        outer bin edges), ``points``, ``points_in_range`` and the inputs of
        the diagram.  Used for the density images of Section 4 (Figs. 8, 9).
    """
    if not isinstance(ds, xr.Dataset):
        raise ValueError(f"ds must be a dataset returned by orbit_diagram, got {type(ds).__name__}")
    varied = _varied(ds)
    if component not in ("y", "v"):
        raise ValueError(f"component must be 'y' or 'v', got {component!r}")
    bins = check_count("bins", bins, 1)
    params = np.asarray(ds[varied].values, dtype=float)
    if param_bins is None:
        param_bins = params.size
    param_bins = check_count("param_bins", param_bins, 1)
    # the float64 histogram, its int64 copy and the edges
    _v.check_memory(f"bins = {bins} by param_bins = {param_bins}", 16 * bins * param_bins + 16 * (bins + param_bins))
    values = np.asarray(ds[component].values, dtype=float)
    finite = np.isfinite(values)
    if range is None:
        if finite.any():
            range = _span(float(values[finite].min()), float(values[finite].max()), 1)
        else:
            range = (0.0, 1.0)
    range = _check_range("range", range)
    param_range = _span(float(params.min()), float(params.max()), param_bins)

    p = np.broadcast_to(params[:, None], values.shape)[finite]
    x = values[finite]
    counts, _, _ = np.histogram2d(p, x, bins=(param_bins, bins), range=(param_range, range))
    counts = counts.astype(np.int64)

    p_edges = np.linspace(*param_range, param_bins + 1)
    x_edges = np.linspace(*range, bins + 1)
    attrs = {k: v for k, v in ds.attrs.items() if k != "title"}
    attrs.update(
        component=component,
        range=np.array(range),
        param_range=np.array(param_range),
        points=int(values.size),
        points_in_range=int(counts.sum()),
        long_name=f"number of kept iterates per cell ({component})",
    )
    return xr.DataArray(
        counts,
        dims=(varied, component),
        coords={
            # edge + half width: the sum of two edges near 1.8e308 would overflow
            varied: (varied, p_edges[:-1] + 0.5 * np.diff(p_edges), {"long_name": _LONG_NAMES[varied]}),
            component: (component, x_edges[:-1] + 0.5 * np.diff(x_edges), {"long_name": _LONG_NAMES[component]}),
        },
        name="count",
        attrs=attrs,
    )
