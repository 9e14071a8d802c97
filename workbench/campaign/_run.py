"""``run_campaign``: a scene with a ``[sweep]`` -> blocks of points on dask -> one dataset."""

from __future__ import annotations

import math
import os
import sys
import time
import uuid
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from workbench.archive import open_run, save_run
from workbench.campaign._assemble import assemble
from workbench.campaign._block import (
    PRELOAD_ENV,
    BlockTask,
    failed,
    ignore_sigint,
    run_block,
)
from workbench.campaign._store import (
    CampaignError,
    CampaignWarning,
    Store,
    SweepGrid,
    campaign_id,
    expand_sweep,
    forcing_period,
    format_point,
)
from workbench.scene import Scene, SceneSource, load_scene, scene_from_toml

__all__ = ["run_campaign"]

_BLOCKS_PER_WORKER = 4


def _cpu_count() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - macOS, Windows
        return os.cpu_count() or 1


def _positive_int(name: str, value: Any) -> int | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise ValueError(f"{name} must be a positive integer or None, got {value!r}")
    return value


def _client_threads(client) -> int:
    info = client.scheduler_info()
    return max(1, sum(w.get("nthreads", 1) for w in info.get("workers", {}).values()))


def run_campaign(
    scene: SceneSource,
    store: str | os.PathLike,
    *,
    client=None,
    workers: int | None = None,
    chunk: int | None = None,
    restart: bool = False,
    progress: bool = False,
) -> xr.Dataset:
    """Run every point of a scene's ``[sweep]`` grid on dask and return one dataset.

    The grid is the outer product of the swept values (one dim per swept parameter, named after
    the scene key, in the ``[sweep]`` order). The points are split into blocks of ``chunk``
    points; each block is one dask task that runs its points with :func:`workbench.simulate`
    and writes its own netCDF file; only this process assembles them. The store is resumable:
    a re-run computes only the blocks whose file is missing.

    Parameters
    ----------
    scene : Scene, path or mapping
        A scene with a ``[sweep]`` table (loaded with :func:`workbench.load_scene` if needed).
    store : str or PathLike
        Path of the assembled archive, e.g. ``"sweep.nc"``. Blocks and the manifest live in
        the sibling directory ``sweep.nc.blocks/`` (see :mod:`workbench.campaign`).
    client : dask.distributed.Client, optional
        Run the tasks on this cluster (its workers must see ``store``'s file system). Default:
        a local pool of processes (dask's multiprocessing scheduler).
    workers : int, optional
        Processes of the local pool (default: the CPUs available). Not allowed with ``client``.
    chunk : int, optional
        Points per block (task). Default: about four blocks per worker; on resume, the
        chunk size the store was started with.
    restart : bool
        Discard whatever the store holds (archive, blocks, manifest) and start afresh. Without
        it, a store of a different scene or chunk size is refused with the differences named.
    progress : bool
        Show a progress bar over points with an ETA (and the dashboard link of a client).

    Returns
    -------
    xarray.Dataset
        The parameter dims first, then ``time`` and the model's dims. Variables: the scene's
        recorded variables (NaN where a point failed), ``status`` (int8 per point: the
        point's :class:`workbench.Status`, or 6 invalid_parameters; CF flag attributes),
        ``failure`` (message per point, empty if none), ``solver_steps``,
        ``solver_rejected_steps``, ``solver_rhs_evaluations``, ``solver_events``,
        ``solver_wall_time`` (s), ``point_wall_time`` (s), and ``forcing_period`` (s) for a
        forced model. When the record times differ between points (a sweep over the forcing
        frequency), ``time`` has no coordinate and ``record_time`` (s; parameter dims, time)
        holds each point's times. Attributes: provenance, the scene TOML, the grid
        (``campaign_grid``, JSON), ``computed_blocks``, ``reused_blocks``, ``failed_points``,
        ``campaign_workers``, ``campaign_compute_wall_time`` (s, the task phase) and
        ``campaign_wall_time`` (s, all of this call but the final write). The same dataset is
        stored at ``store``.

    Raises
    ------
    CampaignError
        The scene has no ``[sweep]``, or the store holds a campaign of another scene or chunk
        size (the message lists the differences; pass ``restart=True``).
    RuntimeError
        A point raised something other than a failed run or invalid parameters (a bug or a
        broken setup); the blocks finished so far are kept.

    Warns
    -----
    CampaignWarning
        Some points failed (they are flagged in ``status`` and the campaign goes on).

    Notes
    -----
    The numbers do not depend on ``workers``, ``chunk`` or ``client``: points are independent
    and placed by grid index. Numba compiles nothing per point: the kernel comes from the
    on-disk cache, loaded once by the local pool's fork server (or once per worker process of
    a cluster). Like any process pool, the local one re-imports the calling script's main
    module in its workers, so a script that calls this needs the usual
    ``if __name__ == "__main__":`` guard.

    Examples
    --------
    >>> import tempfile, workbench
    >>> scene = workbench.load_scene({
    ...     "model": {"name": "duffing"},
    ...     "run": {"cycles": 4, "transient_cycles": 2},
    ...     "record": {"samples_per_period": 1},
    ...     "sweep": {"gamma": [0.3, 0.4, 0.5], "delta": [0.2, 0.3]},
    ... })
    >>> with tempfile.TemporaryDirectory() as d:
    ...     ds = workbench.run_campaign(scene, f"{d}/sweep.nc", workers=2)
    >>> ds.x.dims, ds.gamma.attrs["units"], int(ds.status.sum())
    (('gamma', 'delta', 'time'), 'm s-2', 0)
    """
    wall0 = time.perf_counter()
    scene = load_scene(scene)
    grid = expand_sweep(scene)
    workers = _positive_int("workers", workers)
    chunk = _positive_int("chunk", chunk)
    if client is not None and workers is not None:
        raise ValueError(
            f"workers={workers!r} sets the size of the local pool, but a client brings its own "
            "workers; pass one of them, not both"
        )
    st = Store(store)
    if restart:
        st.clear()
    manifest = st.read_manifest()
    if manifest is None:
        reused = _complete_archive(st, scene, chunk)
        if reused is not None:
            reused.attrs.update(
                campaign_workers=0,
                campaign_compute_wall_time=0.0,
                campaign_wall_time=time.perf_counter() - wall0,
            )
            return reused
        if chunk is None:
            n = _client_threads(client) if client is not None else (workers or _cpu_count())
            chunk = max(1, math.ceil(grid.size / (_BLOCKS_PER_WORKER * n)))
        cid = campaign_id(scene, chunk)
        st.write_manifest(scene, grid, chunk, cid)
    else:
        chunk = st.check_manifest(manifest, scene, chunk)
        cid = manifest["campaign_id"]
    st.remove_temporaries()
    blocks = grid.blocks(chunk)
    done = st.finished_blocks(cid, blocks)
    tasks = [
        BlockTask(
            scene_toml=scene.to_toml(),
            dims=grid.dims,
            flat=tuple(rng),
            values=tuple(tuple(grid.point(f).values()) for f in rng),
            path=str(st.block_path(i)),
            campaign_id=cid,
            block=i,
        )
        for i, rng in enumerate(blocks)
        if i not in done
    ]
    tasks = longest_first(scene, grid, tasks)
    n_workers = _client_threads(client) if client is not None else (workers or _cpu_count())
    compute0 = time.perf_counter()
    results: list[dict] = []
    if tasks:
        bar = _bar(grid.size, sum(len(blocks[i]) for i in done)) if progress else None
        try:
            if client is not None:
                results = _run_distributed(client, tasks, bar, cid)
            else:
                n_workers = min(n_workers, len(tasks))
                results = _run_local(tasks, n_workers, bar)
        finally:
            if bar is not None:
                bar.close()
        if len(results) != len(tasks):  # pragma: no cover - guards the schedulers
            raise RuntimeError(f"{len(tasks)} blocks were scheduled, {len(results)} came back")
    compute = time.perf_counter() - compute0
    in_memory = {r["block"]: r["dataset"] for r in results if r.get("dataset") is not None}
    ds = assemble(
        scene,
        grid,
        st,
        chunk,
        cid,
        {
            "computed_blocks": len(tasks),
            "reused_blocks": len(done),
            "campaign_workers": n_workers if tasks else 0,
            "campaign_compute_wall_time": compute,
            "campaign_wall_time": time.perf_counter() - wall0,
        },
        in_memory,
    )
    save_run(ds, st.archive)
    ds = open_run(st.archive)
    if ds.attrs["failed_points"]:
        _warn_failures(ds, grid)
    return ds


