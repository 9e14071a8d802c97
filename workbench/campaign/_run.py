"""``run_campaign``: a scene with a ``[sweep]`` -> blocks of points run in parallel (a local
process pool or a dask.distributed cluster) -> one dataset; the store it resumes from."""

from __future__ import annotations

import math
import os
import shutil
import sys
import time
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np
import xarray as xr

from workbench._checks import positive_int
from workbench.archive import ArchiveError, open_run
from workbench.campaign._assemble import execution_attrs
from workbench.campaign._block import Task, failed, model_source
from workbench.campaign._engine import Engine
from workbench.campaign._errors import CampaignError, CampaignWarning
from workbench.campaign._execute import available_workers
from workbench.campaign._grid import (
    MAX_POINTS,
    SweepGrid,
    campaign_id,
    check_archive_memory,
    check_points,
    code_of,
    expand_sweep,
    format_point,
    modules_of,
)
from workbench.campaign._schedule import longest_first, partition
from workbench.campaign._store import Store
from workbench.run import format_bytes
from workbench.scene import Scene, SceneSource, load_scene

__all__ = ["run_campaign", "store_paths"]

_BLOCKS_PER_WORKER = 4
_PLAN_NOTICE = 10**6  # a grid of this many points takes about a second to plan: say so


def run_campaign(
    scene: SceneSource,
    store: str | os.PathLike,
    *,
    client=None,
    workers: int | None = None,
    chunk: int | None = None,
    restart: bool = False,
    progress: bool | str = False,
    max_memory: float | str | None = None,
    per_point: Callable[[Scene, xr.Dataset], xr.Dataset] | None = None,
    max_points: int | None = MAX_POINTS,
) -> xr.Dataset:
    """Run every point of a scene's ``[sweep]`` grid in parallel and return one dataset.

    The grid is the outer product of the swept values (one dim per swept parameter, named after
    the scene key, in the ``[sweep]`` order). The points are split into blocks of ``chunk``
    points; each block is one task that runs its points with :func:`workbench.simulate` and
    writes its own netCDF file; the tasks start longest first, as many at a time as there are
    workers; only this process assembles them. The store is resumable: a re-run computes only
    the blocks that are not committed intact (checksums in the manifest), and one process at a
    time writes it (a lock). The processes of the local pool die with this one, however it
    ends.

    Parameters
    ----------
    scene : Scene, path or mapping
        A scene with a ``[sweep]`` table (loaded with :func:`workbench.load_scene` if needed).
    store : str or PathLike
        Path of the assembled archive, e.g. ``"sweep.nc"``. Blocks and the manifest live in
        the sibling directory ``sweep.nc.blocks/`` (see :mod:`workbench.campaign`).
    client : dask.distributed.Client, optional
        Run the tasks on this cluster (its workers must see ``store``'s file system). Default:
        a local pool of processes forked from a server that has loaded the compiled kernel
        (its start method follows dask's ``multiprocessing.context`` setting when set).
    workers : int, optional
        Processes of the local pool (default: the CPUs available). Not allowed with ``client``.
    chunk : int, optional
        Points per block (task). Default: about four blocks per worker; on resume, the
        chunk size the store was started with.
    restart : bool
        Discard whatever the store holds (archive, blocks, manifest) and start afresh. Without
        it, a store of a different scene or chunk size is refused with the differences named.
    progress : bool or str
        Show a progress bar over points with an ETA (and the dashboard link of a client); a
        string names what runs on the bar (``"campaign NAME"``, e.g. a study's case).
    max_memory : float or str, optional
        Refuse, before anything runs, a campaign whose assembled archive (or one point's
        records) would take more memory than this (bytes, or text such as ``"16 GiB"``;
        default: the environment variable ``WORKBENCH_MAX_MEMORY``, else half of this
        machine's memory): a :class:`workbench.run.MemoryLimitError` that says what to lower.
    per_point : callable, optional
        ``per_point(scene, run)``, called in the worker on each point's single-run scene and
        its run (the dataset of :func:`workbench.simulate`) when the run succeeded; returns a
        Dataset of measurements without a ``time`` dim (e.g. a chaos indicator with its
        units), which become variables over the parameter dims (NaN where a run failed). A
        module-level function (it is pickled to the workers); its qualified name is part of
        the campaign's identity, so a store of another measurement is refused.
    max_points : int or None
        Refuse, before anything else is checked or planned, a grid of more points than this
        (default one million; None: no limit): a :class:`CampaignError` that names the size
        and how to raise the limit. Planning and assembling a campaign take memory and time
        in proportion to its points.

    Returns
    -------
    xarray.Dataset
        The parameter dims first, then ``time`` and the model's dims. Variables: the scene's
        recorded variables (NaN where a point failed), ``status`` (int8 per point: the
        point's :class:`workbench.Status`, or 6 invalid_parameters, or 7 error: the point raised
        an exception; CF flag attributes),
        ``failure`` (message per point, empty if none), ``solver_steps``,
        ``solver_rejected_steps``, ``solver_rhs_evaluations``, ``solver_events``,
        ``solver_wall_time`` (s), ``point_wall_time`` (s), and ``forcing_period`` (s) for a
        forced model. When the record times differ between points (a sweep over the forcing
        frequency), they run along ``record``, not ``time``, and ``record_time`` (s;
        parameter dims, record) holds each point's times. Attributes: provenance, the scene
        TOML, the grid
        (``campaign_grid``, JSON), ``computed_blocks`` and ``reused_blocks`` (by this call),
        ``failed_points``, ``campaign_workers``, ``campaign_compute_wall_time`` (s, the task
        phase), ``campaign_wall_time`` (s, all of the call but the final write) and
        ``campaign_block_sha256`` (the SHA-256 of every block file, in block order, space
        separated). The ``campaign_*`` figures are those of the call that computed blocks: a
        call that finds every block done keeps them and adds its own as ``resume_workers``
        (0), ``resume_compute_wall_time`` and ``resume_wall_time``. The same dataset is
        stored at ``store``.

    Raises
    ------
    CampaignError
        The scene has no ``[sweep]``, its grid has more than ``max_points`` points, the forcing
        period of a point cannot be computed, or the store holds a campaign of another scene or
        chunk size (the message lists the differences; pass ``restart=True``).
    workbench.archive.StoreLocked
        Another live process is writing the store (the message names its pid and host). The
        lock is held for the whole call; a lock left by a dead process is taken over.
    RuntimeError
        A worker process died (killed, out of memory); the blocks finished so far are kept
        (the message says where, when there are any).
        (A point that raises an exception does not stop the campaign: it is flagged ``error``
        in ``status``, with the exception in ``failure``.)

    Warns
    -----
    CampaignWarning
        Some points failed (they are flagged in ``status`` and the campaign goes on); a block
        is missing, corrupt (its SHA-256 differs from the one recorded when it was committed)
        or was never committed, and is recomputed (each named); a stale lock was taken over.

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
    (('gamma', 'delta', 'time'), '1', 0)
    """
    wall0 = time.perf_counter()
    scene = load_scene(scene)
    if scene.continuation:
        raise CampaignError(
            "the scene's [sweep] asks for a continued sweep (continuation = "
            f"{scene.continuation['direction']!r}): each point starts from its neighbour's "
            "state, which run_campaign does not do; run it with "
            "workbench.continuation.continued_sweep (CLI: workbench campaign), or remove "
            "sweep.continuation"
        )
    grid = expand_sweep(scene)
    check_points(grid, positive_int("max_points", max_points, allow_none=True))
    workers = positive_int("workers", workers, allow_none=True)
    chunk = positive_int("chunk", chunk, allow_none=True)
    if progress and grid.size >= _PLAN_NOTICE:
        print(f"campaign: planning {grid.size} points ({grid.describe()})", file=sys.stderr)
    size = check_archive_memory(scene, grid, max_memory)
    if client is not None and workers is not None:
        raise ValueError(
            f"workers={workers!r} sets the size of the local pool, but a client brings its own "
            "workers; pass one of them, not both"
        )
    st = Store(store)
    _warn_disk(st, size)
    with st.lock():
        return _run_locked(
            scene,
            grid,
            st,
            client,
            workers,
            chunk,
            restart,
            progress,
            wall0,
            max_memory,
            per_point,
        )


