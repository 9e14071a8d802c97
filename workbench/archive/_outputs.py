"""Output paths checked before any work starts: a file to write, or a directory of files.

Every command checks every file and figure folder it will write with these two functions
before it runs anything, so that a run is never computed only to find its output unwritable:

- the nearest existing ancestor of the path is a directory in which a file can be created
  (tried: a file is made and removed at once, which is what counts on a read-only file
  system, in ``/proc`` or ``/sys``, or for root, whom permission bits do not stop);
- the path is not a directory, and not a device, FIFO, socket or a symbolic link to one: such
  a path is refused whether or not ``--overwrite`` is given (``--overwrite`` replaces only a
  regular file);
- without ``--overwrite``, nothing is at the path.

The messages name the argument and the user's path, never a temporary file.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterable
from pathlib import Path

from workbench.archive._atomic import not_a_regular_file, os_reason, remove_stale_temporaries
from workbench.archive._integrity import ArchiveError

__all__ = ["check_output_directory", "check_output_file"]


def _nearest_existing(path: Path, argument: str, shown: Path) -> Path:
    """The nearest ancestor of ``path`` that exists; ArchiveError if it is not a directory."""
    for parent in path.parents:
        if os.path.lexists(parent):
            if not parent.is_dir():
                what = "a file" if parent.exists() else "a symbolic link to nothing"
                raise ArchiveError(
                    f"{argument}: cannot write {str(shown)!r}: {str(parent)!r} is {what}, not a "
                    "directory; choose a path whose parents are directories"
                )
            return parent
    return Path(".")  # pragma: no cover - a relative path's ancestors end at "."


def _check_writable(directory: Path, argument: str, shown: Path) -> None:
    """ArchiveError unless a file can be created in ``directory`` (tried, then removed)."""
    try:
        fd, name = tempfile.mkstemp(prefix=".workbench-probe-", suffix=".tmp", dir=directory)
    except OSError as exc:
        raise ArchiveError(
            f"{argument}: cannot write {str(shown)!r}: no file can be created in "
            f"{str(directory)!r} ({os_reason(exc)}); choose another path"
        ) from None
    os.close(fd)
    os.unlink(name)


def _check_kind(path: Path, argument: str) -> None:
    """ArchiveError if ``path`` is a device, FIFO, socket, or a link to one."""
    kind = not_a_regular_file(path)
    if kind is not None:
        raise ArchiveError(
            f"{argument}: {str(path)!r} is {kind}, not a regular file; workbench writes only "
            "regular files (--overwrite replaces a regular file, never a device, FIFO or "
            "socket): choose another path"
        )


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
        Allow replacing an existing regular file.
    flag : str
        The option that allows replacing it, for the message.

    Returns
    -------
    Path

    Raises
    ------
    ArchiveError
        ``path`` is a directory, a device, a FIFO, a socket or a link to one; lies under a file
        or in a directory where no file can be created; or exists and ``overwrite`` is false.
        The message names the argument, the value and what is allowed.
    """
    path = Path(path)
    if path.is_dir():
        raise ArchiveError(
            f"{argument}: {str(path)!r} is a directory; give the path of a file to write "
            f"(e.g. {str(path / 'out.nc')!r})"
        )
    _check_kind(path, argument)
    _check_writable(_nearest_existing(path, argument, path), argument, path)
    if path.parent.is_dir():
        remove_stale_temporaries(path)  # of a writer killed before (named in a warning)
    if os.path.lexists(path) and not overwrite:
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
    """Check, before any work, that the files ``names`` can be written into ``directory``
    (made if it does not exist).

    Raises
    ------
    ArchiveError
        ``directory`` is not a directory (a file, a device, ...) or lies under a file; no file
        can be created in it (or, when it does not exist, in its nearest existing ancestor);
        one of the files is a device, a FIFO, a socket or a link to one; or one of them exists
        and ``overwrite`` is false (the message names them).
    """
    directory = Path(directory)
    if os.path.lexists(directory) and not directory.is_dir():
        kind = not_a_regular_file(directory) or (
            "a file" if directory.exists() else "a symbolic link to nothing"
        )
        raise ArchiveError(f"{argument}: {str(directory)!r} is {kind}; give a directory")
    if directory.is_dir():
        _check_writable(directory, argument, directory)
    else:
        _check_writable(_nearest_existing(directory, argument, directory), argument, directory)
    names = list(names)
    for name in names:
        _check_kind(directory / name, argument)
    existing = [n for n in names if os.path.lexists(directory / n)]
    if existing and not overwrite:
        shown = ", ".join(repr(n) for n in existing[:4]) + (" ..." if len(existing) > 4 else "")
        raise ArchiveError(
            f"{argument}: {str(directory)!r} already holds {shown}; pass {flag} to replace "
            "them, or choose another directory"
        )
    return directory
