"""Campaigns on a dask cluster against the local pool, and where a campaign's time goes.

The scene is the paper's Fig. 32 sweep (studies/bifurcation_speed/sweep.toml: nine-bar, joints A
and B, c = 0.1 mm, c_f = 0.01, DOP853 at rtol 1e-6) over ``--points`` values of omega from
0.1 pi to 3 pi rad/s with ``--transient`` + ``--cycles`` crank cycles per point; the points'
costs spread over 10x (low omega: long periods and slow contacts).

Sections (each run is a fresh Python process, so that every campaign starts cold: the pool
starts its fork server, which imports workbench and loads the kernel; the cluster's workers
import workbench and load the kernel through the worker plugin; the cluster's own start is
timed apart, outside the campaign; a second campaign in the same process shows the warm case):

``pool`` / ``cluster`` / ``lean`` (default)
    The local pool of N single-thread processes against a ``distributed.LocalCluster`` of N
    single-thread workers with dask's defaults (``cluster``) and as docs/cluster.md sets one up
    (``lean``: ``workbench.campaign.DASK_CONFIG``, workers that import workbench as they start),
    alternated (pool, cluster, lean, pool, ...) ``--repeats`` times.
    Prints the median wall and CPU time (every process of the run: client, scheduler, fork
    server, workers) of each, the ratio cluster / pool (target <= 1.15) and whether both
    computed the same numbers.
``--threads``
    One cluster worker with N threads against N workers of one thread (the kernels release the
    GIL, so the threads run points at once): wall, CPU, and the threads' overlap (the sum of the
    blocks' walls over the task phase: N when N points run at once, 1 when they take turns).
``--efficiency``
    The local pool at N workers against one worker on the same sweep (default 300 points):
    speed-up and parallel efficiency, and where the time goes: the idle time of the workers
    before their first block (start), between blocks (dispatch) and after their last one (the
    tail), the per-block overhead (dataset, netCDF file), the per-point overhead (scene, problem,
    dataset) and the growth of the summed solver time with N (shared caches, memory bandwidth,
    other load). Then, from the measured cost of every point, the schedule the campaign's blocks
    would get at 16 workers (simulated: the same dispatch rule, no contention), which a 16-core
    machine checks with ``--efficiency --workers 16``.

Every section prints the load average before and after each run (the machine may be shared).

Run: ``python benchmarks/campaign_cluster.py [--workers 2] [--points 32] [--repeats 4]
[--threads] [--efficiency]``; at 16 workers: ``python benchmarks/campaign_cluster.py --workers 16
--points 96 --cycles 30`` (the issue's measurement) and ``--efficiency --workers 16``.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

FIG32 = Path(__file__).resolve().parents[1] / "studies" / "bifurcation_speed" / "sweep.toml"


def fig32_scene(points: int, transient: int, cycles: int):
    """The Fig. 32 sweep with ``points`` values of omega and ``transient`` + ``cycles`` cycles."""
    import workbench

    base = workbench.load_scene(FIG32)
    return base.replace(
        run={"cycles": cycles, "transient_cycles": transient},
        sweep={"omega": {"start": 0.1 * math.pi, "stop": 3 * math.pi, "num": points}},
    )


class TreeCPU:
    """CPU time (user + system, s) of this process and all its descendants, sampled by a thread
    (processes that end between two samples lose at most one interval's time)."""

    def __init__(self, interval: float = 0.05) -> None:
        import psutil

        self._psutil = psutil
        self._me = psutil.Process()
        self.interval = interval
        self._base = self._snapshot()
        self._last = dict(self._base)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _snapshot(self) -> dict[int, float]:
        out = {}
        for p in [self._me, *self._me.children(recursive=True)]:
            try:
                t = p.cpu_times()
                out[p.pid] = t.user + t.system
            except self._psutil.Error:
                continue
        return out

    def _run(self) -> None:
        while not self._stop.wait(self.interval):
            self._last.update(self._snapshot())

    def __enter__(self) -> TreeCPU:
        self._thread.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join()
        self._last.update(self._snapshot())

    @property
    def seconds(self) -> float:
        return sum(v - self._base.get(pid, 0.0) for pid, v in self._last.items())


def block_facts(store: Path, t_call: float, t_return: float) -> dict:
    """Where a campaign's time went, from its block files: per worker slot (process, thread)
    the idle time before its first block, between blocks and after its last one; the summed
    block, point and solver walls (s)."""
    import workbench
    from workbench.campaign import store_paths

    slots: dict[tuple, list] = {}
    point_wall = solver_wall = block_wall = 0.0
    first_extra, later_extra, nblocks = [], [], 0
    for path in sorted(store_paths(store)["blocks"].glob("block-*.nc")):
        with workbench.open_run(path) as b:
            a = b.attrs
            start, wall = float(a["block_started"]), float(a["block_wall_time"])
            slot = (int(a["worker_pid"]), int(a.get("worker_thread", 0)))
            slots.setdefault(slot, []).append((start, start + wall))
            pw, sw = b.point_wall_time.values, b.solver_wall_time.values
            point_wall += float(np.nansum(pw))
            solver_wall += float(np.nansum(sw))
            block_wall += wall
            nblocks += 1
            extra = pw - sw
            if int(a["worker_task_number"]) == 1:
                first_extra.append(float(extra[0]))
                later_extra.extend(extra[1:].tolist())
            else:
                later_extra.extend(extra.tolist())
    end = max(e for v in slots.values() for _, e in v)
    lead = gaps = tail = 0.0
    for v in slots.values():
        v.sort()
        lead += v[0][0] - t_call
        gaps += sum(b[0] - a[1] for a, b in zip(v, v[1:], strict=False))
        tail += end - v[-1][1]
    return {
        "slots": len(slots),
        "blocks": nblocks,
        "lead": lead,
        "gaps": gaps,
        "tail": tail,
        "after": t_return - end,
        "block_wall": block_wall,
        "point_wall": point_wall,
        "solver_wall": solver_wall,
        "first_extra": float(np.mean(first_extra)) if first_extra else float("nan"),
        "later_extra": float(np.median(later_extra)) if later_extra else float("nan"),
        "phase": end - min(v[0][0] for v in slots.values()),
    }


def child(args: argparse.Namespace) -> None:
    """One measurement in this (fresh) process; prints one JSON line."""
    import hashlib

    import workbench

    scene = fig32_scene(args.points, args.transient, args.cycles)
    out: dict = {"mode": args.one, "load": os.getloadavg()[0]}
    client = cluster = None
    kw: dict = {}
    if args.one == "pool":
        kw["workers"] = args.workers
    else:
        import dask
        from distributed import Client, LocalCluster

        from workbench.campaign import DASK_CONFIG
        from workbench.campaign._jobqueue import PRELOAD

        options = {}
        if args.one in ("lean", "threads"):  # the whole child: the scheduler lives here
            dask.config.set(DASK_CONFIG)
            options["preload"] = [PRELOAD]  # workers import workbench as they start
        t0 = time.perf_counter()
        n, threads = (1, args.workers) if args.one == "threads" else (args.workers, 1)
        cluster = LocalCluster(
            n_workers=n,
            threads_per_worker=threads,
            processes=True,
            dashboard_address=None,
            **options,
        )
        client = Client(cluster)
        out["start"] = time.perf_counter() - t0
        kw["client"] = client
    runs = []
    try:
        with tempfile.TemporaryDirectory() as d:
            for label in ("cold", "warm")[: args.runs]:
                store = Path(d) / f"{label}.nc"
                with TreeCPU() as cpu:
                    t_call = time.time()
                    t0 = time.perf_counter()
                    ds = workbench.run_campaign(scene, store, restart=True, **kw)
                    wall = time.perf_counter() - t0
                    t_return = time.time()
                digest = hashlib.sha256(ds.clearance_x.values.tobytes()).hexdigest()[:16]
                facts = block_facts(store, t_call, t_return)
                runs.append(
                    {
                        "label": label,
                        "wall": wall,
                        "cpu": cpu.seconds,
                        "digest": digest,
                        "failed": int(ds.attrs["failed_points"]),
                        "chunk": int(ds.attrs["campaign_chunk"]),
                        "point_costs": np.asarray(ds.point_wall_time.values).ravel().tolist(),
                        **facts,
                    }
                )
                ds.close()
    finally:
        if client is not None:
            client.close()
            cluster.close()
    out["runs"] = runs
    out["load_after"] = os.getloadavg()[0]
    print("JSON " + json.dumps(out))


def measure(mode: str, args: argparse.Namespace, workers: int | None = None) -> dict:
    """Run :func:`child` for ``mode`` in a fresh process (niced like its parent)."""
    cmd = [
        sys.executable,
        __file__,
        "--one",
        mode,
        "--workers",
        str(workers or args.workers),
        "--points",
        str(args.points),
        "--transient",
        str(args.transient),
        "--cycles",
        str(args.cycles),
        "--runs",
        str(args.runs),
    ]
    res = subprocess.run(cmd, capture_output=True, text=True)
    lines = [ln for ln in res.stdout.splitlines() if ln.startswith("JSON ")]
    if res.returncode or not lines:
        sys.stderr.write(res.stderr[-4000:])
        raise RuntimeError(f"{mode} run failed (exit {res.returncode})")
    return json.loads(lines[-1][5:])


def _median(rows: list[dict], key: str, label: str = "cold") -> float:
    return statistics.median(r[key] for row in rows for r in row["runs"] if r["label"] == label)


def _spread(rows: list[dict], key: str, label: str = "cold") -> str:
    vals = sorted(r[key] for row in rows for r in row["runs"] if r["label"] == label)
    return f"{vals[0]:.2f}-{vals[-1]:.2f}"


def describe(run: dict, workers: int) -> str:
    """Where the time of one campaign went, as shares of workers x wall."""
    total = workers * run["wall"]
    parts = {
        "solver": run["solver_wall"],
        "per point": run["point_wall"] - run["solver_wall"],
        "per block": run["block_wall"] - run["point_wall"],
        "start": run["lead"],
        "dispatch": run["gaps"],
        "tail": run["tail"],
        "after": workers * run["after"],
    }
    shown = ", ".join(f"{k} {v / total:5.1%}" for k, v in parts.items())
    return (
        f"{shown} (of {workers} x {run['wall']:.2f} s; {run['blocks']} blocks of "
        f"<= {run['chunk']} points; first point of a worker {run['first_extra'] * 1e3:.0f} ms "
        f"outside the solver, later ones {run['later_extra'] * 1e3:.1f} ms)"
    )


def compare(args: argparse.Namespace, modes: tuple[str, ...]) -> None:
    """Alternate the modes ``--repeats`` times; print medians and the ratios to the first."""
    rows: dict[str, list[dict]] = {m: [] for m in modes}
    for rep in range(args.repeats):
        for mode in modes:
            r = measure(mode, args)
            rows[mode].append(r)
            cold = r["runs"][0]
            print(
                f"  [{rep + 1}/{args.repeats}] {mode:8s} cold {cold['wall']:6.2f} s wall "
                f"{cold['cpu']:6.2f} s CPU"
                + (
                    f", warm {r['runs'][1]['wall']:6.2f} s wall {r['runs'][1]['cpu']:6.2f} s CPU"
                    if len(r["runs"]) > 1
                    else ""
                )
                + (f" (cluster start {r['start']:.2f} s)" if "start" in r else "")
                + f"; load {r['load']:.1f} -> {r['load_after']:.1f}",
                flush=True,
            )
    digests = {r["digest"] for m in modes for row in rows[m] for r in row["runs"]}
    base = modes[0]
    summary: dict = {}
    for label in ("cold", "warm")[: args.runs]:
        med = {m: _median(rows[m], "wall", label) for m in modes}
        cpu = {m: _median(rows[m], "cpu", label) for m in modes}
        summary[label] = {"wall": med, "cpu": cpu}
        print(
            f"{label}: median wall "
            + ", ".join(f"{m} {med[m]:.2f} s ({_spread(rows[m], 'wall', label)})" for m in modes)
            + "; ratio to "
            + base
            + " "
            + ", ".join(f"{m} {med[m] / med[base]:.3f}" for m in modes[1:])
            + "; median CPU "
            + ", ".join(f"{m} {cpu[m]:.2f} s" for m in modes)
            + " (ratio "
            + ", ".join(f"{m} {cpu[m] / cpu[base]:.3f}" for m in modes[1:])
            + ")"
        )
    for m in modes:
        best = min((row["runs"][-1] for row in rows[m]), key=lambda r: r["wall"])
        print(f"  {m} (fastest {best['label']} run): {describe(best, args.workers)}")
        overlap = statistics.median(threads_overlap(row["runs"][-1]) for row in rows[m])
        print(
            f"  {m}: integrations at once (summed solver wall / task phase, median of the "
            f"{best['label']} runs): {overlap:.2f}"
        )
        summary.setdefault("overlap", {})[m] = overlap
    print(f"same numbers in every run: {len(digests) == 1} ({len(digests)} distinct digests)")
    starts = [row["start"] for m in modes for row in rows[m] if "start" in row]
    if starts:
        print(f"cluster start (outside the campaigns): median {statistics.median(starts):.2f} s")
    for row in (r for m in modes for r in rows[m]):
        for run in row["runs"]:
            run.pop("point_costs", None)
    save(
        "-".join(modes), args, {"summary": summary, "rows": rows, "same_numbers": len(digests) == 1}
    )


def save(section: str, args: argparse.Namespace, payload: dict) -> None:
    """Write a section's measurements to benchmarks/results/campaign_cluster-<section>.json."""
    out = Path(__file__).resolve().parent / "results" / f"campaign_cluster-{section}.json"
    from workbench.campaign import DASK_CONFIG

    meta = {
        "args": {k: v for k, v in vars(args).items() if k != "one"},
        "dask_config_lean": DASK_CONFIG,
        "cpus": len(os.sched_getaffinity(0)),
        "load_average_end": os.getloadavg(),
        "date": time.strftime("%Y-%m-%d %H:%M:%S"),
    }
    out.write_text(json.dumps({**meta, **payload}, indent=1) + "\n")
    print(f"-> {out.relative_to(Path.cwd()) if out.is_relative_to(Path.cwd()) else out}")


def threads_overlap(run: dict) -> float:
    """Integrations at once: the points' summed solver wall time over the task phase (N when N
    threads integrate at once; 1 when they take turns holding the GIL, the points' integration
    times then summing to the campaign's)."""
    return run["solver_wall"] / run["phase"]


def simulate_schedule(costs: list[float], blocks: list[list[int]], order: list[int], n: int):
    """Makespan of dispatching ``blocks`` (point indices into ``costs``) in ``order`` to ``n``
    workers, each taking the next block when it is free (the campaign's rule)."""
    import heapq

    free = [0.0] * n
    heapq.heapify(free)
    for b in order:
        t = heapq.heappop(free)
        heapq.heappush(free, t + sum(costs[i] for i in blocks[b]))
    return max(free)


def efficiency(args: argparse.Namespace) -> None:
    """The pool at N workers against 1, and the 16-worker schedule from the measured costs."""
    import workbench
    from workbench.campaign._run import _BLOCKS_PER_WORKER
    from workbench.campaign._schedule import block_order, partition

    print(
        f"--- efficiency: Fig. 32 sweep, {args.points} points, {args.transient} + "
        f"{args.cycles} cycles, local pool"
    )
    one = measure("pool", args, workers=1)["runs"][0]
    print(
        f"  1 worker: {one['wall']:.1f} s wall, {one['cpu']:.1f} s CPU; load "
        f"{os.getloadavg()[0]:.1f}"
    )
    many = measure("pool", args)["runs"][0]
    n = args.workers
    speedup = one["wall"] / many["wall"]
    growth = many["solver_wall"] / one["solver_wall"]
    print(
        f"  {n} workers: {many['wall']:.1f} s wall, {many['cpu']:.1f} s CPU; speed-up "
        f"{speedup:.2f}, efficiency {speedup / n:.1%}; summed solver time "
        f"{many['solver_wall']:.1f} s against {one['solver_wall']:.1f} s at 1 worker "
        f"({growth:.3f}x: contention); load {os.getloadavg()[0]:.1f}"
    )
    print(f"  {n} workers: {describe(many, n)}")
    costs = one["point_costs"]
    scene = fig32_scene(args.points, args.transient, args.cycles)
    grid = workbench.campaign.expand_sweep(scene)
    simulated = {}
    for target in sorted({n, 16}):
        nblocks = _BLOCKS_PER_WORKER * target
        chunk = max(1, math.ceil(grid.size / nblocks))
        blocks = [list(b) for b in partition(scene, grid, chunk)]
        order = block_order(scene, grid, blocks)
        make = simulate_schedule(costs, blocks, order, target)
        eff = sum(costs) / (target * make)
        contiguous = [list(b) for b in grid.blocks(chunk)]
        make_c = simulate_schedule(costs, contiguous, block_order(scene, grid, contiguous), target)
        print(
            f"  simulated at {target} workers from the measured point costs (1 worker; no "
            f"contention, no overhead): {len(blocks)} blocks of <= {chunk} points, makespan "
            f"{make:.1f} s against the ideal {sum(costs) / target:.1f} s: efficiency {eff:.1%} "
            f"(contiguous blocks, longest first: {sum(costs) / (target * make_c):.1%}; "
            f"largest point {max(costs) / sum(costs) * target:.0%} of a worker's share)"
        )
        simulated[target] = {"dealt": eff, "contiguous": sum(costs) / (target * make_c)}
    by_chunk = {}
    for chunk in sorted({max(1, math.ceil(grid.size / (k * 16))) for k in (4, 8, 16, 32)}):
        blocks = [list(b) for b in partition(scene, grid, chunk)]
        make = simulate_schedule(costs, blocks, block_order(scene, grid, blocks), 16)
        by_chunk[chunk] = sum(costs) / (16 * make)
    print(
        "  simulated at 16 workers by chunk (points per block; dealt, longest first): "
        + ", ".join(f"{c}: {e:.1%}" for c, e in by_chunk.items())
    )
    simulated["16 by chunk"] = by_chunk
    print(
        f"  check at 16 workers on a 16-core machine: python benchmarks/campaign_cluster.py "
        f"--efficiency --workers 16 --points {args.points} --transient {args.transient} "
        f"--cycles {args.cycles} (target >= 85 %)"
    )
    for run in (one, many):
        run["point_costs_summary"] = [min(run["point_costs"]), max(run["point_costs"])]
    save(
        f"efficiency-{n}",
        args,
        {"one": one, "many": many, "speedup": speedup, "simulated": simulated},
    )


def _idle_child(config: str, seconds: float) -> None:
    """CPU per second of an idle LocalCluster of 2 workers (this process: client, scheduler,
    nannies; and each worker process)."""
    import dask
    import psutil
    from distributed import Client, LocalCluster

    from workbench.campaign import DASK_CONFIG

    if config == "lean":
        dask.config.set(DASK_CONFIG)
    with (
        LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None) as cluster,
        Client(cluster),
    ):
        time.sleep(2.0)
        me = psutil.Process()
        procs = [me, *me.children(recursive=True)]
        t0 = {p.pid: sum(p.cpu_times()[:2]) for p in procs}
        time.sleep(seconds)
        used = {p.pid: sum(p.cpu_times()[:2]) - t0[p.pid] for p in procs}
    workers = sorted((v / seconds for k, v in used.items() if k != me.pid and v > 0), reverse=True)
    print("JSON " + json.dumps({"client": used[me.pid] / seconds, "workers": workers[:2]}))


