"""Run a study of the paper: its cases, its numbers, its claims and its figures."""

from __future__ import annotations

import json
import math
import os
import time as _time
from pathlib import Path

import numpy as np
import xarray as xr

from workbench.archive import save_run, write_text_atomic
from workbench.run import simulate
from workbench.study._claims import _key, evaluate_claim
from workbench.study._measure import peak, seconds_per_cycle, select, strobe, strobe_spread
from workbench.study._spec import Study, load_study, quick_scene

__all__ = ["run_study", "CLEARANCE_COORDINATES"]

# The four clearance coordinates of the paper's Sec. 5: x1, y1 (joint A), x2, y2 (joint B).
CLEARANCE_COORDINATES = {
    "x1": ("clearance_x", {"joint": "A"}),
    "y1": ("clearance_y", {"joint": "A"}),
    "x2": ("clearance_x", {"joint": "B"}),
    "y2": ("clearance_y", {"joint": "B"}),
}
PEAK_PERIODS = 2  # peaks are read over the first two recorded crank cycles, as in a paper plot


def run_study(
    name: str | Study,
    *,
    out: str | os.PathLike = "out/studies",
    quick: bool = False,
    workers: int | None = None,
    progress: bool = False,
) -> dict:
    """Run every case of a study, measure what the paper reports, check its claims, draw its
    figures.

    Parameters
    ----------
    name : str or Study
        A study under ``studies/`` (``workbench.study.available_studies()`` lists them).
    out : path
        Directory; the study writes ``<out>/<name>/``: one netCDF archive per case, the
        figures (``fig<N>-*.png``, named for the paper's figures) and ``summary.json``.
    quick : bool
        Much shorter runs (:func:`workbench.study.quick_scene`), for smoke tests only.
    workers : int, optional
        Processes for the campaign cases (default: all CPUs).
    progress : bool
        Progress bars.

    Returns
    -------
    dict
        The summary (also written as ``summary.json``): per case the archive, wall time and
        seconds per cycle; the measured paper values beside the paper's; the claims with
        ``reproduced`` and the evidence; chaos and bifurcation measures where the study has
        them; the figure files.
    """
    from workbench.study._figures import study_figures

    study = name if isinstance(name, Study) else load_study(name)
    directory = Path(out) / study.name
    directory.mkdir(parents=True, exist_ok=True)
    runs: dict[str, xr.Dataset] = {}
    scenes = {}
    cases = {}
    for case, scene in study.cases.items():
        scene = quick_scene(scene) if quick else scene
        scenes[case] = scene
        store = directory / f"{case}.nc"
        wall0 = _time.perf_counter()
        if scene.sweep:
            from workbench.campaign import run_campaign

            ds = run_campaign(scene, store, workers=workers, restart=True, progress=progress)
        else:
            ds = simulate(scene, progress=progress)
            save_run(ds, store)
        wall = _time.perf_counter() - wall0
        runs[case] = ds
        cases[case] = {
            "archive": str(store),
            "title": scene.title,
            "wall_time": wall,
            "seconds_per_cycle": None if scene.sweep else seconds_per_cycle(ds, scene),
            "paper_seconds_per_cycle": study.paper_seconds_per_cycle.get(case),
        }
    measures = _measures(study, runs, scenes, cases)
    summary = {
        "study": study.name,
        "title": study.title,
        "section": study.section,
        "paper_figures": study.paper_figures,
        "quick": quick,
        "cases": cases,
        "paper_values": _paper_values(study, runs, measures),
        "claims": [evaluate_claim(c, measures) for c in study.claims],
        "measures": measures,
        "figures": [str(p) for p in study_figures(study, runs, scenes, directory, measures)],
    }
    _write_json(summary, directory / "summary.json")
    return summary


