"""Imported by the fork server of a local campaign pool: load the campaign's compiled kernel once.

The client puts the scene of the campaign's first point (TOML) in the environment variable
``WORKBENCH_CAMPAIGN_PRELOAD`` before the fork server starts; importing this module there loads
(or, on a cold cache, compiles) the model's kernel a single time, and every worker forked from
the server inherits the machine code instead of loading it from disk itself (and xarray's and
netCDF's first-use imports, and the package versions of the provenance). Anything that goes
wrong here is ignored: the workers then load the kernel on their first point as usual.
"""

from __future__ import annotations

import os

from workbench.campaign._block import PRELOAD_ENV


def _load_kernel(scene_toml: str) -> None:
    import numpy as np

    from workbench._scene import load_scene
    from workbench.models import get_model
    from workbench.solver._simulate import integrate

    scene = load_scene(scene_toml)
    if scene.solver["method"].startswith("scipy:"):
        return
    model = get_model(scene.model)
    problem = model.problem(
        scene.resolved_parameters, scene.effects, scene.initial, scene.variables
    )
    # An empty interval: every compiled entry point is loaded, nothing is integrated.
    integrate(problem, np.array([problem.t0]), method=scene.solver["method"])


def _warm_xarray() -> None:
    """First-use costs, paid once here instead of once per worker: xarray's array backends, the
    netCDF writers (netCDF-4 and the netCDF-3 one of the block files), and the package-version
    look-ups of a run's provenance (~20 ms of importlib.metadata on a worker's first point)."""
    import tempfile

    import numpy as np
    import xarray as xr

    from workbench._archive import save_run
    from workbench.solver._simulate import _versions

    ds = xr.Dataset({"a": ("t", np.zeros(2))}, coords={"t": ("t", np.arange(2.0))})
    with tempfile.TemporaryDirectory() as d:
        save_run(ds, os.path.join(d, "warm.nc"))
        save_run(ds, os.path.join(d, "warm3.nc"), classic=True)
    _versions()


if os.environ.get(PRELOAD_ENV):
    try:
        _warm_xarray()
        _load_kernel(os.environ[PRELOAD_ENV])
    except Exception:  # pragma: no cover - best effort only
        pass
