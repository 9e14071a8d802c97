"""Assembly of a campaign's block files into one dataset over the parameter grid (client only)."""

from __future__ import annotations

import json
from collections.abc import Mapping

import numpy as np
import xarray as xr

from workbench._attributes import variable
from workbench._processor import PROCESSOR_ATTRS
from workbench.archive import RECORD_DIM, RECORD_TIME
from workbench.campaign._block import (
    FAILURE_ATTRS,
    POINT_WALL_ATTRS,
    STATS,
    STATUS,
    STATUS_ATTRS,
    failed,
    stat_attrs,
)
from workbench.campaign._grid import SweepGrid, format_point, grid_periods, parameter_attrs
from workbench.models import get_model
from workbench.run import (
    PARAMETERS_ATTR,
    REALISATION_ATTRS,
    parameter_coords,
    provenance,
    record_times,
)
from workbench.scene import Scene

__all__ = ["assemble_blocks", "execution_attrs", "summary"]

_PER_POINT = ("status", "failure", *STATS, "point_wall_time")


def _grid_attrs(scene: Scene, grid: SweepGrid) -> tuple[dict, np.ndarray | None]:
    """Attributes of the record grid shared by every point, and the per-point forcing period (s,
    None for an autonomous model)."""
    periods = grid_periods(scene, grid)
    if periods is None:
        periods_arr = None
        variants = [record_times(scene, 0.0, None)[1]]
    else:
        periods_arr = np.array(np.broadcast_to(periods, grid.shape))
        variants = [record_times(scene, 0.0, p)[1] for p in np.unique(periods).tolist()]
    shared = {k: v for k, v in variants[0].items() if all(w.get(k) == v for w in variants)}
    return shared, periods_arr


def execution_attrs(this: Mapping, previous: Mapping | None) -> dict:
    """The attributes that describe a call of a campaign (``this``: ``campaign_workers``,
    ``campaign_compute_wall_time``, ``campaign_wall_time``, ...) as its archive keeps them
    after a call that computed no block: the ``campaign_*`` values of the call that computed
    them, from ``previous`` (the attributes of the archive assembled from the same blocks
    before, :meth:`Store.assembled_attrs`), and this call's as ``resume_*`` (the latest such
    call's). Without ``previous`` (none, or without those attributes), ``this`` as it is."""
    if previous is None or not all(k in previous for k in this):
        return dict(this)
    kept = {k: previous[k] for k in this}
    return kept | {f"resume_{k.removeprefix('campaign_')}": v for k, v in this.items()}


