"""The errors of one setting of a work-precision study against its reference (the module
docstring of :mod:`workbench.precision._study` defines them), the short horizon they are
measured over, and the flags of errors that lie at the reference's own limit."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import xarray as xr

from workbench.run import divergence_time, separation

__all__ = [
    "ERRORS",
    "LIMIT_BITS",
    "LIMIT_FACTOR",
    "REFERENCE_FLOOR",
    "measure",
    "records_within",
    "reference_limited",
    "short_horizon",
    "strobe",
]

ERRORS = ("short_error", "peak_error", "events_error", "statistic_error")
# The reference must be exact to this fraction of a variable's range over the short horizon:
# 1000x below the 1e-3 error targets `recommend` is meant for.
REFERENCE_FLOOR = 1e-6
# An error within this factor of the reference's own error is flagged: it is not resolved.
LIMIT_FACTOR = 3.0
LIMIT_BITS = {"short_error": 1, "peak_error": 2}


def strobe(ds: xr.Dataset) -> xr.Dataset:
    spp = int(ds.attrs.get("samples_per_period", 1))
    return ds.isel(time=slice(None, None, spp))


def short_horizon(
    ref_short: xr.Dataset, probe: xr.Dataset, twin: xr.Dataset | None = None
) -> float:
    """Half the divergence time of the reference and a looser probe (s), cut where the
    reference and a tighter ``twin`` separate by REFERENCE_FLOOR; the whole record if they never
    diverge; at least 10 records."""
    t = ref_short.time.values - ref_short.time.values[0]
    limit = 0.5 * divergence_time(probe, ref_short)
    if twin is not None:
        # the last record before the twin's separation exceeds the floor
        over = np.flatnonzero(separation(twin, ref_short) > REFERENCE_FLOOR)
        if over.size:
            limit = min(limit, t[max(over[0] - 1, 0)])
    return float(min(t[-1], max(limit, t[min(10, t.size - 1)])))


def records_within(ref_short: xr.Dataset, horizon: float) -> int:
    """Number of records of the short runs that lie within ``horizon`` (s) of their start."""
    return int(np.searchsorted(ref_short.time.values - ref_short.time.values[0], horizon, "right"))


def measure(
    short: xr.Dataset,
    long: xr.Dataset,
    ref_short: xr.Dataset,
    ref_long: xr.Dataset,
    periods: float,
    horizon: float,
) -> dict[str, float]:
    peak_err, stat_err = 0.0, 0.0
    n = records_within(ref_short, horizon)
    short, ref_short = short.isel(time=slice(0, n)), ref_short.isel(time=slice(0, n))
    short_err = float(np.max(separation(short, ref_short)))
    for name in ref_short.data_vars:
        r = ref_short[name].values
        peak_ref = float(np.nanmax(np.abs(r)))
        if peak_ref > 0:
            peak = float(np.nanmax(np.abs(short[name].values)))
            peak_err = max(peak_err, abs(peak - peak_ref) / peak_ref)
    s, sr = strobe(long), strobe(ref_long)
    for name in sr.data_vars:
        spread = float(sr[name].std()) or 1.0
        d_mean = abs(float(s[name].mean() - sr[name].mean())) / spread
        d_std = abs(float(s[name].std() - sr[name].std())) / spread
        stat_err = max(stat_err, d_mean, d_std)
    ev, ev_ref = long.attrs["solver_events"] / periods, ref_long.attrs["solver_events"] / periods
    events_err = abs(ev - ev_ref) / ev_ref if ev_ref else float(ev != ev_ref)
    return {
        "short_error": short_err,
        "peak_error": peak_err,
        "events_error": events_err,
        "statistic_error": stat_err,
    }


def reference_limited(
    out: dict[str, np.ndarray], tolerances: Sequence[float], ref_tol: float, ref_error: float
) -> np.ndarray:
    """CF flag masks per setting: 1 short error, 2 peak error at the reference's limit."""
    flags = np.zeros(out["short_error"].shape, np.int8)
    if math.isnan(ref_error):  # the reference's own error is unknown: judge by tolerance
        near = np.asarray(tolerances) < 100 * ref_tol
        flags[:, near] = LIMIT_BITS["short_error"] | LIMIT_BITS["peak_error"]
        return flags
    for name, bit in LIMIT_BITS.items():
        flags |= np.where(out[name] <= LIMIT_FACTOR * ref_error, bit, 0).astype(np.int8)
    return flags
