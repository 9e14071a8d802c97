"""Speed of the nine-bar model: CPU seconds per crank cycle, and where they go.

The default scene (studies/ninebar.toml: joints A and B, 0.5 mm, omega = 2.5 pi, modified
Coulomb), rtol = atol = 1e-6, on one core, CPU time (``time.process_time``) of the integration
alone, each figure the range over repeats, every baseline measured in the same run:

1. the right-hand side alone, per call, at the 2001 recorded states of the first cycle: the lean
   hook ``rhs`` against ``rhs_reference`` (the full record-time evaluation: the formulation the
   hook had before, "before");
2. the compiled solver, 2 transient + 10 recorded cycles: DOP853 with the lean hook and with the
   reference one (before), and DOPRI5; steps, evaluations per cycle (exact) and CPU time per
   evaluation (right-hand side and solver together);
3. the first cycle: compiled DOP853 against ``scipy:DOP853`` on the same compiled hook (the
   ratio is the solver's own speed-up), and against scipy with the plain-Python hook (numba's
   JIT disabled: every numba function runs as Python), measured over the first 0.1 s and
   extrapolated to the cycle by its number of evaluations;
4. against the paper's MATLAB: 20.05 s per cycle (Coulomb), 37.29 s (LuGre);
5. LuGre: ARK548 (the bristles implicit; the best method at rtol 1e-6, see README "Stiff LuGre
   bristles") and DOP853, 2 + 10 cycles.

6. the implicit method (Radau IIA, ``radau``) and the automatic switching (``auto``) against
   DOP853 over omega = 0.1 pi .. 3 pi: one cycle of the default scene from the state after one
   cycle (a common start), and the 0.1 pi and 0.2 pi points from rest;
7. LuGre at 1 um clearance, omega 0.5 pi, rtol 1e-7: the first ``--lugre-fraction`` of a cycle
   by every method, and a whole cycle by ``auto``;
8. the paper's Fig. 32 (300 points x 200 cycles on 2 workers) estimated from the CPU time per
   cycle measured at 9 values of omega on studies/bifurcation_speed/sweep.toml, from rest and
   past 3 settling cycles.

Targets (one quiet core): <= 0.04 s per cycle (Coulomb DOP853), <= 0.1 s per cycle (LuGre);
``auto`` >= 10x fewer evaluations than DOP853 at 0.1 pi and 0.2 pi, >= 10x faster on the 1 um
LuGre case, Fig. 32 <= 20 min.
With ``--accuracy`` also the short-horizon error of DOP853 and ARK548 at rtol 1e-6 and 1e-8
against DOP853 at 1e-11 (first 30 ms, ``workbench.accuracy``), which backs the choice of ARK548.

Run: ``python benchmarks/ninebar_speed.py [--repeats N] [--accuracy]`` (8-12 min; the first run
also compiles the kernels, ~3-6 min); ``--stiff [--parts sweep,rest,lugre,fig32]`` runs only
sections 6-8; ``--kernel`` only sections 1 and 2, the run after a change of a model's compiled
code (the record-time evaluation is what ``rhs_reference`` calls; ~1 min).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import ninebar_reference_hooks  # noqa: F401  (imported: the loop's cache follows its file)
import numpy as np
from _hook_calls import hook_calls  # benchmarks/_hook_calls.py
from _results import recording  # benchmarks/_results.py: a JSON record per run

import workbench
from workbench import accuracy
from workbench.models.ninebar import _dynamics as dyn
from workbench.run import prepare
from workbench.solver import integrate

SCENE = Path(__file__).resolve().parents[1] / "studies" / "ninebar.toml"
FIG32 = SCENE.parent / "bifurcation_speed" / "sweep.toml"  # c = 0.1 mm, c_f = 0.01
PAPER = {"coulomb": 20.05, "lugre": 37.29}
TARGET = {"coulomb": 0.04, "lugre": 0.1}
REFERENCE_HOOKS = "ninebar_reference_hooks"  # benchmarks/: the hooks whose rhs is rhs_reference


def problem(
    friction: str,
    cycles: float,
    transient: int = 0,
    spp: int = 100,
    scene: Path = SCENE,
    **parameters: float,
):
    """A scene's problem (default: the default scene) with this friction law, its record grid
    and the given parameters (e.g. ``omega`` in rad/s, ``clearance`` in m)."""
    base = workbench.load_scene(scene)
    if parameters:
        base = base.with_parameters(**parameters)
    scene = base.replace(
        effects={**base.effects, "friction": friction},
        run={"cycles": cycles, "transient_cycles": transient},
        record={"samples_per_period": spp, "variables": ["clearance_x"]},
    )
    prepared = prepare(scene)
    return prepared.problem, prepared.times


def solve(
    friction: str,
    method: str,
    cycles: float,
    transient: int,
    repeats: int,
    hooks=None,
    rtol: float = 1e-6,
    scene: Path = SCENE,
    **parameters: float,
):
    """CPU time per cycle (min, max over repeats; s) and the exact counts per cycle, from rest
    over ``transient + cycles`` cycles (``cycles`` may be a fraction when ``transient`` is 0)."""
    prob, t_rec = problem(friction, cycles, transient, scene=scene, **parameters)
    if hooks is not None:
        prob.hooks = hooks
    n = cycles + transient
    return _timed(prob, t_rec, method, n, repeats, rtol)


def _timed(prob, t_rec, method: str, n: float, repeats: int, rtol: float) -> dict:
    """Integrate ``prob`` over ``t_rec`` ``repeats`` times: CPU s per cycle (min, max) and the
    counts per cycle (``n`` cycles), the automatic method's switches and time in Radau (s)."""
    integrate(prob, t_rec[:2], method=method, rtol=rtol, atol=rtol)  # compile or load
    times = []
    for _ in range(repeats):
        c0 = time.process_time()
        run = integrate(prob, t_rec, method=method, rtol=rtol, atol=rtol)
        times.append((time.process_time() - c0) / n)
    run.raise_for_status()
    st = run.stats
    return {
        "s": (min(times), max(times)),
        "steps": st["steps"] / n,
        "evals": st["rhs_evaluations"] / n,
        "events": st["events"] / n,
        # the implicit method's statistics (none for scipy's methods)
        "switches": st.get("switches_to_implicit", 0) + st.get("switches_to_explicit", 0),
        "implicit_time": st.get("implicit_time", 0.0),
        "jacobians": st.get("jacobians", 0) / n,
    }


