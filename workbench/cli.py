"""Command line: ``workbench run | plot | ...`` (``workbench --help`` lists every command)."""

from __future__ import annotations

import argparse
import importlib
import sys
from pathlib import Path


def _cmd_run(args: argparse.Namespace) -> int:
    import workbench

    scene = workbench.load_scene(args.scene)
    ds = workbench.simulate(scene, progress=not args.quiet)
    out = workbench.save_run(ds, args.output)
    a = ds.attrs
    simulated = float(ds.time[-1])
    print(
        f"{scene.model}: simulated {simulated:.6g} s in {a['solver_wall_time']:.3g} s wall, "
        f"{a['solver_steps']} steps ({a['solver_rejected_steps']} rejected), "
        f"{a['solver_rhs_evaluations']} rhs evaluations, {a['solver_events']} events -> {out}"
    )
    if args.figures:
        from workbench.plot._runs import run_figures

        for path in run_figures(ds, Path(args.figures)):
            print(f"figure: {path}")
    return 0


def _cmd_plot(args: argparse.Namespace) -> int:
    import workbench
    from workbench.plot._runs import run_figures

    ds = workbench.open_run(args.run)
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
    "workbench._accuracy_cli",
    "workbench.campaign._cli",
    "workbench.study._cli",
    "workbench.analysis._cli",
    "workbench.verify._cli",
)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``workbench`` console script."""
    parser = build_parser()
    args = parser.parse_args(argv)
    from workbench import SceneError, SolverError

    try:
        return args.func(args)
    except (SceneError, SolverError, FileNotFoundError) as exc:
        print(f"workbench {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"workbench {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