def assemble_blocks(
    scene: Scene, grid: SweepGrid, blocks: list[xr.Dataset], by: str = "workbench.run_campaign"
) -> xr.Dataset:
    """One dataset over the grid from block datasets (:func:`workbench.campaign._block.
    block_dataset`) that together hold every point once; the per-point measurements of a
    block (variables over ``point`` alone) become variables over the parameter dims, NaN where
    a block has none; ``by``: the function that creates the campaign (its provenance).

    Dims: the parameter dims (scene ``[sweep]`` order), then the records', then the model's
    dims; every other parameter of the model is a scalar coordinate with its units
    (:func:`workbench.run.parameter_coords`; ``model_parameters`` lists them, swept first).
    When every point has the same record times the records run along ``time``, their 1-D
    coordinate; otherwise (e.g. a sweep over the forcing frequency, a continued sweep) along
    ``record`` (the record's index in its point's run, no coordinate variable), and the
    auxiliary coordinate ``record_time`` (parameter dims, record; ``standard_name`` "time")
    holds each point's times, NaN-padded (:mod:`workbench.archive._format`, format 4)."""
    n, shape = grid.size, grid.shape
    n_time = max(b.sizes[RECORD_DIM] for b in blocks)
    first = blocks[0]

    def gather(name: str, fill) -> np.ndarray:
        v0 = first[name]
        tail = tuple(n_time if d == RECORD_DIM else v0.sizes[d] for d in v0.dims[1:])
        dtype = object if v0.dtype.kind in "OUS" else v0.dtype
        out = np.full((n,) + tail, fill, dtype=dtype)
        for b in blocks:
            v = b[name].values
            idx = b["point"].values
            if RECORD_DIM in b[name].dims:
                out[idx, : v.shape[1]] = v
            else:
                out[idx] = v
        return out.reshape(shape + tail)

    pdims = grid.dims
    coords: dict = {}
    for d, values in zip(pdims, grid.values, strict=True):
        coords[d] = (d, np.array(values, np.float64), parameter_attrs(scene, d))
    rt = gather(RECORD_TIME, np.nan).reshape(n, n_time)
    usable = rt[np.isfinite(rt).any(axis=1)]
    shared = (
        len(usable) > 0 and np.isfinite(usable[0]).all() and (usable == usable[0]).all(axis=None)
    )
    time_attrs = dict(first[RECORD_TIME].attrs)
    # the records' dim: the shared times' coordinate variable, else the record's index
    rdim = "time" if shared else RECORD_DIM
    if shared:
        coords["time"] = ("time", usable[0], time_attrs)
    else:
        coords[RECORD_TIME] = (
            pdims + (RECORD_DIM,),
            rt.reshape(shape + (n_time,)),
            dict(time_attrs, long_name="time of the record (NaN past the end of the run)"),
        )
    model = get_model(scene.model)
    model_names = {p.name for p in model.parameters}
    for d, (values, attrs) in model.coords(scene.effects).items():
        coords[d] = (d, list(values), dict(attrs))

    data_vars: dict = {}
    for name in scene.variables:
        v0 = first[name]
        dims = tuple(rdim if d == RECORD_DIM else d for d in v0.dims[1:])
        data_vars[name] = (pdims + dims, gather(name, np.nan), dict(v0.attrs))
    grid_attrs, periods = _grid_attrs(scene, grid)
    if periods is not None:
        data_vars["forcing_period"] = (
            pdims,
            periods,
            variable("period of the external forcing", "s"),
        )
    status = gather("status", -1).astype(np.int8)
    data_vars["status"] = (pdims, status, STATUS_ATTRS)
    failure = gather("failure", "").astype(str).astype(object)
    data_vars["failure"] = (pdims, failure, FAILURE_ATTRS)
    for name, (_, dtype, missing, _) in STATS.items():
        data_vars[name] = (pdims, gather(name, missing).astype(dtype), stat_attrs(name))
    data_vars["point_wall_time"] = (pdims, gather("point_wall_time", np.nan), POINT_WALL_ATTRS)
    for name, (tail, attrs) in _measured_variables(scene, blocks).items():
        data_vars[name] = (
            pdims + tail[0],
            _measured(name, tail[1], n, blocks).reshape(shape + tail[1]),
            attrs,
        )

    params = parameter_coords(
        model, scene.resolved_parameters, skip=pdims, taken=[*coords, *data_vars]
    )
    coords.update(params)
    if "realisation" in scene.run and "realisation" not in pdims:
        coords["realisation"] = ((), np.int64(scene.run["realisation"]), dict(REALISATION_ATTRS))
    ds = xr.Dataset(data_vars, coords=coords)
    ds.attrs[PARAMETERS_ATTR] = " ".join([*(d for d in pdims if d in model_names), *params])
    prov = provenance(scene, by=by)
    if not scene.title:
        prov["title"] = f"workbench campaign of model {scene.model} over {', '.join(pdims)}"
    ds.attrs.update(prov)
    s = scene.solver
    n_failed = int(failed(status).sum())
    ds.attrs.update(
        model=scene.model,
        campaign_dims=" ".join(pdims),
        campaign_grid=json.dumps(grid.as_dict()),
        campaign_points=n,
        failed_points=n_failed,
        solver_method=s["method"],
        solver_rtol=s["rtol"],
        solver_atol=s["atol"],
        solver_max_step=s["max_step"],
        solver_max_steps=s["max_steps"],
    )
    ds.attrs.update(grid_attrs)
    compiled_on, processor = _compiled_on(blocks, n, shape, pdims)
    ds.attrs.update(processor)
    if compiled_on is not None:
        ds["compiled_on"] = compiled_on
    return ds


NOT_RECORDED = "not recorded"  # a block written before 0.6.0 names no processor


