"""``workbench bifurcation``: the orbit diagram of a campaign (strobe samples against a
parameter)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from workbench.cli._console import add_quiet
from workbench.cli._exit_codes import UsageError

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["register_cli"]


def _select(ds: xr.Dataset, var: str, param: str | None, at: list[str]) -> tuple[xr.Dataset, str]:
    """Apply ``--at DIM=VALUE`` selections; return the dataset and the parameter of the x axis."""
    from workbench.archive import SERIES_DIMS  # time, or record (each point's record times)

    def recorded(name: str) -> bool:
        return any(d in SERIES_DIMS for d in ds[name].dims)

    if var not in ds.data_vars or not recorded(var):
        names = ", ".join(v for v in ds.data_vars if recorded(v))
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
    extra = [d for d in ds[var].dims if d not in (*SERIES_DIMS, param) and ds.sizes[d] > 1]
    if extra:
        raise ValueError(
            f"{var!r} also varies over {extra!r}; fix them with --at DIM=VALUE "
            f"(e.g. --at {extra[0]}={ds[extra[0]].values[0]})"
        )
    keep = (*SERIES_DIMS, param)
    return ds.squeeze([d for d in ds.dims if d not in keep and ds.sizes[d] == 1]), param


def _cmd_bifurcation(args: argparse.Namespace) -> int:
    from workbench.archive import check_output_file, open_run, save_figure, status_flags
    from workbench.campaign._block import failed

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
    if "status" not in ds:
        raise UsageError(
            f"{args.campaign!r} has no 'status' variable (the outcome of each point), so its "
            "failed points cannot be told from the others: the archive was altered or is not "
            "complete; recompute it with 'workbench campaign'"
        )
    status_flags(ds["status"], repr(args.campaign))  # whole numbers (not NaN), or one line
    check_output_file(out, "-o/--output", overwrite=args.overwrite)
    from workbench.analysis import bifurcation_diagram
    from workbench.plot import bifurcation_figure

    try:
        ds, param = _select(ds, args.var, args.param, args.at or [])
        diagram = bifurcation_diagram(ds, args.var, param)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    save_figure(bifurcation_figure(diagram), out, dpi=150, close=True)
    n_failed = int(failed(status_flags(ds["status"], repr(args.campaign))).sum())
    note = f" ({n_failed} failed points left out)" if n_failed else ""
    print(f"bifurcation diagram of {args.var} over {param}{note}: {out}")
    return 0


def register_cli(sub) -> None:
    """Add the ``bifurcation`` subcommand."""
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
    add_quiet(p, "accepted by every command; this one prints only its results")
    p.set_defaults(func=_cmd_bifurcation)
