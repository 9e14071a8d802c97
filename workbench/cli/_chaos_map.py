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
    compile_kernel(scene, quiet=args.quiet)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", r"\d+ of \d+ campaign points failed")
        ds = chaos_map(
            scene, args.output, workers=args.workers, restart=args.restart, progress=not args.quiet
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
    if args.figure:
        from workbench.plot import chaos_map_figure

        scales = {d: 1 / math.pi for d in ds.attrs["campaign_dims"].split() if d == "omega"}
        labels = {"omega": "crank speed omega / pi"} if scales else {}
        save_figure(
            chaos_map_figure(ds, scales=scales, labels=labels), args.figure, dpi=150, close=True
        )
        print(f"figure: {args.figure}")
    print(f"-> {Path(args.output)}")
    return campaign_exit_code(ds["status"].values)


def register_cli(sub) -> None:
    """Add the ``chaos-map`` subcommand."""
    p = sub.add_parser(
        "chaos-map",
        help="chaos indicators (strobe period, 0-1 test K, largest exponent) over a campaign",
        description="Run a scene's [sweep] as a campaign whose workers measure each point's "
        "strobe period, 0-1 test K and largest Lyapunov exponent with its error (the "
        "Floquet multipliers' where the strobe is periodic, else the variational equations "
        "or the two-trajectory method); resumable like 'workbench campaign'.",
    )
    p.add_argument("scene", help="scene file (TOML) with a [sweep], recorded per period")
    p.add_argument("-o", "--output", required=True, help="campaign netCDF file to write")
    p.add_argument("--workers", type=positive_int, help="processes (default: CPUs)")
    p.add_argument("--figure", metavar="PNG", help="draw the maps (two swept dims)")
    p.add_argument("--restart", action="store_true", help="discard a stored map")
    add_quiet(p)
    p.set_defaults(func=_cmd_chaos_map)