def _run_locked(
    scene: Scene,
    grid: SweepGrid,
    st: Store,
    client,
    workers: int | None,
    chunk: int | None,
    restart: bool,
    progress: bool | str,
    wall0: float,
    max_memory: float | str | None = None,
    per_point: Callable | None = None,
) -> xr.Dataset:
    """run_campaign while holding the store's lock."""
    if restart:
        st.clear()
    manifest = st.read_manifest()
    if manifest is None:
        reused = _complete_archive(st, scene, chunk, per_point)
        if reused is not None:  # computed before: that call's figures stay, this one's added
            this = {
                "campaign_workers": 0,
                "campaign_compute_wall_time": 0.0,
                "campaign_cpu_time": 0.0,
                "campaign_wall_time": time.perf_counter() - wall0,
            }
            reused.attrs.update(execution_attrs(this, reused.attrs))
            return reused
        if chunk is None:
            n = available_workers(client, workers)
            chunk = max(1, math.ceil(grid.size / (_BLOCKS_PER_WORKER * n)))
        cid = campaign_id(scene, chunk, per_point)
        blocks = partition(scene, grid, chunk)
        manifest = st.write_manifest(
            scene, grid, chunk, cid, blocks, code_of(scene, *modules_of(per_point))
        )
    else:
        chunk = st.check_manifest(manifest, scene, chunk)
        cid = manifest["campaign_id"]
        if cid != campaign_id(scene, chunk, per_point):
            raise CampaignError(
                f"{str(st.blocks_dir)!r} holds a campaign measured per point by another function "
                f"(per_point={per_point_name(per_point)}); pass restart=True (CLI --restart) to "
                "start afresh, or choose another output path"
            )
        blocks = st.blocks(manifest, grid)
    code = code_of(scene, *modules_of(per_point))
    engine = Engine(
        st,
        manifest,
        blocks=len(blocks),
        code=code,
        cid=cid,
        client=client,
        workers=workers,
        progress=f"campaign {progress}" if isinstance(progress, str) else progress,
        total=grid.size,
        wall0=wall0,
    )
    model_module, model_directory = model_source(scene)
    toml = scene.to_toml()
    tasks = [
        Task(
            scene_toml=toml,
            dims=grid.dims,
            flat=points,
            axes=grid.values,
            path=str(st.block_path(i)),
            campaign_id=cid,
            block=i,
            max_memory=max_memory,
            model_module=model_module,
            model_directory=model_directory,
            per_point=per_point,
        )
        for i, points in enumerate(blocks)
    ]
    engine.run(longest_first(scene, grid, tasks))
    order = list(range(len(blocks)))
    ds = engine.assemble(scene, grid, [engine.block(i) for i in order])
    ds = engine.finish(
        ds,
        order,
        {
            "campaign_chunk": chunk,
            "campaign_blocks": len(blocks),
            # the measurement's name, only when there is one (None: the attribute is absent)
            **({"campaign_per_point": per_point_name(per_point)} if per_point is not None else {}),
        },
    )
    if ds.attrs["failed_points"]:
        _warn_failures(ds, grid)
    return ds


