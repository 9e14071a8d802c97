"""``workbench analyse``: chaos identification of one variable of a stored run."""

from __future__ import annotations

import argparse

from workbench.cli._exit_codes import UsageError


def _series(ds, var: str, select: list[str]):
    """The 1-D series ``var`` of a run with ``--select DIM=LABEL`` applied (UsageError if not)."""
    if var not in ds or "time" not in ds[var].dims:
        names = ", ".join(v for v in ds.data_vars if "time" in ds[v].dims)
        raise UsageError(f"--var: no variable {var!r} over time in the run; there are: {names}")
    da = ds[var]
    for item in select:
        dim, _, label = item.partition("=")
        if dim not in da.dims or label not in [str(v) for v in da[dim].values]:
            choices = {d: [str(v) for v in da[d].values] for d in da.dims if d != "time"}
            raise UsageError(f"--select takes DIM=LABEL among {choices}, got {item!r}")
        da = da.sel({dim: label})
    if da.ndim != 1:
        raise UsageError(
            f"--var {var!r} has dims {da.dims}; pick one element of the others with "
            "--select DIM=LABEL"
        )
    return da


def _cmd_analyse(args: argparse.Namespace) -> int:
    import numpy as np

    from workbench import analysis, plot
    from workbench.archive import check_output_directory, open_run
    from workbench.scene import scene_from_toml

    ds = open_run(args.run)
    if "campaign_dims" in ds.attrs:
        raise UsageError(
            f"{args.run!r} is a campaign; 'workbench analyse' takes one run (written by "
            "'workbench run')"
        )
    da = _series(ds, args.var, args.select or [])
    period = ds.attrs.get("forcing_period")
    strobe = None
    if period is not None and ds.attrs.get("samples_per_period"):
        strobe = analysis.poincare_section(ds.assign(_v=da), "_v")["_v"]
    label = args.var + "".join(f"[{s}]" for s in args.select or [])
    stem = label.replace("[", "-").replace("]", "").replace("=", "")
    names = ["embedding", "lle"] + (["zero_one"] if strobe is not None else [])
    out = check_output_directory(
        args.output, "-o/--output", [f"{stem}-{n}.png" for n in names], overwrite=args.overwrite
    )
    try:
        ami = analysis.delay_ami(da)
        delay = int(ami.delay)
        fnn = analysis.embedding_fnn(da, delay=delay)
        cao = analysis.embedding_cao(da, delay=delay)
        wolf = analysis.wolf_lle(da, delay=delay, dim=int(fnn.dim), period=period)
        ros = analysis.rosenstein_lle(da, delay=delay, dim=int(fnn.dim))
    except ValueError as exc:  # the estimators name what the series lacks
        raise UsageError(f"--var {label}: {exc}") from None
    print(f"{label}: {da.size} samples, dt = {float(da.time[1] - da.time[0]):.4g} s")
    print(
        f"  delay (first AMI minimum): {delay} samples; ACF 1/e: "
        f"{int(analysis.delay_acf(da).delay)} samples"
    )
    print(f"  embedding dimension: FNN {int(fnn.dim)}, Cao {int(cao.dim)}")
    per = f" = {float(wolf.lle_per_period):.4g} per forcing period" if period else ""
    print(f"  Wolf LLE: {float(wolf.lle):.4g} 1/s{per} ({int(wolf.replacements)} replacements)")
    print(f"  Rosenstein LLE (nolds): {float(ros.lle):.4g} 1/s")
    figures = {
        "embedding": plot.embedding_figure(ami, fnn, cao),
        "lle": plot.lle_figure(wolf, float(ros.lle), label),
    }
    if strobe is not None:
        if strobe.sizes["strobe"] >= 100:
            z = analysis.zero_one_test(strobe)
            print(f"  0-1 test on {strobe.sizes['strobe']} strobe samples: K = {float(z.K):.3f}")
            figures["zero_one"] = plot.zero_one_figure(z)
        else:
            print(f"  0-1 test: skipped ({strobe.sizes['strobe']} strobe samples, needs 100)")
    if args.equations:
        bench = analysis.lle_from_equations(scene_from_toml(ds.attrs["scene"]))
        print(f"  LLE from the equations (Benettin): {float(bench.lle):.4g} 1/s")
    out.mkdir(parents=True, exist_ok=True)
    for name, fig in figures.items():
        path = out / f"{stem}-{name}.png"
        fig.savefig(path, dpi=120)
        print(f"figure: {path}")
    return 0 if np.isfinite(float(wolf.lle)) else 1


def register_cli(sub) -> None:
    """Add the ``analyse`` subcommand."""
    p = sub.add_parser(
        "analyse",
        help="chaos identification of one variable of a stored run (delay, dimension, LLEs)",
        description="Delay (AMI, ACF), embedding dimension (FNN, Cao), largest Lyapunov exponent "
        "(Wolf et al. 1985; Rosenstein via nolds; optionally from the equations), the 0-1 test "
        "on stroboscopic samples, with figures of the evidence.",
    )
    p.add_argument("run", help="netCDF run written by 'workbench run'")
    p.add_argument("--var", required=True, help="variable to analyse")
    p.add_argument(
        "--select",
        action="append",
        metavar="DIM=LABEL",
        help="pick one element of another dim, e.g. --select joint=A",
    )
    p.add_argument(
        "--equations",
        action="store_true",
        help="also compute the LLE from the equations of the stored scene (slow)",
    )
    p.add_argument("-o", "--output", default=".", metavar="DIR", help="directory for the PNGs")
    p.add_argument("--overwrite", action="store_true", help="replace existing figures")
    p.set_defaults(func=_cmd_analyse)
