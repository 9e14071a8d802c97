"""The archive format: every archive carries ``format_version`` (:mod:`workbench._version`);
reading one of an older format upgrades it where the change is known and unambiguous, and
refuses it with a message that says what to do where it is not; a newer format is refused.

Format 1 (workbench 0.1.0, no ``format_version``) differs from format 2 in its status
vocabulary: a run's ``run_status`` was ``done`` (now ``ok``) or ``terminated``; a campaign's or
a work-precision study's ``status`` flags were ``ok`` 0, ``solver_failed`` 1,
``terminated_early`` 2, ``invalid_parameters`` 3 (now the :class:`workbench.Status` codes:
``terminated`` 1, and ``invalid_parameters`` 6). ``solver_failed`` has no single counterpart
(it is now one of ``max_steps``, ``step_underflow``, ``non_finite``, ``model_failure``): an
archive with such a point is refused.

Format 2 differs from format 3 in how the file stores the simulated time (nothing changes in
memory). CF 1.11 (Sec. 4.4) gives a time coordinate the units ``<unit> since <reference
instant>``; a simulation has no date. In memory a dataset's times are seconds since t = 0 of
the run's equations (``units`` "s", ``standard_name`` "time"); on disk (format 3) the same
numbers carry the units ``s since 1970-01-01 00:00:00`` and the calendar ``standard``: the
reference instant stands for t = 0 and no date is meant (:func:`encode_time` on writing,
:func:`decode_time` on reading). A format-2 file wrote them as "s": a reader of format 2 that
decodes CF times (xarray does by default) would read format 3's times as dates.

Format 3 differs from format 4 in the layout of a campaign whose points have their own record
times (a sweep over the forcing frequency, every continued sweep): format 3 ran its records
along a dimension ``time`` without a coordinate variable, each point's times being the
auxiliary coordinate ``record_time`` (parameter dims, time; ``units`` "s", no standard name).
A dimension named ``time`` reads as a time axis (to CF checkers, and to code that selects or
reduces along ``time`` expecting times), but its index was a record's number, not a time.
Format 4 names that dimension ``record`` (:data:`RECORD_DIM`) and gives ``record_time``
(parameter dims, record) the ``standard_name`` "time", so that it is stored as every simulated
time is (:func:`encode_time`). A campaign whose points share their record times keeps the
coordinate variable ``time``. The block files of a campaign's store run along ``record`` in
format 4 (they ran along ``time`` in format 3). The upgrade is a renaming
(:func:`_upgrade_from_3`): the numbers are the same.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from workbench._attributes import flag_names
from workbench._version import FORMAT_VERSION, __version__
from workbench.archive._integrity import ArchiveError
from workbench.run import status_attrs
from workbench.solver import Status

__all__ = [
    "RECORD_DIM",
    "RECORD_TIME",
    "SERIES_DIMS",
    "decode_time",
    "encode_time",
    "stamp_format",
    "status_flags",
    "upgrade_archive",
]

#: the dim of a campaign's records when its points have their own record times (format 4):
#: the index of the record in its point's run; the times are :data:`RECORD_TIME`
RECORD_DIM = "record"
#: the auxiliary coordinate (parameter dims, :data:`RECORD_DIM`) of each point's record times,
#: s since t = 0 of its run (NaN past the end of a shorter run)
RECORD_TIME = "record_time"
#: the dims a run's or a campaign's record runs along: ``time`` (a coordinate variable of
#: times) or :data:`RECORD_DIM` (each point's times in :data:`RECORD_TIME`)
SERIES_DIMS = ("time", RECORD_DIM)

#: the reference instant that stands for t = 0 of a run in the units of its time axis on disk
#: (CF 1.11 requires one; a simulation has no date: none is meant)
TIME_REFERENCE = "1970-01-01 00:00:00"
TIME_CALENDAR = "standard"
#: a simulated time in memory: seconds since t = 0 of the run (workbench.run.TIME_ATTRS)
_SECONDS = "s"
_ON_DISK = f"{_SECONDS} since {TIME_REFERENCE}"

#: format 1's status labels and what they are in format 2 (None: no single counterpart)
FORMAT1_STATUS = {
    "ok": "ok",
    "solver_failed": None,
    "terminated_early": "terminated",
    "invalid_parameters": "invalid_parameters",
}
#: format 2's codes of the status labels that are not a Status: a campaign point that did not
#: run, and one whose run raised an exception (workbench.campaign's INVALID and RAISED)
FORMAT2_EXTRA_FLAGS = {"invalid_parameters": 6, "error": 7}


def stamp_format(ds: xr.Dataset) -> xr.Dataset:
    """``ds`` with the global attribute ``format_version`` of this workbench (a shallow copy
    if it had to be added)."""
    if ds.attrs.get("format_version") == FORMAT_VERSION:
        return ds
    ds = ds.copy(deep=False)
    ds.attrs["format_version"] = np.int32(FORMAT_VERSION)
    return ds


def encode_time(ds: xr.Dataset) -> xr.Dataset:
    """``ds`` as the file stores it (format 3, module docstring): each variable with
    ``standard_name`` "time" in seconds since t = 0 gets the units ``s since 1970-01-01
    00:00:00`` and the calendar ``standard``, its values unchanged (a shallow copy if any did;
    ``ds`` is left alone)."""
    names = [n for n, v in ds.variables.items() if _is_simulated_time(v.attrs, _SECONDS)]
    if not names:
        return ds
    ds = ds.copy(deep=False)
    for name in names:
        var = ds.variables[name]
        var.attrs = {**var.attrs, "units": _ON_DISK, "calendar": TIME_CALENDAR}
    return ds


def decode_time(ds: xr.Dataset) -> xr.Dataset:
    """The inverse of :func:`encode_time`, for a dataset read without decoding CF times: each
    variable the file stores as a simulated time is seconds since t = 0 again (``units`` "s",
    no calendar). Other variables are left as they are."""
    names = [
        n
        for n, v in ds.variables.items()
        if _is_simulated_time(v.attrs, _ON_DISK) and v.attrs.get("calendar") == TIME_CALENDAR
    ]
    if not names:
        return ds
    ds = ds.copy(deep=False)
    for name in names:
        var = ds.variables[name]
        attrs = {k: v for k, v in var.attrs.items() if k != "calendar"}
        var.attrs = {**attrs, "units": _SECONDS}
    return ds


def _is_simulated_time(attrs: dict, units: str) -> bool:
    return attrs.get("standard_name") == "time" and attrs.get("units") == units


def _written_by_workbench(ds: xr.Dataset) -> bool:
    return str(ds.attrs.get("source", "")).startswith("workbench ")


def upgrade_archive(ds: xr.Dataset, path: str) -> xr.Dataset:
    """The archive read from ``path`` in the current format: as it is, or upgraded from an
    older format (with ``upgraded_from_format`` set). A netCDF file that workbench did not
    write (no ``format_version``, no workbench ``source``) is returned as it is.

    Raises
    ------
    ArchiveError
        The archive is of a newer format than this workbench reads, or of an older one that
        cannot be upgraded unambiguously (the message says what to do).
    """
    found = ds.attrs.get("format_version")
    if found is None:
        if not _written_by_workbench(ds):
            return ds
        found = 1
    try:
        whole = float(found) == int(found)
        found = int(found)
    except (TypeError, ValueError, OverflowError):
        whole = False
    if not whole or found < 1:
        raise ArchiveError(
            f"{path!r} has format_version {found!r}; allowed: a whole number from 1 (the first "
            f"archive format) to {FORMAT_VERSION} (this workbench {__version__}): the attribute "
            "was altered, or the file was not written by workbench"
        )
    if found > FORMAT_VERSION:
        raise ArchiveError(
            f"{path!r} has archive format {found}, newer than this workbench {__version__} "
            f"reads (format {FORMAT_VERSION}): upgrade workbench to open it"
        )
    if found == FORMAT_VERSION:
        return ds
    if found == 1:
        ds = _upgrade_from_1(ds, path)
    # format 2 -> 3: the simulated time is stored otherwise, read the same (module docstring)
    if found <= 3:
        ds = _upgrade_from_3(ds)
    ds = ds.copy(deep=False)
    ds.attrs["format_version"] = np.int32(FORMAT_VERSION)
    ds.attrs["upgraded_from_format"] = np.int32(found)
    return ds


def _upgrade_from_3(ds: xr.Dataset) -> xr.Dataset:
    """Format 3 -> 4 (module docstring): a dataset whose ``record_time`` runs along a dim
    ``time`` that has no coordinate variable (a campaign with each point's record times, or a
    block of a campaign's store) runs along ``record`` instead, with ``record_time`` carrying
    the ``standard_name`` "time"; any other dataset is returned as it is."""
    if RECORD_TIME not in ds.variables or "time" in ds.variables:
        return ds
    if "time" not in ds[RECORD_TIME].dims or RECORD_DIM in ds.dims:
        return ds
    ds = ds.rename_dims(time=RECORD_DIM)
    var = ds.variables[RECORD_TIME]
    if var.attrs.get("units") == _SECONDS:
        var.attrs = {**var.attrs, "standard_name": "time"}
    return ds


def _upgrade_from_1(ds: xr.Dataset, path: str) -> xr.Dataset:
    """Format 1 -> 2: the status vocabulary (module docstring)."""
    ds = ds.copy()
    writer = ds.attrs.get("source", "workbench 0.1.0")
    if ds.attrs.get("run_status") == "done":
        ds.attrs["run_status"] = Status.OK.label
    for name, var in ds.variables.items():
        meanings = flag_names(var)
        if not meanings or not set(meanings) <= set(FORMAT1_STATUS):
            continue
        old = dict(zip(np.asarray(var.attrs["flag_values"]).tolist(), meanings, strict=True))
        values = np.asarray(var.values)
        new_values = values.copy()
        for code, label in old.items():
            hit = values == code
            if not hit.any():
                continue
            new = FORMAT1_STATUS[label]
            if new is None:
                raise ArchiveError(
                    f"{path!r} was written by {writer} (archive format 1) and {int(hit.sum())} "
                    f"of its {name!r} flags are {label!r}, which has no single counterpart in "
                    f"format {FORMAT_VERSION} (now max_steps, step_underflow, non_finite or "
                    "model_failure): recompute it with this workbench (e.g. rerun the "
                    "campaign with --restart, or 'make data' for the shipped archives)"
                )
            new_values[hit] = FORMAT2_EXTRA_FLAGS.get(new, None) or int(Status.from_label(new))
        extra = {v: k for k, v in FORMAT2_EXTRA_FLAGS.items()}
        cf = status_attrs(name, extra if "invalid_parameters" in meanings else None)
        attrs = {k: v for k, v in var.attrs.items() if k != "comment"}
        attrs["flag_values"], attrs["flag_meanings"] = cf["flag_values"], cf["flag_meanings"]
        attrs["comment"] = (
            f"upgraded from archive format 1: {' '.join(meanings)} -> the codes of "
            "workbench.Status (terminated_early -> terminated)"
        )
        ds[name] = (var.dims, new_values.astype(var.dtype), attrs)
    return ds


def status_flags(status: xr.DataArray, where: str) -> np.ndarray:
    """The flags of a status variable (a campaign's ``status``: one :class:`workbench.Status`
    code per point, or ``invalid_parameters`` 6, ``error`` 7) as whole numbers.

    Parameters
    ----------
    status : xarray.DataArray
        The variable.
    where : str
        What it was read from, for the message (e.g. the archive's path).

    Raises
    ------
    ArchiveError
        A flag is not a whole number (NaN, inf, 0.5, text): the message names the variable,
        how many flags are wrong and one of them.
    """
    values = np.asarray(status.values)
    name = status.name or "status"
    if values.dtype.kind in "iub":
        return values.astype(np.int64)
    if values.dtype.kind == "f":
        with np.errstate(invalid="ignore"):
            bad = ~np.isfinite(values) | (values != np.round(values))
    else:
        bad = np.ones(values.shape, dtype=bool)
    if bad.any():
        example = values[bad].ravel()[:1].tolist()[0]
        raise ArchiveError(
            f"{where}: {int(bad.sum())} of the {values.size} flags of its {name!r} variable are "
            f"not status codes (e.g. {example!r}); allowed: the whole numbers of "
            f"its flag_values ({status.attrs.get('flag_meanings', 'workbench.Status')}): the "
            "archive was altered or damaged; recompute it"
        )
    return values.astype(np.int64)
