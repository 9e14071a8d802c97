"""What the ``workbench`` command shows a person, shared by its subcommands: argument types that
refuse bad values in one line, warnings as one line per kind, the notice before a first compile, a
result written with its figure beside it, and the one line that says how many parts failed.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import sys
import time
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path

__all__ = [
    "add_quiet",
    "check_store_output",
    "compile_kernel",
    "compile_notice",
    "float_list",
    "max_memory_option",
    "memory_size",
    "one_line_warnings",
    "output_and_figure",
    "positive_float",
    "positive_int",
    "report_failures",
    "save_or_keep",
    "save_with_figure",
]


def positive_int(text: str) -> int:
    """argparse type: an integer >= 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"got {text!r}; allowed: an integer >= 1") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"got {value}; allowed: an integer >= 1")
    return value


def positive_float(text: str) -> float:
    """argparse type: a finite number > 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"got {text!r}; allowed: a number > 0") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"got {text!r}; allowed: a finite number > 0")
    return value


def float_list(text: str) -> list[float]:
    """argparse type: comma-separated finite numbers > 0, e.g. ``1e-4,1e-6``."""
    items = [t.strip() for t in text.split(",")]
    if not items or any(not t for t in items):
        raise argparse.ArgumentTypeError(
            f"got {text!r}; allowed: comma-separated numbers > 0, e.g. 1e-4,1e-6"
        )
    try:
        return [positive_float(t) for t in items]
    except argparse.ArgumentTypeError as exc:
        raise argparse.ArgumentTypeError(
            f"{exc} (in {text!r}; comma-separated numbers > 0, e.g. 1e-4,1e-6)"
        ) from None


@contextlib.contextmanager
def one_line_warnings(command: str) -> Iterator[None]:
    """Show the warnings raised inside, when it ends, one line per kind
    (:func:`workbench._warnings.warnings_by_kind`: alike but for their numbers, e.g. one per
    point of a campaign, with the count) as ``workbench COMMAND: warning: ...`` on stderr (not
    Python's file:line form with the source line)."""
    from workbench._warnings import warnings_by_kind

    def show(message, category, filename, lineno, file=None, line=None) -> None:
        text = " ".join(part.strip() for part in str(message).splitlines() if part.strip())
        print(f"workbench {command}: warning: {text}", file=sys.stderr)

    with warnings.catch_warnings():
        warnings.showwarning = show
        with warnings_by_kind():
            yield


def compile_kernel(scene, *, quiet: bool = False) -> float | None:
    """Compile the kernel of the scene's model before anything runs, when numba's cache does
    not hold it: say so on stderr first (:func:`compile_notice`: what a first run took where it
    was measured), while it runs how long it has lasted (:func:`workbench._progress.elapsed`),
    and after it how long it took (wall and CPU time). Returns the compile's wall time (s), or
    None when the kernel was cached (or cannot be told: e.g. a scipy method). ``quiet``: no
    messages."""
    from workbench.campaign._warm import kernel_cached, load_kernel

    if kernel_cached(scene) is not False:
        return None
    say = (lambda s: None) if quiet else (lambda s: print(s, file=sys.stderr, flush=True))
    say(compile_notice(scene.model))
    t0, cpu0 = time.perf_counter(), time.process_time()
    single = scene.replace(sweep={}) if scene.sweep else scene
    from workbench._progress import elapsed

    with contextlib.nullcontext() if quiet else elapsed(f"compiling the {scene.model} kernel"):
        load_kernel(single.to_toml())
    wall, cpu = time.perf_counter() - t0, time.process_time() - cpu0
    say(f"compiled the {scene.model} kernel in {wall:.0f} s ({cpu:.0f} s of CPU)")
    return wall


def compile_notice(model: str) -> str:
    """The line before a first compile: what the first run of ``model`` took where it was
    measured (:func:`workbench.campaign._warm.compile_record`: CPU and wall time, the machine's
    cores and load; Duffing's for a model not measured, named), and that the wall time grows
    with the load (this machine's now: its 1-minute load average)."""
    from workbench.campaign._warm import compile_record

    found = compile_record(model)
    if found is None:
        return f"compiling the {model} kernel (first run only; later runs load it from the cache)"
    measured, record = found
    low, high = sorted(round(x) for x in record["load"])
    load = f"{low}" if low == high else f"{low}-{high}"
    which = "" if measured == model else f" for the {measured} kernel"
    try:
        now = f", now {os.getloadavg()[0]:.0f}"
    except (AttributeError, OSError):  # pragma: no cover - no load average (Windows)
        now = ""
    return (
        f"compiling the {model} kernel (first run only; measured{which} on a "
        f"{record['cores']}-core machine at a load of {load}: {record['cpu_seconds']:.0f} s of "
        f"CPU, {record['wall_seconds']:.0f} s wall, the wall time growing with the machine's "
        f"load{now}; later runs load it from the cache)"
    )


def add_quiet(parser: argparse.ArgumentParser, what: str = "no progress and no notices") -> None:
    """The one ``-q/--quiet`` of every command: progress and notices on stderr off (errors,
    warnings and results stay)."""
    parser.add_argument("-q", "--quiet", action="store_true", help=f"quiet: {what}")


def check_store_output(output, store: str = ".blocks") -> None:
    """Check before any work the ``-o/--output`` of a command that keeps its finished work in a
    directory beside it (``OUTPUT.blocks/`` of a campaign or a chaos map, ``OUTPUT.runs/`` of a
    work-precision study): whether the output or that directory exists is the store's business
    (resume it, or refuse another computation); that both can be written is checked here
    (:func:`workbench.archive.check_output_file`, ``check_output_directory``)."""
    from workbench.archive import check_output_directory, check_output_file

    out = check_output_file(output, "-o/--output", overwrite=True)
    check_output_directory(
        out.with_name(out.name + store), f"-o/--output (its {store.lstrip('.')})", overwrite=True
    )


def output_and_figure(output, overwrite: bool) -> tuple[Path, Path]:
    """The netCDF file of ``-o/--output`` and the PNG beside it, both checked before any work
    (:func:`workbench.archive.check_output_file`)."""
    from workbench.archive import check_output_file

    out = check_output_file(output, "-o/--output", overwrite=overwrite)
    figure = check_output_file(
        out.with_suffix(".png"), "-o/--output (its figure)", overwrite=overwrite
    )
    return out, figure


def save_with_figure(
    ds, out: Path, figure: Path, what: str, draw: Callable, *, overwrite: bool = True
) -> None:
    """Write ``ds`` to ``out`` (:func:`save_or_keep`) and ``draw(ds)`` to ``figure``
    (:func:`workbench.archive.save_figure`), saying where each went."""
    from workbench.archive import save_figure

    save_or_keep(ds, out, overwrite=overwrite, what=what)
    print(f"{what} -> {out}")
    save_figure(draw(ds), figure, dpi=120, close=True)
    print(f"figure: {figure}")


def max_memory_option(parser: argparse.ArgumentParser, what: str) -> None:
    """Add ``--max-memory SIZE``: refuse before running when ``what`` would need more memory
    (default: the environment variable WORKBENCH_MAX_MEMORY, else half of the machine's)."""
    parser.add_argument(
        "--max-memory",
        type=memory_size,
        metavar="SIZE",
        help=f"refuse to start when {what} would take more memory than SIZE (e.g. '16GiB'; "
        "default: $WORKBENCH_MAX_MEMORY, else half of this machine's memory)",
    )


def memory_size(text: str) -> float:
    """argparse type: a size in bytes, e.g. ``16GiB``, ``500MB``, ``2e9``, ``inf``."""
    from workbench.run import parse_bytes

    try:
        return parse_bytes(text, "SIZE")
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc).removeprefix("SIZE: ")) from None


