"""The numbers of a study, one per realisation: peaks, stroboscopic spreads, contact and energy
per cycle of the sweeps, the chaos measures (Wolf LLE, 0-1 test, the exponent table) and the
bifurcation spreads, as plain lists for ``summary.json``."""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from workbench.scene import Scene
from workbench.study._claims import _key
from workbench.study._exponents import WOLF_SAMPLING, exponent_table
from workbench.study._measure import (
    CLEARANCE_COORDINATES,
    PEAK_PERIODS,
    clearance_of,
    contact_fraction,
    energy_per_cycle,
    force_percentiles,
    friction_law,
    member_run,
    peak,
    record_dim,
    seconds_per_cycle,
    select,
    strobe,
)
from workbench.study._spec import Study, parameter_sweep

__all__ = ["measures", "sweep_contact", "sweep_summary"]

_PER_CASE = ("peak", "peak_ratio_near_one", "strobe_spread")  # statistics measured per case


def measures(study: Study, runs: dict, members: dict, scenes: dict) -> dict:
    """Every number a claim or a paper value of the study asks for, one per realisation."""
    # "peak": over the first PEAK_PERIODS recorded cycles (for the paper's values, read from a
    # plot); "peak_record": over the whole record (for the claims: less sampling noise)
    m: dict = {
        "realisations": study.realisations,
        "units": {},
        "peak": {},
        "peak_record": {},
        "strobe_spread": {},
        "seconds_per_cycle": {},
        "contact": {},
        "friction_law": {},
    }
    entries = study.claims + study.paper_values
    for name, ds in members.items():
        scene = scenes[name]
        walls = ds["solver_wall_time"].values
        m["seconds_per_cycle"][name] = {"": [seconds_per_cycle(w, scene) for w in walls]}
        for entry in entries:
            var = entry.get("var")
            stat = entry.get("statistic", "peak")
            if var is None or var not in ds or stat not in _PER_CASE:
                continue
            where = entry.get("select", {})
            key = _key(entry)
            da = select(ds, var, where)
            m["units"][key] = ds[var].attrs.get("units", "")
            if stat != "strobe_spread":
                reals = [da.sel(realisation=r) for r in ds["realisation"].values]
                m["peak"].setdefault(name, {})[key] = [peak(x, PEAK_PERIODS, ds) for x in reals]
                m["peak_record"].setdefault(name, {})[key] = [peak(x) for x in reals]
            elif where.get("joint") in ds.joint:
                samples = strobe(ds, da)
                spread = samples.std("strobe", skipna=True) / clearance_of(scene, where["joint"])
                m["strobe_spread"].setdefault(name, {})[key] = [float(x) for x in spread.values]
        law = friction_law(ds, scene)
        if law:
            m["friction_law"][name] = law
        if "contact_force" in ds:
            frac = contact_fraction(ds["contact_force"])
            p99 = force_percentiles(ds["contact_force"], (99.0,)).squeeze("percentile")
            m["contact"][name] = {
                str(j): {
                    "fraction": [float(x) for x in frac.sel(joint=j).values],
                    "p99": [float(x) for x in p99.sel(joint=j).values],
                }
                for j in ds["joint"].values
            }
    kinds = {f["kind"] for f in study.figures}
    if kinds & {"phase", "poincare", "lle"}:
        name = study.members[0]
        m.update(_chaos_measures(members[name], scenes[name]))
    if "bifurcation" in kinds:
        case = next(iter(runs))
        m["bifurcation_spread"] = _bifurcation_spread(runs[case], study.cases[case])
    return m


def _chaos_measures(ds: xr.Dataset, scene: Scene) -> dict:
    """Per realisation: Wolf LLE (1/s) of x1, y1, x2, y2 and the 0-1 test K of their
    stroboscopic samples; the automatic choices of Wolf's method for realisation 0; and the
    exponent of the unperturbed scene by every method (:func:`exponent_table`: the converged
    two-trajectory and variational estimates, Wolf at finer samplings and on the stroboscopic
    map)."""
    from workbench import analysis

    out: dict = {"wolf_lle": {}, "wolf_lle_per_period": {}, "wolf_choices": {}, "zero_one_K": {}}
    period = ds.attrs.get("forcing_period")
    for label, (var, where) in CLEARANCE_COORDINATES.items():
        da = select(ds, var, where)
        if not np.isfinite(da.values).any():
            continue
        lle, per_period, k = [], [], []
        for r in ds["realisation"].values:
            x = da.sel(realisation=r)
            if not np.isfinite(x.values).all():
                continue  # a failed realisation
            w = analysis.wolf_lle(x, period=period)
            lle.append(float(w["lle"]))
            per_period.append(float(w["lle_per_period"]) if "lle_per_period" in w else math.nan)
            samples = strobe(ds, x)
            # the 0-1 test needs 100 stroboscopic samples (a --quick run has fewer)
            enough = samples.sizes["strobe"] >= 100
            k.append(float(analysis.zero_one_test(samples)["K"]) if enough else math.nan)
            if not out["wolf_choices"].get(label):
                out["wolf_choices"][label] = {
                    n: float(w[n]) for n in ("delay", "dim", "evolve", "theiler") if n in w
                }
        out["wolf_lle"][label] = lle
        out["wolf_lle_per_period"][label] = per_period
        out["zero_one_K"][label] = k
    table = exponent_table(
        scene.replace(sweep={}),
        cycles=min(EXPONENT_CYCLES, int(scene.run["cycles"])),
        transient_cycles=int(scene.run["transient_cycles"]),
        wolf_sampling=WOLF_SAMPLING if int(scene.run["cycles"]) >= 100 else ((100, 30),),
        strobe_cycles=STROBE_CYCLES if int(scene.run["cycles"]) >= 100 else 120,
    )
    out["exponents"] = {
        "method": [str(m) for m in table.method.values],
        **{k: [_native(v) for v in table[k].values] for k in _EXPONENT_VARS},
        "spectrum": [float(v) for v in table.spectrum.values],
        "spectrum_stderr": [float(v) for v in table.spectrum_stderr.values],
        "spectrum_trusted": [bool(v) for v in table.spectrum_trusted.values],
        **{k: _native(v) for k, v in table.attrs.items()},
    }
    return out


