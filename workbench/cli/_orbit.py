"""``workbench orbit``: a branch of periodic orbits of a forced scene over a parameter (Floquet
multipliers, labelled bifurcations; :func:`workbench.continuation.continue_orbit`), and with
``--curve`` the curve of its first labelled bifurcation in two parameters
(:func:`workbench.continuation.continue_curve`)."""

from __future__ import annotations

import argparse

from workbench.cli._console import add_quiet, positive_float, positive_int
from workbench.cli._exit_codes import UsageError

__all__ = ["register_cli"]


def _check_parameter(scene, option: str, name: str, other: str | None = None) -> None:
    """Refuse ``name`` in one line unless it is a parameter of the scene's model (other than
    ``other``, the parameter of the branch when ``name`` is the curve's second one)."""
    from workbench.models import get_model

    names = [par.name for par in get_model(scene.model).parameters]
    if name not in names:
        raise UsageError(
            f"{option} {name!r}: not a parameter of model {scene.model!r}; allowed: "
            f"{', '.join(sorted(n for n in names if n != other))}"
        )


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


#: the kinds of labelled points a curve can start from
CURVE_KINDS = ("fold", "period_doubling", "neimark_sacker", "grazing")


def _diagram(args):
    """The orbit diagram of ``--diagram`` (a campaign or continued sweep) over ``--param``:
    ``--var``'s strobe samples, other dims fixed by ``--at``."""
    from workbench.analysis import bifurcation_diagram
    from workbench.archive import open_run

    sweep = open_run(args.diagram)
    for item in args.at or []:
        dim, _, raw = item.partition("=")
        if dim not in sweep.dims:
            raise UsageError(f"--at {item!r}: no dim {dim!r} in {args.diagram!r}")
        sel = float(raw) if sweep[dim].dtype.kind in "fiu" else raw
        sweep = sweep.sel({dim: sel}, method="nearest" if isinstance(sel, float) else None)
    return bifurcation_diagram(sweep, args.var, args.param)


def _curve_range(scene, args) -> tuple[float, float]:
    """The second parameter's range (``--curve-start``/``--curve-stop``, else the scene's sweep
    of it), checked to hold the scene's value, where the curve starts."""
    _check_parameter(scene, "--curve", args.curve, other=args.param)
    if args.curve == args.param:
        raise UsageError(f"--curve {args.curve!r}: the same as --param; name a second parameter")
    if args.curve_kind is not None and args.curve_kind not in CURVE_KINDS:
        raise UsageError(f"--curve-kind {args.curve_kind!r}: allowed: {', '.join(CURVE_KINDS)}")
    swept = scene.sweep.get(args.curve)
    start = args.curve_start if args.curve_start is not None else (swept[0] if swept else None)
    stop = args.curve_stop if args.curve_stop is not None else (swept[-1] if swept else None)
    if start is None or stop is None:
        which = "--curve-start" if start is None else "--curve-stop"
        raise UsageError(
            f"{which}: the scene does not sweep {args.curve!r}; give the range of the curve "
            "with --curve-start and --curve-stop"
        )
    q0 = float(scene.resolved_parameters[args.curve])
    if start == stop or not min(start, stop) <= q0 <= max(start, stop):
        raise UsageError(
            f"--curve-start/--curve-stop: the range {start:g} .. {stop:g} of {args.curve!r} "
            f"must contain the scene's value {q0:g}, where the curve starts (set "
            f"{args.curve} in the scene's [parameters], or widen the range)"
        )
    return float(start), float(stop)


def _cmd_orbit(args: argparse.Namespace) -> int:
    from workbench.archive import check_output_file, open_run, save_figure
    from workbench.cli._console import compile_kernel, save_or_keep
    from workbench.continuation import branch_bifurcations, continue_orbit
    from workbench.continuation._newton import NewtonFailure
    from workbench.scene import load_scene

    scene = load_scene(args.scene)
    _check_parameter(scene, "--param", args.param)  # before anything that names it
    check_output_file(args.output, "-o/--output", overwrite=args.overwrite)
    for name, given in (
        ("--curve-start", args.curve_start is not None),
        ("--curve-stop", args.curve_stop is not None),
        ("--curve-kind", args.curve_kind is not None),
        ("--map", args.map is not None),
    ):
        if given and not args.curve:
            raise UsageError(f"{name} needs --curve NAME (the second parameter of the curve)")
    if args.figure:
        check_output_file(args.figure, "--figure", overwrite=args.overwrite)
        if not args.state and not args.curve:
            raise UsageError("--figure needs --state NAME (the state on the y axis, e.g. x_A)")
    if args.diagram and not (args.figure and args.var):
        raise UsageError("--diagram needs --figure and --var (the sweep's variable, e.g. x)")
    if args.map and not args.figure:
        raise UsageError("--map needs --figure (the chaos map is drawn under the curve)")
    start, stop = _range(scene, args.param, args.start, args.stop)
    curve_range = _curve_range(scene, args) if args.curve else None
    maps = None
    if args.map:
        maps = open_run(args.map)
        dims = maps.attrs.get("campaign_dims", "").split()
        if set(dims) != {args.param, args.curve}:
            raise UsageError(
                f"--map {args.map!r}: a chaos map over {dims!r}; the curve needs one over "
                f"{[args.param, args.curve]!r}"
            )
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
            progress=not args.quiet,
        )
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    except NewtonFailure as exc:  # the first orbit not found: one line with what to try
        raise UsageError(f"no first orbit for the branch in {args.param!r}: {exc}") from None
    if args.curve:
        p0 = float(single.resolved_parameters[args.param]) if start is None else start
        return _curve(args, branch, p0, stop, curve_range, maps)
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

        diagram = _diagram(args) if args.diagram else None
        fig = branch_figure(branch, args.state, diagram=diagram)
        save_figure(fig, args.figure, dpi=150, close=True)
        print(f"figure: {args.figure}")
    return 0


