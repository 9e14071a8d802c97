"""Scalar time series from numpy arrays or xarray objects, with their sampling step and units."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

from workbench.archive import RECORD_DIM, RECORD_TIME

__all__ = ["Series", "as_series", "require_samples", "seconds", "time_record"]


@dataclass(frozen=True)
class Series:
    """A uniformly sampled scalar series: values, step ``dt`` (in ``time_units``: "s", or
    "sample" for a plain array given without ``dt``), name, units, forcing period (s) if known,
    and how it was sampled (``sampling``): "time" (a record in time: a ``time`` coordinate or
    an explicit ``dt``), "strobe" (one sample per forcing period, as
    :func:`~workbench.analysis.poincare_section` returns it: dim ``strobe`` with coordinate
    ``strobe_time``) or "index" (a plain array without ``dt``)."""

    values: np.ndarray
    dt: float
    name: str
    units: str
    period: float | None
    time_units: str
    sampling: str = "index"


def seconds(name: str, t, coordinate: str) -> np.ndarray:
    """The times ``t`` of ``name``'s ``coordinate`` as floats (s); ValueError for dates (an
    archive opened with plain xarray, which decodes CF time coordinates: docs/archives.md)."""
    t = np.asarray(t)
    if t.dtype.kind in "Mm":
        raise ValueError(
            f"the {coordinate} of {name!r} are dates, not seconds since t = 0: open the archive "
            "with workbench.open_run (or xarray.open_dataset(..., decode_times=False))"
        )
    return t.astype(float)


def _uniform_step(name: str, t: np.ndarray, coordinate: str) -> float | None:
    t = seconds(name, t, coordinate)
    steps = np.diff(t)
    if steps.size and not np.allclose(steps, steps[0], rtol=1e-6, atol=0):
        raise ValueError(
            f"{name!r} is not uniformly sampled ({coordinate} steps {steps.min():g} .. "
            f"{steps.max():g} s); analyses need a uniform record (record.dt or "
            "record.samples_per_period)"
        )
    return float(steps[0]) if steps.size else None


def time_record(obj):
    """One point of a campaign whose points have their own record times (records along
    ``record``, their times in ``record_time``: docs/archives.md) as a run's record: along
    ``time`` with the coordinate ``time`` (s), without the records past the end of its run
    (NaN times). Several points whose record times are all the same (e.g. the realisations at
    one value of a sweep over the forcing frequency) become one record in time as well. A
    Dataset or DataArray without the dim ``record`` is returned as it is.

    Raises
    ------
    ValueError
        ``obj`` holds the records of several points with different times (``record_time`` has
        other dims than ``record`` and differs along them), or runs along ``record`` without
        ``record_time``: one line that says which point to select.
    """
    if RECORD_DIM not in obj.dims:
        return obj
    name = getattr(obj, "name", None) or "the dataset"
    if RECORD_TIME not in obj.coords:
        raise ValueError(
            f"{name!r} runs along {RECORD_DIM!r} without the coordinate {RECORD_TIME!r} (each "
            "point's record times): open the campaign with workbench.open_run to keep them"
        )
    rt = obj[RECORD_TIME]
    others = [d for d in rt.dims if d != RECORD_DIM]
    rows = seconds(str(name), rt.transpose(*others, RECORD_DIM).values, RECORD_TIME)
    rows = rows.reshape(-1, rt.sizes[RECORD_DIM])
    same = (rows == rows[0]) | (np.isnan(rows) & np.isnan(rows[0]))
    if not same.all():
        raise ValueError(
            f"{name!r} holds the records of several points, each with its own times "
            f"({RECORD_TIME} over {rt.dims!r}): select one point first, e.g. "
            f".sel({others[0]}=...), or pass the whole record to an estimator that maps over "
            "the points (zero_one_test, wolf_lle, ...)"
        )
    times = rows[0]
    keep = np.flatnonzero(np.isfinite(times))
    attrs = dict(rt.attrs, long_name="time")
    out = obj.isel({RECORD_DIM: keep}).drop_vars(RECORD_TIME).rename({RECORD_DIM: "time"})
    return out.assign_coords(time=("time", times[keep], attrs))


def as_series(x, dt: float | None = None) -> Series:
    """A :class:`Series` from a 1-D array or a DataArray with a ``time`` coordinate (s) or a
    ``strobe_time`` coordinate (s, a stroboscopic section), or one point of a campaign whose
    points have their own record times (:func:`time_record`).

    The DataArray gives ``dt`` itself (its records must be uniform to 1e-6 relative) and its
    ``units``; a forcing period is read from ``forcing_period`` in its attributes. Raises
    ValueError for non-1-D input, non-finite values, a non-positive ``dt`` or a non-uniform
    time axis.

    Examples
    --------
    >>> as_series([1.0, 2.0, 3.0], dt=0.1).sampling
    'time'
    >>> as_series([1.0, 2.0, 3.0]).time_units
    'sample'
    """
    name, units, period = "x", "1", None
    sampling = "time" if dt is not None else "index"
    if dt is not None and not (np.isfinite(dt) and dt > 0):
        raise ValueError(f"dt={dt!r}: the sampling step must be a positive number of seconds")
    if isinstance(x, xr.DataArray):
        x = time_record(x)
        name = str(x.name or "x")
        units = str(x.attrs.get("units", "1"))
        period = x.attrs.get("forcing_period")
        if x.ndim != 1:
            raise ValueError(
                f"a series must be 1-D; {name!r} has dims {x.dims!r}: select one element of "
                "the other dims first, e.g. da.sel(joint='A')"
            )
        if dt is None and "time" in x.coords:
            dt = _uniform_step(name, x["time"].values, "time")
            sampling = "time"
        elif "strobe_time" in x.coords and x.dims == ("strobe",):
            step = _uniform_step(name, x["strobe_time"].values, "strobe")
            dt = dt if dt is not None else step
            sampling = "strobe"
        x = x.values
    values = np.asarray(x, dtype=float)
    if values.ndim != 1:
        raise ValueError(f"a series must be 1-D, got shape {values.shape!r}")
    if not np.isfinite(values).all():
        bad = int(np.flatnonzero(~np.isfinite(values))[0])
        raise ValueError(f"the series has a non-finite value at index {bad} ({values[bad]!r})")
    return Series(
        values,
        float(dt) if dt is not None else 1.0,
        name,
        units,
        float(period) if period else None,
        "s" if dt is not None else "sample",
        sampling if dt is not None else "index",
    )


def require_samples(s: Series, minimum: int, what: str) -> None:
    """Raise ValueError naming the series, its length and the ``minimum`` that ``what`` needs."""
    if s.values.size < minimum:
        raise ValueError(
            f"x ({s.name!r}) has {s.values.size} samples; {what} needs at least {minimum}: "
            "record a longer series"
        )
