"""Bifurcation diagrams from campaigns: stroboscopic samples against a swept parameter, and where
a sweep's period-1 motion ends."""

from __future__ import annotations

import numpy as np
import xarray as xr

from workbench.analysis._sections import poincare_section
from workbench.archive import status_flags
from workbench.solver import Status

__all__ = ["bifurcation_diagram", "periodic_run_end"]


def bifurcation_diagram(runs: xr.Dataset, var: str, param: str | None = None) -> xr.Dataset:
    """Stroboscopic samples of ``var`` over the parameter ``param`` of a campaign.

    Parameters
    ----------
    runs : xarray.Dataset
        A campaign (from :func:`workbench.run_campaign`) whose records are per forcing period
        after the transient.
    var : str
        The sampled variable.
    param : str, optional
        The parameter of the x axis; default the campaign's only parameter dim.

    Returns
    -------
    xarray.Dataset
        ``var`` with dims ``(param, strobe, ...)`` (NaN where a point failed) and its units,
        the campaign's ``status`` per point (when it has one); attributes
        ``diagram_parameter`` and ``diagram_variable``. Storable as netCDF and drawn
        by :func:`workbench.plot.bifurcation_figure`.

    Raises
    ------
    ValueError
        If ``param`` is not a swept dim, ``var`` is missing, the runs have no strobe grid, or
        no sample of ``var`` is finite (nothing to draw: the message says whether every point
        failed or the values are inf or NaN).
    workbench.archive.ArchiveError
        A flag of ``status`` is not a whole number (NaN: the archive was altered or damaged).
    """
    swept = [d for d in runs.dims if d in runs.coords and d not in ("time", "joint", "crank")]
    if param is None:
        if len(swept) != 1:
            raise ValueError(
                f"the campaign varies {swept!r}; name the parameter of the diagram (param=...) "
                "and select one value of the others first"
            )
        param = swept[0]
    if param not in runs.dims:
        raise ValueError(f"{param!r} is not a parameter dim of the campaign; dims: {swept!r}")
    if var not in runs:
        raise ValueError(f"no variable {var!r}; variables: {sorted(runs.data_vars)}")
    flags = status_flags(runs["status"], "the campaign") if "status" in runs else None
    samples = poincare_section(runs, var).transpose(param, "strobe", ...)
    values = samples[var].values
    if not np.isfinite(values).any():
        ran = (Status.OK, Status.TERMINATED)
        n_failed = 0 if flags is None else int((~np.isin(flags, ran)).sum())
        why = (
            f"every one of its {flags.size} points failed"
            if flags is not None and n_failed == flags.size
            else f"its {values.size} samples are all inf or NaN "
            f"({int(np.isinf(values).sum())} inf, {int(np.isnan(values).sum())} NaN)"
        )
        raise ValueError(
            f"no finite sample of {var!r} to draw: {why}; choose another variable, or "
            "recompute the campaign"
        )
    if flags is not None:  # which points failed (their samples are NaN), for the figure
        samples["status"] = runs["status"]
    samples.attrs.update(diagram_parameter=param, diagram_variable=var)
    return samples


def periodic_run_end(values, periods) -> float | None:
    """The last of ``values`` (ascending) in the run of period-1 ``periods`` that starts at the
    first value (None: the first is not period-1). For a sweep going up, where its periodic
    motion ends; for one coming down, where periodic motion has set in again.

    >>> periodic_run_end([1.0, 1.1, 1.2, 1.3], [1, 1, 0, 1])
    1.1
    """
    last = None
    for v, k in zip(values, periods, strict=True):
        if k != 1:
            break
        last = v
    return last
