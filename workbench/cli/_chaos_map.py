"""``workbench chaos-map``: chaos indicators over a campaign's parameters (strobe period, 0-1
test K, largest exponent with its error; :func:`workbench.continuation.chaos_map`)."""

from __future__ import annotations

import argparse
import math
import warnings
from pathlib import Path

from workbench.cli._console import add_quiet, positive_int

__all__ = ["register_cli"]


def _cmd_chaos_map(args: argparse.Namespace) -> int:
    from workbench.archive import check_output_file, save_figure
    from workbench.campaign import summary
    from workbench.cli._campaign import campaign_exit_code
    from workbench.cli._console import check_store_output, compile_kernel
    from workbench.continuation import chaos_map
    from workbench.scene import load_scene

    scene = load_scene(args.scene)
    check_store_output(args.output)
    if args.figure:
        check_output_file(args.figure, "--figure", overwrite=True)
    curves = _curves(args, scene)
    compile_kernel(scene, quiet=args.quiet)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", r"\d+ of \d+ campaign points failed")
        ds = chaos_map(
            scene,
            args.output,
            workers=args.workers,
            restart=args.restart,
            progress=not args.quiet,
            full_fraction=args.full_fraction,
            full_seed=args.full_seed,
            along=args.along,
        )
    print(summary(ds))
    status = ds["lle_status"].values if "lle_status" in ds else None
    if status is not None and (status == 1).any():
        print(f"  {int((status == 1).sum())} exponents failed (lle_status = 1, lle NaN)")
    if status is not None and (status == 2).any():
        print(
            f"  {int((status == 2).sum())} exponents are upper bounds (lle_status = 2: the Floquet "
            "multipliers are below the noise of the copies' differences)"
        )
    if "lle_converged" in ds and (ds["lle_converged"] == 0).any():
        print(
            f"  {int((ds['lle_converged'] == 0).sum())} exponents did not converge "
            "(lle_converged = 0; lle_unmet names the conditions; hatched on the figure)"
        )
    n_full = int(ds.attrs.get("lle_full_points", 0))
    if n_full:
        print(
            f"  full protocol at {n_full} points: {ds.attrs['lle_full_agreeing']:.0%} agree with "
            f"the map's exponents (within 10 % or 2 combined errors), "
            f"{ds.attrs['lle_full_same_verdict']:.0%} with the same verdict (chaotic or regular)"
        )
    if args.figure:
        from workbench.plot import chaos_map_figure

        scales = {d: 1 / math.pi for d in ds.attrs["campaign_dims"].split() if d == "omega"}
        labels = {"omega": "crank speed omega / pi"} if scales else {}
        fig = chaos_map_figure(ds, scales=scales, labels=labels, curves=curves)
        save_figure(fig, args.figure, dpi=150, close=True)
        print(f"figure: {args.figure}")
    print(f"-> {Path(args.output)}")
    return campaign_exit_code(ds["status"].values)


def _curves(args: argparse.Namespace, scene) -> list:
    """The ``--curve`` archives (curves of bifurcations in two parameters), checked before the
    map runs: each readable and in the map's two swept parameters, and ``--figure`` given."""
    from workbench.archive import open_run
    from workbench.cli._exit_codes import UsageError

    if not args.curve:
        return []
    if not args.figure:
        raise UsageError("--curve draws on the map's figure: give --figure PNG too")
    dims = set(scene.sweep) - {"continuation"}
    curves = []
    for path in args.curve:
        if not Path(path).is_file():
            raise UsageError(f"--curve {path!r}: no such file; give a netCDF curve archive")
        c = open_run(path)
        pair = {c.attrs.get("continuation_parameter"), c.attrs.get("curve_parameter")}
        if pair != dims:
            raise UsageError(
                f"--curve {path!r}: a curve in {sorted(str(p) for p in pair)!r}, the map is "
                f"over {sorted(dims)!r}; give a curve of workbench.continuation.continue_curve "
                "in the map's two parameters"
            )
        curves.append(c)
    return curves


def _fraction(text: str) -> float:
    """argparse type: a number in [0, 1]."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"got {text!r}; allowed: a number in [0, 1]") from None
    if not 0 <= value <= 1:
        raise argparse.ArgumentTypeError(f"got {value}; allowed: a number in [0, 1]")
    return value


def register_cli(sub) -> None:
    """Add the ``chaos-map`` subcommand."""
    p = sub.add_parser(
        "chaos-map",
        help="chaos indicators (strobe period, 0-1 test K, largest exponent) over a campaign",
        description="Run a scene's [sweep] as a campaign whose workers measure each point's "
        "strobe period, 0-1 test K and largest Lyapunov exponent with its error (the "
        "Floquet multipliers' where the strobe is periodic, else the variational equations "
        "or the two-trajectory method, from where each point's run ended, to a 10 % error or "
        "the sign beyond 3 errors; the full protocol on a random subset); resumable like "
        "'workbench campaign'.",
    )
    p.add_argument("scene", help="scene file (TOML) with a [sweep], recorded per period")
    p.add_argument("-o", "--output", required=True, help="campaign netCDF file to write")
    p.add_argument("--workers", type=positive_int, help="processes (default: CPUs)")
    p.add_argument("--figure", metavar="PNG", help="draw the maps (two swept dims)")
    p.add_argument("--restart", action="store_true", help="discard a stored map")
    p.add_argument(
        "--full-fraction",
        type=_fraction,
        default=0.05,
        metavar="F",
        help="fraction of the points whose exponent the full protocol measures too, to check "
        "the map's own precision (default 0.05; at least 3 points, 0: none)",
    )
    p.add_argument(
        "--full-seed", type=int, default=0, help="seed of that subset's choice (default 0)"
    )
    p.add_argument(
        "--along",
        metavar="NAME",
        help="carry state along this swept parameter (upwards, as a continued sweep): each "
        "point's run starts where the previous one ended and Newton from its periodic orbit",
    )
    p.add_argument(
        "--curve",
        action="append",
        metavar="NC",
        help="draw this curve of bifurcations in the map's two parameters on the figure "
        "(netCDF of workbench.continuation.continue_curve or 'workbench orbit --curve'; "
        "repeat for more)",
    )
    add_quiet(p)
    p.set_defaults(func=_cmd_chaos_map)
