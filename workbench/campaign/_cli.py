"""``workbench campaign`` and ``workbench bifurcation``: campaigns from the command line."""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

__all__ = ["register_cli", "strobe_samples", "bifurcation_figure"]


def _cmd_campaign(args: argparse.Namespace) -> int:
    import workbench
    from workbench.campaign import CampaignError, run_campaign, summary

    scene = workbench.load_scene(args.scene)
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
        return 2
    finally:
        if client is not None:
            client.close()
    print(summary(ds))
    print(f"-> {Path(args.output)}")
    return 0


def strobe_samples(ds: xr.Dataset, var: str) -> xr.DataArray:
    """The stroboscopic (Poincaré) samples of ``var``: one per forcing period.

    A forced scene recorded with ``record.samples_per_period = K`` stores records at
    ``t0 + k T / K`` from the end of the transient on, so every K-th record (starting with the
    first) is a strobe sample. Returns ``var`` with ``time`` replaced by ``strobe`` (sample
    index). Raises ValueError if the dataset has no per-period record grid.
    """
    if var not in ds.data_vars:
        names = ", ".join(v for v in ds.data_vars if "time" in ds[v].dims)
        raise ValueError(f"no variable {var!r} in the campaign; variables over time: {names}")
    spp = ds.attrs.get("samples_per_period")
    if spp is None or "cycles" not in ds.attrs:
        raise ValueError(
            "a bifurcation diagram needs strobe samples: a forced model run for a number of "
            "cycles with record.samples_per_period set (e.g. 1); this campaign has "
            f"samples_per_period={spp!r} and cycles={ds.attrs.get('cycles')!r}"
        )
    da = ds[var].isel(time=slice(None, None, int(spp)))
    return da.rename(time="strobe").drop_vars(
        [c for c in da.coords if "time" in da[c].dims], errors="ignore"
    )


def _diagram_points(ds: xr.Dataset, var: str, param: str) -> tuple[np.ndarray, np.ndarray]:
    """(x, y): parameter value and strobe sample of every point, NaNs dropped."""
    samples = None
    try:  # the analysis layer's version, when it exists
        from workbench.analysis import bifurcation_diagram  # type: ignore[attr-defined]
    except ImportError:
        bifurcation_diagram = None
    if bifurcation_diagram is not None:
        try:
            out = bifurcation_diagram(ds, var)
            if isinstance(out, xr.DataArray) and param in out.dims:
                samples = out
        except Exception:  # another shape of result or a failure: select the samples here
            samples = None
    if samples is None:
        samples = strobe_samples(ds, var)
    other = [d for d in samples.dims if d != param]
    samples = samples.transpose(param, *other)
    x = np.broadcast_to(samples[param].values.reshape((-1,) + (1,) * len(other)), samples.shape)
    y = samples.values
    keep = np.isfinite(y)
    return x[keep], y[keep]


def bifurcation_figure(ds: xr.Dataset, var: str, param: str):
    """Scatter of the strobe samples of ``var`` against the parameter ``param``.

    ``ds`` must have ``param`` as its only dim of size > 1 besides ``time``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from workbench.plot._runs import axis_label

    x, y = _diagram_points(ds, var, param)
    fig, ax = plt.subplots(figsize=(8, 5))
    ax.scatter(x, y, s=1.0, c="k", marker=".", linewidths=0)
    ax.set_xlabel(axis_label(ds[param]))
    ax.set_ylabel(axis_label(ds[var]) + ", strobe samples")
    ax.set_title(ds.attrs.get("title", ""), fontsize=10)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


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
    import workbench

    ds = workbench.open_run(args.campaign)
    if "campaign_dims" not in ds.attrs:
        print(
            f"workbench bifurcation: error: {args.campaign!r} is not a campaign archive (no "
            "'campaign_dims' attribute); write one with 'workbench campaign'",
            file=sys.stderr,
        )
        return 2
    try:
        ds, param = _select(ds, args.var, args.param, args.at or [])
        fig = bifurcation_figure(ds, args.var, param)
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
        help="run a scene's [sweep] grid on dask into one netCDF campaign (resumable)",
        description="Run every point of a scene's [sweep] grid as dask tasks (a local process "
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
