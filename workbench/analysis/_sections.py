"""Phase portraits and Poincaré sections of runs: stroboscopic samples of forced systems and
hyperplane crossings of autonomous ones (Guckenheimer & Holmes 1983, Sec. 1.4)."""

from __future__ import annotations

import numpy as np
import xarray as xr

from workbench._attributes import variable
from workbench.analysis._series import time_record
from workbench.archive import RECORD_DIM, RECORD_TIME

__all__ = ["phase_portrait", "poincare_section", "crossing_section", "rate_of"]


def rate_of(ds: xr.Dataset, var: str) -> str:
    """Name of the variable holding the rate of ``var`` in a run: the one its attribute
    ``rate_variable`` names (the model's declaration, :class:`workbench.models.Quantity`), else
    by the models' convention (``v`` for Duffing's ``x``, ``clearance_vx`` for
    ``clearance_x``); a clear error if none is stored."""
    candidates = {"x": "v", "clearance_x": "clearance_vx", "clearance_y": "clearance_vy"}
    name = ds[var].attrs.get("rate_variable") if var in ds else None
    name = name or candidates.get(var)
    if name is None or name not in ds:
        raise KeyError(
            f"no rate variable for {var!r} in the run (looked for {name!r}); record it or pass "
            "rate=<name>"
        )
    return name


def phase_portrait(ds: xr.Dataset, var: str, *, rate: str | None = None) -> xr.Dataset:
    """(value, rate) pairs of ``var`` over the run: a Dataset with ``value`` and ``rate`` over
    ``time``, with their units.

    Examples
    --------
    >>> import workbench
    >>> ds = workbench.simulate({"model": {"name": "duffing"}, "run": {"cycles": 2}})
    >>> sorted(phase_portrait(ds, "x").data_vars)
    ['rate', 'value']
    """
    rate = rate or rate_of(ds, var)
    return xr.Dataset(
        {"value": ds[var], "rate": ds[rate]},
        attrs={"variable": var, "rate_variable": rate},
    )


def poincare_section(
    ds: xr.Dataset, var: str | None = None, *, period: float | None = None
) -> xr.Dataset:
    """Stroboscopic samples at t0 + k T of a forced run (one per forcing period).

    The samples are read from the run's record grid, which lies exactly at ``t0 + k T /
    samples_per_period`` (no interpolation); ``period`` (s) defaults to the run's
    ``forcing_period`` and must be a whole number of record steps. For a campaign (parameter
    dims) every point is sampled alike; where its points have their own record times (along
    ``record``, with ``record_time``) the samples' times are ``strobe_time`` over the
    parameter dims and ``strobe``.

    Parameters
    ----------
    ds : xarray.Dataset
        A run of :func:`workbench.simulate` or a campaign of :func:`workbench.run_campaign`.
    var : str, optional
        Sample only this variable (default: every variable).
    period : float, optional
        Sampling period, s (default the forcing period).

    Returns
    -------
    xarray.Dataset
        The variables (with their units) over dim ``strobe`` (sample index) with coordinate
        ``strobe_time`` (s).

    Raises
    ------
    ValueError
        If the record grid lacks the strobe times.

    Examples
    --------
    >>> import workbench
    >>> ds = workbench.simulate({"model": {"name": "duffing"}, "run": {"cycles": 5},
    ...                          "record": {"samples_per_period": 10}})
    >>> poincare_section(ds, "x").x.sizes["strobe"]
    6
    """
    spp = ds.attrs.get("samples_per_period")
    # a run has the forcing period as an attribute; a campaign (which may sweep the forcing
    # frequency) as a variable over its parameter dims: its records are per period all the same
    forcing = ds.attrs.get("forcing_period")
    if forcing is None and "forcing_period" in ds.variables:
        forcing = "per point"
    if spp is None or forcing is None:
        raise ValueError(
            "a stroboscopic section needs a forced run recorded per period (record."
            f"samples_per_period); this run has samples_per_period={spp!r}, "
            f"forcing_period={forcing!r}"
        )
    step = float(spp)
    if period is not None:
        if forcing == "per point":
            raise ValueError("period= needs a single run (a campaign's periods differ by point)")
        step = float(period) / float(forcing) * int(spp)
    if abs(step - round(step)) > 1e-9 * max(step, 1) or round(step) < 1:
        raise ValueError(
            f"period={period!r} s is not a whole number of record steps ({forcing!r} s / {spp}): "
            "the record grid does not contain these strobe times"
        )
    out = ds if var is None else ds[[var]]
    rdim = RECORD_DIM if RECORD_DIM in out.dims else "time"  # each point's times, or shared
    out = out.isel({rdim: slice(None, None, int(round(step)))})
    strobe_attrs = variable("strobe time", "s")
    if rdim == RECORD_DIM:
        times = out[RECORD_TIME].variable if RECORD_TIME in out.coords else None
        out = out.drop_vars(RECORD_TIME, errors="ignore").rename({RECORD_DIM: "strobe"})
        if times is not None:
            dims = tuple("strobe" if d == RECORD_DIM else d for d in times.dims)
            out = out.assign_coords(strobe_time=(dims, times.values, strobe_attrs))
        times = None
    else:
        times = out["time"].values if "time" in out.coords else None
        out = out.rename(time="strobe")
    if times is not None:
        out = out.drop_vars("time", errors="ignore").assign_coords(
            strobe_time=("strobe", times, strobe_attrs)
        )
    return out.assign_coords(strobe=("strobe", np.arange(out.sizes["strobe"]), variable("period")))


def crossing_section(ds: xr.Dataset, var: str, level: float, *, direction: int = 1) -> xr.Dataset:
    """States where ``var`` crosses ``level`` (upwards for ``direction=1``, downwards for -1,
    both for 0), linearly interpolated between records: the Poincaré section of an autonomous
    run (e.g. Lorenz at z = rho - 1), or of one point of a campaign (:func:`time_record`). Dim
    ``crossing`` with coordinate ``crossing_time`` (s). ValueError when ``var`` is not a
    single series over ``time``."""
    ds = time_record(ds)
    if ds[var].dims != ("time",):
        raise ValueError(
            f"a crossing section needs one series over 'time'; {var!r} has dims "
            f"{ds[var].dims!r}: select one element of the others first"
        )
    v = ds[var].values - level
    a, b = v[:-1], v[1:]
    up = (a < 0) & (b >= 0)
    down = (a > 0) & (b <= 0)
    hit = up if direction > 0 else down if direction < 0 else (up | down)
    i = np.flatnonzero(hit)
    w = a[i] / (a[i] - b[i])
    t = ds.time.values
    data = {}
    for name, da in ds.data_vars.items():
        if da.dims != ("time",):
            continue
        x = da.values
        data[name] = ("crossing", x[i] + w * (x[i + 1] - x[i]), dict(da.attrs))
    return xr.Dataset(
        data,
        coords={
            "crossing": ("crossing", np.arange(i.size), variable("crossing")),
            "crossing_time": (
                "crossing",
                t[i] + w * (t[i + 1] - t[i]),
                variable("crossing time", "s"),
            ),
        },
        attrs={"section": f"{var} = {level!r}, direction {direction}"},
    )