def _curve(args, branch, start, stop, curve_range, maps) -> int:
    """The curve of the first labelled point (of ``--curve-kind``) of ``branch`` in
    (``--param``, ``--curve``), written to ``-o``, printed, drawn with ``--figure``."""
    from workbench.archive import save_figure
    from workbench.cli._console import save_or_keep
    from workbench.continuation import branch_bifurcations, continue_curve
    from workbench.continuation._newton import NewtonFailure

    found = branch_bifurcations(branch, args.param)
    allowed = (args.curve_kind,) if args.curve_kind else CURVE_KINDS
    hits = [i for i, b in enumerate(found) if b["type"] in allowed]
    if not hits:
        option = "--curve-kind" if args.curve_kind else "--curve"
        what = args.curve_kind or "fold, period_doubling, neimark_sacker or grazing"
        others = ", ".join(f"{b['type']} at {b['value']:.8g}" for b in found) or "none"
        raise UsageError(
            f"{option}: no labelled {what} point found along {args.param} between "
            f"{start:g} and {stop:g} (found: {others}); "
            "widen --start/--stop or pick another --curve-kind"
        )
    first = found[hits[0]]
    try:
        curve = continue_curve(
            branch,
            args.curve,
            start=curve_range[0],
            stop=curve_range[1],
            bifurcation=hits[0],
            max_points=args.max_points,
            progress=not args.quiet,
        )
    except NewtonFailure as exc:
        raise UsageError(
            f"--curve {args.curve!r}: the {first['type']} at {args.param} = "
            f"{first['value']:.8g} could not be continued ({exc})"
        ) from None
    out = save_or_keep(curve, args.output, overwrite=args.overwrite, what="curve")
    a = curve.attrs
    P, Q = args.param, args.curve
    ends = " to ".join(
        f"({P} = {float(curve[P][i]):.8g}, {Q} = {float(curve[Q][i]):.8g})" for i in (0, -1)
    )
    print(
        f"{a['curve_kind']} curve from the {first['type']} at {P} = {first['value']:.8g}: "
        f"{curve.sizes['curve_point']} points from {ends}, {a['map_evaluations']} map "
        f"evaluations, {a['wall_time']:.3g} s wall; ended: {a['curve_ended']} -> {out}"
    )
    from workbench._attributes import flag_meaning

    for i in curve.special_index.values:
        label = flag_meaning(curve.label, curve.label.values[i])
        print(f"  {label} at {P} = {float(curve[P][i]):.8g}, {Q} = {float(curve[Q][i]):.8g}")
    if a["curve_unresolved"] != "none":
        print(f"  not resolved: {a['curve_unresolved']}")
    if args.figure:
        from workbench import plot

        if maps is not None:
            fig = plot.chaos_map_figure(maps, curves=[curve])
        elif args.state:
            diagram = _diagram(args) if args.diagram else None
            fig = plot.branch_figure(branch, args.state, diagram=diagram)
            plot.curve_overlay(fig.axes[0], curve, x=P, y=f"orbit_{args.state}")
            fig.axes[0].legend(fontsize=7, loc="best")
        else:
            fig = plot.curve_figure([curve])
        save_figure(fig, args.figure, dpi=150, close=True)
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
    p.add_argument(
        "--curve",
        metavar="NAME",
        help="continue the first labelled fold, period doubling, Neimark-Sacker or grazing "
        "point found along PARAM in this second parameter; -o then holds the curve",
    )
    p.add_argument("--curve-start", type=float, help="one end of the curve's range of NAME")
    p.add_argument("--curve-stop", type=float, help="the other end of the curve's range")
    p.add_argument(
        "--curve-kind",
        metavar="KIND",
        help=f"the kind of point to continue: {', '.join(CURVE_KINDS)} (default: the first "
        "labelled one of these)",
    )
    p.add_argument(
        "--map", metavar="MAP.nc", help="with --curve: a chaos map over PARAM and NAME under it"
    )
    p.add_argument("--overwrite", action="store_true", help="replace existing outputs")
    add_quiet(p)
    p.set_defaults(func=_cmd_orbit)
