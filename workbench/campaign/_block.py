"""One campaign task: run a block of points and write the block's netCDF file.

This runs in a worker process. It imports workbench once per process (the numba kernels load
from the on-disk cache on the first point of the process, not on every point), writes its own
file atomically and returns a small summary to the client.
"""

from __future__ import annotations

import os
import signal
import time
from dataclasses import dataclass

import numpy as np
import xarray as xr

from workbench._archive import save_run
from workbench._errors import SceneError, SolverError
from workbench._scene import Scene, load_scene
from workbench.models import get_model
from workbench.solver._grid import record_grid
from workbench.solver._simulate import simulate

__all__ = ["BlockTask", "STATUS", "STATS", "run_block"]

# Per-point outcome (int8 ``status``). CF flag_values / flag_meanings.
OK, SOLVER_FAILED, TERMINATED, INVALID = 0, 1, 2, 3
STATUS = {
    OK: "ok",
    SOLVER_FAILED: "solver_failed",
    TERMINATED: "terminated_early",
    INVALID: "invalid_parameters",
}
STATUS_ATTRS = {
    "long_name": "outcome of the point's run",
    "units": "1",
    "flag_values": np.array(list(STATUS), dtype=np.int8),
    "flag_meanings": " ".join(STATUS.values()),
    "comment": "ok: complete run; solver_failed: the solver raised workbench.SolverError (data "
    "NaN, message in 'failure'); terminated_early: a terminal event ended the run (records after "
    "it NaN); invalid_parameters: the model rejects this combination of parameters (data NaN)",
}
FAILURE_ATTRS = {"long_name": "failure message of the point (empty when none)", "units": "1"}
# name in the dataset -> (attribute of simulate's dataset, dtype, missing value, attrs)
STATS = {
    "solver_steps": ("solver_steps", np.int64, -1, "accepted solver steps"),
    "solver_rejected_steps": ("solver_rejected_steps", np.int64, -1, "rejected solver steps"),
    "solver_rhs_evaluations": (
        "solver_rhs_evaluations",
        np.int64,
        -1,
        "right-hand side evaluations",
    ),
    "solver_events": ("solver_events", np.int64, -1, "located events"),
    "solver_wall_time": ("solver_wall_time", np.float64, np.nan, "integration wall time"),
}
POINT_WALL_ATTRS = {
    "long_name": "wall time of the point (scene, problem, integration, dataset)",
    "units": "s",
}
TIME_ATTRS = {"units": "s", "long_name": "time", "standard_name": "time"}

_TASKS_IN_PROCESS = 0
# A block dataset up to this size (bytes) also travels back to the client with the task's
# summary, so that the client assembles it without reading its file again (~15 ms per block of
# netCDF overhead); a larger one the client reads from the file.
RETURN_LIMIT = 32 * 2**20
PRELOAD_ENV = "WORKBENCH_CAMPAIGN_PRELOAD"  # scene TOML whose kernel the fork server loads


@dataclass(frozen=True)
class BlockTask:
    """What one task needs: the campaign scene (TOML), which points, where to write."""

    scene_toml: str
    dims: tuple[str, ...]
    flat: tuple[int, ...]
    values: tuple[tuple[float, ...], ...]
    path: str
    campaign_id: str
    block: int


