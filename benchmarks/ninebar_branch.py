"""The nine-bar's period-1 branch to its end, timed (issue 38: "the nine-bar's branch to its end
within an hour of CPU").

Fig. 32's scene (c = 0.1 mm at A and B, c_f = 0.01, Lankarani-Nikravesh contact), continued in
omega by :func:`workbench.continuation.continue_orbit` at rtol 1e-10 (the settings of
``studies/periodic_end_branch.py``, whose ``branch`` runs each leg):

* ``lasting``: the lasting-contact orbit from ``--lasting-start`` (default 1 pi) to its
  lift-off grazing (near 1.843 pi for the REPORT's member; the stop 1.85 pi lies past it);
* ``impacting``: the 40-event impacting orbit from 1.86105 pi to its end, the border collision
  at 1.8611 pi (``data/periodic_end_branch.nc``).

Per leg: CPU and wall time, points, map evaluations, how far it reached, its labels and why
it ended; then the legs' CPU together against the target of one hour.

Run: ``python benchmarks/ninebar_branch.py [--legs lasting,impacting]`` (one core; records in
``benchmarks/records/ninebar_branch/``).
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import time
from pathlib import Path

from _results import record, recording  # benchmarks/_results.py: a JSON record per run

import workbench
from workbench.continuation import branch_bifurcations

ROOT = Path(__file__).resolve().parents[1]
#: the target: both legs within an hour of CPU
TARGET_CPU = 3600.0
#: omega / pi at the start and stop of each leg
LEGS = {"lasting": (1.0, 1.85), "impacting": (1.86105, 1.8612)}


def _study_branch():
    """``branch`` of studies/periodic_end_branch.py (a script, not a package module)."""
    spec = importlib.util.spec_from_file_location(
        "periodic_end_branch", ROOT / "studies" / "periodic_end_branch.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.branch


def leg(name: str, start: float, stop: float, output: Path | None = None) -> dict:
    """One leg: the branch from ``start`` to ``stop`` (omega / pi) and what it cost; the branch
    saved in ``output`` (a folder) as ``ninebar_branch_<name>.nc``."""
    branch = _study_branch()
    t0, w0 = time.process_time(), time.time()
    r = branch(start * math.pi, stop * math.pi)
    cpu, wall = time.process_time() - t0, time.time() - w0
    if output is not None:
        workbench.save_run(r, output / f"ninebar_branch_{name}.nc", overwrite=True)
    labels = [
        {"type": b["type"], "omega_pi": b["value"] / math.pi}
        for b in branch_bifurcations(r, "omega")
    ]  # fmt: skip
    omega = r.omega.values / math.pi
    return {
        "leg": name, "start_pi": start, "stop_pi": stop, "cpu": cpu, "wall": wall,
        "points": int(r.sizes["point"]), "map_evaluations": int(r.attrs["map_evaluations"]),
        "reached_pi": float(omega.max()), "labels": labels, "ended": str(r.attrs["branch_ended"]),
    }  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--legs", default="lasting,impacting", help="comma-separated, of " + str(list(LEGS))
    )
    ap.add_argument("--lasting-start", type=float, default=LEGS["lasting"][0], help="omega / pi")
    ap.add_argument("-o", "--output", type=Path, help="a folder for the legs' branches (netCDF)")
    args = ap.parse_args()
    legs = dict(LEGS, lasting=(args.lasting_start, LEGS["lasting"][1]))
    rows = []
    for name in args.legs.split(","):
        row = leg(name, *legs[name], output=args.output)
        rows.append(row)
        shown = "; ".join(f"{b['type']} at {b['omega_pi']:.7f} pi" for b in row["labels"]) or "none"
        print(
            f"{name}: {row['start_pi']:g} pi -> reached {row['reached_pi']:.7f} pi (stop "
            f"{row['stop_pi']:g} pi); {row['points']} points, {row['map_evaluations']} map "
            f"evaluations; {row['cpu']:.0f} s CPU, {row['wall']:.0f} s wall; labels: {shown}; "
            f"ended: {row['ended'][:200]}"
        )
    total = sum(r["cpu"] for r in rows)
    print(
        f"the legs together: {total:.0f} s CPU, {total / TARGET_CPU:.2f} of the target "
        f"({TARGET_CPU:.0f} s)"
    )
    record({"legs": rows, "cpu": total, "target_cpu": TARGET_CPU})


if __name__ == "__main__":
    with recording(__file__):
        main()
