"""The points of a campaign: the grid of its sweep, each point's parameters and forcing period,
the limits checked before anything runs (points, memory), and what identifies a campaign (its
scene and block size) and its code (the digest of what computes a block).

Nothing here loops over the points of the grid in Python: a grid of 10^7 points is a few
arrays. The forcing period, model code that takes one point's parameters, is evaluated once
per combination of the swept parameters it reads (:func:`grid_periods`), e.g. once per value
of ``omega`` whatever else is swept.
"""

from __future__ import annotations

import hashlib
import itertools
import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass

import numpy as np

from workbench.campaign._errors import CampaignError
from workbench.models import get_model
from workbench.run import (
    REALISATION_ATTRS,
    check_memory,
    forcing_period,
    parameter_coords,
    record_count,
    results_digest,
    values_per_record,
    what_to_lower,
)
from workbench.scene import RUN_SWEEP_KEYS, Scene, SceneError

__all__ = [
    "MAX_POINTS",
    "SweepGrid",
    "campaign_id",
    "check_archive_memory",
    "check_points",
    "code_of",
    "modules_of",
    "expand_sweep",
    "format_point",
    "grid_periods",
    "parameter_attrs",
]

#: default limit on the points of one campaign (``max_points=``, CLI ``--max-points``)
MAX_POINTS = 10**6


@dataclass(frozen=True)
class SweepGrid:
    """The points of a campaign: the outer product of the swept values, in C order (not to be
    confused with a run's record times, :func:`workbench.run.record_times`).

    Attributes
    ----------
    dims : tuple[str, ...]
        Swept parameter names, in the scene's ``[sweep]`` order (the dataset's leading dims).
    values : tuple[tuple[float, ...], ...]
        The values of each dim (SI units of the parameter).
    """

    dims: tuple[str, ...]
    values: tuple[tuple[float, ...], ...]

    @property
    def shape(self) -> tuple[int, ...]:
        """The number of values of each swept dim, in the order of :attr:`dims`."""
        return tuple(len(v) for v in self.values)

    @property
    def size(self) -> int:
        """The number of points of the grid."""
        return math.prod(self.shape)

    def point(self, flat: int) -> dict[str, float]:
        """Parameter values of the point with flat (C-order) index ``flat``."""
        idx = np.unravel_index(flat, self.shape)
        return {
            d: self.values[k][int(i)] for k, (d, i) in enumerate(zip(self.dims, idx, strict=True))
        }

    def rows(self, flat) -> tuple[tuple[float, ...], ...]:
        """Parameter values of the points ``flat`` (flat indices), one tuple per point in
        ``dims`` order: the values of :meth:`point`, looked up for all points at once."""
        idx = np.unravel_index(np.asarray(flat, np.int64), self.shape)
        columns = [
            np.asarray(v, np.float64)[i].tolist() for v, i in zip(self.values, idx, strict=True)
        ]
        return tuple(zip(*columns, strict=True))

    def describe(self) -> str:
        """The dims and their lengths, e.g. ``"gamma 10000 x delta 1000"``."""
        return " x ".join(f"{d} {n}" for d, n in zip(self.dims, self.shape, strict=True))

    def blocks(self, chunk: int) -> list[range]:
        """Flat point indices of each block of ``chunk`` points (the last may be shorter)."""
        return [range(s, min(s + chunk, self.size)) for s in range(0, self.size, chunk)]

    def as_dict(self) -> dict[str, list[float]]:
        """The grid as ``{dim: values}`` (JSON-ready, as the manifest stores it)."""
        return {d: list(v) for d, v in zip(self.dims, self.values, strict=True)}


