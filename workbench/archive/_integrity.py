"""What keeps a store of files honest: one writer at a time (an advisory lock) and checksums.

A *store* is a directory that one process writes over a long time (a campaign's blocks, an
accuracy study's runs) and that a later process resumes from. Two processes writing one store
would mix their files, so each holds :func:`store_lock` for its whole lifetime; a file reused on
resume is first checked against the SHA-256 recorded when it was written (:func:`sha256_file`).
"""

from __future__ import annotations

import contextlib
import datetime
import errno
import hashlib
import json
import os
import socket
import warnings
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

from workbench._errors import WorkbenchError
from workbench.archive._filesystem import LockScope, lock_scope

__all__ = [
    "ArchiveError",
    "StoreLocked",
    "StoreWarning",
    "file_problem",
    "mapping_diff",
    "read_manifest",
    "sha256_file",
    "store_lock",
]

LOCK_NAME = "lock"


class ArchiveError(WorkbenchError, ValueError):
    """A file or store cannot be used as asked: not a readable netCDF file, or a store that
    another process is writing. The message names the path and what to do."""


class StoreLocked(ArchiveError):
    """The store is held by another live process (named by ``pid`` and ``host``)."""

    def __init__(self, message: str, pid: int | None, host: str | None) -> None:
        super().__init__(message)
        self.pid = pid
        self.host = host


class StoreWarning(UserWarning):
    """A file of a store cannot be reused (missing, corrupt, never committed) and is recomputed,
    or a stale lock was taken over."""


