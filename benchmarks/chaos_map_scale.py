"""What a chaos map costs per point by kind, and what a larger map would cost on more workers,
from the per-point costs a computed map keeps.

A map's archive (``workbench chaos-map``, ``data/<map>_map.nc``) keeps per point the wall time
of its run (``solver_wall_time``, s) and of the whole point (``point_wall_time``, s: the run and
its indicators, in one worker) and its strobe period. This script reads them and prints:

- per kind (periodic: a strobe period >= 1; chaotic: none up to 16) the points' cost (the run
  and its indicators) against their own run: the mean, median, 90th percentile and largest
  ratio ``point_wall_time / solver_wall_time`` and the mean costs (s), without the points of
  the full protocol's subset (``lle_full_protocol``; they run it on purpose), which are given
  apart;
- the schedule of the map itself as the campaign runs it (points in grid order, cut into
  blocks of ``ceil(N / (4 W))`` points, each block to the next free worker, with the measured
  per-point costs), against the measured wall time (``measured_wall_time``): how well the
  model of the schedule holds;
- from the same model, a ``--points`` x ``--points`` map over the same ranges, each point
  costing what the measured map's nearest point cost (the costs of a finer map are those of its
  nearest coarse point: the kinds' regions carry over), on each of ``--workers``: its wall time
  and its workers' time.

Run: ``python benchmarks/chaos_map_scale.py [MAP.nc] [--points 100] [--workers 16,64]`` (default
``data/omega_clearance_map.nc``; records in ``benchmarks/records/chaos_map_scale/``).
"""

from __future__ import annotations

import argparse
import heapq
import math
from pathlib import Path

import numpy as np
from _results import record, recording  # benchmarks/_results.py: a JSON record per run

import workbench

ROOT = Path(__file__).resolve().parents[1]
#: blocks per worker of a campaign without a chunk (workbench.campaign._run)
BLOCKS_PER_WORKER = 4


def schedule(costs: np.ndarray, workers: int) -> float:
    """Wall time (s) of points of ``costs`` (s, grid order) cut into blocks of
    ``ceil(N / (BLOCKS_PER_WORKER * workers))`` points, each block started on the next free
    worker (the campaign's dynamic scheduling)."""
    chunk = max(1, math.ceil(costs.size / (BLOCKS_PER_WORKER * workers)))
    blocks = [float(costs[i : i + chunk].sum()) for i in range(0, costs.size, chunk)]
    free = [0.0] * workers
    for b in blocks:
        heapq.heappush(free, heapq.heappop(free) + b)
    return max(free)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("map", nargs="?", default=str(ROOT / "data" / "omega_clearance_map.nc"))
    ap.add_argument("--points", type=int, default=100, help="points per axis of the projection")
    ap.add_argument("--workers", default="16,64", help="workers of the projection")
    args = ap.parse_args()
    maps = workbench.open_run(args.map)
    dims = [d for d in maps.strobe_period.dims]
    point = maps.point_wall_time.transpose(*dims).values
    run = maps.solver_wall_time.transpose(*dims).values
    periodic = maps.strobe_period.transpose(*dims).values >= 1
    subset = np.zeros(point.shape, bool)
    if "lle_full_protocol" in maps:
        subset = maps.lle_full_protocol.transpose(*dims).values == 1
    figures: dict = {"map": Path(args.map).name, "points": int(point.size), "dims": dims}
    kinds = (("periodic", periodic & ~subset), ("chaotic", ~periodic & ~subset))
    for kind, sel in (*kinds, ("full protocol subset", subset)):
        if not sel.any():
            continue
        ratio = point[sel] / run[sel]
        figures[kind] = {
            "points": int(sel.sum()),
            "run_s": float(run[sel].mean()),
            "point_s": float(point[sel].mean()),
            "ratio_mean": float(ratio.mean()),
            "ratio_median": float(np.median(ratio)),
            "ratio_p90": float(np.percentile(ratio, 90)),
            "ratio_max": float(ratio.max()),
        }
        f = figures[kind]
        print(
            f"{kind}: {f['points']} points, run {f['run_s']:.2f} s, point (run and indicators) "
            f"{f['point_s']:.2f} s: {f['ratio_mean']:.2f}x its run (median "
            f"{f['ratio_median']:.2f}x, 90 % at most {f['ratio_p90']:.2f}x, at most "
            f"{f['ratio_max']:.2f}x)"
        )
    measured_workers = 2
    model = schedule(point.ravel(), measured_workers)
    wall = float(maps.attrs.get("measured_wall_time", math.nan))
    figures["measured"] = {
        "workers": measured_workers,
        "wall_s": wall,
        "worker_s": float(maps.attrs.get("measured_worker_time", math.nan)),
        "points_s": float(point.sum()),
        "model_wall_s": model,
    }
    print(
        f"the map: {point.size} points, {point.sum() / 60:.1f} min of the points' time; on "
        f"{measured_workers} workers the schedule model gives {model / 60:.1f} min wall, "
        f"measured {wall / 60:.1f} min"
    )
    # the projection: nearest measured point along each axis
    idx = [np.rint(np.linspace(0, maps.sizes[d] - 1, args.points)).astype(int) for d in dims[:2]]
    fine = point[np.ix_(*idx)]
    figures["projection"] = {"points_per_axis": args.points, "points_s": float(fine.sum())}
    for w in (int(v) for v in args.workers.split(",")):
        t = schedule(fine.ravel(), w)
        figures["projection"][f"wall_s_{w}"] = t
        print(
            f"{args.points} x {args.points} points: {fine.sum() / 3600:.1f} h of the workers' "
            f"time; on {w} workers {t / 60:.0f} min wall"
        )
    record(figures)


if __name__ == "__main__":
    with recording(__file__):
        main()