def expand_sweep(scene: Scene) -> SweepGrid:
    """The grid of a scene's ``[sweep]`` (CampaignError if it has none)."""
    if not scene.sweep:
        raise CampaignError(
            "a campaign needs a [sweep] table naming at least one parameter, e.g. "
            "[sweep] gamma = {start = 0.2, stop = 0.5, num = 40}; this scene has none "
            "(run a single scene with workbench.simulate)"
        )
    dims = tuple(scene.sweep)
    return SweepGrid(dims, tuple(tuple(float(x) for x in scene.sweep[d]) for d in dims))


def check_points(grid: SweepGrid, max_points: int | None = MAX_POINTS) -> None:
    """Refuse (CampaignError, one line) a grid of more than ``max_points`` points (None: no
    limit), before anything is planned or run: the value, the limit and how to raise it."""
    if max_points is None or grid.size <= max_points:
        return
    raise CampaignError(
        f"the [sweep] grid has {grid.size} points ({grid.describe()}), more than the limit of "
        f"{max_points} points per campaign; sweep fewer points, or raise the limit if this "
        f"size is meant (max_points={grid.size}, CLI --max-points {grid.size})"
    )


class _Reads(Mapping):
    """A point's parameters that note which keys are read (any iteration or ``len`` reads
    them all): what the forcing period of a model depends on."""

    def __init__(self, data: dict) -> None:
        self.data = data
        self.read: set[str] = set()
        self.all = False

    def __getitem__(self, key: str) -> float:
        self.read.add(key)
        return self.data[key]

    def __iter__(self) -> Iterator[str]:
        self.all = True
        return iter(self.data)

    def __len__(self) -> int:
        self.all = True
        return len(self.data)


def grid_periods(scene: Scene, grid: SweepGrid) -> np.ndarray | None:
    """Forcing period (s) of every point of the grid, or None for an autonomous model (no
    period at the scene's own parameters).

    The model's ``forcing_period(params)`` takes one point's parameters (the scene's, with the
    swept values of the point). It is called once per combination of the swept parameters it
    reads, found as it runs (every key it reads is noted, and a key read that was held fixed
    makes the evaluation start again with that dim swept), so a sweep over ``gamma`` x
    ``delta`` of a Duffing oscillator costs one call, and one over ``omega`` one call per
    value of ``omega``.

    Returns
    -------
    numpy.ndarray or None
        The periods (float64), shaped to broadcast against ``grid.shape``: the length of each
        dim the period depends on, 1 for the others.

    Raises
    ------
    CampaignError
        The model's forcing period raises, or gives no finite positive period, at a point of
        the grid (one line naming the point and the error): no point is costed or counted
        without it.
    """
    base = dict(scene.resolved_parameters)
    if _period(scene, base, {}, none=True) is None:
        return None
    fixed = {d: v[0] for d, v in zip(grid.dims, grid.values, strict=True)}
    swept: tuple[int, ...] = ()  # indices of the dims the period reads
    everything = False  # it reads every key, or needs a dict: then it gets plain dicts
    while True:
        shape = tuple(len(grid.values[k]) if k in swept else 1 for k in range(len(grid.dims)))
        periods = np.empty(math.prod(shape))
        read: set[int] = set()
        for i, combo in enumerate(itertools.product(*(grid.values[k] for k in swept))):
            point = {grid.dims[k]: v for k, v in zip(swept, combo, strict=True)}
            data = base | fixed | point
            if everything:
                periods[i] = _period(scene, data, point)
                continue
            params = _Reads(data)
            try:
                periods[i] = _period(scene, params, point)
            except CampaignError:
                if params.all or not (params.read & fixed.keys()) - point.keys():
                    # the error is this point's, or the code needs a dict: then every key
                    # counts as read (a second error is this point's)
                    periods[i] = _period(scene, data, point)
                    params.all = True
            everything = params.all
            read |= {k for k, d in enumerate(grid.dims) if everything or d in params.read}
            if not read <= set(swept):
                break  # a dim held fixed was read: sweep it too
        else:
            return periods.reshape(shape)
        swept = tuple(sorted(read | set(swept)))


