"""The checker's branch rule on an atlas with class-level proofs (issue 44): the
compiled follower against the Python rule, the same rows, the same process.

    python benchmarks/branch_checker.py [--depth 8] [--repeat 3]

Certifies the Fig. 7 window with ``classes=True`` at ``--depth``, then times, best of
``--repeat`` after one untimed call (numba's compilation, the word texts' memo):

1. ``verify_branches.check_atlas_branches`` (what ``sb.verify`` runs on the rows
   proven by the branch rule: ``_check_kernel.follow_boxes``, then the word texts);
2. the baseline: ``verify_branches.follow`` (the rule in Python, one box at a time)
   on the same rows, then the same word comparison.

Prints rows per second of each and the ratio, with the load before and after; both
must accept every row (they are the same rule).
"""

from __future__ import annotations

import argparse
import os

import numpy as np

from _timing import int_options, wall_times


def main(argv=None):
    a = int_options(argparse.ArgumentParser(description=__doc__.splitlines()[0]), depth=8, repeat=3).parse_args(argv)
    import stairbounce as sb
    from stairbounce.structure.certificate import STATUSES
    from stairbounce.structure.verify_branches import _texts, check_atlas_branches, follow

    print(f"load {os.getloadavg()}")
    atlas = sb.certify(e=(0.155, 0.2138), u=(0.6, 0.658), depth=a.depth, classes=True)
    ds = atlas.boxes
    arrays = {k: ds[k].values for k in ("status", "offsets", "e0", "e1", "u0", "u1")}
    arrays["max_iter"] = atlas.max_iter
    status = ds["status"].values
    reason = _texts(ds, "reason")
    sliding = status == STATUSES.index("sliding")
    rows = np.flatnonzero(sliding | ((status == STATUSES.index("no_slide_within")) & (reason == "branches")))
    live, leaves = int(ds.attrs["branch_max_live"]), int(ds.attrs["branch_max_leaves"])
    words = _texts(ds, "word")

    def compiled():
        code = np.full(status.size, -1, np.int64)
        check_atlas_branches(ds, arrays, code, 9)
        return int((code[rows] == 0).sum())

    def python():
        good = 0
        for b in rows:
            claim, got = follow(*(float(ds[k].values[b]) for k in ("e0", "e1", "u0", "u1")), atlas.max_iter,
                                live, leaves)
            if sliding[b]:
                good += claim == "sliding" and got <= set(str(words[b]).split(" | ")) and len(got) > 0
            else:
                good += claim == "no_slide_within"
        return good

    tc, nc = wall_times(compiled, a.repeat, warm=True)
    tp, np_ = wall_times(python, a.repeat, warm=True)
    c, p = min(tc), min(tp)
    print(f"Fig. 7, depth {a.depth}, classes: {status.size:,} boxes, {rows.size:,} proven by the branch rule")
    print(f"  compiled follow_boxes: {c:.3f} s, {rows.size / c:,.0f} rows/s, {nc:,} accepted")
    print(f"  Python follow (baseline): {p:.3f} s, {rows.size / p:,.0f} rows/s, {np_:,} accepted")
    print(f"  ratio x{p / c:.1f}; load {os.getloadavg()}")
    assert nc == np_ == rows.size


if __name__ == "__main__":
    main()
