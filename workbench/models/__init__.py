"""Models: the systems a scene can simulate, looked up by name.

>>> from workbench.models import get_model
>>> get_model("lorenz").parameter("rho").default
28.0
"""

from __future__ import annotations

import importlib

from workbench.models._base import Effect, Model, Parameter, Problem, Quantity

__all__ = [
    "Effect",
    "Model",
    "Parameter",
    "Problem",
    "Quantity",
    "available_models",
    "get_model",
    "joint_stiffness",
    "register",
]

_REGISTRY: dict[str, type[Model]] = {}
# The built-in models by name and the module that defines (and registers) each: imported on
# first use, so that a run loads (and numba compiles) only the model it needs.
_BUILTIN = {
    "bouncing_ball": "workbench.models.bouncing_ball",
    "duffing": "workbench.models.duffing",
    "free_journal": "workbench.models.free_journal",
    "lorenz": "workbench.models.lorenz",
    "ninebar": "workbench.models.ninebar",
    "slider_crank": "workbench.models.slider_crank",
    "stop_oscillator": "workbench.models.stop_oscillator",
}


def register(cls: type[Model]) -> type[Model]:
    """Class decorator: make a model available to scenes under ``cls.name``."""
    _REGISTRY[cls.name] = cls
    return cls


def available_models() -> tuple[str, ...]:
    """Names of the registered and built-in models."""
    return tuple(sorted(set(_REGISTRY) | set(_BUILTIN)))


def get_model(name: str) -> Model:
    """An instance of the model registered as ``name`` (KeyError if unknown)."""
    if name not in _REGISTRY and name in _BUILTIN:
        importlib.import_module(_BUILTIN[name])
    return _REGISTRY[name]()


def joint_stiffness(params, clearance: float) -> float:
    """Contact stiffness K (N m^-n) of a revolute clearance joint with this radial clearance
    (m): the scene's ``contact_stiffness``, or Hertz's for the journal in its bearing (Eq. 4 of
    Chen et al. 2019)."""
    from workbench.models._clearance import stiffness

    return stiffness(params, clearance)
