"""One campaign task: run a block of points and write the block's netCDF file.

This runs in a worker process. It imports workbench once per process (the numba kernels load
from the on-disk cache on the first point of the process, not on every point), writes its own
file atomically and returns a small summary to the client.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from workbench._attributes import variable
from workbench._processor import processor_attrs
from workbench.archive import RECORD_DIM, RECORD_TIME, save_run, sha256_file
from workbench.campaign._grid import SweepGrid, code_of, modules_of
from workbench.campaign._lifeline import die_with_parent, watch_process
from workbench.models import get_model
from workbench.run import TIME_ATTRS, Prepared, prepare, run_status, simulate, status_attrs
from workbench.scene import Scene, SceneError, scene_from_toml
from workbench.scene._modules import import_model_module
from workbench.solver import Status

__all__ = [
    "BlockTask",
    "Task",
    "INVALID",
    "RAISED",
    "STATUS",
    "STATS",
    "block_dataset",
    "block_summary",
    "failed",
    "invalid_outcome",
    "model_source",
    "run_block",
    "run_outcome",
    "task_scene",
    "worker_start",
]

# Per-point outcome (int8 ``status``, CF flag_values / flag_meanings): the run's Status, or
# INVALID for a point that did not run, or RAISED for a point whose run raised an exception.
INVALID = len(Status)
RAISED = INVALID + 1
STATUS_ATTRS = status_attrs(
    "outcome of the point's run", {INVALID: "invalid_parameters", RAISED: "error"}
)
STATUS_ATTRS["comment"] = (
    "a workbench.Status of the point's run (ok; terminated: a terminal event ended the run, "
    "records after it NaN; max_steps, step_underflow, non_finite, model_failure: the run failed, "
    "data NaN, solver statistics up to the failure, message in 'failure'), or "
    "invalid_parameters: the model rejects this combination of parameters (the point did not "
    "run; data NaN), or error: the point raised an exception (a bug or a broken setup; its "
    "type and message in 'failure'; data NaN)"
)
STATUS = dict(
    zip(STATUS_ATTRS["flag_values"].tolist(), STATUS_ATTRS["flag_meanings"].split(), strict=True)
)
FAILURE_ATTRS = variable("failure message of the point (empty when none)", "1")
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
POINT_WALL_ATTRS = variable("wall time of the point (scene, problem, integration, dataset)", "s")

_TASKS_IN_PROCESS = 0
# A block dataset up to this size (bytes) also travels back to the client with the task's
# summary, so that the client assembles it without reading its file again (netCDF's overhead
# per block); a larger one the client reads from the file.
RETURN_LIMIT = 32 * 2**20
PRELOAD_ENV = "WORKBENCH_CAMPAIGN_PRELOAD"  # scene TOML whose kernel the fork server loads
MODEL_ENV = "WORKBENCH_CAMPAIGN_MODEL"  # its model_source(), JSON: imported there first


@dataclass(frozen=True)
class Task:
    """What one task of a campaign needs (the one task type of every plan, see ``_engine``):
    the campaign scene (TOML), which points (``flat``, indices into the grid of the swept
    values ``axes``, in the order they run), where to write, and the module that defines the
    scene's model when it is not one of workbench's (a user's model, registered when imported:
    a worker process that did not import it yet does so first), and the function (if any) that
    measures each point's run in the worker (``per_point``, see
    :func:`workbench.run_campaign`). Each point's values are looked up when the block runs
    (:attr:`values`), not when it is planned.

    A continued sweep's segment (:func:`workbench.continuation.continued_sweep`) runs its
    points in order, each from the state the one before ended in: its first ``own_from``
    points are seam points (computed only to compare), and ``seed_state`` / ``seed_aux`` (a
    chained segment) the state its first point starts from."""

    scene_toml: str
    dims: tuple[str, ...]
    flat: tuple[int, ...]
    axes: tuple[tuple[float, ...], ...]  # the values of each dim (SweepGrid.values)
    path: str
    campaign_id: str
    block: int
    max_memory: float | str | None = None  # the memory limit of one point's records
    model_module: str = ""  # model_source(): the module the user named, imported in the worker
    model_directory: str = ""  # where it lies, for a worker without it on its import path
    per_point: Callable[[Scene, xr.Dataset], xr.Dataset] | None = None
    own_from: int = 0  # a segment's first own point (the ones before: seam points)
    seed_state: tuple[float, ...] | None = None  # a chained segment: the state to start from
    seed_aux: tuple[float, ...] | None = None  # ... and its discrete state

    @property
    def values(self) -> tuple[tuple[float, ...], ...]:
        """The parameter values of each point of the block, in ``dims`` order."""
        return SweepGrid(self.dims, self.axes).rows(self.flat)


#: the name of :class:`Task` before the engine had one task type
BlockTask = Task


def worker_start(pids, campaign: int) -> None:
    """Initializer of a local pool's worker: die with the campaign (process ``campaign``; see
    ``_lifeline``), report this process's id (``pids``, a multiprocessing queue) so that the
    client can stop the blocks in flight, and leave Ctrl-C to the client (it stops the
    workers), so that a terminal's interrupt does not print a traceback per worker."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    die_with_parent(os.getppid())
    watch_process(campaign)
    pids.put(os.getpid())


