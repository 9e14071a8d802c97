"""What continuation buys on the paper's Fig. 32, and what a Newton step costs on the nine-bar.

1. ``fig32``: the omega sweep of ``studies/bifurcation_speed/sweep.toml`` (A+B, c = 0.1 mm,
   Coulomb c_f = 0.01) at the paper's resolution: ``--points`` (300) values of omega from
   0.1 pi to 3 pi, ``--cycles`` (100) recorded cycles each, solver ``auto`` at the study's
   tolerances. The continued sweep (``[sweep] continuation``, direction up, ``--segments``
   segments, ``--transient`` (10) cycles per continued point, the segments' seeds 100 cycles
   from rest) runs on ``--workers`` (2) local workers; its workers' CPU time is summed from its
   blocks (``campaign_cpu_time``). The baseline, measured in the same run: brute force, every
   point 100 transient + 100 recorded cycles from rest (the assumption of
   ``benchmarks/campaign.py`` for the paper's figure), on every ``--stride``-th point (10 of
   300) in this process, its CPU time scaled to all points. Both are divided by the workers for
   the time on an idle machine (the continued sweep's longest segment is printed too: no
   schedule beats it).
2. ``newton``: one Newton step on the nine-bar's period-1 branch (the map over one crank cycle
   with its Jacobian by copies, and its derivative in omega) at omega = 1.0, 1.5 and 1.7 pi,
   CPU time (the orbits are found first).
3. ``chaos_maps``: what a point of the nine-bar's chaos maps (``make chaos-maps``:
   ``studies/chaos_maps/*.toml``) costs: the run and its indicators
   (:func:`workbench.continuation.chaos_indicators`: strobe period, 0-1 K, largest exponent)
   at ``--map-points`` (2) corners of each grid in this process, CPU time per point, beside
   the mean point of the whole map as ``make chaos-maps`` measured it (``data/<map>_map.nc``,
   the points' wall times). Corners are no estimate of a map: a periodic point takes seconds, a
   chaotic one minutes, more with more friction.

Prints every figure with the CPU time (``time.process_time``), the wall time and the load, and
records them (``benchmarks/records/continuation/``, :mod:`_results`: ``newton``,
``continued_sweep`` and ``brute_force``, ``chaos_map_corners``); writes the continued diagram to
``benchmarks/results/continuation_fig32.png``.

Run: ``python benchmarks/continuation.py [--parts newton,fig32,chaos_maps] [--points 300]`` (the
continued figure takes ~13 min of the workers' CPU: ``benchmarks/RESULTS.md``).
"""

from __future__ import annotations

import argparse
import math
import os
import tempfile
import time
from pathlib import Path

import numpy as np
from _results import record, recording  # benchmarks/_results.py: a JSON record per run

import workbench
from workbench.analysis import bifurcation_diagram
from workbench.continuation import StrobeMap, continued_sweep
from workbench.continuation._newton import orbit_at

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "studies" / "bifurcation_speed" / "sweep.toml"
RESULTS = ROOT / "benchmarks" / "results"


def fig32_scene(points: int, cycles: int, transient: int, segments: int, seed_transient: int):
    base = workbench.load_scene(SCENE)
    solver = dict(base.solver, method="auto")
    sweep = {
        "omega": {"start": 0.1 * math.pi, "stop": 3 * math.pi, "num": points},
        "continuation": {
            "direction": "up",
            "segments": segments,
            "transient_cycles": transient,
        },
    }
    return base.replace(
        solver=solver,
        run={"cycles": cycles, "transient_cycles": seed_transient},
        sweep=sweep,
    )


def brute_force_cpu(scene, stride: int) -> tuple[float, int]:
    """CPU seconds of every ``stride``-th point run by brute force (100 + 100 cycles from
    rest) in this process, and how many points."""
    brute = scene.replace(run={"cycles": 100, "transient_cycles": 100}, sweep={})
    values = scene.sweep["omega"][::stride]
    c0 = time.process_time()
    for w in values:
        workbench.simulate(brute.with_parameters(omega=float(w)))
    return time.process_time() - c0, len(values)


