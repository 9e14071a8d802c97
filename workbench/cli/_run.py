"""``workbench run``: simulate one scene and write its netCDF run (and figures)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from workbench.cli._console import add_quiet, compile_kernel, max_memory_option, save_or_keep
from workbench.cli._exit_codes import exit_code

__all__ = ["register_cli"]


def _check_outputs(scene, args: argparse.Namespace) -> None:
    """Refuse, before the run, outputs that cannot be written or exist (without --overwrite)."""
    from workbench.archive import check_output_directory, check_output_file
    from workbench.plot import run_figure_names

    check_output_file(args.output, "-o/--output", overwrite=args.overwrite)
    if args.figures:
        from workbench.models import get_model

        forced = get_model(scene.model).forcing_period(scene.resolved_parameters) is not None
        strobe = forced and ("cycles" in scene.run or "samples_per_period" in scene.record)
        names = run_figure_names(scene.model, len(scene.variables), strobe=strobe)
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
    from workbench.models import get_model
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
    compiled = compile_kernel(scene, quiet=args.quiet)
    ds = simulate(scene, progress=not args.quiet, throw=False, max_memory=args.max_memory)
    out = save_or_keep(ds, args.output, overwrite=args.overwrite, what="run")
    a = ds.attrs
    status = run_status(ds)
    simulated = float(ds.time[-1]) if ds.sizes["time"] else float("nan")
    compile_note = "" if compiled is None else f" (after compiling the kernel in {compiled:.0f} s)"
    print(
        f"{scene.model}: simulated {simulated:.6g} s in {a['solver_wall_time']:.3g} s of "
        f"integration{compile_note}, "
        f"{a['solver_steps']} steps ({a['solver_rejected_steps']} rejected), "
        f"{a['solver_rhs_evaluations']} rhs evaluations, {a['solver_events']} events, "
        f"status {status.label}{_check_summary(a)}"
        f"{get_model(scene.model).summary(ds, scene.resolved_parameters)} -> {out}"
    )
    if args.figures:
        from workbench.plot import run_figures

        for path in run_figures(ds, Path(args.figures)):
            print(f"figure: {path}")
    if status.failed:
        print(f"workbench run: {status.label}: {a['run_message']}", file=sys.stderr)
    return exit_code(status)


def register_cli(sub) -> None:
    """Add the ``run`` subcommand."""
    p = sub.add_parser(
        "run",
        help="simulate one scene and write a netCDF run",
        description="Simulate one scene (TOML) and write its run as netCDF.",
    )
    p.add_argument("scene", help="scene file (TOML)")
    p.add_argument("-o", "--output", required=True, help="netCDF file to write (atomically)")
    p.add_argument("--figures", metavar="DIR", help="also write the run's figures (PNG) here")
    add_quiet(p)
    p.add_argument("--overwrite", action="store_true", help="replace existing output files")
    max_memory_option(p, "the run's records")
    p.set_defaults(func=_cmd_run)