def stat_attrs(name: str) -> dict:
    _, dtype, missing, long_name = STATS[name]
    units = "s" if dtype is np.float64 else "1"
    if dtype is np.int64:
        return variable(
            long_name, units, comment=f"{missing}: not available (the point did not run)"
        )
    return variable(long_name, units)


def failed(status: np.ndarray) -> np.ndarray:
    """Which per-point flags are failures: a failed run or a point that did not run."""
    status = np.asarray(status)
    return (status != Status.OK) & (status != Status.TERMINATED)


def invalid_outcome(exc: SceneError, wall: float) -> dict:
    """The outcome of a point whose parameters the model rejects (it did not run)."""
    out = {"status": INVALID, "failure": f"invalid_parameters: {exc}", "wall": wall}
    return out | {"ds": None, "times": np.zeros(0)}


def raised_outcome(exc: Exception, wall: float) -> dict:
    """The outcome of a point that raised an exception (RAISED, with the exception's type,
    message and where it was raised in ``failure``)."""
    where = traceback.extract_tb(exc.__traceback__)[-1]
    failure = (
        f"error: {type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''} "
        f"(raised at {Path(where.filename).name}:{where.lineno} in {where.name})"
    )
    out = {"status": RAISED, "failure": failure, "wall": wall}
    return out | {"ds": None, "times": np.zeros(0)}


def run_outcome(ds: xr.Dataset, wall: float) -> dict:
    """The outcome of a point that ran: its status and failure message from the run's
    dataset (see :func:`block_dataset`)."""
    status = run_status(ds)
    failure = f"{status.label}: {ds.attrs['run_message']}" if status.failed else ""
    if status is Status.TERMINATED:
        failure = "terminated: a terminal event ended the run early"
    out = {"status": int(status), "failure": failure, "ds": ds, "times": ds["time"].values}
    return out | {"wall": wall}


def _point(base: Prepared, params: dict[str, float], per_point=None) -> dict:
    """Run one point: the campaign's scene prepared for its points (``base``) at ``params``
    (:meth:`workbench.run.Prepared.at`). Its outcome is data: a failed run (its Status),
    rejected parameters (INVALID) or any exception the point raised (RAISED): one bad point
    never stops its campaign. An interrupt (KeyboardInterrupt, SystemExit) still stops the
    block."""
    t0 = time.perf_counter()
    try:
        prepared = base.at(**params)
        ds = simulate(prepared, throw=False)
        measured = None
        if per_point is not None and not run_status(ds).failed:
            measured = per_point(prepared.scene, ds)
    except SceneError as exc:
        return invalid_outcome(exc, time.perf_counter() - t0)
    except Exception as exc:  # any error is this point's data (flag error, the docstring)
        return raised_outcome(exc, time.perf_counter() - t0)
    return run_outcome(ds, time.perf_counter() - t0) | {"measured": measured}


def model_source(scene: Scene) -> tuple[str, str]:
    """The module a worker imports to know the model of ``scene`` and the directory its
    top-level file or package lies in: the scene's ``[model] module`` (the user named it), else
    the module that defines a model registered outside workbench; ('', '') for a model of
    workbench."""
    module = scene.model_module or type(get_model(scene.model)).__module__
    if module.split(".")[0] == "workbench":
        return "", ""
    file = getattr(sys.modules.get(module), "__file__", None)
    if not file:
        return module, ""
    depth = module.count(".") + (Path(file).name == "__init__.py")
    return module, str(Path(file).resolve().parents[depth])


def task_scene(scene_toml: str, model_module: str = "", model_directory: str = "") -> Scene:
    """The scene of a task, in a worker: the TOML and the model's module come from the client,
    which took them from the user's scene (never from a manifest or an archive). The module
    (:func:`model_source`) is imported first, by name, else by file path from
    ``model_directory`` (a worker whose path lacks it; the directory is not put on
    ``sys.path``), and so trusted for the scene's ``[model] module``."""
    if model_module:
        import_model_module(model_module, [Path(model_directory)] if model_directory else [])
    return scene_from_toml(scene_toml)


