"""Workers of a dask cluster as ready as the local pool's: a worker plugin that imports
workbench, loads the campaign's compiled kernel and warms the netCDF writers once per worker
process, before the process's first block (the local pool's fork server does the same once for
all its workers: ``_preload``).

Registered by the client before it submits the first block (:func:`ready_workers`), the plugin
runs on every worker of the cluster and on every worker that joins later (a restarted or an
added one); registration waits until each worker is ready. Workers that find the kernel in the
cache load it at once; one that does not compiles it while the others wait (a lock file in the
cache directory), so that a cold shared cache is compiled once, not once per worker. One
plugin per kernel: its name carries the model's hooks module, the method and the digest of the
code that computes a block (:func:`workbench.campaign._grid.code_of`), so a second campaign of
the same model on the same cluster registers nothing new (``idempotent``).
"""

from __future__ import annotations

import asyncio
import contextlib
import hashlib
import logging
import os
from collections.abc import Iterator

from distributed.diagnostics.plugin import WorkerPlugin

from workbench.campaign._block import task_scene
from workbench.campaign._warm import kernel_cached, load_kernel, warm_io
from workbench.scene import scene_from_toml

__all__ = ["WorkerReady", "ready_workers"]

_log = logging.getLogger(__name__)


def _ready(scene_toml: str, model_module: str = "", model_directory: str = "") -> None:
    """Warm the writers and load the kernel of ``scene_toml`` (the module of a user's model,
    ``model_module`` from ``model_directory``, imported first: see
    :func:`workbench.campaign._block.task_scene`); failures are logged only (the
    first block then loads the kernel itself, and reports any real error). A kernel that is
    not in the cache yet is compiled by one worker at a time (a lock file in the cache
    directory): the first compiles it, the others then find it there and only load it."""
    try:
        warm_io()
        scene = task_scene(scene_toml, model_module, model_directory)
        if kernel_cached(scene) is False:
            with _compile_lock():
                load_kernel(scene_toml, model_module, model_directory)
        else:
            load_kernel(scene_toml, model_module, model_directory)
    except Exception:  # pragma: no cover - any error: preloading only saves time, and the
        # first block loads the kernel itself and reports a real error as its points' outcome
        _log.warning("workbench: preloading the campaign's kernel failed", exc_info=True)


@contextlib.contextmanager
def _compile_lock() -> Iterator[None]:
    """Hold ``flock`` on ``compile.lock`` in the cache directory (workers sharing the cache wait
    for one another; where the file system has no flock, nobody waits)."""
    import fcntl

    from workbench._cache import cache_root

    fd = os.open(cache_root() / "compile.lock", os.O_RDWR | os.O_CREAT, 0o666)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
        except OSError:  # no flock here: compile without waiting
            pass
        yield
    finally:
        os.close(fd)  # releases the lock


class WorkerReady(WorkerPlugin):
    """Load a campaign's compiled kernel in a dask worker before its first task.

    Parameters
    ----------
    scene_toml : str
        A single-point scene of the campaign (TOML): its model's kernel is loaded from the
        on-disk cache (``$WORKBENCH_CACHE_DIR``), or compiled there on a cold cache.
    """

    idempotent = True  # the same kernel registered again: nothing to do

    def __init__(self, scene_toml: str, model_module: str = "", model_directory: str = "") -> None:
        self.scene_toml = scene_toml
        self.model = (model_module, model_directory)

    async def setup(self, worker) -> None:
        # in a thread, so that the worker's event loop (heartbeats) goes on meanwhile
        await _ready_async(self.scene_toml, *self.model)


def plugin_name(scene_toml: str) -> str:
    """The name of the plugin of a campaign's kernel: one per model hooks module, method (the
    loop is compiled per method family) and code digest."""
    from workbench.campaign._grid import code_of
    from workbench.run import prepare

    scene = scene_from_toml(scene_toml)
    try:
        hooks = prepare(scene).problem.hooks
    except Exception:  # any error (the model's own code runs here): a name of its own; the
        # task reports the error as its points' outcome, and one point never stops a campaign
        hooks = hashlib.sha256(scene_toml.encode()).hexdigest()[:12]
    return f"workbench-kernel-{hooks}-{scene.solver['method']}-{code_of(scene)[:16]}"


async def _ready_async(scene_toml: str, *model: str) -> None:
    await asyncio.get_running_loop().run_in_executor(None, _ready, scene_toml, *model)


def ready_workers(
    client, scene_toml: str, model_module: str = "", model_directory: str = ""
) -> str:
    """Register the :class:`WorkerReady` plugin of a campaign's kernel on ``client``'s cluster
    (waits until every worker has loaded it, all at once); returns the plugin's name.
    ``model_module``, ``model_directory``: the campaign's
    :func:`workbench.campaign._block.model_source`."""
    name = plugin_name(scene_toml)
    client.register_plugin(WorkerReady(scene_toml, model_module, model_directory), name=name)
    return name
