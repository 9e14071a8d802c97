"""Speed of a declared mechanism against its built-in twin (issue 42, item 5): CPU seconds per
crank cycle of the declared nine-bar (studies/mechanisms/ninebar.toml) and of the built-in
``ninebar`` on the default scene (studies/ninebar.toml: joints A and B, 0.5 mm, omega = 2.5 pi,
modified Coulomb, DOP853 at rtol = atol = 1e-6), 2 transient + ``--cycles`` recorded cycles from
rest, the integration alone (``time.process_time``), each figure the range over repeats; and the
cost of one right-hand side call of each at the 2001 recorded states of the first cycle.

Target: the declared nine-bar at most 1.2x the built-in's CPU per cycle. The two runs take
different step sequences (the motion is chaotic and their right-hand sides differ by rounding),
so the CPU per evaluation is the comparison of their code, the CPU per cycle that of what a
user waits for.

Run: ``python benchmarks/declared_speed.py [--repeats N] [--cycles N]`` (about a minute once
the kernels are compiled; the first run compiles the declared nine-bar's, a few minutes).
"""

from __future__ import annotations

import argparse
import importlib
import time
import tomllib
from pathlib import Path

import numpy as np
from _hook_calls import hook_calls  # benchmarks/_hook_calls.py
from _results import record, recording  # benchmarks/_results.py: a JSON record per run

import workbench
from workbench.run import prepare
from workbench.solver import integrate

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "studies" / "ninebar.toml"
DECLARATION = ROOT / "studies" / "mechanisms" / "ninebar.toml"
TARGET = 1.2


def scenes(cycles: int) -> dict[str, workbench.Scene]:
    """The built-in and the declared nine-bar on the default scene's effects and parameters."""
    base = workbench.load_scene(SCENE)
    p = base.parameters
    with open(DECLARATION, "rb") as f:
        mechanism = tomllib.load(f)["mechanism"]
    declared = workbench.load_scene(
        {
            "model": {"name": "declared"},
            "mechanism": mechanism,
            "effects": dict(base.effects),
            "parameters": {
                "omega": p["omega"],
                "clearance_A": p["clearance"],
                "clearance_B": p["clearance"],
                "friction_coefficient": p["friction_coefficient"],
            },
        }
    )
    out = {}
    for name, scene in (("builtin", base), ("declared", declared)):
        out[name] = scene.replace(
            solver=dict(base.solver),
            run={"cycles": cycles, "transient_cycles": 2},
            record={"samples_per_period": 100, "variables": ["clearance_x"]},
        )
    return out


def per_cycle(scene, cycles: int, repeats: int) -> dict:
    """CPU seconds per cycle (min, max over repeats) and evaluations per cycle."""
    prepared = prepare(scene)
    prob, t = prepared.problem, prepared.times
    rtol, atol = scene.solver["rtol"], scene.solver["atol"]
    integrate(prob, t[:2], method="dop853", rtol=rtol, atol=atol)  # compile or load
    n = cycles + 2
    times = []
    for _ in range(repeats):
        c0 = time.process_time()
        run = integrate(prob, t, method="dop853", rtol=rtol, atol=atol)
        times.append((time.process_time() - c0) / n)
    run.raise_for_status()
    evals = run.stats["rhs_evaluations"] / n
    return {"s": (min(times), max(times)), "evals": evals}


def rhs_cost(scene, repeats: int, reps: int = 100) -> tuple[float, float]:
    """CPU microseconds per right-hand side call (min, max) at the first cycle's records."""
    one = scene.replace(
        run={"cycles": 1, "transient_cycles": 0},
        record={"samples_per_period": 2000, "variables": ["clearance_x"]},
    )
    prepared = prepare(one)
    prob = prepared.problem
    run = integrate(prob, prepared.times, method="dop853", rtol=1e-6, atol=1e-6)
    rhs = importlib.import_module(prob.hooks).rhs
    work = np.zeros(prob.work_size)
    hook_calls(rhs, run.t, run.Y, prob.p, prob.ip, run.AUX, work, 1)
    times = []
    for _ in range(repeats):
        c0 = time.process_time()
        hook_calls(rhs, run.t, run.Y, prob.p, prob.ip, run.AUX, work, reps)
        times.append((time.process_time() - c0) / (reps * run.t.size) * 1e6)
    return min(times), max(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--cycles", type=int, default=10)
    args = parser.parse_args()
    figures = {}
    for name, scene in scenes(args.cycles).items():
        r = per_cycle(scene, args.cycles, args.repeats)
        us = rhs_cost(scene, args.repeats)
        figures[name] = {
            "s_per_cycle": list(r["s"]),
            "evals_per_cycle": r["evals"],
            "us_per_eval_in_solver": r["s"][0] / r["evals"] * 1e6,
            "us_per_rhs_call": list(us),
        }
        print(
            f"{name:9s} {r['s'][0]:.4f}-{r['s'][1]:.4f} s/cycle, {r['evals']:.0f} evaluations "
            f"per cycle, {r['s'][0] / r['evals'] * 1e6:.3f} us per evaluation in the solver, "
            f"rhs alone {us[0]:.3f}-{us[1]:.3f} us per call"
        )
    ratio = figures["declared"]["s_per_cycle"][0] / figures["builtin"]["s_per_cycle"][0]
    per_eval = (
        figures["declared"]["us_per_eval_in_solver"] / figures["builtin"]["us_per_eval_in_solver"]
    )
    rhs = figures["declared"]["us_per_rhs_call"][0] / figures["builtin"]["us_per_rhs_call"][0]
    print(
        f"declared / built-in: {ratio:.2f}x per cycle, {per_eval:.2f}x per evaluation in the "
        f"solver, {rhs:.2f}x per rhs call (target <= {TARGET}x per cycle: "
        f"{'met' if ratio <= TARGET else 'NOT met'})"
    )
    figures["ratio_per_cycle"] = ratio
    figures["ratio_per_evaluation"] = per_eval
    figures["ratio_per_rhs_call"] = rhs
    record(figures)


if __name__ == "__main__":
    with recording():
        main()
