"""workbench: nonlinear dynamics of mechanisms with clearance joints.

A declarative *scene* (TOML) becomes labelled :class:`xarray.Dataset` runs through a compiled
solver; :mod:`workbench.analysis` identifies chaos in them; runs are archived as netCDF.

>>> import workbench
>>> scene = workbench.load_scene({"model": {"name": "duffing"}, "run": {"cycles": 2}})
>>> ds = workbench.simulate(scene)
>>> float(ds.time[-1] - ds.time[0]) == 2 * ds.attrs["forcing_period"]
True

Layers, lowest first (each imports only those before it; :data:`workbench._layers.LAYERS`,
checked by ``tests/package/test_layers.py``): solver -> models -> scene -> run -> archive ->
precision
(``accuracy``) -> analysis -> plot -> campaign -> continuation -> verification (``verify``) ->
study -> cli. Every public name loads on first use (``verify`` needs the optional extra exudyn
when called): ``import workbench`` alone imports none of numba, xarray, dask or matplotlib.
"""

from typing import TYPE_CHECKING

from workbench._version import FORMAT_VERSION, __version__

if TYPE_CHECKING:  # the public names, imported on first use (``__getattr__`` below)
    from workbench import analysis, plot
    from workbench._errors import ModelWarning, WorkbenchError
    from workbench.archive import open_run, save_run
    from workbench.campaign import CampaignError, run_campaign
    from workbench.precision import Recommendation, accuracy, recommend
    from workbench.run import prepare, simulate
    from workbench.scene import Scene, SceneError, load_scene, scene_from_toml
    from workbench.solver import SolverError, Status
    from workbench.verification import verify

__all__ = [
    "FORMAT_VERSION",
    "CampaignError",
    "ModelWarning",
    "Recommendation",
    "Scene",
    "SceneError",
    "SolverError",
    "Status",
    "WorkbenchError",
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

# Where each public name lives: ``import workbench`` imports none of them (numba, xarray, dask,
# matplotlib load with the first name used), so that the command line starts at once.
_HOMES = {
    "ModelWarning": "workbench._errors",
    "WorkbenchError": "workbench._errors",
    "open_run": "workbench.archive",
    "save_run": "workbench.archive",
    "CampaignError": "workbench.campaign",
    "run_campaign": "workbench.campaign",
    "Recommendation": "workbench.precision",
    "accuracy": "workbench.precision",
    "recommend": "workbench.precision",
    "prepare": "workbench.run",
    "simulate": "workbench.run",
    "Scene": "workbench.scene",
    "SceneError": "workbench.scene",
    "load_scene": "workbench.scene",
    "scene_from_toml": "workbench.scene",
    "SolverError": "workbench.solver",
    "Status": "workbench.solver",
    "verify": "workbench.verification",
}
#: the subpackages, imported on first use too (``workbench.campaign.summary`` after ``import
#: workbench``)
_LAZY_MODULES = (
    "analysis",
    "archive",
    "campaign",
    "continuation",
    "models",
    "plot",
    "precision",
    "run",
    "scene",
    "solver",
    "study",
    "verification",
)


def __getattr__(name: str):
    """The public names, imported on first use (subpackages and functions alike)."""
    import importlib

    if name in _LAZY_MODULES:
        return importlib.import_module(f"workbench.{name}")
    if name in _HOMES:
        value = getattr(importlib.import_module(_HOMES[name]), name)
        globals()[name] = value  # later look-ups skip this function
        return value
    raise AttributeError(f"module 'workbench' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
