"""What the ``workbench`` command shows a person, shared by its subcommands: argument types that
refuse bad values in one line, warnings as one line each, the notice before a first compile, a
result written with its figure beside it, and the one line that says how many parts failed.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path

__all__ = [
    "announce_compile",
    "float_list",
    "one_line_warnings",
    "output_and_figure",
    "positive_float",
    "positive_int",
    "report_failures",
    "save_with_figure",
]

# Measured with a cold cache on the shared 2-core machine (load ~5): duffing 15 s, ninebar and
# slider_crank 28 s; the issue reports 25-60 s for the mechanisms.
_COMPILE_SECONDS = {"ninebar": "~30-60 s", "slider_crank": "~30-60 s"}  # others ~15-30 s


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


def announce_compile(scene, out: Callable[[str], None] | None = None) -> bool:
    """Print "compiling the <model> kernel (first run only, ...)" to stderr when the cache does
    not hold it; return whether it was printed."""
    from workbench.campaign._warm import kernel_cached

    if kernel_cached(scene) is not False:
        return False
    seconds = _COMPILE_SECONDS.get(scene.model, "~15-30 s")
    text = (
        f"compiling the {scene.model} kernel (first run only, {seconds}; later runs load it "
        "from the cache)"
    )
    (out or (lambda s: print(s, file=sys.stderr, flush=True)))(text)
    return True


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
