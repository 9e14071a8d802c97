"""What a model declares: its parameters, effects, state, outputs and compiled hooks.

A model is a small object (one per system) that the scene validates against and that builds the
solver's :class:`~workbench.solver.Problem` for a run. Everything it can put in a dataset is
declared once as a :class:`Quantity` with units and a description, so that what comes out is
self-described. The guide to writing one: :mod:`workbench.models` and ``docs/own-models.md``.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

# The solver's protocol, which models build: re-exported so that a model module imports its
# vocabulary from one place.
from workbench.solver import EVENT_INSIDE_STEP, Problem

__all__ = ["EVENT_INSIDE_STEP", "Effect", "Model", "Parameter", "Problem", "Quantity"]

_PLUGINS = ("overview_figure", "verification")  # the plug-ins named "module:function"


@dataclass(frozen=True)
class Quantity:
    """A state or output variable: name, UDUNITS units, long name, extra dims beyond ``time``,
    and optionally the name of the variable that holds its rate of change (``rate``, e.g.
    ``"v"`` for a displacement ``x``): phase portraits and Poincaré sections pair the two, and
    the dataset says so in the variable's attribute ``rate_variable``."""

    name: str
    units: str
    long_name: str
    dims: tuple[str, ...] = ()
    rate: str | None = None


@dataclass(frozen=True)
class Parameter:
    """A scalar model parameter in SI units with its default and its allowed interval."""

    name: str
    default: float
    units: str
    long_name: str
    lower: float = -math.inf
    upper: float = math.inf
    lower_open: bool = False
    upper_open: bool = False

    def check(self, value: float) -> str | None:
        """None if ``value`` is allowed, else a sentence saying what is allowed."""
        if not math.isfinite(value):
            return "must be a finite number"
        lo_bad = value <= self.lower if self.lower_open else value < self.lower
        hi_bad = value >= self.upper if self.upper_open else value > self.upper
        if lo_bad or hi_bad:
            lo = "(" if self.lower_open else "["
            hi = ")" if self.upper_open else "]"
            unit = "" if self.units == "1" else f" {self.units}"  # a pure number: no unit
            return f"must lie in {lo}{self.lower:g}, {self.upper:g}{hi}{unit}".rstrip()
        return None


@dataclass(frozen=True)
class Effect:
    """A switchable effect of a model.

    ``kind`` is ``"choice"`` (one of ``allowed``), ``"subset"`` (a list of distinct members of
    ``allowed``) or ``"bool"``.
    """

    name: str
    default: Any
    kind: str
    description: str
    allowed: tuple = ()


