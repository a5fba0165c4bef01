"""The explorer inside Jupyter: :func:`inline` returns the page as a Panel object.

In a notebook there is no Bokeh server session to hand results back to, so the
page runs its work where it is asked for (on the kernel's thread) instead of
on the server's worker thread: a render blocks the cell for the second or so
it takes, then the image updates in place.

(Not called ``app``: that name is the module :mod:`stairbounce.explorer.app`,
which the import system binds on the package.)
"""

from __future__ import annotations

from .view import COLOR_VARS, DEFAULT_VIEW, View, check_view

__all__ = ["inline"]


class _Here:
    """An executor that runs submitted work at once, on the calling thread."""

    def submit(self, fn, *args):
        fn(*args)


def _run_here():
    """The keyword that makes an :class:`~.app.Explorer` run its work on the
    calling thread: an executor for the page that takes one, a scheduler run to
    completion on submission for the page that shares a scheduler between
    sessions (the explorer's newer internals)."""
    try:
        from .scheduler import Scheduler
    except ImportError:
        return {"executor": _Here()}

    class _Now(Scheduler):
        def __init__(self):
            super().__init__(thread=False)

        def submit(self, *args, **kwargs):
            job = super().submit(*args, **kwargs)
            self.run_all()
            return job

    return {"scheduler": _Now()}


def inline(e=(0.0, 1.0), u=(0.0, 1.5), width=400, height=400, max_iter=1000, color="word_length", point=None):
    """inline(e=(0, 1), u=(0, 1.5), width=400, height=400, max_iter=1000, color="word_length", point=None) -> panel.layout.FlexBox

    The explorer of ``stairbounce explore`` as a Panel object, for a notebook.

    The first view is computed before the call returns; the returned object
    displays inline in Jupyter (``pn.extension()`` once per notebook), and
    zooming, panning and tapping work there as on the served page.  The same
    limits apply as to a page URL (:func:`stairbounce.explorer.check_view`).

    Parameters
    ----------
    e, u : (lo, hi) or (lo, hi, n), default the paper's Fig. 4 window
        The window of the (e, u) plane, ``0 <= e_lo < e_hi <= 1``,
        ``0 <= u_lo < u_hi``; ``n``: the pixels along that axis (as
        ``width`` or ``height``; giving both is refused).
    width, height : int, default 400
        Pixels along e and along u.
    max_iter : int, default 1000
        Steps before a point counts as having no periodic sliding solution.
    color : str, default ``"word_length"``
        The coloured variable, one of ``word_length``, ``period``, ``impacts``,
        ``jumps``, ``status``, or a non-sliding motion field ``k_mean``,
        ``lyap1`` (computed with the scan).
    point : (e, u) or None
        A point whose word, trajectory and orbit diagram are shown.
    """
    from .app import Explorer

    from .. import _validate as _v

    (e_lo, e_hi, n_e), (u_lo, u_hi, n_u) = _v.window("e", e), _v.window("u", u)
    for n, name, given, default in ((n_e, "width", width, 400), (n_u, "height", height, 400)):
        if n is not None and given != default:
            raise ValueError(f"{name} = {given!r} and the window's pixel count {n!r}: give the pixels once")
    width = width if n_e is None else n_e
    height = height if n_u is None else n_u
    if color not in COLOR_VARS:
        raise ValueError(f"color must be one of {', '.join(COLOR_VARS)}, got {color!r}")
    view = View(float(e_lo), float(e_hi), float(u_lo), float(u_hi), width, height,
                max_iter=max_iter, color=color, overlays=DEFAULT_VIEW.overlays,
                point=None if point is None else (float(point[0]), float(point[1])))
    check_view(view)  # ValueError naming the limit
    explorer = Explorer(view, **_run_here())
    explorer._doc = None  # no server session: results are shown where they are computed
    explorer.start()
    layout = explorer.layout
    layout.explorer = explorer  # for inspection (tests, curious users)
    return layout
