"""Where and how the periodic motion of a study's route ends (``[route] refine``).

The coarse continued sweep brackets the end: the first value going up where the strobe is
period-1 while the next is not. Within that bracket:

1. a continued sweep of ``refine`` values both ways (each from its neighbour's settled state,
   ``end_transient_cycles`` transient cycles each, default 30: near the end the contraction to
   the orbit is slow and a short transient reads as a spread) says where the attractor stops
   being period-1 going up, where it starts again coming down, and whether the two differ
   there (hysteresis at the end);
2. the orbit Newton finds at the last periodic value going up (from the state the refined
   sweep settled to there): its events per period and smallest event value say whether the
   contact still lasts through the cycle; and the period-1 orbit continued upwards from the
   bracket's lower end, from the state the refined sweep settled to there (or the next values,
   where Newton does not converge;
   ``end_branch_points`` points at most, default 150; ``end_max_step`` the largest scaled
   arclength step, default 1: the strobe velocities of the nine-bar's lasting-contact orbit
   change fast with omega, and a step of 0.05 moves omega by ~1e-4 pi there): its multipliers
   say whether it loses stability by a smooth bifurcation, the smallest value of its event
   functions (the mechanisms: the smallest penetration of a joint in lasting contact, m)
   whether it ends by lifting off a contact (a grazing, the contact bifurcation of impacting
   systems; di Bernardo et al. 2008, Ch. 2), and why the branch ended;
3. the orbit's dependence on its history: where the model holds a discrete state through the
   orbit (the mechanisms: each contact's onset velocity, which sets the Lankarani-Nikravesh
   damping, Lankarani & Nikravesh 1990, for as long as the contact lasts), the same orbit is
   found again with those held values scaled by ``HELD_FACTORS``, and its largest |multiplier|
   reported for each: a family of orbits, one per onset velocity, not one orbit;
4. with ``end_other_contact`` (a table: ``contact``, the ``[effects]`` contact law, and that
   law's ``[parameters]``, e.g. ``{contact = "hunt_crossley", hunt_crossley_damping = 47.5}``):
   the refined sweep of 1. again under that law, and the orbit Newton finds at its highest
   period-1 value going up, to say whether the end survives a contact law without the memory
   of 3.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from workbench._errors import WorkbenchError
from workbench.analysis import periodic_run_end
from workbench.study._route_parts import branch_summary, indicators, settled

__all__ = ["HELD_FACTORS", "end_bracket", "periodic_end"]

#: the held discrete states of the last periodic orbit are scaled by these factors to show how
#: its multipliers depend on them
HELD_FACTORS = (0.1, 1.0, 10.0)


def end_bracket(periods: list[int]) -> int | None:
    """The index i of the first value whose strobe is period-1 while the next one's is not, or
    None."""
    for i in range(len(periods) - 1):
        if periods[i] == 1 and periods[i + 1] != 1:
            return i
    return None


def periodic_end(
    scene,
    cscene,
    param: str,
    values: list[float],
    per: dict,
    spec: dict,
    directory: Path,
    case: str,
    workers: int | None,
) -> dict:
    """Where the period-1 motion of the continued sweep ``per`` (over ``values``) ends, and how
    (see the module docstring): a dict for the summary."""
    i = end_bracket(per["up"]["period"])
    if i is None:
        return {"status": "no end", "reason": "no period-1 value is followed by another going up"}
    lo, hi = values[i], values[i + 1]
    fine = [float(v) for v in np.linspace(lo, hi, int(spec["refine"]))]
    transient = int(spec.get("end_transient_cycles", 30))
    path = directory / f"{case}-refined.nc"
    ds, refined = _refined(scene, cscene, param, fine, transient, path, workers)
    out: dict = {"status": "computed", "bracket": [lo, hi], "transient_cycles": transient}
    out |= refined
    other = spec.get("end_other_contact")
    if other:
        out["other_contact"] = _under_other_contact(
            scene, cscene, param, fine, transient, dict(other), directory / f"{case}-refined-"
            f"{other['contact']}.nc", workers
        )  # fmt: skip
    if out["last_periodic_up"] is None:
        out["branch_error"] = "the refined sweep is not period-1 at its first value"
        return out
    end_spec = dict(
        spec,
        branch_points=int(spec.get("end_branch_points", 150)),
        branch_max_step=float(spec.get("end_max_step", 1.0)),
    )
    out["last_orbit"] = _orbit_at(scene, ds, param, out["last_periodic_up"])
    # the orbit continued up from the bracket's lower end (period-1 in the coarse sweep), from
    # the state the refined sweep settled to; where Newton does not converge, the next values
    tried = []
    for start in [v for v in fine if v <= out["last_periodic_up"]][:3]:
        point = scene.replace(sweep={}).with_parameters(**{param: start})
        y, aux = settled(ds.sel(direction="up"), point, param, start)
        try:
            out["branch"] = branch_summary(
                point, param, start, hi, end_spec, directory / f"{case}-end-branch.nc", y, aux
            )
        except WorkbenchError as exc:  # a failed start is a finding, not a crash
            tried.append(f"from {start:.6g}: {type(exc).__name__}: {str(exc)[:160]}")
            continue
        out["failed_starts"] = tried
        out["held"] = _held_dependence(point, param, start, out["branch"]["archive"])
        return out
    out["branch_error"] = "; ".join(tried)
    return out


def _refined(scene, cscene, param: str, fine: list, transient: int, path: Path, workers):
    """The continued sweep of ``cscene`` over ``fine`` both ways (``transient`` cycles per
    value, one segment) and what it says: the dataset and a dict of its archive, values,
    per-direction indicators, the last periodic value each way (:func:`workbench.analysis.
    periodic_run_end`), the last period-1 value going up with none above it, and its CPU."""
    from workbench.continuation import continued_sweep

    sweep = {
        param: fine,
        "continuation": dict(cscene.continuation, segments=1, transient_cycles=transient),
    }
    ds = continued_sweep(cscene.replace(sweep=sweep), path, workers=workers, restart=True)
    fper, _ = indicators(ds, scene, param, fine)
    ones = [v for v, k in zip(fine, fper["up"]["period"], strict=True) if k == 1]
    return ds, {
        "archive": str(path),
        "values": fine,
        "directions": fper,
        "last_periodic_up": periodic_run_end(fine, fper["up"]["period"]),
        "last_periodic_down": periodic_run_end(fine, fper["down"]["period"]),
        "highest_periodic_up": ones[-1] if ones else None,
        "cpu_time": float(ds.attrs["campaign_cpu_time"]),
    }


def _under_other_contact(
    scene, cscene, param, fine, transient, other: dict, path: Path, workers
) -> dict:
    """:func:`_refined` under another contact law (``other``: ``contact``, the law, and its
    parameters), with the orbit Newton finds at its highest period-1 value going up."""
    law = other.pop("contact")

    def changed(s):
        return s.replace(effects=dict(s.effects, contact=law), parameters=s.parameters | other)

    scene, cscene = changed(scene), changed(cscene)
    ds, out = _refined(scene, cscene, param, fine, transient, path, workers)
    out |= {"contact": law, "parameters": other}
    if out["highest_periodic_up"] is not None:
        out["last_orbit"] = _orbit_at(scene, ds, param, out["highest_periodic_up"])
    return out


#: the tolerances Newton's method tries in turn for the orbit at the end: on an impacting
#: orbit the map's noise at rtol 1e-8 (1.6e-4 scaled on the nine-bar at 1.86 pi) lies above
#: Newton's tolerance 1e-6, and Newton stagnates there; at 1e-10 it converges
ORBIT_RTOLS = (1e-8, 1e-10)


def _orbit_at(scene, ds, param: str, value: float) -> dict:
    """The period-1 orbit Newton finds at ``value`` from the state the refined sweep settled to
    going up (at the first of :data:`ORBIT_RTOLS` where it converges): its largest
    |multiplier|, events per period and smallest event value (the mechanisms: penetration, m;
    negative where a contact lifts off during the cycle), and that rtol."""
    from workbench.continuation import periodic_orbit

    point = scene.replace(sweep={}).with_parameters(**{param: value})
    y, aux = settled(ds.sel(direction="up"), point, param, value)
    errors = []
    for rtol in ORBIT_RTOLS:
        try:
            orbit = periodic_orbit(point, state=y, discrete_state=aux, rtol=rtol, tolerance=1e-6)
        except WorkbenchError as exc:  # a failed Newton is a finding, not a crash
            errors.append(f"rtol {rtol:g}: {type(exc).__name__}: {str(exc)[:160]}")
            continue
        lowest = float(orbit.event_min.values.min()) if "event_min" in orbit else math.nan
        return {
            "value": value,
            "rtol": rtol,
            "largest_modulus": float(np.nanmax(orbit.multiplier_modulus.values)),
            "events_per_period": float(orbit.events_per_period.values[0]),
            "smallest_event": lowest,
        }
    return {"value": value, "error": "; ".join(errors)}


def _held_dependence(point, param: str, value: float, archive: str) -> list[dict]:
    """The first orbit of the end branch found again with its held discrete states scaled by
    each of ``HELD_FACTORS``: the held values and the largest |multiplier| (NaN where Newton
    failed). Empty when the orbit holds none."""
    from workbench.archive import open_run
    from workbench.continuation import StrobeMap
    from workbench.continuation._newton import NewtonFailure, orbit_at

    branch = open_run(archive)
    if "orbit_discrete_state" not in branch:
        return []
    held = branch.orbit_discrete_state.values[0]
    if not np.any(held != 0.0):
        return []
    smap = StrobeMap(point, param, rtol=1e-8)
    pb = smap.prepared(value).problem
    if any(f"orbit_{q.name}" not in branch for q in pb.states):
        return []
    y = np.array([float(branch[f"orbit_{q.name}"].values[0]) for q in pb.states])
    rows = []
    for f in HELD_FACTORS:
        aux = held * f
        try:
            pt = orbit_at(smap, y, aux, value, tolerance=1e-6)
            largest = float(np.abs(pt.multipliers).max())
        except NewtonFailure:
            largest = math.nan
        rows.append({"factor": f, "held": [float(a) for a in aux], "largest_modulus": largest})
    return rows
