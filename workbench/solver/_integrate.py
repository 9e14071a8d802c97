"""``integrate``: a :class:`Problem` and record times -> a :class:`RunResult` with its status."""

from __future__ import annotations

import math
import time as _time
from collections.abc import Callable

import numpy as np

from workbench.solver import _scipy_backend
from workbench.solver._compile import kernel_for
from workbench.solver._loop_types import (
    ARK548,
    AUTO,
    CT_F_INSIDE,
    CT_H,
    CT_T,
    DONE,
    DOP853,
    DOPRI5,
    IS_JAC,
    IS_LU,
    IS_NEWTON,
    IS_NEWTON_FAIL,
    IS_RHS,
    IS_STEPS,
    IS_TO_EXPLICIT,
    IS_TO_IMPLICIT,
    MAX_STEPS,
    MODEL_FAILURE,
    NON_FINITE,
    PAUSED,
    RADAU5,
    RC_TIME_IMPLICIT,
    ST_EVENT_RETRIES,
    ST_EVENTS,
    ST_MODEL_CODE,
    ST_RECORDED,
    ST_REJECTED,
    ST_RHS,
    ST_STEPS,
    STEP_UNDERFLOW,
    TERMINATED,
    Settings,
    allocate,
    hooks_of,
    implicit_of,
)
from workbench.solver._problem import EVENT_INSIDE_STEP, Problem
from workbench.solver._result import RunResult, Status, solver_stats
from workbench.solver._tangent import state_scale

__all__ = ["COMPILED_METHODS", "METHODS", "PAUSE_SECONDS", "integrate"]

#: Wall time (s) between two returns of the compiled loop to Python, where signals (Ctrl-C)
#: and the progress callback are seen; the loop's step budget per call is adapted to it.
PAUSE_SECONDS = 0.1
_FIRST_BUDGET = 128  # steps of the first call, before the rate is known

_METHOD_IDS = {"dop853": DOP853, "dopri5": DOPRI5, "ark548": ARK548, "radau": RADAU5, "auto": AUTO}
COMPILED_METHODS = tuple(_METHOD_IDS)
# every method a scene may name
METHODS = COMPILED_METHODS + tuple(f"scipy:{m}" for m in _scipy_backend.METHODS)
_STATUS = {
    DONE: Status.OK,
    TERMINATED: Status.TERMINATED,
    MAX_STEPS: Status.MAX_STEPS,
    STEP_UNDERFLOW: Status.STEP_UNDERFLOW,
    NON_FINITE: Status.NON_FINITE,
    MODEL_FAILURE: Status.MODEL_FAILURE,
}


