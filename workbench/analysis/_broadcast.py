"""Series estimators over the parameter dims of a campaign: one result per point, lazily.

A campaign's record ``x`` has parameter dims (``omega``, ``clearance``, ...), a model dim or two
(``joint``) and one dim of its own, the series' (``time``; ``record`` when the points have their
own record times; ``strobe`` for a Poincaré section).
:func:`over_parameters` makes an estimator of one series (the 0-1 test, Wolf's exponent, ...)
map over every other dim: ``zero_one_test(campaign.x)`` returns ``K`` over (omega, clearance)
with each point's evidence (``K_c`` over (omega, clearance, c)), the units of the estimator's
own result, and ``analysis_error`` (the message of a point the estimator refused: a failed
campaign point, all NaN; empty when none).

Each point is an ordinary call of the estimator on a 1-D DataArray: its values without the NaN
that pad a shorter run at the end, its own record times (``record_time`` over ``record``, s,
when the points' times differ: a sweep over the forcing frequency, a continued sweep; the
point's series then runs along ``time`` with them as its coordinate; ``strobe_time`` over
``strobe`` for the Poincaré section of such a campaign) or the shared ``time`` coordinate, and
the series' name, units and attributes (a ``forcing_period`` coordinate over the parameter dims
becomes the point's ``forcing_period`` attribute).

On a dask-backed record (an archive opened with chunks, ``workbench.open_run(path,
chunks=...)``) nothing is loaded or computed: the result is dask-backed too
(:func:`xarray.apply_ufunc` with ``dask="parallelized"``, one task per chunk of points, run by
whatever dask scheduler computes it, a cluster's included). Dask needs every output's shape
before anything runs, so the layout (variables, their dims, the length of each evidence dim) is
read from a few points computed at once (the first, middle and last: ``PROBES``); a point whose
evidence is longer than that layout (or whose evidence coordinate differs from the one the
probes share) keeps its values (every scalar) but has that evidence cut or blanked, and
``evidence_complete`` (int8) is 0 there. ``evidence_sizes={"lag": 200}`` enlarges the layout.
On an in-memory record every point is computed first and the layout fits them all.

Layout of the result: the parameter dims first, then each variable's own dims. An evidence dim
keeps its coordinate when all points share it (the 0-1 test's ``c``; a lag in samples; on a
shared prefix when lengths differ); otherwise the dim is positional and ``<coord>_value`` holds
each point's coordinate (Wolf's ``elapsed`` time). Shorter evidence is padded (NaN, or -1 for
integers). An attribute of the estimator's result that differs between points becomes a
variable per point (``<attribute>`` for the dataset's, ``<variable>_<attribute>`` for a
variable's: Wolf's ``warning`` and ``reliable_message``). The layout and its filling live in
``_broadcast_layout``.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

import numpy as np
import xarray as xr

from workbench.analysis._broadcast_layout import ResultLayout, all_failed
from workbench.analysis._series import seconds
from workbench.archive import RECORD_DIM, RECORD_TIME

__all__ = ["PROBES", "SERIES_DIMS", "broadcast", "over_parameters"]

#: the dims a series runs along: a record (``time``, or ``record`` with each point's times in
#: ``record_time``), a section
SERIES_DIMS = ("time", RECORD_DIM, "strobe")
PROBES = 3  # points computed at once to lay out the result of a dask-backed record


def over_parameters(estimator: Callable[..., xr.Dataset]) -> Callable[..., xr.Dataset]:
    """An estimator of one series (first argument ``x``) that also takes a DataArray with
    more dims: it then maps over every dim but the series' own (:func:`broadcast`); any other
    input goes to ``estimator`` unchanged."""

    @functools.wraps(estimator)
    def wrapper(x: Any = None, *args: Any, **kwargs: Any) -> xr.Dataset:
        if isinstance(x, xr.DataArray) and x.ndim > 1:
            return broadcast(estimator, x, *args, **kwargs)
        kwargs.pop("evidence_sizes", None)
        return estimator(x, *args, **kwargs)

    wrapper.__doc__ = (estimator.__doc__ or "") + _NOTE
    return wrapper


_NOTE = """
    Over parameter dims: given a DataArray with dims besides its series' (``time``,
    ``record`` or ``strobe``), e.g. a campaign's record, it returns one result per point over
    those dims, lazily for a dask-backed one (see :mod:`workbench.analysis._broadcast`;
    ``evidence_sizes`` sets the length of evidence dims in the lazy layout).
