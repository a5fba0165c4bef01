"""The border's dimension, two estimators that share no method (issue 12).

For the paper's Fig. 6 and Fig. 7 windows (``figures.DIMENSION_WINDOWS``;
the paper: D = 1.324 and 1.403 by box counting on 500 px pictures):

1. the uncertainty exponent (``fractal.uncertainty_dimension``): ``--points``
   random points (default 10^6), eps over five decades (11 values, 1e-6 to
   0.1 of the window), at each ``--max-iter`` (default 1000, 4000, 16000),
   for the border of the sliding region (``which="sliding"``) and the
   borders between word lengths (``which="words"``).  Both borders come from
   one classification of the same points (``scan_points`` returns status
   and word length; the second pass reads them back).
2. box counting beyond memory (``atlas_boxes.store_box_counts``): a tiled
   ``--box-resolution``^2 store per window (``atlas.scan_to_zarr``, resumable:
   an interrupted run continues), its border counted tile by tile, fitted
   over ``--box-fit`` box sides (default from 16 px to 1/64 of the picture,
   away from the pixel scale) and, for comparison, over 1 px to 1/8 of the
   picture (the paper's protocol at 500 px, pixel scale included).

Prints D with its 95% CI per case and a closing table; writes every number to
``--results`` (JSON, one entry per case, so a rerun skips finished cases),
draws f(eps), the local dimensions ``2 - d log f / d log eps`` and the local
box-counting slopes against scale (in units of the window) to ``--png``, and
with ``--json`` writes ``src/stairbounce/data/border_dimension.json``.

Run: ``python benchmarks/dimension_study.py --quick`` (10^5 points, max_iter
1000, 2048^2 px boxes: about a minute on an idle 2-core machine);
the full study (defaults) took the time recorded in docs/guide/dimension-study.md
on the machine named there.  Stores go under ``--store-dir`` (default
``/work/scratch/i12``); they are large (about 1.5 GB per 32768^2 window).
"""

from __future__ import annotations

import argparse
import datetime
import hashlib
import json
import math
import os
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from stairbounce._io import atomic_path
from stairbounce.atlas import scan_to_zarr
from stairbounce.atlas_boxes import store_box_counts
from stairbounce.figures import DIMENSION_WINDOWS
from stairbounce.dimension import (
    DEFAULT_EPS,
    box_dimension_from_counts,
    uncertainty_dimension,
    uncertainty_dimension_from_counts,
)
from stairbounce.plane import scan_points


class SharedClassification:
    """The model's two classifications of the same points from one scan:
    ``sliding`` (status) computes and keeps the word lengths, ``words`` reads
    them back (the same seed gives the same point arrays in the same order)."""

    def __init__(self, max_iter):
        self.max_iter = max_iter
        self.kept = {}
        self.points = 0
        self.seconds = 0.0

    @staticmethod
    def _key(e, u):
        return hashlib.blake2b(np.ascontiguousarray(e).tobytes() + np.ascontiguousarray(u).tobytes(),
                               digest_size=16).digest()

    def _scan(self, e, u):
        t = time.perf_counter()
        ds = scan_points(e, u, max_iter=self.max_iter)
        self.seconds += time.perf_counter() - t
        self.points += e.size
        return ds["status"].values, ds["word_length"].values

    def sliding(self, e, u):
        status, words = self._scan(e, u)
        self.kept[self._key(e, u)] = words
        return status

    def words(self, e, u):
        hit = self.kept.pop(self._key(e, u), None)
        return self._scan(e, u)[1] if hit is None else hit


def _ci(d):
    return f"{d['dimension']:.4f} [{d['ci'][0]:.4f}, {d['ci'][1]:.4f}]"