class Model:
    """Base class of a model. Subclasses set the class attributes and override the methods.

    Adding a model means writing one subclass and its compiled hooks, and registering it with
    :func:`workbench.models.register`; the solver is never touched. A system whose state,
    parameters and events are fixed needs no method at all: the default :meth:`problem` passes
    the parameters to the hooks in their declared order (``p[k]`` is the k-th of
    :attr:`parameters`), starts from :attr:`initial_values` overridden by the scene's
    ``[initial]``, and takes the hooks from :attr:`hooks` (default: the module that defines the
    class); :attr:`forcing_frequency` names the parameter of a periodic forcing. Its plug-ins
    (:attr:`overview_figure`, :attr:`verification`, :attr:`compile_stand_in`) are what the
    figures, the exudyn verification and the compile notice use for it.
    """

    name: ClassVar[str]
    description: ClassVar[str] = ""
    reference: ClassVar[str] = ""
    parameters: ClassVar[tuple[Parameter, ...]] = ()
    effects: ClassVar[tuple[Effect, ...]] = ()
    #: the state and the outputs of a model whose variables do not depend on its effects (a
    #: model whose do overrides :meth:`states` and :meth:`outputs` instead)
    fixed_states: ClassVar[tuple[Quantity, ...] | None] = None
    fixed_outputs: ClassVar[tuple[Quantity, ...]] = ()
    #: module defining the compiled hooks ``rhs``, ``event_values``, ``apply_event`` (and
    #: optionally ``jacobian``); None: the module that defines the model's class
    hooks: ClassVar[str | None] = None
    #: initial value of each state (state units) unless the scene's ``[initial]`` gives one;
    #: a state not named here starts at 0
    initial_values: ClassVar[Mapping[str, float]] = {}
    #: per event function: +1 fires on a rising zero, -1 on a falling one, 0 on both
    event_directions: ClassVar[tuple[int, ...]] = ()
    #: per event function: whether it is a switching surface (the vector field or the state
    #: changes across it, so its grazings are bifurcations) or, False, a locator or a time
    #: event (:attr:`workbench.solver.Problem.event_surface`); empty: all are surfaces
    event_surfaces: ClassVar[tuple[bool, ...]] = ()
    #: initial discrete state ``aux`` (changed only by ``apply_event``; recorded with the run)
    initial_aux: ClassVar[tuple[float, ...]] = ()
    #: units of the event functions' values and of the discrete state (``units`` attributes of
    #: outputs that report them, e.g. a periodic orbit's smallest event value)
    event_units: ClassVar[str] = "1"
    discrete_state_units: ClassVar[str] = "1"
    #: name of the parameter that is the angular frequency (rad s-1) of a periodic forcing:
    #: the forcing period is 2 pi / that value; None for an autonomous system
    forcing_frequency: ClassVar[str | None] = None

    # -- plug-ins: what the layers above the models use, named "module:function" and imported
    # only by them (:meth:`plugin`), so that importing a model imports neither matplotlib nor
    # exudyn, and no module of the models imports a layer above it
    #: the overview figure of a run, ``f(ds: xarray.Dataset) -> matplotlib.figure.Figure``,
    #: which :func:`workbench.plot.run_figures` draws beside the time series; None: no overview
    overview_figure: ClassVar[str | None] = None
    #: the model as the exudyn multibody engine rebuilds it, ``f(scene) ->
    #: workbench.verification._mechanisms.Mechanism`` (:func:`workbench.verification.verify`);
    #: None: not verifiable
    verification: ClassVar[str | None] = None
    #: the model whose measured first compile (``workbench/campaign/compile_times.json``) the
    #: notice before a first compile quotes while this model has no record of its own: one of
    #: a kernel of about this model's size (default Duffing's, the smallest kernel measured)
    compile_stand_in: ClassVar[str] = "duffing"

    # -- declarations -------------------------------------------------------------------------
    def plugin(self, kind: str) -> Callable | None:
        """The plug-in function ``kind`` (``"overview_figure"`` or ``"verification"``), imported
        from the module its dotted name ``"module:function"`` names; None when the model
        declares none.

        >>> from workbench.models import get_model
        >>> get_model("lorenz").plugin("overview_figure") is None
        True
        """
        if kind not in _PLUGINS:
            raise ValueError(f"plug-in {kind!r} is not one of {', '.join(_PLUGINS)}")
        dotted = getattr(self, kind)
        if dotted is None:
            return None
        module, _, name = dotted.partition(":")
        return getattr(importlib.import_module(module), name)

    def parameter(self, name: str) -> Parameter:
        """The declared parameter ``name``."""
        for p in self.parameters:
            if p.name == name:
                return p
        raise KeyError(name)

    def default_parameters(self) -> dict[str, float]:
        """Each parameter's default value, by name."""
        return {p.name: float(p.default) for p in self.parameters}

    def default_effects(self) -> dict[str, Any]:
        """Each effect's default setting, by name."""
        return {e.name: e.default for e in self.effects}

    def states(self, effects: Mapping[str, Any]) -> tuple[Quantity, ...]:
        """The integrated state for these effects (:attr:`fixed_states` unless overridden)."""
        if self.fixed_states is None:
            raise NotImplementedError
        return self.fixed_states

    def outputs(self, effects: Mapping[str, Any]) -> tuple[Quantity, ...]:
        """Derived output variables available for these effects (besides the states;
        :attr:`fixed_outputs` unless overridden)."""
        return self.fixed_outputs

    def coords(self, effects: Mapping[str, Any]) -> dict[str, tuple[list, dict]]:
        """Coordinates of the model's extra dims: name -> (values, attrs)."""
        return {}

    def variables(self, effects: Mapping[str, Any]) -> dict[str, Quantity]:
        """Every variable a run can store, states first."""
        out = {q.name: q for q in self.states(effects)}
        out.update({q.name: q for q in self.outputs(effects)})
        return out

    def recorded_always(self, effects: Mapping[str, Any]) -> tuple[str, ...]:
        """Output variables every run with these effects records, whatever the scene lists
        (diagnostics of a law that can leave its physics); none by default."""
        return ()

    def diagnose(self, ds, params: Mapping[str, float]) -> list[str]:
        """Warnings about a run's dataset ``ds`` (one sentence each; none by default)."""
        return []

    def summary(self, ds, params: Mapping[str, float]) -> str:
        """What the run's summary line adds for this model ('' by default; else starting with
        '; ')."""
        return ""

    def forcing_period(self, params: Mapping[str, float]) -> float | None:
        """Period of the external forcing, s; None for an autonomous system (default: 2 pi /
        the parameter :attr:`forcing_frequency`, if the model names one)."""
        if self.forcing_frequency is None:
            return None
        return 2.0 * math.pi / params[self.forcing_frequency]

    def validate(self, params: Mapping[str, float], effects: Mapping[str, Any]) -> None:
        """Cross-field checks; raise :class:`workbench.SceneError` naming the key."""

    # -- building and post-processing ------------------------------------------------------------
    def problem(
        self,
        params: Mapping[str, float],
        effects: Mapping[str, Any],
        initial: Mapping[str, float],
        requested: tuple[str, ...],
    ) -> Problem:
        """The compiled problem for one run.

        The default serves a model with fixed states (:attr:`fixed_states`): the hooks of
        :attr:`hooks`, ``p`` = the parameters in their declared order, ``y0`` from
        :attr:`initial_values` and ``initial``, :attr:`event_directions`,
        :attr:`event_surfaces` and :attr:`initial_aux`. Override it to pass other arrays
        (integer parameters ``ip``, a scratch array ``work``, per-state tolerance scales
        ``atol_scale``, model failure messages), or a state that depends on the effects.
        """
        hooks = self.hooks or type(self).__module__
        if hooks == "__main__":
            raise TypeError(
                f"model {self.name!r} is defined in __main__ (a script run directly or a "
                "notebook): its compiled hooks must live in an importable module, which the "
                "generated kernel imports by name; put the model in a file (e.g. "
                f"{self.name}_model.py) beside the script and import it"
            )
        states = self.states(effects)
        y0 = [float(initial.get(q.name, self.initial_values.get(q.name, 0.0))) for q in states]
        return Problem(
            hooks=hooks,
            states=states,
            y0=np.array(y0),
            p=np.array([float(params[p.name]) for p in self.parameters]),
            aux0=np.array(self.initial_aux, dtype=np.float64),
            event_direction=np.array(self.event_directions, dtype=np.int64),
            event_surface=np.array(self.event_surfaces, dtype=bool)
            if self.event_surfaces
            else None,
        )

    def derive(
        self,
        problem: Problem,
        t: np.ndarray,
        Y: np.ndarray,
        AUX: np.ndarray,
        requested: tuple[str, ...],
    ) -> dict[str, np.ndarray]:
        """Derived outputs at the record times (arrays with dims ``time`` + the quantity's)."""
        return {}

    def initial_state(self, problem_states, defaults: Mapping[str, float], initial) -> np.ndarray:
        """Helper: the initial state vector from defaults overridden by the scene's [initial]."""
        return np.array([float(initial.get(q.name, defaults[q.name])) for q in problem_states])
