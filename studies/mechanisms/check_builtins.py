"""The declared nine-bar and slider-crank of this folder against the built-in models (issue 42,
item 4): prints the measured differences.

- ideal joints, one cycle: the largest difference of each crank's driving torque, over its range
  (the check: <= 1e-8);
- clearances, the first 0.2 cycle: the largest difference of the clearance vectors, over the
  clearance c (the check: <= 1e-6); the nine-bar at the tolerance of studies/ninebar.toml
  (rtol = atol = 1e-6) and at 1e-10, with the time at which the difference first exceeds
  1e-6 c and the first contact's, the slider-crank at 1e-9;
- the nine-bar's own sensitivity: the built-in against itself with the initial normal velocity
  at A changed by 1e-12 m s-1 (the same measures).

Run from the repository's root: ``python studies/mechanisms/check_builtins.py`` (a few minutes
the first time: the declared mechanisms' kernels compile).
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np

import workbench

HERE = Path(__file__).resolve().parent
STUDY = HERE.parent / "ninebar.toml"
C = 0.5e-3  # m


def _declaration(name: str) -> dict:
    with open(HERE / f"{name}.toml", "rb") as f:
        return tomllib.load(f)["mechanism"]


def _run(model: dict, effects: dict, solver: dict, params: dict, variables, initial=None):
    scene = {
        **model,
        "effects": effects,
        "solver": solver,
        "parameters": params,
        "run": {"cycles": 1},
        "record": {"samples_per_period": 2000, "variables": variables},
        "initial": initial or {},
    }
    return workbench.simulate(workbench.load_scene(scene))


def pair(name: str, effects: dict, solver: dict, variables):
    """The built-in model and its declared twin with the same effects, solver and parameters."""
    builtin, declared = {}, {}
    if name == "ninebar":
        with open(STUDY, "rb") as f:
            p = tomllib.load(f)["parameters"]
        builtin = dict(p)
        declared = {
            "omega": p["omega"],
            "clearance_A": p["clearance"],
            "clearance_B": p["clearance"],
            "friction_coefficient": p["friction_coefficient"],
        }
    a = _run({"model": {"name": name}}, effects, solver, builtin, variables)
    b = _run(
        {"model": {"name": "declared"}, "mechanism": _declaration(name)},
        effects,
        solver,
        declared,
        variables,
    )
    return a, b


def clearance_report(label: str, a, b) -> None:
    window = slice(0, 401)  # the first 0.2 cycle of 2000 samples
    diff = np.maximum(
        np.abs(a.clearance_x.values - b.clearance_x.values).max(axis=1),
        np.abs(a.clearance_y.values - b.clearance_y.values).max(axis=1),
    )
    period = float(a.time[-1] - a.time[0])
    contact = int(np.argmax((a.penetration.values > 0).any(axis=1)))
    beyond = np.flatnonzero(diff > 1e-6 * C)
    first = f"{float(a.time[beyond[0]] - a.time[0]) / period:.4f}" if beyond.size else "never"
    print(
        f"{label}: max |difference| over the first 0.2 cycle = {diff[window].max() / C:.3g} c; "
        f"up to the first contact ({float(a.time[contact] - a.time[0]) / period:.4f} cycle) "
        f"{diff[:contact].max() / C:.3g} c; exceeds 1e-6 c from {first} cycle"
    )


def main() -> None:
    ideal = {"clearance": [], "friction": "none"}
    for name in ("ninebar", "slider_crank"):
        a, b = pair(name, ideal, {"method": "dop853", "rtol": 1e-6, "atol": 1e-6}, ["torque"])
        span = np.ptp(a.torque.values, axis=0)
        rel = np.abs(a.torque.values - b.torque.values).max(axis=0) / span
        print(f"{name}, ideal joints, one cycle: max |torque difference| / range = {rel}")
    variables = ["clearance_x", "clearance_y", "penetration"]
    with open(STUDY, "rb") as f:
        study = tomllib.load(f)
    effects = dict(study["effects"])
    for tol in (1e-6, 1e-10):
        solver = {"method": "dop853", "rtol": tol, "atol": tol}
        a, b = pair("ninebar", effects, solver, variables)
        clearance_report(f"ninebar, clearances A and B, rtol {tol:g}", a, b)
        if tol == 1e-10:
            c = _run(
                {"model": {"name": "ninebar"}},
                effects,
                solver,
                dict(study["parameters"]),
                variables,
                {"vx_A": 1e-12},
            )
            clearance_report("ninebar against itself with vx_A(0) = 1e-12 m/s", a, c)
    solver = {"method": "dop853", "rtol": 1e-9, "atol": 1e-9}
    a, b = pair("slider_crank", {"clearance": ["B"], "friction": "none"}, solver, variables)
    clearance_report("slider_crank, clearance B, rtol 1e-9", a, b)


if __name__ == "__main__":
    main()
