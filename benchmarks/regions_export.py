"""The regions' export (issue 37, regions_geojson): CPU time of the export step
and the shapely checks of its polygons, on the report's windows.

    python benchmarks/regions_export.py [--windows fig5e,chatter,fig4] [--seed 128]

For each window the regions are traced once (window_regions, not timed), then
the export is timed (process CPU time) twice in the same process: the
baseline re-tests every pair of segments in every round of the untangling
(as the export did before the incremental test), the current code tests only
the chords changed since the round before.  Printed: CPU seconds of each,
their ratio, and for the current export the polygons, the invalid ones
(shapely.is_valid), the pairs of polygons overlapping by more than 1e-15 of the
window, the union's area against the sum of areas, the crossings left, the
points noded and the boxes clipped out (metadata.clipped).  Windows: Fig. 5e
[0.04, 0.065] x [0.92, 0.945]; the chatter-rich window [0.30, 0.36] x [0.32, 0.38]; Fig. 4 [0, 0.999] x
[0.001, 1.5] (e = 1 and u = 0 left out, as words --regions needs);
"fig5e-corners" is Fig. 5e with from_corners=True.
"""

from __future__ import annotations

import argparse
import os
import time

import stairbounce as sb
from stairbounce.structure import export as rx

WINDOWS = {
    "fig5e": ((0.04, 0.065), (0.92, 0.945), False),
    "fig5e-corners": ((0.04, 0.065), (0.92, 0.945), True),
    "chatter": ((0.30, 0.36), (0.32, 0.38), False),
    "fig4": ((0.0, 0.999), (0.001, 1.5), False),
}


def _full_retest():
    """The baseline: every chord fresh before every round (all pairs re-tested)."""
    find = rx._find_crossings

    def every_pair(edges, window=None):
        for ed in edges:
            ed.fresh[:] = True
        return find(edges, window)
    return every_pair


def _export(regs, graph, res):
    t = time.process_time()
    gj = rx.geojson(regs, None, res, 1000, graph=graph)
    return gj, time.process_time() - t


def _check(regs, gj):
    import shapely
    from shapely.geometry import shape

    geoms = [shape(f["geometry"]) for f in gj["features"] if f["geometry"] is not None]
    bad = sum(not g.is_valid for g in geoms)
    e, u = regs[0].e, regs[0].u
    W = (e[1] - e[0]) * (u[1] - u[0])
    ok = [g if g.is_valid else g.buffer(0) for g in geoms]
    a, b = shapely.STRtree(ok).query(ok, predicate="intersects")
    over = sum(1 for i, j in zip(a, b) if i < j and ok[i].intersection(ok[j]).area > 1e-15 * W)
    gap = (sum(g.area for g in ok) - shapely.union_all(ok).area) / W
    return len(geoms), bad, over, gap


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--windows", default="fig5e,chatter,fig4")
    ap.add_argument("--seed", type=int, default=128)
    ap.add_argument("--no-baseline", action="store_true")
    args = ap.parse_args()
    print(f"load {os.getloadavg()}")
    sb.regions_geojson(sb.window_regions((0.04, 0.065), (0.92, 0.945), resolution=8))   # compile
    for name in args.windows.split(","):
        e, u, corners = WINDOWS[name]
        t = time.process_time()
        regs = sb.window_regions(e, u, resolution=args.seed, from_corners=corners)
        graph = sb.border_graph(regs)
        print(f"{name} (seed {args.seed}): {len(regs)} words traced in {time.process_time() - t:.1f} s CPU")
        base = None
        if not args.no_baseline:
            find, rx._find_crossings = rx._find_crossings, _full_retest()
            try:
                _, base = _export(regs, graph, args.seed)
            finally:
                rx._find_crossings = find
        gj, now = _export(regs, graph, args.seed)
        n, bad, over, gap = _check(regs, gj)
        m = gj["metadata"]
        clip = sum((b[1] - b[0]) * (b[3] - b[2]) for b in m["clipped"])
        print(f"  export {now:.2f} s CPU" + (f" (baseline, every pair re-tested: {base:.2f} s; x{base / now:.1f})"
                                            if base else "")
              + f"; {n} polygons, {bad} invalid, {over} overlapping pairs, (sum - union) / window {gap:.1e}, "
              f"crossings left {m['crossings']}, points noded {m['noded']}, vertices {m['vertices']}, "
              f"boxes clipped {len(m['clipped'])} ({clip / m['window_area']:.1e} of the window)", flush=True)


if __name__ == "__main__":
    main()
