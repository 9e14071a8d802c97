"""What a chaos-map point costs against its own run, by kind (periodic, chaotic), with the
map's own precision (the fast protocol) and with the full protocol (the old per-point path).

On a small nine-bar map (``studies/chaos_maps/omega_clearance.toml`` at ``--omegas`` x
``--clearances`` points, ``--cycles`` recorded after ``--transient`` cycles), every point runs
in this process: its run (:func:`workbench.simulate`), its indicators with the fast protocol
(:func:`workbench.continuation.chaos_indicators`: strobe period, 0-1 K, the exponent from
where the run ended: Newton from the end state where the strobe is periodic, else one start of
the two-trajectory method from there, the 10 % target or the sign beyond 3 errors), and the
exponent by the full protocol (:func:`workbench.continuation.point_exponent` with
``protocol="full"``, which is what every point ran before: Newton from the state integrated
again, or four starts after the transient with the separation and growth variants and a 3 %
target). CPU time (``time.process_time``) per point and the ratio to the point's run; the
mean ratio per kind (periodic: a strobe period >= 1).

In the same run, each clearance's line of crank speeds (ascending) also runs as a map that
carries state along ``omega`` (:func:`workbench.continuation.chaos_map` with ``along``): each
point's run starts from the previous point's end state with the continuation's per-point
transient, and its indicators start Newton from the previous point's periodic orbit
(``seeded``). Per point: its run's CPU, its indicators' CPU and their ratio in both ways
(``fast_*``: its own brute-force run, Newton from the run's end; ``seeded_*``), whether the
seed was taken, and a profile of where the seeded periodic points spend their time (Newton's
map evaluations against the Floquet check's).

Run: ``python benchmarks/chaos_map_precision.py [--omegas 1.0,1.5,2.5] [--clearances
4e-5,8e-5] [--cycles 50] [--transient 20] [--no-full]`` (records in ``benchmarks/records/
chaos_map_precision/``; ``python benchmarks/_results.py`` regenerates RESULTS.md).
"""

from __future__ import annotations

import argparse
import math
import os
import time
import warnings
from pathlib import Path

import numpy as np
from _results import record, recording  # benchmarks/_results.py: a JSON record per run