def _measures(study: Study, runs: dict, scenes: dict, cases: dict) -> dict:
    """Every number a claim or a paper value of the study asks for."""
    # "peak": over the first PEAK_PERIODS recorded cycles (as in a paper plot; for the paper's
    # values); "peak_record": over the whole record (for the claims: less sampling noise)
    m: dict = {"peak": {}, "peak_record": {}, "strobe_spread": {}, "seconds_per_cycle": {}}
    entries = study.claims + study.paper_values
    for case, ds in runs.items():
        if scenes[case].sweep:
            continue
        m["seconds_per_cycle"][case] = {"": cases[case]["seconds_per_cycle"]}
        for entry in entries:
            var = entry.get("var")
            if var is None or var not in ds:
                continue
            where = entry.get("select", {})
            key = _key(entry)
            da = select(ds, var, where)
            m["peak"].setdefault(case, {})[key] = peak(da, PEAK_PERIODS, ds)
            m["peak_record"].setdefault(case, {})[key] = peak(da)
            if "joint" in where and var.startswith("clearance_") and where["joint"] in ds.joint:
                m["strobe_spread"].setdefault(case, {})[key] = strobe_spread(
                    ds, scenes[case], var, where
                )
    kinds = {f["kind"] for f in study.figures}
    if kinds & {"phase", "poincare", "lle"}:
        case = next(iter(runs))
        m.update(_chaos_measures(runs[case], scenes[case]))
    if "bifurcation" in kinds:
        case = next(iter(runs))
        m["bifurcation_spread"] = _bifurcation_spread(runs[case], scenes[case])
    return m


def _chaos_measures(ds: xr.Dataset, scene) -> dict:
    """Wolf LLE (1/s) of x1, y1, x2, y2 with its automatic choices, the 0-1 test K of their
    stroboscopic samples, and the LLE from the equations (Benettin) of the same scene."""
    from workbench import analysis

    out: dict = {"wolf_lle": {}, "wolf_lle_per_period": {}, "wolf_choices": {}, "zero_one_K": {}}
    for label, (var, where) in CLEARANCE_COORDINATES.items():
        da = select(ds, var, where)
        if not np.isfinite(da.values).any():
            continue
        w = analysis.wolf_lle(da, period=ds.attrs.get("forcing_period"))
        out["wolf_lle"][label] = float(w["lle"])
        if "lle_per_period" in w:
            out["wolf_lle_per_period"][label] = float(w["lle_per_period"])
        out["wolf_choices"][label] = {
            k: float(w[k]) for k in ("delay", "dim", "evolve", "theiler") if k in w
        }
        z = analysis.zero_one_test(strobe(ds, da))
        out["zero_one_K"][label] = float(z["K"])
    horizon = min(10, int(scene.run["cycles"]))
    bench = analysis.lle_from_equations(scene, cycles=horizon)
    out["lle_from_equations"] = float(bench["lle"])
    out["lle_from_equations_cycles"] = horizon
    return out


def _bifurcation_spread(ds: xr.Dataset, scene) -> dict:
    """Per parameter value: the mean over x1, y1, x2, y2 of the stroboscopic spread, in units of
    the clearance (the swept clearance where the sweep is over the clearance)."""
    (param,) = list(scene.sweep)
    values = [float(v) for v in ds[param].values]
    spreads = []
    for v in values:
        point = ds.sel({param: v})
        c = v if param == "clearance" else None
        acc = []
        for var, where in CLEARANCE_COORDINATES.values():
            da = select(point, var, where)
            cj = c if c is not None else _clearance(scene, where["joint"])
            acc.append(float(np.nanstd(da.values)) / cj)
        spreads.append(float(np.nanmean(acc)))
    return {"parameter": param, "values": values, "spread": spreads}


def _clearance(scene, joint: str) -> float:
    from workbench.study._measure import clearance_of

    return clearance_of(scene, joint)


def _paper_values(study: Study, runs: dict, measures: dict) -> list[dict]:
    rows = []
    for entry in study.paper_values:
        stat = entry.get("statistic", "peak")
        key = _key(entry)
        if stat == "wolf_lle":
            label = next(
                (
                    k
                    for k, (v, w) in CLEARANCE_COORDINATES.items()
                    if _key({"var": v, "select": w}) == key
                ),
                key,
            )
            ours = measures.get("wolf_lle", {}).get(label)
            units = "1/s"
        else:
            ours = measures["peak"].get(entry["case"], {}).get(key)
            units = runs[entry["case"]][entry["var"]].attrs.get("units", "")
        paper = float(entry["value"])
        ratio = abs(ours) / abs(paper) if ours is not None and math.isfinite(ours) else None
        rows.append(
            {
                "case": entry["case"],
                "quantity": key,
                "statistic": stat,
                "units": units,
                "paper": paper,
                "ours": ours,
                "ratio_of_magnitudes": ratio,
            }
        )
    return rows


def _write_json(data: dict, path: Path) -> None:
    write_text_atomic(path, json.dumps(data, indent=1, default=_plain))


def _plain(x):
    if isinstance(x, np.generic):
        return x.item()
    raise TypeError(f"not JSON serialisable: {x!r}")