def ignore_sigint() -> None:
    """Initializer of a local pool's worker: Ctrl-C is the client's to handle (it stops the
    workers), so that a terminal's interrupt does not print a traceback per worker."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def stat_attrs(name: str) -> dict:
    _, dtype, missing, long_name = STATS[name]
    units = "s" if dtype is np.float64 else "1"
    attrs = {"long_name": long_name, "units": units}
    if dtype is np.int64:
        attrs["comment"] = f"{missing}: not available (the point failed)"
    return attrs


def planned_times(scene: Scene) -> np.ndarray:
    """Record times (s) a run of a single-point scene would have had (empty if unknown)."""
    try:
        model = get_model(scene.model)
        params = scene.resolved_parameters
        problem = model.problem(params, scene.effects, scene.initial, scene.variables)
        t, _ = record_grid(scene, problem.t0, model.forcing_period(params))
        return np.asarray(t, dtype=np.float64)
    except Exception:
        return np.zeros(0)


def _point(scene: Scene, params: dict[str, float]) -> dict:
    """Run one point; SolverError and rejected parameters become data, anything else raises."""
    t0 = time.perf_counter()
    out: dict = {"status": OK, "failure": "", "ds": None, "times": np.zeros(0)}
    try:
        pscene = scene.with_parameters(**params)
    except SceneError as exc:
        out.update(status=INVALID, failure=f"invalid_parameters: {exc}")
        out["wall"] = time.perf_counter() - t0
        return out
    try:
        ds = simulate(pscene)
    except SolverError as exc:
        out.update(status=SOLVER_FAILED, failure=f"{exc.cause}: {exc}", times=planned_times(pscene))
    except SceneError as exc:
        out.update(status=INVALID, failure=f"invalid_parameters: {exc}")
    except Exception as exc:
        shown = ", ".join(f"{k}={v:.6g}" for k, v in params.items())
        raise RuntimeError(
            f"campaign point {shown} raised {type(exc).__name__}: {exc}. Only "
            "workbench.SolverError is recorded as a failed point; anything else is a bug or a "
            "broken setup. Finished blocks are kept: fix the cause and run the campaign again."
        ) from exc
    else:
        out["ds"] = ds
        out["times"] = ds["time"].values
        if ds.attrs.get("run_status") == "terminated":
            out["status"] = TERMINATED
            out["failure"] = "terminated: a terminal event ended the run early"
    out["wall"] = time.perf_counter() - t0
    return out


def run_block(task: BlockTask) -> dict:
    """Run the points of one block and write them to ``task.path`` (atomically).

    Returns a summary: block index, number of points, failures ``[(flat, message)]``, wall time
    of the block and the sum of the solvers' wall times (s), worker process id, and ``dataset``:
    the block as written (None when larger than RETURN_LIMIT bytes; then read the file).
    """
    global _TASKS_IN_PROCESS
    _TASKS_IN_PROCESS += 1
    wall0 = time.perf_counter()
    scene = load_scene(task.scene_toml)
    model = get_model(scene.model)
    runs = [_point(scene, dict(zip(task.dims, v, strict=True))) for v in task.values]
    ds = _block_dataset(scene, model, task, runs)
    ds.attrs.update(
        worker_pid=os.getpid(),
        worker_task_number=_TASKS_IN_PROCESS,
        block_wall_time=time.perf_counter() - wall0,
    )
    save_run(ds, task.path, classic=True)  # read back by the client only: speed over HDF5
    return {
        "dataset": ds if ds.nbytes <= RETURN_LIMIT else None,
        "block": task.block,
        "points": len(task.flat),
        "failures": [
            (f, r["failure"])
            for f, r in zip(task.flat, runs, strict=True)
            if r["status"] != OK and r["status"] != TERMINATED
        ],
        "wall": time.perf_counter() - wall0,
        "solver_wall": float(np.nansum(ds["solver_wall_time"].values)),
        "pid": os.getpid(),
    }


def _block_dataset(scene: Scene, model, task: BlockTask, runs: list[dict]) -> xr.Dataset:
    n = len(runs)
    n_time = max([len(r["times"]) for r in runs] + [0])
    declared = model.variables(scene.effects)
    mcoords = model.coords(scene.effects)
    msizes = {d: len(v) for d, (v, _) in mcoords.items()}
    first_ok = next((r["ds"] for r in runs if r["ds"] is not None), None)
    time_attrs = dict(first_ok["time"].attrs) if first_ok is not None else dict(TIME_ATTRS)

    record_time = np.full((n, n_time), np.nan)
    for i, r in enumerate(runs):
        record_time[i, : len(r["times"])] = r["times"]
    data_vars: dict = {}
    for name in scene.variables:
        q = declared[name]
        arr = np.full((n, n_time) + tuple(msizes[d] for d in q.dims), np.nan)
        attrs = {"units": q.units, "long_name": q.long_name}
        for i, r in enumerate(runs):
            if r["ds"] is not None:
                v = r["ds"][name]
                arr[i, : v.shape[0]] = v.values
                attrs = dict(v.attrs)
        data_vars[name] = (("point", "time") + q.dims, arr, attrs)
    data_vars["record_time"] = (("point", "time"), record_time, time_attrs)
    data_vars["status"] = (
        "point",
        np.array([r["status"] for r in runs], np.int8),
        STATUS_ATTRS,
    )
    data_vars["failure"] = ("point", np.array([r["failure"] for r in runs], object), FAILURE_ATTRS)
    for name, (attr, dtype, missing, _) in STATS.items():
        vals = np.array(
            [r["ds"].attrs.get(attr, missing) if r["ds"] is not None else missing for r in runs],
            dtype,
        )
        data_vars[name] = ("point", vals, stat_attrs(name))
    data_vars["point_wall_time"] = (
        "point",
        np.array([r["wall"] for r in runs], np.float64),
        POINT_WALL_ATTRS,
    )
    coords = {
        "point": (
            "point",
            np.array(task.flat, np.int64),
            {"long_name": "flat (C-order) index of the point in the grid", "units": "1"},
        )
    }
    for d, (values, attrs) in mcoords.items():
        coords[d] = (d, list(values), dict(attrs))
    ds = xr.Dataset(data_vars, coords=coords)
    ds.attrs.update(campaign_id=task.campaign_id, block=task.block, model=scene.model)
    return ds