def save_or_keep(ds, output, *, overwrite: bool, what: str) -> Path:
    """Write a computed dataset to ``output`` (atomically; replacing a regular file there only
    with ``overwrite``). When that fails for any reason (a full disk, a directory that refuses
    the file, an input/output error: :class:`workbench.archive.WriteFailed`), write it where
    there is room and say where in the error; a file that appeared at ``output`` meanwhile is
    never replaced (the result is kept beside it, :class:`workbench.archive.OutputExists` says
    where)."""
    from workbench.archive import ArchiveError, WriteFailed, keep_elsewhere, save_run

    try:
        return save_run(ds, output, overwrite=overwrite)
    except WriteFailed as exc:
        kept = keep_elsewhere(lambda p: save_run(ds, p, overwrite=False), output, ds.nbytes)
        where = (
            f"the computed {what} was kept at {str(kept)!r}"
            if kept is not None
            else f"no other place (the temporary, home or working directory) could take the "
            f"computed {what} either: it is lost"
        )
        raise ArchiveError(f"{exc}; {where}") from None


def report_failures(command: str, failures: str, code: int) -> None:
    """Say on stderr ``workbench COMMAND: FAILURES; exit code CODE`` (``failures`` says how
    many of what failed)."""
    print(f"workbench {command}: {failures}; exit code {code}", file=sys.stderr)
