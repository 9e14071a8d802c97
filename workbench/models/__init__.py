"""Models: the systems a scene can simulate, looked up by name, and how to write your own.

>>> from workbench.models import get_model
>>> get_model("lorenz").parameter("rho").default
28.0

A model is a module with compiled hooks and a registered :class:`Model` subclass that declares
the parameters (:class:`Parameter`, SI units), the state and outputs (:class:`Quantity`) and,
when the defaults do not fit, builds the solver's :class:`Problem`. Everything it needs is
public: ``from workbench.models import Model, Parameter, Quantity, register`` (and
``Problem``, ``Effect``, ``EVENT_INSIDE_STEP``), with :mod:`workbench.models.no_events` for a
system without events. The guide with worked examples (Rössler with its Lyapunov spectrum, a
bouncing ball with events): ``docs/own-models.md``.

The built-in models are found, not listed: every public module or package of this package is
the model of its name (but the libraries :mod:`.contact`, :mod:`.friction` and
:mod:`.no_events`), imported on first use. A model names what the layers above it use for it
(:attr:`Model.overview_figure`, :attr:`Model.verification`, :attr:`Model.compile_stand_in`),
which those layers import (:meth:`Model.plugin`).

The hooks, in the model's module, compiled with ``numba.njit(cache=True)``; the integration
loop imports them by name from the module (``Model.hooks``, default the class's module):

``rhs(t, y, p, ip, aux, work, dydt) -> int``
    Write dy/dt into ``dydt``; return 0, or a positive model failure code (the step is
    retried smaller; if it persists the run fails with ``Status.MODEL_FAILURE``).
``event_values(t, y, p, ip, aux, work, g) -> None``
    Write the event functions g_k; event k fires where g_k crosses zero in the direction of
    ``Model.event_directions[k]``.
``apply_event(k, t, y, p, ip, aux, work) -> int``
    Apply event k in place (``y``, ``aux``); return 1 to stop the run (status ``terminated``),
    else 0.
``jacobian(t, y, p, ip, aux, work, J) -> int`` (optional)
    Write dF/dy into the n x n array ``J``; without it, central differences of ``rhs``.

``t`` is the time (s), ``y`` the state (state units), ``p`` the float parameters (by default
the declared parameters in order), ``ip`` integer parameters, ``aux`` the discrete state
(changed only by events), ``work`` a scratch array of ``Problem.work_size`` floats.
"""

from __future__ import annotations

import functools
import importlib
import pkgutil

from workbench.models._base import EVENT_INSIDE_STEP, Effect, Model, Parameter, Problem, Quantity

__all__ = [
    "EVENT_INSIDE_STEP",
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
#: the models of declared mechanisms by name, made from a scene's data, not defined by modules
#: (:func:`workbench.models._declared_model.declared_model` adds them)
_DECLARED: dict[str, type[Model]] = {}
# The public modules of this package that are libraries for models, not models: every other
# public module or package of workbench.models is the built-in model of its name.
_LIBRARIES = frozenset({"contact", "friction", "no_events"})


@functools.cache
def _builtin() -> dict[str, str]:
    """The built-in models by name and the module that defines (and registers) each: the public
    modules and packages of this package (listed from its own folder, never imported here),
    so that a run loads (and numba compiles) only the model it needs."""
    return {
        m.name: f"{__name__}.{m.name}"
        for m in pkgutil.iter_modules(__path__)
        if not m.name.startswith("_") and m.name not in _LIBRARIES
    }


def register(cls: type[Model]) -> type[Model]:
    """Class decorator: make a model available to scenes under ``cls.name`` (a name of a
    built-in model is refused for any other class; registering a name again replaces it)."""
    builtin = _builtin().get(cls.name)
    if builtin is not None and not (cls.__module__ + ".").startswith(builtin + "."):
        raise ValueError(
            f"model name {cls.name!r} is taken by the built-in model of {builtin}; choose "
            f"another name (built-in: {', '.join(sorted(_builtin()))})"
        )
    _REGISTRY[cls.name] = cls
    return cls


def available_models() -> tuple[str, ...]:
    """Names of the registered and built-in models."""
    return tuple(sorted(set(_REGISTRY) | set(_builtin()) | set(_DECLARED)))


def get_model(name: str) -> Model:
    """An instance of the model registered as ``name`` (KeyError if unknown)."""
    if name in _DECLARED:
        return _DECLARED[name]()
    if name not in _REGISTRY and name in _builtin():
        importlib.import_module(_builtin()[name])
    return _REGISTRY[name]()


def joint_stiffness(params, clearance: float) -> float:
    """Contact stiffness K (N m^-n) of a revolute clearance joint with this radial clearance
    (m): the scene's ``contact_stiffness``, or Hertz's for the journal in its bearing (Eq. 4 of
    Chen et al. 2019)."""
    from workbench.models._clearance import stiffness

    return stiffness(params, clearance)
