"""A declared mechanism's period-1 branch through its contact events, timed, and every label
checked by simulation alone (issue 38: labels checked on systems the tests do not contain).

Systems (``--system``), each a declaration under ``studies/mechanisms/`` with a clearance of
0.5 mm at B and Coulomb friction c_f = 0.1, continued in omega by
:func:`workbench.continuation.continue_orbit`:

- ``fourbar``: the four-bar of ``data/fourbar_sweep.nc`` (``data/regenerate.py``'s
  ``fourbar_scenes``), from 44 rad/s. Past a lift-off near 43.95 rad/s its journal strikes the
  bearing's wall and rebounds along it; one rebound after another grazes the wall as omega
  grows.
- ``slider_crank``: Flores' slider-crank (``studies/mechanisms/slider_crank.toml``, given
  friction), from 300 rad/s, where the journal rides the bearing's wall in a lasting contact
  (simulated from rest it keeps no events past its transient up to 300 rad/s, and impacts
  about twice a cycle at 400).

Every label is checked without the continuation, by :func:`workbench.simulate` alone (rtol
1e-9, atol 1e-12), on the branch's orbits (their strobe states and held onset velocities) at
their own omega. On each side of the label along the branch (between it and its neighbouring
labels), the orbit nearest it that lies clearly on that side is taken: for a grazing, its
margin to it (the value of the grazing's extremum, read on the orbit nearest the label's phase)
is at least :data:`MARGIN_FACTOR` times the orbit's own uncertainty (Newton's tolerance, scaled,
times the clearance); for a multiplier's crossing (fold, period doubling, Neimark-Sacker), its
largest |multiplier| lies at least :data:`MU_MARGIN` from 1. Per orbit: its events over one
period must be the branch's, and its stability must show: from a stable orbit the motion stays
on it (within :data:`STAYS`, period 1, the branch's events), from an unstable one it leaves it
(its own residual grows past :data:`STAYS`). A grazing is confirmed where both sides check and
their events differ, a crossing where both check and their stability differs; the orbits'
distance from the label is the bracket's width. Where the branch ends inside its range (a
border collision, a sharp turn), the motion just past its end (:data:`BEYOND` of omega) from
the last orbit (where it is stable) must not be the branch's period-1 motion.

Prints the branch's cost (CPU, points, map evaluations), how far it reached and why it ended,
where Newton's tolerance was raised to the map's noise, its labels and each one's check.

Run: ``python benchmarks/declared_branch.py [--system fourbar] [--start W] [--stop W]
[--max-points 400] [--rtol R] [--tolerance T] [-o BRANCH.nc] [--branch BRANCH.nc]`` (one
core; ``--branch`` checks a stored branch instead of continuing: the record then has no cost;
records in ``benchmarks/records/declared_branch/``).
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import time
import tomllib
from pathlib import Path

import numpy as np
from _results import record, recording  # benchmarks/_results.py: a JSON record per run

import workbench
from workbench.analysis import poincare_section
from workbench.continuation import branch_bifurcations, continue_orbit, strobe_period
from workbench.continuation._contacts import nearest_extremum
from workbench.solver._tangent import state_scale

ROOT = Path(__file__).resolve().parents[1]
#: the simulation's tolerances
CHECK_SOLVER = {"rtol": 1e-9, "atol": 1e-12}
#: cycles integrated from a stable orbit before the counted ones, and those counted
SETTLE, COUNTED = 10, 32
#: cycles from an unstable orbit before the counted ones (its residual must grow to the motion)
UNSTABLE_SETTLE = 400
#: a stable orbit's motion stays within this (scaled: the clearance, c omega) of its start, an
#: unstable one's leaves it by more
STAYS = 1e-3
#: a grazing's side orbit keeps this many times its own uncertainty off the grazing's surface
MARGIN_FACTOR = 10.0
#: a crossing's side orbit has its largest |multiplier| at least this far from 1
MU_MARGIN = 0.05
#: past the branch's end, the motion is simulated this fraction of omega beyond it
BEYOND = (1e-4, 1e-3)
#: per system: the default range of omega (rad/s) and the clearance's parameter
SYSTEMS = {
    "fourbar": {"start": 44.0, "stop": 52.0, "clearance": "clearance_B"},
    "slider_crank": {"start": 300.0, "stop": 700.0, "clearance": "clearance_B"},
}


def _regenerate():
    """``data/regenerate.py`` (a script, not a package module)."""
    spec = importlib.util.spec_from_file_location("regenerate", ROOT / "data" / "regenerate.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def system_scene(name: str) -> workbench.Scene:
    """The single-run scene of a system (see the module docstring)."""
    if name == "fourbar":
        sweep, _ = _regenerate().fourbar_scenes()
        return sweep.replace(sweep={}, run={"cycles": 5, "transient_cycles": 200})
    with open(ROOT / "studies" / "mechanisms" / f"{name}.toml", "rb") as f:
        table = tomllib.load(f)["mechanism"]
    return workbench.load_scene(
        {
            "mechanism": table,
            "effects": {"friction": "coulomb"},
            "parameters": {"friction_coefficient": 0.1},
            "solver": {"rtol": 1e-6, "atol": 1e-6},
            "record": {"samples_per_period": 1, "variables": ["clearance_x", "clearance_y"]},
            "run": {"cycles": 5, "transient_cycles": 200},
        }
    )


def simulated(scene: workbench.Scene, omega: float, y0, aux0, settle: int) -> dict:
    """The motion from the strobe state ``y0`` (the model's states) and discrete state ``aux0``
    at ``omega`` (rad/s), over ``settle`` forcing periods and then :data:`COUNTED` more (the
    map is periodic in time: the second run restarts at the first's start time from where it
    ended): the events per period and the strobe period (:func:`workbench.continuation.
    strobe_period`) of the counted periods, and how far the last strobe state lies from ``y0``
    (max over the states of the difference over each state's scale, the clearance for lengths
    and c omega for rates). ``settle`` 0: one period alone, counted."""
    s = scene.replace(solver=CHECK_SOLVER).with_parameters(omega=omega)
    y, aux = np.asarray(y0, float), np.asarray(aux0, float)
    for cycles in (settle, COUNTED) if settle else (1,):
        p = workbench.prepare(s.replace(run={"cycles": cycles, "transient_cycles": 0}))
        ds = workbench.simulate(p.restart(p.problem.t0, y, aux))
        y = np.atleast_1d(np.asarray(ds.attrs["end_state"], float))
        aux = np.atleast_1d(np.asarray(ds.attrs["end_discrete_state"], float))
    section = poincare_section(ds)
    x = np.concatenate(
        [section[v].values.reshape(section.sizes["strobe"], -1) for v in scene.variables], axis=1
    )
    return {
        "events": int(ds.attrs["solver_events"]) / cycles,
        "period": strobe_period(x),
        "distance": float(np.max(np.abs(y - np.asarray(y0, float)) / state_scale(p.problem))),
    }


def _margin(r, i: int, k: int, phase: float, kind: float) -> float:
    """The value (m) of event ``k``'s extremum of ``kind`` nearest ``phase`` on orbit ``i``."""
    e = np.column_stack(
        [r.extremum_phase.values[i, k], r.extremum_value.values[i, k], r.extremum_kind.values[i, k]]
    )
    e = e[np.isfinite(e).all(axis=1)]
    j = nearest_extremum(e, phase, kind, _span(r, i))
    return float(e[j, 1]) if j >= 0 else math.nan


def _span(r, i: int) -> float:
    """The period (s) of orbit ``i``."""
    return float(r.periods.values[i]) * 2.0 * math.pi / float(r.omega.values[i])


def _kind(r, i: int, k: int, phase: float) -> float:
    """The kind (+1 maximum, -1 minimum) of event ``k``'s extremum nearest ``phase`` on orbit
    ``i`` (the grazing's own, read at its located orbit)."""
    ph, kind = r.extremum_phase.values[i, k], r.extremum_kind.values[i, k]
    ok = np.isfinite(ph)
    d = np.abs(ph[ok] - phase) % _span(r, i)
    return float(kind[ok][np.argmin(np.minimum(d, _span(r, i) - d))])


def side_orbit(r, j: int, window: range, uncertainty: float):
    """The orbit of ``window`` (point indices, nearest the label first) that lies clearly on
    its side of label ``j`` (row of the branch's bifurcations; module docstring), with its
    margin or largest |multiplier|; None where none does."""
    mu = np.nanmax(r.multiplier_modulus.values, axis=1)
    grazing = int(r.bifurcation_event.values[j]) >= 0
    if grazing:
        k = int(r.bifurcation_event.values[j])
        phase = float(r.bifurcation_phase.values[j])
        kind = _kind(r, int(r.bifurcation_point.values[j]), k, phase)
    for i in window:
        if r.branch.values[i] != 0:
            continue
        if grazing:
            m = _margin(r, i, k, phase, kind)
            if np.isfinite(m) and abs(m) >= MARGIN_FACTOR * uncertainty:
                return i, {"margin": m}
        elif abs(mu[i] - 1.0) >= MU_MARGIN:
            return i, {"largest_multiplier": float(mu[i])}
    return None, {}


def _state(r, names: list[str], i: int):
    y0 = [float(np.ravel(r[f"orbit_{n}"].values[i])[0]) for n in names]
    aux0 = np.ravel(r["orbit_discrete_state"].values[i]).astype(float)
    return y0, aux0


def orbit_check(scene, r, names: list[str], i: int) -> dict:
    """Orbit ``i`` of the branch by simulation alone: its events over one period against the
    branch's (and how far the state is from its start after it: the orbit's periodicity), and
    its stability: a stable orbit's motion stays on it (period 1, the branch's events, within
    :data:`STAYS` after :data:`SETTLE` + :data:`COUNTED` cycles), an unstable one's leaves it
    (further than that after :data:`UNSTABLE_SETTLE` + :data:`COUNTED`: its own residual
    grows)."""
    omega = float(r.omega.values[i])
    y0, aux0 = _state(r, names, i)
    one = simulated(scene, omega, y0, aux0, 0)
    stable = bool(r.stable.values[i])
    long = simulated(scene, omega, y0, aux0, SETTLE if stable else UNSTABLE_SETTLE)
    branch_events = float(r.events_per_period.values[i])
    if stable:
        holds = long["distance"] <= STAYS and long["period"] == 1
        holds = holds and long["events"] == branch_events
    else:
        holds = long["distance"] > STAYS
    return {
        "omega": omega,
        "stable": stable,
        "largest_multiplier": float(np.nanmax(r.multiplier_modulus.values[i])),
        "branch_events": branch_events,
        "one_period_events": one["events"],
        "one_period_distance": one["distance"],
        "events_agree": one["events"] == branch_events,
        "simulated_events": long["events"],
        "simulated_period": long["period"],
        "distance": long["distance"],
        "stability_agrees": bool(holds),
    }


def check(scene, r, names: list[str], labels: list[dict], j: int, uncertainty: float) -> dict:
    """Label ``j`` checked by simulation on its two sides along the branch (module
    docstring): the orbits between it and its neighbouring labels, nearest it first."""
    b = labels[j]
    points = r.bifurcation_point.values
    at = int(points[j])
    lo = int(points[j - 1]) if j > 0 else -1
    hi = int(points[j + 1]) if j + 1 < len(labels) else r.sizes["point"]
    row: dict = {"type": b["type"], "omega": b["value"], "resolved": b["resolved"]}
    for side, window in (("before", range(at - 1, lo, -1)), ("after", range(at + 1, hi))):
        i, why = side_orbit(r, j, window, uncertainty)
        if i is not None:
            row[side] = orbit_check(scene, r, names, i) | why
            row[side]["distance_from_label"] = abs(row[side]["omega"] - b["value"])
    before, after = row.get("before"), row.get("after")
    ok = bool(before and after)
    ok = ok and all(s["events_agree"] and s["stability_agrees"] for s in (before, after))
    if b["type"] == "grazing":  # the events change across it
        ok = ok and before["branch_events"] != after["branch_events"]
    else:  # a multiplier crosses the unit circle: the stability changes across it
        ok = ok and before["stable"] != after["stable"]
    row["confirmed"] = bool(ok)
    return row


def beyond_end(scene, r, names: list[str]) -> dict:
    """The motion just past the branch's end (:data:`BEYOND`), from its last orbit: whether
    it is the branch's period-1 motion there."""
    omega = r.omega.values
    last = int(np.flatnonzero(r.branch.values == 0)[-1])
    direction = math.copysign(1.0, omega[last] - omega[last - 1])
    y0, aux0 = _state(r, names, last)
    out = {
        "omega": float(omega[last]),
        "branch_events": float(r.events_per_period.values[last]),
        "stable": bool(r.stable.values[last]),
    }
    if not out["stable"]:  # its motion leaves it at its own omega already: nothing to show
        out["runs"], out["left_period_1"] = [], False
        return out
    runs = []
    for f in BEYOND:
        w = float(omega[last]) * (1 + direction * f)
        runs.append({"omega": w, **simulated(scene, w, y0, aux0, UNSTABLE_SETTLE)})
    out["runs"] = runs
    out["left_period_1"] = all(
        not (s["period"] == 1 and s["events"] == out["branch_events"]) for s in runs
    )
    return out


def _describe(row: dict) -> str:
    parts = []
    for side in ("before", "after"):
        if side not in row:
            parts.append(f"{side}: no orbit clearly on that side")
            continue
        s = row[side]
        mu = s.get("largest_multiplier")
        extra = f"margin {s['margin']:.2g} m" if "margin" in s else f"|mu| {mu:.3f}"
        motion = "stays" if s["distance"] <= STAYS else f"leaves ({s['distance']:.2g})"
        parts.append(
            f"{side} at {s['omega']:.6f} ({extra}, {'stable' if s['stable'] else 'unstable'}, "
            f"{s['branch_events']:g} events): one period {s['one_period_events']:g} events, "
            f"back to {s['one_period_distance']:.2g}; the motion {motion}, "
            f"{s['simulated_events']:g} events, period {s['simulated_period']}"
        )
    return "; ".join(parts)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--system", choices=sorted(SYSTEMS), default="fourbar")
    ap.add_argument("--start", type=float, help="omega at the start, rad/s")
    ap.add_argument("--stop", type=float, help="omega to stop at, rad/s")
    ap.add_argument("--max-points", type=int, default=400)
    ap.add_argument("--rtol", type=float, help="the strobe map's rtol (default: its own)")
    ap.add_argument("--tolerance", type=float, default=1e-8, help="Newton's (scaled)")
    ap.add_argument("-o", "--output", type=Path, help="write the branch to this netCDF file")
    ap.add_argument("--branch", type=Path, help="check this stored branch (no continuation)")
    args = ap.parse_args()
    system = SYSTEMS[args.system]
    start = system["start"] if args.start is None else args.start
    stop = system["stop"] if args.stop is None else args.stop
    scene = system_scene(args.system)
    cost: dict = {}
    if args.branch is not None:
        r = workbench.open_run(args.branch)
        print(f"branch read from {args.branch} (its cost is not measured here)")
    else:
        t0, w0 = time.process_time(), time.time()
        r = continue_orbit(
            scene.with_parameters(omega=start),
            "omega",
            stop=stop,
            max_points=args.max_points,
            rtol=args.rtol,
            tolerance=args.tolerance,
        )
        cost = {"cpu": time.process_time() - t0, "wall": time.time() - w0}
        if args.output is not None:
            workbench.save_run(r, args.output)
    labels = [
        {"type": b["type"], "value": b["value"], "resolved": bool(b["resolved"]),
         "transition": b["transition"]}
        for b in branch_bifurcations(r, "omega")
    ]  # fmt: skip
    on = r.omega.values[r.branch.values == 0]
    reached = float(on.max() if stop > start else on.min())
    print(
        f"{args.system}: branch {start:g} -> reached {reached:.4f} rad/s, ended at "
        f"{float(on[-1]):.4f} (stop {stop:g}); "
        f"{r.sizes['point']} points, {r.attrs['map_evaluations']} map evaluations"
        + (f"; {cost['cpu']:.0f} s CPU, {cost['wall']:.0f} s wall" if cost else "")
        + f"; ended: {str(r.attrs['branch_ended'])[:240]}"
    )
    events = sorted({int(e) for e in r.events_per_period.values})
    print(f"events per period along it: {events}")
    raised = str(r.attrs.get("tolerance_raised", ""))
    print(f"Newton's tolerance raised to the map's noise: {raised or 'no'}")
    tolerance = max(float(r.attrs["tolerance"]), float(r.attrs["tolerance_requested"]))
    uncertainty = tolerance * float(scene.resolved_parameters[system["clearance"]])
    p = workbench.prepare(scene)
    names = [q.name for q in p.model.states(p.scene.effects)]
    checks = []
    for j, b in enumerate(labels):
        row = check(scene, r, names, labels, j, uncertainty)
        checks.append(row)
        state = "resolved" if b["resolved"] else "UNRESOLVED"
        verdict = "confirmed by simulation" if row["confirmed"] else "NOT confirmed"
        print(
            f"{b['type']} at {b['value']:.7f} rad/s ({state}, {b['transition'] or '-'}): "
            f"{verdict} ({_describe(row)})"
        )
    ended = str(r.attrs["branch_ended"])
    end = {}
    if not ended.startswith(("the parameter reached its bound", f"{args.max_points} points")):
        end = beyond_end(scene, r, names)  # it ended inside its range: why, by simulation
        runs = "; ".join(
            f"{s['omega']:.6f}: {s['events']:g} events, period {s['period']}" for s in end["runs"]
        )
        if not end["stable"]:
            said = "its last orbit is unstable: nothing past it to check by simulation"
        elif end["left_period_1"]:
            said = f"{runs}: not the branch's period-1 motion"
        else:
            said = f"{runs}: STILL the branch's period-1 motion"
        print(
            f"past the end at {end['omega']:.7f} (branch {end['branch_events']:g} events): {said}"
        )
    unresolved = sum(not b["resolved"] for b in labels)
    confirmed = sum(c["confirmed"] for c in checks)
    print(
        f"{len(labels)} labels, {unresolved} unresolved, {confirmed} confirmed by simulation "
        f"(side orbits at least {MARGIN_FACTOR:g} x {uncertainty:.2g} m off a grazing's surface, "
        f"|mu| at least {MU_MARGIN:g} from 1)"
    )
    record(
        {"system": args.system, "start": start, "stop": stop, **cost,
         "rtol": float(r.attrs["rtol"]), "tolerance": args.tolerance,
         "branch_file": str(args.branch) if args.branch else "",
         "points": int(r.sizes["point"]), "map_evaluations": int(r.attrs["map_evaluations"]),
         "reached": reached, "ended_at": float(on[-1]), "ended": str(r.attrs["branch_ended"]),
         "events_per_period": events, "tolerance_raised": raised, "uncertainty": uncertainty,
         "labels": labels, "unresolved": unresolved, "confirmed": confirmed, "checks": checks,
         "beyond_end": end}
    )  # fmt: skip


if __name__ == "__main__":
    with recording(__file__):
        main()
