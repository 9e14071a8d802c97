"""``workbench orbit``: a branch of periodic orbits of a forced scene over a parameter (Floquet
multipliers, labelled bifurcations; :func:`workbench.continuation.continue_orbit`)."""

from __future__ import annotations

import argparse

from workbench.cli._console import add_quiet, positive_float, positive_int
from workbench.cli._exit_codes import UsageError

__all__ = ["register_cli"]


def _range(scene, param: str, start: float | None, stop: float | None) -> tuple[float, float]:
    """The branch's range: ``--start``/``--stop``, else the scene's sweep of ``param`` (its
    first and last values), else the scene's value."""
    swept = scene.sweep.get(param)
    if start is None:
        start = swept[0] if swept else None
    if stop is None:
        stop = swept[-1] if swept else None
    if stop is None:
        raise UsageError(
            f"--stop: the scene does not sweep {param!r}; give the end of the branch with --stop"
        )
    return start, stop


def _cmd_orbit(args: argparse.Namespace) -> int:
    from workbench.archive import check_output_file, open_run, save_figure
    from workbench.cli._console import compile_kernel, save_or_keep
    from workbench.continuation import branch_bifurcations, continue_orbit
    from workbench.scene import load_scene

    scene = load_scene(args.scene)
    check_output_file(args.output, "-o/--output", overwrite=args.overwrite)
    if args.figure:
        check_output_file(args.figure, "--figure", overwrite=args.overwrite)
        if not args.state:
            raise UsageError("--figure needs --state NAME (the state on the y axis, e.g. x_A)")
    if args.diagram and not (args.figure and args.var):
        raise UsageError("--diagram needs --figure and --var (the sweep's variable, e.g. x)")
    start, stop = _range(scene, args.param, args.start, args.stop)
    single = scene.replace(sweep={}) if scene.sweep else scene
    compile_kernel(single, quiet=args.quiet)
    try:
        branch = continue_orbit(
            single,
            args.param,
            start=start,
            stop=stop,
            periods=args.periods,
            doublings=args.doublings,
            tolerance=args.tolerance,
            max_points=args.max_points,
            rtol=args.rtol,
        )
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    out = save_or_keep(branch, args.output, overwrite=args.overwrite, what="branch")
    found = [
        f"{b['type']} at {args.param} = {b['value']:.8g} (multiplier "
        f"{b['critical'].real:+.4f}{b['critical'].imag:+.4f}i)"
        if b["resolved"]
        else f"unresolved: a {b['type']} suspected at {args.param} = {b['value']:.8g}, not "
        "confirmed by its defining quantity (bracket and value in the archive)"
        for b in branch_bifurcations(branch, args.param)
    ]
    print(
        f"{branch.sizes['point']} orbits on {int(branch.branch.max()) + 1} branch(es), "
        f"{branch.attrs['map_evaluations']} map evaluations, {branch.attrs['wall_time']:.3g} s "
        f"wall; ended: {branch.attrs['branch_ended']} -> {out}"
    )
    for line in found or ["no bifurcation in the range"]:
        print(f"  {line}")
    a = branch.attrs
    if a["integration_method"] != a["scene_method"]:
        print(
            f"  integrated by {a['integration_method']} in place of the scene's "
            f"{a['scene_method']} (the tangent and copies systems need an explicit method)"
        )
    if args.figure:
        from workbench.plot import branch_figure

        diagram = None
        if args.diagram:
            from workbench.analysis import bifurcation_diagram

            sweep = open_run(args.diagram)
            for item in args.at or []:
                dim, _, raw = item.partition("=")
                if dim not in sweep.dims:
                    raise UsageError(f"--at {item!r}: no dim {dim!r} in {args.diagram!r}")
                sel = float(raw) if sweep[dim].dtype.kind in "fiu" else raw
                sweep = sweep.sel({dim: sel}, method="nearest" if isinstance(sel, float) else None)
            diagram = bifurcation_diagram(sweep, args.var, args.param)
        fig = branch_figure(branch, args.state, diagram=diagram)
        save_figure(fig, args.figure, dpi=150)
        print(f"figure: {args.figure}")
    return 0


def register_cli(sub) -> None:
    """Add the ``orbit`` subcommand."""
    p = sub.add_parser(
        "orbit",
        help="continue a branch of periodic orbits over a parameter (Floquet multipliers, "
        "folds, period doublings, Neimark-Sacker, grazing)",
        description="Find a periodic orbit of a forced scene by shooting (from the state after "
        "its transient) and continue it over PARAM by pseudo-arclength, with its Floquet "
        "multipliers and labelled bifurcations; write the branch as netCDF.",
    )
    p.add_argument("scene", help="scene file (TOML); its [sweep] of PARAM gives the range")
    p.add_argument("-o", "--output", required=True, help="netCDF file of the branch")
    p.add_argument("--param", required=True, help="model parameter to continue in")
    p.add_argument("--start", type=float, help="first value (default: the sweep's first)")
    p.add_argument("--stop", type=float, help="last value (default: the sweep's last)")
    p.add_argument("--periods", type=positive_int, default=1, help="period k (default 1)")
    p.add_argument(
        "--doublings",
        type=int,
        default=0,
        help="switch to the doubled branch at the first period doubling, N times (default 0)",
    )
    p.add_argument(
        "--tolerance", type=positive_float, default=1e-8, help="Newton tolerance (scaled)"
    )
    p.add_argument(
        "--rtol", type=positive_float, help="integration rtol (default min(scene, 1e-9))"
    )
    p.add_argument("--max-points", type=positive_int, default=300, help="points per branch")
    p.add_argument("--figure", metavar="PNG", help="draw the branch (needs --state)")
    p.add_argument("--state", help="state on the figure's y axis (e.g. x, x_A)")
    p.add_argument("--diagram", metavar="SWEEP.nc", help="a campaign or continued sweep under it")
    p.add_argument("--var", help="the sweep's variable on the figure (e.g. x, clearance_x)")
    p.add_argument(
        "--at",
        action="append",
        metavar="DIM=VALUE",
        help="fix another dim of the sweep, e.g. --at joint=A; repeatable",
    )
    p.add_argument("--overwrite", action="store_true", help="replace existing outputs")
    add_quiet(p)
    p.set_defaults(func=_cmd_orbit)
