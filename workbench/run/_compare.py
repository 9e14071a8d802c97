"""Comparing two runs of one scene: the scenes that make the comparison and the measure of it.

Used by a run's self-check (``solver.check``, :func:`workbench.run.check_error`) and by the
work-precision studies of :mod:`workbench.precision`.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from workbench.scene import Scene

__all__ = ["divergence_time", "separation", "short_scene", "with_solver"]


def _solver(scene: Scene, method: str, rtol: float, atol: float | None) -> dict:
    atol = rtol if atol is None else atol
    return {**scene.solver, "method": method, "rtol": rtol, "atol": atol, "check": False}


def with_solver(scene: Scene, method: str, rtol: float, atol: float | None = None) -> Scene:
    """The scene (without its sweep) run by ``method`` at ``rtol`` and ``atol`` (default
    ``rtol``), without a self-check."""
    return scene.replace(solver=_solver(scene, method, rtol, atol), sweep={})


def short_scene(scene: Scene, method: str, rtol: float, atol: float | None = None) -> Scene:
    """The first forcing period from t0 (or the first 10 % of the run), densely recorded (400
    records), run by ``method`` at ``rtol`` and ``atol`` (see :func:`with_solver`)."""
    if "cycles" in scene.run:
        run, record = {"cycles": 1, "transient_cycles": 0}, {"samples_per_period": 400}
    else:
        horizon = 0.1 * (scene.run["duration"] + scene.run["transient"])
        run, record = {"duration": horizon, "transient": 0.0}, {"dt": horizon / 400}
    record["variables"] = list(scene.variables)
    solver = _solver(scene, method, rtol, atol)
    return scene.replace(solver=solver, run=run, record=record, sweep={})


def separation(a: xr.Dataset, b: xr.Dataset) -> np.ndarray:
    """Per record: the largest ``|a - b|`` over the variables, relative to each variable's range
    in ``b`` (dimensionless; inf where ``a`` or ``b`` is NaN)."""
    worst = np.zeros(b.sizes["time"])
    for name in b.data_vars:
        r = b[name].values.reshape(b.sizes["time"], -1)
        span = float(np.nanmax(r) - np.nanmin(r)) or 1.0
        d = np.abs(a[name].values.reshape(r.shape) - r) / span
        worst = np.maximum(worst, np.nan_to_num(np.nanmax(d, axis=1), nan=np.inf))
    return worst


def divergence_time(a: xr.Dataset, b: xr.Dataset, threshold: float = 1e-2) -> float:
    """Time (s, from the record start) at which two runs first differ by ``threshold`` of a
    variable's range; ``inf`` if they never do within the record."""
    over = np.flatnonzero(separation(a, b) > threshold)
    if over.size == 0:
        return math.inf
    return float(b.time.values[over[0]] - b.time.values[0])
