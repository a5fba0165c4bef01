"""The scan kernel's own paths (issue 26), each checked against what it replaces.

- ``model._step_closed_log`` with kept values (``_geometric_memo``) is
  ``model._step_closed`` bit for bit, kept values hit or missed;
- the kept impact number (``model._impacts_kept``) answers as the logarithm
  of Prop. 2.2 does, or not at all;
- the pruning test from row and column factors (``plane._prune_pixel``) is
  ``plane._never_slides`` pixel by pixel;
- a unit of parallel work streams its segments through its lanes: any
  segment size and any split into units give the arrays of one pixel at a time
  (``model._slide_or_steps``), transients, pruning and closed-form steps
  included;
- the common step that counts to the seventh impact (after a lockstep step
  with a fourth impact) gives the same arrays whenever it is switched on;
- the wide-vector attribute (``_simd.prefer_wide_vectors``) reaches the
  LLVM function, and on a machine with AVX-512 its loops use the 512-bit
  registers;
- no reference count (numba's ``NRT_incref``/``NRT_decref``, atomic
  operations) is left inside a loop of the lane kernel ``plane._run_unit``.
"""

from __future__ import annotations

import math
import re

import numba
import numpy as np
import pytest

from stairbounce import plane as sc
from stairbounce._simd import WIDE_ATTRIBUTE, prefer_wide_vectors
from stairbounce.model import (
    _MEMO_SIZE,
    _MEMO_SLOTS,
    _constants,
    _geometric_memo,
    _impact_time_log,
    _impacts_and_time_log,
    _impacts_kept,
    _power_slot,
    _slide_or_steps,
    _step_closed,
    _step_closed_log,
    iterate,
    no_sliding_bound,
)

FIELDS = ("status", "word_length", "jumps", "period", "impacts")


@numba.njit
def _closed_both(ys, vs, es, us, out):
    """Per state: _step_closed, then _step_closed_log with a memo kept across
    the states of one e (as a lane keeps it across its pixel's steps); counts
    the states where the two differ in any bit, and the memo hits."""
    memo = np.full(_MEMO_SIZE, -1.0)
    last = -1.0
    bad = 0
    for i in range(ys.size):
        T, r = _constants(es[i], us[i])
        if es[i] != last:
            memo[:] = -1.0
            last = es[i]
        a = _step_closed(ys[i], vs[i], es[i], T, r)
        le = math.log(es[i]) if es[i] > 0.0 else -math.inf
        b = _step_closed_log(ys[i], vs[i], es[i], T, r, le, memo, 0)
        c = _step_closed_log(ys[i], vs[i], es[i], T, r, le, None, 0)
        same = True
        for x, y in ((a[0], b[0]), (a[1], b[1]), (a[0], c[0]), (a[1], c[1])):
            if not (x == y or (x != x and y != y)):
                same = False
        if not same or a[2] != b[2] or a[2] != c[2]:
            bad += 1
        out[i] = a[2]
    return bad


def test_closed_form_with_kept_values_is_the_closed_form():
    rng = np.random.default_rng(3)
    # runs of states sharing e (the memo is kept across them), from e = 0 to e one ulp below 1
    base = np.concatenate([rng.uniform(0.0, 1.0, 300), 1.0 - 10.0 ** rng.uniform(-15.9, -1, 300),
                           10.0 ** rng.uniform(-12, -1, 100), [0.0, np.nextafter(1.0, 0.0)]])
    es = np.repeat(base, 400)
    n = es.size
    ys = 10.0 ** rng.uniform(-2, 2, n)
    vs = rng.normal(0.0, 2.0, n)
    us = 10.0 ** rng.uniform(-2, 0.5, n)
    ks = np.empty(n, np.int64)
    assert _closed_both(ys, vs, es, us, ks) == 0
    # the states do reach the closed form's many-impact answers, and repeats of them
    assert (ks >= 8).sum() > 10_000 and (ks == -1).sum() > 1000 and (ks == 0).sum() > 1000


