"""The solver's protocol: what a model hands the integrators (:class:`Problem`) and the one
return code of its hooks that is not a failure (:data:`EVENT_INSIDE_STEP`).

The solver knows nothing of scenes or models beyond this: a model builds a Problem whose
``hooks`` module defines the compiled ``rhs``, ``event_values`` and ``apply_event`` (their
signatures are in :mod:`workbench.solver._templates.integration_loop`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

__all__ = ["EVENT_INSIDE_STEP", "Named", "Problem"]


class Named(Protocol):
    """Anything with a ``name``: how the solver sees a declared state."""

    name: str


# Hook protocol: besides 0 (fine) and positive model failure codes, ``rhs`` may return
# EVENT_INSIDE_STEP after filling ``dydt`` completely, to say that this (trial) state lies beyond
# an event surface whose event has not fired (e.g. a journal in contact whose onset was not
# located). The compiled loop then keeps the step only if the step's end also lies beyond that
# surface, so that the event is located; otherwise the whole event happened between the step's
# ends, where the sign test on g cannot see it, and the step is retried at half the size.
EVENT_INSIDE_STEP = -1


@dataclass
class Problem:
    """Everything the solver needs for one run of a model (built by a model's ``problem``).

    Attributes
    ----------
    hooks : str
        Module that defines the compiled ``rhs``, ``event_values`` and ``apply_event``.
    states : tuple
        The integrated state, in the order of ``y0``: objects with a ``name`` (models pass their
        :class:`workbench.models.Quantity` declarations); the solver names states by it in its
        failure messages.
    y0 : ndarray
        Initial state (state units).
    p, ip : ndarray
        Float and integer parameter arrays passed to the hooks.
    aux0 : ndarray
        Initial discrete state (changed only by events; recorded with the state).
    event_direction : ndarray of int64
        Per event: +1 fires on a rising zero, -1 on a falling one, 0 on both.
    event_surface : ndarray of bool, optional
        Per event function: whether its zero set is a switching surface, where the vector
        field or the state changes (a contact's onset or end, an impact), so that a local
        extremum of it through zero is a grazing (di Bernardo, Budd, Champneys & Kowalczyk
        2008, Sec. 2.5); False for a locator (an event that only helps locate another, e.g.
        the impact oscillator's turning points) or a time event, whose crossings appear and
        vanish with nothing happening to the orbit. Default: all True. The solver ignores
        it; continuation looks for grazings on the surfaces alone.
    atol_scale : ndarray
        Per state: the scene's ``atol`` is multiplied by this (a characteristic size of the
        state), so that one number means the same for states of very different magnitude.
    aux_scale : ndarray
        Per discrete state that the flow depends on (a contact's held onset velocity): its
        characteristic size (units of the discrete state), in which tangent vectors measure
        their discrete-state components; inf (the default) for a discrete state the flow does
        not depend on (a counter, the time of the last event), left out of their size.
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
        :mod:`workbench.solver._templates.integration_loop`.
    error_blocks : ndarray of int64, optional
        Boundaries ``0 = b_0 < b_1 < ... < b_k = n`` of the blocks of the state whose scaled
        RMS error each step must keep below 1: the step's error is the largest block's
        (default one block, the whole state; ``[0]``, no block, where n = 0). A derived
        system whose extra states must not dilute the error of the original ones (tangent
        vectors beside the state) gives each its own block, as CVODES does for sensitivities
        (Serban & Hindmarsh 2005).
    data : dict
        Model-private values needed later by the model's ``derive`` (the solver ignores them).
    """

    hooks: str
    states: tuple[Named, ...]
    y0: np.ndarray
    p: np.ndarray
    ip: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    aux0: np.ndarray = field(default_factory=lambda: np.zeros(0))
    event_direction: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    event_surface: np.ndarray | None = None
    atol_scale: np.ndarray | None = None
    aux_scale: np.ndarray | None = None
    t0: float = 0.0
    work_size: int = 0
    failure: Callable[[int], str] = lambda code: f"model failure code {code}"
    data: dict = field(default_factory=dict)
    stiff_states: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    stiff_slots: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    implicit_slot: int = -1
    error_blocks: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.y0 = np.ascontiguousarray(self.y0, dtype=np.float64)
        self.p = np.ascontiguousarray(self.p, dtype=np.float64)
        self.ip = np.ascontiguousarray(self.ip, dtype=np.int64)
        self.aux0 = np.ascontiguousarray(self.aux0, dtype=np.float64)
        self.event_direction = np.ascontiguousarray(self.event_direction, dtype=np.int64)
        if self.event_surface is None:
            self.event_surface = np.ones(self.event_direction.shape, dtype=bool)
        self.event_surface = np.ascontiguousarray(self.event_surface, dtype=bool)
        if self.event_surface.shape != self.event_direction.shape:
            raise ValueError(
                f"event_surface {self.event_surface!r}: one flag per event function "
                f"({self.event_direction.size}, as event_direction)"
            )
        if self.atol_scale is None:
            self.atol_scale = np.ones_like(self.y0)
        self.atol_scale = np.ascontiguousarray(self.atol_scale, dtype=np.float64)
        if self.aux_scale is None:
            self.aux_scale = np.full(self.aux0.shape, np.inf)
        self.aux_scale = np.ascontiguousarray(self.aux_scale, dtype=np.float64)
        n = self.y0.size
        if self.error_blocks is None:  # one block; none for a problem without states
            self.error_blocks = np.array([0, n] if n else [0], dtype=np.int64)
        self.error_blocks = np.ascontiguousarray(self.error_blocks, dtype=np.int64)
        b = self.error_blocks
        if b.ndim != 1 or b.size < 1 or b[0] != 0 or b[-1] != n or np.any(np.diff(b) <= 0):
            raise ValueError(
                f"error_blocks {b!r}: must rise strictly from 0 to the state's size {n}"
            )
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

    def state_dict(self, y: np.ndarray) -> dict[str, float]:
        """State name -> value of a state vector (state units)."""
        return {q.name: float(v) for q, v in zip(self.states, y, strict=True)}
