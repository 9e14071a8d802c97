"""One task of a continued sweep, in a worker: run a segment's points in order, each from the
settled state of the one before, and write the segment's block file.

A point continued from its neighbour starts at the problem's own start time ``t0`` from the
neighbour's state at the end of its run. The end of a run of a forced model lies a whole number
of forcing periods after ``t0`` (records at ``t0 + k T / samples_per_period``), and the models'
forcing depends on time only through its phase ``omega t``, so that state is a state at
forcing phase 0 for any value of the parameter: the neighbour's end is a valid start. The
discrete state (e.g. a contact's held onset velocity) is carried with it; internal quadratures
(states named ``_...``, e.g. the energy integrals) restart from the model's initial values.
"""

from __future__ import annotations

import os
import time

import numpy as np
import xarray as xr

from workbench._attributes import flags, variable
from workbench.archive import RECORD_DIM, save_run
from workbench.campaign._block import (
    Task,
    block_dataset,
    block_summary,
    invalid_outcome,
    run_outcome,
    task_scene,
)
from workbench.campaign._grid import code_of, modules_of
from workbench.models import get_model
from workbench.run import Prepared, derive, integrate, prepare, run_status, to_dataset
from workbench.scene import Scene, SceneError
from workbench.solver import Status

__all__ = ["SEED_ATTRS", "SegmentTask", "Starts", "continue_point", "run_segment", "segment_code"]

#: how a point of a continued sweep started (int8 ``seed``, CF flags)
CONTINUED, BRUTE_FORCE, CHAINED_START, RESTARTED = 0, 1, 2, 3
SEED_ATTRS = flags(
    "how the point's run started",
    {
        CONTINUED: "continued",
        BRUTE_FORCE: "brute_force_seed",
        CHAINED_START: "chained_seed",
        RESTARTED: "restarted_after_failure",
    },
    comment="continued: from the previous point's final state with the per-point transient; "
    "brute_force_seed: from the scene's initial state with the scene's transient (the first "
    "point of a segment); chained_seed: from the final state of the previous segment's last "
    "point (a segment run again after its seam disagreed); restarted_after_failure: from the "
    "scene's initial state because the previous point failed",
)


#: the name of a segment's task before the campaign engine had one task type
SegmentTask = Task


def _settled(scene: Scene, c) -> Scene:
    """The scene of a continued point: the sweep's per-point transient (continuation settings
    ``c``) instead of the scene's."""
    run = dict(scene.run)
    if "transient_cycles" in c:
        run["transient_cycles"] = c["transient_cycles"]
    else:
        run["transient"] = c["transient"]
    return scene.replace(run=run)


class Starts:
    """The sweep's scene prepared once for its points (:meth:`workbench.run.Prepared.at`): as
    it is (a brute-force start) and with the per-point transient (a continued start); a scene
    that cannot be prepared keeps its error, which each point then reports."""

    def __init__(self, scene: Scene) -> None:
        self.scene = scene
        self._prepared: dict[bool, Prepared | SceneError] = {}

    def at(self, continued: bool, params: dict[str, float]) -> Prepared:
        """The point ``params`` prepared for a continued start or a brute-force one."""
        if continued not in self._prepared:
            scene = _settled(self.scene, self.scene.continuation) if continued else self.scene
            try:
                self._prepared[continued] = prepare(scene, points=True)
            except SceneError as exc:
                self._prepared[continued] = exc
        base = self._prepared[continued]
        if isinstance(base, SceneError):
            raise base
        return base.at(**params)


def continue_point(
    starts: Starts,
    params: dict[str, float],
    carried: tuple[np.ndarray, np.ndarray] | None,
    per_point=None,
    seed=None,
) -> tuple[dict, tuple[np.ndarray, np.ndarray] | None]:
    """Run one point of a continued sweep (its scene, with its ``continuation`` settings,
    prepared for its points: ``starts``), and measure it (``per_point``).

    Parameters
    ----------
    starts : Starts
        The sweep's scene prepared for its points.
    params : dict
        The point's swept values.
    carried : (y, aux) or None
        The state (state units) and discrete state to start from, with the per-point
        transient; None: the scene's initial state and transient (a brute-force start).
    per_point : callable, optional
        ``per_point(scene, run, seed=seed)``: the measurement of a run that succeeded (as
        :func:`workbench.run_campaign`'s), which may leave in its dataset's attribute
        ``carry`` what the next point's measurement starts from (its ``seed``, e.g. a
        periodic orbit for the next point's Newton).
    seed : object, optional
        What the previous point's measurement left (``carry``), for ``per_point``.

    Returns
    -------
    outcome : dict
        As :func:`workbench.campaign._block.run_outcome` (or ``invalid_outcome``), with
        ``measured`` (the measurement, or None) and ``carry`` (for the next point, or None).
    final : (y, aux) or None
        The state at the end of the run, to carry to the next point (None if the run failed
        or ended early).
    """
    t0 = time.perf_counter()
    try:
        prepared = starts.at(carried is not None, params)
        if carried is not None:
            pb = prepared.problem
            y0 = np.array(pb.y0, dtype=float)
            y, aux = carried
            keep = np.array([not q.name.startswith("_") for q in pb.states])
            y0[keep] = y[keep]
            prepared = prepared.restart(pb.t0, y0, np.array(aux, dtype=float))
        result = integrate(prepared)
        derived, result = derive(prepared, result)
        ds = to_dataset(prepared, result, derived)
        measured = carry = None
        if per_point is not None and not run_status(ds).failed:
            measured = per_point(prepared.scene, ds, seed=seed)
            carry = measured.attrs.pop("carry", None)
    except SceneError as exc:
        return invalid_outcome(exc, time.perf_counter() - t0), None
    except Exception as exc:
        shown = ", ".join(f"{k}={v:.6g}" for k, v in params.items())
        raise RuntimeError(
            f"continued sweep point {shown} raised {type(exc).__name__}: {exc}. Only a failed "
            "run (a workbench.Status) or invalid parameters are recorded as a point's outcome; "
            "anything else is a bug or a broken setup. Finished blocks are kept: fix the cause "
            "and run the sweep again."
        ) from exc
    outcome = run_outcome(ds, time.perf_counter() - t0) | {"measured": measured, "carry": carry}
    final = None
    if result.status is Status.OK:
        final = (result.Y[-1].copy(), result.AUX[-1].copy())
    outcome["final"] = final
    outcome["states"] = prepared.problem.states
    return outcome, final