def idle(args: argparse.Namespace) -> None:
    """Idle CPU of a 2-worker LocalCluster with dask's defaults and with DASK_CONFIG."""
    print("--- idle LocalCluster of 2 workers: CPU s per s of wall time (alternated)")
    out: dict = {"default": [], "lean": []}
    for _ in range(args.repeats):
        for config in out:
            code = (
                f"import sys; sys.path.insert(0, {str(Path(__file__).parent)!r}); "
                f"import campaign_cluster as c; c._idle_child({config!r}, 15.0)"
            )
            res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
            line = [ln for ln in res.stdout.splitlines() if ln.startswith("JSON ")][-1]
            r = json.loads(line[5:])
            r["total"] = r["client"] + sum(r["workers"])
            out[config].append(r)
            print(
                f"  {config:8s} client+scheduler {r['client']:.4f}, workers "
                f"{', '.join(f'{w:.4f}' for w in r['workers'])}: total {r['total']:.4f}; load "
                f"{os.getloadavg()[0]:.1f}",
                flush=True,
            )
    med = {k: statistics.median(r["total"] for r in v) for k, v in out.items()}
    print(
        f"median total: dask's defaults {med['default']:.3f}, DASK_CONFIG {med['lean']:.3f} "
        "CPU-s per s"
    )
    save("idle", args, {"idle": out, "median": med})


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workers", type=int, default=2, help="workers (single-thread) (2)")
    ap.add_argument(
        "--points", type=int, default=None, help="omega values (32; 300 with --efficiency)"
    )
    ap.add_argument("--transient", type=int, default=2, help="transient cycles per point (2)")
    ap.add_argument("--cycles", type=int, default=4, help="recorded cycles per point (4)")
    ap.add_argument("--repeats", type=int, default=4, help="alternations (4)")
    ap.add_argument("--runs", type=int, default=2, help="campaigns per process: cold, warm (2)")
    ap.add_argument("--threads", action="store_true", help="1 worker x N threads vs N x 1")
    ap.add_argument("--efficiency", action="store_true", help="N workers against 1 (pool)")
    ap.add_argument("--idle", action="store_true", help="idle CPU of dask's processes")
    ap.add_argument("--one", choices=("pool", "cluster", "lean", "threads"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.points is None:
        args.points = 300 if args.efficiency else 32
    if args.one:
        child(args)
        return
    print(
        f"CPUs available: {len(os.sched_getaffinity(0))}; load average {os.getloadavg()}; "
        f"{args.workers} workers; Fig. 32 sweep, {args.points} points x ({args.transient} + "
        f"{args.cycles}) cycles"
    )
    if args.efficiency:
        args.runs = 1
        efficiency(args)
    elif args.idle:
        idle(args)
    elif args.threads:
        print(
            f"--- 1 worker x {args.workers} threads against {args.workers} workers x 1 thread "
            "(LocalCluster, workbench.campaign.DASK_CONFIG)"
        )
        compare(args, ("lean", "threads"))
    else:
        print(
            f"--- local pool against LocalCluster, {args.workers} single-thread workers each: "
            "dask's defaults (cluster) and workbench.campaign.DASK_CONFIG (lean)"
        )
        compare(args, ("pool", "cluster", "lean"))
    print(f"load average at the end: {os.getloadavg()}")


if __name__ == "__main__":
    main()
