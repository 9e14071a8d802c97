"""``workbench campaign`` and ``workbench bifurcation``: campaigns from the command line."""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import xarray as xr

from workbench._exit_codes import EXIT_INVALID, exit_code
from workbench.campaign._block import INVALID
from workbench.solver import Status

__all__ = ["campaign_exit_code", "register_cli"]


def _cmd_campaign(args: argparse.Namespace) -> int:
    from workbench.campaign import CampaignError, run_campaign, summary
    from workbench.scene import load_scene

    scene = load_scene(args.scene)
    client = None
    try:
        if args.scheduler:
            if args.workers is not None:
                raise CampaignError(
                    f"--workers {args.workers} sizes the local pool, but --scheduler "
                    f"{args.scheduler!r} brings its own workers; give one of them"
                )
            from distributed import Client

            client = Client(args.scheduler)
            if args.quiet:  # otherwise run_campaign prints it above its progress bar
                print(f"campaign: dask dashboard at {client.dashboard_link}", file=sys.stderr)
        with warnings.catch_warnings():  # the summary below lists every failed point
            warnings.filterwarnings("ignore", r"\d+ of \d+ campaign points failed")
            ds = run_campaign(
                scene,
                args.output,
                client=client,
                workers=args.workers,
                chunk=args.chunk,
                restart=args.restart,
                progress=not args.quiet,
            )
    except CampaignError as exc:
        print(f"workbench campaign: error: {exc}", file=sys.stderr)
        return exit_code(exc)
    finally:
        if client is not None:
            client.close()
    print(summary(ds))
    print(f"-> {Path(args.output)}")
    return campaign_exit_code(ds["status"].values)


def campaign_exit_code(flags) -> int:
    """The largest exit code among a campaign's point flags (a run's Status, or
    invalid_parameters: invalid input)."""
    codes = [EXIT_INVALID if f == INVALID else exit_code(Status(f)) for f in set(flags.flat)]
    return max(codes, default=0)


def _select(ds: xr.Dataset, var: str, param: str | None, at: list[str]) -> tuple[xr.Dataset, str]:
    """Apply ``--at DIM=VALUE`` selections; return the dataset and the parameter of the x axis."""
    if var not in ds.data_vars or "time" not in ds[var].dims:
        names = ", ".join(v for v in ds.data_vars if "time" in ds[v].dims)
        raise ValueError(f"no variable {var!r} over time in the campaign; there are: {names}")
    for item in at:
        dim, sep, raw = item.partition("=")
        if not sep or dim not in ds.dims:
            raise ValueError(f"--at takes DIM=VALUE with DIM among {list(ds.dims)}, got {item!r}")
        if ds[dim].dtype.kind in "fiu":
            ds = ds.sel({dim: float(raw)}, method="nearest")
        else:
            ds = ds.sel({dim: raw})
    pdims = [d for d in ds.attrs["campaign_dims"].split() if d in ds.dims]
    if param is None:
        wide = [d for d in pdims if ds.sizes[d] > 1]
        if len(wide) != 1:
            raise ValueError(
                f"the campaign varies {wide!r}; a bifurcation diagram has one parameter on its x "
                "axis: choose it with --param and fix the others with --at DIM=VALUE"
            )
        param = wide[0]
    if param not in pdims:
        raise ValueError(f"--param must be one of the campaign's dims {pdims!r}, got {param!r}")
    extra = [d for d in ds[var].dims if d not in ("time", param) and ds.sizes[d] > 1]
    if extra:
        raise ValueError(
            f"{var!r} also varies over {extra!r}; fix them with --at DIM=VALUE "
            f"(e.g. --at {extra[0]}={ds[extra[0]].values[0]})"
        )
    return ds.squeeze([d for d in ds.dims if d not in ("time", param) and ds.sizes[d] == 1]), param


def _cmd_bifurcation(args: argparse.Namespace) -> int:
    from workbench.archive import open_run

    ds = open_run(args.campaign)
    if "campaign_dims" not in ds.attrs:
        print(
            f"workbench bifurcation: error: {args.campaign!r} is not a campaign archive (no "
            "'campaign_dims' attribute); write one with 'workbench campaign'",
            file=sys.stderr,
        )
        return 2
    try:
        from workbench.analysis import bifurcation_diagram
        from workbench.plot import bifurcation_figure

        ds, param = _select(ds, args.var, args.param, args.at or [])
        fig = bifurcation_figure(bifurcation_diagram(ds, args.var, param))
    except ValueError as exc:
        print(f"workbench bifurcation: error: {exc}", file=sys.stderr)
        return 2
    out = Path(
        args.output
        or Path(args.campaign).with_name(f"{Path(args.campaign).stem}-bifurcation-{args.var}.png")
    )
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=150)
    n_failed = int((ds["status"] != 0).sum())
    note = f" ({n_failed} failed points left out)" if n_failed else ""
    print(f"bifurcation diagram of {args.var} over {param}{note}: {out}")
    return 0


def register_cli(sub) -> None:
    """Add the ``campaign`` and ``bifurcation`` subcommands."""
    p = sub.add_parser(
        "campaign",
        help="run a scene's [sweep] grid in parallel into one netCDF campaign (resumable)",
        description="Run every point of a scene's [sweep] grid as tasks (a local process "
        "pool, or a dask.distributed scheduler) and assemble one netCDF archive. Blocks go to "
        "OUTPUT.blocks/; running the same command again computes only missing blocks.",
    )
    p.add_argument("scene", help="scene file (TOML) with a [sweep] table")
    p.add_argument("-o", "--output", required=True, help="campaign netCDF file to write")
    p.add_argument("--workers", type=int, help="processes of the local pool (default: CPUs)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="dask.distributed scheduler address")
    p.add_argument("--chunk", type=int, metavar="K", help="points per block (task)")
    p.add_argument(
        "--restart", action="store_true", help="discard a stored campaign and start afresh"
    )
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_campaign)

    p = sub.add_parser(
        "bifurcation",
        help="bifurcation diagram (PNG) of a campaign: strobe samples against a parameter",
        description="Scatter the stroboscopic samples of one variable against the swept "
        "parameter of a campaign archive.",
    )
    p.add_argument("campaign", help="campaign netCDF written by 'workbench campaign'")
    p.add_argument("--var", required=True, help="variable on the y axis (e.g. x)")
    p.add_argument("-o", "--output", help="PNG to write (default: beside the campaign)")
    p.add_argument("--param", help="parameter on the x axis (default: the one swept dim)")
    p.add_argument(
        "--at",
        action="append",
        metavar="DIM=VALUE",
        help="fix another dim (nearest value), e.g. --at omega=1.2; repeatable",
    )
    p.set_defaults(func=_cmd_bifurcation)
