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

Run: ``python benchmarks/chaos_map_precision.py [--omegas 1.0,1.5,2.5] [--clearances
4e-5,8e-5] [--cycles 50] [--transient 20]`` (records in ``benchmarks/records/
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
from workbench.continuation import chaos_indicators, lle_cycles, point_exponent

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "studies" / "chaos_maps" / "omega_clearance.toml"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--omegas", default="1.0,1.5,2.5", help="crank speeds / pi")
    ap.add_argument("--clearances", default="4e-5,8e-5", help="m")
    ap.add_argument("--cycles", type=int, default=50)
    ap.add_argument("--transient", type=int, default=20)
    args = ap.parse_args()
    base = workbench.load_scene(SCENE)
    base = base.replace(sweep={}, run={"cycles": args.cycles, "transient_cycles": args.transient})
    workbench.simulate(base.replace(run={"cycles": 1, "transient_cycles": 0}))  # the kernel
    rows = []
    for w in [float(v) for v in args.omegas.split(",")]:
        for c in [float(v) for v in args.clearances.split(",")]:
            point = base.with_parameters(omega=w * math.pi, clearance=c)
            load0 = os.getloadavg()[0]
            c0 = time.process_time()
            run = workbench.simulate(point)
            c1 = time.process_time()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", ConvergenceWarning)
                fast = chaos_indicators(point, run)
                c2 = time.process_time()
                full = point_exponent(
                    point,
                    period=int(fast.strobe_period),
                    cycles=lle_cycles(point),
                    start_cycles=args.transient + args.cycles,
                )
            c3 = time.process_time()
            kind = "periodic" if int(fast.strobe_period) >= 1 else "chaotic"
            row = {
                "omega_over_pi": w, "clearance_m": c, "kind": kind,
                "strobe_period": int(fast.strobe_period), "run_cpu_s": c1 - c0,
                "fast_cpu_s": c2 - c1, "full_exponent_cpu_s": c3 - c2,
                "fast_ratio": (c2 - c1) / (c1 - c0), "full_ratio": (c3 - c2) / (c1 - c0),
                "lle_fast": float(fast.lle), "lle_fast_stderr": float(fast.lle_stderr),
                "lle_fast_converged": int(fast.lle_converged), "lle_full": full.value,
                "lle_full_stderr": full.error, "lle_full_converged": int(full.converged_code),
                "method": full.method, "load": load0,
            }  # fmt: skip
            rows.append(row)
            print(
                f"omega {w} pi, c {c:g} m ({kind}, period {row['strobe_period']}): run "
                f"{row['run_cpu_s']:.1f} s CPU; fast point {row['fast_cpu_s']:.1f} s "
                f"({row['fast_ratio']:.2f}x the run; lle {row['lle_fast']:.4g} +- "
                f"{row['lle_fast_stderr']:.2g} 1/s, converged {row['lle_fast_converged']}); full "
                f"protocol's exponent {row['full_exponent_cpu_s']:.1f} s "
                f"({row['full_ratio']:.2f}x; lle {full.value:.4g} +- {full.error:.2g}, "
                f"converged {row['lle_full_converged']}); load {load0:.1f}"
            )
            record({"points": {f"omega {w} pi, c {c:g}": row}})
    summary = {}
    for kind in ("periodic", "chaotic"):
        sel = [r for r in rows if r["kind"] == kind]
        if not sel:
            continue
        summary[kind] = {
            "points": len(sel),
            "run_cpu_s": float(np.mean([r["run_cpu_s"] for r in sel])),
            "fast_cpu_s": float(np.mean([r["fast_cpu_s"] for r in sel])),
            "full_exponent_cpu_s": float(np.mean([r["full_exponent_cpu_s"] for r in sel])),
            "fast_ratio_mean": float(np.mean([r["fast_ratio"] for r in sel])),
            "fast_ratio_max": float(np.max([r["fast_ratio"] for r in sel])),
            "full_ratio_mean": float(np.mean([r["full_ratio"] for r in sel])),
        }
        s = summary[kind]
        print(
            f"{kind}: {s['points']} points, run {s['run_cpu_s']:.1f} s CPU; the fast point "
            f"{s['fast_ratio_mean']:.2f}x its run (at most {s['fast_ratio_max']:.2f}x), the full "
            f"protocol's exponent {s['full_ratio_mean']:.2f}x"
        )
    record(
        {
            "by_kind": summary,
            "cycles": args.cycles,
            "transient_cycles": args.transient,
            "lle_cycles": lle_cycles(base),
        }
    )


if __name__ == "__main__":
    with recording(__file__):
        main()