def segment_code(scene: Scene, per_point=None) -> str:
    """Digest of the code that computes a segment's block (the campaign's
    :func:`workbench.campaign._grid.code_of` with this module and that of ``per_point``)."""
    return code_of(scene, __name__, *modules_of(per_point))


def run_segment(task: Task) -> dict:
    """Run a segment (in a worker) and write its block file (atomically); the summary has the
    fields of :func:`workbench.campaign._block.run_block`'s."""
    wall0, cpu0 = time.perf_counter(), time.process_time()
    scene = task_scene(task.scene_toml, task.model_module, task.model_directory)
    starts = Starts(scene)
    carried, seed = None, None
    if task.seed_state is not None:
        carried = (np.array(task.seed_state), np.array(task.seed_aux or ()))
    runs, seeds = [], []
    for i, v in enumerate(task.values):
        if carried is not None:
            kind = CHAINED_START if (i == 0 and task.seed_state is not None) else CONTINUED
        else:
            kind = BRUTE_FORCE if i == 0 else RESTARTED
        params = dict(zip(task.dims, v, strict=True))
        outcome, carried = continue_point(starts, params, carried, task.per_point, seed)
        seed = outcome.get("carry") if carried is not None else None
        runs.append(outcome)
        seeds.append(kind)
    own = slice(task.own_from, None)
    ds = block_dataset(scene, task.flat[own], runs[own])
    ds = ds.merge(_finals(scene, runs[own], seeds[own]))
    if task.own_from:
        ds = ds.merge(_seam_points(scene, task.flat[: task.own_from], runs[: task.own_from]))
    ran = next((r for r in runs if r.get("states") is not None), None)
    code = segment_code(scene, task.per_point)
    ds.attrs.update(
        code_digest=code,
        campaign_id=task.campaign_id,
        block=task.block,
        state_names=" ".join(q.name for q in ran["states"]) if ran else "",
        worker_pid=os.getpid(),
        block_wall_time=time.perf_counter() - wall0,
        block_cpu_time=time.process_time() - cpu0,
    )
    save_run(ds, task.path, classic=True)
    return block_summary(task, ds, runs, code, wall0, cpu0)


def _finals(scene: Scene, runs: list[dict], seeds: list[int]) -> xr.Dataset:
    """Per point: how it started (``seed``), its final state (``final_<state>``, one variable
    per state with its units; NaN where the run failed) and discrete state."""
    data = {"seed": ("point", np.array(seeds, np.int8), SEED_ATTRS)}
    ran = next((r for r in runs if r.get("final") is not None), None)
    if ran is None:
        return xr.Dataset(data)
    states, na = ran["states"], ran["final"][1].size
    y = np.full((len(runs), len(states)), np.nan)
    a = np.full((len(runs), na), np.nan)
    for i, r in enumerate(runs):
        if r.get("final") is not None:
            y[i], a[i] = r["final"]
    for k, q in enumerate(states):
        if not q.name.startswith("_"):
            attrs = variable(f"{q.long_name} at the end of the run", q.units)
            data[f"final_{q.name}"] = ("point", y[:, k], attrs)
    if na:
        data["final_discrete_state"] = (
            ("point", "discrete_state"),
            a,
            variable(
                "the model's discrete state at the end of the run (the mechanisms: each joint's "
                "held contact onset velocity, 0 out of contact)",
                get_model(scene.model).discrete_state_units,
            ),
        )
    return xr.Dataset(data)


def _seam_points(scene: Scene, flat: tuple[int, ...], runs: list[dict]) -> xr.Dataset:
    """A segment's seam points (before its own range), renamed ``seam_*`` over ``seam_point``
    and ``seam_time``: what the seam check compares with the previous segment."""
    ds = block_dataset(scene, flat, runs)
    keep = [*scene.variables, "record_time", "status"]
    ds = ds[keep].rename({name: f"seam_{name}" for name in keep})
    return ds.rename({"point": "seam_point", RECORD_DIM: "seam_time"})
