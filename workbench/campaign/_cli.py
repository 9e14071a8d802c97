"""``workbench campaign`` and ``workbench bifurcation``: campaigns from the command line."""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from workbench._console import positive_float, positive_int, report_failures
from workbench._exit_codes import UsageError, worst_exit_code
from workbench.campaign._block import INVALID, STATUS, failed

__all__ = ["campaign_exit_code", "register_cli"]


def _client(address: str, timeout: float):
    """A dask client of the scheduler at ``address``; CampaignError (one line) if it cannot be
    reached within ``timeout`` seconds."""
    from distributed import Client

    from workbench.campaign import CampaignError

    try:
        return Client(address, timeout=timeout)
    except (OSError, TimeoutError, ValueError, TypeError) as exc:
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise CampaignError(
            f"--scheduler: cannot reach a dask scheduler at {address!r} within "
            f"{timeout:g} s ({reason}); give the address of a running scheduler, e.g. "
            "tcp://HOST:8786 (raise the wait with --scheduler-timeout), or drop --scheduler "
            "to use local processes"
        ) from None


def _cmd_campaign(args: argparse.Namespace) -> int:
    from workbench._console import announce_compile
    from workbench.archive import check_output_file
    from workbench.campaign import CampaignError, run_campaign, summary
    from workbench.scene import load_scene

    scene = load_scene(args.scene)
    if args.scheduler and args.workers is not None:
        raise CampaignError(
            f"--workers {args.workers} sizes the local pool, but --scheduler "
            f"{args.scheduler!r} brings its own workers; give one of them"
        )
    # existence is the store's business (resume, or refuse another campaign); the path's is here
    check_output_file(args.output, "-o/--output", overwrite=True)
    client = None
    try:
        if args.scheduler:
            client = _client(args.scheduler, args.scheduler_timeout)
            if args.quiet:  # otherwise run_campaign prints it above its progress bar
                print(f"campaign: dask dashboard at {client.dashboard_link}", file=sys.stderr)
        else:
            announce_compile(scene)
        with warnings.catch_warnings():  # the summary below lists every failed point
            warnings.filterwarnings("ignore", r"\d+ of \d+ campaign points failed")
            if scene.continuation:  # [sweep] continuation: points from their neighbours
                ds = _continued(scene, args, client)
            else:
                ds = run_campaign(
                    scene,
                    args.output,
                    client=client,
                    workers=args.workers,
                    chunk=args.chunk,
                    restart=args.restart,
                    progress=not args.quiet,
                )
    finally:
        if client is not None:
            client.close()
    print(summary(ds))
    print(f"-> {Path(args.output)}")
    code = campaign_exit_code(ds["status"].values)
    if code:
        flags = ds["status"].values.reshape(-1)
        n_failed = int(failed(flags).sum())
        counts = ", ".join(
            f"{int((flags == f).sum())} {name}"
            for f, name in STATUS.items()
            if failed(np.array([f]))[0] and (flags == f).any()
        )
        report_failures("campaign", f"{n_failed} of {flags.size} points failed ({counts})", code)
    return code


def _continued(scene, args: argparse.Namespace, client):
    """A continued sweep (``[sweep] continuation``): segments, not chunks, make its tasks."""
    from workbench.continuation import continued_sweep

    if args.chunk is not None:
        raise UsageError(
            f"--chunk {args.chunk}: a continued sweep ([sweep] continuation) is cut into "
            "segments, not chunks; set sweep.continuation.segments in the scene instead"
        )
    return continued_sweep(
        scene,
        args.output,
        client=client,
        workers=args.workers,
        restart=args.restart,
        progress=not args.quiet,
    )


def campaign_exit_code(flags) -> int:
    """The largest exit code among a campaign's point flags (a run's Status, or
    invalid_parameters: invalid input)."""
    return worst_exit_code(flags, INVALID)


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
    from workbench.archive import check_output_file, open_run

    out = Path(
        args.output
        or Path(args.campaign).with_name(f"{Path(args.campaign).stem}-bifurcation-{args.var}.png")
    )
    ds = open_run(args.campaign)
    if "campaign_dims" not in ds.attrs:
        raise UsageError(
            f"{args.campaign!r} is not a campaign archive (no 'campaign_dims' attribute); write "
            "one with 'workbench campaign'"
        )
    check_output_file(out, "-o/--output", overwrite=args.overwrite)
    from workbench.analysis import bifurcation_diagram
    from workbench.plot import bifurcation_figure

    try:
        ds, param = _select(ds, args.var, args.param, args.at or [])
        diagram = bifurcation_diagram(ds, args.var, param)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    fig = bifurcation_figure(diagram)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=150)
    n_failed = int(failed(ds["status"].values).sum())
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
        "OUTPUT.blocks/; running the same command again computes only missing blocks. With "
        "[sweep] continuation = 'up' | 'down' | 'both' each point starts from its neighbour's "
        "settled state (a continued sweep, in parallel by segments).",
    )
    p.add_argument("scene", help="scene file (TOML) with a [sweep] table")
    p.add_argument("-o", "--output", required=True, help="campaign netCDF file to write")
    p.add_argument(
        "--workers", type=positive_int, help="processes of the local pool (default: CPUs)"
    )
    p.add_argument("--scheduler", metavar="ADDRESS", help="dask.distributed scheduler address")
    p.add_argument(
        "--scheduler-timeout",
        type=positive_float,
        default=10.0,
        metavar="S",
        help="seconds to wait for the scheduler (default 10)",
    )
    p.add_argument("--chunk", type=positive_int, metavar="K", help="points per block (task)")
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
    p.add_argument("--overwrite", action="store_true", help="replace an existing PNG")
    p.add_argument(
        "--at",
        action="append",
        metavar="DIM=VALUE",
        help="fix another dim (nearest value), e.g. --at omega=1.2; repeatable",
    )
    p.set_defaults(func=_cmd_bifurcation)
