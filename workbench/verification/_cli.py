"""``workbench verify``: compare a scene with exudyn from the command line."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def _cmd_verify(args: argparse.Namespace) -> int:
    from workbench import load_scene, save_run
    from workbench.plot import verification_figure
    from workbench.verification import STATISTICS, verify

    scene = load_scene(args.scene)
    steps = [float(h) for h in args.steps.split(",")]
    try:
        ds = verify(scene, horizon=args.horizon, steps=steps, record_dt=args.record_dt)
    except (ValueError, RuntimeError, ImportError) as exc:
        print(f"workbench verify: error: {exc}", file=sys.stderr)
        return 2
    out = save_run(ds, args.output)
    print(f"verification -> {out}")
    figure = Path(args.output).with_suffix(".png")
    verification_figure(ds).savefig(figure, dpi=120)
    print(f"figure: {figure}")
    print(ds.max_relative_error.to_pandas().T.to_string(float_format="{:.3g}".format))
    if "joint" in ds.dims:
        for name in ("first_impact_time", "first_impact_force", *STATISTICS):
            print(f"\n{name} [{ds[name].attrs['units']}]")
            print(ds[name].to_pandas().to_string(float_format="{:.6g}".format))
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
    p.add_argument("--horizon", type=float, help="simulated time from t = 0, s (default 1 cycle)")
    p.add_argument(
        "--steps",
        default="4e-6,2e-6,1e-6",
        help="exudyn's fixed steps, s, comma-separated (default 4e-6,2e-6,1e-6)",
    )
    p.add_argument("--record-dt", type=float, help="record interval, s (default: coarsest step)")
    p.set_defaults(func=_cmd_verify)
