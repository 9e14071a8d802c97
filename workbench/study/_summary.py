"""The dataset a study returns (``summary.nc``): its numbers, the paper's values, the sweeps'
contact statistics and the claims' verdicts, with units on every variable."""

from __future__ import annotations

import math
import re

import numpy as np
import xarray as xr

from workbench._attributes import variable
from workbench.run import REALISATION_ATTRS
from workbench.scene import Scene
from workbench.study._measure import PEAK_PERIODS
from workbench.study._spec import Study

__all__ = ["summary_dataset"]


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
        "member": ("member", names, variable("case or view of the study")),
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
                # by hand: a measure's units may be unknown (""), which variable() refuses
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
    law = measures.get("friction_law", {})
    for key, units, long_name in (
        ("mu_max", "1", "largest friction coefficient |F_t| / F_n at the records"),
        ("mu_median", "1", "median friction coefficient |F_t| / F_n at the records in contact"),
        ("above", "s", "time per crank cycle with |F_t| / F_n above mu_s (LuGre)"),
        ("beyond", "s", "time per crank cycle with |F_t| / F_n beyond 2 mu_s + s2 |v_t| (LuGre)"),
    ):
        if not law:
            break
        arr = np.full((len(names), n_real), np.nan)
        for i, name in enumerate(names):
            values = law.get(name, {}).get(key)
            if values is not None:
                arr[i, : len(values)] = values
        data[f"friction_law_{key}"] = (
            ("member", "realisation"),
            arr,
            variable(long_name, units),
        )
    for row in paper_rows:
        if row["statistic"] != "peak":
            continue
        var = f"paper_{_slug(row['quantity'])}"
        if var not in data:
            data[var] = (
                ("member",),
                np.full(len(names), np.nan),
                # by hand: units may be unknown (""), which variable() refuses
                {"units": row["units"], "long_name": f"the paper's peak of {row['quantity']}"},
            )
        data[var][1][names.index(row["case"])] = row["paper"]
    if measures.get("wolf_lle"):
        labels = list(measures["wolf_lle"])
        coords["coordinate"] = (
            "coordinate",
            labels,
            variable("clearance coordinate (x1, y1: joint A; x2, y2: joint B)"),
        )
        for field, u, long_name in (
            ("wolf_lle", "s-1", "largest Lyapunov exponent (Wolf et al. 1985)"),
            ("zero_one_K", "1", "0-1 test for chaos K of the stroboscopic samples"),
        ):
            arr = np.full((len(labels), n_real), np.nan)
            for i, k in enumerate(labels):
                arr[i, : len(measures[field][k])] = measures[field][k]
            data[field] = (("coordinate", "realisation"), arr, variable(long_name, u))
    exponents = measures.get("exponents")
    if exponents:
        coords["method"] = ("method", exponents["method"], variable("estimator"))
        for field, units, long_name in (
            ("lle", "s-1", "largest Lyapunov exponent of realisation 0 by each method"),
            ("lle_per_cycle", "1", "the same per crank cycle"),
            ("stderr", "s-1", "standard error of the finite window"),
        ):
            values = np.array([np.nan if v is None else v for v in exponents[field]], float)
            data[f"exponent_{field}"] = ("method", values, variable(long_name, units))
        data["exponent_trusted"] = (
            "method",
            np.array(exponents["trusted"], bool),
            variable("converged (equations) or reliable (Wolf)"),
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
                variable(long_name),
            )
    ds = xr.Dataset(data, coords=coords)
    if sweeps:
        stacked = xr.concat(
            [d.expand_dims(sweep_case=[c]) for c, d in sweeps.items()], "sweep_case", join="outer"
        )
        stacked["sweep_case"].attrs.update(variable("case of the parameter sweep"))
        stacked = stacked.assign_coords(
            realisation=ds["realisation"][: stacked.sizes["realisation"]]
        )
        ds = xr.merge([ds, stacked], combine_attrs="drop_conflicts")
    if claims:
        ds = ds.assign_coords(claim=("claim", np.arange(len(claims)), variable("claim")))
        for field in ("text", "verdict", "evidence", "reason"):
            ds[f"claim_{field}"] = (
                "claim",
                np.array([c.get(field, "") for c in claims], dtype=object),
                variable(f"{field} of the paper's claim"),
            )
        ds["claim_p_value"] = (
            "claim",
            np.array([c.get("p_value", math.nan) for c in claims], float),
            variable("p-value of the claim's rank test"),
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
    from workbench.campaign._grid import parameter_attrs

    return parameter_attrs(scene, name)
