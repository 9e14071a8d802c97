"""Command line: ``workbench run | plot | ...`` (``workbench --help`` lists every command).

The command line is one layer, the top one: this package holds the entry point (:func:`main`),
the console helpers (``_console``), the exit codes (``_exit_codes``) and one module per command
(``_run``, ``_plot``, ``_accuracy``, ``_campaign``, ``_bifurcation``, ``_orbit``, ``_chaos_map``,
``_study``, ``_analyse``, ``_verify``, ``_kernel``), and the writer of its reference page
``docs/cli.md`` (``_reference``); nothing else in workbench imports it. The command modules
import the numerical libraries (numba, xarray, dask, matplotlib) when a command runs, not when
the parser is built: ``workbench --help`` starts at once.

Exit codes: :mod:`workbench.cli._exit_codes` (0 ok, 2 invalid input, 3 max_steps, 4 step_underflow
or non_finite, 5 model_failure, 130 interrupted, 143 terminated by SIGTERM).
"""

from __future__ import annotations

import argparse
import importlib
import sys

from workbench._errors import WorkbenchError
from workbench._version import FORMAT_VERSION, __version__
from workbench.cli._console import one_line_warnings
from workbench.cli._exit_codes import exit_code
from workbench.cli._signals import Terminated, signals_as_interrupts


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line (``workbench CMD: error: ...``, exit code
    2), without the usage block; ``--help`` shows the usage."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``workbench`` command."""
    parser = _Parser(
        prog="workbench",
        description="Nonlinear dynamics of mechanisms with clearance joints: run scenes, "
        "campaigns and analyses; results are netCDF files and PNG figures.",
    )
    parser.add_argument(
        "--version",
        action="version",
        version=f"workbench {__version__} (archive format {FORMAT_VERSION})",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    for module in _COMMAND_MODULES:
        importlib.import_module(module).register_cli(sub)
    return parser


# One module per command (or pair of commands): each defines ``register_cli(subparsers)``; the
# order is the order of ``workbench --help``.
_COMMAND_MODULES: tuple[str, ...] = (
    "workbench.cli._run",
    "workbench.cli._plot",
    "workbench.cli._accuracy",
    "workbench.cli._campaign",
    "workbench.cli._bifurcation",
    "workbench.cli._orbit",
    "workbench.cli._chaos_map",
    "workbench.cli._study",
    "workbench.cli._analyse",
    "workbench.cli._verify",
    "workbench.cli._kernel",
)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``workbench`` console script; returns the exit code
    (:func:`workbench.cli._exit_codes.exit_code`: 0 ok, 2 invalid input, 3-5 failed runs, 130
    interrupted, 143 SIGTERM). Expected errors (every :class:`workbench.WorkbenchError`: a
    scene, an argument, a file, a store, a failed run) are one line on stderr that names what is
    wrong; warnings are one line each."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        with signals_as_interrupts(), one_line_warnings(args.command):
            return args.func(args)
    except WorkbenchError as exc:  # refused input (exit code 2), a failed run (3-5), other: 1
        print(f"workbench {args.command}: error: {exc}", file=sys.stderr)
        return exit_code(exc)
    except FileNotFoundError as exc:
        print(f"workbench {args.command}: error: no such file: {exc.filename!r}", file=sys.stderr)
        return exit_code(exc)
    except KeyboardInterrupt as exc:
        how = f"terminated by {exc.name}" if isinstance(exc, Terminated) else "interrupted"
        notes = "".join(f"; {n}" for n in getattr(exc, "__notes__", ()))
        print(f"workbench {args.command}: {how}{notes}", file=sys.stderr)
        return exit_code(exc)
