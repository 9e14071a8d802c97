"""``workbench analyse``: chaos identification of one variable of a stored run."""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path

from workbench.cli._console import add_quiet, positive_int
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


def _before_failure(ds, da, run: str):
    """A failed run's series cut to its records before the failure (the records after it are
    NaN), and the line that says so; a run that did not fail: the series as it is and ''."""
    import numpy as np

    from workbench.solver import Status

    label = ds.attrs.get("run_status")
    if label is None:
        return da, ""
    try:
        status = Status.from_label(str(label))
    except ValueError:
        raise UsageError(
            f"{run!r} has run_status {label!r}, which is not a status of workbench "
            f"({', '.join(s.label for s in Status)}); analyse a run written by 'workbench run'"
        ) from None
    if not status.failed:
        return da, ""
    finite = np.isfinite(da.values)
    n = int(finite.argmin()) if not finite.all() else finite.size
    if n == 0:
        raise UsageError(
            f"{run!r} is a failed run (status {status.label}) with no finite record of "
            f"{da.name!r}: nothing to analyse; {ds.attrs.get('run_message', '')}".rstrip("; ")
        )
    part = da.isel(time=slice(0, n))
    rest = da.sizes["time"] - n
    left_out = f"; the {rest} records after it (NaN) are left out" if rest else ""
    return part, (
        f"the run failed (status {status.label}): only its {n} records before the failure "
        f"(t = {float(part.time[0]):.6g} to {float(part.time[-1]):.6g} s) are "
        f"analysed{left_out}"
    )


def _surrogates(text: str) -> int:
    """argparse type of --surrogates: 0 or a whole number >= 19."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value != 0 and value < 19:
        raise argparse.ArgumentTypeError(
            f"got {text!r}; allowed: 0 (no noise test) or a whole number >= 19"
        )
    return value


def _units(da) -> str:
    """Units as a person reads them: 1/s for s-1, "per sample" for 1."""
    return {"s-1": "1/s", "1": "per sample"}.get(da.attrs.get("units", ""), da.attrs["units"])


def _reliability_lines(wolf) -> list[str]:
    """The Wolf estimate's flag and its reasons, one per line."""
    if int(wolf.reliable):
        return ["  reliable: yes (sampling, length, Cao's E2 and the surrogate test pass)"]
    reasons = wolf.reliable.attrs["reasons"].splitlines()
    return ["  reliable: NO, flagged:"] + [f"    - {r}" for r in reasons]


def _surrogate_line(wolf) -> str:
    flag = int(wolf.surrogate_stochastic)
    if flag < 0:
        return "  surrogate test: not run (the estimate is not positive, or --surrogates 0)"
    es = wolf.surrogate_error.values
    verdict = "not told from linear noise" if flag else "deterministic"
    error = float(wolf.prediction_error)
    return (
        f"  surrogate test: {verdict} (nonlinear prediction error {error:.3g} against "
        f"{es.min():.3g}-{es.max():.3g} for {es.size} IAAFT surrogates)"
    )


