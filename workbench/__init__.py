"""workbench: nonlinear dynamics of mechanisms with clearance joints.

A declarative *scene* (TOML) becomes labelled :class:`xarray.Dataset` runs through a compiled
solver; :mod:`workbench.analysis` identifies chaos in them; runs are archived as netCDF.

>>> import workbench
>>> scene = workbench.load_scene({"model": {"name": "duffing"}, "run": {"cycles": 2}})
>>> ds = workbench.simulate(scene)
>>> float(ds.time[-1] - ds.time[0]) == 2 * ds.attrs["forcing_period"]
True
"""

from workbench._cache import configure_numba_cache

configure_numba_cache()

from workbench._archive import open_run, save_run  # noqa: E402
from workbench._errors import SceneError, SolverError  # noqa: E402
from workbench._scene import Scene, load_scene  # noqa: E402
from workbench.campaign import run_campaign  # noqa: E402
from workbench.solver import simulate  # noqa: E402

__version__ = "0.1.0"

__all__ = [
    "Scene",
    "SceneError",
    "SolverError",
    "load_scene",
    "open_run",
    "run_campaign",
    "save_run",
    "simulate",
    "__version__",
]
