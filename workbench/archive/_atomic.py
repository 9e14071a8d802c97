"""Atomic writes that cannot silently replace a file or vanish.

Every file workbench writes goes through :func:`atomic_path`: the data go to a temporary file
beside the target (``.NAME.HOST-PID-RANDOM.tmp``), which is renamed onto the target only when
complete, so a reader never sees half a file and an interrupted write leaves the previous file
intact. On top of the rename:

- *No silent replace.* With ``overwrite=False`` the target's existence is checked again at the
  rename, atomically (a hard link, which fails if the name exists): a file that another process
  wrote there meanwhile is left alone, and the finished result is kept beside it
  (``NAME.kept-PID.nc``) and named in :class:`OutputExists`.
- *A failed write is one line naming the target.* A write that fails for lack of space
  (``ENOSPC``, ``EDQUOT``, or the netCDF library's "HDF error" with the file system full)
  raises :class:`DiskFull` naming the path, the bytes needed and the bytes free; one that fails
  for any other reason (``EACCES``, ``EROFS``, ``EIO``, a netCDF library error, ...) raises
  :class:`WriteFailed` naming the path and the reason, never the temporary file.
- *Only a regular file is replaced.* A device, FIFO or socket at the target (or a symbolic
  link to one) is refused before the write and again at the rename (:class:`WriteFailed`).
- *No stale temporaries.* A process killed mid-write (``kill -9``) leaves its temporary file;
  the next write of the same target removes those whose process (on this host) is gone.

:func:`keep_elsewhere` writes a result that could not be written where asked (any
:class:`WriteFailed`) to a place that has room (the temporary directory, the home directory, the
working directory), so that a computed run is never thrown away without saying where it is.
:func:`save_figure` writes a matplotlib figure through the same atomic path.
"""

from __future__ import annotations

import contextlib
import copy
import errno
import glob
import hashlib
import os
import re
import shutil
import socket
import stat
import tempfile
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path

from workbench.archive._integrity import ArchiveError, StoreWarning
from workbench.run import format_bytes

__all__ = [
    "DiskFull",
    "OutputExists",
    "WriteFailed",
    "atomic_path",
    "keep_elsewhere",
    "not_a_regular_file",
    "remove_stale_temporaries",
    "save_figure",
    "write_text_atomic",
]

_HOST = hashlib.sha256(socket.gethostname().encode()).hexdigest()[:6]
_FULL = (errno.ENOSPC, errno.EDQUOT)
# the netCDF library reports a full disk as "NetCDF: HDF error": below this much free space
# after a failed write, the failure is taken to be the full disk
_LOW_SPACE = 1 << 20


class OutputExists(ArchiveError):
    """The target appeared while the result was computed (another process wrote it) and
    replacing it was not allowed; ``kept`` is where the result was kept instead."""

    def __init__(self, message: str, kept: str | None = None) -> None:
        super().__init__(message)
        self.kept = kept

    def __reduce__(self):
        return (type(self), (str(self), self.kept))


class WriteFailed(ArchiveError):
    """A write of ``path`` failed (the message names the path and the reason; ``errno`` is
    the operating system's error number, None where there is none): nothing was written
    there, and what was to be written is still in the caller's hands."""

    def __init__(self, message: str, path: str | None = None, code: int | None = None) -> None:
        super().__init__(message)
        self.path, self.errno = path, code

    def __reduce__(self):  # a campaign's worker raises it in another process
        return (type(self), (str(self), self.path, self.errno))

    def reworded(self, message: str) -> WriteFailed:
        """The same failure with another message (e.g. one that adds where the work is)."""
        new = copy.copy(self)
        new.args = (message,)
        return new


class DiskFull(WriteFailed):
    """A write failed for lack of space: ``path``, ``needed`` and ``free`` (bytes; None where
    unknown) are in the message."""

    def __init__(
        self,
        message: str,
        path: str | None = None,
        needed: float | None = None,
        free: float | None = None,
    ) -> None:
        super().__init__(message, path, errno.ENOSPC)
        self.needed, self.free = needed, free

    def __reduce__(self):
        return (type(self), (str(self), self.path, self.needed, self.free))