def _compiled_on(
    blocks: list[xr.Dataset], n: int, shape: tuple[int, ...], pdims: tuple[str, ...]
) -> tuple[xr.DataArray | None, dict[str, str]]:
    """Which processor and compile target computed each point (each block records its worker's,
    :func:`workbench._processor.processor_attrs`): the campaign's attributes when every block
    names the same, else those attributes say "mixed" and the variable ``compiled_on`` (over the
    parameter dims) gives each point's index into the attribute ``compile_targets``."""
    keys = [tuple(b.attrs.get(a, NOT_RECORDED) for a in PROCESSOR_ATTRS) for b in blocks]
    distinct = list(dict.fromkeys(keys))
    if len(distinct) == 1:
        return None, dict(zip(PROCESSOR_ATTRS, distinct[0], strict=True))
    index = np.full(n, -1, np.int16)
    for b, key in zip(blocks, keys, strict=True):
        index[b["point"].values] = distinct.index(key)
    listing = "; ".join(
        f"{i}: " + ", ".join(f"{a} {v}" for a, v in zip(PROCESSOR_ATTRS, key, strict=True))
        for i, key in enumerate(distinct)
    )
    var = xr.DataArray(
        index.reshape(shape),
        dims=pdims,
        attrs=variable(
            "index of the processor and compile target that computed the point",
            "1",
            compile_targets=listing,
            comment="other processors round differently: a chaotic quantity agrees across "
            "them within its error, not in digits (docs/cluster.md)",
        ),
    )
    mixed = "mixed: see the variable compiled_on"
    return var, dict.fromkeys(PROCESSOR_ATTRS, mixed)


def _measured(name: str, tail: tuple[int, ...], n: int, blocks: list[xr.Dataset]) -> np.ndarray:
    """One per-point measurement over the ``n`` points: in its own dtype where every point has
    it (an integer flag stays an integer, as CF flags must), else as floats, NaN where a point
    has none."""
    values = [(b["point"].values, b[name].values) for b in blocks if name in b.data_vars]
    dtypes = {v.dtype for _, v in values}
    covered = sum(len(idx) for idx, _ in values) == n
    keep = len(dtypes) == 1 and covered and next(iter(dtypes)).kind in "biu"
    out = np.full((n,) + tail, 0 if keep else np.nan, dtype=next(iter(dtypes)) if keep else float)
    for idx, v in values:
        out[idx] = v
    return out


def _measured_variables(scene: Scene, blocks: list[xr.Dataset]) -> dict:
    """Per-point measurements found in the blocks: name -> ((dims, sizes) after ``point``,
    attrs), in the order first seen."""
    known = {*scene.variables, *_PER_POINT, RECORD_TIME}
    found: dict = {}
    for b in blocks:
        for name, v in b.data_vars.items():
            if name in known or name in found or RECORD_DIM in v.dims or v.dims[:1] != ("point",):
                continue
            found[name] = ((v.dims[1:], v.shape[1:]), dict(v.attrs))
    return found


def summary(ds: xr.Dataset, *, limit: int = 20) -> str:
    """A few lines on a campaign dataset: points, blocks, time, and every failed point's cause.

    Parameters
    ----------
    ds : xarray.Dataset
        As returned by :func:`workbench.run_campaign` (or read with :func:`workbench.open_run`).
    limit : int
        Show at most this many failed points.
    """
    a = ds.attrs
    dims = a["campaign_dims"].split()
    status = ds["status"]
    counts = {name: int((status == code).sum()) for code, name in STATUS.items()}
    head = (
        f"campaign of {a['model']} over {' x '.join(f'{d} ({ds.sizes[d]})' for d in dims)}: "
        f"{a['campaign_points']} points in {a['campaign_blocks']} blocks "
        f"({a.get('computed_blocks', '?')} computed, {a.get('reused_blocks', '?')} reused)"
    )
    if "resume_wall_time" in a:  # nothing computed: this call's time, and the computation's
        head += (
            f", {a['resume_wall_time']:.3g} s wall (computed before in "
            f"{a['campaign_wall_time']:.3g} s wall)"
        )
    elif "campaign_wall_time" in a:
        head += f", {a['campaign_wall_time']:.3g} s wall"
    lines = [head, "; ".join(f"{v} {k}" for k, v in counts.items() if v or k == "ok")]
    flags = status.transpose(*dims).values.reshape(-1)
    failure = ds["failure"].transpose(*dims).values.reshape(-1)
    bad = np.flatnonzero(failed(flags))
    for i in bad[:limit]:
        idx = np.unravel_index(i, tuple(ds.sizes[d] for d in dims))
        point = {d: float(ds[d].values[j]) for d, j in zip(dims, idx, strict=True)}
        lines.append(f"  failed {format_point(point)}: {failure[i]}")
    if len(bad) > limit:
        lines.append(f"  ... and {len(bad) - limit} more failed points (see 'failure')")
    return "\n".join(lines)
