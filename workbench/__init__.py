"""workbench: nonlinear dynamics of mechanisms with clearance joints.

A declarative *scene* (TOML) becomes labelled :class:`xarray.Dataset` runs through a compiled
solver; :mod:`workbench.analysis` identifies chaos in them; runs are archived as netCDF.

>>> import workbench
>>> scene = workbench.load_scene({"model": {"name": "duffing"}, "run": {"cycles": 2}})
>>> ds = workbench.simulate(scene)
>>> float(ds.time[-1] - ds.time[0]) == 2 * ds.attrs["forcing_period"]
True

Layers, lowest first (each imports only those before it; :data:`workbench._layers.LAYERS`,
checked by ``tests/test_layers.py``): solver -> models -> scene -> run -> archive -> precision
(``accuracy``) -> analysis -> plot -> campaign -> continuation -> verification (``verify``) ->
study -> cli. ``workbench.analysis``, ``workbench.plot`` and ``verify`` (which needs the
optional extra exudyn when called) load on first use.
"""

from workbench._cache import register_cache_locator

register_cache_locator()  # before any workbench module defines a cached compiled function

from workbench._errors import ModelWarning  # noqa: E402
from workbench._version import FORMAT_VERSION, __version__  # noqa: E402
from workbench.archive import open_run, save_run  # noqa: E402
from workbench.campaign import CampaignError, run_campaign  # noqa: E402
from workbench.precision import Recommendation, accuracy, recommend  # noqa: E402
from workbench.run import prepare, simulate  # noqa: E402
from workbench.scene import Scene, SceneError, load_scene, scene_from_toml  # noqa: E402
from workbench.solver import SolverError, Status  # noqa: E402

__all__ = [
    "FORMAT_VERSION",
    "CampaignError",
    "ModelWarning",
    "Recommendation",
    "Scene",
    "SceneError",
    "SolverError",
    "Status",
    "accuracy",
    "analysis",
    "load_scene",
    "open_run",
    "plot",
    "prepare",
    "recommend",
    "run_campaign",
    "save_run",
    "scene_from_toml",
    "simulate",
    "verify",
    "__version__",
]

_LAZY_MODULES = ("analysis", "plot", "models", "verification")


def __getattr__(name: str):
    """The lazy names: subpackages that cost an import (matplotlib, nolds) and ``verify``."""
    import importlib

    if name in _LAZY_MODULES:
        return importlib.import_module(f"workbench.{name}")
    if name == "verify":
        return importlib.import_module("workbench.verification").verify
    raise AttributeError(f"module 'workbench' has no attribute {name!r}")
