"""The scan kernel at past commits against the frozen baseline (issue 26): which change cost what.

    python benchmarks/scan_history.py [--repeat 7] [--threads 1] [COMMIT ...]

Each commit's ``src/stairbounce`` is extracted with ``git archive`` into a
temporary folder and timed in a child process of its own, beside the frozen
kernel of ``benchmarks/baseline_kernel.py`` in the same process: the ratio
(frozen time / kernel time, process CPU time, best of ``repeat``) is what
compares across commits on a shared machine.  Cases, max_iter 1000: the
Fig. 5e window at 768 x 768 (nothing prunable) and the paper's grid
(500 x 350) unpruned and pruned (where the version has pruning).  Cycles per
step per core = CPU time x clock / map steps done.

Default commits: the round of issues 11-17 one change at a time --
86e8f8d (before it), 22ec1d2 (+ the point path of scan_points), b83818c
(+ pruning, one inlined load), 3b720d7 (+ the cancellation-free closed form
past 8 impacts), 77b3d1b (+ the Ctrl-C halt flag; the kernel of today until
issue 26), and the working tree (``HEAD`` files as they are on disk: ``.``).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tarfile
import tempfile
import io
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DEFAULT = ["86e8f8d", "22ec1d2", "b83818c", "3b720d7", "77b3d1b", "."]

CHILD = r"""
import json, os, sys, time, inspect
import numba, numpy as np
numba.set_num_threads(int(sys.argv[2]))
sys.path.insert(0, sys.argv[1])
from baseline_kernel import baseline_scan
import stairbounce.plane as P
has_prune = "prune" in inspect.signature(P.scan).parameters
rep = int(sys.argv[3])

def best(f, r):
    cpus = []
    for _ in range(r):
        c = time.process_time(); out = f(); cpus.append(time.process_time() - c)
    return min(cpus), out

def steps(ds, pruned):
    per = np.where(ds.status.values == 0, ds.period.values, int(ds.attrs["max_iter"]))
    if not pruned:
        return int(per.sum())
    E, U = np.meshgrid(ds.e.values, ds.u.values)
    return int(per[~P.prunable(E, U)].sum())

P.scan((0, 1, 40), (0, 1.5, 30), 50); baseline_scan(np.array([.5]), np.array([.5]), 5)
res = {"load": os.getloadavg()[0]}
for name, e, u in (("fig5e_768", (0.04, 0.065, 768), (0.92, 0.945, 768)),
                   ("paper", (0.0, 1.0, 500), (0.0, 1.5, 350))):
    es, us = P.pixel_centres(*e), P.pixel_centres(*u)
    tb, ref = best(lambda: baseline_scan(es, us, 1000), 2)
    kw = {"prune": False} if has_prune else {}
    tk, ds = best(lambda: P.scan(e, u, 1000, **kw), rep)
    same = all(np.array_equal(ds[k].values, ref[k]) for k in ref)
    res[name] = {"baseline": tb, "unpruned": tk, "steps": steps(ds, False), "same": same}
    if has_prune and name == "paper":
        tp, dp = best(lambda: P.scan(e, u, 1000), 3 * rep)
        res[name].update(pruned=tp, steps_pruned=steps(dp, True))
res["load_end"] = os.getloadavg()[0]
print("RESULT" + json.dumps(res))
"""


def extract(commit, dest):
    """``src/stairbounce`` of ``commit`` (or of the working tree for ``.``) under ``dest``."""
    if commit == ".":
        return str(ROOT / "src")
    data = subprocess.run(["git", "archive", commit, "src/stairbounce"], cwd=ROOT, check=True,
                          capture_output=True).stdout
    with tarfile.open(fileobj=io.BytesIO(data)) as t:
        t.extractall(dest)
    return str(Path(dest) / "src")


def clock_ghz():
    with open("/proc/cpuinfo") as f:
        mhz = [float(line.split(":")[1]) for line in f if line.startswith("cpu MHz")]
    return mhz[0] / 1000.0


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("commits", nargs="*", default=DEFAULT)
    p.add_argument("--repeat", type=int, default=7)
    p.add_argument("--threads", type=int, default=1)
    a = p.parse_args(argv)
    ghz = clock_ghz()
    print(f"clock {ghz:.2f} GHz, {a.threads} thread(s), process CPU time, best of {a.repeat}; "
          f"ratio = frozen baseline / kernel in the same process")
    with tempfile.TemporaryDirectory() as tmp:
        for c in a.commits:
            src = extract(c, os.path.join(tmp, c.strip(".") or "wt"))
            env = dict(os.environ, PYTHONPATH=src)
            out = subprocess.run([sys.executable, "-c", CHILD, str(ROOT / "benchmarks"), str(a.threads),
                                  str(a.repeat)], env=env, capture_output=True, text=True)
            line = [ln for ln in out.stdout.splitlines() if ln.startswith("RESULT")]
            if not line:
                print(f"{c}: failed\n{out.stderr[-2000:]}")
                continue
            r = json.loads(line[0][6:])
            f5, pg = r["fig5e_768"], r["paper"]
            cyc = lambda t, n: ghz * 1e9 * t / n / a.threads  # noqa: E731
            text = (f"{c:8s} load {r['load']:.1f}-{r['load_end']:.1f} | Fig.5e 768: x{f5['baseline'] / f5['unpruned']:.1f}, "
                    f"{cyc(f5['unpruned'], f5['steps']):.2f} cyc/step | paper unpruned: "
                    f"x{pg['baseline'] / pg['unpruned']:.1f}, {cyc(pg['unpruned'], pg['steps']):.2f} cyc/step")
            if "pruned" in pg:
                text += (f" | paper pruned: {pg['pruned'] * 1e3:.1f} ms CPU, x{pg['baseline'] / pg['pruned']:.0f}, "
                         f"{cyc(pg['pruned'], pg['steps_pruned']):.0f} cyc/step done")
            text += "" if f5["same"] and pg["same"] else "  ANSWERS DIFFER from the baseline"
            print(text, flush=True)


if __name__ == "__main__":
    main()
