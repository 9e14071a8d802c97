"""Cost of the tangent (variational) system on the nine-bar's chaos case, per crank cycle.

The chaos case (studies/chaos/chaos.toml: joints A and B, c = 0.1 mm, omega = 2 pi, c_f = 0.01,
DOP853, rtol = atol = 1e-6 as in the scene), advanced through its default transient (20
cycles), then ``--cycles`` cycles (default 2) integrated

1. plain (the model alone; the baseline, best of ``--repeats``);
2. with m = 1, 4 and 8 tangent vectors (``--exponents``): the run
   ``lyapunov_spectrum(scene, exponents=m, check=False)`` makes over that window
   (:func:`workbench.analysis._lyapunov.tangent_run`: variational equations with saltation,
   re-orthonormalised by Gram-Schmidt where the orthogonality defect reaches DEFECT).

For each: CPU seconds per cycle (``time.process_time``: the machine is shared), steps, rejected
steps, right-hand-side evaluations (of the system integrated: one tangent evaluation costs
about 2 m + 1 model evaluations, the Jacobian by central differences) and events per cycle,
re-orthonormalisations per cycle, the CPU ratio to the plain run, and the sum check: the sum of
the m exponents against the mean rate of the integrated log volume the vectors span (relative
difference). Recorded (``benchmarks/records/tangent_speed/``): the window (``cycles``, ``t0`` in
s, ``rtol``, ``defect``) and, per run (``runs``: "plain", "m = 1", ...), the columns as named
figures.

Run: ``python benchmarks/tangent_speed.py [--cycles 2] [--exponents 1,4,8] [--rtol R]`` (the
first run compiles the tangent kernel, ~1-2 min).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from _results import record, recording  # benchmarks/_results.py: a JSON record per run

import workbench
from workbench.analysis._lyapunov import DEFECT, tangent_run
from workbench.analysis._window import measurement_window

SCENE = Path(__file__).resolve().parents[1] / "studies" / "chaos" / "chaos.toml"


def plain(prep, cycles: float, rtol: float, repeats: int) -> dict:
    """The model alone over the window: best CPU time of ``repeats``, and its statistics."""
    times = prep.problem.t0 + cycles * prep.period * np.linspace(0.0, 1.0, 101)[1:]
    best = np.inf
    for _ in range(repeats):
        cpu = time.process_time()
        res = prep.solve(prep.problem, times, rtol)
        best = min(best, time.process_time() - cpu)
    return {"cpu": best, "stats": res.stats, "reorthonormalisations": 0, "check": None}


def tangent(prep, m: int, cycles: float, rtol: float, defect: float) -> dict:
    """The tangent run of ``lyapunov_spectrum`` with m vectors over the window."""
    cpu = time.process_time()
    run = tangent_run(prep, m, rtol=rtol, defect=defect, length=cycles * prep.period)
    cpu = time.process_time() - cpu
    T = run["times"][-1] - run["start"]
    total = float(run["log_growth"].sum()) / T
    volume = float(run["log_volume"].sum()) / T
    check = (total, volume, abs(total - volume) / max(abs(volume), 1e-300))
    return {
        "cpu": cpu,
        "stats": run["stats"],
        "reorthonormalisations": run["reorthonormalisations"],
        "check": check,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=float, default=2.0, help="measured cycles")
    parser.add_argument("--exponents", default="1,4,8", help="numbers of tangent vectors")
    parser.add_argument("--rtol", type=float, default=None, help="default: the scene's")
    parser.add_argument("--defect", type=float, default=DEFECT, help="re-orthonormalisation")
    parser.add_argument("--repeats", type=int, default=3, help="repeats of the plain run")
    args = parser.parse_args()
    scene = workbench.load_scene(SCENE).replace(sweep={})
    prep = measurement_window(scene, method="dop853")
    rtol = prep.rtol if args.rtol is None else args.rtol
    k = args.cycles
    print(
        f"nine-bar chaos case, {k:g} cycles after the default transient (t0 = "
        f"{prep.problem.t0:.3f} s), DOP853, rtol {rtol:g}, defect {args.defect:g}"
    )
    tangent(prep, 1, 0.01, rtol, args.defect)  # compiles the tangent kernel (not timed)
    rows = [("plain", plain(prep, k, rtol, args.repeats))]
    for m in (int(v) for v in args.exponents.split(",")):
        rows.append((f"m = {m}", tangent(prep, m, k, rtol, args.defect)))
    base = rows[0][1]["cpu"] / k
    print(
        f"{'run':>7} {'CPU s/cyc':>10} {'x plain':>8} {'steps/cyc':>10} {'rej/cyc':>8} "
        f"{'evals/cyc':>10} {'events/cyc':>10} {'QR/cyc':>8}  sum check (sum, volume rate, rel)"
    )
    runs = {}
    for label, r in rows:
        s = r["stats"]
        check = "" if r["check"] is None else "{:.6g} {:.6g} {:.2g}".format(*r["check"])
        print(
            f"{label:>7} {r['cpu'] / k:10.4g} {r['cpu'] / k / base:8.4g} "
            f"{s['steps'] / k:10.6g} {s['rejected_steps'] / k:8.6g} "
            f"{s['rhs_evaluations'] / k:10.6g} {s['events'] / k:10.6g} "
            f"{r['reorthonormalisations'] / k:8.6g}  {check}"
        )
        runs[label] = {
            "cpu_s_per_cycle": r["cpu"] / k,
            "times_plain": r["cpu"] / k / base,
            "steps_per_cycle": s["steps"] / k,
            "rejected_per_cycle": s["rejected_steps"] / k,
            "evaluations_per_cycle": s["rhs_evaluations"] / k,
            "events_per_cycle": s["events"] / k,
            "reorthonormalisations_per_cycle": r["reorthonormalisations"] / k,
        }
        if r["check"] is not None:
            names = ("exponent_sum", "volume_rate", "sum_check")
            runs[label] |= dict(zip(names, r["check"], strict=True))
    record({"cycles": k, "t0": prep.problem.t0, "rtol": rtol, "defect": args.defect, "runs": runs})


if __name__ == "__main__":
    with recording(__file__):
        main()
