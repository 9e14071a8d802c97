"""Models: the systems a scene can simulate, looked up by name.

>>> from workbench.models import get_model
>>> get_model("lorenz").parameter("rho").default
28.0
"""

from __future__ import annotations

from workbench.models._base import Effect, Model, Parameter, Problem, Quantity

__all__ = [
    "Effect",
    "Model",
    "Parameter",
    "Problem",
    "Quantity",
    "available_models",
    "get_model",
    "register",
]

_REGISTRY: dict[str, type[Model]] = {}


def register(cls: type[Model]) -> type[Model]:
    """Class decorator: make a model available to scenes under ``cls.name``."""
    _REGISTRY[cls.name] = cls
    return cls


def available_models() -> tuple[str, ...]:
    _load_builtin()
    return tuple(sorted(_REGISTRY))


def get_model(name: str) -> Model:
    """An instance of the model registered as ``name`` (KeyError if unknown)."""
    _load_builtin()
    return _REGISTRY[name]()


def _load_builtin() -> None:
    from workbench.models import (  # noqa: F401
        bouncing_ball,
        duffing,
        free_journal,
        lorenz,
        ninebar,
        slider_crank,
    )
