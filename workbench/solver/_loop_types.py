"""The compiled loop's vocabulary: method ids, return codes, the layout of its statistics and
controller arrays, and the few grouped arguments its functions take.

The loop's functions (:mod:`workbench.solver._templates.integration_loop`, specialised per
model) take their inputs
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
RADAU5 = 3
AUTO = 4  # DOP853 and RADAU5, switched on measured stiffness

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

# Indices of the implicit method's float64 controller array (Implicit.rc): the step size of the
# current LU factors (0: none), flags "J belongs to the current discrete state" and "J was
# evaluated at the current point", the Newton iteration's contraction (faccon) and convergence
# rate (theta) of the last step, the predictive controller's last accepted step and error
# (0: none), the last accepted implicit step (0: no collocation polynomial to extrapolate), the
# spectral radius of J (1/s); for the automatic method: the method in use, the simulated time
# integrated implicitly (s), the average costs per step of either method (evaluations), and
# the counters of the stiffness tests; the bound on the step from the last Newton failure; the
# last stiffness estimate |h lambda| of the explicit method, the positive stiffness tests
# needed to switch to the implicit method, and the steps of the current implicit phase.
RC_H_LU = 0
RC_JAC = 1
RC_JAC_FRESH = 2
RC_FACCON = 3
RC_THETA = 4
RC_H_ACC = 5
RC_ERR_ACC = 6
RC_H_OLD = 7
RC_RHO = 8
RC_CURRENT = 9
RC_TIME_IMPLICIT = 10
RC_COST_EXPLICIT = 11
RC_COST_IMPLICIT = 12
RC_STIFF_HITS = 13
RC_NONSTIFF_RUN = 14
RC_EXPLICIT_OK = 15
RC_H_FAIL = 16
RC_H_LAMBDA = 17
RC_HITS_NEEDED = 18
RC_PHASE_STEPS = 19
N_RC = 20

# Indices of the implicit method's int64 statistics (Implicit.stats).
IS_JAC = 0  # Jacobian evaluations
IS_LU = 1  # LU decompositions (each a real and a complex one)
IS_NEWTON = 2  # Newton iterations
IS_NEWTON_FAIL = 3  # steps retried because the Newton iteration did not converge
IS_STEPS = 4  # accepted implicit steps
IS_REJECTED = 5  # rejected implicit steps (Newton failures included)
IS_RHS = 6  # evaluations by the implicit method (its finite-difference Jacobians' included)
IS_TO_IMPLICIT = 7  # switches of the automatic method to the implicit one
IS_TO_EXPLICIT = 8  # and back
N_IS = 9


class Settings(NamedTuple):
    """What the run asks for (constant during a run)."""

    method: int  # one of the method ids above
    rtol: float
    atol: np.ndarray  # per state, state units
    max_step: float  # s
    max_steps: int  # accepted steps
    t_rec: np.ndarray  # record times, s, ascending
    blocks: np.ndarray  # int64 boundaries of the error norm's blocks (Problem.error_blocks)


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
    step's end, stage and interpolated states, event functions there, stiff decay rates; the
    event functions' rates (1/s times their units) at the step's start and end, and where in
    the step each one's monitored extremum lies (-1: none to check)."""

    K: np.ndarray
    F: np.ndarray
    y_new: np.ndarray
    ytmp: np.ndarray
    yint: np.ndarray
    g_new: np.ndarray
    gtmp: np.ndarray
    decay_new: np.ndarray
    dg_old: np.ndarray
    dg_new: np.ndarray
    x_ext: np.ndarray


class Implicit(NamedTuple):
    """The implicit method's tolerances, Jacobian, LU factors, controller and statistics (kept
    across calls of ``advance``), and its scratch arrays. None for a run of an explicit
    method: the loop is then compiled without the implicit method."""

    rtol: float  # the run's tolerances (see workbench.solver._radau)
    atol: np.ndarray
    jac_scale: np.ndarray  # state scales: finite-difference steps, stiffness norms
    blocks: np.ndarray  # int64 boundaries of the error norm's blocks (Problem.error_blocks)
    J: np.ndarray
    LUr: np.ndarray
    pivr: np.ndarray
    LUc: np.ndarray
    pivc: np.ndarray
    Q: np.ndarray  # collocation polynomial of the last accepted implicit step (3, n)
    rc: np.ndarray  # controller, RC_* above
    stats: np.ndarray  # IS_* above
    Z: np.ndarray  # scratch: stage increments, transformed ones, Newton step, stage rates
    W: np.ndarray
    dW: np.ndarray
    Fs: np.ndarray
    br: np.ndarray
    bc: np.ndarray
    ez: np.ndarray
    e: np.ndarray
    scale: np.ndarray
    f_new: np.ndarray
    v: np.ndarray
    u: np.ndarray


def implicit_of(problem, rtol: float, atol: np.ndarray, jac_scale: np.ndarray, method: int):
    """A fresh :class:`Implicit` for ``problem``; ``method`` RADAU5 or AUTO (which starts with
    DOP853)."""
    n = problem.y0.size
    rc = np.zeros(N_RC)
    rc[RC_FACCON] = 1.0
    rc[RC_CURRENT] = RADAU5 if method == RADAU5 else DOP853
    return Implicit(
        rtol=float(rtol),
        atol=np.ascontiguousarray(atol, dtype=np.float64),
        jac_scale=np.ascontiguousarray(jac_scale, dtype=np.float64),
        blocks=problem.error_blocks,
        J=np.zeros((n, n)),
        LUr=np.zeros((n, n)),
        pivr=np.zeros(n, np.int64),
        LUc=np.zeros((n, n), np.complex128),
        pivc=np.zeros(n, np.int64),
        Q=np.zeros((3, n)),
        rc=rc,
        stats=np.zeros(N_IS, np.int64),
        Z=np.zeros((3, n)),
        W=np.zeros((3, n)),
        dW=np.zeros((3, n)),
        Fs=np.zeros((3, n)),
        br=np.zeros(n),
        bc=np.zeros(n, np.complex128),
        ez=np.zeros(n),
        e=np.zeros(n),
        scale=np.zeros(n),
        f_new=np.zeros(n),
        v=np.zeros(n),
        u=np.zeros(n),
    )


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
