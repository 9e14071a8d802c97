"""The compiled kernel of a scene's model: whether numba's on-disk cache holds it, and loading
(or compiling) it once, before any worker needs it."""

from __future__ import annotations

from workbench.run import integrate, prepare, provenance
from workbench.scene import Scene, scene_from_toml

__all__ = ["kernel_cached", "load_kernel"]


def kernel_cached(scene: Scene) -> bool | None:
    """Whether numba's on-disk cache holds the compiled kernel of a scene's model (None when it
    cannot tell: a scipy method, a model without states, a scene that does not prepare, or a
    numba that keeps its cache elsewhere). Reads the index of the kernel's main entry point,
    as numba itself does before it compiles."""
    if scene.solver["method"].startswith("scipy:"):
        return None
    try:
        problem = prepare(scene.replace(sweep={}) if scene.sweep else scene).problem
    except Exception:  # the run itself will report it
        return None
    if problem.y0.size == 0:
        return None
    try:
        from workbench.solver._compile import kernel_for

        index = kernel_for(problem.hooks).advance._cache._cache_file._load_index()
    except Exception:  # pragma: no cover - numba internals changed
        return None
    return bool(index)


def load_kernel(scene_toml: str) -> None:
    """The provenance's package versions, then the compiled kernel of the scene's model (from
    the cache, or compiled into it)."""
    prepared = prepare(scene_from_toml(scene_toml))
    provenance(prepared.scene)  # the package versions: importlib.metadata look-ups, once
    if prepared.scene.solver["method"].startswith("scipy:"):
        return
    # An empty interval: every compiled entry point is loaded, nothing is integrated.
    integrate(prepared, [prepared.problem.t0])
