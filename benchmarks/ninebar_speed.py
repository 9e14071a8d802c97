"""Speed of the nine-bar model: seconds per crank cycle, steps and evaluations per cycle.

The default scene (studies/ninebar.toml: A and B, 0.5 mm, omega = 2.5 pi, modified Coulomb),
2 transient + 10 recorded cycles at rtol 1e-6, with the compiled DOP853 and DOPRI5, and the first
cycle with the compiled DOP853 and with ``scipy:DOP853`` on the same compiled right-hand side
(their ratio is the speed-up on the same work); then the same with LuGre. The time per
right-hand-side evaluation (solver overhead included) shows why the ratio to scipy is what it
is: scipy adds ~10-15 us of Python per evaluation to a ~2 us model.
With LuGre also the implicit-explicit ARK548 (the bristle states implicit), and what it costs
in accuracy: the short-horizon error (30 ms of the first cycle, ``workbench.accuracy``) of
DOP853 and ARK548 at rtol 1e-6 and 1e-8 against DOP853 at 1e-11.
Targets on one core: <= 0.02 s per cycle (Coulomb), <= 0.06 s (LuGre); >= 50x scipy.
The paper's MATLAB needed 20.05 s (Coulomb) and 37.29 s (LuGre) per cycle.

Run: ``python benchmarks/ninebar_speed.py``.
"""

from __future__ import annotations

from pathlib import Path

import workbench
from workbench import accuracy

SCENE = Path(__file__).resolve().parents[1] / "studies" / "ninebar.toml"
PAPER = {"coulomb": 20.05, "lugre": 37.29}


def per_cycle(friction: str, method: str, cycles: int, transient: int) -> dict:
    base = workbench.load_scene(SCENE)
    scene = base.replace(
        effects={
            **base.effects,
            "friction": friction,
            "clearance": list(base.effects["clearance"]),
        },
        solver={**base.solver, "method": method, "rtol": 1e-6, "atol": 1e-6},
        run={"cycles": cycles, "transient_cycles": transient},
        record={"samples_per_period": 100, "variables": ["clearance_x"]},
    )
    ds = workbench.simulate(scene)
    a = ds.attrs
    n = cycles + transient
    return {
        "s_per_cycle": a["solver_wall_time"] / n,
        "steps": a["solver_steps"] / n,
        "rhs": a["solver_rhs_evaluations"] / n,
        "events": a["solver_events"] / n,
    }


def main() -> None:
    for friction in ("coulomb", "lugre"):
        print(f"--- friction = {friction} (paper's MATLAB: {PAPER[friction]} s per cycle)")
        per_cycle(friction, "dop853", 1, 0)  # compile / load the kernel
        rows = {
            "dop853": per_cycle(friction, "dop853", 10, 2),
            "dopri5": per_cycle(friction, "dopri5", 10, 2),
            "dop853 cycle 1": per_cycle(friction, "dop853", 1, 0),
            "scipy:DOP853": per_cycle(friction, "scipy:DOP853", 1, 0),
        }
        if friction == "lugre":
            rows["ark548"] = per_cycle(friction, "ark548", 10, 2)
        for method, r in rows.items():
            print(
                f"{method:14s} {r['s_per_cycle']:9.4f} s/cycle  {r['steps']:9.0f} steps/cycle  "
                f"{r['rhs']:10.0f} rhs/cycle  {r['events']:6.0f} events/cycle  "
                f"{r['s_per_cycle'] / r['rhs'] * 1e6:5.2f} us/rhs  "
                f"{PAPER[friction] / r['s_per_cycle']:8.0f}x the paper"
            )
        # the same first cycle (the transient's cost differs from a settled cycle's)
        ratio = rows["scipy:DOP853"]["s_per_cycle"] / rows["dop853 cycle 1"]["s_per_cycle"]
        target = 0.02 if friction == "coulomb" else 0.06
        print(
            f"compiled dop853 vs scipy:DOP853 (same rhs, same first cycle): {ratio:.0f}x "
            f"(target >= 50x; bounded by (rhs + scipy's per-call overhead) / rhs, see us/rhs); "
            f"target <= {target} s/cycle: "
            f"{'met' if rows['dop853']['s_per_cycle'] <= target else 'NOT met'}"
        )
        if friction == "lugre":
            stiff_remedy()


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
    print("LuGre, first 30 ms: short-horizon error (fraction of range) and rhs evaluations")
    for m in wp.solver_method.values:
        for tol in wp.rtol.values:
            r = wp.sel(solver_method=m, rtol=tol)
            print(
                f"  {m:7s} rtol {tol:.0e}: error {float(r.short_error):.2e}, "
                f"{int(r.rhs_evaluations):8d} rhs evaluations (the long run)"
            )


if __name__ == "__main__":
    main()
