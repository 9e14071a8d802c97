"""Planning a huge campaign: the time from ``run_campaign`` to its first task, for grids of 10^5,
10^6 and 10^7 points (issue 37: a 10^7-point grid printed nothing for minutes).

Two Duffing grids of N points (4 + 2 cycles, one sample per period): ``gamma x delta``
(``gamma`` N / 1000 values x ``delta`` 1000; the forcing period is the same at every point)
and ``omega x gamma`` (``omega`` 1000 values x ``gamma`` N / 1000; a period per value of
omega, so the blocks are dealt by cost). What is timed is everything ``run_campaign`` does
before it starts the first block: the limit and memory checks, the store's lock and manifest,
the deal of the points to 8 blocks (2 workers), the tasks and their order; the execution is
replaced by a stop. Each measure runs in a fresh process and reports the wall and the CPU
seconds of the planning (on a shared machine the wall time follows the load; the CPU time
much less) and the process's peak resident memory.

With ``--old COMMIT`` the same is measured on the package as it was at that commit (extracted
with ``git archive`` into a temporary directory), up to ``--old-max`` points (the old planner
takes minutes at 10^7), and the ratio old / new is printed.

Run: ``python benchmarks/campaign_plan.py [--points 1e5 1e6 1e7] [--old d43be3e]
[--old-max 1e6]``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _results import recording  # benchmarks/_results.py: a JSON record per run

ROOT = Path(__file__).resolve().parents[1]
GRIDS = ("gamma x delta", "omega x gamma")


def scene_spec(grid: str, points: int) -> dict:
    """The Duffing scene of ``grid`` with ``points`` points."""
    first = {"start": 0.2, "stop": 0.5, "num": points // 1000}
    thousand = {"start": 0.1, "stop": 0.4, "num": 1000}
    sweep = (
        {"gamma": first, "delta": thousand}
        if grid == "gamma x delta"
        else {"omega": {"start": 0.5, "stop": 3.0, "num": 1000}, "gamma": first}
    )
    return {
        "model": {"name": "duffing"},
        "run": {"cycles": 4, "transient_cycles": 2},
        "record": {"samples_per_period": 1},
        "sweep": sweep,
    }


def measure(grid: str, points: int) -> dict:
    """In this process: the wall and CPU seconds from ``run_campaign`` to its first task, and
    the peak resident memory (MiB)."""
    import resource

    import workbench
    import workbench.campaign._run as run_module

    class Started(Exception):
        pass

    started = {}

    def first_task(tasks, **kwargs):
        started.update(t=time.perf_counter(), cpu=time.process_time(), tasks=len(tasks))
        raise Started

    run_module.execute = first_task  # the plan, not the work
    scene = workbench.load_scene(scene_spec(grid, points))
    limit = {"max_points": None} if "max_points" in run_module.run_campaign.__kwdefaults__ else {}
    with tempfile.TemporaryDirectory() as d:
        t0, cpu0 = time.perf_counter(), time.process_time()
        try:
            workbench.run_campaign(scene, Path(d) / "c.nc", workers=2, max_memory="1 TiB", **limit)
        except Started:
            pass
    return {
        "seconds": started["t"] - t0,
        "cpu": started["cpu"] - cpu0,
        "tasks": started["tasks"],
        "peak_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    }


def in_process(tree: Path, grid: str, points: int) -> dict:
    """:func:`measure` in a fresh Python whose ``workbench`` is the one under ``tree``."""
    env = {**os.environ, "PYTHONPATH": str(tree), "WORKBENCH_RESULTS": "0"}
    out = subprocess.run(
        [sys.executable, __file__, "--measure", grid, str(points)],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def old_tree(commit: str, into: Path) -> Path:
    """The ``workbench`` package at ``commit``, extracted under ``into``."""
    archive = subprocess.run(
        ["git", "-C", str(ROOT), "archive", commit, "workbench"], capture_output=True, check=True
    )
    subprocess.run(["tar", "-x", "-C", str(into)], input=archive.stdout, check=True)
    return into


def main(args: argparse.Namespace) -> None:
    sizes = [int(float(p)) for p in args.points]
    print("--- planning: wall (CPU) seconds from run_campaign to its first task (2 workers)")
    with tempfile.TemporaryDirectory() as d:
        old = old_tree(args.old, Path(d)) if args.old else None
        for grid in GRIDS:
            for n in sizes:
                new = in_process(ROOT, grid, n)
                line = (
                    f"  {grid:13s} {n:>9d} points: {new['seconds']:6.2f} s ({new['cpu']:.2f} s "
                    f"CPU), {new['tasks']} tasks, peak {new['peak_mib']:.0f} MiB"
                )
                if old is not None and n <= float(args.old_max):
                    before = in_process(old, grid, n)
                    line += (
                        f"; at {args.old}: {before['seconds']:.2f} s ({before['cpu']:.2f} s "
                        f"CPU, {before['cpu'] / new['cpu']:.0f}x), peak "
                        f"{before['peak_mib']:.0f} MiB"
                    )
                print(line, flush=True)


if __name__ == "__main__":
    if sys.argv[1:2] == ["--measure"]:
        print(json.dumps(measure(sys.argv[2], int(sys.argv[3]))))
        sys.exit(0)
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--points", nargs="+", default=["1e5", "1e6", "1e7"])
    parser.add_argument("--old", metavar="COMMIT", help="also measure the package at COMMIT")
    parser.add_argument("--old-max", default="1e6", help="largest grid measured at --old")
    with recording(__file__):
        main(parser.parse_args())