def run_block(task: Task) -> dict:
    """Run the points of one block and write them to ``task.path`` (atomically).

    Returns a summary: the SHA-256 of the file written, the digest of the code that computed it
    (``code_digest``, also an attribute of the file), block index, number of points, failures
    ``[(flat, message)]``, wall and CPU time of the block and the sum of the solvers' wall
    times (s), worker process id, and ``dataset``: the block as written (None when larger than
    RETURN_LIMIT bytes; then read the file).
    """
    global _TASKS_IN_PROCESS
    _TASKS_IN_PROCESS += 1
    started = time.time()
    wall0, cpu0 = time.perf_counter(), time.process_time()
    scene = task_scene(task.scene_toml, task.model_module, task.model_directory)
    runs = _points(scene, task)
    ds = block_dataset(scene, task.flat, runs)
    ds.attrs.update(campaign_id=task.campaign_id, block=task.block)
    code = code_of(scene, *modules_of(task.per_point))
    ds.attrs.update(
        code_digest=code,
        worker_pid=os.getpid(),
        worker_thread=threading.get_native_id(),
        worker_task_number=_TASKS_IN_PROCESS,
        block_started=started,
        block_wall_time=time.perf_counter() - wall0,
    )
    save_run(ds, task.path, classic=True)  # read back by the client only: speed over HDF5
    return block_summary(task, ds, runs, code, wall0, cpu0, keep=ds.nbytes <= RETURN_LIMIT)


def _points(scene: Scene, task: Task) -> list[dict]:
    """The outcomes of the points of a block (:func:`_point`), each prepared from the scene
    prepared once for them (a scene that cannot be prepared at all: each point's outcome is
    that error)."""
    t0 = time.perf_counter()
    try:
        base = prepare(scene, max_memory=task.max_memory, points=True)
    except SceneError as exc:
        return [invalid_outcome(exc, time.perf_counter() - t0) for _ in task.flat]
    except Exception as exc:  # any error is the points' data (flag error, _point)
        return [raised_outcome(exc, time.perf_counter() - t0) for _ in task.flat]
    return [_point(base, dict(zip(task.dims, v, strict=True)), task.per_point) for v in task.values]


def block_summary(task: Task, ds: xr.Dataset, runs: list[dict], code: str, wall0: float,
                  cpu0: float, *, keep: bool = True) -> dict:  # fmt: skip
    """What a worker returns for the block it wrote to ``task.path`` (a campaign's block or a
    continued sweep's segment): see :func:`run_block`; ``keep``: return the dataset itself,
    ``wall0`` and ``cpu0``: :func:`time.perf_counter` and :func:`time.process_time` when the
    block started (s)."""
    return {
        "sha256": sha256_file(task.path),
        "code_digest": code,
        "dataset": ds if keep else None,
        "block": task.block,
        "points": len(task.flat),
        "failures": [
            (f, r["failure"]) for f, r in zip(task.flat, runs, strict=True) if failed(r["status"])
        ],
        "wall": time.perf_counter() - wall0,
        "cpu": time.process_time() - cpu0,
        "solver_wall": float(np.nansum(ds["solver_wall_time"].values)),
        "pid": os.getpid(),
    }


def block_dataset(scene: Scene, flat, runs: list[dict]) -> xr.Dataset:
    """The dataset of a block: the points ``flat`` (flat grid indices) with their outcomes
    (:func:`run_outcome`, :func:`invalid_outcome`; an outcome's ``measured`` dataset, if any,
    becomes per-point variables, NaN where a point has none). The records run along
    ``record`` with each point's times in ``record_time`` (point, record), NaN-padded: the
    assembly makes them the coordinate ``time`` when every point has the same."""
    model = get_model(scene.model)
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
        attrs = variable(q.long_name, q.units)
        for i, r in enumerate(runs):
            if r["ds"] is not None and not failed(r["status"]):
                v = r["ds"][name]
                arr[i, : v.shape[0]] = v.values
                attrs = dict(v.attrs)
        data_vars[name] = (("point", RECORD_DIM) + q.dims, arr, attrs)
    data_vars[RECORD_TIME] = (("point", RECORD_DIM), record_time, time_attrs)
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
            np.array(flat, np.int64),
            variable("flat (C-order) index of the point in the grid", "1"),
        )
    }
    for d, (values, attrs) in mcoords.items():
        coords[d] = (d, list(values), dict(attrs))
    ds = xr.Dataset(data_vars, coords=coords)
    ds = ds.merge(_measured(runs), combine_attrs="override")
    ds.attrs.update(model=scene.model, **processor_attrs())  # this worker's: one per block
    return ds


def _measured(runs: list[dict]) -> xr.Dataset:
    """The per-point measurements of a block over ``point`` (NaN where a point has none)."""
    found = [r.get("measured") for r in runs]
    template = next((m for m in found if m is not None), None)
    if template is None:
        return xr.Dataset()
    blank = xr.full_like(template, np.nan, dtype=np.float64)
    return xr.concat([blank if m is None else m for m in found], dim="point")