def integrate(
    problem: Problem,
    t_rec: np.ndarray,
    *,
    method: str = "dop853",
    rtol: float = 1e-8,
    atol: float = 1e-10,
    max_step: float = math.inf,
    max_steps: int = 50_000_000,
    progress: Callable[[float], None] | None = None,
) -> RunResult:
    """Integrate a problem and record its state at ``t_rec``.

    Parameters
    ----------
    problem : Problem
        The compiled right-hand side, its events, initial state and tolerances' scales.
    t_rec : array_like
        Record times, s, ascending, the first at or after ``problem.t0``.
    method : str
        ``"auto"`` (DOP853 and Radau IIA, switched on measured stiffness), ``"dop853"``,
        ``"dopri5"``, ``"ark548"``, ``"radau"`` (compiled) or ``"scipy:<solve_ivp method>"``.
    rtol, atol : float
        Tolerances; ``atol`` is multiplied per state by ``problem.atol_scale``.
    max_step : float
        Largest step, s.
    max_steps : int
        Accepted steps after which the run stops with :attr:`Status.MAX_STEPS`.
    progress : callable, optional
        ``progress(t)`` is called whenever the compiled loop pauses: after each 1 % of the
        simulated time and about every :data:`PAUSE_SECONDS` of wall time.

    Returns
    -------
    RunResult
        Never raises for a failed integration: the result's ``status`` and ``message`` say how
        the run ended (:meth:`RunResult.raise_for_status` turns a failure into a
        :class:`SolverError`).

    Raises
    ------
    ValueError
        For record times before ``t0`` or not finite, or an unknown method.
    KeyboardInterrupt
        On Ctrl-C (or a signal the caller turns into it) within about :data:`PAUSE_SECONDS`:
        the compiled loop returns to Python that often, so Python's signal handlers run.

    Notes
    -----
    The loop pauses (returns to Python and continues where it stopped, bit-identically) after
    a number of steps adapted to take about :data:`PAUSE_SECONDS` of wall time, with or without
    ``progress``: a run of any length stays interruptible, and the pauses cost one comparison
    per step.
    """
    t_rec = np.ascontiguousarray(t_rec, dtype=np.float64)
    if t_rec.size == 0 or not t_rec[0] >= problem.t0:
        raise ValueError(
            f"record times must be non-empty and start at or after t0={problem.t0!r}; got "
            f"{t_rec.size} times from {t_rec[0] if t_rec.size else None!r}"
        )
    if not np.isfinite(t_rec[-1]):
        raise ValueError(
            f"record times must be finite; got {t_rec.size} times from {t_rec[0]!r} to "
            f"{t_rec[-1]!r}"
        )
    atol_arr = atol * problem.atol_scale
    if not np.all(np.isfinite(problem.y0)):
        stats0 = solver_stats(method, rtol, atol, max_step)
        return _refused(problem, t_rec, stats0, "the initial state is not finite")
    if method.startswith("scipy:"):
        why = _scipy_backend.cannot_start(problem, rtol, atol_arr)
        if why:
            return _refused(problem, t_rec, solver_stats(method, rtol, atol, max_step), why)
        result = _scipy_backend.integrate(
            problem, t_rec, method[6:], rtol, atol_arr, max_step, max_steps
        )
        result.stats["atol"] = atol
        return result
    if method not in METHODS:
        raise ValueError(f"method={method!r}; allowed: {', '.join(METHODS)}")
    stats0 = solver_stats(method, rtol, atol, max_step)
    if problem.y0.size == 0:  # nothing to integrate (e.g. a mechanism with ideal joints)
        AUX = np.tile(problem.aux0, (t_rec.size, 1))
        return RunResult(t_rec, np.empty((t_rec.size, 0)), AUX, stats0, time=float(t_rec[-1]))
    k = kernel_for(problem.hooks)
    mid = _METHOD_IDS[method]
    settings = Settings(
        mid, float(rtol), atol_arr, float(max_step), int(max_steps), t_rec, problem.error_blocks
    )
    hooks = hooks_of(problem)
    state = allocate(problem, t_rec.size)
    implicit = _implicit(problem, settings)
    t_end = float(t_rec[-1])
    _compiled(k, problem, settings)
    wall0 = _time.perf_counter()
    code = k.start(problem.t0, hooks, state)
    state.ctrl[CT_F_INSIDE] = 1.0 if code == EVENT_INSIDE_STEP else 0.0
    if code != 0 and code != EVENT_INSIDE_STEP:
        message = f"the model cannot start at t = {problem.t0:g} s: {problem.failure(code)}"
        state_d = problem.state_dict(state.y)
        return RunResult(
            t_rec, state.Yrec, state.AUXrec, stats0, Status.MODEL_FAILURE, message, 0,
            problem.t0, state_d, code,
        )  # fmt: skip
    h0 = k.initial_step(mid, problem.t0, t_end, settings, hooks, state)
    if not (h0 >= 0.0 and math.isfinite(h0)):
        derivative = ", ".join(f"d{n}/dt={v:.6g}" for n, v in problem.state_dict(state.f).items())
        return _refused(
            problem,
            t_rec,
            stats0,
            "the initial step cannot be formed: the state or its derivative overflows its norm "
            f"scaled by the tolerances (derivative: {derivative})",
        )
    state.ctrl[CT_T] = problem.t0
    state.ctrl[CT_H] = h0
    chunk = (t_end - problem.t0) / 100.0 if progress is not None else math.inf
    t_pause = problem.t0 + chunk
    budget = _FIRST_BUDGET
    while True:
        steps0 = int(state.stats[ST_STEPS])
        c0 = _time.perf_counter()
        code = k.advance(t_end, t_pause, steps0 + budget, settings, hooks, state, implicit)
        budget = _next_budget(budget, int(state.stats[ST_STEPS]) - steps0, c0)
        if progress is not None:
            progress(float(state.ctrl[CT_T]))
        if code != PAUSED:
            break
        if state.ctrl[CT_T] >= t_pause:
            t_pause += chunk
    stats, ctrl, y = state.stats, state.ctrl, state.y
    Y, AUX = state.Yrec, state.AUXrec
    st = solver_stats(
        method,
        rtol,
        atol,
        max_step,
        steps=int(stats[ST_STEPS]),
        rejected_steps=int(stats[ST_REJECTED]),
        rhs_evaluations=int(stats[ST_RHS]),
        events=int(stats[ST_EVENTS]),
        event_retries=int(stats[ST_EVENT_RETRIES]),
        wall_time=_time.perf_counter() - wall0,
    )
    st.update(_implicit_stats(implicit, float(ctrl[CT_T]) - problem.t0))
    status = _STATUS[code]
    t_now = float(ctrl[CT_T])
    n_rec = int(stats[ST_RECORDED])
    if status is Status.TERMINATED:
        t_rec, Y, AUX = t_rec[:n_rec], Y[:n_rec], AUX[:n_rec]
    if not status.failed:
        return RunResult(t_rec, Y, AUX, st, status, "", n_rec, t_now)
    model_code = int(stats[ST_MODEL_CODE]) if status is Status.MODEL_FAILURE else 0
    explanation = problem.failure(model_code) if model_code else ""
    where = problem.state_dict(y)
    message = failure_message(
        status, t_now, where, h=float(ctrl[CT_H]), max_steps=max_steps, explanation=explanation
    )
    return RunResult(t_rec, Y, AUX, st, status, message, n_rec, t_now, where, model_code)


