"""Run a study of the paper: its cases as ensembles, their numbers, its claims and figures."""

from __future__ import annotations

import json
import math
import os
import re
import time as _time
from pathlib import Path

import numpy as np
import xarray as xr

from workbench.archive import save_run, write_text_atomic
from workbench.run import REALISATION_ATTRS
from workbench.scene import Scene
from workbench.study._claims import _key, evaluate_claim
from workbench.study._exponents import WOLF_SAMPLING, exponent_table
from workbench.study._measure import (
    CLEARANCE_COORDINATES,
    PEAK_PERIODS,
    clearance_of,
    contact_fraction,
    energy_per_cycle,
    force_percentiles,
    member_run,
    peak,
    seconds_per_cycle,
    select,
    strobe,
)
from workbench.study._spec import Study, load_study, parameter_sweep, quick_study
from workbench.study._stats import describe

__all__ = ["run_study", "ensemble_scene"]

_PER_CASE = ("peak", "peak_ratio_near_one", "strobe_spread")  # statistics measured per case

# Why a paper value may lie outside our ensemble's range (the report's known causes).
_CAUSE_TORQUE = (
    "known cause 3: the paper's crank torques exceed what its own contact forces allow (spec "
    "doubt 2); not a validation target"
)
_CAUSE_LLE_UNITS = (
    "known cause 5: the paper does not state the unit of its LLEs (per second, per crank period "
    "or per sample of its output step); ours are 1/s, so no ratio is formed (see the exponent "
    "table of this study for what the paper's numbers could be)"
)
_CAUSE_ABOVE = (
    "known causes 1-2: the geometry is reconstructed, and the paper's 1 ms output step "
    "under-samples contact peaks that last 1e-5 to 1e-3 s (spec doubt 3)"
)
_CAUSE_BELOW = (
    "known cause 1: the geometry (L71, L72, beta, L8, O6, S0, initial phase) is reconstructed "
    "(spec doubt 1)"
)


def ensemble_scene(scene: Scene, realisations: int, perturbation: float) -> Scene:
    """``scene`` as a campaign over ``realisation = 0 .. realisations - 1`` (after its own swept
    parameters, if any) with the initial-state perturbation ``perturbation`` (relative)."""
    sweep = {k: list(v) for k, v in scene.sweep.items()}
    sweep.setdefault("realisation", list(range(realisations)))
    return scene.replace(run=dict(scene.run, perturbation=perturbation), sweep=sweep)


