"""Largest Lyapunov exponent of Lorenz x: workbench's Wolf estimate against nolds.

Lorenz (10, 28, 8/3), x sampled at dt = 0.01 after a 20 s transient, 10 000 and 20 000 points.
For each: ``workbench.analysis.wolf_lle`` with every choice automatic (map or flow detected,
delay, dimension, evolution time, scales, the reliability checks), ``nolds.lyap_r`` with its
defaults, and ``nolds.lyap_r`` tuned (emb_dim 5, lag 16, min_tsep 100, fit over samples
100-400), all in the same run: wall time (an untraced call), peak memory (tracemalloc: Python
allocations, numpy included; a second call) and the error against 0.9056 1/s. Target: under
0.5 s for 10 000 points, under 100 MB for 20 000, at least 10x faster than nolds. (The error
against the exponent of each window is what tests/analysis/test_wolf_heldout.py judges; a
100-s window's
own exponent scatters by several % about 0.9056.) Then wolf_lle's verdict on the same run
sampled every 20th point (dt = 0.2 s): flagged.

Then the exponents from the equations, per method with its converged flag and wall time: on
Lorenz (200 s after 10 s) ``lle_from_equations`` (two trajectories, five knob variants, the
variational exponent on the same trajectory) and ``lyapunov_spectrum`` (QR); on the nine-bar
chaos case (studies/chaos/chaos.toml, 4 transient + 3 crank cycles) the same two
(``--skip-ninebar`` leaves it out: several minutes).

``--scan``: the bias of the two-trajectory estimate on the chaos case (issue 24, item 2): on
four independent starts (realisations 0-3 after 20 transient cycles) copies at scaled
separations d0 = 1e-10 .. 1e-4 and the variational equations ride one fiducial trajectory, at
rtol 1e-6 (10 cycles per start) and 1e-10 (5 cycles) by default (``--scan-configs
RTOL:CYCLES ...``, ``--max-step`` S to cap the steps); printed per d0: each start's estimate
minus the variational exponent on the same trajectory, their mean and its standard error
(``benchmarks/results/lle_separation_scan.json``, and the run's record: per tolerance,
``separations``, ``mean_difference``, ``stderr_difference``).

``--chaos RTOL [RTOL ...]``: the default call ``lle_from_equations(chaos, cycles=40,
budget=80, rtol=RTOL)`` (four starts), its value +/- error, cycles, verdict, the variational
exponent on the same trajectories +/- error, the difference, the copies' renormalisations
(all, and those on shrinkage), CPU time and load (``benchmarks/results/lle_chaos.json``, one
entry per tolerance, and the run's record: the same per tolerance).

Run: ``python benchmarks/lle.py [--skip-ninebar | --scan | --chaos 1e-6 1e-10]``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import time
import tracemalloc
import warnings

import nolds
import numpy as np
from _results import record, recording  # benchmarks/_results.py: a JSON record per run

import workbench
from workbench.analysis import ConvergenceWarning, lle_from_equations, lyapunov_spectrum, wolf_lle
from workbench.analysis._convergence import batch_error
from workbench.analysis._copies_run import follow_copies
from workbench.analysis._window import measurement_window

CHAOS = "studies/chaos/chaos.toml"
RESULTS_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "results")

TRUE = 0.9056  # 1/s
DT = 0.01


def measure(f):
    """Value and wall time of one plain call, peak memory of a second, traced call: tracemalloc
    hooks every allocation and slows allocation-heavy Python code (wolf_lle on 10 000 points
    by ~70 %), so it must not run while the time is taken."""
    t0 = time.perf_counter()
    value = f()
    wall = time.perf_counter() - t0
    tracemalloc.start()
    f()
    peak = tracemalloc.get_traced_memory()[1] / 2**20
    tracemalloc.stop()
    return value, wall, peak


def nolds_tuned(x):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        _, (ks, div, _) = nolds.lyap_r(
            x, emb_dim=5, lag=16, min_tsep=100, trajectory_len=400, debug_data=True
        )
    ks, div = np.asarray(ks), np.asarray(div)
    sel = (ks >= 100) & (ks <= 400) & np.isfinite(div)
    return float(np.polyfit(ks[sel], div[sel], 1)[0]) / DT


def nolds_default(x):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return float(nolds.lyap_r(x)) / DT


def equations(label: str, scene, lyapunov_exponents: int | None) -> None:
    """The exponents from the equations of one scene: value, converged flag, wall time."""
    t0 = time.perf_counter()
    b = lle_from_equations(scene)
    wall_b = time.perf_counter() - t0
    t0 = time.perf_counter()
    v = lyapunov_spectrum(scene, exponents=lyapunov_exponents)
    wall_v = time.perf_counter() - t0
    print(
        f"{label:>10} {'two trajectories':>26} {float(b.lle):9.4f} {str(bool(b.converged)):>9} "
        f"{wall_b:8.1f}   variants {100 * float(b.spread):.2g} %, stderr {float(b.stderr):.3g}"
    )
    print(
        f"{label:>10} {'variational, same run':>26} {float(b.lle_variational):9.4f} "
        f"{'':>9} {'':>8}   differs by {100 * float(b.method_difference):.2g} %"
    )
    print(
        f"{label:>10} {'variational spectrum (QR)':>26} {float(v.exponent[0]):9.4f} "
        f"{str(bool(v.converged)):>9} {wall_v:8.1f}   rtol/100: "
        f"{float(v.exponent_tight[0]):.4g}, stderr {float(v.stderr[0]):.3g}, sum "
        f"{float(v.spectrum_sum):.4g} (volume rate {float(v.volume_rate):.4g}, sum check "
        f"{float(v.sum_check):.2g})"
    )


def _save(name: str, key: str, entry: dict) -> None:
    path = os.path.join(RESULTS_DIR, name)
    data = {}
    if os.path.exists(path):
        with open(path) as f:
            data = json.load(f)
    data[key] = entry
    with open(path, "w") as f:
        json.dump(data, f, indent=1)


def scan(configs: list[tuple[float, int]], max_step: float | None = None) -> None:
    """Two-trajectory estimate minus the variational exponent on the same trajectory, per
    separation and tolerance (``configs``: rtol and cycles per start), over four independent
    starts, optionally with the step capped at ``max_step`` (s)."""
    seps = 10.0 ** np.arange(-10, -3)
    base = workbench.load_scene(CHAOS)
    out = {}
    for rtol, cycles in configs:
        diffs, rates, cpu = [], [], 0.0
        for k in range(4):
            scene = base.replace(run={"cycles": cycles, "transient_cycles": 20, "realisation": k})
            prep = measurement_window(scene)
            if max_step is not None:
                prep = dataclasses.replace(prep, max_step=max_step)
            t0 = time.process_time()
            run = follow_copies(
                prep, seps, np.full(seps.size, math.log(10)), prep.length, rtol, k,
                variational=True,
            )  # fmt: skip
            cpu += time.process_time() - t0
            T = run["times"][-1] - run["times"][0]
            lv = run["variational"][-1] / T
            rates.append([lv, *(run["total"][-1] / T)])
            diffs.append(run["total"][-1] / T - lv)
            errs = [
                batch_error(
                    run["times"][1:], np.diff(run["total"][:, c] - run["variational"])[:, None],
                    run["times"][0],
                )[0]
                for c in range(seps.size)
            ]  # fmt: skip
            print(
                f"rtol {rtol:g}, start {k}, {cycles} cycles: variational {lv:.3f} 1/s; minus it "
                + ", ".join(
                    f"{d:.0e}: {x:+.3f}+/-{e:.2f}"
                    for d, x, e in zip(seps, diffs[-1], errs, strict=True)
                )
            )
        diffs = np.array(diffs)
        mean, se = diffs.mean(axis=0), diffs.std(axis=0, ddof=1) / 2.0
        print(f"rtol {rtol:g}, mean over 4 starts of (two trajectories - variational), 1/s:")
        for d, m, e in zip(seps, mean, se, strict=True):
            print(f"  d0 {d:.0e}: {m:+.3f} +/- {e:.3f}")
        print(f"  ({cpu:.0f} s CPU)")
        out[f"{rtol:g}" + ("" if max_step is None else f", max_step {max_step:g} s")] = {
            "separations": seps.tolist(),
            "cycles_per_start": cycles,
            "rates_variational_then_copies": np.array(rates).tolist(),
            "mean_difference": mean.tolist(),
            "stderr_difference": se.tolist(),
            "cpu_s": cpu,
        }
    record(out)
    path = os.path.join(RESULTS_DIR, "lle_separation_scan.json")
    data = json.load(open(path)) if os.path.exists(path) else {}
    data.setdefault("scan", {}).update(out)
    with open(path, "w") as f:
        json.dump(data, f, indent=1)


def chaos_calls(rtols: list[float]) -> None:
    """The default call on the chaos case at each tolerance."""
    base = workbench.load_scene(CHAOS).replace(run={"cycles": 40, "transient_cycles": 20})
    for rtol in rtols:
        load0 = os.getloadavg()[0]
        t0, w0 = time.process_time(), time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            r = lle_from_equations(base, budget=80, rtol=rtol)
        cpu, wall = time.process_time() - t0, time.perf_counter() - w0
        load1 = os.getloadavg()[0]
        print(
            f"rtol {rtol:g}: two trajectories {float(r.lle):.2f} +/- {float(r.stderr):.2f} 1/s "
            f"(starts {float(r.stderr_starts):.2f}, batches {float(r.stderr_batches):.2f}) over "
            f"{r.attrs['starts']} x {r.attrs['cycles_per_start']:g} cycles, converged "
            f"{bool(r.converged)}; variational (same trajectories) "
            f"{float(r.lle_variational):.2f} +/- {float(r.stderr_variational):.2f}; difference "
            f"{float(r.difference):+.3f} +/- {float(r.stderr_difference):.3f}; at rtol "
            f"{max(rtol / 100, 1e-11):g}: {float(r.lle_tight):.2f} +/- "
            f"{float(r.stderr_tight):.2f}; "
            f"variants {np.round(r.estimate.values, 2).tolist()}; starts "
            f"{np.round(r.start_lle.values, 2).tolist()}; renormalisations "
            f"{r.renormalisations.values.astype(int).tolist()}, of them on shrinkage "
            f"{r.shrink_renormalisations.values.astype(int).tolist()}; "
            f"{cpu:.0f} s CPU, {wall:.0f} s wall, "
            f"load {load0:.1f} -> {load1:.1f}, {r.attrs['solver_steps']} steps"
        )
        for line in r.attrs["failed"].splitlines():
            print(f"    failed: {line}")
        entry = {
            "lle": float(r.lle), "stderr": float(r.stderr),
            "stderr_starts": float(r.stderr_starts),
            "stderr_batches": float(r.stderr_batches),
            "start_lle": r.start_lle.values.tolist(),
            "cycles": r.attrs["cycles"], "starts": r.attrs["starts"],
            "converged": bool(r.converged), "failed": r.attrs["failed"],
            "lle_variational": float(r.lle_variational),
            "stderr_variational": float(r.stderr_variational),
            "difference": float(r.difference),
            "stderr_difference": float(r.stderr_difference),
            "lle_tight": float(r.lle_tight), "stderr_tight": float(r.stderr_tight),
            "estimates": r.estimate.values.tolist(), "rtol_used": r.attrs["rtol"],
            "renormalisations": r.renormalisations.values.tolist(),
            "shrink_renormalisations": r.shrink_renormalisations.values.tolist(),
            "cpu_s": cpu, "wall_s": wall, "load": [load0, load1],
        }  # fmt: skip
        _save("lle_chaos.json", f"{rtol:g}", entry)
        extra = {
            "cycles_per_start": r.attrs["cycles_per_start"],
            "rtol_tight": max(rtol / 100, 1e-11),
            "solver_steps": r.attrs["solver_steps"],
        }
        record({f"{rtol:g}": entry | extra})


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--skip-ninebar", action="store_true", help="leave out the nine-bar")
    parser.add_argument("--scan", action="store_true", help="only the separation scan")
    parser.add_argument(
        "--scan-configs", nargs="+", default=["1e-6:10", "1e-10:5"],
        help="rtol:cycles per start of the scan (default 1e-6:10 1e-10:5)",
    )  # fmt: skip
    parser.add_argument("--max-step", type=float, help="cap the scan's steps (s)")
    parser.add_argument("--chaos", type=float, nargs="+", help="only the default call at RTOLs")
    args = parser.parse_args()
    if args.scan:
        configs = [(float(c.split(":")[0]), int(c.split(":")[1])) for c in args.scan_configs]
        return scan(configs, args.max_step)
    if args.chaos:
        return chaos_calls(args.chaos)
    ds = workbench.simulate(
        {
            "model": {"name": "lorenz"},
            "run": {"duration": 200.0, "transient": 20.0},
            "record": {"dt": DT},
            "solver": {"rtol": 1e-10, "atol": 1e-10},
        }
    )
    wolf_lle(ds.x[:2000])  # warm-up (imports, caches)
    print(
        f"{'points':>7} {'estimator':>22} {'LLE 1/s':>9} {'error':>8} {'time s':>8} {'peak MB':>8}"
    )
    for n in (10_000, 20_000):
        x = ds.x[:n]
        rows = [("wolf_lle (automatic)", lambda x=x: float(wolf_lle(x).lle))]
        rows.append(("nolds.lyap_r tuned", lambda x=x: nolds_tuned(x.values)))
        rows.append(("nolds.lyap_r defaults", lambda x=x: nolds_default(x.values)))
        results = {}
        for name, f in rows:
            value, wall, peak = measure(f)
            results[name] = wall
            print(
                f"{n:7d} {name:>22} {value:9.4f} {value / TRUE - 1:+8.1%} {wall:8.2f} {peak:8.1f}"
            )
        ratio = results["nolds.lyap_r tuned"] / results["wolf_lle (automatic)"]
        print(f"{'':7} wolf_lle is {ratio:.1f}x faster than tuned nolds")
        r = wolf_lle(x)
        print(
            f"{'':7} wolf_lle: {r.attrs['series_kind']}, dim {int(r.dim)}, delay {int(r.delay)}, "
            f"evolve {int(r.evolve)}, {int(r.replacements)} replacements, lambda dt "
            f"{float(r.lle_per_sample):.4f}, reliable {bool(r.reliable)}"
        )
    coarse = wolf_lle(ds.x[::20])
    print(
        f"dt = 0.2 s ({coarse.sizes['elapsed']} steps): LLE {float(coarse.lle):.3f} 1/s, reliable "
        f"{bool(coarse.reliable)}: {coarse.reliable.attrs['message'][:110]}..."
    )
    print(f"\n{'system':>10} {'method':>26} {'LLE 1/s':>9} {'converged':>9} {'time s':>8}")
    lorenz = {"model": {"name": "lorenz"}, "run": {"duration": 200.0, "transient": 10.0}}
    equations("Lorenz", lorenz, None)
    if not args.skip_ninebar:
        chaos = workbench.load_scene("studies/chaos/chaos.toml").replace(
            run={"cycles": 3, "transient_cycles": 4}
        )
        equations("nine-bar", chaos, 1)


if __name__ == "__main__":
    with recording(__file__):
        main()
