"""How often border labels and words are fixed by rounding (issue 36, item 6).

Prints, for the referee's chatter-rich window (e 0.30-0.36, u 0.32-0.38) and
the Fig. 6 window ((0, 0.333) x (0.4, 0.733)), at an n x n grid: the share of
border_points labels proven (sb.prove_labels), by kind and by outcome ("word":
every word border, "sliding": the sliding region's border), the widening the
proofs needed, the reasons of the others, and the words of word_table proven
(a proven lower bound on the number of distinct words, N(p)).

    PYTHONPATH=src python benchmarks/proven_labels.py [n=256]
"""

import os
import sys
import time

import numpy as np

import stairbounce as sb

WINDOWS = {"chatter-rich (referee)": ((0.30, 0.36), (0.32, 0.38)),
           "Fig. 6": ((0.0, 0.333), (0.4, 0.733))}


def main(n=256):
    print(f"grid {n} x {n}, load {os.getloadavg()[0]:.1f}")
    for name, (e, u) in WINDOWS.items():
        for outcome in ("word", "sliding"):
            t0 = time.perf_counter()
            pts = sb.border_points(e=(*e, n), u=(*u, n), outcome=outcome)
            t1 = time.perf_counter()
            pr = sb.prove_labels(pts)
            t2 = time.perf_counter()
            df = pr.to_dataframe()
            by_kind = ", ".join(f"{k} {g.proven.mean():.1%} of {len(g)}" for k, g in df.groupby("kind"))
            ulps = (df.proof_distance / df.width).dropna()
            print(f"{name}, outcome={outcome}: {df.proven.sum()} of {len(df)} labels proven "
                  f"({df.proven.mean():.1%}; {by_kind}); widening median {ulps.median():.0f}, "
                  f"max {ulps.max():.0f} brackets; {t1 - t0:.1f} s points, {t2 - t1:.1f} s proofs")
            bad = df[~df.proven]
            if len(bad):
                kinds = bad.reason.str.replace(r"\d+", "N", regex=True).str.replace(r"^(low|high) end: ", "",
                                                                                    regex=True)
                gap = bad.step - bad.unproven_step
                print("   not proven:", "; ".join(f"{r} {c}" for r, c in kinds.value_counts().items()),
                      f"| the failing decision lies {int(gap.median())} steps before the event "
                      f"(median; max {int(gap.max())})")
        t0 = time.perf_counter()
        tab = sb.word_table(e=(*e, n), u=(*u, n), prove=True)
        t1 = time.perf_counter()
        n_words, n_proven = tab.sizes["word"], int(tab.attrs["proven_distinct_words"])
        short = tab.p.values <= 20
        print(f"{name}: words {n_words}, proven {n_proven} ({n_proven / max(n_words, 1):.1%}); "
              f"pixels of proven words {tab.pixels.values[tab.proven.values].sum() / max(tab.pixels.values.sum(), 1):.1%}; "
              f"N(p) for p <= 20: {tab.distinct_words.values[short].sum()}, proven {tab.proven_words.values[short].sum()}; "
              f"{t1 - t0:.1f} s")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 256)
