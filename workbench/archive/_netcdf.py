"""netCDF archives: atomic writing, exact reading."""

from __future__ import annotations

import contextlib
import errno
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import xarray as xr

from workbench.archive._format import stamp_format, upgrade_archive
from workbench.archive._integrity import ArchiveError

__all__ = ["atomic_path", "open_run", "save_run", "write_text_atomic"]


def _encodable(ds: xr.Dataset) -> xr.Dataset:
    """netCDF cannot store booleans or None in attributes: store them as int8 / omit them."""
    ds = ds.copy(deep=False)
    for obj in [ds, *ds.variables.values()]:
        for k, v in list(obj.attrs.items()):
            if isinstance(v, bool | np.bool_):
                obj.attrs[k] = np.int8(v)
            elif v is None:
                del obj.attrs[k]
    return ds


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Context manager for an atomic write: yields a temporary path beside ``path``; on success
    the file gets the usual permissions (0666 less the umask, not mkstemp's 0600) and is renamed
    onto ``path``, on failure it is removed and ``path`` is left as it was."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_text_atomic(path: str | os.PathLike, text: str) -> Path:
    """Write ``text`` to ``path`` atomically (see :func:`atomic_path`)."""
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    return Path(path)


def save_run(
    ds: xr.Dataset, path: str | os.PathLike, *, compress: bool = True, classic: bool = False
) -> Path:
    """Write a dataset to netCDF-4 atomically: a temporary file beside ``path``, then a rename.

    A reader never sees a half-written file, and an interrupted write leaves any previous file
    at ``path`` intact. Float variables are zlib-compressed (level 4, lossless) when ``compress``.
    ``classic`` writes the netCDF-3 64-bit-offset format instead (no compression, 64-bit
    integers stored as 32-bit where their values fit) with scipy's writer: faster than netCDF-4
    for a small file, whose cost is mostly HDF5's per-variable overhead (the campaign's block
    files; measured in the README, "Campaigns"); the files read back identical.

    The file carries the global attribute ``format_version`` (:data:`workbench.FORMAT_VERSION`),
    added if ``ds`` lacks it.

    Returns the path written.
    """
    path = Path(path)
    ds = stamp_format(ds)
    encoding = {}
    if classic:
        with atomic_path(path) as tmp:
            _encodable(ds).to_netcdf(tmp, engine="scipy", format="NETCDF3_64BIT")
        return path
    if compress:
        for name, var in ds.data_vars.items():
            if var.dtype.kind in "fiu" and var.ndim > 0:
                encoding[name] = {"zlib": True, "complevel": 4}
    with atomic_path(path) as tmp:
        _encodable(ds).to_netcdf(tmp, engine="netcdf4", format="NETCDF4", encoding=encoding)
    return path


def open_run(path: str | os.PathLike) -> xr.Dataset:
    """Read a stored run (or campaign) fully into memory and close the file.

    An archive of an older format (its ``format_version``, :mod:`workbench._version`) is
    upgraded in memory where the change is unambiguous (``upgraded_from_format`` says so).

    Raises
    ------
    FileNotFoundError
        There is no file at ``path``.
    ArchiveError
        The file is not a readable netCDF file (truncated, corrupt, or something else), or an
        archive of a newer format, or of an older one that cannot be upgraded (the message
        says what to do).
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(errno.ENOENT, "no such file", str(path))
    if path.is_dir():
        raise ArchiveError(f"{str(path)!r} is a directory, not a netCDF file")
    try:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            ds = ds.load()
    except (OSError, ValueError, RuntimeError, KeyError, IndexError) as exc:
        raise ArchiveError(
            f"{str(path)!r} is not a readable netCDF file (truncated or corrupt?): "
            f"{type(exc).__name__}: {exc}"
        ) from None
    return upgrade_archive(ds, str(path))
