"""Numbers a study compares with the paper: peaks, stroboscopic spreads, LLEs, timings, contact.

A study runs every case as an ensemble (dim ``realisation``, see :mod:`workbench.run._ensemble`);
:func:`member_run` and :func:`realisation_run` cut one case (or one point of a sweep) and one
realisation out of the campaign dataset, and the functions below measure a single run. Peaks
carry the units of the variable, spreads are in units of the clearance c (dimensionless), LLEs
in 1/s, timings in s, contact fractions in 1 and energies per cycle in J.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from workbench._attributes import variable
from workbench.archive import SERIES_DIMS
from workbench.models import get_model
from workbench.scene import Scene

__all__ = [
    "select",
    "peak",
    "strobe",
    "strobe_spread",
    "seconds_per_cycle",
    "clearance_of",
    "member_run",
    "realisation_run",
    "contact_fraction",
    "force_percentiles",
    "energy_per_cycle",
    "friction_law",
    "PERCENTILES",
]

# The four clearance coordinates of the paper's Sec. 5: x1, y1 (joint A), x2, y2 (joint B).
CLEARANCE_COORDINATES = {
    "x1": ("clearance_x", {"joint": "A"}),
    "y1": ("clearance_y", {"joint": "A"}),
    "x2": ("clearance_x", {"joint": "B"}),
    "y2": ("clearance_y", {"joint": "B"}),
}
PEAK_PERIODS = 2  # paper values: peaks over the first two recorded crank cycles, as in a plot

PERCENTILES = (50.0, 90.0, 99.0)  # of the contact force over time, %


def select(ds: xr.Dataset, var: str, where: dict | None = None) -> xr.DataArray:
    """``ds[var]`` with labels picked by ``where`` (e.g. ``{"joint": "A"}``); a clear error if
    the run lacks the variable or the label."""
    if var not in ds:
        raise KeyError(f"the run has no variable {var!r}; it has {sorted(ds.data_vars)}")
    da = ds[var]
    for dim, label in (where or {}).items():
        if dim not in da.dims or label not in da[dim].values:
            # e.g. contact force at B in a run with clearance only at A: nothing to measure
            return xr.full_like(da.isel({d: 0 for d in da.dims if d not in SERIES_DIMS}), np.nan)
        da = da.sel({dim: label})
    return da


def member_run(ds: xr.Dataset, select_params: dict[str, float] | None = None) -> xr.Dataset:
    """One case of a study's campaign as an ensemble: the point ``select_params`` of its
    parameter sweep (none for a case without one), dims ``realisation``, ``time`` and the
    model's; the forcing period (s) as the attribute ``forcing_period``."""
    from workbench.analysis._series import time_record

    if select_params:
        # a point of a sweep over the forcing frequency: its realisations' records in time
        ds = time_record(ds.sel(select_params, method="nearest"))
    if "forcing_period" in ds.data_vars:
        period = float(np.nanmax(ds["forcing_period"].values))
        ds = ds.drop_vars("forcing_period")
        ds.attrs["forcing_period"] = period
    return ds


def realisation_run(ds: xr.Dataset, realisation: int) -> xr.Dataset:
    """Realisation number ``realisation`` of a :func:`member_run`: a dataset like one run of
    :func:`workbench.simulate` (dims ``time`` and the model's)."""
    return ds.sel(realisation=float(realisation))


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


def seconds_per_cycle(wall_time: float, scene: Scene) -> float:
    """Wall time ``wall_time`` (s) of one run's integration per simulated crank cycle (s),
    transient included."""
    cycles = scene.run.get("cycles", 0) + scene.run.get("transient_cycles", 0)
    return float(wall_time) / max(cycles, 1)


def record_dim(da: xr.DataArray) -> str:
    """The dim ``da``'s records run along: ``time``, or ``record`` in a campaign whose points have
    their own record times (docs/archives.md)."""
    found = [d for d in da.dims if d in SERIES_DIMS]
    if len(found) != 1:
        raise ValueError(f"{da.name!r} (dims {da.dims!r}) has no record dim of {SERIES_DIMS!r}")
    return found[0]


def contact_fraction(force: xr.DataArray) -> xr.DataArray:
    """Fraction of the record with a contact force above zero (1): the share of time the
    journal touches its bearing (records are equally spaced in time). NaN records (a failed
    run) are left out; reduces dim ``time``."""
    valid = np.isfinite(force)
    rdim = record_dim(force)
    out = (force > 0).where(valid).sum(rdim) / valid.sum(rdim)
    return out.assign_attrs(variable("fraction of the time in contact"))


def force_percentiles(force: xr.DataArray, q: tuple[float, ...] = PERCENTILES) -> xr.DataArray:
    """The contact force exceeded during (100 - q) % of the time, for each q in ``q`` (N):
    percentiles over the record (zero while out of contact); new dim ``percentile`` (%)."""
    out = force.quantile(np.asarray(q) / 100.0, dim=record_dim(force), skipna=True)
    out = out.rename(quantile="percentile").assign_coords(
        percentile=("percentile", np.asarray(q), variable("percentile", "%"))
    )
    return out.assign_attrs(
        variable("percentile of the contact force over time", force.attrs.get("units", "N"))
    )


def energy_per_cycle(ds: xr.Dataset, var: str) -> xr.DataArray:
    """Change of a cumulative energy (``driver_work`` or ``dissipated_energy``, J) over the
    record, per forcing period (J per crank cycle); reduces dim ``time``."""
    da = ds[var]
    t = ds["time"]
    span = (t.isel(time=-1) - t.isel(time=0)) / float(ds.attrs["forcing_period"])
    out = (da.isel(time=-1) - da.isel(time=0)) / span
    long_name = f"{da.attrs.get('long_name', var)}: change per crank cycle"
    return out.drop_vars("time", errors="ignore").assign_attrs(variable(long_name, "J"))


def friction_law(ds: xr.Dataset, scene: Scene) -> dict[str, list[float]]:
    """Per realisation of a member (dim ``realisation``): ``mu_max``, the largest friction
    coefficient |F_t| / F_n at the records over the joints (1; from ``friction_ratio``,
    else from the friction and contact forces), ``mu_median``, its median over the records in
    contact (1), and for LuGre runs ``above`` and ``beyond``,
    the time per crank cycle (s, summed over the joints) with the coefficient above mu_s and
    beyond the law's envelope 2 mu_s + s2 |v_t| (the quadratures of
    :mod:`workbench.models._friction_report`, NaN without them). Empty without friction."""
    if "friction_ratio" in ds:
        mu = ds["friction_ratio"]
    elif "friction_force" in ds and "contact_force" in ds:
        fn = ds["contact_force"]
        mu = abs(ds["friction_force"]).where(fn > 0, 0.0) / fn.where(fn > 0, 1.0)
    else:
        return {}
    touching = ds["contact_force"] > 0 if "contact_force" in ds else mu > 0
    out = {
        "mu_max": [float(x) for x in mu.max(["time", "joint"]).values],
        "mu_median": [
            float(np.nanmedian(np.where(c, m, np.nan))) if c.any() else float("nan")
            for m, c in zip(
                mu.transpose("realisation", ...).values,
                touching.transpose("realisation", ...).values,
                strict=True,
            )
        ],
    }
    cycles = scene.run.get("cycles", 0)
    times = {"above": "time_above_static_friction", "beyond": "time_beyond_friction_law"}
    for key, var in times.items():
        if var in ds and cycles:
            total = ds[var].max("time").sum("joint", min_count=1) / cycles
            out[key] = [float(x) for x in total.values]
        else:
            out[key] = [float("nan")] * ds.sizes["realisation"]
    return out