_KINDS = (
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISSOCK, "a socket"),
    (stat.S_ISDIR, "a directory"),
)


def _kind(mode: int) -> str:
    return next((name for test, name in _KINDS if test(mode)), "not a regular file")


def not_a_regular_file(path: str | os.PathLike) -> str | None:
    """What is at ``path`` when it is something a write must not replace: a device, a FIFO, a
    socket, a directory, or a symbolic link to one (e.g. ``"a symbolic link to a character
    device ('/dev/null')"``); None when nothing is there, or a regular file, or a symbolic link
    to a regular file or to nothing (replacing such a link replaces the link alone)."""
    try:
        mode = os.lstat(path).st_mode
    except OSError:  # nothing there, or under something that is not a directory
        return None
    if stat.S_ISREG(mode):
        return None
    if not stat.S_ISLNK(mode):
        return _kind(mode)
    try:
        target = os.stat(path).st_mode
    except OSError:
        return None
    if stat.S_ISREG(target):
        return None
    return f"a symbolic link to {_kind(target)} ({os.readlink(path)!r})"


def _temporary_prefix(path: Path) -> str:
    return f".{path.name}.{_HOST}-{os.getpid()}-"


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's live process
        return True
    return True


def remove_stale_temporaries(path: str | os.PathLike) -> list[Path]:
    """Remove the temporary files of interrupted writes of ``path`` whose process (on this
    host) is gone, each named in a :class:`StoreWarning`; return them. Temporary files of live
    processes, of other hosts and of other names are left alone."""
    path = Path(path)
    pattern = re.compile(rf"^\.{re.escape(path.name)}\.([0-9a-f]{{6}})-(\d+)-[a-z0-9_]+\.tmp$")
    removed = []
    for p in path.parent.glob(f".{glob.escape(path.name)}.*.tmp"):
        m = pattern.match(p.name)
        if m is None or m.group(1) != _HOST:
            continue
        pid = int(m.group(2))
        if pid == os.getpid() or _alive(pid):
            continue
        try:
            size = p.stat().st_size
            p.unlink()
        except OSError:
            continue
        removed.append(p)
        warnings.warn(
            StoreWarning(
                f"removed {str(p)!r} ({format_bytes(size)}), the temporary file of a write of "
                f"{path.name!r} by process {pid}, which was interrupted (the process is gone)"
            ),
            stacklevel=3,
        )
    return removed


def _chain(exc: BaseException) -> Iterator[BaseException]:
    seen = set()
    while exc is not None and id(exc) not in seen:
        seen.add(id(exc))
        yield exc
        exc = exc.__cause__ or exc.__context__


def _free_bytes(directory: Path) -> float | None:
    try:
        return float(shutil.disk_usage(directory).free)
    except OSError:
        return None


def _os_errors(exc: BaseException) -> list[int]:
    """The operating system's error numbers in the chain of ``exc`` (the netCDF library's
    negative codes left out: they do not say why)."""
    found = (getattr(e, "errno", None) for e in _chain(exc))
    return [e for e in found if isinstance(e, int) and e > 0]


def _lack_of_space(exc: BaseException, directory: Path) -> bool:
    """Whether a failed write failed for lack of space: the operating system says so, or it
    names no reason (the netCDF library's "HDF error") and the file system is nearly full."""
    errors = _os_errors(exc)
    if any(e in _FULL for e in errors):
        return True
    if not errors and isinstance(exc, OSError | RuntimeError):
        free = _free_bytes(directory)
        return free is not None and free < _LOW_SPACE
    return False


def _a_write_failure(exc: BaseException) -> bool:
    """Whether an exception raised while writing is the write failing (the operating system's
    or the netCDF library's error), not a bug of the writer."""
    return isinstance(exc, OSError) or str(exc).startswith("NetCDF:")


