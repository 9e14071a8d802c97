"""What the ``workbench`` command shows a person, shared by its subcommands: argument types that
refuse bad values in one line, warnings as one line each, the notice before a first compile, a
result written with its figure beside it, and the one line that says how many parts failed.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
import time
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path

__all__ = [
    "add_quiet",
    "compile_kernel",
    "float_list",
    "one_line_warnings",
    "output_and_figure",
    "positive_float",
    "positive_int",
    "report_failures",
    "save_with_figure",
]

# What the first compile of a model's kernel took, measured with a cold cache on the shared
# 2-core machine: Duffing 15 s and the mechanisms 28 s at a load of 5; the mechanisms 74-95 s
# when more processes than cores were running. It is CPU-bound: it scales with the
# share of a core the process gets.
_COMPILE_SECONDS = {"ninebar": "30-95 s", "slider_crank": "30-95 s"}  # the others 15-40 s


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
    """Show each warning raised inside as one line ``workbench COMMAND: warning: ...`` on
    stderr (not Python's file:line form with the source line), and each distinct one once."""

    def show(message, category, filename, lineno, file=None, line=None) -> None:
        print(f"workbench {command}: warning: {message}", file=sys.stderr)

    with warnings.catch_warnings():
        warnings.showwarning = show
        yield


def compile_kernel(scene, *, quiet: bool = False) -> float | None:
    """Compile the kernel of the scene's model before anything runs, when numba's cache does
    not hold it: say so on stderr first ("compiling the <model> kernel ..."), with what it
    depends on, and after it how long it took. Returns the compile's wall time (s), or None
    when the kernel was cached (or cannot be told: e.g. a scipy method). ``quiet``: no
    messages."""
    from workbench.campaign._warm import kernel_cached, load_kernel

    if kernel_cached(scene) is not False:
        return None
    seconds = _COMPILE_SECONDS.get(scene.model, "15-40 s")
    say = (lambda s: None) if quiet else (lambda s: print(s, file=sys.stderr, flush=True))
    say(
        f"compiling the {scene.model} kernel (first run only: measured {seconds} on a 2-core "
        "machine, longer when other processes share the CPU; later runs load it from the cache)"
    )
    t0 = time.perf_counter()
    single = scene.replace(sweep={}) if scene.sweep else scene
    load_kernel(single.to_toml())
    wall = time.perf_counter() - t0
    say(f"compiled the {scene.model} kernel in {wall:.0f} s")
    return wall


def add_quiet(parser: argparse.ArgumentParser, what: str = "no progress and no notices") -> None:
    """The one ``-q/--quiet`` of every command: progress and notices on stderr off (errors,
    warnings and results stay)."""
    parser.add_argument("-q", "--quiet", action="store_true", help=f"quiet: {what}")


def output_and_figure(output, overwrite: bool) -> tuple[Path, Path]:
    """The netCDF file of ``-o/--output`` and the PNG beside it, both checked before any work
    (:func:`workbench.archive.check_output_file`)."""
    from workbench.archive import check_output_file

    out = check_output_file(output, "-o/--output", overwrite=overwrite)
    figure = check_output_file(
        out.with_suffix(".png"), "-o/--output (its figure)", overwrite=overwrite
    )
    return out, figure


def save_with_figure(ds, out: Path, figure: Path, what: str, draw: Callable) -> None:
    """Write ``ds`` to ``out`` and ``draw(ds)`` to ``figure``, saying where each went."""
    from workbench.archive import save_run

    save_run(ds, out)
    print(f"{what} -> {out}")
    draw(ds).savefig(figure, dpi=120)
    print(f"figure: {figure}")


def report_failures(command: str, failures: str, code: int) -> None:
    """Say on stderr ``workbench COMMAND: FAILURES; exit code CODE`` (``failures`` says how
    many of what failed)."""
    print(f"workbench {command}: {failures}; exit code {code}", file=sys.stderr)
