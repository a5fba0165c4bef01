"""Re-verification of certificates by the independent checker (issue 36, item 4).

    python benchmarks/verify.py [--n 20000] [--repeat 3] [--depth 12]

Boxes: the Fig. 7 window cut into a 2^depth x 2^depth grid (depth 12: boxes of
1.4e-5 x 1.4e-5), boxes drawn at random from it and certified by the Arb
reference (``structure.reference``) until ``--n`` of them are proven (kept in
memory, never written).  Timed, best of ``--repeat`` after a warm-up call:

1. ``verify_arrays`` on all n proven boxes at once (numpy intervals), and on
   the ``word`` boxes alone;
2. baselines in the same process, per box: ``verify`` of one certificate at a
   time (the same numpy checker on arrays of one box), and the Arb reference
   re-deriving the certificate (``reference_certificate``), on a sample.

Prints boxes per second and the ratios.

With ``--atlas-depth D`` (issue 43 item 3; 0 skips), also, against the numpy
checker the compiled one replaced (``tests/_verify_numpy.py``) in the same
process: the Fig. 7 atlas ``sb.certify(depth=D)`` re-verified (boxes/s), a
no_slide_within certificate of ``--steps`` steps (``certify_box`` and
``verify``; the numpy checker on ``--old-steps`` of them, per step), and a
trapping region (``verify_region``).
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

from stairbounce.structure.certificate import STATUSES
from stairbounce.structure.reference import reference_certificate
from stairbounce.structure.verdict import verify
from stairbounce.structure.verify import verify_arrays
from _timing import wall_times

FIG7 = ((0.155, 0.2138), (0.6, 0.658))


def proven_boxes(n, depth, seed=0):
    rng = np.random.default_rng(seed)
    (ea, eb), (ua, ub) = FIG7
    side = 2**depth
    we, wu = (eb - ea) / side, (ub - ua) / side
    certs, tried = [], 0
    while len(certs) < n:
        i, j = rng.integers(side, size=2)
        c = reference_certificate((ea + i * we, ea + (i + 1) * we), (ua + j * wu, ua + (j + 1) * wu))
        tried += 1
        if c.proven:
            certs.append(c)
    return certs, tried


def arrays(certs):
    lengths = [len(c.itinerary) for c in certs]
    return (np.array([c.e[0] for c in certs]), np.array([c.e[1] for c in certs]),
            np.array([c.u[0] for c in certs]), np.array([c.u[1] for c in certs]),
            np.array([STATUSES.index(c.status) for c in certs], dtype=np.int8), certs[0].max_iter,
            np.concatenate([np.asarray(c.itinerary, dtype=np.int64) for c in certs]),
            np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64))


def best(f, repeat):
    times, _ = wall_times(f, repeat, warm=True)
    return min(times)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=20000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--depth", type=int, default=12)
    ap.add_argument("--sample", type=int, default=500, help="boxes of the per-box baselines")
    ap.add_argument("--atlas-depth", type=int, default=12, help="the Fig. 7 atlas's depth (0: skip)")
    ap.add_argument("--steps", type=int, default=10**6, help="steps of the no_slide_within certificate")
    ap.add_argument("--old-steps", type=int, default=20000, help="steps given to the numpy checker")
    a = ap.parse_args()
    print(f"load before: {os.getloadavg()}")
    t = time.perf_counter()
    certs, tried = proven_boxes(a.n, a.depth)
    t_ref = time.perf_counter() - t
    by = {s: sum(c.status == s for c in certs) for s in STATUSES}
    steps = sum(len(c.itinerary) for c in certs)
    print(f"{a.n} proven boxes of {tried} tried (depth {a.depth}), {by}, {steps} steps in all; "
          f"reference certifier: {tried / t_ref:.0f} boxes/s")
    arr = arrays(certs)
    assert verify_arrays(*arr).all()
    t_all = best(lambda: verify_arrays(*arr), a.repeat)
    words = [c for c in certs if c.status == "word"]
    warr = arrays(words)
    t_words = best(lambda: verify_arrays(*warr), a.repeat)
    print(f"verify_arrays, all proven: {a.n / t_all:,.0f} boxes/s ({t_all:.3f} s)")
    print(f"verify_arrays, word boxes: {len(words) / t_words:,.0f} boxes/s ({t_words:.3f} s, {len(words)} boxes)")
    rng = np.random.default_rng(1)
    sample = [certs[i] for i in rng.choice(len(certs), size=min(a.sample, len(certs)), replace=False)]
    t_one = best(lambda: [verify(c) for c in sample], 1)
    t_arb = best(lambda: [reference_certificate(c.e, c.u) for c in sample], 1)
    print(f"per box, verify(certificate): {len(sample) / t_one:,.0f} boxes/s  "
          f"(verify_arrays x{(a.n / t_all) / (len(sample) / t_one):.0f})")
    print(f"per box, Arb reference re-derived: {len(sample) / t_arb:,.0f} boxes/s  "
          f"(verify_arrays x{(a.n / t_all) / (len(sample) / t_arb):.0f})")
    if a.atlas_depth:
        compiled_vs_numpy(a)
    print(f"load after: {os.getloadavg()}")


def compiled_vs_numpy(a):
    import sys
    from pathlib import Path

    import stairbounce as sb
    from stairbounce.structure.verify import verify_codes
    from stairbounce.structure.verify_trapping import verify_region

    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from tests import _verify_numpy as old

    t = time.perf_counter()
    atlas = sb.certify(e=FIG7[0], u=FIG7[1], depth=a.atlas_depth)
    t_cert = time.perf_counter() - t
    b = atlas.boxes
    arr = [np.asarray(b[k].values) for k in ("e0", "e1", "u0", "u1")] + [b["status"].values.astype(np.int64)]
    arr += [atlas.max_iter, b["itinerary"].values.astype(np.int64), b["offsets"].values.astype(np.int64)]
    n = len(arr[0])
    t_new = best(lambda: verify_codes(*arr), a.repeat)
    t = time.perf_counter()
    c_old = old.verify_codes(*arr)[0]
    t_old = time.perf_counter() - t
    assert (verify_codes(*arr)[0] == c_old).all() and (c_old == 0).all()
    print(f"Fig. 7 atlas depth {a.atlas_depth}: {n:,} boxes, {len(arr[6]):,} steps (certify {t_cert:.1f} s); "
          f"compiled {n / t_new:,.0f} boxes/s ({t_new:.2f} s), numpy {n / t_old:,.0f} boxes/s ({t_old:.2f} s): "
          f"x{t_old / t_new:.1f}  load {os.getloadavg()}")
    box = ((0.2995, 0.2995 + 3e-16), (0.4135, 0.4135 + 3e-16))
    t = time.perf_counter()
    c = sb.certify_box(*box, max_iter=a.steps)
    t_box = time.perf_counter() - t
    t_ver = best(lambda: sb.verify(c), a.repeat)
    short = [np.array([x]) for x in (c.e[0], c.e[1], c.u[0], c.u[1])] + [np.array([2]), a.old_steps]
    short += [np.asarray(c.itinerary[:a.old_steps], np.int64), np.array([0, a.old_steps])]
    t = time.perf_counter()
    assert old.verify_codes(*short)[0][0] == 0
    t_old = (time.perf_counter() - t) * a.steps / a.old_steps
    print(f"{c.status} certificate of {len(c.itinerary):,} steps ({len(c.decisions):,} decisions): certify_box "
          f"{t_box:.2f} s, verify {t_ver:.3f} s; numpy checker {t_old:.1f} s (from {a.old_steps:,} steps): "
          f"x{t_old / t_ver:.0f}  load {os.getloadavg()}")
    r = sb.trapping_region((0.299, 0.30), (0.413, 0.414))
    args = (*r.e, *r.u, 1000, r.itinerary, r.grid, r.cells)
    t_new = best(lambda: verify_region(*args), a.repeat)
    t_old = best(lambda: old.verify_region(*args), a.repeat)
    print(f"trapping region ({len(r.cells)} cells): compiled {1e3 * t_new:.2f} ms, numpy {1e3 * t_old:.1f} ms: "
          f"x{t_old / t_new:.0f}  load {os.getloadavg()}")


if __name__ == "__main__":
    main()