def os_reason(exc: BaseException) -> str:
    """Why an operation failed, in words, without the file name: the operating system's reason
    with its symbol (``EACCES: permission denied``), else the library's message."""
    errors = _os_errors(exc)
    if errors:
        code = errors[0]
        return f"{errno.errorcode.get(code, code)}: {os.strerror(code).lower()}"
    return str(getattr(exc, "strerror", None) or exc).splitlines()[0]


def _write_failed(path: Path, tmp: Path | None, size: float | None, exc: BaseException):
    """The one-line error of a failed write of ``path`` (:class:`DiskFull` for lack of space),
    the temporary file removed; the message names ``path``, never the temporary file."""
    if _lack_of_space(exc, path.parent):
        return _disk_full(path, tmp, size, exc)
    if tmp is not None:
        tmp.unlink(missing_ok=True)
    errors = _os_errors(exc)
    reason = os_reason(exc)
    if tmp is not None:
        reason = reason.replace(str(tmp), str(path))
    return WriteFailed(
        f"cannot write {str(path)!r}: {reason}",
        str(path),
        errors[0] if errors else None,
    )


def _refuse_special(path: Path) -> None:
    """WriteFailed if ``path`` is something a write must not replace (a device, ...)."""
    kind = not_a_regular_file(path)
    if kind is not None:
        raise WriteFailed(
            f"cannot write {str(path)!r}: it is {kind}, not a regular file, and workbench "
            "replaces only regular files; choose another path",
            str(path),
        )


def _disk_full(path: Path, tmp: Path | None, size: float | None, exc: BaseException) -> DiskFull:
    written = 0
    if tmp is not None:
        with contextlib.suppress(OSError):
            written = tmp.stat().st_size
            # the netCDF library may keep the failed file open: emptying it frees its space now
            os.truncate(tmp, 0)
        tmp.unlink(missing_ok=True)
    free = _free_bytes(path.parent)
    if size is not None:
        needed = f"needs up to {format_bytes(size)}"
    else:
        needed = f"had written {format_bytes(written)} when it failed"
    shown = "unknown" if free is None else format_bytes(free)
    return DiskFull(
        f"cannot write {str(path)!r}: no space left on its file system (the file {needed}; "
        f"{shown} free in {str(path.parent)!r}); free some space or write elsewhere",
        str(path),
        size,
        free,
    )


def _link_no_clobber(src: Path, dst: Path) -> None:
    """Give the file ``src`` the name ``dst`` unless ``dst`` exists, atomically: a hard link
    (``src`` keeps its name too); on a file system without hard links, an exclusive create of
    ``dst``, then the rename of ``src`` onto it. FileExistsError if ``dst`` exists."""
    try:
        os.link(src, dst)
        return
    except FileExistsError:
        raise
    except OSError as exc:
        if exc.errno not in (errno.EPERM, errno.ENOTSUP, errno.EOPNOTSUPP, errno.EXDEV):
            raise
    fd = os.open(dst, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o666)
    os.close(fd)
    os.replace(src, dst)


def _kept_name(path: Path, n: int) -> Path:
    tag = f"kept-{os.getpid()}" + (f"-{n}" if n else "")
    return path.with_name(f"{path.stem}.{tag}{path.suffix}")


def _keep_beside(tmp: Path, path: Path) -> Path:
    """Give the finished temporary file a visible name beside ``path`` that nothing uses."""
    for n in range(1000):
        kept = _kept_name(path, n)
        try:
            _link_no_clobber(tmp, kept)
        except FileExistsError:
            continue
        return kept
    raise ArchiveError(f"no free name beside {str(path)!r} to keep the result")  # pragma: no cover


