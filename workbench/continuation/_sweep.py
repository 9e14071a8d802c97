"""``continued_sweep``: a sweep whose points start from their neighbour's settled state (up,
down or both), in parallel by segments, resumable and reproducible like a campaign."""

from __future__ import annotations

import os
import time

import numpy as np
import xarray as xr

from workbench._attributes import flags, variable
from workbench.archive import RECORD_DIM, RECORD_TIME, open_run
from workbench.campaign import CampaignError, expand_sweep
from workbench.campaign._block import Task, model_source
from workbench.campaign._engine import Engine
from workbench.campaign._grid import campaign_id
from workbench.campaign._run import per_point_name
from workbench.campaign._store import Store
from workbench.continuation._plan import BRUTE, CHAINED, Plan, SegmentSpec
from workbench.continuation._seams import attractor_distance, cloud, line_scale
from workbench.continuation._segment import SEED_ATTRS, run_segment, segment_code
from workbench.scene import Scene, SceneSource, load_scene

__all__ = ["continued_sweep"]

DIRECTION_ATTRS = variable("direction of the continuation over the swept parameter", "1")


def continued_sweep(
    scene: SceneSource,
    store: str | os.PathLike,
    *,
    client=None,
    workers: int | None = None,
    restart: bool = False,
    progress: bool = False,
    per_point=None,
) -> xr.Dataset:
    """Run a scene's ``[sweep]`` as a continued sweep (``[sweep] continuation``): along one
    swept parameter each point starts from the state its neighbour settled to, with a short
    per-point transient, upwards, downwards or both ways.

    Parallel by segments: each line (combination of the other swept values) and direction is
    cut into ``segments`` runs of consecutive points continued side by side, each seeded by a
    brute-force point ``overlap`` points before its own range (the scene's initial state and
    transient). At each seam the last overlap point, computed by both segments, is compared
    (:mod:`workbench.continuation._seams`); where the two did not reach the same attractor the
    later segment is run again from the state the earlier one left at its last point, which is
    what one sequential continuation does, until every seam agrees or is chained. The result
    does not depend on the number of workers (segments are fixed by the scene); the store is
    resumable like a campaign's (:func:`workbench.run_campaign`: lock, manifest, checksummed
    block files; brute-force and chained segments are blocks).

    Parameters
    ----------
    scene : Scene, path or mapping
        With a ``[sweep]`` and its ``continuation`` (``"up"``, ``"down"``, ``"both"`` or a
        table: ``direction``, ``along`` (default: the first swept parameter), ``segments``
        (default ``min(8, max(1, n // 10))`` for ``n`` values along), ``overlap`` (points, 2),
        ``transient_cycles`` (per continued point; default a tenth of the scene's
        ``run.transient_cycles``, at least 1; ``transient`` in s for an autonomous model),
        ``seam_tolerance`` (0.05 of each variable's range)).
    store : path
        The archive to write; blocks and manifest go to ``<store>.blocks/``.
    client, workers, restart, progress
        As :func:`workbench.run_campaign`.
    per_point : callable, optional
        As :func:`workbench.run_campaign`'s, called ``per_point(scene, run, seed=seed)``:
        ``seed`` is what the previous point's measurement left in its dataset's attribute
        ``carry`` (None at a segment's start or after a failed point), e.g. a periodic orbit
        to start Newton from (:func:`workbench.continuation.chaos_map` along an axis).

    Returns
    -------
    xarray.Dataset
        The campaign's variables (:func:`workbench.run_campaign`), with a leading ``direction``
        dim (``up``, ``down``) when ``direction = "both"``; per point ``seed`` (how it started,
        CF flags) and its final state (``final_<state>``, ``final_discrete_state``); per seam
        (dim ``seam``: between segments j-1 and j) ``seam_distance`` and ``seam_spread`` (the
        cross and within distances of the check, fractions of the ranges) and
        ``seam_chained`` (1 where the segment was run again from its predecessor's state).
        Attributes: those of a campaign, the settings (``continuation_*``), the rounds of
        chained segments (``continuation_rounds``) and the workers' CPU time of the blocks
        computed by the call that computed them (``campaign_cpu_time``, s; a rerun that
        computes none adds its own as ``resume_cpu_time``, as the other ``resume_*``).

    Examples
    --------
    >>> import tempfile, workbench
    >>> from workbench.continuation import continued_sweep
    >>> scene = workbench.load_scene({
    ...     "model": {"name": "duffing"},
    ...     "parameters": {"alpha": 1.0, "beta": 0.04, "delta": 0.1, "gamma": 0.1},
    ...     "run": {"cycles": 4, "transient_cycles": 100},
    ...     "record": {"samples_per_period": 1},
    ...     "sweep": {"omega": {"start": 1.2, "stop": 1.6, "num": 6}, "continuation": "both"},
    ... })
    >>> with tempfile.TemporaryDirectory() as d:
    ...     ds = continued_sweep(scene, f"{d}/sweep.nc", workers=2)
    >>> ds.x.dims, [str(d) for d in ds.direction.values]
    (('direction', 'omega', 'record'), ['up', 'down'])
    """
    wall0 = time.perf_counter()
    scene = load_scene(scene)
    if not scene.continuation:
        raise CampaignError(
            "the scene's [sweep] has no continuation setting; run it with "
            'workbench.run_campaign, or add e.g. continuation = "both" to [sweep]'
        )
    grid = expand_sweep(scene)
    plan = Plan(grid, scene.continuation)
    st = Store(store)
    with st.lock():
        if restart:
            st.clear()
        return _run(scene, plan, st, client, workers, progress, wall0, per_point)


