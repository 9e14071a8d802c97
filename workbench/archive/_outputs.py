"""Output paths checked before any work starts: a file to write, or a directory of files."""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

from workbench.archive._atomic import remove_stale_temporaries
from workbench.archive._integrity import ArchiveError

__all__ = ["check_output_directory", "check_output_file"]


def _check_parents(path: Path, argument: str) -> None:
    """ArchiveError if an existing ancestor of ``path`` is not a directory or not writable."""
    for parent in path.parents:
        if parent.exists():
            if not parent.is_dir():
                raise ArchiveError(
                    f"{argument}: cannot write {str(path)!r}: {str(parent)!r} is a file, not a "
                    "directory; choose a path whose parents are directories"
                )
            if not os.access(parent, os.W_OK | os.X_OK):
                raise ArchiveError(
                    f"{argument}: cannot write {str(path)!r}: the directory {str(parent)!r} is "
                    "not writable; choose another path"
                )
            return


def check_output_file(
    path: str | os.PathLike, argument: str, *, overwrite: bool = False, flag: str = "--overwrite"
) -> Path:
    """Check, before any work, that a file can be written at ``path``; remove the temporary
    files that writers of ``path`` killed mid-write left beside it
    (:func:`workbench.archive.remove_stale_temporaries`).

    Parameters
    ----------
    path : str or PathLike
        The file to write.
    argument : str
        The argument that gave it, for the message (e.g. ``"-o/--output"``).
    overwrite : bool
        Allow replacing an existing file.
    flag : str
        The option that allows replacing it, for the message.

    Returns
    -------
    Path

    Raises
    ------
    ArchiveError
        ``path`` is a directory, lies under a file or an unwritable directory, or exists and
        ``overwrite`` is false; the message names the argument, the value and what is allowed.
    """
    path = Path(path)
    if path.is_dir():
        raise ArchiveError(
            f"{argument}: {str(path)!r} is a directory; give the path of a file to write "
            f"(e.g. {str(path / 'out.nc')!r})"
        )
    _check_parents(path, argument)
    if path.parent.is_dir():
        remove_stale_temporaries(path)  # of a writer killed before (named in a warning)
    if path.exists() and not overwrite:
        raise ArchiveError(
            f"{argument}: {str(path)!r} exists; pass {flag} to replace it, or choose another path"
        )
    return path


def check_output_directory(
    directory: str | os.PathLike,
    argument: str,
    names: Iterable[str] = (),
    *,
    overwrite: bool = False,
    flag: str = "--overwrite",
) -> Path:
    """Check, before any work, that the files ``names`` can be written into ``directory``.

    Raises
    ------
    ArchiveError
        ``directory`` is a file or lies under one, or one of the files exists and
        ``overwrite`` is false (the message names them).
    """
    directory = Path(directory)
    if directory.exists() and not directory.is_dir():
        raise ArchiveError(
            f"{argument}: {str(directory)!r} is a file; give a directory for the figures"
        )
    _check_parents(directory / "_", argument)
    existing = [n for n in names if (directory / n).exists()]
    if existing and not overwrite:
        shown = ", ".join(repr(n) for n in existing[:4]) + (" ..." if len(existing) > 4 else "")
        raise ArchiveError(
            f"{argument}: {str(directory)!r} already holds {shown}; pass {flag} to replace "
            "them, or choose another directory"
        )
    return directory