"""


def broadcast(
    estimator: Callable[..., xr.Dataset],
    x: xr.DataArray,
    *args: Any,
    evidence_sizes: dict[str, int] | None = None,
    **kwargs: Any,
) -> xr.Dataset:
    """Apply ``estimator(series, *args, **kwargs)`` to the series at every point of ``x``'s other
    dims (see the module docstring for the layout of the result).

    Parameters
    ----------
    estimator : callable
        Takes a 1-D DataArray (dim ``time`` or ``strobe``) and returns an :class:`xarray.Dataset`
        (a record along ``record`` reaches it along ``time``, with the point's times).
    x : xarray.DataArray
        One dim in :data:`SERIES_DIMS`, any others; numpy- or dask-backed.
    evidence_sizes : dict, optional
        Length of evidence dims (name -> int) in the layout of a dask-backed ``x``.

    Raises
    ------
    ValueError
        ``x`` has no series dim or two; an evidence dim of the estimator has the name of one of
        ``x``'s dims; every probed point of a dask-backed ``x`` failed (the message says why).
    """
    sdim = _series_dim(x)
    loop = tuple(d for d in x.dims if d != sdim)
    x = x.transpose(*loop, sdim)
    times, shared_times = _times(x, sdim, loop)
    for t in (times, None if shared_times is None else x[shared_times]):
        if t is not None:  # dates (plain xarray decodes CF times) are refused, not read as ns
            seconds(str(x.name), np.empty(0, t.dtype), str(t.name))
    periods = _periods(x, loop)
    shape = tuple(x.sizes[d] for d in loop)
    template = _template(x, sdim, shared_times)

    def run(values, t, period) -> xr.Dataset | str:
        try:
            series = _series(template, sdim, values, t, period)
            return estimator(series, *args, **kwargs)
        except Exception as exc:  # any error is this point's data (its analysis_error), as a
            # campaign point's is: a failed point (all NaN), one the estimator refuses, ...
            return f"{type(exc).__name__}: {exc}"

    def point(index: tuple[int, ...]) -> xr.Dataset | str:
        t = None if times is None else times[index].values
        period = None if periods is None else float(periods[index].values)
        return run(x[index].values, t, period)

    lazy = x.chunks is not None
    indices = list(np.ndindex(*shape))
    if lazy:
        picks = sorted({0, len(indices) // 2, len(indices) - 1}) if indices else []
        results = {indices[k]: point(indices[k]) for k in picks}
        extra = [k for k in range(len(indices)) if k not in picks]
        while extra and len(results) < 4 * PROBES:
            if any(isinstance(r, xr.Dataset) for r in results.values()):
                break
            k = extra.pop(0)  # every probe failed: look further for a point that works
            results[indices[k]] = point(indices[k])
    else:
        x, times, periods = x.load(), _load(times), _load(periods)
        results = {i: point(i) for i in indices}
    good = [r for r in results.values() if isinstance(r, xr.Dataset)]
    if not good:
        if lazy or not results:
            first = next(iter(results.values()), "x has no points")
            raise ValueError(f"the estimator failed at every probed point of x: {first}")
        return all_failed(x, loop, results, shape)
    layout = ResultLayout(good, loop, evidence_sizes, lazy)
    if not lazy:
        arrays = layout.allocate(shape)
        for i, r in results.items():
            layout.fill(arrays, i, r)
        return layout.dataset(x, loop, arrays)

    outputs = layout.outputs

    def block(values: np.ndarray, t: np.ndarray, period: np.ndarray) -> tuple[np.ndarray, ...]:
        lead = values.shape[:-1]
        arrays = layout.allocate(lead)
        for i in np.ndindex(*lead):
            tt = None if times is None else t[i]
            pp = None if periods is None else float(period[i])
            layout.fill(arrays, i, run(values[i], tt, pp))
        return tuple(arrays[name] for name, _, _, _ in outputs)

    t_in = times if times is not None else xr.zeros_like(x, dtype=np.float64)
    p_in = periods if periods is not None else xr.zeros_like(x.isel({sdim: 0}), dtype=float)
    result = xr.apply_ufunc(
        block,
        x,
        t_in,
        p_in,
        input_core_dims=[[sdim], [sdim], []],
        output_core_dims=[list(dims) for _, dims, _, _ in outputs],
        dask="parallelized",
        output_dtypes=[dtype for _, _, dtype, _ in outputs],
        dask_gufunc_kwargs={"output_sizes": layout.sizes, "allow_rechunk": True},
        keep_attrs=False,
    )
    arrays = {name: r.variable for (name, _, _, _), r in zip(outputs, result, strict=True)}
    return layout.dataset(x, loop, arrays)


def _load(a: xr.DataArray | None) -> xr.DataArray | None:
    return None if a is None else a.load()


def _series_dim(x: xr.DataArray) -> str:
    found = [d for d in x.dims if d in SERIES_DIMS]
    if len(found) != 1:
        raise ValueError(
            f"x ({x.name!r}, dims {x.dims!r}) needs exactly one series dim of "
            f"{SERIES_DIMS!r} to map an estimator over its other dims; it has {len(found)}"
        )
    return found[0]


def _times(x: xr.DataArray, sdim: str, loop: tuple[str, ...]):
    """Each point's record times (s) when they differ between points (``record_time`` or
    ``strobe_time`` over the parameter dims and ``sdim``), else None with the shared
    coordinate's name."""
    for name in (RECORD_TIME, "strobe_time"):
        if name in x.coords and sdim in x[name].dims and x[name].ndim > 1:
            rt = x[name].reset_coords(drop=True)
            return rt.broadcast_like(x).transpose(*loop, sdim), None
    if sdim == RECORD_DIM:
        raise ValueError(
            f"x ({x.name!r}) runs along {RECORD_DIM!r} without {RECORD_TIME!r} over it (each "
            "point's record times): open the campaign with workbench.open_run to keep them"
        )
    for name in (sdim, "strobe_time"):
        if name in x.coords and x[name].dims == (sdim,):
            return None, name
    return None, None


