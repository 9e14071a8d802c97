"""What a model declares: its parameters, effects, state, outputs and compiled hooks.

A model is a small object (one per system) that the scene validates against and that builds the
solver's :class:`~workbench.solver.Problem` for a run. Everything it can put in a dataset is
declared once as a :class:`Quantity` with units and a description, so that what comes out is
self-described.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

# The solver's protocol, which models build: re-exported so that a model module imports its
# vocabulary from one place.
from workbench.solver import EVENT_INSIDE_STEP, Problem

__all__ = ["EVENT_INSIDE_STEP", "Effect", "Model", "Parameter", "Problem", "Quantity"]


@dataclass(frozen=True)
class Quantity:
    """A state or output variable: name, UDUNITS units, long name, extra dims beyond ``time``."""

    name: str
    units: str
    long_name: str
    dims: tuple[str, ...] = ()


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
            return f"must lie in {lo}{self.lower:g}, {self.upper:g}{hi} {self.units}".rstrip()
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
    :func:`workbench.models.register`; the solver is never touched.
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

    # -- declarations -------------------------------------------------------------------------
    def parameter(self, name: str) -> Parameter:
        """The declared parameter ``name``."""
        for p in self.parameters:
            if p.name == name:
                return p
        raise KeyError(name)

    def default_parameters(self) -> dict[str, float]:
        return {p.name: float(p.default) for p in self.parameters}

    def default_effects(self) -> dict[str, Any]:
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
        """Period of the external forcing, s; None for an autonomous system."""
        return None

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
        """The compiled problem for one run."""
        raise NotImplementedError

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
