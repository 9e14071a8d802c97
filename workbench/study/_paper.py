"""The paper's values beside ours: per value the range of our ensemble, whether the paper's
number lies in it, and where it does not, the report's known cause."""

from __future__ import annotations

import numpy as np

from workbench.study._claims import _key
from workbench.study._measure import CLEARANCE_COORDINATES
from workbench.study._spec import Study
from workbench.study._stats import describe

__all__ = ["paper_values"]


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


def paper_values(study: Study, measures: dict) -> list[dict]:
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
