"""Failures on figures: a failed campaign point is marked where its parameter value lies and
counted in the legend and title; a failed run's figure names its status.

Statuses are read from the datasets' own CF flags (``status``: ``flag_values`` and
``flag_meanings``; a run's ``run_status``), so an archive opened without its scene is enough.
A point is failed unless its status is ``ok`` or ``terminated`` (an event ended the run as the
model intends).
"""

from __future__ import annotations

from collections import Counter

import numpy as np
import xarray as xr

from workbench._attributes import flag_names
from workbench.archive import status_flags
from workbench.plot._base import display_unit
from workbench.solver import Status

__all__ = ["FAILED_STYLE", "failed_mask", "failure_note", "mark_failed", "run_status_note"]

_NOT_FAILED = ("ok", "terminated")
#: how a failed point is drawn: a red cross on the bottom edge of the panel
FAILED_STYLE = {"marker": "x", "color": "tab:red", "ms": 7, "mew": 1.6, "ls": "none"}


def _meanings(status: xr.DataArray) -> dict[int, str]:
    """Flag value -> meaning: the variable's CF flags, else the statuses' own labels."""
    values = np.atleast_1d(status.attrs.get("flag_values", []))
    names = flag_names(status)
    if len(values) and len(values) == len(names):
        return {int(v): n for v, n in zip(values, names, strict=True)}
    return {int(s): s.label for s in Status}


def failed_mask(ds: xr.Dataset) -> tuple[xr.DataArray | None, Counter]:
    """Which points of a campaign failed (bool over its parameter dims; None without a
    ``status`` variable) and how many of each status. A flag that is not a whole number (NaN)
    is an :class:`workbench.archive.ArchiveError` naming the variable."""
    if "status" not in ds:
        return None, Counter()
    status = ds["status"]
    meanings = _meanings(status)
    flags = status_flags(status, "the campaign")
    labels = np.vectorize(lambda v: meanings.get(int(v), f"status {int(v)}"), otypes=[object])(
        flags
    )
    failed = ~np.isin(labels, _NOT_FAILED)
    return status.copy(data=failed), Counter(labels[failed].tolist())


def failure_note(ds: xr.Dataset) -> str:
    """``"2 of 30 points failed (2 max_steps)"`` for a campaign with failed points, else ''."""
    mask, counts = failed_mask(ds)
    if mask is None or not counts:
        return ""
    kinds = ", ".join(f"{n} {k}" for k, n in counts.most_common())
    return f"{int(mask.sum())} of {mask.size} points failed ({kinds})"


def mark_failed(ax, ds: xr.Dataset, param: str, *, scale: float | None = None) -> str:
    """Mark on ``ax`` (x axis: ``param`` times ``scale``; default: in its display unit,
    :func:`~workbench.plot.display_unit`) every value of ``param`` at which a point failed: a
    red cross on the bottom edge, with a legend entry naming the count and the statuses.
    Returns :func:`failure_note` ('' when nothing failed)."""
    mask, counts = failed_mask(ds)
    if mask is None or not counts or param not in mask.dims:
        return ""
    other = [d for d in mask.dims if d != param]
    at = mask.any(other) if other else mask
    if scale is None:
        scale, _ = display_unit(ds[param].attrs.get("units"))
    x = ds[param].values[at.values] * scale
    note = failure_note(ds)
    kinds = ", ".join(f"{n} {k}" for k, n in counts.most_common())
    ax.plot(
        x,
        np.zeros_like(x, dtype=float),
        transform=ax.get_xaxis_transform(),
        clip_on=False,
        zorder=5,
        label=f"failed ({kinds})",
        **FAILED_STYLE,
    )
    return note


def run_status_note(ds: xr.Dataset) -> str:
    """For a run that failed: ``"run failed: max_steps (records end at t = 1.23 s)"``; ''
    for a run that ended as asked (``ok``, ``terminated``) or a dataset without a status."""
    status = ds.attrs.get("run_status")
    if status is None or status in _NOT_FAILED:
        return ""
    end = ""
    names = [v for v in ds.data_vars if "time" in ds[v].dims]
    if names and "time" in ds.coords:
        finite = np.isfinite(ds[names[0]].values).reshape(ds.sizes["time"], -1).any(axis=1)
        last = np.flatnonzero(finite)
        end = (
            f" (records end at t = {float(ds.time[last[-1]]):.4g} s)"
            if last.size
            else " (no record before the failure)"
        )
    return f"run failed: {status}{end}"
