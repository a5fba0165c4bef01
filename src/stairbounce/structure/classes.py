"""Class-level proofs (issue 44, item 3): a box where every point slides within
``max_iter`` steps, with one of several words, or where no point does.

:func:`certify_box` proves one itinerary over a box; at a decision it cannot take
over the whole box, the box is undecided.  Here both sides of such a decision are
followed (*branches*): the points of the box where the decision goes one way
follow one branch, the others the other.  Along every branch the corners bounds
of the kernel (:func:`_kernel._corners`) stay valid for the points following it:
each step's maps ``v' = v - T + B_k s``, ``s'^2 = 2 + e^(2k) s^2`` (Prop. 2.3,
eq. (2.2)) and every margin ``T - v - C s`` are monotone in ``v, s, e`` and ``T``
(``B_k, C, e^k >= 0``, ``s >= 0``), so upper bounds of ``v, s`` on a set of points
give upper bounds of ``v', s'`` on it, the same for lower bounds, whatever the
itinerary that led there.  A set of branches may therefore be *merged* into one
whose bounds are their hull (the itinerary is then unknown), as the trapping
regions merge cells.

The rule, shared with the checker (``structure/verify_branches.py``, which
follows it with its own arithmetic):

* at each step each live branch takes the slide test, the first impact and the
  later impacts; a decision proven over the branch's bounds is taken, an
  undecided one splits the branch (the slide test: a *leaf*, the branch's
  itinerary ending in the slide, and a branch that goes on);
* after a step, when more than ``max_live`` branches live, they are merged into
  one (itinerary unknown); a leaf of a merged branch fails the box (its word
  could not be named);
* at most ``max_leaves`` leaves and :data:`_NEXT` branches within a step.

The box is proven ``sliding`` (status 4, :data:`certificate.STATUSES`) when no
branch is left after ``max_iter`` steps: every point slides within ``max_iter``
steps, with the word of one of the leaves.  It is proven ``no_slide_within`` when
no leaf was made: no point slides in the first ``max_iter`` steps.  Otherwise
(some leaves, some branches left: the box meets the border of the region sliding
within ``max_iter``, or a cap was hit) it stays undecided.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .._interrupt import halted
from . import _kernel as K
from ._kernel import _dn, _up

SLIDING = 4  # the status code (certificate.STATUSES[4] == "sliding")
# the rule's caps (stored in an atlas's attributes for the checker)
MAX_LIVE = 8
MAX_LEAVES = 32
_NEXT = 64  # branches made within one step
_NODES_PER_STEP = 16  # the itinerary tree's nodes: max_iter * this + 64


@njit(cache=True)
def _node(par, val, nn, parent, value):
    if nn >= par.shape[0]:
        return -1, nn
    par[nn] = parent
    val[nn] = value
    return nn, nn + 1


@njit(cache=True)
def _branch_box(E0, E1, U0, U1, max_iter, cap, max_live, max_leaves, par, val, leaves):
    """Follow every branch over the box ``[E0, E1] x [U0, U1]`` (the module's rule).

    Returns ``(status, n_leaves)``: :data:`SLIDING` with the leaves' nodes in
    ``leaves[:n_leaves]`` (a leaf's itinerary: follow ``par`` from it, reading
    ``val``, to the root -1), ``K.NO_SLIDE_WITHIN`` or ``K.UNDECIDED``.
    """
    Tl = _dn(1.0 / U1)
    Th = _up(1.0 / U0)
    Rh = _up(_up(1.0 + E1) / _dn(1.0 - E1))
    Rl = _dn(_dn(1.0 + E0) / _up(1.0 - E0))
    vh = np.zeros(_NEXT)
    vl = np.zeros(_NEXT)
    sh = np.zeros(_NEXT)
    sl = np.zeros(_NEXT)
    nd = np.full(_NEXT, -1, np.int64)
    mg = np.zeros(_NEXT, np.bool_)
    xvh = np.zeros(_NEXT)
    xvl = np.zeros(_NEXT)
    xsh = np.zeros(_NEXT)
    xsl = np.zeros(_NEXT)
    xnd = np.full(_NEXT, -1, np.int64)
    xmg = np.zeros(_NEXT, np.bool_)
    live = 1
    sh[0] = _up(math.sqrt(2.0))
    sl[0] = _dn(math.sqrt(2.0))
    nn = 0
    nl = 0
    for n in range(max_iter):
        nx = 0
        for b in range(live):
            bvh, bvl, bsh, bsl, bnd, bmg = vh[b], vl[b], sh[b], sl[b], nd[b], mg[b]
            lo = _dn(_dn(Tl - bvh) - _up(Rh * bsh))
            hi = _up(_up(Th - bvl) - np.maximum(_dn(Rl * bsl), 0.0))
            if not hi < 0.0:  # may slide: a leaf
                if bmg or nl >= max_leaves:
                    return K.UNDECIDED, nl
                leaf, nn = _node(par, val, nn, bnd, -1)
                if leaf < 0:
                    return K.UNDECIDED, nl
                leaves[nl] = leaf
                nl += 1
                if lo >= 0.0:
                    continue
            th = _up(bvh + bsh)
            tl = _dn(bvl + bsl)
            lo = _dn(Tl - th)
            hi = _up(Th - tl)
            if not lo >= 0.0:  # may fly over
                if nx >= _NEXT:
                    return K.UNDECIDED, nl
                xvh[nx] = _up(bvh - Tl)
                xvl[nx] = _dn(bvl - Th)
                xsh[nx] = _up(math.sqrt(_up(2.0 + _up(bsh * bsh))))
                xsl[nx] = _dn(math.sqrt(_dn(2.0 + _dn(bsl * bsl))))
                xmg[nx] = bmg
                xnd[nx] = -1
                if not bmg:
                    xnd[nx], nn = _node(par, val, nn, bnd, 0)
                    if xnd[nx] < 0:
                        return K.UNDECIDED, nl
                nx += 1
            if hi < 0.0:
                continue
            wh = _up(E1 * bsh)
            wl = np.maximum(_dn(E0 * bsl), 0.0)
            k = 1
            while True:
                tnh = _up(th + 2.0 * wh)
                tnl = _dn(tl + 2.0 * wl)
                lo = _dn(Tl - tnh)
                hi = _up(Th - tnl)
                if not lo >= 0.0:  # may stop after k impacts
                    if nx >= _NEXT:
                        return K.UNDECIDED, nl
                    xvh[nx] = _up(_up(wh + th) - Tl)
                    xvl[nx] = _dn(_dn(wl + tl) - Th)
                    xsh[nx] = _up(math.sqrt(_up(2.0 + _up(wh * wh))))
                    xsl[nx] = _dn(math.sqrt(_dn(2.0 + _dn(wl * wl))))
                    xmg[nx] = bmg
                    xnd[nx] = -1
                    if not bmg:
                        xnd[nx], nn = _node(par, val, nn, bnd, k)
                        if xnd[nx] < 0:
                            return K.UNDECIDED, nl
                    nx += 1
                if hi < 0.0:
                    break
                if k >= cap:
                    return K.UNDECIDED, nl
                th = tnh
                tl = tnl
                wh = _up(E1 * wh)
                wl = np.maximum(_dn(E0 * wl), 0.0)
                k += 1
        if nx > max_live:  # merged: the hull of the branches, itinerary unknown
            a, b_, c, d = xvh[0], xvl[0], xsh[0], xsl[0]
            for q in range(1, nx):
                a = max(a, xvh[q])
                b_ = min(b_, xvl[q])
                c = max(c, xsh[q])
                d = min(d, xsl[q])
            xvh[0], xvl[0], xsh[0], xsl[0], xnd[0], xmg[0] = a, b_, c, d, -1, True
            nx = 1
        vh, xvh = xvh, vh
        vl, xvl = xvl, vl
        sh, xsh = xsh, sh
        sl, xsl = xsl, sl
        nd, xnd = xnd, nd
        mg, xmg = xmg, mg
        live = nx
        if live == 0:
            return SLIDING, nl
    if nl == 0:
        return K.NO_SLIDE_WITHIN, 0
    return K.UNDECIDED, nl


def _buffers(max_iter):
    size = max_iter * _NODES_PER_STEP + 64
    return np.empty(size, np.int64), np.empty(size, np.int64), np.empty(MAX_LEAVES, np.int64)


def leaf_itineraries(par, val, leaves, n):
    """The leaves' itineraries (lists of impact numbers ending in -1), read up the tree."""
    out = []
    for leaf in leaves[:n]:
        it = []
        x = int(leaf)
        while x >= 0:
            it.append(int(val[x]))
            x = int(par[x])
        out.append(it[::-1])
    return out


def branch_words(e0, e1, u0, u1, max_iter):
    """branch_words(e0, e1, u0, u1, max_iter) -> (status, words): the branch rule over
    one box; ``words`` the sorted ASCII texts of the leaves' words (status
    :data:`SLIDING`), else empty."""
    from ..symbolic import word_from_impacts

    par, val, leaves = _buffers(max_iter)
    st, nl = _branch_box(e0, e1, u0, u1, max_iter, K.IMPACT_CAP, MAX_LIVE, MAX_LEAVES, par, val, leaves)
    if st != SLIDING:
        return int(st), []
    texts = sorted({word_from_impacts(it).format(ascii=True) for it in leaf_itineraries(par, val, leaves, nl)})
    return int(st), texts


WORD_SEP = " | "
"""Between the possible words of a ``sliding`` box in an atlas's ``word`` column."""


@njit(cache=True, parallel=True, nogil=True)
def _branch_level(win, level, ii, jj, sel, max_iter, cap, max_live, max_leaves, status, reason, nsteps, halt):
    """The branch rule on the boxes ``sel`` of a level (undecided, reason a border
    event): ``status`` becomes :data:`SLIDING` or ``NO_SLIDE_WITHIN`` where proven
    (``reason`` -1), else stays."""
    ew = win[1] - win[0]
    uw = win[3] - win[2]
    size = max_iter * _NODES_PER_STEP + 64
    for c in prange((sel.shape[0] + K._CHUNK - 1) // K._CHUNK):
        if halted(halt):
            continue
        par = np.empty(size, np.int64)
        val = np.empty(size, np.int64)
        leaves = np.empty(max_leaves, np.int64)
        for q in range(c * K._CHUNK, min(sel.shape[0], (c + 1) * K._CHUNK)):
            b = sel[q]
            E0 = K._edge(win[0], ew, win[1], ii[b], level)
            E1 = K._edge(win[0], ew, win[1], ii[b] + 1, level)
            U0 = K._edge(win[2], uw, win[3], jj[b], level)
            U1 = K._edge(win[2], uw, win[3], jj[b] + 1, level)
            st, nl = _branch_box(E0, E1, U0, U1, max_iter, cap, max_live, max_leaves, par, val, leaves)
            if st != K.UNDECIDED:
                status[b] = st
                reason[b] = -1
                nsteps[b] = 0  # no single itinerary


def classify_level(win, level, ii, jj, max_iter, status, reason, nsteps):
    """Try the branch rule on the undecided boxes of a level whose reason is a border
    event (graze, edge, chatter): proven ones get status ``sliding`` or
    ``no_slide_within`` (their words are spelled again by :func:`branch_words`)."""
    from .._interrupt import run_kernel

    sel = np.flatnonzero((status == K.UNDECIDED) & ((reason == K.GRAZE) | (reason == K.EDGE)
                                                     | (reason == K.CHATTER)))
    if sel.size:
        run_kernel(_branch_level, win, level, ii, jj, sel, max_iter, K.IMPACT_CAP, MAX_LIVE, MAX_LEAVES,
                   status, reason, nsteps)


def mark_atlas(ds):
    """Name what the branch rule proved in an atlas's table (in place): the ``sliding``
    boxes' possible words (spelled again, :func:`branch_words`) and reason
    ``"branches"``, the ``no_slide_within`` boxes without an itinerary reason
    ``"branches"``; the rule's caps in the attributes (for the checker)."""
    st = ds["status"].values
    length = np.diff(ds["offsets"].values)
    words = ds["word"].values.copy()
    reasons = ds["reason"].values.copy()
    mi = int(ds.attrs["max_iter"])
    cols = [ds[k].values for k in ("e0", "e1", "u0", "u1")]
    for b in np.flatnonzero(st == SLIDING):
        got, texts = branch_words(*(float(c[b]) for c in cols), mi)
        if got != SLIDING:  # the same computation, the same answer
            raise AssertionError("the branch rule answered otherwise on the same box")
        words[b] = WORD_SEP.join(texts)
        reasons[b] = "branches"
    reasons[(st == K.NO_SLIDE_WITHIN) & (length == 0)] = "branches"
    ds["word"] = ("box", words)
    ds["reason"] = ("box", reasons)
    ds.attrs["branch_max_live"] = MAX_LIVE
    ds.attrs["branch_max_leaves"] = MAX_LEAVES
