"""netCDF archives: atomic writing, exact reading."""

from __future__ import annotations

import errno
import os
from pathlib import Path

import numpy as np
import xarray as xr

from workbench.archive._atomic import atomic_path
from workbench.archive._format import decode_time, encode_time, stamp_format, upgrade_archive
from workbench.archive._integrity import ArchiveError

__all__ = ["open_run", "save_run"]


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


def _cf_encoding(ds: xr.Dataset) -> dict:
    """xarray's encoding of ``ds`` made CF 1.11: no ``_FillValue`` on a dimension's coordinate
    variable (CF forbids one there; xarray gives every float variable one). Other variables
    keep theirs (NaN marks a missing value)."""
    return {name: {"_FillValue": None} for name in ds.dims if name in ds.variables}


def save_run(
    ds: xr.Dataset,
    path: str | os.PathLike,
    *,
    compress: bool = True,
    classic: bool = False,
    overwrite: bool = True,
) -> Path:
    """Write a dataset to netCDF atomically: a temporary file beside ``path``, then a rename
    (:func:`workbench.archive.atomic_path`).

    A reader never sees a half-written file, and an interrupted write leaves any previous file
    at ``path`` intact. The file carries the global attribute ``format_version``
    (:data:`workbench.FORMAT_VERSION`), added if ``ds`` lacks it; it follows the CF 1.11
    conventions where workbench's datasets need it: a coordinate variable has no
    ``_FillValue``, and the simulated time (``standard_name`` "time", seconds since t = 0 of
    the run) is stored as a CF time coordinate since a reference instant that stands for t = 0
    (:mod:`workbench.archive._format`); :func:`open_run` reads both back as they were.

    Parameters
    ----------
    ds : xarray.Dataset
        What to write (left untouched).
    path : str or path
        The file to write.
    compress : bool
        Compress float variables with zlib (level 4, lossless; netCDF-4 only).
    classic : bool
        Write the netCDF-3 64-bit-offset format instead (no compression, 64-bit integers
        stored as 32-bit where their values fit) with scipy's writer: a flat file without
        HDF5's per-variable overhead, meant for many small files (the campaign's block
        files); the files read back identical.
    overwrite : bool
        Replace a file at ``path``. False: a file that appeared at ``path`` meanwhile is never
        replaced (checked atomically at the rename; the new file is kept beside it and named
        in :class:`OutputExists`).

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    OutputExists
        ``overwrite=False`` and a file is at ``path``.
    DiskFull
        The disk is full: the message names the path, the bytes needed and the bytes free;
        ``ds`` can be written elsewhere.
    """
    path = Path(path)
    ds = encode_time(stamp_format(ds))
    encoding = _cf_encoding(ds)
    if classic:
        # Serialised in memory, then written: xarray writes to a path under a lock of the dask
        # scheduler in use, which inside a dask.distributed task is a distributed lock (round
        # trips to the scheduler: 0.5 s per block file on a loaded 2-core machine, against
        # 0.01 s in memory; benchmarks/campaign_cluster.py). A new file needs no lock.
        data = _encodable(ds).to_netcdf(
            None, engine="scipy", format="NETCDF3_64BIT", encoding=encoding
        )
        with atomic_path(path, overwrite=overwrite, size=len(data)) as tmp:
            tmp.write_bytes(data)
        return path
    if compress:
        for name, var in ds.data_vars.items():
            if var.dtype.kind in "fiu" and var.ndim > 0:
                encoding[name] = {"zlib": True, "complevel": 4}
    with atomic_path(path, overwrite=overwrite, size=ds.nbytes) as tmp:
        _encodable(ds).to_netcdf(tmp, engine="netcdf4", format="NETCDF4", encoding=encoding)
    return path


def _read(path: Path, chunks: int | str | dict | None) -> xr.Dataset:
    """The file as workbench wrote it: its simulated time in seconds again
    (:func:`workbench.archive._format.decode_time`), other CF times decoded as xarray does."""
    raw = xr.open_dataset(
        path, engine="netcdf4", chunks=chunks, decode_times=False, decode_timedelta=False
    )
    ds = decode_time(raw)
    if any(" since " in str(v.attrs.get("units", "")) for v in ds.variables.values()):
        ds = xr.decode_cf(ds, mask_and_scale=False, decode_timedelta=False)
    return _closing(ds, raw)


def _closing(ds: xr.Dataset, source: xr.Dataset) -> xr.Dataset:
    """``ds`` (made from ``source``) closes ``source``'s file when closed (a copy does not)."""
    if ds is not source:
        ds.set_close(source.close)
    return ds


def open_run(path: str | os.PathLike, *, chunks: int | str | dict | None = None) -> xr.Dataset:
    """Read a stored run (or campaign).

    An archive of an older format (its ``format_version``, :mod:`workbench._version`) is
    upgraded in memory where the change is unambiguous (``upgraded_from_format`` says so).

    Parameters
    ----------
    path : str or path
        A netCDF file written by :func:`save_run` (or :func:`workbench.run_campaign`).
    chunks : int, "auto", dict or None
        None (default): read everything into memory and close the file. Otherwise open it
        lazily: variables are dask arrays in chunks of this size (as :func:`xarray.open_dataset`
        takes them, e.g. ``{"time": 100_000}``, ``"auto"``, or ``{}`` for one chunk per
        variable) read when computed; the file stays open until ``ds.close()``.

    Returns
    -------
    xarray.Dataset
        The archive's dataset.

    Raises
    ------
    FileNotFoundError
        There is no file at ``path``.
    ArchiveError
        The file is not a readable netCDF file (truncated, corrupt, or something else), or an
        archive of a newer format, or of an older one that cannot be upgraded (the message
        says what to do).

    Examples
    --------
    >>> import workbench, tempfile, pathlib
    >>> ds = workbench.simulate({"model": {"name": "duffing"}, "run": {"cycles": 2}})
    >>> path = workbench.save_run(ds, pathlib.Path(tempfile.mkdtemp()) / "run.nc")
    >>> lazy = open_run(path, chunks={"time": 50})
    >>> lazy.x.chunks[0][:2], float(lazy.x.max()) == float(ds.x.max())
    ((50, 50), True)
    >>> lazy.close()
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(errno.ENOENT, "no such file", str(path))
    if path.is_dir():
        raise ArchiveError(f"{str(path)!r} is a directory, not a netCDF file")
    try:
        with _read(path, None) as ds:
            if chunks is None:
                ds = ds.load()
    except (OSError, ValueError, RuntimeError, KeyError, IndexError) as exc:
        raise ArchiveError(
            f"{str(path)!r} is not a readable netCDF file (truncated or corrupt?): "
            f"{type(exc).__name__}: {exc}"
        ) from None
    if chunks is None:
        return upgrade_archive(ds, str(path))
    # readable: now lazily, where a chunk that names no dim is xarray's own error
    lazy = _read(path, chunks)
    return _closing(upgrade_archive(lazy, str(path)), lazy)
