"""How a chaos map's exponents agree with another map's at the points the two share: the map's
own precision (the fast protocol) against the fully checked exponents of an older map.

At every point of ``REFERENCE`` that ``MAP`` also has (the same parameter values, to 1e-9
relative), per point: both exponents (s-1) with their errors, whether they agree (within 10 %
of the reference or two combined standard errors; a reference without an error, e.g. an upper
bound, within 10 % or below it when it is a bound) and whether the verdict is the same
(chaotic where the exponent is positive). Prints the points that disagree and the fractions;
records them.

Run: ``python benchmarks/chaos_map_agreement.py REFERENCE MAP`` (e.g. the 11 x 5 map of
``git show 5d2be48:data/omega_clearance_map.nc`` against a 41 x 21 map of the same scene;
records in ``benchmarks/records/chaos_map_agreement/``).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
from _results import record, recording  # benchmarks/_results.py: a JSON record per run

import workbench

#: agreement: within this fraction of the reference, or two combined standard errors
RELATIVE = 0.1
ERRORS = 2.0


def agree(ref: float, ref_err: float, ref_bound: bool, new: float, new_err: float) -> bool:
    """Whether ``new`` (s-1, error ``new_err``) agrees with ``ref`` (a bound where
    ``ref_bound``: ``new`` may lie below it)."""
    if ref_bound and new <= ref * (1 - RELATIVE * math.copysign(1.0, ref)):
        return True
    if abs(new - ref) <= RELATIVE * abs(ref):
        return True
    combined = math.hypot(0.0 if math.isnan(ref_err) else ref_err, new_err)
    return bool(np.isfinite(combined) and abs(new - ref) <= ERRORS * combined)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("reference", help="the older map (netCDF)")
    ap.add_argument("map", help="the map to check (netCDF)")
    args = ap.parse_args()
    ref, new = workbench.open_run(args.reference), workbench.open_run(args.map)
    dims = ref.attrs["campaign_dims"].split()
    rows = []
    for idx in np.ndindex(*(ref.sizes[d] for d in dims)):
        at = {d: float(ref[d].values[i]) for d, i in zip(dims, idx, strict=True)}
        sel = {}
        for d, v in at.items():
            j = int(np.argmin(np.abs(new[d].values - v)))
            if abs(float(new[d].values[j]) - v) > 1e-9 * abs(v):
                break
            sel[d] = j
        else:
            r, n = ref.isel(dict(zip(dims, idx, strict=True))), new.isel(sel)
            row = {
                **at,
                "lle_reference": float(r.lle), "stderr_reference": float(r.lle_stderr),
                "bound_reference": int(r.lle_status) == 2,
                "lle": float(n.lle), "stderr": float(n.lle_stderr),
                "period_reference": int(r.strobe_period), "period": int(n.strobe_period),
            }  # fmt: skip
            row["agree"] = agree(
                row["lle_reference"], row["stderr_reference"], row["bound_reference"],
                row["lle"], row["stderr"],
            )  # fmt: skip
            row["same_verdict"] = (row["lle_reference"] > 0) == (row["lle"] > 0)
            rows.append(row)
    shared = len(rows)
    agreeing = sum(r["agree"] for r in rows)
    same = sum(r["same_verdict"] for r in rows)
    for r in rows:
        if not (r["agree"] and r["same_verdict"]):
            where = ", ".join(f"{d} {r[d]:.6g}" for d in dims)
            print(
                f"{where}: {r['lle']:.4g} +- {r['stderr']:.2g} 1/s against "
                f"{'<= ' if r['bound_reference'] else ''}{r['lle_reference']:.4g} +- "
                f"{r['stderr_reference']:.2g} (periods {r['period']} / {r['period_reference']})"
            )
    print(
        f"{shared} shared points: {agreeing} agree ({agreeing / max(shared, 1):.0%}; within "
        f"{RELATIVE:.0%} or {ERRORS:g} combined errors), {same} with the same verdict "
        f"({same / max(shared, 1):.0%})"
    )
    record(
        {
            "reference": Path(args.reference).name, "map": Path(args.map).name,
            "shared": shared, "agreeing": agreeing, "same_verdict": same, "rows": rows,
        }
    )  # fmt: skip


if __name__ == "__main__":
    with recording(__file__):
        main()
