"""The compiled loop's vocabulary: method ids, return codes, the layout of its statistics and
controller arrays, and the few grouped arguments its functions take.

The loop's functions (:mod:`workbench.solver._kernel`, specialised per model) take their inputs
in three named tuples instead of twenty positional arguments: :class:`Settings` (what the run
asks for), :class:`Hooks` (the arrays the model's hooks receive besides time, state and discrete
state) and :class:`State` (everything that a call of ``advance`` continues from and leaves for
the next, so that a run split into pauses is bit-identical to an unbroken one). Numba compiles
named tuples of arrays as plain structs (no boxing in the loop) and caches functions that take
them; :func:`allocate` builds them for :func:`workbench.solver.integrate`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

# Method ids (the scene's names are in workbench.solver._integrate).
DOPRI5 = 0
DOP853 = 1
ARK548 = 2

# Return codes of `advance`.
DONE = 0
PAUSED = 1
TERMINATED = 2
STEP_UNDERFLOW = -1
NON_FINITE = -2
MAX_STEPS = -3
MODEL_FAILURE = -4

# Indices of the int64 statistics array.
ST_STEPS = 0
ST_REJECTED = 1
ST_RHS = 2  # every evaluation of rhs, those of finite-difference Jacobians included
ST_EVENTS = 3
ST_RECORDED = 4
ST_MODEL_CODE = 5
ST_EVENT_RETRIES = 6  # steps retried because an event happened between their ends
N_STATS = 7

# Indices of the float64 controller array: current time (s), next step size (s), flag "last
# failure was non-finite", flag "the current derivative f was flagged EVENT_INSIDE_STEP"; then
# one entry per stiff state: its decay rate a_k (s-1) at the current point.
CT_T = 0
CT_H = 1
CT_NONFINITE = 2
CT_F_INSIDE = 3
N_CTRL = 4


class Settings(NamedTuple):
    """What the run asks for (constant during a run)."""

    method: int  # one of the method ids above
    rtol: float
    atol: np.ndarray  # per state, state units
    max_step: float  # s
    max_steps: int  # accepted steps
    t_rec: np.ndarray  # record times, s, ascending


class Hooks(NamedTuple):
    """The model's arrays that every hook call receives, and its event and stiff-state
    declarations (see :class:`workbench.solver.Problem`)."""

    p: np.ndarray
    ip: np.ndarray
    work: np.ndarray
    ev_dir: np.ndarray
    stiff_idx: np.ndarray
    stiff_slot: np.ndarray
    implicit_slot: int


class State(NamedTuple):
    """What the loop continues from: state, derivative, discrete state, event functions at the
    current point, controller and statistics arrays, and the records written so far."""

    y: np.ndarray
    f: np.ndarray
    aux: np.ndarray
    g_old: np.ndarray
    ctrl: np.ndarray
    stats: np.ndarray
    Yrec: np.ndarray
    AUXrec: np.ndarray


class Scratch(NamedTuple):
    """Scratch arrays of one call of ``advance``: stages, dense-output coefficients, the trial
    step's end, stage and interpolated states, event functions there, stiff decay rates."""

    K: np.ndarray
    F: np.ndarray
    y_new: np.ndarray
    ytmp: np.ndarray
    yint: np.ndarray
    g_new: np.ndarray
    gtmp: np.ndarray
    decay_new: np.ndarray


def allocate(problem, n_rec: int) -> State:
    """A fresh :class:`State` for ``problem`` (a :class:`workbench.solver.Problem`) with room
    for ``n_rec`` records (NaN until written)."""
    n, na, ne = problem.y0.size, problem.aux0.size, problem.event_direction.size
    return State(
        y=problem.y0.copy(),
        f=np.empty(n),
        aux=problem.aux0.copy(),
        g_old=np.empty(ne),
        ctrl=np.zeros(N_CTRL + problem.stiff_states.size),
        stats=np.zeros(N_STATS, np.int64),
        Yrec=np.full((n_rec, n), np.nan),
        AUXrec=np.full((n_rec, na), np.nan),
    )


def hooks_of(problem) -> Hooks:
    """The :class:`Hooks` of ``problem``, with a fresh scratch ``work`` array."""
    return Hooks(
        p=problem.p,
        ip=problem.ip,
        work=np.zeros(max(problem.work_size, 1)),
        ev_dir=problem.event_direction,
        stiff_idx=problem.stiff_states,
        stiff_slot=problem.stiff_slots,
        implicit_slot=int(problem.implicit_slot),
    )