def fig32(args) -> None:
    scene = fig32_scene(args.points, args.cycles, args.transient, args.segments, 100)
    workbench.simulate(scene.replace(sweep={}, run={"cycles": 1, "transient_cycles": 0}))
    load0 = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as d:
        t0 = time.perf_counter()
        ds = continued_sweep(scene, Path(d) / "fig32.nc", workers=args.workers)
        wall = time.perf_counter() - t0
        seg_cpu = []
        for p in sorted((Path(d) / "fig32.nc.blocks").glob("block-*.nc")):
            seg_cpu.append(workbench.open_run(p).attrs["block_cpu_time"])
    cpu = float(ds.attrs["campaign_cpu_time"])
    load1, rounds = os.getloadavg()[0], int(ds.attrs["continuation_rounds"])
    seams = int(ds.seam_chained.sum()) if "seam_chained" in ds else 0
    print(
        f"continued sweep (up): {args.points} points x ({args.transient} + {args.cycles}) "
        f"cycles, {args.segments} segments (seeds 100 + {args.cycles} from rest), "
        f"{rounds} round(s), chained seams {seams}: workers' CPU "
        f"{cpu / 60:.1f} min, longest segment {max(seg_cpu) / 60:.1f} min; wall "
        f"{wall / 60:.1f} min on {args.workers} workers (load {load0:.1f} -> "
        f"{load1:.1f}); on an idle machine >= {cpu / args.workers / 60:.1f} min"
    )
    bf, n = brute_force_cpu(scene, args.stride)
    total = bf * args.points / n
    print(
        f"brute force (100 + 100 cycles from rest), {n} of {args.points} points: CPU "
        f"{bf / 60:.2f} min -> {total / 60:.1f} min for all, {total / args.workers / 60:.1f} "
        f"min on {args.workers} workers; continuation {total / cpu:.1f}x less CPU"
    )
    record(
        {
            "continued_sweep": {
                "points": args.points, "transient_cycles": args.transient,
                "cycles": args.cycles, "segments": args.segments, "seed_transient_cycles": 100,
                "seed_cycles": args.cycles, "rounds": rounds, "chained_seams": seams,
                "workers_cpu_min": cpu / 60, "longest_segment_min": max(seg_cpu) / 60,
                "wall_min": wall / 60, "workers": args.workers, "load_before": load0,
                "load_after": load1, "idle_min": cpu / args.workers / 60,
            },
            "brute_force": {
                "transient_cycles": 100, "cycles": 100, "points_run": n,
                "points": args.points, "cpu_min": bf / 60, "cpu_min_all": total / 60,
                "min_on_workers": total / args.workers / 60, "workers": args.workers,
                "cpu_ratio": total / cpu,
            },
        }
    )  # fmt: skip
    diagram = bifurcation_diagram(ds.sel(joint="A"), "clearance_x", "omega")
    from workbench.plot import bifurcation_figure

    fig = bifurcation_figure(diagram, scale=1 / math.pi, xlabel="crank speed omega / pi")
    fig.axes[0].set_title(
        f"Fig. 32 continued upwards: {args.points} points, {args.transient} + {args.cycles} "
        f"cycles each ({cpu / 60:.1f} min CPU; brute force {total / 60:.1f} min CPU)",
        fontsize=8,
    )
    RESULTS.mkdir(parents=True, exist_ok=True)
    fig.savefig(RESULTS / "continuation_fig32.png", dpi=150)
    print(f"figure: {RESULTS / 'continuation_fig32.png'}")