def rhs_cost(friction: str, repeats: int) -> dict[str, tuple[float, float]]:
    """CPU time per call (us; min, max over repeats) of the lean and the reference hook."""
    prob, t_rec = problem(friction, 1, spp=2000)
    run = integrate(prob, t_rec, method="dop853", rtol=1e-6, atol=1e-6)
    work = np.zeros(prob.work_size)
    out = {}
    for name, f in (("lean", dyn.rhs), ("reference", dyn.rhs_reference)):
        reps = 400 if name == "lean" else 50
        hook_calls(f, run.t, run.Y, prob.p, prob.ip, run.AUX, work, 1)
        times = []
        for _ in range(repeats):
            c0 = time.process_time()
            hook_calls(f, run.t, run.Y, prob.p, prob.ip, run.AUX, work, reps)
            times.append((time.process_time() - c0) / (reps * run.t.size) * 1e6)
        out[name] = (min(times), max(times))
    return out


def plain_python(friction: str, horizon: float) -> dict:
    """scipy:DOP853 with numba's JIT disabled over the first ``horizon`` (s), in a fresh
    process: CPU seconds and evaluations."""
    code = (
        "import json, sys, time\n"
        f"sys.path.insert(0, {str(Path(__file__).parent)!r})\n"
        "from ninebar_speed import problem\n"
        "from workbench.solver import integrate\n"
        f"prob, t = problem({friction!r}, 1)\n"
        f"t = t[t <= {horizon!r}]\n"
        "c0 = time.process_time()\n"
        "run = integrate(prob, t, method='scipy:DOP853', rtol=1e-6, atol=1e-6)\n"
        "print(json.dumps({'s': time.process_time() - c0,"
        " 'evals': run.stats['rhs_evaluations']}))\n"
    )
    env = {**os.environ, "NUMBA_DISABLE_JIT": "1"}
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def _range(r: tuple[float, float], fmt: str = ".4f") -> str:
    return f"{r[0]:{fmt}}-{r[1]:{fmt}}"


