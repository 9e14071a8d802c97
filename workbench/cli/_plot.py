"""``workbench plot``: the standard figures of a stored run or campaign."""

from __future__ import annotations

import argparse
from pathlib import Path

from workbench.cli._console import add_quiet
from workbench.cli._exit_codes import UsageError

__all__ = ["register_cli"]


def _cmd_plot(args: argparse.Namespace) -> int:
    from workbench.archive import SERIES_DIMS, check_output_directory, open_run
    from workbench.plot import run_figure_names, run_figures

    ds = open_run(args.run)
    campaign = "campaign_dims" in ds.attrs
    series = [v for v in ds.data_vars if any(d in SERIES_DIMS for d in ds[v].dims)]
    if not series:
        raise UsageError(
            f"{args.run!r} has no variables over time: it is not a run or a campaign archive "
            "(write one with 'workbench run' or 'workbench campaign')"
        )
    strobe = "forcing_period" in ds.attrs and "samples_per_period" in ds.attrs
    names = run_figure_names(ds.attrs.get("model"), len(series), campaign=campaign, strobe=strobe)
    check_output_directory(args.output, "-o/--output", names, overwrite=args.overwrite)
    for path in run_figures(ds, Path(args.output)):
        print(f"figure: {path}")
    return 0


def register_cli(sub) -> None:
    """Add the ``plot`` subcommand."""
    p = sub.add_parser(
        "plot",
        help="figures (PNG) of a stored run or campaign",
        description="Write the standard figures of a stored run as PNG files: its time series "
        "(up to 8 panels per figure), phase portraits, stroboscopic Poincaré sections (a forced "
        "run) and the model's overview; of a campaign, every variable against the swept "
        "parameter, failed points marked.",
    )
    p.add_argument("run", help="netCDF run or campaign written by 'workbench run | campaign'")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="directory for the PNGs")
    p.add_argument("--overwrite", action="store_true", help="replace existing figures")
    add_quiet(p, "accepted by every command; this one prints only its results")
    p.set_defaults(func=_cmd_plot)