def _complete_archive(st: Store, scene: Scene, chunk: int | None) -> xr.Dataset | None:
    """The stored archive if it is this campaign, complete, and its blocks are gone; a
    CampaignError if the file at the store path is something else; None if there is none."""
    if not st.archive.is_file():
        return None
    try:
        ds = open_run(st.archive)
    except Exception as exc:
        raise CampaignError(
            f"{str(st.archive)!r} exists but is not a readable netCDF file ({exc}); pass "
            "restart=True (CLI --restart) to overwrite it, or choose another output path"
        ) from None
    if "campaign_id" not in ds.attrs or "scene" not in ds.attrs:
        raise CampaignError(
            f"{str(st.archive)!r} exists and is not a workbench campaign archive (it has no "
            "'campaign_id' attribute); pass restart=True (CLI --restart) to overwrite it, or "
            "choose another output path"
        )
    st.check_scene(ds.attrs["scene"], scene, repr(str(st.archive)))
    if chunk is not None and chunk != int(ds.attrs["campaign_chunk"]):
        return None  # same numbers, other blocks: recompute with the chunk size asked for
    ds.attrs.update(computed_blocks=0, reused_blocks=int(ds.attrs["campaign_blocks"]))
    return ds


def _warn_failures(ds: xr.Dataset, grid: SweepGrid) -> None:
    flags = ds["status"].values.reshape(-1)
    messages = ds["failure"].values.reshape(-1)
    bad = np.flatnonzero(failed(flags))
    shown = "; ".join(f"{format_point(grid.point(int(f)))}: {messages[f]}" for f in bad[:3])
    more = f"; and {len(bad) - 3} more" if len(bad) > 3 else ""
    warnings.warn(
        CampaignWarning(
            f"{len(bad)} of {grid.size} campaign points failed and are flagged in 'status' "
            f"with their message in 'failure' (the campaign went on): {shown}{more}"
        ),
        stacklevel=3,
    )


