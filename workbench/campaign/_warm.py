"""The compiled kernel of a scene's model: whether numba's on-disk cache holds it, and loading
(or compiling) it once, before any worker needs it; and the first-use costs of the writers."""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path

from workbench.campaign._block import task_scene
from workbench.models import Model, get_model
from workbench.run import derive, integrate, prepare, provenance, to_dataset
from workbench.scene import Scene

__all__ = ["compile_record", "kernel_cached", "load_kernel", "warm_io", "warm_kernel"]

#: What the first run of a model (import, prepare, one simulated cycle) took with an empty
#: kernel cache where it was last measured, per model: ``cpu_seconds``, ``wall_seconds``,
#: ``cores``, ``load`` (the 1-min load average before and after), ``date``, ``commit``,
#: ``command``. Written by ``benchmarks/cache.py``, read by :func:`compile_record`.
COMPILE_TIMES = Path(__file__).with_name("compile_times.json")


def compile_record(model: str) -> tuple[str, dict] | None:
    """The measured first run with an empty kernel cache (:data:`COMPILE_TIMES`) of ``model``,
    else of the model that stands in for it (the model's
    :attr:`~workbench.models.Model.compile_stand_in`), as (the model measured, its record);
    None when neither was measured."""
    try:
        records = json.loads(COMPILE_TIMES.read_text())
    except (OSError, ValueError):  # pragma: no cover - a package installed without it
        return None
    try:
        stand_in = get_model(model).compile_stand_in
    except KeyError:  # a model this process does not know
        stand_in = Model.compile_stand_in
    for name in (model, stand_in):
        if name in records:
            return name, records[name]
    return None


def kernel_cached(scene: Scene) -> bool | None:
    """Whether numba's on-disk cache holds the compiled kernel of a scene's model (None when it
    cannot tell: a scipy method, a model without states, a scene that does not prepare, or a
    numba that keeps its cache elsewhere; a cache that is refused raises its CacheError). Reads
    the index of the kernel's main entry point, as numba itself does before it compiles."""
    if scene.solver["method"].startswith("scipy:"):
        return None
    try:
        problem = prepare(scene.replace(sweep={}) if scene.sweep else scene).problem
    except Exception:  # any error (the model's own code runs here): cannot tell; the run
        # reports it, as its points' outcome in a campaign (one point never stops a campaign)
        return None
    if problem.y0.size == 0:
        return None
    from workbench._cache import CacheError

    try:
        from workbench.solver._compile import kernel_for

        index = kernel_for(problem.hooks).advance._cache._cache_file._load_index()
    except CacheError:  # a refused cache: said before anything runs
        raise
    except Exception:  # pragma: no cover - any error: numba's private attributes and index
        # format change between its versions; the answer is a hint only (None: cannot tell)
        return None
    return bool(index)


def load_kernel(scene_toml: str, model_module: str = "", model_directory: str = "") -> None:
    """The provenance's package versions, then every compiled function a point of the scene
    runs (from the cache, or compiled into it): the kernel of the scene's model and the model's
    derived outputs, over an empty interval (one record at the start: nothing is integrated).
    ``model_module``, ``model_directory``: the campaign's :func:`model_source`, imported first
    (see :func:`task_scene`)."""
    prepared = prepare(task_scene(scene_toml, model_module, model_directory))
    provenance(prepared.scene)  # the package versions: importlib.metadata look-ups, once
    if prepared.scene.solver["method"].startswith("scipy:"):
        return
    result = integrate(prepared, [prepared.problem.t0])
    derived, result = derive(prepared, result)
    to_dataset(prepared, result, derived)


def warm_io() -> None:
    """First-use costs of a worker, paid before its first block: xarray's array backends and
    the netCDF writers (netCDF-4, and the netCDF-3 one of the block files)."""
    import numpy as np
    import xarray as xr

    from workbench.archive import save_run

    ds = xr.Dataset({"a": ("t", np.zeros(2))}, coords={"t": ("t", np.arange(2.0))})
    with tempfile.TemporaryDirectory() as d:
        save_run(ds, os.path.join(d, "warm.nc"))
        save_run(ds, os.path.join(d, "warm3.nc"), classic=True)


def warm_kernel(scene: Scene) -> bool:
    """Compile the kernel of a scene's model into the on-disk cache if it is not there yet
    (``$WORKBENCH_CACHE_DIR``, else ``~/.cache/workbench``), so that workers sharing that cache
    only load it. The scene of a campaign stands for its first point (the kernel is the same
    for every point of a sweep). Returns whether anything was compiled.

    >>> import workbench
    >>> from workbench.campaign import warm_kernel
    >>> scene = workbench.load_scene({"model": {"name": "duffing"}})
    >>> _ = warm_kernel(scene)  # compiles on a cold cache
    >>> warm_kernel(scene)  # now only loads
    False
    """
    if kernel_cached(scene) is not False:
        return False
    load_kernel(scene.replace(sweep={}).to_toml())
    return True