def _periods(x: xr.DataArray, loop: tuple[str, ...]):
    """Each point's forcing period (s) from a ``forcing_period`` coordinate over parameter dims."""
    if "forcing_period" in x.coords and x["forcing_period"].ndim > 0:
        fp = x["forcing_period"].reset_coords(drop=True)
        return fp.broadcast_like(x.isel({d: 0 for d in x.dims if d not in loop})).transpose(*loop)
    return None


def _template(x: xr.DataArray, sdim: str, shared: str | None) -> dict:
    """What every point's series carries: name, attributes, the shared series coordinate."""
    attrs = dict(x.attrs)
    if "forcing_period" in x.coords and x["forcing_period"].ndim == 0:
        attrs.setdefault("forcing_period", float(x["forcing_period"]))
    coord = None
    if shared is not None:
        c = x[shared]
        coord = (shared, np.asarray(c.values), dict(c.attrs))
    time_attrs = {"units": "s"}
    for name in (RECORD_TIME, "strobe_time"):
        if name in x.coords and sdim in x[name].dims:
            time_attrs = dict(x[name].attrs)
    return {"name": x.name, "attrs": attrs, "coord": coord, "time_attrs": time_attrs}


def _series(template: dict, sdim: str, values, t, period) -> xr.DataArray:
    """One point's series: its values and times without the trailing NaN of a shorter run."""
    values = np.asarray(values, dtype=float)
    keep = values.size
    t = None if t is None else np.asarray(t, dtype=float)
    pad = ~np.isfinite(values) if t is None else (~np.isfinite(values) & ~np.isfinite(t))
    while keep and pad[keep - 1]:
        keep -= 1
    if keep == 0:
        raise ValueError("the point's record is all NaN (a campaign point that failed?)")
    coords = {}
    if sdim == RECORD_DIM:  # a point's own record: along time, as a run's
        sdim = "time"
    if t is not None:
        name = "time" if sdim == "time" else "strobe_time"
        coords[name] = (sdim, t[:keep], template["time_attrs"])
    elif template["coord"] is not None:
        name, c, attrs = template["coord"]
        coords[name] = (sdim, c[:keep], attrs)
    attrs = dict(template["attrs"])
    if period is not None and np.isfinite(period):
        attrs["forcing_period"] = period
    return xr.DataArray(
        values[:keep], dims=(sdim,), coords=coords, name=template["name"], attrs=attrs
    )
