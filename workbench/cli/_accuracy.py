"""``workbench accuracy``: the work-precision study of a scene from the command line."""

from __future__ import annotations

import argparse

from workbench.cli._console import (
    add_quiet,
    check_store_output,
    compile_kernel,
    float_list,
    output_and_figure,
    positive_float,
    report_failures,
    save_with_figure,
)
from workbench.cli._exit_codes import worst_exit_code


def _cmd_accuracy(args: argparse.Namespace) -> int:
    from workbench.plot import work_precision_figure
    from workbench.precision import DEFAULT_METHODS, DEFAULT_TOLERANCES, accuracy, recommend
    from workbench.scene import load_scene

    scene = load_scene(args.scene)
    methods = [m.strip() for m in args.methods.split(",")] if args.methods else DEFAULT_METHODS
    tolerances = args.tolerances or DEFAULT_TOLERANCES
    out, figure = output_and_figure(args.output, args.overwrite)
    check_store_output(out, ".runs")
    store = out.with_name(out.name + ".runs")
    compile_kernel(scene, quiet=args.quiet)
    try:
        wp = accuracy(
            scene,
            methods=methods,
            tolerances=tolerances,
            progress=not args.quiet,
            store=store,
            restart=args.restart,
        )
    except KeyboardInterrupt as exc:
        exc.add_note(
            f"the finished runs are kept in '{store}/': run the same command again to resume"
        )
        raise
    save_with_figure(
        wp, out, figure, "work-precision study", work_precision_figure, overwrite=args.overwrite
    )
    try:
        r = recommend(wp, args.target)
        print(
            f"recommended for errors < {args.target:g}: method {r.method}, rtol = atol = "
            f"{r.rtol:.0e} ({r.wall_time:.3g} s; short-horizon error "
            f"{r.errors['short_error']:.2e}, peak error {r.errors['peak_error']:.2e}; reference "
            f"error {wp.attrs['reference_error']:.2e})"
        )
    except ValueError as exc:
        print(f"no recommendation: {exc}")
    flags = wp.status.values
    code = worst_exit_code(flags)
    if code:
        failed = [
            f"{m} {r:g} ({wp.failure.sel(solver_method=m, rtol=r).item()[:80]})"
            for m in wp.solver_method.values
            for r in wp.rtol.values
            if int(wp.status.sel(solver_method=m, rtol=r)) > 1
        ]
        report_failures(
            "accuracy",
            f"{len(failed)} of {flags.size} settings failed: "
            f"{'; '.join(failed[:4])}{' ...' if len(failed) > 4 else ''}",
            code,
        )
    return code


def register_cli(sub) -> None:
    p = sub.add_parser(
        "accuracy",
        help="work-precision study of a scene (error vs cost per method and tolerance)",
        description="Run a scene with several methods and tolerances against a reference 100x "
        "tighter; store errors and costs as netCDF, draw the work-precision diagram, recommend "
        "the cheapest setting under a target error (never one at the reference's own limit). "
        "Finished runs are kept in OUTPUT.runs/ until the study is complete: running the same "
        "command again after an interruption resumes it.",
    )
    p.add_argument("scene", help="scene file (TOML)")
    p.add_argument("-o", "--output", required=True, help="netCDF file (the figure goes beside it)")
    p.add_argument(
        "--methods",
        # workbench.precision's DEFAULT_METHODS (tests/package/test_public_surfaces.py), not
        # imported
        # here: `workbench --help` loads no numerical library
        help="comma-separated methods (default: dop853,dopri5,scipy:DOP853,scipy:Radau,"
        "scipy:LSODA)",
    )
    p.add_argument(
        "--tolerances",
        type=float_list,
        help="comma-separated tolerances (default 1e-3..1e-11)",
    )
    p.add_argument(
        "--target", type=positive_float, default=1e-3, help="error target (default 1e-3)"
    )
    p.add_argument(
        "--restart", action="store_true", help="discard the runs kept from an interrupted study"
    )
    p.add_argument(
        "--overwrite", action="store_true", help="replace an existing study and its figure"
    )
    add_quiet(p)
    p.set_defaults(func=_cmd_accuracy)