def newton(args) -> None:
    base = workbench.load_scene(SCENE).replace(sweep={})
    for w in (1.0, 1.5, 1.7):
        scene = base.with_parameters(omega=w * math.pi).replace(
            run={"cycles": 1, "transient_cycles": 20}
        )
        smap = StrobeMap(scene, "omega", rtol=1e-8)
        y, aux = smap.initial(smap.value)
        pt = orbit_at(smap, y, aux, smap.value, tolerance=1e-7)
        c0 = time.process_time()
        v = smap(pt.y, pt.aux, pt.p)
        c1 = time.process_time()
        smap.parameter_derivative(pt.y, pt.aux, pt.p, v.live, 1.0)
        c2 = time.process_time()
        largest, load = float(np.abs(np.linalg.eigvals(v.M)).max()), os.getloadavg()[0]
        print(
            f"Newton step at omega = {w} pi ({smap.monodromy}): map and Jacobian {c1 - c0:.2f} s "
            f"CPU ({v.stats['steps']} steps, {smap.monodromy} of {v.M.shape[0]} unknowns), "
            f"parameter derivative {c2 - c1:.2f} s; largest |multiplier| {largest:.4f}; "
            f"load {load:.1f}"
        )
        record(
            {
                "newton": {
                    f"{w}": {
                        "monodromy": smap.monodromy, "map_jacobian_cpu_s": c1 - c0,
                        "steps": v.stats["steps"], "unknowns": v.M.shape[0],
                        "derivative_cpu_s": c2 - c1, "largest_multiplier": largest,
                        "load": load,
                    }
                }
            }
        )  # fmt: skip


def chaos_maps(args) -> None:
    from workbench.continuation import chaos_indicators

    for path in sorted((ROOT / "studies" / "chaos_maps").glob("*.toml")):
        scene = workbench.load_scene(path)
        dims = list(scene.sweep)
        grid = [scene.sweep[d] for d in dims]
        size = math.prod(len(v) for v in grid)
        corners = [[v[0] for v in grid], [v[-1] for v in grid]][: args.map_points]
        cpu = []
        for corner in corners:
            point = scene.replace(sweep={}).with_parameters(**dict(zip(dims, corner, strict=True)))
            c0 = time.process_time()
            run = workbench.simulate(point)
            found = chaos_indicators(point, run)
            cpu.append(time.process_time() - c0)
            shown = ", ".join(f"{d}={v:.4g}" for d, v in zip(dims, corner, strict=True))
            print(
                f"  {path.stem} at {shown}: {cpu[-1]:.1f} s CPU (strobe period "
                f"{int(found.strobe_period)}, K {float(found.zero_one_K):.2f}, lle "
                f"{float(found.lle):.3g} +- {float(found.lle_stderr):.2g} s-1)"
            )
            record(
                {
                    "chaos_map_corners": {
                        f"{path.stem} at {shown}": {
                            "cpu_s": cpu[-1], "strobe_period": int(found.strobe_period),
                            "zero_one_K": float(found.zero_one_K), "lle": float(found.lle),
                            "lle_stderr": float(found.lle_stderr),
                        }
                    }
                }
            )  # fmt: skip
        shape = " x ".join(f"{d} {len(v)}" for d, v in zip(dims, grid, strict=True))
        shipped = ROOT / "data" / f"{path.stem}_map.nc"
        measured = "no archive in data/"
        if shipped.exists():
            maps = workbench.open_run(shipped)
            if workbench.scene_from_toml(maps.attrs["scene"]).to_toml() == scene.to_toml():
                wall = maps.point_wall_time.values
                measured = (
                    f"the whole map (make chaos-maps): {wall.mean():.1f} s per point, "
                    f"{wall.min():.1f}-{wall.max():.1f} s, {wall.sum() / 60:.0f} min of the "
                    f"workers' time"
                )
            else:
                measured = "data/ holds another grid's map"
        print(
            f"chaos map {path.stem} ({shape} = {size} points, "
            f"{scene.run['transient_cycles']} + {scene.run['cycles']} cycles): corners "
            f"{float(np.mean(cpu)):.1f} s CPU per point; {measured}; "
            f"load {os.getloadavg()[0]:.1f}"
        )
        record({"chaos_map_cpu_s_per_point": {path.stem: float(np.mean(cpu))}})


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--parts", default="newton,fig32")
    ap.add_argument("--points", type=int, default=300)
    ap.add_argument("--cycles", type=int, default=100)
    ap.add_argument("--transient", type=int, default=10)
    ap.add_argument("--segments", type=int, default=8)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--stride", type=int, default=30)
    ap.add_argument("--map-points", type=int, default=2)
    args = ap.parse_args()
    parts = args.parts.split(",")
    if "newton" in parts:
        newton(args)
    if "fig32" in parts:
        fig32(args)
    if "chaos_maps" in parts:
        chaos_maps(args)


if __name__ == "__main__":
    with recording(__file__):
        main()