@contextlib.contextmanager
def atomic_path(
    path: str | os.PathLike, *, overwrite: bool = True, size: float | None = None
) -> Iterator[Path]:
    """Context manager for an atomic write: yields a temporary path beside ``path`` to write;
    on success the file gets the usual permissions (0666 less the umask, not mkstemp's 0600)
    and takes the name ``path``; on failure it is removed and ``path`` is left as it was.

    Parameters
    ----------
    path : str or PathLike
        The file to write.
    overwrite : bool
        Replace a regular file at ``path``. Without it the name is given only if it is still
        free at the rename (checked atomically): if another process wrote ``path`` meanwhile,
        the finished file is kept beside it and :class:`OutputExists` names where.
    size : float, optional
        Bytes the file may take (for the message of a full disk).

    Raises
    ------
    DiskFull
        The write failed for lack of space (the message names the path, the bytes needed and
        the bytes free); nothing is left behind.
    WriteFailed
        The write failed for another reason of the operating system or the netCDF library
        (the message names ``path`` and the reason), or ``path`` is a device, a FIFO, a socket
        or a link to one (refused before the write and again at the rename, whatever
        ``overwrite`` says); nothing is left behind.
    OutputExists
        ``overwrite`` is false and ``path`` appeared meanwhile.
    """
    path = Path(path)
    _refuse_special(path)
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        remove_stale_temporaries(path)
        fd, name = tempfile.mkstemp(prefix=_temporary_prefix(path), suffix=".tmp", dir=path.parent)
        os.close(fd)
    except OSError as exc:
        raise _write_failed(path, None, size, exc) from None
    tmp = Path(name)
    try:
        try:
            yield tmp
        except Exception as exc:  # re-raised as it is unless the write failed
            if _lack_of_space(exc, path.parent) or _a_write_failure(exc):
                raise _write_failed(path, tmp, size, exc) from None
            raise
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        _refuse_special(path)  # a device put there meanwhile: never replaced
        if overwrite:
            os.replace(tmp, path)
            return
        try:
            _link_no_clobber(tmp, path)
        except FileExistsError:
            kept = _keep_beside(tmp, path)
            raise OutputExists(
                f"{str(path)!r} appeared while this result was computed (another process wrote "
                f"it); it was left unchanged and this result was kept at {str(kept)!r} (pass "
                "--overwrite, or overwrite=True, to replace instead)",
                str(kept),
            ) from None
        tmp.unlink(missing_ok=True)
    except OSError as exc:
        raise _write_failed(path, tmp, size, exc) from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_text_atomic(path: str | os.PathLike, text: str, *, overwrite: bool = True) -> Path:
    """Write ``text`` to ``path`` atomically (see :func:`atomic_path`)."""
    with atomic_path(path, overwrite=overwrite, size=len(text.encode())) as tmp:
        tmp.write_text(text)
    return Path(path)


def save_figure(fig, path: str | os.PathLike, *, close: bool = False, **savefig: object) -> Path:
    """Write a matplotlib figure to ``path`` atomically (see :func:`atomic_path`; a regular
    file there is replaced), in the format of its suffix (PNG without one); ``savefig`` are
    :meth:`matplotlib.figure.Figure.savefig`'s options (e.g. ``dpi``). ``close``: release the
    figure from pyplot afterwards (a figure drawn only to be written; pyplot keeps every
    figure it made until it is closed)."""
    path = Path(path)
    form = path.suffix.lstrip(".").lower() or "png"
    try:
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format=form, **savefig)
    finally:
        if close:
            import matplotlib.pyplot as plt

            plt.close(fig)
    return path


def keep_elsewhere(
    write: Callable[[Path], object], path: str | os.PathLike, size: float
) -> Path | None:
    """Write a result that could not be written at ``path`` (a full disk, a directory that
    refuses it, a failing device: any :class:`WriteFailed`) where there is room: ``write(p)``
    writes it to ``p``, a file named like ``path`` with ``.kept-PID`` in the system's
    temporary directory, else the home directory, else the working directory, on a file system
    with ``size`` bytes (and 10 %) free. Returns the path written, or None if nowhere had room
    (or every write failed)."""
    path = Path(path)
    seen = set()
    for directory in (Path(tempfile.gettempdir()), Path.home(), Path.cwd()):
        try:
            device = directory.stat().st_dev
        except OSError:
            continue
        free = _free_bytes(directory)
        if device in seen or free is None or free < 1.1 * size:
            continue
        seen.add(device)
        target = _kept_name(directory / path.name, 0)
        try:
            write(target)
        except (OSError, ArchiveError, RuntimeError):
            continue
        return target
    return None