def _warn_disk(st: Store, size: float) -> None:
    """Warn when the file system of the store has less room than the blocks and the archive
    may take (twice the data, uncompressed: an upper bound)."""
    directory = st.archive.parent
    while not directory.exists():
        directory = directory.parent
    free = shutil.disk_usage(directory).free
    if free < 2 * size:
        warnings.warn(
            CampaignWarning(
                f"the campaign's blocks and archive may take up to {format_bytes(2 * size)} "
                f"(uncompressed), and {str(directory)!r} has {format_bytes(free)} free: it may "
                "stop on a full disk (its finished blocks are kept; free space and run it again)"
            ),
            stacklevel=3,
        )


def per_point_name(fn: Callable | None) -> str:
    """The name of a per-point measurement (its module and qualified name; 'None')."""
    return "None" if fn is None else f"{fn.__module__}.{fn.__qualname__}"


def _complete_archive(
    st: Store, scene: Scene, chunk: int | None, per_point: Callable | None = None
) -> xr.Dataset | None:
    """The stored archive if it is this campaign, complete, and its blocks are gone; a
    CampaignError if the file at the store path is something else; None if there is none."""
    if not st.archive.is_file():
        return None
    try:
        ds = open_run(st.archive)
    except (OSError, ArchiveError) as exc:
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
    if ds.attrs.get("campaign_per_point", "None") != per_point_name(per_point):
        return None  # same runs, another measurement: recompute
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


def store_paths(store: str | os.PathLike) -> dict[str, Path]:
    """Where a campaign at ``store`` keeps its files: ``archive``, ``blocks``, ``manifest``."""
    st = Store(store)
    return {"archive": st.archive, "blocks": st.blocks_dir, "manifest": st.manifest_path}