def run_study(
    name: str | Study,
    *,
    out: str | os.PathLike = "out/studies",
    quick: bool = False,
    workers: int | None = None,
    progress: bool = False,
) -> xr.Dataset:
    """Run every case of a study as an ensemble, measure what the paper reports, check its
    claims, draw its figures.

    Parameters
    ----------
    name : str or Study
        A study under ``studies/`` (``workbench.study.available_studies()`` lists them).
    out : path
        Directory; the study writes ``<out>/<name>/``: one campaign archive per case (dims
        ``realisation`` and any swept parameter), the figures (``fig<N>-*.png``, named for the
        paper's figures), ``summary.json`` (what the report reads) and ``summary.nc`` (the
        returned dataset).
    quick : bool
        Much shorter runs and at most 4 realisations (:func:`workbench.study.quick_study`),
        for smoke tests only.
    workers : int, optional
        Processes for the campaigns (default: all CPUs).
    progress : bool
        Progress bars.

    Returns
    -------
    xarray.Dataset
        Per member (a case without a parameter sweep, or a view) and realisation: the peaks
        (``peak_<quantity>`` over the whole record, ``peak2_<quantity>`` over the first two
        cycles, units of the quantity), stroboscopic spreads (``strobe_spread_<quantity>``, 1),
        ``seconds_per_cycle`` (s), the paper's values beside them (``paper_<quantity>``); the
        Wolf LLEs and 0-1 test of a chaos study; the bifurcation spreads; for sweeps that
        record the contact force, ``contact_fraction``, ``contact_force_percentile`` (N),
        ``driver_work_per_cycle`` and ``dissipated_energy_per_cycle`` (J); per claim its
        ``verdict``, ``evidence``, ``reason`` and ``p_value``. Units on every variable; the
        study's metadata and the summary's path in the attributes.
    """
    from workbench.campaign import run_campaign
    from workbench.study._figures import study_figures

    study = name if isinstance(name, Study) else load_study(name)
    if quick:
        study = quick_study(study)
    directory = Path(out) / study.name
    directory.mkdir(parents=True, exist_ok=True)
    study_wall0 = _time.perf_counter()
    runs: dict[str, xr.Dataset] = {}
    cases = {}
    for case, scene in study.cases.items():
        store = directory / f"{case}.nc"
        wall0 = _time.perf_counter()
        escene = ensemble_scene(scene, study.realisations, study.perturbation)
        ds = run_campaign(escene, store, workers=workers, restart=True, progress=progress)
        runs[case] = ds.load()
        cases[case] = {
            "archive": str(store),
            "title": scene.title,
            "wall_time": _time.perf_counter() - wall0,
            "runs": int(ds.attrs["campaign_points"]),
            "failed_runs": int(ds.attrs["failed_points"]),
            "seconds_per_cycle": describe(
                [seconds_per_cycle(w, scene) for w in ds["solver_wall_time"].values.ravel()]
            ),
            "paper_seconds_per_cycle": study.paper_seconds_per_cycle.get(case),
        }
    members = {m: _member(study, runs, m) for m in study.members}
    scenes = {m: study.member_scene(m) for m in study.members}
    measures = _measures(study, runs, members, scenes)
    sweeps = _sweep_contact(study, runs)
    measures["sweep_contact"] = {c: _sweep_summary(d) for c, d in sweeps.items()}
    claims = [evaluate_claim(c, measures) for c in study.claims]
    paper_rows = _paper_values(study, measures)
    figures = study_figures(study, runs, members, scenes, sweeps, directory, measures)
    summary = {
        "study": study.name,
        "title": study.title,
        "section": study.section,
        "paper_figures": study.paper_figures,
        "quick": quick,
        "note": study.note,
        "realisations": study.realisations,
        "perturbation": study.perturbation,
        "cycles": _cycles(study),
        "cases": cases,
        "views": study.views,
        "paper_values": paper_rows,
        "claims": claims,
        "measures": measures,
        "flutter": _flutter(study, quick),
        "figures": [str(p) for p in figures],
        "wall_time": _time.perf_counter() - study_wall0,
    }
    _write_json(summary, directory / "summary.json")
    result = summary_dataset(study, members, measures, claims, paper_rows, sweeps)
    result.attrs.update(
        summary_json=str(directory / "summary.json"),
        archives=json.dumps({c: v["archive"] for c, v in cases.items()}),
        runs=sum(v["runs"] for v in cases.values()),
        wall_time=summary["wall_time"],
        quick=int(quick),
    )
    save_run(result, directory / "summary.nc")
    return result


def _member(study: Study, runs: dict, name: str) -> xr.Dataset:
    if name in study.views:
        v = study.views[name]
        return member_run(runs[v["case"]], v["select"])
    return member_run(runs[name])


def _cycles(study: Study) -> dict[str, list[int]]:
    """Recorded and transient cycles per case (the report states them)."""
    return {
        c: [int(s.run.get("cycles", 0)), int(s.run.get("transient_cycles", 0))]
        for c, s in study.cases.items()
    }


def _measures(study: Study, runs: dict, members: dict, scenes: dict) -> dict:
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
        **{k: _native(v) for k, v in table.attrs.items()},
    }
    return out


