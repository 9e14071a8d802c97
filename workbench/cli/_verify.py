"""``workbench verify``: compare a scene with exudyn from the command line."""

from __future__ import annotations

import argparse
from functools import partial

from workbench.cli._console import (
    add_quiet,
    compile_kernel,
    float_list,
    output_and_figure,
    positive_float,
    save_with_figure,
)
from workbench.cli._exit_codes import UsageError


def _frame(ds, names: list[str], drop_reference: bool = False):
    """The variables ``names`` (dims run, and joint or series) side by side, one row per run,
    columns ``name joint``; None when nothing in them is finite (no empty tables)."""
    import numpy as np
    import pandas as pd

    parts = []
    for name in names:
        if name not in ds:
            continue
        da = ds[name]
        if drop_reference:
            da = da.sel(run=[r for r in da.run.values if r != "workbench"])
        if da.size == 0 or not np.isfinite(da.values).any():
            continue
        frame = da.to_pandas()
        if len(names) > 1:
            frame.columns = [f"{name} {c}" for c in frame.columns]
        parts.append(frame)
    if not parts:
        return None
    table = pd.concat(parts, axis=1)
    table.index.name = None
    table.columns.name = None
    return table


def _print_tables(ds) -> None:
    """One header line per table, saying what its numbers are."""
    from workbench.verification import STATISTICS

    tables = [
        (
            "largest difference from the workbench over the horizon, divided by the workbench's "
            "largest magnitude [1], per series (exudyn at each step):",
            _frame(ds, ["max_relative_error"], drop_reference=True),
        ),
        (
            "first contact per joint: its time [s] and the peak normal force of that contact [N]:",
            _frame(ds, ["first_impact_time", "first_impact_force"]),
        ),
        (
            "over the horizon, per joint: "
            + ", ".join(f"{name} = {long} [{units}]" for name, (units, long) in STATISTICS.items())
            + ":",
            _frame(ds, list(STATISTICS)),
        ),
    ]
    for header, table in tables:
        if table is None:
            continue
        print(f"\n{header}")
        print(table.to_string(float_format="{:.6g}".format))


def _progress(steps: list[float]):
    """Progress over the runs of :func:`workbench.verification.verify` (the workbench's, then
    exudyn's at each step), its time left from exudyn's runs weighted by their steps (1/h;
    the workbench's run, first, is not counted)."""
    from workbench._progress import Progress, TimeLeft

    left = TimeLeft({h: ("exudyn", 1.0 / h) for h in steps})
    return Progress(1 + len(steps), desc="verify", unit="run", time_left=left)


def _ended(bar, step: float | None, label: str, wall_time: float) -> None:
    """A run of verify ended: the progress moves on and says so in a line."""
    bar.update(1, job=step)
    bar.write(f"{label}: {wall_time:.3g} s")


def _cmd_verify(args: argparse.Namespace) -> int:
    from workbench.plot import verification_figure
    from workbench.scene import load_scene
    from workbench.verification import verify

    scene = load_scene(args.scene)
    out, figure = output_and_figure(args.output, args.overwrite)
    compile_kernel(scene, quiet=args.quiet)  # the workbench's run, announced
    bar = None if args.quiet else _progress(args.steps)
    try:
        ds = verify(
            scene,
            horizon=args.horizon,
            steps=args.steps,
            record_dt=args.record_dt,
            on_run=None if bar is None else partial(_ended, bar),
        )
    except (ValueError, RuntimeError, ImportError) as exc:
        raise UsageError(str(exc)) from None
    finally:
        if bar is not None:
            bar.close()
    save_with_figure(ds, out, figure, "verification", verification_figure, overwrite=args.overwrite)
    _print_tables(ds)
    print(
        "\nwall time [s]: "
        + ", ".join(f"{r} {w:.3g}" for r, w in zip(ds.run.values, ds.wall_time.values, strict=True))
    )
    return 0


def register_cli(sub) -> None:
    p = sub.add_parser(
        "verify",
        help="compare a scene with the exudyn multibody engine (extra 'verify')",
        description="Run a mechanism scene (ninebar, slider_crank) in the workbench and in "
        "exudyn (fixed-step generalised-alpha at several steps) and compare torques, slider "
        "kinematics, first impacts and chaos-robust statistics; write the comparison as netCDF "
        "and an overlay figure beside it.",
    )
    p.add_argument("scene", help="scene file (TOML), model 'ninebar' or 'slider_crank'")
    p.add_argument("-o", "--output", required=True, help="netCDF file (the figure goes beside it)")
    p.add_argument(
        "--horizon", type=positive_float, help="simulated time from t = 0, s (default 1 cycle)"
    )
    p.add_argument(
        "--steps",
        type=float_list,
        default=[4e-6, 2e-6, 1e-6],
        help="exudyn's fixed steps, s, comma-separated (default 4e-6,2e-6,1e-6)",
    )
    p.add_argument(
        "--record-dt",
        type=positive_float,
        help="record interval, s, a whole multiple of every step (default: the coarsest step "
        "for a scene with clearance joints, else 1e-3)",
    )
    p.add_argument("--overwrite", action="store_true", help="replace existing output files")
    add_quiet(p)
    p.set_defaults(func=_cmd_verify)
