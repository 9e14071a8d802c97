"""Beyond the paper: how the motion of a bifurcation study becomes chaotic (``[route]`` of a
``study.toml``).

For the study's swept case: the sweep continued both ways (each point from its neighbour's
settled state, :func:`workbench.continuation.continued_sweep`), so that coexisting attractors
and hysteresis show; per point and direction the strobe spread, period and 0-1 test K; where
the two directions sit on different attractors; optionally the period-1 orbit continued over
the parameter (:func:`workbench.continuation.continue_orbit`) until it loses stability, with
the type, parameter and multipliers of every bifurcation; and the largest Lyapunov exponent at a
few values (:func:`workbench.continuation.point_exponent`: from the Floquet multipliers of the
orbit Newton finds from the continued sweep's settled state where the strobe is periodic, else
by the two-trajectory method over 20 cycles). ``[route]`` keys: ``case`` (default the swept
one), ``segments``, ``transient_cycles`` (per continued point), ``cycles`` (recorded; >= 100
for the 0-1 test), ``method`` (solver), ``branch_start``, ``branch_stop`` (the orbit's range;
no branch without them), ``branch_points`` (the most points of the branch, default 300: it
ends there, and says so, which bounds the study's cost), ``branch_max_step`` (its largest
scaled arclength step, default 0.05), ``exponents`` (how many values of the sweep get an
exponent, default 0), ``refine`` (where the periodic motion ends: that many values between
the last period-1 value and the next, continued again, and the orbit continued from there;
:mod:`workbench.study._route_end`, with ``end_transient_cycles``, ``end_branch_points`` and
``end_max_step``).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from workbench.study._route_parts import branch_summary, indicators, settled
from workbench.study._spec import Study, parameter_sweep

__all__ = ["route"]
#: two attractors differ at a point when their clouds are further apart than this fraction of
#: the clearance plus twice their own record spacing (the seam test of the continued sweep)
HYSTERESIS_TOLERANCE = 0.05
EXPONENT_CYCLES = 20


def _continued_scene(scene, spec: dict, quick: bool):
    (param,) = list(parameter_sweep(scene))
    values = list(scene.sweep[param])
    run = dict(scene.run, cycles=int(spec.get("cycles", scene.run["cycles"])))
    if quick:
        values = values[:: max(1, len(values) // 6)]
        run.update(cycles=min(run["cycles"], 6), transient_cycles=min(run["transient_cycles"], 4))
    sweep = {
        param: values,
        "continuation": {
            "direction": "both",
            "segments": min(int(spec.get("segments", 2)), len(values)),
            "transient_cycles": int(spec.get("transient_cycles", 3)),
        },
    }
    solver = dict(scene.solver, method=spec.get("method", scene.solver["method"]))
    return scene.replace(run=run, sweep=sweep, solver=solver), param


def route(study: Study, directory: Path, quick: bool, workers: int | None) -> dict | None:
    """The route to chaos of a study with ``[route]`` (see the module docstring): a dict for
    ``summary.json`` (parameter values, per direction spread / period / K, hysteresis, the
    branch's bifurcations, exponents, the files written and the wall time of each part)."""
    if not study.route:
        return None
    from workbench.continuation import continued_sweep, point_exponent

    spec = dict(study.route)
    swept = [c for c, s in study.cases.items() if parameter_sweep(s)]
    case = spec.get("case", swept[0] if swept else None)
    scene = study.cases[case]
    cscene, param = _continued_scene(scene, spec, quick)
    out: dict = {"case": case, "parameter": param, "status": "computed", "wall_time": {}}
    t0 = time.perf_counter()
    ds = continued_sweep(cscene, directory / f"{case}-continued.nc", workers=workers, restart=True)
    out["wall_time"]["continued_sweep"] = time.perf_counter() - t0
    out["cpu_time_continued_sweep"] = float(ds.attrs["campaign_cpu_time"])
    out["archive"] = str(directory / f"{case}-continued.nc")
    values = [float(v) for v in ds[param].values]
    out["values"] = values
    out["cycles"] = [int(cscene.run["cycles"]), int(cscene.continuation["transient_cycles"])]
    out["chained_seams"] = int(ds["seam_chained"].sum()) if "seam_chained" in ds else 0
    per, clouds = indicators(ds, scene, param, values)
    out["directions"] = per
    out["hysteresis"] = _hysteresis(clouds, values)
    if "branch_start" in spec and not quick:
        t0 = time.perf_counter()
        start, stop = float(spec["branch_start"]), float(spec["branch_stop"])
        point = scene.replace(sweep={}).with_parameters(**{param: start})
        out["branch"] = branch_summary(
            point, param, start, stop, spec, directory / f"{case}-branch.nc"
        )
        out["wall_time"]["branch"] = time.perf_counter() - t0
    if spec.get("refine") and not quick:
        from workbench.study._route_end import periodic_end

        t0 = time.perf_counter()
        out["end"] = periodic_end(scene, cscene, param, values, per, spec, directory, case, workers)
        out["wall_time"]["end"] = time.perf_counter() - t0
    n_exp = int(spec.get("exponents", 0)) if not quick else 0
    if n_exp:
        t0 = time.perf_counter()
        picks = np.unique(np.linspace(0, len(values) - 1, n_exp).round().astype(int))
        out["exponents"] = []
        up = ds.sel(direction="up")
        for i in picks:
            point = scene.with_parameters(**{param: values[i]})
            y, aux = settled(up, point, param, values[i])
            e = point_exponent(
                point,
                period=max(per["up"]["period"][i], 0),
                cycles=EXPONENT_CYCLES,
                state=y,
                discrete_state=aux,
            )
            row = {"value": values[i], "method": e.method, "note": e.detail[:300]}
            if e.failed:  # a failed run is a finding, not a crash of the study
                row["error"] = e.detail[:200]
            else:
                row.update(lle=e.value, stderr=e.error, bound=e.bound)
            out["exponents"].append(row)
        out["wall_time"]["exponents"] = time.perf_counter() - t0
    return out


def _hysteresis(clouds: dict, values: list[float]) -> dict:
    """Per value: the distance of the up and down attractors (mean nearest-record distance,
    in units of c) and whether they differ (beyond the tolerance and their own spacing)."""
    from workbench.continuation import attractor_distance

    cross, within, differs = [], [], []
    for a, b in zip(clouds["up"], clouds["down"], strict=True):
        c, w = attractor_distance(a, b, np.ones(a.shape[1] if a.ndim == 2 else 4))
        cross.append(c)
        within.append(w)
        differs.append(bool(np.isfinite(c) and c > HYSTERESIS_TOLERANCE + 2 * w))
    return {
        "distance": cross,
        "spread": within,
        "differs": differs,
        "values": [v for v, d in zip(values, differs, strict=True) if d],
        "tolerance": HYSTERESIS_TOLERANCE,
    }