def sha256_file(path: str | os.PathLike) -> str:
    """Hex SHA-256 digest of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def file_problem(path: str | os.PathLike, expected: str | None) -> str | None:
    """Why the file of a store at ``path`` cannot be reused, or None if it can: ``expected`` is
    the SHA-256 recorded when it was committed (None if it never was; then a file there is an
    uncommitted left-over, and no file is simply work to do)."""
    path = Path(path)
    if expected is None:
        if path.exists():
            return (
                "was written but never committed (no checksum in the manifest: the process "
                "stopped before recording it)"
            )
        return None
    if not path.is_file():
        return "is missing"
    try:
        actual = sha256_file(path)
    except OSError as exc:
        return f"is unreadable ({exc})"
    return None if actual == expected else "is corrupt: checksum mismatch"


def read_manifest(
    path: str | os.PathLike,
    format: str | tuple[str, ...],
    what: str,
    error: type[Exception] = ArchiveError,
) -> dict:
    """The JSON manifest of a store at ``path``, which must have ``"format": format`` (or one of
    several formats, a tuple: the current one first, then older ones still read).

    Raises ``error`` naming the path when the file cannot be read or parsed, or holds another
    format; the message says that ``restart=True`` (CLI ``--restart``) starts ``what`` (e.g.
    ``"the campaign"``) afresh.
    """
    try:
        data = json.loads(Path(path).read_text())
    except (OSError, ValueError) as exc:
        raise error(
            f"{str(path)!r} cannot be read ({exc}); pass restart=True (CLI --restart) to start "
            f"{what} afresh"
        ) from None
    formats = (format,) if isinstance(format, str) else tuple(format)
    if not isinstance(data, dict) or data.get("format") not in formats:
        found = data.get("format") if isinstance(data, dict) else None
        raise error(
            f"{str(path)!r} has format {found!r}, expected {' or '.join(map(repr, formats))}; "
            "pass restart=True (CLI "
            f"--restart) to start {what} afresh, or choose another output path"
        )
    return data


def _short(v: Any) -> str:
    if isinstance(v, list | tuple) and len(v) > 4:
        return f"[{len(v)} values from {v[0]!r} to {v[-1]!r}]"
    return repr(v)


def mapping_diff(old: Mapping, new: Mapping, prefix: str = "") -> list[str]:
    """Lines ``key: old -> new`` for every dotted key whose value differs (nested mappings)."""
    out = []
    for k in list(old) + [k for k in new if k not in old]:
        key = f"{prefix}{k}"
        a, b = old.get(k, "<absent>"), new.get(k, "<absent>")
        if isinstance(a, Mapping) and isinstance(b, Mapping):
            out += mapping_diff(a, b, key + ".")
        elif a != b:
            out.append(f"{key}: {_short(a)} -> {_short(b)}")
    return out


def _read_holder(fd: int) -> dict:
    """The holder recorded in an open lock file ({} if empty or unreadable)."""
    try:
        raw = os.pread(fd, 4096, 0)
        holder = json.loads(raw.decode()) if raw.strip() else {}
    except (OSError, ValueError):
        return {}
    return holder if isinstance(holder, dict) else {}


def _check_other_node(fd: int, path: Path, previous: dict, scope: LockScope, what: str) -> None:
    """Where a lock is only seen on its own node: refuse a lock file left by another host (its
    campaign may still run there: the free lock proves nothing), else warn that a process on
    another node would not be refused."""
    if previous and previous.get("host") not in (None, socket.gethostname()):
        os.close(fd)
        raise StoreLocked(
            f"the {what} was locked by {_describe(previous)} (lock file {str(path)!r}), and on "
            f"this file system a lock is not seen from other nodes ({scope.reason}), so that "
            "process may still be writing it. If it no longer runs, delete the lock file and "
            "start again; see docs/cluster.md",
            previous.get("pid"),
            previous.get("host"),
        )
    warnings.warn(
        StoreWarning(
            f"the {what} is on {scope.fstype} at {scope.mountpoint!r} ({scope.reason}): its lock "
            "keeps out other processes on this node only; run one campaign per store, or keep "
            "the store where flock reaches every node (docs/cluster.md)"
        ),
        stacklevel=4,
    )


def _describe(holder: dict) -> str:
    if not holder:
        return "a process that recorded no pid"
    since = f", since {holder['started']}" if holder.get("started") else ""
    return f"process {holder.get('pid')} on host {holder.get('host')!r}{since}"


@contextlib.contextmanager
def store_lock(directory: str | os.PathLike, what: str = "store") -> Iterator[dict]:
    """Hold the advisory lock of a store directory (``fcntl.flock`` on ``DIRECTORY/lock``) for
    the duration of the ``with`` block.

    The lock file records the holder's pid, host and start time, so that a refused process can
    name it. The kernel drops an ``flock`` when its holder dies (whatever the signal), so a lock
    file left by a dead process is stale by construction: it is taken over with a
    :class:`StoreWarning` that names the previous holder.

    Parameters
    ----------
    directory : str or PathLike
        The store directory (created if missing).
    what : str
        What the store is, for the message (e.g. ``"campaign store '/x/sweep.nc'"``).

    Yields
    ------
    dict
        The previous holder recorded in a stale lock file (``pid``, ``host``, ``started``), or
        an empty dict.

    Raises
    ------
    StoreLocked
        Another live process holds the lock (the message names its pid and host); or, on a file
        system whose locks other nodes do not see (:func:`workbench.archive._filesystem.
        lock_scope`: NFS with ``local_lock``, Lustre with ``localflock``), the lock file names
        a holder on another host, which may still run.
    ArchiveError
        The file system refuses ``flock`` (Lustre without ``-o flock``).

    Warns
    -----
    StoreWarning
        A stale lock was taken over; or the store is on a file system whose locks other nodes
        do not see (a second campaign there would not be refused).
    """
    import fcntl  # POSIX only; imported here so that the module loads everywhere

    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / LOCK_NAME
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            holder = _read_holder(fd)
            os.close(fd)
            if exc.errno in (errno.ENOSYS, errno.EOPNOTSUPP, errno.ENOLCK, errno.EINVAL):
                scope = lock_scope(directory)
                raise ArchiveError(
                    f"cannot lock the {what}: flock on {str(path)!r} fails ({exc.strerror}; "
                    f"{scope.reason or 'the file system refuses it'}); put the store on a file "
                    "system with flock (Lustre: mount with -o flock), see docs/cluster.md"
                ) from None
            if exc.errno not in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                raise
            raise StoreLocked(
                f"the {what} is in use by {_describe(holder)} (lock file {str(path)!r}); one "
                "process writes a store at a time: wait for it to finish or stop it, or choose "
                "another output path",
                holder.get("pid"),
                holder.get("host"),
            ) from None
        # A releasing holder unlinks the file: the inode locked must still be the one at path.
        try:
            same = os.fstat(fd).st_ino == os.stat(path).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    previous = _read_holder(fd)
    scope = lock_scope(directory)
    if scope.node_local:
        _check_other_node(fd, path, previous, scope, what)
    if previous:
        warnings.warn(
            StoreWarning(
                f"took over the lock of the {what} left by {_describe(previous)}, which no "
                "longer runs"
            ),
            stacklevel=3,
        )
    me = {
        "pid": os.getpid(),
        "host": socket.gethostname(),
        "started": datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
    }
    os.ftruncate(fd, 0)
    os.pwrite(fd, (json.dumps(me) + "\n").encode(), 0)
    try:
        yield previous
    finally:
        with contextlib.suppress(FileNotFoundError):
            path.unlink()
        os.close(fd)  # releases the lock
