"""Work-precision study of the nine-bar mechanism: what each digit of accuracy costs.

The default scene (studies/ninebar.toml: clearances at A and B, 0.5 mm, omega = 2.5 pi, modified
Coulomb) and the same scene with LuGre friction, 1 transient + 2 recorded crank cycles, run with
the compiled DOP853, DOPRI5 and ARK548 (implicit-explicit: with LuGre the bristle states are
implicit; with Coulomb it runs its explicit table) and with scipy's DOP853, LSODA and Radau on the
same compiled right-hand side, each over its own range of tolerances (scipy's methods only where
they finish in reasonable time), against the compiled DOP853 at rtol = atol = 1e-11. Errors are
those of :func:`workbench.accuracy` (short-horizon trajectory error, peak error, event-count error,
stroboscopic statistic error). Prints a table with the cost ratio of each method to scipy's DOP853
at the same tolerance, checks that DOP853's error falls over >= 4 decades of tolerance and that its
cost grows sub-linearly in 1/tol, and prints the recommended tolerance for an error target of 1e-3
of each variable's range. Writes ``benchmarks/results/work_precision_*.nc`` and ``.png``.

Run: ``python benchmarks/work_precision.py [--quick]`` (``--quick``: compiled methods only).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import xarray as xr
from _results import recording  # benchmarks/_results.py: a JSON record per run

import workbench
from workbench import accuracy, recommend
from workbench.plot import work_precision_figure

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "studies" / "ninebar.toml"
RESULTS = Path(__file__).resolve().parent / "results"
REFERENCE = ("dop853", 1e-11)
TARGET = 1e-3
PLAN = {
    "dop853": [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10],
    "dopri5": [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9],
    "ark548": [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9],
    "scipy:DOP853": [1e-3, 1e-5, 1e-7],
    "scipy:LSODA": [1e-3, 1e-5],
    "scipy:Radau": [1e-3, 1e-4],
}


def study(friction: str, methods: list[str]) -> xr.Dataset:
    base = workbench.load_scene(SCENE)
    scene = base.replace(
        effects={
            **base.effects,
            "clearance": list(base.effects["clearance"]),
            "friction": friction,
        },
        run={"cycles": 2, "transient_cycles": 1},
        record={
            "samples_per_period": 200,
            "variables": ["clearance_x", "clearance_y", "contact_force", "torque"],
        },
    )
    parts = [
        accuracy(scene, methods=[m], tolerances=PLAN[m], reference=REFERENCE, progress=True)
        for m in methods
    ]
    wp = xr.concat(parts, dim="solver_method", join="outer", combine_attrs="override")
    wp.attrs["scene_friction"] = friction
    return wp


def report(wp: xr.Dataset, friction: str) -> None:
    print(
        f"\n== {friction}: reference {REFERENCE[0]} at {REFERENCE[1]:.0e}; short horizon "
        f"{wp.attrs['short_horizon'] * 1e3:.1f} ms, over which the reference and its twin at "
        f"{wp.attrs['reference_twin_tolerance']:.0e} differ by {wp.attrs['reference_error']:.1e} "
        "(errors below that are not resolved) =="
    )
    print(
        f"{'method':>14} {'tol':>7} {'wall s':>8} {'steps':>8} {'short err':>10} "
        f"{'peak err':>9} {'x scipy':>8}"
    )
    has_scipy = "scipy:DOP853" in wp.solver_method.values
    for m in wp.solver_method.values:
        for tol in wp.rtol.values:
            pt = wp.sel(solver_method=m, rtol=tol)
            if not np.isfinite(float(pt.wall_time)):
                continue
            ratio = ""
            if has_scipy:
                ref = float(wp.wall_time.sel(solver_method="scipy:DOP853", rtol=tol))
                if np.isfinite(ref):
                    ratio = f"{ref / float(pt.wall_time):8.1f}"
            print(
                f"{m:>14} {tol:7.0e} {float(pt.wall_time):8.3f} {int(pt.steps):8d} "
                f"{float(pt.short_error):10.2e} {float(pt.peak_error):9.2e} {ratio:>8}"
            )
    d = wp.sel(solver_method="dop853").dropna("rtol", subset=["wall_time"])
    err = d.short_error.values[::-1]  # tightening tolerance
    falls = int(np.sum(np.diff(np.log10(err)) < 0.3))  # within noise: no rise above 2x
    tol = d.rtol.values[::-1]
    slope = np.polyfit(np.log10(1 / tol), np.log10(d.wall_time.values[::-1]), 1)[0]
    print(
        f"dop853: error non-increasing (within 2x) in {falls} of {len(err) - 1} tightenings "
        f"over {np.log10(tol[0] / tol[-1]):.0f} decades; cost ~ (1/tol)^{slope:.2f}"
    )
    try:
        r = recommend(wp, TARGET)
        print(
            f"recommended for errors < {TARGET:g}: {r.method} at rtol = atol = "
            f"{r.rtol:.0e}: {r.wall_time:.3f} s for 3 cycles, short error "
            f"{r.errors['short_error']:.2e}, peak error {r.errors['peak_error']:.2e}"
        )
    except ValueError as exc:
        print(f"no recommendation: {exc}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="compiled methods only")
    args = parser.parse_args()
    methods = ["dop853", "dopri5", "ark548"] if args.quick else list(PLAN)
    RESULTS.mkdir(exist_ok=True)
    for friction in ("coulomb", "lugre"):
        wp = study(friction, methods)
        workbench.save_run(wp, RESULTS / f"work_precision_{friction}.nc")
        fig = work_precision_figure(wp)
        fig.axes[0].set_title(
            f"nine-bar, {friction} friction, 3 crank cycles: short-horizon error vs cost\n"
            f"(reference {REFERENCE[0]} at {REFERENCE[1]:.0e})",
            fontsize=9,
        )
        fig.savefig(RESULTS / f"work_precision_{friction}.png", dpi=120)
        report(wp, friction)
    print(f"\nresults in {RESULTS}")


if __name__ == "__main__":
    with recording(__file__):
        main()
