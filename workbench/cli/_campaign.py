"""``workbench campaign``: a scene's sweep in parallel, into one resumable netCDF archive."""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path

from workbench.cli._console import (
    add_quiet,
    max_memory_option,
    positive_float,
    positive_int,
    report_failures,
)
from workbench.cli._exit_codes import UsageError, worst_exit_code

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
    import numpy as np

    from workbench.campaign import CampaignError, expand_sweep, run_campaign, summary
    from workbench.campaign._block import STATUS, failed
    from workbench.campaign._grid import MAX_POINTS, check_points
    from workbench.campaign._store import Store
    from workbench.cli._console import check_store_output, compile_kernel
    from workbench.scene import load_scene

    scene = load_scene(args.scene)
    if scene.continuation:
        _check_continued(args)
    if args.scheduler and args.workers is not None:
        raise CampaignError(
            f"--workers {args.workers} sizes the local pool, but --scheduler "
            f"{args.scheduler!r} brings its own workers; give one of them"
        )
    check_store_output(args.output)
    max_points = MAX_POINTS if args.max_points is None else args.max_points
    if not scene.continuation:
        check_points(expand_sweep(scene), max_points)  # before a kernel is compiled
    client = None
    try:
        if args.scheduler:
            # the dashboard link is a notice: run_campaign (continued_sweep) prints it above its
            # progress bar unless -q
            client = _client(args.scheduler, args.scheduler_timeout)
        else:
            compile_kernel(scene, quiet=args.quiet)
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
                    max_memory=args.max_memory,
                    max_points=max_points,
                )
    except KeyboardInterrupt as exc:
        kept = Store(args.output).kept_note()
        if kept:
            exc.add_note(f"{kept}: run the same command again to compute the rest")
        raise
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


def _check_continued(args: argparse.Namespace) -> None:
    """Refuse, before any work, the options a continued sweep (``[sweep] continuation``) does
    not take: ``--chunk`` (segments, not chunks, make its tasks), ``--max-memory`` and
    ``--max-points`` (:func:`workbench.continuation.continued_sweep` takes neither limit)."""
    if args.chunk is not None:
        raise UsageError(
            f"--chunk {args.chunk}: a continued sweep ([sweep] continuation) is cut into "
            "segments, not chunks; set sweep.continuation.segments in the scene instead"
        )
    if args.max_memory is not None:
        from workbench.run import format_bytes

        raise UsageError(
            f"--max-memory {format_bytes(args.max_memory)}: a continued sweep ([sweep] "
            "continuation) takes no memory limit; drop --max-memory (each point's run is still "
            "checked against $WORKBENCH_MAX_MEMORY, else half of the machine's memory)"
        )
    if args.max_points is not None:
        raise UsageError(
            f"--max-points {args.max_points}: a continued sweep ([sweep] continuation) takes "
            "no limit on its points; drop --max-points"
        )


def _continued(scene, args: argparse.Namespace, client):
    """A continued sweep (``[sweep] continuation``; its options checked by
    :func:`_check_continued`)."""
    from workbench.continuation import continued_sweep

    return continued_sweep(
        scene,
        args.output,
        client=client,
        workers=args.workers,
        restart=args.restart,
        progress=not args.quiet,
    )


def campaign_exit_code(flags) -> int:
    """The largest exit code among a campaign's point flags (a run's Status;
    invalid_parameters: invalid input; error: the point raised an exception)."""
    from workbench.campaign._block import INVALID, RAISED

    return worst_exit_code(flags, INVALID, RAISED)


def register_cli(sub) -> None:
    """Add the ``campaign`` subcommand."""
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
    add_quiet(p)
    max_memory_option(
        p, "the campaign's archive (or one point's records; not with [sweep] continuation)"
    )
    p.add_argument(
        "--max-points",
        type=positive_int,
        metavar="N",
        # the default is workbench.campaign's MAX_POINTS
        # (tests/package/test_public_surfaces.py), not
        # imported here: `workbench --help` loads no numerical library
        help="refuse a [sweep] grid of more than N points, before any work (default 1000000; "
        "not with [sweep] continuation)",
    )
    p.set_defaults(func=_cmd_campaign)
