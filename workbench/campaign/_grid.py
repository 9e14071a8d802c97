"""The points of a campaign: the grid of its sweep, each point's parameters and forcing period,
and what identifies a campaign (its scene and block size) and its code (the digest of what
computes a block)."""

from __future__ import annotations

import hashlib
import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from workbench.campaign._errors import CampaignError
from workbench.models import get_model
from workbench.run import (
    REALISATION_ATTRS,
    check_memory,
    parameter_coords,
    record_count,
    results_digest,
    values_per_record,
    what_to_lower,
)
from workbench.scene import RUN_SWEEP_KEYS, Scene

__all__ = [
    "SweepGrid",
    "campaign_id",
    "check_archive_memory",
    "code_of",
    "modules_of",
    "expand_sweep",
    "format_point",
    "forcing_period",
    "parameter_attrs",
]


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


def forcing_period(scene: Scene, grid: SweepGrid, flat: int) -> float | None:
    """Forcing period (s) of the grid point ``flat`` (None for an autonomous model)."""
    params = dict(scene.resolved_parameters)
    params.update(grid.point(flat))
    return get_model(scene.model).forcing_period(params)


def check_archive_memory(scene: Scene, grid: SweepGrid, max_memory=None) -> float:
    """Refuse, before anything runs, a campaign whose assembled archive would exceed the memory
    limit (:func:`workbench.run.check_memory`): points x the most records of a point x the
    values of a record (the variables and the record time), 8 bytes each. Each point's own
    records are checked again when it is prepared. Returns the estimate (bytes)."""
    model = get_model(scene.model)
    base = scene.resolved_parameters
    counts = set()
    if model.forcing_period(base) is None:
        counts.add(record_count(scene.run, scene.record, None))
    else:
        for values in itertools.product(*grid.values):
            params = dict(base)
            params.update(
                (d, v) for d, v in zip(grid.dims, values, strict=True) if d not in RUN_SWEEP_KEYS
            )
            counts.add(record_count(scene.run, scene.record, model.forcing_period(params)))
    n_time = max(counts)
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