import workbench
from workbench.analysis import ConvergenceWarning
from workbench.continuation import _exponent, _newton, chaos_indicators, lle_cycles, point_exponent
from workbench.continuation._segment import Starts, continue_point

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "studies" / "chaos_maps" / "omega_clearance.toml"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--omegas", default="1.0,1.5,2.5", help="crank speeds / pi")
    ap.add_argument("--clearances", default="4e-5,8e-5", help="m")
    ap.add_argument("--cycles", type=int, default=50)
    ap.add_argument("--transient", type=int, default=20)
    ap.add_argument("--no-full", action="store_true", help="skip the full protocol's exponent")
    args = ap.parse_args()
    base = workbench.load_scene(SCENE)
    base = base.replace(sweep={}, run={"cycles": args.cycles, "transient_cycles": args.transient})
    workbench.simulate(base.replace(run={"cycles": 1, "transient_cycles": 0}))  # the kernel
    rows = []
    omegas = sorted(float(v) for v in args.omegas.split(","))
    clearances = [float(v) for v in args.clearances.split(",")]
    carried = base.replace(
        sweep={
            "omega": [w * math.pi for w in omegas],
            "clearance": clearances,
            "continuation": {"direction": "up", "along": "omega"},
        }
    )
    starts = Starts(carried)
    for c in clearances:
        state, orbit = None, None  # carried along the line of crank speeds
        for w in omegas:
            point = base.with_parameters(omega=w * math.pi, clearance=c)
            load0 = os.getloadavg()[0]
            c0 = time.process_time()
            run = workbench.simulate(point)
            c1 = time.process_time()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", ConvergenceWarning)
                fast = chaos_indicators(point, run)
                c2 = time.process_time()
                full = None
                if not args.no_full:
                    full = point_exponent(
                        point,
                        period=int(fast.strobe_period),
                        cycles=lle_cycles(point),
                        start_cycles=args.transient + args.cycles,
                    )
            c3 = time.process_time()
            seeded = _seeded_point(starts, {"omega": w * math.pi, "clearance": c}, state, orbit)
            state, orbit = seeded.pop("final"), seeded.pop("orbit")
            kind = "periodic" if int(fast.strobe_period) >= 1 else "chaotic"
            row = {
                "omega_over_pi": w, "clearance_m": c, "kind": kind,
                "strobe_period": int(fast.strobe_period), "run_cpu_s": c1 - c0,
                "fast_cpu_s": c2 - c1, "full_exponent_cpu_s": c3 - c2,
                "fast_ratio": (c2 - c1) / (c1 - c0),
                "lle_fast": float(fast.lle), "lle_fast_stderr": float(fast.lle_stderr),
                "lle_fast_converged": int(fast.lle_converged), "load": load0, **seeded,
            }  # fmt: skip
            if full is not None:
                row.update({
                    "full_ratio": (c3 - c2) / (c1 - c0), "lle_full": full.value,
                    "lle_full_stderr": full.error, "lle_full_converged": int(full.converged_code),
                    "method": full.method,
                })  # fmt: skip
            rows.append(row)
            print(
                f"omega {w} pi, c {c:g} m ({kind}, period {row['strobe_period']}): run "
                f"{row['run_cpu_s']:.1f} s CPU; fast point {row['fast_cpu_s']:.1f} s "
                f"({row['fast_ratio']:.2f}x the run; lle {row['lle_fast']:.4g} +- "
                f"{row['lle_fast_stderr']:.2g} 1/s, converged {row['lle_fast_converged']}); "
                f"seeded: run {row['seeded_run_cpu_s']:.1f} s, point {row['seeded_cpu_s']:.1f} s "
                f"({row['seeded_ratio']:.2f}x its run, seed taken {row['seeded']}, period "
                f"{row['seeded_strobe_period']}, lle {row['lle_seeded']:.4g}; Newton "
                f"{row['newton_cpu_s']:.1f} s, {row['newton_evaluations']} evaluations; check "
                f"{row['check_cpu_s']:.1f} s); load {load0:.1f}"
            )
            if full is not None:
                print(
                    f"  full protocol's exponent {row['full_exponent_cpu_s']:.1f} s "
                    f"({row['full_ratio']:.2f}x; lle {full.value:.4g} +- {full.error:.2g}, "
                    f"converged {row['lle_full_converged']})"
                )
            record({"points": {f"omega {w} pi, c {c:g}": row}})
    summary = {}
    for kind in ("periodic", "chaotic"):
        sel = [r for r in rows if r["kind"] == kind]
        if not sel:
            continue
        summary[kind] = {
            k: float(np.mean([r[k] for r in sel]))
            for k in ("run_cpu_s", "fast_cpu_s", "seeded_run_cpu_s", "seeded_cpu_s",
                      "newton_cpu_s", "check_cpu_s", "full_exponent_cpu_s")
            if k in sel[0]
        }  # fmt: skip
        summary[kind].update(
            points=len(sel),
            seeds_taken=int(sum(r["seeded"] for r in sel)),
            fast_ratio_mean=float(np.mean([r["fast_ratio"] for r in sel])),
            fast_ratio_max=float(np.max([r["fast_ratio"] for r in sel])),
            seeded_ratio_mean=float(np.mean([r["seeded_ratio"] for r in sel])),
            seeded_ratio_max=float(np.max([r["seeded_ratio"] for r in sel])),
        )
        if "full_ratio" in sel[0]:
            summary[kind]["full_ratio_mean"] = float(np.mean([r["full_ratio"] for r in sel]))
        s = summary[kind]
        print(
            f"{kind}: {s['points']} points, run {s['run_cpu_s']:.1f} s CPU; the fast point "
            f"{s['fast_ratio_mean']:.2f}x its run (at most {s['fast_ratio_max']:.2f}x); carried "
            f"along omega: run {s['seeded_run_cpu_s']:.1f} s, the point "
            f"{s['seeded_ratio_mean']:.2f}x its run (at most {s['seeded_ratio_max']:.2f}x; "
            f"seed taken at {s['seeds_taken']}; Newton {s['newton_cpu_s']:.1f} s, check "
            f"{s['check_cpu_s']:.1f} s)"
        )
    record(
        {
            "by_kind": summary,
            "cycles": args.cycles,
            "transient_cycles": args.transient,
            "lle_cycles": lle_cycles(base),
        }
    )


def _seeded_point(starts: Starts, params: dict, state, orbit) -> dict:
    """One point of the map carried along omega: its run from ``state`` (the previous point's
    end, None: a brute-force start) and its indicators with Newton seeded by ``orbit``; CPU
    of each, of Newton (map evaluations) and of the Floquet check inside the indicators."""
    spent = {"newton": 0.0, "check": 0.0, "evaluations": 0}
    newton, floquet = _newton.orbit_at, _exponent.floquet_exponent

    def timed_orbit(*a, **k):  # Newton: the seed's, the run end's, and the check's (tangent)
        t = time.process_time()
        try:
            pt = newton(*a, **k)
        finally:
            spent["newton"] += time.process_time() - t
        spent["evaluations"] += pt.evaluations
        return pt

    def timed_floquet(*a, **k):
        t = time.process_time()
        try:
            return floquet(*a, **k)
        finally:
            spent["check"] += time.process_time() - t

    c0 = time.process_time()
    outcome, final = continue_point(starts, params, state)
    c1 = time.process_time()
    scene = starts.at(state is not None, params).scene
    _exponent.orbit_at, _exponent.floquet_exponent = timed_orbit, timed_floquet
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            ind = chaos_indicators(scene, outcome["ds"], seed=orbit, carry=True)
    finally:
        _exponent.orbit_at, _exponent.floquet_exponent = newton, floquet
    c2 = time.process_time()
    return {
        "seeded_run_cpu_s": c1 - c0, "seeded_cpu_s": c2 - c1,
        "seeded_ratio": (c2 - c1) / (c1 - c0), "seeded": int(ind.lle_seeded),
        "seeded_strobe_period": int(ind.strobe_period), "lle_seeded": float(ind.lle),
        "newton_cpu_s": spent["newton"], "newton_evaluations": spent["evaluations"],
        "check_cpu_s": spent["check"] - spent["newton"],  # Floquet's, beside Newton
        "final": final, "orbit": ind.attrs["carry"],
    }  # fmt: skip


if __name__ == "__main__":
    with recording(__file__):
        main()
