"""Command line: ``workbench run | plot | ...`` (``workbench --help`` lists every command).

Exit codes: :mod:`workbench._exit_codes` (0 ok, 2 invalid input, 3 max_steps, 4 step_underflow
or non_finite, 5 model_failure, 130 interrupted).
"""

from __future__ import annotations

import argparse
import importlib
import sys
from pathlib import Path

from workbench._exit_codes import exit_code


def _cmd_run(args: argparse.Namespace) -> int:
    from workbench.archive import save_run
    from workbench.run import run_status, simulate
    from workbench.scene import load_scene

    scene = load_scene(args.scene)
    ds = simulate(scene, progress=not args.quiet, throw=False)
    out = save_run(ds, args.output)
    a = ds.attrs
    status = run_status(ds)
    simulated = float(ds.time[-1]) if ds.sizes["time"] else float("nan")
    print(
        f"{scene.model}: simulated {simulated:.6g} s in {a['solver_wall_time']:.3g} s wall, "
        f"{a['solver_steps']} steps ({a['solver_rejected_steps']} rejected), "
        f"{a['solver_rhs_evaluations']} rhs evaluations, {a['solver_events']} events, "
        f"status {status.label} -> {out}"
    )
    if args.figures:
        from workbench.plot import run_figures

        for path in run_figures(ds, Path(args.figures)):
            print(f"figure: {path}")
    if status.failed:
        print(f"workbench run: {status.label}: {a['run_message']}", file=sys.stderr)
    return exit_code(status)


def _cmd_plot(args: argparse.Namespace) -> int:
    from workbench.archive import open_run
    from workbench.plot import run_figures

    ds = open_run(args.run)
    for path in run_figures(ds, Path(args.output)):
        print(f"figure: {path}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``workbench`` command."""
    parser = argparse.ArgumentParser(
        prog="workbench",
        description="Nonlinear dynamics of mechanisms with clearance joints: run scenes, "
        "campaigns and analyses; results are netCDF files and PNG figures.",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser(
        "run",
        help="simulate one scene and write a netCDF run",
        description="Simulate one scene (TOML) and write its run as netCDF.",
    )
    p.add_argument("scene", help="scene file (TOML)")
    p.add_argument("-o", "--output", required=True, help="netCDF file to write (atomically)")
    p.add_argument("--figures", metavar="DIR", help="also write the run's figures (PNG) here")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_run)

    p = sub.add_parser(
        "plot",
        help="figures (PNG) of a stored run",
        description="Write the standard figures of a stored run as PNG files.",
    )
    p.add_argument("run", help="netCDF run written by 'workbench run'")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="directory for the PNGs")
    p.set_defaults(func=_cmd_plot)
    for module in _COMMAND_MODULES:
        importlib.import_module(module).register_cli(sub)
    return parser


# Modules that add their own subcommands: each defines ``register_cli(subparsers)``.
_COMMAND_MODULES: tuple[str, ...] = (
    "workbench.precision._cli",
    "workbench.campaign._cli",
    "workbench.study._cli",
    "workbench.analysis._cli",
    "workbench.verification._cli",
)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``workbench`` console script; returns the exit code
    (:func:`workbench._exit_codes.exit_code`: 0 ok, 2 invalid input, 3-5 failed runs)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    from workbench.campaign import CampaignError
    from workbench.scene import SceneError
    from workbench.solver import SolverError

    try:
        return args.func(args)
    except (SceneError, SolverError, CampaignError, FileNotFoundError) as exc:
        print(f"workbench {args.command}: error: {exc}", file=sys.stderr)
        return exit_code(exc)
    except KeyboardInterrupt as exc:
        print(f"workbench {args.command}: interrupted", file=sys.stderr)
        return exit_code(exc)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