def _next_budget(budget: int, steps: int, c0: float) -> int:
    """Steps until the next pause: about PAUSE_SECONDS at the rate of the last call (at most 8x
    the last budget, so that a slow stretch after a fast one is not one long call)."""
    if steps <= 0:
        return budget
    per_step = max(_time.perf_counter() - c0, 1e-9) / steps
    return int(min(8 * budget, max(_FIRST_BUDGET, PAUSE_SECONDS / per_step)))


def _refused(problem: Problem, t_rec: np.ndarray, stats0: dict, why: str) -> RunResult:
    """A run that cannot start (Status.NON_FINITE at t0): no records, ``why`` and the state in
    its message."""
    n = problem.y0.size
    Y = np.full((t_rec.size, n), np.nan)
    AUX = np.full((t_rec.size, problem.aux0.size), np.nan)
    state = problem.state_dict(problem.y0)
    shown = ", ".join(f"{k}={v:.6g}" for k, v in state.items())
    message = (
        f"the run cannot start at t = {problem.t0:.9g} s: {why} (state: {shown}); the initial "
        "state or a parameter lies far outside the model's range"
    )
    return RunResult(
        t_rec, Y, AUX, stats0, Status.NON_FINITE, message, 0, problem.t0, state, 0
    )  # fmt: skip


def failure_message(
    status: Status, t: float, state: dict[str, float], *, h: float, max_steps: int, explanation: str
) -> str:
    """What a failed compiled run reports: where, in which state, and what to change."""
    shown = ", ".join(f"{n}={v:.6g}" for n, v in state.items())
    if status is Status.MODEL_FAILURE:
        return f"integration failed at t = {t:.9g} s: {explanation} (state: {shown})"
    if status is Status.NON_FINITE:
        return (
            f"integration failed at t = {t:.9g} s: the state became non-finite (NaN or inf) and "
            f"smaller steps did not help (state: {shown}); likely an overflow in the model or an "
            "unphysical parameter"
        )
    if status is Status.MAX_STEPS:
        return (
            f"integration stopped at t = {t:.9g} s after solver.max_steps = {max_steps} steps "
            f"(state: {shown}); raise solver.max_steps or loosen solver.rtol"
        )
    return (
        f"integration failed at t = {t:.9g} s: step size underflow (h = {h:.3g} s) (state: "
        f"{shown}); the problem is stiff or discontinuous here, or the tolerances are too tight"
    )


def _implicit(problem: Problem, settings: Settings):
    """The implicit method's arrays for Radau IIA and the automatic method, else None (the
    loop is then compiled without the implicit method)."""
    if settings.method not in (RADAU5, AUTO):
        return None
    return implicit_of(problem, settings.rtol, settings.atol, state_scale(problem), settings.method)


def _implicit_stats(implicit, duration: float) -> dict:
    """The implicit method's and the automatic switching's statistics (zeros for an explicit
    method): Jacobian evaluations, LU decompositions (a real and a complex one each), Newton
    iterations and the steps they failed, implicit steps, evaluations and simulated time (s),
    the explicit method's simulated time (s), and the switches either way."""
    if implicit is None:
        counts = np.zeros(9, np.int64)
        t_implicit = 0.0
    else:
        counts, t_implicit = implicit.stats, float(implicit.rc[RC_TIME_IMPLICIT])
    return {
        "jacobians": int(counts[IS_JAC]),
        "lu_decompositions": int(counts[IS_LU]),
        "newton_iterations": int(counts[IS_NEWTON]),
        "newton_failures": int(counts[IS_NEWTON_FAIL]),
        "implicit_steps": int(counts[IS_STEPS]),
        "implicit_rhs_evaluations": int(counts[IS_RHS]),
        "implicit_time": t_implicit,
        "explicit_time": max(duration - t_implicit, 0.0),
        "switches_to_implicit": int(counts[IS_TO_IMPLICIT]),
        "switches_to_explicit": int(counts[IS_TO_EXPLICIT]),
    }


def _compiled(k, problem: Problem, settings: Settings) -> None:
    """Compile (or load from cache) every kernel entry point before the clock starts, so that
    the recorded wall time is integration only."""
    hooks = hooks_of(problem)
    state = allocate(problem, 0)
    t0 = problem.t0
    state.ctrl[CT_T] = t0
    k.start(t0, hooks, state)
    k.initial_step(settings.method, t0, t0 + 1.0, settings, hooks, state)
    short = settings._replace(max_steps=1, t_rec=np.zeros(0))
    k.advance(t0, t0, 1, short, hooks, state, _implicit(problem, settings))