#: measured crank cycles of the exponents from the equations (at least; grown to twice that
#: until their standard error is 3 %: a few cycles are far from it on the chaos case, 4 x 20
#: cycles reach it, docs/analysis.md; the two-trajectory estimate shares them among four
#: independent starts), and of the stroboscopic map
EXPONENT_CYCLES = 40
STROBE_CYCLES = 400
_EXPONENT_VARS = ("lle", "lle_per_cycle", "stderr", "trusted", "note", "wall_time")


def _native(v):
    """A JSON-ready Python value of a numpy or Python scalar (non-finite floats as None)."""
    v = v.item() if hasattr(v, "item") else v
    return None if isinstance(v, float) and not math.isfinite(v) else v


def _bifurcation_spread(ds: xr.Dataset, scene: Scene) -> dict:
    """Per parameter value and realisation: the mean over x1, y1, x2, y2 of the stroboscopic
    spread, in units of the clearance (the swept clearance where the sweep is over it), and the
    share of the stroboscopic samples with a journal in contact (eccentricity above c)."""
    (param,) = list(parameter_sweep(scene))
    values = [float(v) for v in ds[param].values]
    spreads, in_contact = [], []
    for v in values:
        point = ds.sel({param: v})
        acc, touch = [], []
        for joint in ("A", "B"):
            c = v if param == "clearance" else clearance_of(scene, joint)
            x = select(point, "clearance_x", {"joint": joint})
            y = select(point, "clearance_y", {"joint": joint})
            rdim = record_dim(x)  # time, or record (each point's own record times)
            for da in (x, y):
                acc.append(da.std(rdim, skipna=True).values / c)
            touch.append((np.hypot(x, y) > c).where(np.isfinite(x)).mean(rdim).values)
        spreads.append([float(s) for s in np.nanmean(acc, axis=0)])
        in_contact.append([float(s) for s in np.nanmean(touch, axis=0)])
    return {"parameter": param, "values": values, "spread": spreads, "in_contact": in_contact}


def sweep_contact(study: Study, runs: dict) -> dict[str, xr.Dataset]:
    """For each case with a parameter sweep that records the contact force: contact fraction,
    force percentiles (50/90/99 %) and, where recorded, driver work and dissipation per cycle,
    per swept value, realisation and joint."""
    out = {}
    for case, ds in runs.items():
        if not parameter_sweep(study.cases[case]) or "contact_force" not in ds:
            continue
        run = member_run(ds)
        data = {
            "contact_fraction": contact_fraction(run["contact_force"]),
            "contact_force_percentile": force_percentiles(run["contact_force"]),
        }
        for var in ("driver_work", "dissipated_energy"):
            if var in run:
                data[f"{var}_per_cycle"] = energy_per_cycle(run, var)
        out[case] = xr.Dataset(data).drop_vars("quantile", errors="ignore")
        out[case].attrs["clearance"] = float(study.cases[case].resolved_parameters["clearance"])
    return out


def sweep_summary(d: xr.Dataset) -> dict:
    """Medians and quartiles over the realisations of a :func:`sweep_contact` dataset, as
    plain lists for the JSON summary."""
    (param,) = [k for k in d.dims if k not in ("realisation", "joint", "percentile")]
    out: dict = {
        "parameter": param,
        "values": [float(v) for v in d[param].values],
        "clearance": d.attrs["clearance"],
        "joints": [str(j) for j in d["joint"].values],
        "percentiles": [float(q) for q in d["percentile"].values],
    }
    for name, da in d.data_vars.items():
        q = da.quantile([0.25, 0.5, 0.75], dim="realisation", skipna=True)
        out[name] = {
            "units": da.attrs["units"],
            "q25": q.sel(quantile=0.25).values.tolist(),
            "median": q.sel(quantile=0.5).values.tolist(),
            "q75": q.sel(quantile=0.75).values.tolist(),
            "dims": [x for x in da.dims if x != "realisation"],
        }
    return out
