"""``workbench accuracy``: the work-precision study of a scene from the command line."""

from __future__ import annotations

import argparse
from pathlib import Path


def _cmd_accuracy(args: argparse.Namespace) -> int:
    from workbench.archive import save_run
    from workbench.plot import work_precision_figure
    from workbench.precision import DEFAULT_METHODS, DEFAULT_TOLERANCES, accuracy, recommend
    from workbench.scene import load_scene

    scene = load_scene(args.scene)
    methods = args.methods.split(",") if args.methods else list(DEFAULT_METHODS)
    tolerances = (
        [float(t) for t in args.tolerances.split(",")] if args.tolerances else DEFAULT_TOLERANCES
    )
    wp = accuracy(scene, methods=methods, tolerances=tolerances, progress=True)
    out = save_run(wp, args.output)
    print(f"work-precision study -> {out}")
    figure = Path(args.output).with_suffix(".png")
    fig = work_precision_figure(wp)
    fig.savefig(figure, dpi=120)
    print(f"figure: {figure}")
    try:
        r = recommend(wp, args.target)
        print(
            f"recommended for errors < {args.target:g}: method {r.method}, rtol = atol = "
            f"{r.rtol:.0e} ({r.wall_time:.3g} s; short-horizon error "
            f"{r.errors['short_error']:.2e}, peak error {r.errors['peak_error']:.2e})"
        )
    except ValueError as exc:
        print(f"no recommendation: {exc}")
    return 0


def register_cli(sub) -> None:
    p = sub.add_parser(
        "accuracy",
        help="work-precision study of a scene (error vs cost per method and tolerance)",
        description="Run a scene with several methods and tolerances against a tight reference; "
        "store errors and costs as netCDF, draw the work-precision diagram, recommend the "
        "cheapest setting under a target error.",
    )
    p.add_argument("scene", help="scene file (TOML)")
    p.add_argument("-o", "--output", required=True, help="netCDF file (the figure goes beside it)")
    p.add_argument("--methods", help="comma-separated methods (default: all)")
    p.add_argument("--tolerances", help="comma-separated tolerances (default 1e-3..1e-11)")
    p.add_argument("--target", type=float, default=1e-3, help="error target (default 1e-3)")
    p.set_defaults(func=_cmd_accuracy)