def _row(name: str, r: dict, friction: str) -> str:
    us = (r["s"][0] / r["evals"] * 1e6, r["s"][1] / r["evals"] * 1e6)
    return (
        f"  {name:24s} {_range(r['s'])} s/cycle  {r['steps']:6.0f} steps  "
        f"{r['evals']:7.0f} evaluations  {r['events']:4.0f} events per cycle  "
        f"{_range(us, '.2f')} us/evaluation  {PAPER[friction] / r['s'][1]:5.0f}x the paper"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=5, help="repeats of each timing (5)")
    ap.add_argument("--accuracy", action="store_true", help="also ARK548's short-horizon error")
    ap.add_argument("--stiff", action="store_true", help="only the implicit and auto sections")
    ap.add_argument(
        "--kernel",
        action="store_true",
        help="only the right-hand sides alone and the Coulomb rows (after a kernel change)",
    )
    ap.add_argument(
        "--lugre-fraction",
        type=float,
        default=0.01,
        help="fraction of the 1 um LuGre cycle measured by every method (0.01)",
    )
    ap.add_argument(
        "--parts", default="sweep,rest,lugre,fig32", help="sections of --stiff (all four)"
    )
    args = ap.parse_args()
    if args.stiff:
        stiff_main(args.repeats, args.lugre_fraction, args.parts)
        return
    print(
        "nine-bar, default scene (A+B, 0.5 mm, omega 2.5 pi), rtol 1e-6; CPU time of one "
        f"process, min-max over {args.repeats} repeats"
    )

    print("--- right-hand side alone (2001 states of the first cycle, Coulomb)")
    cost = rhs_cost("coulomb", args.repeats)
    ratio = (cost["reference"][0] / cost["lean"][1], cost["reference"][1] / cost["lean"][0])
    print(
        f"  lean rhs {_range(cost['lean'], '.3f')} us/call; reference rhs (the full "
        f"evaluation, before) {_range(cost['reference'], '.3f')} us/call: "
        f"{_range(ratio, '.1f')}x"
    )

    print("--- Coulomb (paper's MATLAB: 20.05 s per cycle), 2 + 10 cycles")
    rows = {
        "dop853": solve("coulomb", "dop853", 10, 2, args.repeats),
        "dop853, reference rhs": solve(
            "coulomb", "dop853", 10, 2, max(1, args.repeats // 2), hooks=REFERENCE_HOOKS
        ),
        "dopri5": solve("coulomb", "dopri5", 10, 2, args.repeats),
    }
    for name, r in rows.items():
        print(_row(name, r, "coulomb"))
    best = rows["dop853"]["s"]
    before = rows["dop853, reference rhs"]["s"]
    print(
        f"  lean vs reference rhs in the solver: {before[0] / best[1]:.1f}-"
        f"{before[1] / best[0]:.1f}x; target <= {TARGET['coulomb']} s/cycle: "
        f"{'met' if best[0] <= TARGET['coulomb'] else 'NOT met'} (best repeat {best[0]:.4f})"
    )
    if args.kernel:
        return

    print("--- first cycle (the transient; from rest)")
    first = solve("coulomb", "dop853", 1, 0, args.repeats)
    sp = solve("coulomb", "scipy:DOP853", 1, 0, max(1, args.repeats // 2))
    horizon = 0.1  # s: an eighth of the cycle, impacts and sliding included
    py = plain_python("coulomb", horizon)
    py_cycle = py["s"] / py["evals"] * sp["evals"]
    print(_row("dop853", first, "coulomb"))
    print(_row("scipy:DOP853, same rhs", sp, "coulomb"))
    print(
        f"  scipy:DOP853 with the plain-Python rhs (numba JIT off): {py['s']:.1f} s for the "
        f"first {horizon * 1e3:.0f} ms ({py['evals']} evaluations, "
        f"{py['s'] / py['evals'] * 1e6:.0f} us each), extrapolated to the cycle's "
        f"{sp['evals']:.0f} evaluations: {py_cycle:.0f} s/cycle"
    )
    print(
        f"  compiled dop853 vs scipy:DOP853 on the same compiled rhs: "
        f"{sp['s'][0] / first['s'][1]:.0f}-{sp['s'][1] / first['s'][0]:.0f}x; vs scipy with "
        f"the plain-Python rhs: ~{py_cycle / first['s'][1]:.0f}-{py_cycle / first['s'][0]:.0f}x "
        f"(extrapolated); vs the paper's MATLAB (20.05 s/cycle): "
        f"{PAPER['coulomb'] / best[1]:.0f}-{PAPER['coulomb'] / best[0]:.0f}x"
    )

    print("--- LuGre (paper's MATLAB: 37.29 s per cycle), 2 + 10 cycles")
    lugre = {
        "ark548": solve("lugre", "ark548", 10, 2, args.repeats),
        "dop853": solve("lugre", "dop853", 10, 2, max(1, args.repeats // 2)),
    }
    for name, r in lugre.items():
        print(_row(name, r, "lugre"))
    best = lugre["ark548"]["s"]
    print(
        f"  ARK548 target <= {TARGET['lugre']} s/cycle: "
        f"{'met' if best[0] <= TARGET['lugre'] else 'NOT met'}; vs the paper: "
        f"{PAPER['lugre'] / best[1]:.0f}-{PAPER['lugre'] / best[0]:.0f}x"
    )
    stiff_main(args.repeats, args.lugre_fraction)
    if args.accuracy:
        stiff_remedy()


def stiff_main(repeats: int, lugre_fraction: float, parts: str = "sweep,rest,lugre,fig32") -> None:
    """The implicit method and the automatic switching (issue 16 items 2-3); ``parts`` selects
    the sections."""
    if "sweep" in parts:
        _sweep(repeats)
    if "rest" in parts:
        _from_rest()
    if "lugre" in parts:
        lugre_micron(lugre_fraction)
    if "fig32" in parts:
        fig32_estimate()


def _sweep(repeats: int) -> None:
    """DOP853, Radau IIA and auto over SWEEP_PI, one cycle each from a common state."""
    print(
        "--- automatic switching over the Fig. 32 range of omega: the default scene (0.5 mm, "
        "Coulomb, rtol 1e-6), one cycle from the state after one cycle (DOP853 at rtol 1e-9), "
        "the same start for every method"
    )
    for w in SWEEP_PI:
        start, period = steady_start(w * math.pi)
        t_rec = np.array([start.t0, start.t0 + period])
        reps = repeats if w >= 0.5 else max(1, repeats // 2)
        rows = {m: _timed(start, t_rec, m, 1, reps, 1e-6) for m in ("dop853", "radau", "auto")}
        print(_stiff_row(f"{w:.1f} pi", rows))


def _from_rest() -> None:
    """DOP853, Radau IIA and auto at 0.1 pi and 0.2 pi over the first two cycles from rest."""
    print(
        "--- omega = 0.1 pi and 0.2 pi from rest (1 + 1 cycles: the transient included), "
        "evaluations per cycle"
    )
    for w in (0.1, 0.2):
        rows = {
            m: solve("coulomb", m, 1, 1, 1, omega=w * math.pi) for m in ("dop853", "radau", "auto")
        }
        print(_stiff_row(f"{w:.1f} pi", rows))


#: omega / pi of the sweep over the range of the paper's Fig. 32
SWEEP_PI = (0.1, 0.2, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0)


def steady_start(omega: float, scene: Path = SCENE, transient: int = 1, rtol: float = 1e-9):
    """The default scene at ``omega`` (rad/s) from the state after ``transient`` crank cycles
    from rest, integrated by DOP853 at ``rtol`` (1e-9): a common start for comparing methods on a
    cycle past the transient (the transient's impacts leave the contacts' impact velocities,
    and with them the damping of the contact modes, sensitive to every integration error).
    Returns the problem and the crank period (s)."""
    prob, _ = problem("coulomb", 1, scene=scene, omega=omega)
    period = 2.0 * math.pi / omega
    t_end = prob.t0 + transient * period
    ref = integrate(prob, np.array([prob.t0, t_end]), method="dop853", rtol=rtol, atol=rtol)
    ref.raise_for_status()
    return dataclasses.replace(prob, y0=ref.Y[-1].copy(), aux0=ref.AUX[-1].copy(), t0=t_end), period


def _stiff_row(name: str, rows: dict) -> str:
    """DOP853, Radau IIA and auto on one point: CPU time and evaluations per cycle, auto's
    switches, and the ratios of DOP853's evaluations and of the cheaper fixed method's CPU time
    to auto's."""
    d, r, a = rows["dop853"], rows["radau"], rows["auto"]
    cheaper = "dop853" if d["s"][0] <= r["s"][0] else "radau"
    return (
        f"  {name:7s} dop853 {d['s'][0]:.4f} s {d['evals']:8.0f} ev | radau {r['s'][0]:.4f} s "
        f"{r['evals']:7.0f} ev {r['jacobians']:5.0f} jac | auto {a['s'][0]:.4f} s "
        f"{a['evals']:8.0f} ev, {a['switches']:3d} switches, {a['implicit_time']:6.2f} s in radau"
        f" | dop853/auto evaluations {d['evals'] / a['evals']:6.1f}x; cheaper fixed method "
        f"{cheaper}, auto's CPU / its {a['s'][0] / rows[cheaper]['s'][0]:.2f}"
    )


def lugre_micron(fraction: float) -> None:
    """LuGre at 1 um clearance, omega = 0.5 pi, rtol 1e-7 (the issue's 6 minutes per cycle):
    the first ``fraction`` of a cycle from rest by every method, and a whole cycle by auto."""
    params = {"omega": 0.5 * math.pi, "clearance": 1e-6}
    print(
        f"--- LuGre, 1 um clearance, omega 0.5 pi, rtol 1e-7: the first {fraction:g} cycle "
        "from rest, CPU s per cycle (extrapolated from the fraction)"
    )
    prob, t_rec = problem("lugre", 1, spp=400, **params)
    part = t_rec[t_rec <= prob.t0 + fraction * 4.0 + 1e-12]  # the period is 4 s
    rows = {
        m: _timed(prob, part, m, fraction, 1, 1e-7) for m in ("dop853", "ark548", "radau", "auto")
    }
    for m, r in rows.items():
        print(
            f"  {m:7s} {r['s'][0]:8.2f} s/cycle {r['steps'] * fraction:8.0f} steps "
            f"{r['evals'] * fraction:9.0f} evaluations, {r['switches']} switches"
        )
    best_explicit = min(rows["dop853"]["s"][0], rows["ark548"]["s"][0])
    for m in ("radau", "auto"):
        print(
            f"  {m} vs the better of DOP853/ARK548 on the same fraction: "
            f"{best_explicit / rows[m]['s'][0]:.1f}x CPU, "
            f"{min(rows['dop853']['evals'], rows['ark548']['evals']) / rows[m]['evals']:.1f}x "
            "evaluations (target >= 10x)"
        )
    whole = solve("lugre", "auto", 1, 0, 1, rtol=1e-7, **params)
    print(
        f"  auto over the whole first cycle: {whole['s'][0]:.2f} s ({whole['evals']:.0f} "
        f"evaluations, {whole['switches']} switches, {whole['implicit_time']:.2f} s of 4 s in "
        "radau)"
    )


#: the paper's Fig. 32: points, cycles per point (assumed; see benchmarks/campaign.py), workers
FIG32_POINTS, FIG32_CYCLES, FIG32_WORKERS = 300, 200, 2
FIG32_SAMPLE_PI = (0.1, 0.2, 0.4, 0.7, 1.0, 1.5, 2.0, 2.5, 3.0)


def fig32_estimate(cycles: int = 3, settle: int = 3) -> None:
    """Fig. 32 (studies/bifurcation_speed/sweep.toml: 0.1 mm, c_f 0.01) at 300 points x 200
    cycles on 2 workers, from the CPU time per cycle at FIG32_SAMPLE_PI measured twice: over
    the first ``cycles`` from rest, and over ``cycles`` from the state after ``settle`` cycles
    (DOP853 at rtol 1e-6; the same start for both methods). The cost per cycle is integrated
    over omega by the trapezoidal rule; the 2 workers are taken as 2x (1.96-1.98x measured by
    benchmarks/campaign.py)."""
    print(
        f"--- Fig. 32 estimate: 0.1 mm, c_f 0.01, CPU s per cycle over the first {cycles} "
        f"cycles from rest | over {cycles} cycles after {settle}"
    )
    methods = ("dop853", "auto")
    per = {(m, k): [] for m in methods for k in ("rest", "settled")}
    for w in FIG32_SAMPLE_PI:
        omega = w * math.pi
        rest = {m: solve("coulomb", m, cycles, 0, 1, scene=FIG32, omega=omega) for m in methods}
        start, period = steady_start(omega, FIG32, settle, rtol=1e-6)
        t_rec = np.array([start.t0, start.t0 + cycles * period])
        settled = {m: _timed(start, t_rec, m, cycles, 1, 1e-6) for m in methods}
        line = f"  {w:.1f} pi"
        for k, rows in (("rest", rest), ("settled", settled)):
            for m in methods:
                per[m, k].append(rows[m]["s"][0])
            d, a = rows["dop853"], rows["auto"]
            line += (
                f" | dop853 {d['s'][0]:.4f} s {d['evals']:7.0f} ev, auto {a['s'][0]:.4f} s "
                f"{a['evals']:7.0f} ev {a['switches']:2d} sw: {d['s'][0] / a['s'][0]:.1f}x"
            )
        print(line)
    x = np.array(FIG32_SAMPLE_PI)
    for k in ("rest", "settled"):
        est = {}
        for m in methods:
            c = np.array(per[m, k])
            mean = float(np.sum((c[1:] + c[:-1]) / 2 * np.diff(x)) / (x[-1] - x[0]))
            est[m] = FIG32_POINTS * FIG32_CYCLES * mean / FIG32_WORKERS
        print(
            f"  estimate ({k}) {FIG32_POINTS} x {FIG32_CYCLES} cycles on {FIG32_WORKERS} "
            f"workers: auto {est['auto'] / 60:.1f} min, dop853 {est['dop853'] / 60:.1f} min "
            f"({est['dop853'] / est['auto']:.1f}x); target <= 20 min: "
            f"{'met' if est['auto'] <= 1200 else 'NOT met'}"
        )


def stiff_remedy() -> None:
    """What ARK548 costs in accuracy: short-horizon errors against DOP853 at 1e-11."""

    base = workbench.load_scene(SCENE)
    scene = base.replace(
        effects={**base.effects, "friction": "lugre"},
        run={"cycles": 1, "transient_cycles": 0},
        record={"samples_per_period": 200, "variables": ["clearance_x", "clearance_y"]},
    )
    wp = accuracy(
        scene,
        methods=["dop853", "ark548"],
        tolerances=[1e-6, 1e-8],
        reference=("dop853", 1e-11),
        horizon=0.03,
    )
    print("--- LuGre, first 30 ms: short-horizon error (fraction of range), rhs evaluations")
    for m in wp.solver_method.values:
        for tol in wp.rtol.values:
            r = wp.sel(solver_method=m, rtol=tol)
            print(
                f"  {m:7s} rtol {tol:.0e}: error {float(r.short_error):.2e}, "
                f"{int(r.rhs_evaluations):8d} rhs evaluations (the long run)"
            )


if __name__ == "__main__":
    with recording(__file__):
        main()