def _run(
    scene: Scene, plan: Plan, st: Store, client, workers, progress, wall0, per_point=None
) -> xr.Dataset:
    manifest = st.read_manifest()
    cid = campaign_id(scene, plan.segments, per_point)
    code = segment_code(scene, per_point)
    if manifest is None:
        if st.archive.is_file():
            ds = open_run(st.archive)
            st.check_scene(ds.attrs.get("scene", ""), scene, repr(str(st.archive)))
            return ds
        manifest = st.write_manifest(scene, plan.grid, plan.segments, cid, code)
    else:
        st.check_manifest(manifest, scene, plan.segments)
    engine = Engine(
        st,
        manifest,
        blocks=plan.n_blocks,
        code=code,
        cid=cid,
        client=client,
        workers=workers,
        progress="continued sweep" if progress else False,
        total=sum(len(s.flat) for s in plan.all_segments()),
        runner=run_segment,
        wall0=wall0,
        by="workbench.continuation.continued_sweep",
    )

    def run(tasks: list[Task]) -> None:
        # longest first (Graham 1969)
        engine.run(sorted(tasks, key=lambda t: (-len(t.flat), t.block)))

    try:
        run([_task(scene, plan, st, cid, s, BRUTE, None, per_point) for s in plan.all_segments()])
        blocks = _Blocks(engine)
        final, seams = _settle_seams(scene, plan, engine, blocks, run, per_point)
    finally:
        engine.close()
    chosen = sorted(final.values())
    ds = _assemble(scene, plan, final, seams, blocks)
    return engine.finish(
        ds,
        chosen,
        {
            "campaign_chunk": plan.segments,
            "campaign_blocks": len(final),
            "continuation_rounds": engine.rounds,
            **({"campaign_per_point": per_point_name(per_point)} if per_point is not None else {}),
        },
    )


def _task(
    scene: Scene,
    plan: Plan,
    st: Store,
    cid: str,
    seg: SegmentSpec,
    kind: int,
    seed=None,
    per_point=None,
) -> Task:
    block = plan.block(kind, seg)
    model_module, model_directory = model_source(scene)
    return Task(
        scene_toml=scene.to_toml(),
        dims=plan.grid.dims,
        flat=seg.flat,
        axes=plan.grid.values,
        path=str(st.block_path(block)),
        campaign_id=cid,
        block=block,
        model_module=model_module,
        model_directory=model_directory,
        per_point=per_point,
        own_from=seg.own_from,
        seed_state=None if seed is None else tuple(float(x) for x in seed[0]),
        seed_aux=None if seed is None else tuple(float(x) for x in seed[1]),
    )


def _final_state(ds: xr.Dataset, flat: int):
    """(y, aux) a block's point ``flat`` ended in, or None if it failed."""
    names = ds.attrs.get("state_names", "").split()
    if not names:
        return None
    p = ds.sel(point=flat)
    y = np.array([float(p[f"final_{n}"]) if f"final_{n}" in p else 0.0 for n in names])
    aux = p["final_discrete_state"].values if "final_discrete_state" in p else np.zeros(0)
    if not (np.isfinite(y).all() and np.isfinite(aux).all()):
        return None
    return y, np.asarray(aux, dtype=float)


class _Blocks:
    """The blocks of a continued sweep by index, each read once (loaded) from its task's result
    or its file."""

    def __init__(self, engine: Engine) -> None:
        self.engine, self.read = engine, {}

    def __getitem__(self, index: int) -> xr.Dataset:
        if index not in self.read:
            self.read[index] = self.engine.block(index).load()
        return self.read[index]