def uncertainty_case(name, max_iter, n_points, eps, seed, log):
    (e, u), _ = DIMENSION_WINDOWS[name]
    shared = SharedClassification(max_iter)
    out = {}
    t0 = time.perf_counter()
    for which in ("sliding", "words"):
        t = time.perf_counter()
        est = uncertainty_dimension(getattr(shared, which), (e, u), eps=eps, n_points=n_points, seed=seed)
        mid, local = est.local_dimensions
        out[which] = dict(
            dimension=est.dimension, ci=list(est.ci), stderr=est.stderr,
            stderr_binomial=est.stderr_binomial, stderr_fit=est.stderr_fit, r=est.r,
            alpha=est.alpha, eps=est.eps.tolist(), fraction=est.fraction.tolist(),
            uncertain=est.uncertain.tolist(), fit_range=list(est.fit_range),
            local_eps=mid.tolist(), local_dimension=local.tolist(),
            seconds=time.perf_counter() - t,
        )
        log(f"  {name} uncertainty max_iter {max_iter:6d} {which:8s} D = {_ci(out[which])}  "
            f"(+-{(est.ci[1] - est.ci[0]) / 2:.4f}; stderr binomial {est.stderr_binomial:.4f}, "
            f"scatter {est.stderr_fit:.4f})  r = {est.r:.5f}  {out[which]['seconds']:.1f} s")
    out.update(n_points=n_points, seed=seed, max_iter=max_iter, classified=shared.points,
               scan_seconds=shared.seconds, seconds=time.perf_counter() - t0, method="uncertainty")
    return out