def test_row_and_column_factors_give_the_pruning_test():
    rng = np.random.default_rng(4)
    e = np.concatenate([rng.uniform(0.0, 1.0, 300), 1.0 - 10.0 ** rng.uniform(-12, -1, 60),
                        10.0 ** rng.uniform(-12, -1, 60), [0.0]])
    u = np.concatenate([np.array([no_sliding_bound(x) for x in e[e > 0][:200]])
                        * (1 + 10.0 ** rng.uniform(-12, -3, 200) * rng.choice([-1, 1], 200)),
                        10.0 ** rng.uniform(-3, 3, 200), [1e-150, 1e150]])
    for energy0 in (1.0, 0.0, 5e3):
        cols, rows = sc._grid_factors(e, u, energy0)
        grid = np.array([[sc._prune_pixel(rows[0, i], rows[1, i], rows[2, i], cols[2, j], cols[3, j], cols[4, j])
                          for j in range(e.size)] for i in range(u.size)])
        direct = np.array([[sc._never_slides(e[j], *_constants(e[j], u[i]), energy0) for j in range(e.size)]
                           for i in range(u.size)])
        assert np.array_equal(grid, direct)
        assert 0 < grid.sum() < grid.size  # both answers occur, near the curve too


def _pixel_by_pixel(es, us, max_iter, y0, v0):
    """model._slide_or_steps pixel after pixel: the arrays every kernel path must give."""
    out = {k: np.zeros((us.size, es.size), dtype=dt) for k, (dt, _) in sc._FIELDS.items()}
    for i, u in enumerate(us):
        for j, e in enumerate(es):
            T, ratio = _constants(e, u)
            n = 1
            if (y0, v0) != (1.0, 0.0):
                n = _slide_or_steps(y0, v0, e, T, ratio, max_iter)[0]
            imp = jmp = 0
            if n:
                n, imp, jmp = _slide_or_steps(1.0, 0.0, e, T, ratio, max_iter)
            out["status"][i, j] = 0 if n else 1
            out["word_length"][i, j] = imp + 1 if n else 0
            out["jumps"][i, j] = jmp if n else 0
            out["period"][i, j] = n
            out["impacts"][i, j] = imp if n else 0
    return out


# the step limit of the windows checked pixel by pixel
MAX_ITER = 300


def _window(e, u, y0, v0):
    """A window's pixel centres (``np.linspace`` of ``e`` and ``u``, each
    ``(lo, hi, n)``) and its arrays computed pixel by pixel at MAX_ITER."""
    es, us = np.linspace(*e), np.linspace(*u)
    return es, us, _pixel_by_pixel(es, us, MAX_ITER, y0, v0)


def _assert_scan_fast_gives(ref, case, es, us, y0, v0, prune, units, chunk, *long_min):
    """sc._scan_fast over the window at MAX_ITER, into arrays filled with 77
    (never an answer), gives ``ref`` field by field; a failure names ``case``
    and the field."""
    npix = es.size * us.size
    outs = [np.full(npix, 77, dtype=dt) for dt, _ in sc._FIELDS.values()]
    sc._scan_fast(es, us, True, MAX_ITER, y0, v0, prune, units, chunk, *outs, np.zeros(1, np.int64), *long_min)
    for k, o in zip(FIELDS, outs):
        assert np.array_equal(o.reshape(us.size, es.size), ref[k]), (*case, k)


@pytest.mark.parametrize("y0, v0", [(1.0, 0.0), (2.5, -0.7)])
def test_any_segments_and_units_give_the_pixel_by_pixel_arrays(y0, v0):
    # a window across the Corollary 2.1 curve with many-impact steps (closed
    # form), short and long periods, and pixels that never slide
    es, us, ref = _window((0.05, 0.95, 23), (0.03, 1.2, 19), y0, v0)
    npix = es.size * us.size
    # units that take segments from a shared counter: one, several, more
    # units than segments (the extra ones find none left)
    for chunk, units in ((7, 1), (37, 3), (64, 5), (npix, 1), (npix, 3), (5, 40)):
        for prune in (True, False):
            _assert_scan_fast_gives(ref, (chunk, units, prune), es, us, y0, v0, prune, units, chunk)
    # the window exercises what it is meant to: periods of several steps,
    # pixels that never slide, pruned pixels and steps past 8 impacts
    assert (ref["status"] == 1).any() and (ref["period"] > 5).any()
    # and pixels answered while listed, sliding on their first step
    assert ((ref["period"] == 1) & (ref["impacts"] == 0)).sum() > 20
    assert sc.prunable(*np.meshgrid(es, us), y0, v0).any()
    ks = np.concatenate([iterate(1.0, 0.0, e, u, 100)[2] for e in es[::2] for u in us[::2]])
    assert (ks >= 8).sum() > 50


