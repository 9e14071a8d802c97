"""The parts of a study's route to chaos (:mod:`workbench.study._route`) that its end
(:mod:`workbench.study._route_end`) shares: the strobe indicators of a continued sweep, the
state a continued point settled to, and a periodic branch with the numbers the report needs."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import xarray as xr

from workbench._attributes import flag_names
from workbench.archive import save_run
from workbench.study._measure import CLEARANCE_COORDINATES, clearance_of, select

__all__ = ["branch_summary", "coordinates", "indicators", "settled"]


def coordinates(ds: xr.Dataset, scene, param: str, value: float) -> np.ndarray:
    """Strobe samples of x1, y1, x2, y2 at one value (rows: samples), in units of c."""
    point = ds.sel({param: value})
    cols = []
    for var, where in CLEARANCE_COORDINATES.values():
        c = value if param == "clearance" else clearance_of(scene, where["joint"])
        cols.append(select(point, var, where).values / c)
    rows = np.column_stack(cols)
    return rows[np.isfinite(rows).all(axis=1)]


def settled(part: xr.Dataset, point, param: str, value: float):
    """(state, discrete state) a continued point ended in (at forcing phase 0), or (None,
    None) where its run failed."""
    from workbench.run import prepare

    pb = prepare(point, variables=()).problem
    p = part.sel({param: value})
    y = np.array(
        [float(p[f"final_{q.name}"]) if f"final_{q.name}" in p else 0.0 for q in pb.states]
    )
    aux = p["final_discrete_state"].values if "final_discrete_state" in p else pb.aux0
    aux = np.asarray(aux, dtype=float)
    if not (np.isfinite(y).all() and np.isfinite(aux).all()):
        return None, None
    return y, aux


def indicators(ds: xr.Dataset, scene, param: str, values: list[float]) -> tuple[dict, dict]:
    """Per direction of a continued sweep and per value: the strobe spread (in units of c),
    period (0: none up to 16) and 0-1 test K; and the strobe samples themselves."""
    from workbench.continuation import strobe_period, strobe_zero_one

    per: dict = {}
    clouds: dict = {}
    for d in ("up", "down"):
        part = ds.sel(direction=d)
        rows = {"spread": [], "period": [], "K": []}
        clouds[d] = []
        for v in values:
            x = coordinates(part, scene, param, v)
            clouds[d].append(x)
            rows["spread"].append(float(np.mean(np.std(x, axis=0))) if len(x) else math.nan)
            rows["period"].append(strobe_period(x) if len(x) else -1)
            ks = [strobe_zero_one(x[:, j]) for j in range(x.shape[1])] if len(x) else []
            rows["K"].append(float(np.nanmedian(ks)) if np.isfinite(ks).any() else math.nan)
        per[d] = rows
    return per, clouds


def branch_summary(
    point, param: str, start: float, stop: float, spec: dict, path: Path, state=None, aux=None
) -> dict:
    """The period-1 orbit of ``point`` continued from ``start`` towards ``stop`` (Newton's start:
    ``state`` and ``aux``, default after the scene's transient), written to ``path``, and the
    numbers the report needs: per point its value, stability, largest |multiplier|, events per
    period and smallest event value; the bifurcations with their multipliers; why it ended."""
    from workbench.continuation import branch_bifurcations, continue_orbit

    branch = continue_orbit(
        point,
        param,
        start=start,
        stop=stop,
        state=state,
        discrete_state=aux,
        rtol=1e-8,
        tolerance=1e-6,
        max_points=int(spec.get("branch_points", 300)),
        max_step=float(spec.get("branch_max_step", 0.05)),
    )
    save_run(branch, path)
    stable = branch.stable.values
    bifurcations = []
    for b in branch_bifurcations(branch, param):
        i = b["index"]
        mu = branch.multiplier_real.values[i] + 1j * branch.multiplier_imag.values[i]
        mu = mu[np.isfinite(mu)]
        bifurcations.append(
            {
                "type": b["type"],
                "value": b["value"],
                "resolved": b["resolved"],
                "transition": b["transition"],
                "critical": [b["critical"].real, b["critical"].imag],
                "multipliers": [[float(z.real), float(z.imag)] for z in mu[:4]],
                "stable_before": bool(stable[max(i - 1, 0)]),
                "stable_after": bool(stable[min(i + 1, stable.size - 1)]),
                "events_before": float(branch.events_per_period.values[max(i - 1, 0)]),
                "events_after": float(branch.events_per_period.values[min(i + 1, stable.size - 1)]),
            }
        )
    modulus = np.nanmax(branch.multiplier_modulus.values, axis=1)
    if "event_min" in branch:
        lowest = np.min(branch.event_min.values, axis=1)
    else:
        lowest = np.full(stable.size, np.nan)
    names = flag_names(branch.label)
    return {
        "archive": str(path),
        "start": start,
        "stop": stop,
        "values": [float(v) for v in branch[param].values],
        "stable": [int(s) for s in stable],
        "largest_modulus": [float(m) for m in modulus],
        "events_per_period": [float(e) for e in branch.events_per_period.values],
        "smallest_event": [float(e) for e in lowest],
        "last_label": names[int(branch.label.values[-1])],
        "bifurcations": bifurcations,
        "ended": branch.attrs["branch_ended"],
        "map_evaluations": int(branch.attrs["map_evaluations"]),
        "monodromy": branch.attrs["monodromy"],
    }
