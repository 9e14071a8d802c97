"""Command line: ``workbench run | plot | ...`` (``workbench --help`` lists every command).

Exit codes: :mod:`workbench._exit_codes` (0 ok, 2 invalid input, 3 max_steps, 4 step_underflow
or non_finite, 5 model_failure, 130 interrupted).
"""

from __future__ import annotations

import argparse
import importlib
import sys
from pathlib import Path

from workbench._console import announce_compile, one_line_warnings
from workbench._exit_codes import UsageError, exit_code


def _check_outputs(scene, args: argparse.Namespace) -> None:
    """Refuse, before the run, outputs that cannot be written or exist (without --overwrite)."""
    from workbench.archive import check_output_directory, check_output_file
    from workbench.plot import run_figure_names

    check_output_file(args.output, "-o/--output", overwrite=args.overwrite)
    if args.figures:
        names = run_figure_names(scene.model, len(scene.variables))
        check_output_directory(args.figures, "--figures", names, overwrite=args.overwrite)


def _check_summary(attrs: dict) -> str:
    """The self-check of ``solver.check = true`` in words ('' when the run did not do one)."""
    if "solver_check_error" not in attrs:
        return ""
    parted = attrs["solver_check_divergence_time"]
    parted = "never part by 1 %" if parted == float("inf") else f"part by 1 % at {parted:.3g} s"
    return (
        f"; self-check (solver.check): error {attrs['solver_check_error']:.2g} of a range over "
        f"{attrs['solver_check_horizon']:.3g} s against rtol {attrs['solver_check_tolerance']:.0e}"
        f" (the two {parted})"
    )


def _cmd_run(args: argparse.Namespace) -> int:
    from workbench.archive import save_run
    from workbench.run import run_status, simulate
    from workbench.scene import SceneError, load_scene

    scene = load_scene(args.scene)
    if scene.sweep:
        raise SceneError(
            "sweep",
            f"the scene sweeps {list(scene.sweep)}; 'workbench run' runs one scene: run the "
            "sweep with 'workbench campaign SCENE -o OUT.nc', or remove the [sweep] table",
        )
    _check_outputs(scene, args)
    announce_compile(scene)
    ds = simulate(scene, progress=not args.quiet, throw=False)
    out = save_run(ds, args.output)
    a = ds.attrs
    status = run_status(ds)
    simulated = float(ds.time[-1]) if ds.sizes["time"] else float("nan")
    print(
        f"{scene.model}: simulated {simulated:.6g} s in {a['solver_wall_time']:.3g} s wall, "
        f"{a['solver_steps']} steps ({a['solver_rejected_steps']} rejected), "
        f"{a['solver_rhs_evaluations']} rhs evaluations, {a['solver_events']} events, "
        f"status {status.label}{_check_summary(a)} -> {out}"
    )
    if args.figures:
        from workbench.plot import run_figures

        for path in run_figures(ds, Path(args.figures)):
            print(f"figure: {path}")
    if status.failed:
        print(f"workbench run: {status.label}: {a['run_message']}", file=sys.stderr)
    return exit_code(status)


def _cmd_plot(args: argparse.Namespace) -> int:
    from workbench.archive import check_output_directory, open_run
    from workbench.plot import run_figure_names, run_figures

    ds = open_run(args.run)
    campaign = "campaign_dims" in ds.attrs
    series = [v for v in ds.data_vars if "time" in ds[v].dims]
    if not series:
        raise UsageError(
            f"{args.run!r} has no variables over time: it is not a run or a campaign archive "
            "(write one with 'workbench run' or 'workbench campaign')"
        )
    names = run_figure_names(ds.attrs.get("model"), len(series), campaign=campaign)
    check_output_directory(args.output, "-o/--output", names, overwrite=args.overwrite)
    for path in run_figures(ds, Path(args.output)):
        print(f"figure: {path}")
    return 0


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line (``workbench CMD: error: ...``, exit code
    2), without the usage block; ``--help`` shows the usage."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``workbench`` command."""
    parser = _Parser(
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
    p.add_argument("--overwrite", action="store_true", help="replace existing output files")
    p.set_defaults(func=_cmd_run)

    p = sub.add_parser(
        "plot",
        help="figures (PNG) of a stored run or campaign",
        description="Write the standard figures of a stored run as PNG files: its time series "
        "(up to 8 panels per figure) and the model's overview; of a campaign, every variable "
        "against the swept parameter.",
    )
    p.add_argument("run", help="netCDF run or campaign written by 'workbench run | campaign'")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="directory for the PNGs")
    p.add_argument("--overwrite", action="store_true", help="replace existing figures")
    p.set_defaults(func=_cmd_plot)
    for module in _COMMAND_MODULES:
        importlib.import_module(module).register_cli(sub)
    return parser


# Modules that add their own subcommands: each defines ``register_cli(subparsers)``.
_COMMAND_MODULES: tuple[str, ...] = (
    "workbench.precision._cli",
    "workbench.campaign._cli",
    "workbench.continuation._cli",
    "workbench.study._cli",
    "workbench.analysis._cli",
    "workbench.verification._cli",
)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``workbench`` console script; returns the exit code
    (:func:`workbench._exit_codes.exit_code`: 0 ok, 2 invalid input, 3-5 failed runs, 130
    interrupted). Expected errors (a scene, an argument, a file, a store) are one line on
    stderr that names what is wrong; warnings are one line each."""
    parser = build_parser()
    args = parser.parse_args(argv)
    from workbench.archive import ArchiveError
    from workbench.campaign import CampaignError
    from workbench.scene import SceneError
    from workbench.solver import SolverError

    try:
        with one_line_warnings(args.command):
            return args.func(args)
    except (SceneError, SolverError, CampaignError, ArchiveError, UsageError) as exc:
        print(f"workbench {args.command}: error: {exc}", file=sys.stderr)
        return exit_code(exc)
    except FileNotFoundError as exc:
        print(f"workbench {args.command}: error: no such file: {exc.filename!r}", file=sys.stderr)
        return exit_code(exc)
    except KeyboardInterrupt as exc:
        print(f"workbench {args.command}: interrupted", file=sys.stderr)
        return exit_code(exc)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