#: measured crank cycles of the exponents from the equations, and of the stroboscopic map
EXPONENT_CYCLES = 6
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
            for da in (x, y):
                acc.append(da.std("time", skipna=True).values / c)
            touch.append((np.hypot(x, y) > c).where(np.isfinite(x)).mean("time").values)
        spreads.append([float(s) for s in np.nanmean(acc, axis=0)])
        in_contact.append([float(s) for s in np.nanmean(touch, axis=0)])
    return {"parameter": param, "values": values, "spread": spreads, "in_contact": in_contact}


def _sweep_contact(study: Study, runs: dict) -> dict[str, xr.Dataset]:
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


def _sweep_summary(d: xr.Dataset) -> dict:
    """Medians and quartiles over the realisations of a :func:`_sweep_contact` dataset, as
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


#: records per crank cycle, and cycles after the scene's transient, of the flutter analysis
FLUTTER_SAMPLES = 200
FLUTTER_CYCLES = 1


def _flutter(study: Study, quick: bool) -> dict | None:
    """The flutter of the sliding contact against the friction coefficient: for every value of
    each ``[flutter]`` case's sweep, the eigenvalues of the rhs Jacobian
    (:func:`workbench.analysis.jacobian_spectrum`) at the records where both journals are in
    contact, over one crank cycle after the transient (200 records). Per value: the median and
    90th percentile of the largest real part (s-1), the frequency (Hz) at the largest, and the
    fraction of records in continuous contact. The onset is where the median first exceeds the
    crank frequency (the sliding mode then grows e-fold within a crank cycle), interpolated."""
    if not study.flutter:
        return None
    from workbench import analysis

    spec = dict(study.flutter)
    param = spec["parameter"]
    out = {**spec, "status": "computed", "cases": {}}
    for case in spec["cases"]:
        scene = study.cases[case]
        values = list(scene.sweep[param])
        if quick:
            values = values[:: max(1, len(values) // 3)]
        rows = {"values": values, "median": [], "p90": [], "frequency": [], "fraction": []}
        omega = float(scene.resolved_parameters["omega"])
        for v in values:
            point = scene.with_parameters(**{param: v}).replace(
                run={"cycles": FLUTTER_CYCLES, "transient_cycles": scene.run["transient_cycles"]},
                record={"samples_per_period": FLUTTER_SAMPLES},
            )
            r = analysis.jacobian_spectrum(point)
            both = [i for i, m in enumerate(r.modes.values) if m.count("contact") == 2]
            sel = np.isin(r.mode.values, both)
            top = r.largest_real.values[sel]
            rows["fraction"].append(float(sel.mean()))
            if top.size:
                i = int(np.argmax(top))
                rows["median"].append(float(np.median(top)))
                rows["p90"].append(float(np.quantile(top, 0.9)))
                rows["frequency"].append(float(r.frequency.values[sel][i]))
            else:
                rows["median"].append(math.nan)
                rows["p90"].append(math.nan)
                rows["frequency"].append(math.nan)
        threshold = omega / (2 * math.pi)
        rows["threshold"] = threshold
        rows["onset"] = _first_crossing(values, rows["median"], threshold)
        out["cases"][case] = rows
    return out


def _first_crossing(x: list, y: list, level: float) -> float:
    """First x where y rises through ``level`` (linear interpolation; NaN if it never does)."""
    for i in range(1, len(x)):
        a, b = y[i - 1], y[i]
        if np.isfinite(a) and np.isfinite(b) and a < level <= b:
            return float(x[i - 1] + (level - a) / (b - a) * (x[i] - x[i - 1]))
    return math.nan


def _paper_values(study: Study, measures: dict) -> list[dict]:
    rows = []
    for entry in study.paper_values:
        stat = entry.get("statistic", "peak")
        key = _key(entry)
        if stat == "wolf_lle":
            label = next(
                k
                for k, (v, w) in CLEARANCE_COORDINATES.items()
                if _key({"var": v, "select": w}) == key
            )
            values = np.asarray(measures.get("wolf_lle", {}).get(label, []), float)
            units = "1/s"
        else:
            values = np.asarray(measures["peak"].get(entry["case"], {}).get(key, []), float)
            units = measures["units"].get(key, "")
        paper = float(entry["value"])
        mags = describe(np.abs(values))
        finite = values[np.isfinite(values)]
        within = mags["n"] > 0 and mags["min"] <= abs(paper) <= mags["max"]
        if stat == "wolf_lle":
            note = _CAUSE_LLE_UNITS  # a value of unknown units is never "within our range"
            within = False
        elif within:
            note = ""
        elif entry["var"] == "torque":
            note = _CAUSE_TORQUE
        else:
            note = _CAUSE_ABOVE if mags["median"] > abs(paper) else _CAUSE_BELOW
        rows.append(
            {
                "case": entry["case"],
                "quantity": key,
                "statistic": stat,
                "units": units,
                "paper": paper,
                "ours": mags,
                "same_sign": int(np.sum(np.sign(finite) == np.sign(paper))),
                "ratio_of_medians": (
                    mags["median"] / abs(paper) if mags["n"] and stat != "wolf_lle" else None
                ),
                "within_range": bool(within),
                "note": note,
            }
        )
    return rows


# -- the returned dataset ---------------------------------------------------------------------
def _slug(key: str) -> str:
    """A variable name for a measured quantity: 'torque[crank=1]' -> 'torque_crank_1'."""
    return re.sub(r"[^0-9A-Za-z]+", "_", key.replace("=", "_")).strip("_")


def summary_dataset(
    study: Study,
    members: dict,
    measures: dict,
    claims: list[dict],
    paper_rows: list[dict],
    sweeps: dict[str, xr.Dataset],
) -> xr.Dataset:
    """The study's numbers as one dataset with units on every variable (see
    :func:`run_study`)."""
    names = list(members)
    n_real = study.realisations
    coords = {
        "member": ("member", names, {"long_name": "case or view of the study", "units": "1"}),
        "realisation": ("realisation", np.arange(n_real), dict(REALISATION_ATTRS)),
    }
    data: dict = {}

    def table(field: str, prefix: str, units_of, long_name: str) -> None:
        keys = sorted({k for per in measures.get(field, {}).values() for k in per})
        for key in keys:
            arr = np.full((len(names), n_real), np.nan)
            for i, name in enumerate(names):
                vals = measures[field].get(name, {}).get(key)
                if vals is not None:
                    arr[i, : len(vals)] = vals
            var = f"{prefix}_{_slug(key)}" if key else prefix
            data[var] = (
                ("member", "realisation"),
                arr,
                {"units": units_of(key), "long_name": long_name.format(key=key)},
            )

    units = measures.get("units", {})
    table(
        "peak_record",
        "peak",
        lambda k: units.get(k, ""),
        "value of largest magnitude (signed) of {key} over the whole record",
    )
    table(
        "peak",
        "peak2",
        lambda k: units.get(k, ""),
        f"value of largest magnitude (signed) of {{key}} over the first {PEAK_PERIODS} cycles",
    )
    table(
        "strobe_spread",
        "strobe_spread",
        lambda k: "1",
        "standard deviation of the stroboscopic samples of {key} in units of the clearance",
    )
    table(
        "seconds_per_cycle",
        "seconds_per_cycle",
        lambda k: "s",
        "integration wall time per simulated crank cycle",
    )
    for row in paper_rows:
        if row["statistic"] != "peak":
            continue
        var = f"paper_{_slug(row['quantity'])}"
        if var not in data:
            data[var] = (
                ("member",),
                np.full(len(names), np.nan),
                {"units": row["units"], "long_name": f"the paper's peak of {row['quantity']}"},
            )
        data[var][1][names.index(row["case"])] = row["paper"]
    if measures.get("wolf_lle"):
        labels = list(measures["wolf_lle"])
        coords["coordinate"] = (
            "coordinate",
            labels,
            {"long_name": "clearance coordinate (x1, y1: joint A; x2, y2: joint B)", "units": "1"},
        )
        for field, u, long_name in (
            ("wolf_lle", "s-1", "largest Lyapunov exponent (Wolf et al. 1985)"),
            ("zero_one_K", "1", "0-1 test for chaos K of the stroboscopic samples"),
        ):
            arr = np.full((len(labels), n_real), np.nan)
            for i, k in enumerate(labels):
                arr[i, : len(measures[field][k])] = measures[field][k]
            data[field] = (("coordinate", "realisation"), arr, {"units": u, "long_name": long_name})
    exponents = measures.get("exponents")
    if exponents:
        coords["method"] = ("method", exponents["method"], {"long_name": "estimator", "units": "1"})
        for field, units, long_name in (
            ("lle", "s-1", "largest Lyapunov exponent of realisation 0 by each method"),
            ("lle_per_cycle", "1", "the same per crank cycle"),
            ("stderr", "s-1", "standard error of the finite window"),
        ):
            values = np.array([np.nan if v is None else v for v in exponents[field]], float)
            data[f"exponent_{field}"] = ("method", values, {"units": units, "long_name": long_name})
        data["exponent_trusted"] = (
            "method",
            np.array(exponents["trusted"], bool),
            {"long_name": "converged (equations) or reliable (Wolf)"},
        )
    spread = measures.get("bifurcation_spread")
    if spread:
        param = spread["parameter"]
        scene = next(iter(study.cases.values()))
        coords[param] = (param, spread["values"], _param_attrs(scene, param))
        for field, long_name in (
            ("spread", "mean stroboscopic spread of x1, y1, x2, y2 in units of the clearance"),
            ("in_contact", "share of stroboscopic samples with a journal in contact"),
        ):
            arr = np.full((len(spread["values"]), n_real), np.nan)
            for i, row in enumerate(spread[field]):
                arr[i, : len(row)] = row
            data[f"bifurcation_{field}"] = (
                (param, "realisation"),
                arr,
                {"units": "1", "long_name": long_name},
            )
    ds = xr.Dataset(data, coords=coords)
    if sweeps:
        stacked = xr.concat(
            [d.expand_dims(sweep_case=[c]) for c, d in sweeps.items()], "sweep_case", join="outer"
        )
        stacked["sweep_case"].attrs.update(long_name="case of the parameter sweep", units="1")
        stacked = stacked.assign_coords(
            realisation=ds["realisation"][: stacked.sizes["realisation"]]
        )
        ds = xr.merge([ds, stacked], combine_attrs="drop_conflicts")
    if claims:
        ds = ds.assign_coords(
            claim=("claim", np.arange(len(claims)), {"long_name": "claim", "units": "1"})
        )
        for field in ("text", "verdict", "evidence", "reason"):
            ds[f"claim_{field}"] = (
                "claim",
                np.array([c.get(field, "") for c in claims], dtype=object),
                {"units": "1", "long_name": f"{field} of the paper's claim"},
            )
        ds["claim_p_value"] = (
            "claim",
            np.array([c.get("p_value", math.nan) for c in claims], float),
            {"units": "1", "long_name": "p-value of the claim's rank test"},
        )
    ds.attrs.update(
        study=study.name,
        title=study.title,
        section=study.section,
        paper_figures=study.paper_figures,
        realisations=study.realisations,
        perturbation=study.perturbation,
    )
    return ds


def _param_attrs(scene: Scene, name: str) -> dict:
    from workbench.campaign._store import parameter_attrs

    return parameter_attrs(scene, name)


def _write_json(data: dict, path: Path) -> None:
    write_text_atomic(path, json.dumps(data, indent=1, default=_plain))


def _plain(x):
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    raise TypeError(f"not JSON serialisable: {x!r}")
