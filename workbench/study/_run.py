"""Run a study of the paper: its cases as ensembles, their numbers, its claims and figures."""

from __future__ import annotations

import json
import os
import time as _time
from pathlib import Path

import numpy as np
import xarray as xr

from workbench._warnings import warnings_by_kind
from workbench.archive import save_run, write_text_atomic
from workbench.scene import Scene
from workbench.study._claims import evaluate_claim
from workbench.study._flutter import flutter
from workbench.study._measure import member_run, seconds_per_cycle
from workbench.study._numbers import measures as study_measures
from workbench.study._numbers import sweep_contact, sweep_summary
from workbench.study._paper import paper_values
from workbench.study._route import route
from workbench.study._spec import Study, load_study, quick_study
from workbench.study._stats import describe
from workbench.study._summary import summary_dataset

__all__ = ["ensemble_scene", "run_study"]


def ensemble_scene(scene: Scene, realisations: int, perturbation: float) -> Scene:
    """``scene`` as a campaign over ``realisation = 0 .. realisations - 1`` (after its own swept
    parameters, if any) with the initial-state perturbation ``perturbation`` (relative)."""
    sweep = {k: list(v) for k, v in scene.sweep.items()}
    sweep.setdefault("realisation", list(range(realisations)))
    return scene.replace(run=dict(scene.run, perturbation=perturbation), sweep=sweep)


@warnings_by_kind()  # one warning per kind (e.g. per friction law), with its count
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
        Much shorter runs and at most 4 realisations
        (:func:`workbench.study._spec.quick_study`), for smoke tests only.
    workers : int, optional
        Processes for the campaigns (default: all CPUs).
    progress : bool
        Progress bars (a campaign's names its case).

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

    Warns
    -----
    Warning
        What its runs warned about (e.g. a :class:`workbench.ModelWarning` where a friction law
        left its range), once per kind at the end, with the count.
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
        label = f"{study.name}/{case}" if progress else False  # names the case on its lines
        ds = run_campaign(escene, store, workers=workers, restart=True, progress=label)
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
    measures = study_measures(study, runs, members, scenes)
    sweeps = sweep_contact(study, runs)
    measures["sweep_contact"] = {c: sweep_summary(d) for c, d in sweeps.items()}
    claims = [evaluate_claim(c, measures) for c in study.claims]
    paper_rows = paper_values(study, measures)
    route_result = route(study, directory, quick, workers)
    figures = study_figures(study, runs, members, scenes, sweeps, directory, measures)
    if route_result is not None:
        from workbench.study._route_figures import route_figures

        figures += route_figures(study, route_result, directory)
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
        "flutter": flutter(study, quick),
        "route": route_result,
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


def _write_json(data: dict, path: Path) -> None:
    write_text_atomic(path, json.dumps(data, indent=1, default=_plain))


def _plain(x):
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    raise TypeError(f"not JSON serialisable: {x!r}")
