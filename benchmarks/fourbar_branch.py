"""The declared four-bar's period-1 branch through its grazings, timed, and each grazing checked
by simulation alone (issue 38: labels checked on a system the tests do not contain).

The four-bar of ``data/fourbar_sweep.nc`` (``studies/mechanisms/fourbar.toml``, c = 0.5 mm at
B, Coulomb friction c_f = 0.1, Lankarani-Nikravesh contact; ``data/regenerate.py``'s
``fourbar_scenes``), continued in omega by :func:`workbench.continuation.continue_orbit` from
``--start`` to ``--stop`` (rad/s). Past a lift-off near 43.95 rad/s its orbit strikes the
bearing's wall and rebounds along it; one rebound after another grazes the wall as omega grows.

Each grazing is checked without the continuation: the branch's orbits just below and just
above it (their strobe states and held onset velocities) are integrated at their own omega by
:func:`workbench.simulate` (rtol 1e-9, atol 1e-12), and the events per forcing period of that
motion over cycles 10 to 30 are compared with the branch's. Where both agree and differ from
each other, the simulation alone brackets the grazing between those two omegas.

Prints the branch's cost (CPU, points, map evaluations), how far it reached and why it ended,
where Newton's tolerance was raised to the map's noise, its labels, and per grazing the check.

Run: ``python benchmarks/fourbar_branch.py [--start 44] [--stop 52] [--max-points 400]`` (one
core; records in ``benchmarks/records/fourbar_branch/``).
"""

from __future__ import annotations

import argparse
import importlib.util
import time
from pathlib import Path

import numpy as np
from _results import record, recording  # benchmarks/_results.py: a JSON record per run

import workbench
from workbench.continuation import branch_bifurcations, continue_orbit

ROOT = Path(__file__).resolve().parents[1]
#: the simulation's tolerances and the cycles whose events are counted (the count over cycles
#: C0..C1 is the difference of two runs' event totals, each from the same start)
CHECK_SOLVER = {"rtol": 1e-9, "atol": 1e-12}
CYCLES = (10, 30)


def fourbar_scene() -> workbench.Scene:
    """The sweep scene of ``data/regenerate.py`` (a script, not a package module) as one run."""
    spec = importlib.util.spec_from_file_location("regenerate", ROOT / "data" / "regenerate.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    sweep, _ = module.fourbar_scenes()
    return sweep.replace(sweep={}, run={"cycles": 5, "transient_cycles": 200})


def events_per_period(scene: workbench.Scene, omega: float, y0, aux0) -> float:
    """Events per forcing period of the motion from the state ``y0`` (the model's states) and
    discrete state ``aux0`` at the strobe time, at ``omega`` (rad/s), over cycles CYCLES."""
    totals = []
    for cycles in CYCLES:
        s = scene.replace(
            run={"cycles": cycles, "transient_cycles": 0}, solver=CHECK_SOLVER
        ).with_parameters(omega=omega)
        p = workbench.prepare(s)
        ds = workbench.simulate(p.restart(p.problem.t0, np.asarray(y0), np.asarray(aux0)))
        totals.append(int(ds.attrs["solver_events"]))
    return (totals[1] - totals[0]) / (CYCLES[1] - CYCLES[0])


def check(scene: workbench.Scene, r, names: list[str], value: float) -> dict:
    """The grazing at ``value`` (rad/s) checked on the branch ``r``'s nearest orbits on either
    side of it."""
    omega = r.omega.values
    row: dict = {"omega": value}
    for side, sel in (("below", omega < value * (1 - 1e-9)), ("above", omega > value * (1 + 1e-9))):
        if not sel.any():
            continue
        i = int(np.flatnonzero(sel)[np.argmin(np.abs(omega[sel] - value))])
        y0 = [float(np.ravel(r[f"orbit_{n}"].values[i])[0]) for n in names]
        aux0 = np.ravel(r["orbit_discrete_state"].values[i]).astype(float)
        row[side] = {
            "omega": float(omega[i]),
            "branch": float(r.events_per_period.values[i]),
            "simulated": events_per_period(scene, float(omega[i]), y0, aux0),
        }
    b, a = row.get("below"), row.get("above")
    row["bracketed"] = bool(
        b and a and b["branch"] == b["simulated"] and a["branch"] == a["simulated"]
        and b["branch"] != a["branch"]
    )  # fmt: skip
    return row


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--start", type=float, default=44.0, help="omega at the start, rad/s")
    ap.add_argument("--stop", type=float, default=52.0, help="omega to stop at, rad/s")
    ap.add_argument("--max-points", type=int, default=400)
    args = ap.parse_args()
    scene = fourbar_scene()
    t0, w0 = time.process_time(), time.time()
    r = continue_orbit(
        scene.with_parameters(omega=args.start), "omega", stop=args.stop, max_points=args.max_points
    )
    cpu, wall = time.process_time() - t0, time.time() - w0
    labels = [
        {"type": b["type"], "omega": b["value"], "resolved": bool(b["resolved"]),
         "transition": b["transition"]}
        for b in branch_bifurcations(r, "omega")
    ]  # fmt: skip
    print(
        f"branch {args.start:g} -> reached {float(r.omega.max()):.4f} rad/s (stop {args.stop:g}); "
        f"{r.sizes['point']} points, {r.attrs['map_evaluations']} map evaluations; {cpu:.0f} s "
        f"CPU, {wall:.0f} s wall; ended: {str(r.attrs['branch_ended'])[:240]}"
    )
    events = sorted({int(e) for e in r.events_per_period.values})
    print(f"events per period along it: {events}")
    raised = str(r.attrs.get("tolerance_raised", ""))
    print(f"Newton's tolerance raised to the map's noise: {raised or 'no'}")
    for b in labels:
        state = "resolved" if b["resolved"] else "UNRESOLVED"
        print(f"  {b['type']} at {b['omega']:.7f} rad/s, {state}, {b['transition'] or '-'}")
    p = workbench.prepare(scene)
    names = [q.name for q in p.model.states(p.scene.effects)]
    checks = []
    for b in labels:
        if b["type"] != "grazing":
            continue
        row = check(scene, r, names, b["omega"])
        checks.append(row)
        sides = "; ".join(
            f"{side} at {row[side]['omega']:.6f}: branch {row[side]['branch']:g}, simulated "
            f"{row[side]['simulated']:g}"
            for side in ("below", "above")
            if side in row
        )
        verdict = "bracketed by simulation" if row["bracketed"] else "NOT bracketed"
        print(f"grazing at {b['omega']:.7f}: {verdict} ({sides})")
    unresolved = sum(not b["resolved"] for b in labels)
    print(
        f"{len(labels)} labels, {unresolved} unresolved; {sum(c['bracketed'] for c in checks)} "
        f"of {len(checks)} grazings bracketed by simulation"
    )
    record(
        {"start": args.start, "stop": args.stop, "cpu": cpu, "wall": wall,
         "points": int(r.sizes["point"]), "map_evaluations": int(r.attrs["map_evaluations"]),
         "reached": float(r.omega.max()), "ended": str(r.attrs["branch_ended"]),
         "events_per_period": events, "tolerance_raised": raised, "labels": labels,
         "unresolved": unresolved,
         "checks": checks}
    )  # fmt: skip


if __name__ == "__main__":
    with recording(__file__):
        main()
