"""``workbench study``: run the paper's studies and write the comparison report."""

from __future__ import annotations

import argparse
import json
import os
import sys
import time as _time
from pathlib import Path

from workbench.cli._console import add_quiet, compile_kernel, positive_int, report_failures
from workbench.cli._exit_codes import UsageError, worst_exit_code


def _failed_runs(ds) -> tuple[int, int]:
    """Failed runs of a study (read from its case archives) and their worst exit code."""
    from workbench.archive import open_run
    from workbench.campaign._block import INVALID, RAISED, failed

    n, code = 0, 0
    for archive in json.loads(ds.attrs["archives"]).values():
        status = open_run(archive)["status"].values
        n += int(failed(status).sum())
        code = max(code, worst_exit_code(status, INVALID, RAISED))
    return n, code


def _cmd_study(args: argparse.Namespace) -> int:
    from workbench.study import available_studies, load_study, run_study, write_report

    if args.no_progress:
        print(
            "workbench study: warning: --no-progress is deprecated; use -q (--quiet), as every "
            "command does",
            file=sys.stderr,
        )
        args.quiet = True
    if args.name == "report":
        print(f"report: {write_report(args.output)}")
        return 0
    if args.name == "list":
        for name in available_studies():
            print(name)
        return 0
    names = available_studies() if args.name == "all" else [args.name]
    unknown = [n for n in names if n not in available_studies() and not Path(n).is_dir()]
    if unknown:
        raise UsageError(
            f"no study {unknown[0]!r}; available: {', '.join(available_studies())} (or 'all', "
            "'report', 'list', or the directory of a study)"
        )
    from workbench.archive import check_output_directory

    # each study's files (archives, figures, summary) go to OUTPUT/NAME/, replaced as it reruns
    check_output_directory(args.output, "-o/--output", overwrite=True)
    t_all = _time.perf_counter()
    runs, n_failed, code = 0, 0, 0
    for name in names:
        t0 = _time.perf_counter()
        for scene in load_study(name).cases.values():  # a cold cache: say so, then compile
            compile_kernel(scene, quiet=args.quiet)
        ds = run_study(
            name,
            out=args.output,
            quick=args.quick,
            workers=args.workers,
            progress=not args.quiet,
        )
        runs += int(ds.attrs["runs"])
        failed, worst = _failed_runs(ds)
        n_failed, code = n_failed + failed, max(code, worst)
        verdicts = [str(v) for v in ds["claim_verdict"].values] if "claim" in ds.dims else []
        counts = ", ".join(
            f"{verdicts.count(v)} {v}" for v in ("reproduced", "contradicted", "not resolved")
        )
        print(
            f"{name}: {ds.attrs['runs']} runs ({ds.attrs['realisations']} realisation(s) per "
            f"case), {failed} failed, claims: {counts}, {_time.perf_counter() - t0:.1f} s -> "
            f"{args.output}/{name}/"
        )
    if args.name == "all":
        print(f"report: {write_report(args.output)}")
    workers = args.workers or os.cpu_count()
    print(
        f"{len(names)} stud{'y' if len(names) == 1 else 'ies'}: {runs} runs on {workers} "
        f"workers, {_time.perf_counter() - t_all:.1f} s"
    )
    if code:
        report_failures(
            "study",
            f"{n_failed} of {runs} runs failed (their status and message are in the case archives)",
            code,
        )
    return code


def register_cli(sub) -> None:
    """Add the ``study`` subcommand."""
    p = sub.add_parser(
        "study",
        help="run a study of the paper (or 'all'; 'report' writes the report)",
        description="Run one of the paper's studies (scenes under studies/NAME/): archives, "
        "figures named for the paper's figures, and a summary of paper values and claims. "
        "NAME 'all' runs every study and writes the report; 'report' only writes the report "
        "from the summaries stored under OUTPUT; 'list' lists the studies. The report goes to "
        "studies/REPORT.md in a repository checkout, else (an installed package) to "
        "OUTPUT/REPORT.md; the command prints where.",
    )
    p.add_argument("name", help="study name, 'all', 'report' or 'list'")
    p.add_argument("-o", "--output", default="out/studies", help="directory (default out/studies)")
    p.add_argument(
        "--quick",
        action="store_true",
        help="much shorter runs, at most 4 realisations (smoke test only)",
    )
    p.add_argument(
        "--workers", type=positive_int, help="processes for campaign cases (default: all)"
    )
    add_quiet(p)
    # the flag before -q, kept for old scripts (deprecated: says so when used)
    p.add_argument("--no-progress", action="store_true", help=argparse.SUPPRESS)
    p.set_defaults(func=_cmd_study)
