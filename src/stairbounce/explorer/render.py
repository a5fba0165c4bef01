"""The scan of a view: computed whole (:func:`compute_view`) or one bounded
slice at a time for the server's scheduler (:func:`render_slices`,
:func:`grid_scan_slices`), and the picture of a render in progress
(:class:`Partial`, :func:`preview_rgba`).

Pure Python, no Panel or Bokeh; :mod:`stairbounce.explorer.view` re-exports
everything here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

from .. import plane
from .colors import NOT_COMPUTED_COLOR, _rgba32, shade
from .window import (
    COARSE,
    MOTION_COLOR_VARS,
    PREVIEW_WORK,
    SLICE_WORK,
    Cancelled,
    View,
    check_view,
)


@dataclass
class Partial:
    """A render in progress, yielded by :func:`render_slices` after each slice.

    ``coarse``: scans of bands of the coarse grid, every ``step``-th pixel
    centre of both axes from offset ``step // 2`` (empty when the view skips
    the preview); ``parts``: the scans of the first ``rows_done`` rows, in order.
    """

    view: View
    coarse: list
    parts: list
    rows_done: int
    step: int = COARSE

    @property
    def fraction(self) -> float:
        return self.rows_done / self.view.height


def render_slices(view: View, slice_work: int | None = None, coarse: int = COARSE,
                  preview_work: int | None = None):
    """render_slices(view, slice_work=SLICE_WORK, coarse=COARSE, preview_work=PREVIEW_WORK) -> generator

    The scan of a view computed one bounded slice at a time.

    A generator: each ``next()`` computes one slice and yields the
    :class:`Partial` so far; the generator's return value (``StopIteration.value``)
    is the finished dataset, equal bit for bit to :func:`stairbounce.plane.scan`
    on the view's window (pixels are independent, so scanning rows of
    :func:`~stairbounce.plane.pixel_centres` in bands changes nothing).

    First, when the view costs more than ``preview_work`` map steps, the
    coarse preview: every ``coarse``-th pixel centre of both axes (exact
    values of those pixels, 1/coarse^2 of the work); then the full grid.
    Both in bands of rows of at most ``slice_work`` potential map steps
    (``max_iter`` per pixel), a row over it in pieces of at most that
    (:func:`_bands`; one pixel at least).  A view coloured by a motion
    field (:data:`MOTION_COLOR_VARS`) also has the fields of
    :func:`stairbounce.nonsliding.motion_coords` in every band (``max_iter``
    transient and ``max_iter`` kept steps, 3 ``max_iter`` per pixel in all),
    so it is cut into slices and cancelled like any render.

    Raises :class:`ValueError` from :func:`check_view` for a view over budget.
    """
    check_view(view)
    slice_work = SLICE_WORK if slice_work is None else slice_work
    preview_work = PREVIEW_WORK if preview_work is None else preview_work
    es = plane.pixel_centres(view.e_lo, view.e_hi, view.width)
    us = plane.pixel_centres(view.u_lo, view.u_hi, view.height)

    motion = view.color in MOTION_COLOR_VARS
    # a motion field costs max_iter transient + max_iter kept steps per pixel
    per_pixel = view.max_iter * (3 if motion else 1)

    def compute(e, u):
        band = plane.scan_coords(e, u, max_iter=view.max_iter)
        return _with_motion(band, view, e, u) if motion else band

    pre = []
    if coarse > 1 and view.work > preview_work and min(view.width, view.height) >= 2 * coarse:
        off = coarse // 2
        for _, band in _bands(es[off::coarse], us[off::coarse], per_pixel, slice_work, compute):
            if band is not None:
                pre.append(band)
            yield Partial(view, pre, [], 0, coarse)
    parts, rows = [], 0
    for done, band in _bands(es, us, per_pixel, slice_work, compute):
        if band is not None:
            parts.append(band)
            rows = done
        if done < view.height or band is None:
            yield Partial(view, pre, parts, rows, coarse)
    ds = parts[0] if len(parts) == 1 else xr.concat(parts, dim="u", combine_attrs="override")
    ds.attrs.update(
        e_min=view.e_lo, e_max=view.e_hi, n_e=view.width,
        u_min=view.u_lo, u_max=view.u_hi, n_u=view.height,
    )
    return ds


def _bands(es, us, per_pixel, slice_work, compute):
    """The grid ``us x es`` computed by ``compute(e, u) -> Dataset`` in blocks of
    at most ``slice_work`` potential map steps (``per_pixel`` each;
    :func:`stairbounce.structure.borders.grid_blocks`): yields ``(rows done, band)``
    after each block, ``band`` the Dataset of the rows just completed, or
    ``None`` after a piece of a row (pixels are independent: the pieces
    joined along ``e`` are the row bit for bit)."""
    from ..structure.borders import grid_blocks

    pieces = []
    for r, c in grid_blocks(es.size, us.size, per_pixel, slice_work):
        pieces.append(compute(es[c], us[r]))
        if c.stop < es.size:
            yield r.start, None
            continue
        band = pieces[0] if len(pieces) == 1 else xr.concat(pieces, dim="e", combine_attrs="override")
        pieces = []
        yield r.stop, band


def grid_scan_slices(e, u, max_iter, slice_work=None):
    """grid_scan_slices(e=(lo, hi, n), u=(lo, hi, n), max_iter, slice_work=SLICE_WORK) -> generator, returning xarray.Dataset

    :func:`stairbounce.plane.scan_coords` of the window's pixel centres in
    blocks of at most ``slice_work`` potential map steps (:func:`_bands`),
    yielding ``(rows done, rows)`` after each; returns the scan with the
    window's attributes (as :func:`stairbounce.scan`'s), which the border
    points and the word table read.
    """
    slice_work = SLICE_WORK if slice_work is None else slice_work
    es, us = plane.pixel_centres(*e), plane.pixel_centres(*u)
    parts = []
    for done, band in _bands(es, us, max_iter, slice_work,
                             lambda a, b: plane.scan_coords(a, b, max_iter=max_iter)):
        if band is not None:
            parts.append(band)
        yield done, us.size
    ds = parts[0] if len(parts) == 1 else xr.concat(parts, dim="u", combine_attrs="override")
    ds.attrs.update(e_min=float(e[0]), e_max=float(e[1]), n_e=int(e[2]),
                    u_min=float(u[0]), u_max=float(u[1]), n_u=int(u[2]))
    return ds


def compute_view(view: View, cancelled=None, progress=None) -> xr.Dataset:
    """compute_view(view, cancelled=None, progress=None) -> xarray.Dataset

    The scan of a view: :func:`stairbounce.plane.scan` on its window and pixels.

    Runs :func:`render_slices` to the end (same values bit for bit as one
    call of ``scan``; the dataset carries the same attributes).  Between
    slices ``cancelled()`` is asked whether a newer request superseded this
    one (then :class:`Cancelled` is raised) and ``progress(done, total)`` is
    told how many rows are done.

    Raises :class:`ValueError` from :func:`check_view` for a view over budget.
    """
    gen = render_slices(view)
    while True:
        if cancelled is not None and cancelled():
            gen.close()
            raise Cancelled
        try:
            part = next(gen)
        except StopIteration as stop:
            ds = stop.value
            if progress is not None:
                progress(view.height, view.height)
            return ds
        if progress is not None:
            progress(part.rows_done, view.height)


def preview_rgba(part: Partial, var: str) -> np.ndarray:
    """preview_rgba(part, var) -> uint32 array (n_u, n_e)

    The picture of a render in progress: the rows already computed at full
    resolution, the others from the coarse preview (each coarse sample
    painted over the ``step x step`` block of pixels around it), and
    the not-yet-computed colour where there is neither.
    """
    v, c = part.view, part.step
    out = np.full((v.height, v.width), _rgba32((NOT_COMPUTED_COLOR,))[0], dtype=np.uint32)
    row = 0
    for band in part.coarse:
        block = np.repeat(np.repeat(shade(band, var), c, axis=0), c, axis=1)
        rows = min(block.shape[0], v.height - row)
        if rows <= 0:
            break
        # the last block column (row) covers what is left of a side not divisible by step
        block = np.pad(block, ((0, 0), (0, max(0, v.width - block.shape[1]))), mode="edge")
        out[row : row + rows] = block[:rows, : v.width]
        row += rows
    n_coarse = len(range(c // 2, v.height, c))
    if part.coarse and sum(b.sizes["u"] for b in part.coarse) == n_coarse and 0 < row < v.height:
        out[row:] = out[row - 1]  # a side not divisible by step: its last block is taller
    row = 0
    for p in part.parts:
        n = p.sizes["u"]
        out[row : row + n] = shade(p, var)
        row += n
    return out


def _with_motion(ds, view, es, us):
    """``ds`` (a band of rows) with the fields of
    :func:`stairbounce.nonsliding.motion_coords` (``max_iter`` transient +
    ``max_iter`` kept steps) at the same pixel centres."""
    from ..nonsliding import motion_coords

    m = motion_coords(es, us, steps=max(2, view.max_iter), transient=view.max_iter)
    return ds.assign({k: m[k] for k in m.data_vars}).assign_attrs(motion_steps=m.attrs["steps"])