# -- execution -------------------------------------------------------------------------------------
def simulated_span(scene: Scene, grid: SweepGrid, flat: int) -> float:
    """Simulated time (s) of one point: transient and recorded cycles times its forcing period,
    or transient + duration. The cost estimate of a point (the solver's work grows with the
    simulated time; a sweep over the forcing frequency spans 30x between 0.1 pi and 3 pi)."""
    try:
        period = forcing_period(scene, grid, flat)
    except Exception:  # the point is invalid: it costs nothing (it fails at validation)
        return 0.0
    run = scene.run
    if period is not None and "cycles" in run:
        return (run["cycles"] + run["transient_cycles"]) * period
    return run.get("duration", 0.0) + run.get("transient", 0.0)


def longest_first(scene: Scene, grid: SweepGrid, tasks: list[BlockTask]) -> list[BlockTask]:
    """The tasks ordered by decreasing estimated cost (their points' simulated time), so that
    the longest blocks start first and no worker is left with one at the end: Graham's (1969)
    longest-processing-time rule, within 4/3 of the best schedule. Ties keep block order."""
    cost = {t.block: sum(simulated_span(scene, grid, f) for f in t.flat) for t in tasks}
    return sorted(tasks, key=lambda t: (-cost[t.block], t.block))


def _bar(total: int, initial: int):
    from tqdm.auto import tqdm

    return tqdm(total=total, initial=initial, unit="pt", desc="campaign", smoothing=0.05)


def _mp_context(first_point_toml: str):
    """The multiprocessing context of the local pool: dask's ``multiprocessing.context`` if set,
    else a fork server (else spawn). The fork server imports workbench once and, when this call
    starts it, loads the campaign's compiled kernel once (see ``_preload``): workers forked from
    it start in milliseconds with the machine code in memory, and exit as fast."""
    import multiprocessing

    name = dask_config_get("multiprocessing.context")
    if name is not None:
        return multiprocessing.get_context(name)
    if "forkserver" not in multiprocessing.get_all_start_methods():  # pragma: no cover
        return multiprocessing.get_context("spawn")
    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload(["workbench.campaign._block", "workbench.campaign._preload"])
    os.environ[PRELOAD_ENV] = first_point_toml  # read by the server if this run starts it
    return ctx


