"""Work cut into bounded slices: the pieces the explorer's scheduler and the
tiles run one at a time (:func:`grid_blocks` over a grid of pixels,
:func:`_work_blocks` over a list of items).  A leaf of the structure
package: stairbounce.structure.borders and regions both import it."""

import numpy as np

__all__ = ["grid_blocks"]


def _work_blocks(work, slice_work):
    """Consecutive ``slice(start, stop)`` of the items whose summed ``work`` is at
    most ``slice_work`` (an item over it alone: one item cannot be cut)."""
    work = np.asarray(work, np.int64)
    start, total = 0, 0
    for i, w in enumerate(work.tolist()):
        if i > start and total + w > slice_work:
            yield slice(start, i)
            start, total = i, 0
        total += w
    if start < work.size or work.size == 0:
        yield slice(start, work.size)


def grid_blocks(n_e, n_u, per_pixel, slice_work):
    """grid_blocks(n_e, n_u, per_pixel, slice_work) -> iterator of (rows, cols) slices

    Blocks covering an ``n_u x n_e`` grid of pixels costing ``per_pixel``
    map steps each, in row-major order, of at most ``slice_work`` map steps
    each (one pixel at least): bands of whole rows while a row fits, else
    pieces of one row.
    """
    per_pixel = max(1, int(per_pixel))
    per_row = n_e * per_pixel
    if per_row <= slice_work:
        rows = max(1, min(n_u, slice_work // per_row))
        for s in range(0, n_u, rows):
            yield slice(s, min(n_u, s + rows)), slice(0, n_e)
        return
    cols = max(1, slice_work // per_pixel)
    for i in range(n_u):
        for c in range(0, n_e, cols):
            yield slice(i, i + 1), slice(c, min(n_e, c + cols))
