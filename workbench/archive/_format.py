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
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from workbench._version import FORMAT_VERSION, __version__
from workbench.archive._integrity import ArchiveError
from workbench.solver import Status

__all__ = ["stamp_format", "status_flags", "upgrade_archive"]

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
    return _upgrade_from_1(ds, path)


def _upgrade_from_1(ds: xr.Dataset, path: str) -> xr.Dataset:
    """Format 1 -> 2: the status vocabulary (module docstring)."""
    ds = ds.copy()
    writer = ds.attrs.get("source", "workbench 0.1.0")
    if ds.attrs.get("run_status") == "done":
        ds.attrs["run_status"] = Status.OK.label
    for name, var in ds.variables.items():
        meanings = str(var.attrs.get("flag_meanings", "")).split()
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
        flags = {int(s): s.label for s in Status}
        if "invalid_parameters" in meanings:
            flags |= {v: k for k, v in FORMAT2_EXTRA_FLAGS.items()}
        attrs = {k: v for k, v in var.attrs.items() if k != "comment"}
        attrs["flag_values"] = np.array(list(flags), dtype=np.int8)
        attrs["flag_meanings"] = " ".join(flags.values())
        attrs["comment"] = (
            f"upgraded from archive format 1: {' '.join(meanings)} -> the codes of "
            "workbench.Status (terminated_early -> terminated)"
        )
        ds[name] = (var.dims, new_values.astype(var.dtype), attrs)
    ds.attrs["format_version"] = np.int32(FORMAT_VERSION)
    ds.attrs["upgraded_from_format"] = np.int32(1)
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