@pytest.mark.parametrize("y0, v0", [(1.0, 0.0), (2.5, -0.7)])
def test_the_long_common_step_at_any_switch_gives_the_pixel_by_pixel_arrays(y0, v0):
    # the common step counts to the seventh impact in a lockstep step after
    # one with a fourth impact in long_min lanes (1 in production): always
    # (0), never (2**62) or switching (1, 3), the arrays of model._step one
    # pixel at a time; a window of steps with every count of impacts 1 to 9
    es, us, ref = _window((0.3, 0.97, 29), (0.01, 0.5, 23), y0, v0)
    npix = es.size * us.size
    chunk, units = sc._chunking(npix, 2, unit_min=64)
    for long_min in (0, 1, 3, 2**62):
        _assert_scan_fast_gives(ref, (long_min,), es, us, y0, v0, False, units, chunk, long_min)
    ks = np.concatenate([iterate(1.0, 0.0, e, u, 60)[2] for e in es[::2] for u in us[::2]])
    counts = np.bincount(ks[ks >= 0], minlength=10)
    assert (counts[1:10] > 20).all(), counts


def test_chunking_gives_a_unit_per_thread_and_segments_for_each():
    for npix in (1, 31, 32, 4095, 4096, 8193, 175_000, 360_000, 1_000_003):
        for threads in (1, 2, 16):
            chunk, units = sc._chunking(npix, threads)
            nseg = -(-npix // chunk)
            assert 1 <= units <= threads and units <= max(1, npix // sc._UNIT_MIN)
            # segments of at most _CHUNK_MAX pixels, at least one per unit
            assert chunk <= sc._CHUNK_MAX and nseg >= units
            # every thread busy on a plane of at least unit_min pixels per thread
            assert units == threads or npix < threads * sc._UNIT_MIN


def test_units_take_every_segment_once_whatever_the_threads():
    # the units take segments from one counter (an atomic add); with more
    # threads than units or than segments, every pixel is still written once:
    # the arrays equal those of one unit on one thread
    es = np.linspace(0.05, 0.95, 41)
    us = np.linspace(0.03, 1.2, 37)
    npix = es.size * us.size
    ref = [np.full(npix, 77, dtype=dt) for dt, _ in sc._FIELDS.values()]
    sc._scan_fast(es, us, True, 200, 1.0, 0.0, True, 1, 32, *ref, np.zeros(1, np.int64))
    before = numba.get_num_threads()
    try:
        for threads in sorted({1, numba.config.NUMBA_NUM_THREADS}):
            numba.set_num_threads(threads)
            for units, chunk in ((threads, 32), (2 * threads + 1, 17), (npix, 64)):
                outs = [np.full(npix, 77, dtype=dt) for dt, _ in sc._FIELDS.values()]
                pruned = sc._scan_fast(es, us, True, 200, 1.0, 0.0, True, units, chunk, *outs, np.zeros(1, np.int64))
                for o, r in zip(outs, ref):
                    assert np.array_equal(o, r), (threads, units, chunk)
                E, U = np.meshgrid(es, us)
                assert pruned == sc.prunable(E, U).sum() > 0
    finally:
        numba.set_num_threads(before)


@numba.njit
def _kept_against_log(vs, ss, es, Ts, offsets, fill, counts):
    """For every state and kept impact number ``k_log + offset`` (k_log the
    logarithm's answer, model._impacts_and_time_log without a memo), with the
    values G(n) kept for n around it when ``fill``: the kept path
    (_impacts_kept) answers nothing or the same (k, t_k) bit for bit.
    counts[0]: answered, counts[1]: differed, counts[2]: states."""
    memo = np.full(_MEMO_SIZE, -1.0)
    for i in range(vs.size):
        v, s, e, T = vs[i], ss[i], es[i], Ts[i]
        le = math.log(e)
        k, t = _impacts_and_time_log(v, s, e, T, le, None, 0)
        if k < 1:
            continue
        counts[2] += 1
        for off in offsets:
            kk = k + off
            if kk < 1:
                continue
            memo[:] = -1.0
            if fill:
                for n in range(max(kk - 4, 0), kk + 4):
                    _geometric_memo(e, n, le, memo, 0)
            memo[0] = kk
            memo[1] = math.pow(e, float(kk))
            j, tj = _impacts_kept(v, s, e, T, le, memo, 0)
            if j != 0:
                counts[0] += 1
                if j != k or tj != t:
                    counts[1] += 1


def _kept_states(rng, n, e):
    """States with a first impact before the edge and many impacts; a third of them
    with T set on a computed impact time or an ulp beside it (the bracket's edges)."""
    y = 10.0 ** rng.uniform(-1, 2, n)
    v = rng.normal(0.0, 3.0, n)
    s = np.sqrt(v * v + 2.0 * y)
    kmax = np.minimum(np.maximum(3.0, 30.0 / -np.log(e)), 1e7)
    k = np.floor(3 + rng.uniform(0, 1, n) * (kmax - 3)).astype(np.int64)
    # T between the exact impact times t_k and t_(k+1)
    gk = -np.expm1((k - 1) * np.log(e)) / (1 - e)
    tk = v + s + 2 * e * s * gk
    T = tk + rng.uniform(0, 2, n) * e**k * s
    edge = rng.uniform(0, 1, n) < 1 / 3
    T[edge] = np.array([_impact_time_log(v[i], s[i], e[i], k[i], math.log(e[i])) for i in np.nonzero(edge)[0]])
    # an ulp down, none, or an ulp up (written without 0 * inf, which is NaN)
    step = rng.choice([-1.0, 0.0, 1.0], edge.sum())
    T[edge] = np.where(step == 0.0, T[edge], np.nextafter(T[edge], np.copysign(np.inf, step)))
    return v, s, T


def test_the_kept_impact_number_gives_the_logarithms_answer():
    # model._impacts_kept claims the closed form's answer (the logarithm of
    # Prop. 2.2 and its correction loop) wherever it answers, by the proof in
    # its docstring; this checks the claim on 1.2 M states x 7 kept numbers,
    # from e = 0.01 to one ulp below 1, T on the bracket's edges included
    rng = np.random.default_rng(26)
    es = np.concatenate([rng.uniform(0.01, 0.99, 40_000), 1.0 - 10.0 ** rng.uniform(-15.9, -2, 40_000),
                         np.full(2000, np.nextafter(1.0, 0.0))])
    es = np.repeat(es, 14)
    v, s, T = _kept_states(rng, es.size, es)
    offsets = np.array([0, -1, 1, -2, 2, -3, 3])
    for fill in (True, False):
        counts = np.zeros(3, np.int64)
        _kept_against_log(v, s, es, T, offsets, fill, counts)
        assert counts[1] == 0, counts
        assert counts[2] > 0.99 * es.size
        if fill:
            # the kept path does answer most states when its number is right or one off
            assert counts[0] > 0.3 * 3 * counts[2], counts
        else:
            assert counts[0] == 0  # nothing kept, nothing answered


@numba.njit
def _pass_against_closed(S0, I0, M0, blocks, counts):
    """Each 32-lane block through plane._kept_pass then plane._closed for the
    lanes it left, against plane._closed alone: the lane rows and the kept
    impact numbers bit for bit.  counts[0]: lanes with MORE, counts[1]: answered
    by the pass, counts[2]: lanes or kept numbers that differ."""
    L = sc.LANES
    for b in range(blocks):
        S = S0[b].copy()
        I = I0[b].copy()
        M = M0[b].copy()
        S2 = S0[b].copy()
        I2 = I0[b].copy()
        M2 = M0[b].copy()
        sc._kept_pass(S, I, M)
        for l in range(L):
            counts[0] += I0[b, sc._MORE, l]
            counts[1] += I0[b, sc._MORE, l] - I[sc._MORE, l]
            if I[sc._MORE, l]:
                sc._closed(l, S, I, M)
            if I2[sc._MORE, l]:
                sc._closed(l, S2, I2, M2)
            same = (S[sc._Y, l] == S2[sc._Y, l] and S[sc._V, l] == S2[sc._V, l]
                    and I[sc._IMP, l] == I2[sc._IMP, l]
                    and I[sc._MORE, l] == I2[sc._MORE, l] and M[l * _MEMO_SIZE] == M2[l * _MEMO_SIZE])
            counts[2] += 0 if same else 1


def test_the_lanes_kept_pass_is_the_closed_form_lane_by_lane():
    # plane._kept_pass answers, in one loop over the lanes, the closed-form
    # steps whose impact number the kept one gives (model._impacts_kept) with
    # e^j kept too, and leaves the rest to plane._closed; blocks of 32 lanes
    # with kept numbers right, one or three off, powers kept or not, log(e)
    # not yet computed (a new pixel), lanes without MORE, T on the impact times
    rng = np.random.default_rng(2026)
    L = sc.LANES
    blocks = 3000
    n = blocks * L
    e = np.concatenate([rng.uniform(0.05, 0.95, n // 2), 1.0 - 10.0 ** rng.uniform(-12, -2, n - n // 2)])
    rng.shuffle(e)
    v, s, T = _kept_states(rng, n, e)
    S0 = np.zeros((blocks, sc._FLOAT_ROWS, L))
    I0 = np.zeros((blocks, sc._INT_ROWS, L), np.int64)
    M0 = np.full((blocks, L * _MEMO_SIZE), -1.0)
    for i in range(n):
        b, l = divmod(i, L)
        S0[b, sc._E, l], S0[b, sc._V, l], S0[b, sc._SS, l], S0[b, sc._T, l] = e[i], v[i], s[i], T[i]
        S0[b, sc._Y, l] = 0.5 * (s[i] ** 2 - v[i] ** 2)
        le = math.log(e[i])
        new_pixel = rng.uniform() < 0.05
        S0[b, sc._LOGE, l] = 1.0 if new_pixel else le
        I0[b, sc._MORE, l] = rng.uniform() < 0.9
        I0[b, sc._IMP, l] = rng.integers(0, 100)
        k, _ = _impacts_and_time_log(v[i], s[i], e[i], T[i], le, None, 0)
        if k < 1 or new_pixel:
            continue
        kk = max(k + rng.choice([0, 0, 0, -1, 1, -3, 3]), 1)
        memo = M0[b, l * _MEMO_SIZE:(l + 1) * _MEMO_SIZE]
        for m in range(max(kk - 3, 0), kk + 3):
            _geometric_memo(e[i], m, le, memo, 0)
        memo[0] = kk
        memo[1] = math.pow(e[i], float(kk))
        if rng.uniform() < 0.8:  # the powers of the neighbours kept too
            for m in (kk - 1, kk, kk + 1):
                memo[_power_slot(m)] = m
                memo[_power_slot(m) + _MEMO_SLOTS] = math.pow(e[i], float(m))
    counts = np.zeros(3, np.int64)
    _pass_against_closed(S0, I0, M0, blocks, counts)
    assert counts[2] == 0, counts
    # the pass answers most lanes and leaves some to _closed
    assert 0.15 * counts[0] < counts[1] < 0.95 * counts[0], counts


def _wide_loop(wide):
    """A lane loop like the common step's square root, compiled afresh (no cache), with or
    without the wide-vector attribute; its LLVM IR and assembly."""

    def loop(a, b, out):
        if wide:
            prefer_wide_vectors()
        for l in range(64):
            out[l] = math.sqrt(a[l] * a[l] + 2.0 * b[l])

    f = numba.njit(cache=False)(loop)
    a, b = np.linspace(-1.0, 1.0, 64), np.linspace(1.0, 2.0, 64)
    out = np.empty(64)
    f(a, b, out)
    np.testing.assert_array_equal(out, np.sqrt(a * a + 2.0 * b))
    sig = f.signatures[0]
    return f.inspect_llvm(sig), f.inspect_asm(sig)


def test_the_wide_vector_attribute_reaches_the_loop():
    """The attribute is in the IR of a function that asks for it, and not of one
    that does not; where the host has AVX-512 (llvmlite's host features), the
    loop uses the zmm registers with it (without it, LLVM's tuning for the
    Xeons since Skylake prefers 256 bits: no zmm on the development machine,
    not asserted, as other hosts tune otherwise)."""
    import llvmlite.binding as ll

    ir_wide, asm_wide = _wide_loop(True)
    ir_plain, _ = _wide_loop(False)
    assert WIDE_ATTRIBUTE in ir_wide
    assert WIDE_ATTRIBUTE not in ir_plain
    features = ll.get_host_cpu_features()
    if features.get("avx512f") and "x86" in ll.get_process_triple():
        assert "zmm" in asm_wide


def _blocks(function_ir):
    """``(label, text)`` of each basic block of one function of LLVM's textual IR."""
    out, label, lines = [], "%entry", []
    for line in function_ir.splitlines()[1:-1]:
        m = re.match(r'^("?[\w.$-]+"?):', line)
        if m:
            out.append((label, "\n".join(lines)))
            label, lines = "%" + m.group(1).strip('"'), []
        else:
            lines.append(line)
    out.append((label, "\n".join(lines)))
    return out


def _counted_in_loops(ir, name):
    """The blocks of function ``name`` in ``ir`` that count references and lie
    on a cycle of its control-flow graph (an edge is a ``label %...`` operand:
    only terminators have them), and the number of blocks."""
    found = [m.group(0) for m in re.finditer(r"^define [^\n]*@(\S+)\(.*?^}$", ir, re.S | re.M)
             if name in m.group(1) and "cpython" not in m.group(1) and not m.group(1).startswith("cfunc")]
    assert len(found) == 1, len(found)
    blocks = _blocks(found[0])
    succ = {b: ["%" + s.strip('"') for s in re.findall(r'label %("?[\w.$-]+"?)', t)] for b, t in blocks}

    def on_cycle(b):
        seen, stack = set(), list(succ[b])
        while stack:
            x = stack.pop()
            if x == b:
                return True
            if x not in seen:
                seen.add(x)
                stack.extend(succ.get(x, []))
        return False

    bad = [b for b, t in blocks if ("@NRT_incref" in t or "@NRT_decref" in t) and on_cycle(b)]
    return bad, len(blocks)


def test_no_reference_counting_inside_the_lane_kernels_loops():
    """numba counts a reference to every array argument of an inlined
    function on entry and exit, and does not always prune the pairs: a lane's
    reload through an inlined function with fifteen arrays did 30 atomic
    operations per pixel (17 % of the samples on Fig. 5e, issue 26, seventh
    round), and four inlined variants of the common step brought the counts on
    its row views back into every lockstep step (3-4x slower). The optimised
    IR of plane._run_unit, compiled afresh, has none in a block on a cycle.
    The check itself is checked on a small function whose IR is written out:
    a count in its loop is found, one before and after it is not."""
    run_unit = numba.njit(sc._run_unit.py_func)
    es, us = sc.pixel_centres(0.0, 1.0, 8), sc.pixel_centres(0.0, 1.5, 8)
    cols, rows = sc._grid_factors(es, us, 1.0)
    outs = [np.empty(64, dtype=dt) for dt, _ in sc._FIELDS.values()]
    run_unit(es, us, True, cols, rows, 100, 1.0, 0.0, True, np.array([0, 1], np.int64), 64, 64, *outs,
             np.zeros(1, np.int64), sc._LONG_MIN)
    bad, nblocks = _counted_in_loops(run_unit.inspect_llvm(run_unit.signatures[0]), "_run_unit")
    assert nblocks > 20
    assert bad == []
    for in_loop in (True, False):
        count = "  call void @NRT_incref(ptr %a)\n"
        ir = ("define void @f(ptr %a, i64 %n) {\n" + ("" if in_loop else count)
              + "  br label %B1\nB1:\n  %i = phi i64 [ 0, %entry ], [ %j, %B2 ]\n"
              + "  %c = icmp slt i64 %i, %n\n  br i1 %c, label %B2, label %B3\nB2:\n"
              + (count if in_loop else "") + "  %j = add i64 %i, 1\n  br label %B1\nB3:\n"
              + "  call void @NRT_decref(ptr %a)\n  ret void\n}\n")
        assert _counted_in_loops(ir, "f") == ((["%B2"] if in_loop else []), 4)
