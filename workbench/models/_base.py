"""What a model declares: its parameters, effects, state, outputs and compiled hooks.

A model is a small object (one per system) that the scene validates against and the solver
integrates. Everything it can put in a dataset is declared once as a :class:`Quantity` with
units and a description, so that what comes out is self-described.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

__all__ = ["Effect", "Model", "Parameter", "Problem", "Quantity"]


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


# Hook protocol: besides 0 (fine) and positive model failure codes, ``rhs`` may return
# EVENT_INSIDE_STEP after filling ``dydt`` completely, to say that this (trial) state lies beyond
# an event surface whose event has not fired (e.g. a journal in contact whose onset was not
# located). The compiled loop then keeps the step only if the step's end also lies beyond that
# surface, so that the event is located; otherwise the whole event happened between the step's
# ends, where the sign test on g cannot see it, and the step is retried at half the size.
EVENT_INSIDE_STEP = -1


@dataclass
class Problem:
    """Everything the solver needs for one run of a model (built by :meth:`Model.problem`).

    Attributes
    ----------
    hooks : str
        Module that defines the compiled ``rhs``, ``event_values`` and ``apply_event``.
    states : tuple[Quantity, ...]
        The integrated state, in the order of ``y0``.
    y0 : ndarray
        Initial state (state units).
    p, ip : ndarray
        Float and integer parameter arrays passed to the hooks.
    aux0 : ndarray
        Initial discrete state (changed only by events; recorded with the state).
    event_direction : ndarray of int64
        Per event: +1 fires on a rising zero, -1 on a falling one, 0 on both.
    atol_scale : ndarray
        Per state: the scene's ``atol`` is multiplied by this (a characteristic size of the
        state), so that one number means the same for states of very different magnitude.
    t0 : float
        Initial time, s.
    work_size : int
        Length of the scratch array passed to the hooks (allocated once per run).
    failure : callable
        ``failure(code) -> str``: explains a model failure code returned by ``rhs``.
    stiff_states, stiff_slots, implicit_slot : ndarray of int64, int
        Optional stiff states for the implicit–explicit method ``ark548``: indices k of states
        whose rate is ``r_k(y) - a_k(y) y_k`` with a decay rate ``a_k >= 0`` (s-1) independent
        of every stiff state, the ``work`` slots where ``rhs`` writes ``a_k``, and the slot
        where the solver puts ``h gamma`` (s) for which ``rhs`` replaces ``y[k]`` by
        ``(y[k] + h gamma r_k) / (1 + h gamma a_k)`` (0 outside implicit stages); see
        :mod:`workbench.solver._kernel`.
    data : dict
        Model-private values needed later by :meth:`Model.derive`.
    """

    hooks: str
    states: tuple[Quantity, ...]
    y0: np.ndarray
    p: np.ndarray
    ip: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    aux0: np.ndarray = field(default_factory=lambda: np.zeros(0))
    event_direction: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    atol_scale: np.ndarray | None = None
    t0: float = 0.0
    work_size: int = 0
    failure: Callable[[int], str] = lambda code: f"model failure code {code}"
    data: dict = field(default_factory=dict)
    stiff_states: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    stiff_slots: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    implicit_slot: int = -1

    def __post_init__(self) -> None:
        self.y0 = np.ascontiguousarray(self.y0, dtype=np.float64)
        self.p = np.ascontiguousarray(self.p, dtype=np.float64)
        self.ip = np.ascontiguousarray(self.ip, dtype=np.int64)
        self.aux0 = np.ascontiguousarray(self.aux0, dtype=np.float64)
        self.event_direction = np.ascontiguousarray(self.event_direction, dtype=np.int64)
        if self.atol_scale is None:
            self.atol_scale = np.ones_like(self.y0)
        self.atol_scale = np.ascontiguousarray(self.atol_scale, dtype=np.float64)
        self.stiff_states = np.ascontiguousarray(self.stiff_states, dtype=np.int64)
        self.stiff_slots = np.ascontiguousarray(self.stiff_slots, dtype=np.int64)
        if self.stiff_states.shape != self.stiff_slots.shape or (
            self.stiff_states.size > 0 and not 0 <= self.implicit_slot < self.work_size
        ):
            raise ValueError(
                f"stiff_states {self.stiff_states!r}, stiff_slots {self.stiff_slots!r} and "
                f"implicit_slot {self.implicit_slot!r}: one slot per stiff state, and an "
                f"implicit slot inside work (size {self.work_size!r}) when there are any"
            )


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
        """The integrated state for these effects."""
        raise NotImplementedError

    def outputs(self, effects: Mapping[str, Any]) -> tuple[Quantity, ...]:
        """Derived output variables available for these effects (besides the states)."""
        return ()

    def coords(self, effects: Mapping[str, Any]) -> dict[str, tuple[list, dict]]:
        """Coordinates of the model's extra dims: name -> (values, attrs)."""
        return {}

    def variables(self, effects: Mapping[str, Any]) -> dict[str, Quantity]:
        """Every variable a run can store, states first."""
        out = {q.name: q for q in self.states(effects)}
        out.update({q.name: q for q in self.outputs(effects)})
        return out

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