def box_fits(counts_sizes, counts, resolution, fit):
    s = np.asarray(counts_sizes)
    fits = {}
    ranges = {
        "away": fit,
        "paper protocol (1 px .. 1/8)": (1, resolution // 8),
    }
    for label, fr in ranges.items():
        try:
            est = box_dimension_from_counts(s, counts, fit_range=fr)
        except ValueError as exc:
            fits[label] = {"error": str(exc)}
            continue
        fits[label] = dict(dimension=est.dimension, ci=list(est.ci), stderr=est.stderr, r=est.r,
                           fit_range=list(est.fit_range))
    return fits


def box_case(name, resolution, max_iter, tile, store_dir, scheduler, log):
    (e, u), _ = DIMENSION_WINDOWS[name]
    path = Path(store_dir) / f"{name}_{resolution}_{max_iter}_t{tile}.zarr"
    t = time.perf_counter()
    last = [0.0]

    def progress(done, total):
        now = time.perf_counter()
        if now - last[0] > 30 or done == total:
            last[0] = now
            log(f"    scan {path.name}: {done}/{total} tiles, {now - t:.0f} s")

    scan_to_zarr(path, e=(e[0], e[1], resolution), u=(u[0], u[1], resolution), max_iter=max_iter,
                 tile=tile, client=scheduler, progress=progress)
    scan_seconds = time.perf_counter() - t
    out = {"resolution": resolution, "max_iter": max_iter, "tile": tile, "store": str(path),
           "scan_seconds": scan_seconds, "method": "boxes"}
    for which in ("sliding", "words"):
        t = time.perf_counter()
        s, c = store_box_counts(path, which=which, client=scheduler)
        seconds = time.perf_counter() - t
        s_arr = np.asarray(s, dtype=float)
        c_arr = np.asarray(c, dtype=float)
        local = np.diff(np.log(c_arr)) / np.diff(np.log(1.0 / s_arr))
        out[which] = dict(sizes=s.tolist(), counts=c.tolist(), seconds=seconds,
                          local_scale=(np.sqrt(s_arr[1:] * s_arr[:-1]) / resolution).tolist(),
                          local_dimension=local.tolist())
        log(f"  {name} boxes {resolution} px {which:8s} counted in {seconds:.1f} s")
    return out


def refit(results, fit):
    """The fits of every box case from its stored counts (so a new fit range
    needs no new count)."""
    for key, c in results.items():
        if c["method"] != "boxes":
            continue
        res = c["resolution"]
        for which in ("sliding", "words"):
            d = c[which]
            d["fits"] = box_fits(d["sizes"], d["counts"], res, fit or (16, max(64, res // 32)))


def _load(path):
    try:
        return json.loads(Path(path).read_text())
    except (FileNotFoundError, ValueError):
        return {}


def _save(path, results):
    with atomic_path(path) as tmp:
        Path(tmp).write_text(json.dumps(results, indent=1))


def draw(results, png):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 3, figsize=(16, 9))
    for row, name in enumerate(DIMENSION_WINDOWS):
        ax_f, ax_l, ax_b = axes[row]
        for key, case in sorted(results.items()):
            if not key.startswith(f"{name}/"):
                continue
            for which, style in (("sliding", "-"), ("words", "--")):
                if which not in case:
                    continue
                d = case[which]
                if case["method"] == "uncertainty":
                    lab = f"max_iter {case['max_iter']}, {which}, {case['n_points']:.0e} pts from eps {min(d['eps']):.0e}"
                    ax_f.loglog(d["eps"], d["fraction"], style, marker="o", ms=3, label=lab)
                    ax_l.semilogx(d["local_eps"], d["local_dimension"], style, marker="o", ms=3,
                                  label=f"uncertainty, {lab}")
                else:
                    lab = f"boxes {case['resolution']} px, {which}"
                    ax_b.semilogx(d["local_scale"], d["local_dimension"], style, marker="s", ms=3, label=lab)
                    ax_l.semilogx(d["local_scale"], d["local_dimension"], style, marker="s", ms=3,
                                  color="k", alpha=0.6, label=lab)
        ax_f.set(xlabel="eps (window units)", ylabel="uncertain fraction f(eps)", title=f"{name}: f(eps)")
        ax_l.set(xlabel="scale (window units)", ylabel="local dimension", ylim=(0.8, 2.0),
                 title=f"{name}: 2 - dlog f/dlog eps and box-counting slopes")
        ax_b.set(xlabel="box side (window units)", ylabel="d log N / d log(1/s)", ylim=(0.5, 2.0),
                 title=f"{name}: local box-counting slopes")
        paper = DIMENSION_WINDOWS[name][1]
        for ax in (ax_l, ax_b):
            ax.axhline(paper, color="grey", lw=0.8, ls=":")
        for ax in (ax_f, ax_l, ax_b):
            ax.legend(fontsize=6)
    fig.tight_layout()
    with atomic_path(png) as tmp:
        fig.savefig(tmp, dpi=110)
    plt.close(fig)


FINE_MAX_EPS = 1e-3
"""Fine scales: eps up to 1e-3 of the window, away from the window's extent."""


def _case_fit(case, which, fit_range=None):
    d = case[which]
    measured = SimpleNamespace(eps=d["eps"], uncertain=d["uncertain"], n_points=case["n_points"],
                               seed=case["seed"])
    return uncertainty_dimension_from_counts(measured, fit_range=fit_range)


def fine_scales(results, name, which="sliding"):
    """The fit over eps <= 1e-3 of the case reaching small eps (1e-8 or
    less) at the largest max_iter, or None."""
    cases = [c for k, c in results.items() if k.startswith(f"{name}/unc/") and which in c
             and min(c[which]["eps"]) <= 1e-8]
    if not cases:
        return None, None
    c = max(cases, key=lambda c: (c["max_iter"], c["n_points"]))
    return c, _case_fit(c, which, (min(c[which]["eps"]), FINE_MAX_EPS))


def default_range(results, name):
    """The default-eps case at the largest max_iter."""
    cases = [c for k, c in results.items()
             if k.startswith(f"{name}/unc/") and k.count("/") == 2 and "sliding" in c]
    return max(cases, key=lambda c: (c["max_iter"], c["n_points"])) if cases else None


def _rounded(lo_hi):
    return [round(v, 4) for v in lo_hi]


def write_data(results, path, command):
    out = {}
    for name in DIMENSION_WINDOWS:
        c = default_range(results, name)
        if c is None:
            continue
        d = c["sliding"]
        same = {"uncertainty": {"dimension": round(d["dimension"], 4), "ci95": _rounded(d["ci"]),
                                "eps": [d["fit_range"][0], d["fit_range"][1]], "n_points": c["n_points"],
                                "max_iter": c["max_iter"]}}
        boxes = [b for k, b in results.items() if k.startswith(f"{name}/box/")]
        if boxes:
            b = max(boxes, key=lambda b: b["resolution"])
            f = b["sliding"]["fits"]["away"]
            if "error" not in f:
                same["boxes"] = {"dimension": round(f["dimension"], 4), "ci95": _rounded(f["ci"]),
                                 "resolution": b["resolution"], "max_iter": b["max_iter"],
                                 "fit_range_px": f["fit_range"],
                                 "fit_range_window": [f["fit_range"][0] / b["resolution"],
                                                      f["fit_range"][1] / b["resolution"]]}
        fc, fine = fine_scales(results, name)
        if fine is not None:
            finest = _case_fit(fc, "sliding", (min(fc["sliding"]["eps"]), 1e-5))
            entry = {
                "dimension": round(fine.dimension, 4), "ci95": _rounded(fine.ci),
                "method": "uncertainty exponent, fine scales",
                "details": (f"border of the sliding region; {fc['n_points']} random points, eps "
                            f"{fine.fit_range[0]:.0e}..{fine.fit_range[1]:.0e} of the window, max_iter "
                            f"{fc['max_iter']}, seed {fc['seed']}. The CI covers the binomial noise and the "
                            f"scatter about the line, not the drift of the exponent with the scale "
                            f"(eps {finest.fit_range[0]:.0e}..{finest.fit_range[1]:.0e}: {finest.dimension:.3f} "
                            f"[{finest.ci[0]:.3f}, {finest.ci[1]:.3f}]). At the coarser scales both estimators "
                            "measure ('same_scales') they agree with each other."),
            }
        else:
            entry = {
                "dimension": round(d["dimension"], 4), "ci95": _rounded(d["ci"]),
                "method": "uncertainty exponent",
                "details": (f"border of the sliding region, {c['n_points']} random points, eps "
                            f"{d['fit_range'][0]:.0e}..{d['fit_range'][1]:.0e} of the window, max_iter "
                            f"{c['max_iter']}, seed {c['seed']}; the CI covers the binomial noise and the "
                            "scatter about the line"),
            }
        entry["paper"] = DIMENSION_WINDOWS[name][1]
        entry["same_scales"] = same
        entry["uncertainty_by_max_iter"] = {
            str(v["max_iter"]): {w: {"dimension": round(v[w]["dimension"], 4), "ci95": _rounded(v[w]["ci"])}
                                 for w in ("sliding", "words")}
            for k, v in results.items() if k.startswith(f"{name}/unc/") and k.count("/") == 2}
        out[name] = entry
    out["generated_by"] = command
    out["date"] = datetime.date.today().isoformat()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        Path(tmp).write_text(json.dumps(out, indent=1) + "\n")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--quick", action="store_true", help="10^5 points, max_iter 1000, 2048^2 px boxes")
    p.add_argument("--points", type=int, default=1_000_000)
    p.add_argument("--max-iter", default="1000,4000,16000")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--eps", default=None,
                   help="MIN:MAX:N, N perturbations log-spaced (default 1e-6:0.1:11, fractal.DEFAULT_EPS)")
    p.add_argument("--windows", default="fig6,fig7")
    p.add_argument("--box-resolution", type=int, default=32768, help="0: no box counting")
    p.add_argument("--box-max-iter", type=int, default=1000)
    p.add_argument("--box-fit", default=None, help="MIN:MAX box sides in px (default 16 : resolution/32)")
    p.add_argument("--tile", type=int, default=1024)
    p.add_argument("--store-dir", default="/work/scratch/i12")
    p.add_argument("--scheduler", default=None, help="Dask scheduler address for the stores")
    p.add_argument("--skip-uncertainty", action="store_true")
    p.add_argument("--results", default="dimension_study.json")
    p.add_argument("--png", default="dimension_study.png")
    p.add_argument("--note", default="", help="appended to generated_by in --json (where the cases ran)")
    p.add_argument("--json", default=None, help="write the answer file (src/stairbounce/data/border_dimension.json)")
    a = p.parse_args(argv)
    if a.quick:
        a.points, a.max_iter, a.box_resolution, a.tile = 100_000, "1000", 2048, 512
    max_iters = [int(m) for m in a.max_iter.split(",") if m]
    names = [n for n in a.windows.split(",") if n]
    fit = tuple(int(v) for v in a.box_fit.split(":")) if a.box_fit else None
    eps, tag = DEFAULT_EPS, ""
    if a.eps:
        lo, hi, n = a.eps.split(":")
        eps, tag = np.logspace(math.log10(float(lo)), math.log10(float(hi)), int(n)), f"/eps{a.eps}"
    results = _load(a.results)
    t_all = time.perf_counter()

    def log(msg):
        print(msg, flush=True)

    log(f"dimension study: points {a.points}, eps {eps[0]:.0e}..{eps[-1]:.0e} "
        f"({eps.size} values), max_iter {max_iters}, boxes {a.box_resolution} px (fit {fit or '16 px .. 1/32 of the picture'}); "
        f"load {os.getloadavg()[0]:.2f}, {os.cpu_count()} cpus")
    for name in names:
        if not a.skip_uncertainty:
            for mi in max_iters:
                key = f"{name}/unc/{mi}{tag}"
                if key in results and results[key]["n_points"] == a.points:
                    log(f"  {key}: done before, D = {_ci(results[key]['sliding'])}")
                    continue
                results[key] = uncertainty_case(name, mi, a.points, eps, a.seed, log)
                _save(a.results, results)
        if a.box_resolution:
            key = f"{name}/box/{a.box_resolution}/{a.box_max_iter}"
            if key not in results:
                Path(a.store_dir).mkdir(parents=True, exist_ok=True)
                results[key] = box_case(name, a.box_resolution, a.box_max_iter, a.tile, a.store_dir,
                                        a.scheduler, log)
                _save(a.results, results)
    refit(results, fit)
    log(f"\nsummary ({time.perf_counter() - t_all:.0f} s; load {os.getloadavg()[0]:.2f})")
    log("| window | paper | method | max_iter | sliding border D [95% CI] | word borders D [95% CI] |")
    log("|---|---|---|---|---|---|")
    for key, c in results.items():
        name = key.split("/")[0]
        paper = DIMENSION_WINDOWS[name][1]
        if c["method"] == "uncertainty":
            eps = c["sliding"]["eps"]
            log(f"| {name} | {paper} | uncertainty, {c['n_points']:.0e} points, eps {eps[0]:.0e}..{eps[-1]:.0e} "
                f"| {c['max_iter']} | "
                f"{_ci(c['sliding'])} | {_ci(c['words'])} |")
        else:
            for label in c["sliding"]["fits"]:
                fs, fw = c["sliding"]["fits"][label], c["words"]["fits"][label]
                if "error" in fs or "error" in fw:
                    continue
                log(f"| {name} | {paper} | boxes {c['resolution']} px, {fs['fit_range'][0]}..{fs['fit_range'][1]} px "
                    f"| {c['max_iter']} | {_ci(fs)} | {_ci(fw)} |")
    for key, c in results.items():
        name = key.split("/")[0]
        if c["method"] == "uncertainty" and min(c["sliding"]["eps"]) <= 1e-8:
            fine = _case_fit(c, "sliding", (min(c["sliding"]["eps"]), FINE_MAX_EPS))
            words = _case_fit(c, "words", (min(c["words"]["eps"]), FINE_MAX_EPS))
            paper = DIMENSION_WINDOWS[name][1]
            log(f"| {name} | {paper} | uncertainty, {c['n_points']:.0e} points, fine scales: eps "
                f"{fine.fit_range[0]:.0e}..{fine.fit_range[1]:.0e} | {c['max_iter']} | "
                f"{fine.dimension:.4f} [{fine.ci[0]:.4f}, {fine.ci[1]:.4f}] | "
                f"{words.dimension:.4f} [{words.ci[0]:.4f}, {words.ci[1]:.4f}] |")
    if a.png:
        draw(results, a.png)
        log(f"wrote {a.png}")
    if a.json:
        args, shown = list(sys.argv[1:] if argv is None else argv), []
        while args:
            item = args.pop(0)
            if item in ("--note", "--results", "--png"):
                args = args[1:]  # where files went is not how the numbers were made
            elif not item.startswith(("--note=", "--results=", "--png=")):
                shown.append(item)
        command = " ".join(["python benchmarks/dimension_study.py", *shown])
        write_data(results, a.json, command + (f" ({a.note})" if a.note else ""))
        log(f"wrote {a.json}")


if __name__ == "__main__":
    main()