def _cmd_analyse(args: argparse.Namespace) -> int:
    from workbench import analysis, plot
    from workbench.archive import check_output_directory, open_run, save_figure
    from workbench.scene import scene_from_toml

    ds = open_run(args.run)
    if "campaign_dims" in ds.attrs:
        raise UsageError(
            f"{args.run!r} is a campaign; 'workbench analyse' takes one run (written by "
            "'workbench run')"
        )
    scene = None
    if args.equations:  # the stored scene is data: it imports only a module trusted here
        scene = scene_from_toml(ds.attrs["scene"], trust_modules=args.trust_module or ())
    da = _series(ds, args.var, args.select or [])
    label = args.var + "".join(f"[{s}]" for s in args.select or [])
    da, failure = _before_failure(ds, da, args.run)
    if failure:
        print(f"{label}: {failure}")
        ds = ds.isel(time=slice(0, da.sizes["time"]))  # the strobe samples too
    try:
        verdict = analysis.no_dynamics(da)
    except ValueError as exc:  # e.g. a non-finite value in a run that did not fail
        raise UsageError(f"--var {label}: {exc}") from None
    if verdict:  # nothing to estimate: say so at once, write nothing
        print(verdict.replace(f"{da.name} ", f"{label} ", 1))
        return 0
    period = ds.attrs.get("forcing_period")
    strobe = None
    if period is not None and ds.attrs.get("samples_per_period"):
        strobe = analysis.poincare_section(ds.assign(_v=da), "_v")["_v"]
    stem = label.replace("[", "-").replace("]", "").replace("=", "")
    names = ["embedding", "lle"] + (["zero_one"] if strobe is not None else [])
    out = check_output_directory(
        "." if args.output is None else args.output,
        "-o/--output",
        [f"{stem}-{n}.png" for n in names],
        overwrite=args.overwrite,
    )
    flow = {"auto": None, "flow": True, "map": False}[args.kind]
    try:  # the API's automatic choices, unless overridden
        wolf = analysis.wolf_lle(
            da,
            delay=args.delay,
            dim=args.dim,
            flow=flow,
            period=period,
            surrogates=args.surrogates,
        )
        ros = analysis.rosenstein_lle(
            da, delay=int(wolf.delay), dim=int(wolf.dim), theiler=int(wolf.theiler)
        )
    except ValueError as exc:  # the estimators name what the series lacks
        raise UsageError(f"--var {label}: {exc}") from None
    chosen = wolf.attrs["chosen"].split(", ")

    def how(name: str, rule: str) -> str:
        return rule if name in chosen else "given"

    kind = wolf.attrs["series_kind"]
    print(f"{label}: {da.size} samples, dt = {float(da.time[1] - da.time[0]):.4g} s")
    print(
        f"  series: {kind} ({how('flow', 'detected')}; smoothness {float(wolf.smoothness):.2f}, "
        f"{float(wolf.samples_per_period):.1f} samples per mean period)"
    )
    delay_rule = "first minimum of the AMI" if kind == "sampled flow" else "a map: one step"
    delay = int(wolf.delay)
    print(f"  delay: {delay} sample{'s' if delay > 1 else ''} ({how('delay', delay_rule)})")
    print(
        f"  embedding dimension: {int(wolf.dim)} ({how('dim', 'false nearest neighbours')}; "
        f"Cao E1: {int(wolf.cao_dim)})"
    )
    per = f" = {float(wolf.lle_per_period):.4g} per forcing period" if period else ""
    print(
        f"  Wolf LLE: {float(wolf.lle):.4g} {_units(wolf.lle)}{per} "
        f"({int(wolf.replacements)} replacements)"
    )
    print("\n".join(_reliability_lines(wolf)))
    print(_surrogate_line(wolf))
    print(f"  Rosenstein LLE (nolds, same embedding): {float(ros.lle):.4g} {_units(ros.lle)}")
    equations = None
    if args.equations:
        with warnings.catch_warnings():  # its failed conditions are printed below
            warnings.simplefilter("ignore", analysis.ConvergenceWarning)
            bench = analysis.lle_from_equations(scene)
        equations = float(bench.lle)
        verdict = "converged" if bool(bench.converged) else "not converged"
        print(
            f"  LLE from the equations (Benettin): {equations:.4g} +/- "
            f"{float(bench.stderr):.2g} 1/s, {verdict}"
        )
        for line in bench.attrs["failed"].splitlines():
            print(f"    {line}")
    figures = {
        "embedding": plot.embedding_figure(wolf),
        "lle": plot.lle_figure(wolf, float(ros.lle), label, equations=equations),
    }
    if strobe is not None:
        if strobe.sizes["strobe"] >= 100:
            z = analysis.zero_one_test(strobe)
            print(f"  0-1 test on {strobe.sizes['strobe']} strobe samples: K = {float(z.K):.3f}")
            figures["zero_one"] = plot.zero_one_figure(z)
        else:
            print(f"  0-1 test: skipped ({strobe.sizes['strobe']} strobe samples, needs 100)")
    for name, fig in figures.items():
        path = save_figure(fig, out / f"{stem}-{name}.png", dpi=120)
        print(f"figure: {path}")
    if args.output is None:  # said, since no option named the place
        print(f"figures written to the current directory, {Path.cwd()} (-o DIR for another)")
    return 0


def register_cli(sub) -> None:
    """Add the ``analyse`` subcommand."""
    p = sub.add_parser(
        "analyse",
        help="chaos identification of one variable of a stored run (delay, dimension, LLEs)",
        description="The largest Lyapunov exponent of one variable by Wolf et al. (1985) with "
        "the API's automatic choices (map or flow, delay by the AMI, dimension by false nearest "
        "neighbours; override them with --kind, --delay, --dim), its reliability flag and "
        "reasons, a surrogate test for noise (Theiler et al. 1992), Rosenstein's estimate "
        "(nolds) in the same embedding, optionally the LLE from the equations, the 0-1 test on "
        "stroboscopic samples, and figures of the evidence. A series with no dynamics "
        "(constant, parked at one value, a few repeated values) gets that verdict at once.",
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
        "--kind",
        choices=("auto", "flow", "map"),
        default="auto",
        help="the series samples a flow or iterates a map (default: detected)",
    )
    p.add_argument("--delay", type=positive_int, help="embedding delay, samples (default: chosen)")
    p.add_argument("--dim", type=positive_int, help="embedding dimension (default: chosen)")
    p.add_argument(
        "--surrogates",
        type=_surrogates,
        default=19,
        metavar="N",
        help="IAAFT surrogates of the noise test (default 19: 5 %% level; 0: no test)",
    )
    p.add_argument(
        "--equations",
        action="store_true",
        help="also compute the LLE from the equations of the stored scene (slow)",
    )
    p.add_argument(
        "--trust-module",
        action="append",
        metavar="NAME",
        help="with --equations: let the stored scene import its [model] module NAME (it runs "
        "that module's code; from the import path or the working directory); repeatable",
    )
    p.add_argument(
        "-o", "--output", metavar="DIR", help="directory for the PNGs (default: the current one)"
    )
    p.add_argument("--overwrite", action="store_true", help="replace existing figures")
    add_quiet(p, "accepted by every command; this one prints only its results")
    p.set_defaults(func=_cmd_analyse)
