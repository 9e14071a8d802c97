"""Numbers a study compares with the paper: peaks, stroboscopic spreads, LLEs, timings.

All functions take the runs of a study (case name -> Dataset) and return plain floats with the
units of the variable (peaks), dimensionless spreads (in units of the clearance c), 1/s (LLEs)
or s (timings), so that they can be stored in the study's JSON summary.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from workbench.models import get_model
from workbench.scene import Scene

__all__ = [
    "select",
    "peak",
    "strobe",
    "strobe_spread",
    "seconds_per_cycle",
    "clearance_of",
]


def select(ds: xr.Dataset, var: str, where: dict | None = None) -> xr.DataArray:
    """``ds[var]`` with labels picked by ``where`` (e.g. ``{"joint": "A"}``); a clear error if
    the run lacks the variable or the label."""
    if var not in ds:
        raise KeyError(f"the run has no variable {var!r}; it has {sorted(ds.data_vars)}")
    da = ds[var]
    for dim, label in (where or {}).items():
        if dim not in da.dims or label not in da[dim].values:
            # e.g. contact force at B in a run with clearance only at A: nothing to measure
            return xr.full_like(da.isel({d: 0 for d in da.dims if d != "time"}), np.nan)
        da = da.sel({dim: label})
    return da


def peak(da: xr.DataArray, periods: float | None = None, ds: xr.Dataset | None = None) -> float:
    """The value of largest magnitude, with its sign (the paper's "peak value"), optionally over
    the first ``periods`` forcing periods of the record only (units of ``da``)."""
    if periods is not None and ds is not None and "forcing_period" in ds.attrs:
        t0 = float(ds.time[0])
        da = da.sel(time=slice(t0, t0 + periods * float(ds.attrs["forcing_period"]) * (1 + 1e-9)))
    values = np.asarray(da.values, dtype=float)
    if not np.isfinite(values).any():
        return float("nan")
    return float(values.flat[int(np.nanargmax(np.abs(values)))])


def strobe(ds: xr.Dataset, da: xr.DataArray) -> xr.DataArray:
    """Stroboscopic samples of ``da`` (a variable of the run ``ds``, possibly with labels
    selected): :func:`workbench.analysis.poincare_section` on it."""
    from workbench.analysis import poincare_section

    name = da.name or "value"
    return poincare_section(xr.Dataset({name: da}, attrs=ds.attrs), name)[name]


def clearance_of(scene: Scene, joint: str) -> float:
    """Radial clearance (m) of ``joint`` in a nine-bar scene."""
    return float(get_model(scene.model).clearances(dict(scene.resolved_parameters))[joint])


def strobe_spread(ds: xr.Dataset, scene: Scene, var: str, where: dict) -> float:
    """Standard deviation of the stroboscopic samples of a clearance coordinate, in units of the
    joint's clearance (dimensionless): 0 for a period-1 orbit, about 0.3-0.7 for a journal that
    wanders over its bearing."""
    da = strobe(ds, select(ds, var, where))
    return float(np.nanstd(da.values) / clearance_of(scene, where["joint"]))


def seconds_per_cycle(ds: xr.Dataset, scene: Scene) -> float:
    """Wall time of the integration per simulated crank cycle (s), transient included."""
    cycles = scene.run.get("cycles", 0) + scene.run.get("transient_cycles", 0)
    return float(ds.attrs["solver_wall_time"]) / max(cycles, 1)
