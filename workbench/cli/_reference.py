"""The command-line reference page, ``docs/cli.md``, written from the argument parsers
(:func:`workbench.cli.build_parser`): every command's description, usage and arguments, as
``workbench COMMAND --help`` shows them. ``python -m workbench.cli._reference`` rewrites the
page; ``tests/cli/test_cli.py`` holds the committed page to what the parsers say now.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

__all__ = ["PAGE", "reference_page"]

#: the page, from the repository's root
PAGE = Path("docs") / "cli.md"
_WIDTH = 100  # of the usage lines (argparse wraps them to the terminal's width otherwise)


def _subparsers(parser: argparse.ArgumentParser) -> argparse._SubParsersAction:
    return next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))


def _usage(parser: argparse.ArgumentParser) -> str:
    formatter = argparse.HelpFormatter(parser.prog, width=_WIDTH)
    formatter.add_usage(parser.usage, parser._actions, parser._mutually_exclusive_groups)
    return formatter.format_help().strip()


def _cell(text: str) -> str:
    """Text for a Markdown table cell: on one line, with ``|`` escaped."""
    return " ".join(text.split()).replace("|", "\\|")


def _argument(parser: argparse.ArgumentParser, action: argparse.Action) -> str:
    """How an argument is written (``-o OUTPUT``, ``--overwrite``, ``scene``), in code."""
    formatter = argparse.HelpFormatter(parser.prog, width=_WIDTH)
    if not action.option_strings:
        return f"`{formatter._format_args(action, action.dest)}`"
    if action.nargs == 0:
        return ", ".join(f"`{s}`" for s in action.option_strings)
    metavar = formatter._format_args(action, formatter._get_default_metavar_for_optional(action))
    return ", ".join(f"`{s} {metavar}`" for s in action.option_strings)


def _help(parser: argparse.ArgumentParser, action: argparse.Action) -> str:
    """An argument's help text as ``--help`` shows it (``%(default)s`` and ``%%`` expanded),
    with its choices and whether it is required."""
    formatter = argparse.HelpFormatter(parser.prog, width=_WIDTH)
    text = formatter._expand_help(action) if action.help else ""
    if action.choices is not None and action.metavar is not None:  # else the metavar shows them
        text += f" (one of: {', '.join(str(c) for c in action.choices)})"
    if action.required and action.option_strings:
        text += " (required)"
    return _cell(text)


def _command(name: str, summary: str, parser: argparse.ArgumentParser) -> list[str]:
    lines = [f"## {name}", "", _cell(parser.description or summary), ""]
    lines += ["```text", _usage(parser), "```", ""]
    rows = [
        f"| {_argument(parser, a)} | {_help(parser, a)} |"
        for a in parser._actions
        if a.help != argparse.SUPPRESS and not isinstance(a, argparse._HelpAction)
    ]
    if rows:
        lines += ["| argument | meaning |", "|---|---|", *rows, ""]
    return lines


def _exit_code_table() -> str:
    """The table of exit codes in the docstring of :mod:`workbench.cli._exit_codes`."""
    from workbench.cli import _exit_codes

    lines = (_exit_codes.__doc__ or "").splitlines()
    rules = [i for i, line in enumerate(lines) if line.startswith("====")]
    return "\n".join(lines[rules[0] : rules[-1] + 1])


def reference_page(parser: argparse.ArgumentParser | None = None) -> str:
    """The text of ``docs/cli.md`` for ``parser`` (default :func:`workbench.cli.build_parser`)."""
    from workbench.cli import build_parser

    parser = build_parser() if parser is None else parser
    sub = _subparsers(parser)
    summaries = {a.dest: a.help or "" for a in sub._choices_actions}
    lines = [
        "# Command line",
        "",
        "<!-- Written by `python -m workbench.cli._reference` from the argument parsers; do not",
        "edit by hand: tests/cli/test_cli.py fails when this page and the parsers differ. -->",
        "",
        _cell(parser.description or ""),
        "",
        "```text",
        _usage(parser),
        "```",
        "",
        "| command | what it does |",
        "|---|---|",
        *(f"| [`{name}`](#{name}) | {_cell(summaries[name])} |" for name in sub.choices),
        "",
        "Every command takes `-h` (`--help`: its text as below) and `-q` (`--quiet`: no progress",
        "and no notices on stderr; errors, warnings and results stay). An expected error is one",
        "line on stderr that names what is wrong. Exit codes (`workbench.cli._exit_codes`):",
        "",
        "```text",
        _exit_code_table(),
        "```",
        "",
    ]
    for name, command in sub.choices.items():
        lines += _command(name, summaries[name], command)
    return "\n".join(lines).rstrip("\n") + "\n"


def main(argv: list[str] | None = None) -> int:
    """``python -m workbench.cli._reference [PATH]``: write the page (default ``docs/cli.md``,
    from the repository's root)."""
    args = sys.argv[1:] if argv is None else argv
    path = Path(args[0]) if args else PAGE
    path.write_text(reference_page())
    print(f"command-line reference -> {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
