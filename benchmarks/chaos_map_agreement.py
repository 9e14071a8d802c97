"""How a chaos map's exponents agree with another map's at the points the two share: the map's
own precision (the fast protocol) against the fully checked exponents of an older map.

At every point of ``REFERENCE`` that ``MAP`` also has (the same parameter values, to 1e-9
relative), per point: both exponents (s-1) with their errors, whether they agree (within 10 %
of the reference or two combined standard errors; a reference without an error, e.g. an upper
bound, within 10 % or below it when it is a bound) and whether the verdict is the same
(chaotic where the exponent is positive). Prints the points that disagree and the fractions;
records them.

With ``--same-orbit``, at every shared point where either map's strobe is periodic: the
point's run again (the map's scene), its indicators with the full protocol as
:func:`workbench.continuation.chaos_indicators` runs it now (Newton from where the run ended:
the fast value's own orbit), and the full protocol's Floquet exponent from the state integrated
again from the scene's start (the way the full protocol found its orbit before), with the
onset velocities each orbit holds. A periodic orbit of the nine-bar under Lankarani-Nikravesh
contact is one of a family (each lasting contact holds the velocity it began with), so the
two orbits can have the same state at the strobe and other held values and exponents: the
fast values are compared with the full protocol on the same orbit, and with the reference,
and the differences of the held values are printed.

Run: ``python benchmarks/chaos_map_agreement.py REFERENCE MAP [--same-orbit] [--workers N]``
(e.g. the 11 x 5 map of ``git show 5d2be48:data/omega_clearance_map.nc`` against a 41 x 21 map
of the same scene; records in ``benchmarks/records/chaos_map_agreement/``).
"""

from __future__ import annotations

import argparse
import concurrent.futures
import math
import time
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


def same_orbit(scene_toml: str, at: dict) -> dict:
    """At one point of a map's scene: the fast exponent and the full protocol's from where the
    run ended (:func:`workbench.continuation.chaos_indicators`), and the full protocol's Floquet
    exponent from the state integrated again, with the held values of both orbits."""
    from workbench.continuation import chaos_indicators, point_exponent
    from workbench.continuation._indicators import lle_cycles

    t0 = time.process_time()
    scene = workbench.scene_from_toml(scene_toml).with_parameters(**at)
    run = workbench.simulate(scene)
    ind = chaos_indicators(scene, run, full_protocol=True)
    period = int(ind.strobe_period)
    held_end = [float(a) for a in np.atleast_1d(run.attrs.get("end_discrete_state", []))]
    out = {
        "period_now": period, "lle_fast": float(ind.lle), "stderr_fast": float(ind.lle_stderr),
        "lle_full_same_orbit": float(ind.lle_full),
        "stderr_full_same_orbit": float(ind.lle_full_stderr), "held_run_end": held_end,
    }  # fmt: skip
    if period >= 1:
        again = point_exponent(
            scene, period=period, cycles=lle_cycles(scene),
            start_cycles=scene.run["transient_cycles"] + scene.run["cycles"],
        )  # fmt: skip
        out |= {
            "lle_full_again": again.value, "stderr_full_again": again.error,
            "method_again": again.method,
            "held_again": [] if again.orbit is None else [float(a) for a in again.orbit[1]],
        }  # fmt: skip
    out["cpu"] = time.process_time() - t0
    return out


def _held(values: list[float]) -> str:
    return "(" + ", ".join(f"{v * 1e3:.3g}" for v in values) + ") mm/s"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("reference", help="the older map (netCDF)")
    ap.add_argument("map", help="the map to check (netCDF)")
    ap.add_argument(
        "--same-orbit", action="store_true",
        help="recompute the periodic points: the full protocol on the fast value's orbit",
    )  # fmt: skip
    ap.add_argument("--workers", type=int, default=2, help="processes for --same-orbit")
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
    figures = {
        "reference": Path(args.reference).name, "map": Path(args.map).name,
        "shared": shared, "agreeing": agreeing, "same_verdict": same, "rows": rows,
    }  # fmt: skip
    if args.same_orbit:
        figures |= _same_orbit_check(new.attrs["scene"], dims, rows, args.workers)
    record(figures)


def _same_orbit_check(scene_toml: str, dims: list[str], rows: list[dict], workers: int) -> dict:
    """:func:`same_orbit` at the rows where either strobe is periodic (in parallel); prints and
    returns the fractions: fast against the full protocol on the same orbit, against the one
    integrated again, and the rows whose two orbits hold other onset velocities."""
    periodic = [r for r in rows if r["period"] >= 1 or r["period_reference"] >= 1]
    with concurrent.futures.ProcessPoolExecutor(workers) as pool:
        done = pool.map(same_orbit, [scene_toml] * len(periodic),
                        [{d: r[d] for d in dims} for r in periodic])  # fmt: skip
        for r, o in zip(periodic, done, strict=True):
            r.update(o)
    n = len(periodic)
    same_agree = again_agree = held_differ = held_differ_of_disagreeing = disagreeing = 0
    for r in periodic:
        r["agree_same_orbit"] = agree(
            r["lle_full_same_orbit"], r["stderr_full_same_orbit"], False, r["lle_fast"],
            r["stderr_fast"],
        )  # fmt: skip
        same_agree += r["agree_same_orbit"]
        if "lle_full_again" not in r:
            continue
        r["agree_again"] = agree(
            r["lle_full_again"], r["stderr_full_again"], False, r["lle_fast"], r["stderr_fast"]
        )
        a, b = np.array(r["held_run_end"]), np.array(r["held_again"])
        r["held_differ"] = bool(
            a.shape != b.shape or np.any(np.abs(a - b) > 0.01 * np.maximum(np.abs(a), 1e-12))
        )
        again_agree += r["agree_again"]
        held_differ += r["held_differ"]
        disagreeing += not r["agree_again"]
        held_differ_of_disagreeing += r["held_differ"] and not r["agree_again"]
        where = ", ".join(f"{d} {r[d]:.6g}" for d in dims)
        print(
            f"{where} (period {r['period_now']}): fast {r['lle_fast']:.4g} +- "
            f"{r['stderr_fast']:.2g} 1/s (the map's {r['lle']:.4g} +- {r['stderr']:.2g}); "
            f"full on its orbit {r['lle_full_same_orbit']:.4g} +- "
            f"{r['stderr_full_same_orbit']:.2g}; full integrated again "
            f"{r['lle_full_again']:.4g} +- {r['stderr_full_again']:.2g}; held "
            f"{_held(r['held_run_end'])} against {_held(r['held_again'])}; {r['cpu']:.0f} s CPU"
        )
    print(
        f"{n} periodic points: the fast exponent agrees with the full protocol on its own orbit "
        f"at {same_agree} ({same_agree / max(n, 1):.0%}), with the full protocol's orbit "
        f"integrated again at {again_agree}; the two orbits hold other onset velocities (by "
        f"more than 1 %) at {held_differ}, and at {held_differ_of_disagreeing} of the "
        f"{disagreeing} points where the exponents disagree"
    )
    return {
        "periodic": n, "agree_same_orbit": same_agree, "agree_again": again_agree,
        "held_differ": held_differ, "disagreeing_again": disagreeing,
        "held_differ_of_disagreeing": held_differ_of_disagreeing,
    }  # fmt: skip


if __name__ == "__main__":
    with recording(__file__):
        main()