def _settle_seams(scene: Scene, plan: Plan, engine: Engine, blocks: _Blocks, run, per_point):
    """Walk every line's seams in order; a seam whose two runs disagree has its later segment
    run again (chained) from the earlier one's final state, round by round, until every seam
    agrees or is chained. Returns the block chosen per segment and the seam measurements."""
    tol = scene.continuation["seam_tolerance"]
    variables = scene.variables
    st, cid = engine.store, engine.cid
    final: dict[tuple[int, int, int], int] = {}
    seams: dict[tuple[int, int, int], tuple[float, float, int]] = {}
    scales = {}
    for d in range(len(plan.directions)):
        for line in range(plan.lines):
            clouds = []
            for j in range(plan.segments):
                b = blocks[plan.block(BRUTE, plan.segment(d, line, j))]
                clouds += [cloud(b, variables, "point", f, RECORD_DIM) for f in b.point.values]
            scales[d, line] = line_scale(clouds)
            final[d, line, 0] = plan.block(BRUTE, plan.segment(d, line, 0))
    while True:
        pending = []
        for d in range(len(plan.directions)):
            for line in range(plan.lines):
                for j in range(1, plan.segments):
                    if (d, line, j) in final:
                        continue
                    prev = blocks[final[d, line, j - 1]]
                    spec = plan.segment(d, line, j)
                    brute = blocks[plan.block(BRUTE, spec)]
                    f = spec.flat[spec.own_from - 1]
                    a = cloud(prev, variables, "point", f, RECORD_DIM)
                    seam_vars = [f"seam_{v}" for v in variables]
                    b = cloud(brute, seam_vars, "seam_point", f, "seam_time")
                    cross, within = attractor_distance(a, b, scales[d, line])
                    if cross <= tol + 2 * within:
                        final[d, line, j] = plan.block(BRUTE, spec)
                        seams[d, line, j] = (cross, within, 0)
                        continue
                    chained = plan.segment(d, line, j, CHAINED)
                    seams[d, line, j] = (cross, within, 1)
                    block = plan.block(CHAINED, chained)
                    if block in engine.computed or block in engine.reused:
                        final[d, line, j] = block
                        continue
                    seed = _final_state(prev, f)
                    pending.append(_task(scene, plan, st, cid, chained, CHAINED, seed, per_point))
                    break  # the next seam of this line waits for this segment
        if not pending:
            return final, seams
        run(pending)


def _assemble(scene: Scene, plan: Plan, final: dict, seams: dict, blocks: _Blocks) -> xr.Dataset:
    engine = blocks.engine
    per_direction = []
    for d in range(len(plan.directions)):
        chosen = [
            blocks[final[d, line, j]].drop_dims(["seam_point"], errors="ignore")
            for line in range(plan.lines)
            for j in range(plan.segments)
        ]
        ds = engine.assemble(scene, plan.grid, chosen)
        ds["seed"] = ds["seed"].fillna(-1).astype(np.int8).assign_attrs(SEED_ATTRS)
        if plan.segments > 1:
            ds = _with_seams(ds, plan, seams, d)
        per_direction.append(ds)
    ds = per_direction[0]
    if len(per_direction) > 1:
        ds = xr.concat(
            per_direction,
            dim="direction",
            data_vars="all",
            coords="minimal",
            compat="override",
            combine_attrs="override",
        )
        if "forcing_period" in ds:
            ds["forcing_period"] = per_direction[0]["forcing_period"]
        if RECORD_TIME in ds.coords:  # each direction's own (coords="minimal" kept the first's)
            times = xr.concat([p[RECORD_TIME] for p in per_direction], dim="direction")
            ds = ds.assign_coords({RECORD_TIME: times})
        ds = ds.assign_coords(direction=("direction", list(plan.directions), DIRECTION_ATTRS))
        ds.attrs["campaign_dims"] = "direction " + ds.attrs["campaign_dims"]
        ds.attrs["campaign_points"] = len(plan.directions) * plan.grid.size
        ds.attrs["failed_points"] = sum(d.attrs["failed_points"] for d in per_direction)
    ds.attrs.update({f"continuation_{k}": v for k, v in scene.continuation.items()})
    return ds


def _with_seams(ds: xr.Dataset, plan: Plan, seams: dict, d: int) -> xr.Dataset:
    """The seam measurements of direction ``d`` over (the other swept dims, ``seam``)."""
    shape = plan.other_shape + (plan.segments - 1,)
    dist, spread = np.full(shape, np.nan), np.full(shape, np.nan)
    chained = np.zeros(shape, np.int8)
    for line in range(plan.lines):
        idx = tuple(np.unravel_index(line, plan.other_shape)) if plan.other_shape else ()
        for j in range(1, plan.segments):
            k = idx + (j - 1,)
            dist[k], spread[k], chained[k] = seams[d, line, j]
    dims = plan.other_dims + ("seam",)
    ds["seam_distance"] = (
        dims,
        dist,
        variable(
            "mean nearest-record distance at a seam between the two segments' runs",
            "1",
            comment="in fractions of each recorded variable's range over the line",
        ),
    )
    ds["seam_spread"] = (
        dims,
        spread,
        variable("mean nearest-record distance within the two runs at a seam", "1"),
    )
    ds["seam_chained"] = (
        dims,
        chained,
        flags(
            "whether the later segment was run again from the earlier one's state",
            ["seam_agreed", "chained"],
        ),
    )
    seam_attrs = variable("seam before segment j (between segments j-1 and j)", "1")
    return ds.assign_coords(seam=("seam", np.arange(1, plan.segments), seam_attrs))
