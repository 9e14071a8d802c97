"""LuGre's bristle damping and what it does to the nine-bar (issue 29).

Two cases, each under four friction laws:

- ``sec42``: the paper's LuGre case of Sec. 4.2 (``studies/friction_models/lugre.toml``: A and
  B, 0.5 mm, omega = 2.5 pi, c_f = 0.05 for Coulomb);
- ``hard``: 1 um clearance, omega = 0.5 pi, c_f = 0.1, restitution 0.9 (the hard case of the
  issue);

laws: modified Coulomb; LuGre with the default damping (s1 = 316.2 s/m fading as
exp(-(v/v_d)^2) above v_d = 1 mm/s, Olsson et al. 1998); LuGre with the paper's constant
s1 = 316.2 s/m (``lugre_damping_velocity = 0``); LuGre with the largest passive constant
damping, s2 mu_k / (mu_s - mu_k) = 0.2 s/m (Barabanov & Ortega 2000). Each run: one crank cycle
recorded after one transient cycle, DOP853 at rtol = atol = 1e-7, 20 000 records per cycle (the
issue's setup). Printed per run: the largest |F_t| / F_n at the records (LuGre: the law's, with
the bristles on their invariant set, ``friction_coefficient``; the raw ratio of the recorded
forces and the records whose bristle deflection left that set, DOP853's dense output, go to the
JSON file), the time per cycle above
mu_s and beyond the envelope 2 mu_s + s2 |v_t| (quadratures, summed over the joints), the peaks
of the contact force, friction force and crank torque, the largest penetration in units of c,
the energy dissipated per cycle, the energy balance's residual, steps, evaluations, events and
the CPU time of the run (``time.process_time``, kernels compiled beforehand).

Speed: the default scene (``studies/ninebar.toml``) with LuGre, 2 + 10 cycles, ARK548 and DOP853
at rtol 1e-6 (as ``benchmarks/ninebar_speed.py`` section 5), the default law against the paper's
in the same run: CPU s per cycle (min-max over the repeats) and their ratio.

Writes ``benchmarks/results/lugre_damping.json``. Run: ``python benchmarks/lugre_damping.py
[--repeats N]`` (~4-8 min on a quiet core; the paper's law takes ~2 min of it on the hard case).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

import workbench

sys.path.insert(0, str(Path(__file__).resolve().parent))
from ninebar_speed import solve  # noqa: E402 (this directory's benchmark)

ROOT = Path(__file__).resolve().parents[1]
RESULTS = Path(__file__).resolve().parent / "results" / "lugre_damping.json"
LAWS = {
    "coulomb": {"friction": "coulomb"},
    "lugre default": {"friction": "lugre"},
    "lugre paper s1": {"friction": "lugre", "lugre_damping_velocity": 0.0},
    "lugre passive constant": {
        "friction": "lugre",
        "lugre_sigma1": 0.2,
        "lugre_damping_velocity": 0.0,
    },
}
CASES = {
    "sec42": {},
    "hard": {
        "clearance": 1e-6,
        "omega": 0.5 * math.pi,
        "friction_coefficient": 0.1,
        "restitution": 0.9,
    },
}
VARIABLES = [
    "contact_force",
    "friction_force",
    "torque",
    "penetration",
    "driver_work",
    "dissipated_energy",
    "kinetic_energy",
    "potential_energy",
]


def scene(case: str, law: str, cycles: int = 1, transient: int = 1):
    """The scene of a case under a law (see the module docstring)."""
    base = workbench.load_scene(ROOT / "studies" / "friction_models" / "lugre.toml")
    params = {**base.parameters, **CASES[case]}
    params.update({k: v for k, v in LAWS[law].items() if k != "friction"})
    return base.replace(
        effects={**base.effects, "friction": LAWS[law]["friction"]},
        parameters=params,
        solver={**base.solver, "method": "dop853", "rtol": 1e-7, "atol": 1e-7},
        run={"cycles": cycles, "transient_cycles": transient},
        record={"samples_per_period": 20_000, "variables": VARIABLES},
    )


def measure(case: str, law: str) -> dict:
    """One run of a case under a law: its numbers (module docstring)."""
    sc = scene(case, law)
    c0 = time.process_time()
    ds = workbench.simulate(sc, throw=False)
    cpu = time.process_time() - c0
    fn = ds.contact_force.values
    ft = np.abs(ds.friction_force.values)
    raw = np.where(fn > 0, ft / np.where(fn > 0, fn, 1.0), 0.0)
    mu = ds.friction_coefficient.values if "friction_coefficient" in ds else raw
    cycles = float(ds.time[-1] - ds.time[0]) / float(ds.attrs["forcing_period"])
    energy = ds.kinetic_energy + ds.potential_energy
    residual = (energy - energy[0]) - ds.driver_work + ds.dissipated_energy
    out = {
        "status": ds.attrs["run_status"],
        "mu_max": float(np.max(mu)),
        "mu_p999_in_contact": float(np.percentile(mu[fn > 0], 99.9)) if (fn > 0).any() else 0.0,
        "raw_force_ratio_max": float(np.max(raw)),
        "contact_force_max_N": float(np.max(fn)),
        "contact_force_median_in_contact_N": float(np.median(fn[fn > 0])) if (fn > 0).any() else 0,
        "friction_force_max_N": float(np.max(ft)),
        "torque_max_Nm": float(np.max(np.abs(ds.torque.values))),
        "penetration_max_over_c": float(ds.penetration.max())
        / float(sc.resolved_parameters["clearance"]),
        "dissipated_J_per_cycle": float(ds.dissipated_energy[-1] - ds.dissipated_energy[0])
        / cycles,
        "energy_residual_J": float(np.abs(residual).max()),
        "driver_work_swing_J": float(np.abs(ds.driver_work).max()),
        "steps": int(ds.attrs["solver_steps"]),
        "rhs_evaluations": int(ds.attrs["solver_rhs_evaluations"]),
        "events": int(ds.attrs["solver_events"]),
        "cpu_s": cpu,
    }
    for key, var in (
        ("above", "time_above_static_friction"),
        ("beyond", "time_beyond_friction_law"),
    ):
        if var in ds:
            out[f"{key}_s_per_cycle"] = float(ds[var][-1].sum()) / cycles
    if "lugre_z" in ds:
        p = sc.resolved_parameters
        bound = max(p["lugre_mu_s"], p["lugre_mu_k"]) / p["lugre_sigma0"]
        out["records_bristles_outside"] = int(np.sum(np.abs(ds.lugre_z.values) > bound * 1.000001))
    return out


def _row(law: str, r: dict) -> str:
    times = (
        f"{1e3 * r['above_s_per_cycle']:8.3f} {1e3 * r['beyond_s_per_cycle']:8.3f}"
        if "above_s_per_cycle" in r
        else f"{'-':>8s} {'-':>8s}"
    )
    return (
        f"  {law:24s} {r['mu_max']:7.3g} {times} {r['contact_force_max_N']:9.4g} "
        f"{r['friction_force_max_N']:9.4g} {r['torque_max_Nm']:8.4g} "
        f"{r['penetration_max_over_c']:7.3g} {r['dissipated_J_per_cycle']:9.4g} "
        f"{r['energy_residual_J']:8.2g} {r['steps']:9d} {r['rhs_evaluations']:10d} "
        f"{r['events']:7d} {r['cpu_s']:7.1f}  {r['status']}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="repeats of the speed rows (3)")
    args = parser.parse_args()
    for friction in ("coulomb", "lugre"):  # compile (or load) the kernels outside the timings
        law = next(k for k, v in LAWS.items() if v["friction"] == friction)
        workbench.simulate(
            scene("sec42", law, cycles=1, transient=0).replace(run={"duration": 1e-3})
        )
    results: dict = {"cases": {}, "speed": {}}
    head = (
        f"  {'law':24s} {'|Ft|/Fn':>7s} {'>mu_s':>8s} {'>envel.':>8s} {'Fn max':>9s} "
        f"{'|Ft| max':>9s} {'|tau|':>8s} {'pen/c':>7s} {'diss/cyc':>9s} {'resid.':>8s} "
        f"{'steps':>9s} {'evals':>10s} {'events':>7s} {'CPU s':>7s}"
    )
    units = "  (|Ft|/Fn at the records; ms per cycle; N, N, N m, 1, J per cycle, J)"
    for case in CASES:
        print(f"--- {case}: {CASES[case] or 'the paper Sec. 4.2 LuGre scene'}")
        print(head)
        print(units)
        results["cases"][case] = {}
        for law in LAWS:
            r = measure(case, law)
            results["cases"][case][law] = r
            print(_row(law, r), flush=True)
    print("--- speed: default scene with LuGre, 2 + 10 cycles, rtol 1e-6, CPU s per cycle")
    for method in ("ark548", "dop853"):
        repeats = args.repeats if method == "ark548" else max(1, args.repeats // 2)
        rows = {
            "default": solve("lugre", method, 10, 2, repeats),
            "paper s1": solve("lugre", method, 10, 2, repeats, lugre_damping_velocity=0.0),
        }
        for law, r in rows.items():
            print(
                f"  {method} {law:9s} {r['s'][0]:.4f}-{r['s'][1]:.4f} s/cycle "
                f"{r['steps']:7.0f} steps {r['evals']:8.0f} evaluations {r['events']:5.0f} "
                "events per cycle",
                flush=True,
            )
        ratio = rows["paper s1"]["s"][0] / rows["default"]["s"][0]
        print(f"  {method}: the paper's law / the default (best repeats): {ratio:.2f}x")
        results["speed"][method] = {**rows, "ratio_paper_over_default": ratio}
    RESULTS.parent.mkdir(exist_ok=True)
    RESULTS.write_text(json.dumps(results, indent=1))
    print(f"results in {RESULTS}")


if __name__ == "__main__":
    main()