def _period(scene: Scene, params: Mapping, point: dict, none: bool = False) -> float | None:
    """The forcing period (s) with ``params`` (:func:`workbench.run.forcing_period`), the values
    of ``point`` swept (:func:`grid_periods`); CampaignError naming the point unless it is a
    finite positive number (or None, if ``none``)."""
    try:
        period = forcing_period(get_model(scene.model), params)
    except SceneError as exc:  # not a finite positive number (workbench.run.forcing_period)
        bad = str(exc)
    except Exception as exc:  # any error: the model's own code; refused below in one line
        # naming the point and the error (never costed)
        bad = f"{type(exc).__name__}: {exc}"
    else:
        bad = "it gives None" if period is None and not none else None
    if bad is None:
        return period
    at = f"{format_point(point)} (any other swept values)" if point else "the scene's parameters"
    raise CampaignError(
        f"the forcing period of model {scene.model!r} cannot be computed at {at}: {bad}; a "
        "campaign is planned from the forcing period (s) of every point, a finite positive "
        "number: remove those values from the [sweep], or fix the model's forcing_period"
    )


def check_archive_memory(scene: Scene, grid: SweepGrid, max_memory=None) -> float:
    """Refuse, before anything runs, a campaign whose assembled archive would exceed the memory
    limit (:func:`workbench.run.check_memory`): points x the most records of a point x the
    values of a record (the variables and the record time), 8 bytes each. Each point's own
    records are checked again when it is prepared. Returns the estimate (bytes)."""
    model = get_model(scene.model)
    periods = grid_periods(scene, grid)
    if periods is None:
        n_time = record_count(scene.run, scene.record, None)
    else:
        n_time = max(record_count(scene.run, scene.record, p) for p in np.unique(periods).tolist())
    per_record = values_per_record(model, scene.effects, scene.variables)
    key, lower = what_to_lower(scene.run, scene.record)
    needed = 8.0 * grid.size * n_time * per_record
    check_memory(
        needed,
        what="the campaign's archive",
        count=f"{grid.size} points x {n_time:.3g} records x {per_record} values x 8 bytes",
        key=key,
        lower=f"{lower}, sweep fewer points",
        max_memory=max_memory,
    )
    return needed


def parameter_attrs(scene: Scene, name: str) -> dict[str, str]:
    """``units``, ``long_name`` and ``comment`` of a model parameter (from its declaration, as a
    run's coordinate of it has them), or of a swept ``[run]`` key (``realisation``)."""
    if name in RUN_SWEEP_KEYS:
        return dict(REALISATION_ATTRS)
    model = get_model(scene.model)
    model.parameter(name)  # KeyError for a name that is no parameter
    # the attributes a run gives the parameter's coordinate (units, long name, comment)
    return parameter_coords(model, {name: 0.0})[name][2]


def format_point(point: Mapping[str, float]) -> str:
    return ", ".join(f"{k}={v:.6g}" for k, v in point.items())


def code_of(scene: Scene, *modules: str) -> str:
    """Digest of the code that computes a block of ``scene``'s campaign (the run layer, the
    model, the kernels, the block task and ``modules``, e.g. the module of a per-point
    measurement or of another block task; :func:`workbench.run.results_digest`)."""
    return results_digest(scene.model, "workbench.campaign._block", *modules)


def modules_of(fn) -> tuple[str, ...]:
    """The module of a per-point function as a tuple (empty for None), for :func:`code_of`."""
    return () if fn is None else (fn.__module__,)


def campaign_id(scene: Scene, chunk: int, per_point=None) -> str:
    """Digest of what fixes the content of every block: the scene, the chunk size and the
    function that measures each point (its qualified name; None: none)."""
    h = hashlib.sha256(scene.to_toml().encode())
    h.update(f"\nchunk={chunk}".encode())
    if per_point is not None:
        h.update(f"\nper_point={per_point.__module__}.{per_point.__qualname__}".encode())
    return h.hexdigest()[:16]