def dask_config_get(key: str):
    import dask

    return dask.config.get(key, None)


def _run_local(tasks: list[BlockTask], workers: int, bar) -> list[dict]:
    """Tasks on dask's multiprocessing scheduler: a pool of ``workers`` processes, one thread
    each, one block per dispatch."""
    from concurrent.futures import ProcessPoolExecutor
    from concurrent.futures.process import BrokenProcessPool

    import dask.multiprocessing
    from dask.callbacks import Callback

    class _Points(Callback):
        def _posttask(self, key, result, dsk, state, id):
            if bar is not None:
                bar.update(result["points"])

    dsk = _graph_in_order(tasks)
    first = tasks[0]
    first_point = scene_from_toml(first.scene_toml).with_parameters(
        **dict(zip(first.dims, first.values[0], strict=True))
    )
    pool = ProcessPoolExecutor(
        workers, mp_context=_mp_context(first_point.to_toml()), initializer=ignore_sigint
    )
    try:
        return list(
            dask.multiprocessing.get(
                dsk,
                list(dsk),
                pool=pool,
                chunksize=1,
                optimize_graph=False,
                callbacks=[_Points()._callback],
            )
        )
    except BaseException as exc:  # Ctrl-C or a failed task: stop the blocks in flight now
        for p in list((getattr(pool, "_processes", None) or {}).values()):
            p.terminate()
        if isinstance(exc, BrokenProcessPool):
            raise RuntimeError(
                "a worker process of the local pool died (killed, out of memory, or the calling "
                "script lacks the `if __name__ == '__main__':` guard that process pools need); "
                "the finished blocks are kept: run the campaign again to compute the rest"
            ) from exc
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
        os.environ.pop(PRELOAD_ENV, None)


def _graph_in_order(tasks: list[BlockTask]) -> dict:
    """A dask graph of the tasks whose scheduling priority follows the list order.

    Independent tasks are run by dask's local scheduler in the order of ``dask.order.order``,
    which for tasks without dependencies depends only on their key names (reverse name order in
    dask 2025); so the names are drawn first, ranked by dask, and given to the tasks in turn.
    """
    from dask.order import order

    names = [f"campaign-task-{i:05d}" for i in range(len(tasks))]
    rank = order({k: (run_block, None) for k in names})
    names.sort(key=rank.__getitem__)
    return {name: (run_block, t) for name, t in zip(names, tasks, strict=True)}


def _run_distributed(client, tasks: list[BlockTask], bar, cid: str) -> list[dict]:
    """Tasks on a dask.distributed cluster; a killed worker's task is rescheduled by dask."""
    from distributed import as_completed

    if bar is not None:
        link = getattr(client, "dashboard_link", None)
        if link:
            print(f"campaign: dask dashboard at {link}", file=sys.stderr)
    token = uuid.uuid4().hex[:8]
    futures = [
        client.submit(
            run_block,
            t,
            key=f"campaign-{cid}-block-{t.block:05d}-{token}",
            pure=False,
            priority=len(tasks) - i,  # higher runs first: the list is longest first
        )
        for i, t in enumerate(tasks)
    ]
    results, errors = [], []
    try:
        for fut in as_completed(futures):
            if fut.status == "error":
                errors.append(fut)
                continue
            r = fut.result()
            results.append(r)
            if bar is not None:
                bar.update(r["points"])
    finally:
        client.cancel([f for f in futures if not f.done()])
    if errors:
        errors[0].result()  # re-raise the first error, with its traceback
    return results


def store_paths(store: str | os.PathLike) -> dict[str, Path]:
    """Where a campaign at ``store`` keeps its files: ``archive``, ``blocks``, ``manifest``."""
    st = Store(store)
    return {"archive": st.archive, "blocks": st.blocks_dir, "manifest": st.manifest_path}
