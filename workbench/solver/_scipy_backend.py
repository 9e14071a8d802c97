"""Reference backend: the same compiled right-hand side integrated by ``scipy.integrate.solve_ivp``.

It shares nothing with the compiled loop but the model's hooks: scipy's own step control, dense
output and event location (Brent's method), so agreement between the two is an independent check.
Events that change the state stop scipy's integration (``terminal=True``); the update is applied
and a new ``solve_ivp`` call continues. Rejected steps are not reported by scipy (stored as -1).

solve_ivp finds an event only where its function changes sign between the ends of a step, so
it misses a crossing that both ends hide: a contact entered and left within one step, or a
lasting contact that lifts off and touches again (a shallow contact near a grazing). The
compiled loop monitors its event functions inside each step for these (see
:mod:`workbench.solver._templates.integration_loop`); this backend does not, so near a
grazing the two can disagree on the contacts, and a smaller ``max_step`` or tighter tolerances
are this backend's only remedy.

``solver.max_steps`` bounds the right-hand side evaluations (``EVALUATIONS_PER_STEP`` per
step: solve_ivp does not count its steps as it goes), and an initial state whose first step
cannot be formed is refused (:func:`cannot_start`), as in the compiled loop.

A failed ``solve_ivp`` (status -1: its step size fell below the spacing of floating-point
numbers near t) ends the run with :attr:`Status.STEP_UNDERFLOW`, or with
:attr:`Status.MODEL_FAILURE` when the model rejected a trial state beyond the last accepted
step (scipy retries smaller after the NaN derivative that a model failure becomes here, so a
persistent model failure ends in scipy's step-size failure too).
"""

from __future__ import annotations

import importlib
import math
import time as _time

import numpy as np
from scipy.integrate import solve_ivp

from workbench.solver._compile import defines_hook
from workbench.solver._problem import EVENT_INSIDE_STEP, Problem
from workbench.solver._result import RunResult, Status, solver_stats

METHODS = ("RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA")  # of solve_ivp
#: solve_ivp does not count its steps as it goes: a run stops after this many right-hand side
#: evaluations per allowed step (``max_steps``), more than any of its methods spends per step
EVALUATIONS_PER_STEP = 20


class _TooMany(Exception):
    """Raised inside solve_ivp's right-hand side to stop a run at its evaluation limit."""


def cannot_start(problem: Problem, rtol: float, atol: np.ndarray) -> str:
    """Why no first step can be formed from the problem's initial state ('' if one can): its
    derivative, or the state itself, overflows its norm scaled by the tolerances (as the
    compiled loop's initial step tests; scipy would take steps of 1e-323 s forever), or its
    hooks define ``step_end`` (a tangent system's re-orthonormalisation), which only the compiled
    loop calls."""
    hooks = importlib.import_module(problem.hooks)
    if defines_hook(hooks, "step_end"):
        return (
            f"the hooks {problem.hooks!r} define step_end (e.g. the tangent system's "
            "re-orthonormalisation at the end of each step), which only the compiled loop calls: "
            "integrate with a compiled method"
        )
    f0 = np.empty(problem.y0.size)
    aux = problem.aux0.copy()
    work = np.zeros(max(problem.work_size, 1))
    y0 = np.ascontiguousarray(problem.y0, dtype=np.float64)
    hooks.rhs(problem.t0, y0, problem.p, problem.ip, aux, work, f0)
    scale = atol + np.abs(y0) * rtol
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        norms = [np.sqrt(np.mean((v / scale) ** 2)) for v in (y0, f0)]
    if all(np.isfinite(norms)):
        return ""
    shown = ", ".join(f"d{n}/dt={v:.6g}" for n, v in problem.state_dict(f0).items())
    return (
        "the initial step cannot be formed: the state or its derivative overflows its norm "
        f"scaled by the tolerances (derivative: {shown})"
    )


def integrate(
    problem: Problem,
    t_rec: np.ndarray,
    name: str,
    rtol: float,
    atol: np.ndarray,
    max_step: float,
    max_steps: int = 50_000_000,
) -> RunResult:
    """Integrate ``problem`` with ``solve_ivp(method=name)`` and record at ``t_rec`` (s); stop
    with :attr:`Status.MAX_STEPS` after ``EVALUATIONS_PER_STEP * max_steps`` evaluations."""
    hooks = importlib.import_module(problem.hooks)
    p, ip = problem.p, problem.ip
    aux = problem.aux0.copy()
    work = np.zeros(max(problem.work_size, 1))
    ne = problem.event_direction.size
    nfev = [0]
    last_failure = [0, 0.0]
    max_evaluations = EVALUATIONS_PER_STEP * max_steps

    def fun(t, y):
        nfev[0] += 1
        if nfev[0] > max_evaluations:
            raise _TooMany(t, y.copy())
        dydt = np.empty(y.size)
        code = hooks.rhs(t, np.ascontiguousarray(y, dtype=np.float64), p, ip, aux, work, dydt)
        if code != 0 and code != EVENT_INSIDE_STEP:
            # a trial stage outside the model's domain: NaN makes scipy reject the step and
            # retry smaller, as the compiled loop does; a persistent failure ends the run
            last_failure[:] = [code, t]
            dydt[:] = np.nan
        return dydt

    def make_event(k, guard):
        direction = int(problem.event_direction[k])

        def ev(t, y):
            g = np.empty(ne)
            hooks.event_values(t, np.ascontiguousarray(y, dtype=np.float64), p, ip, aux, work, g)
            if guard is not None and t <= guard[0]:
                return guard[1] * max(abs(g[k]), 1e-300)
            return g[k]

        ev.terminal = True
        ev.direction = direction
        return ev

    t = problem.t0
    y = problem.y0.copy()
    t_end = float(t_rec[-1])
    Y = np.full((t_rec.size, y.size), np.nan)
    AUX = np.full((t_rec.size, aux.size), np.nan)
    i_rec = 0
    steps = events = 0
    guard: dict[int, tuple[float, float]] = {}
    status, failure = Status.OK, None
    wall0 = _time.perf_counter()
    while True:
        while i_rec < t_rec.size and t_rec[i_rec] <= t:
            Y[i_rec], AUX[i_rec] = y, aux
            i_rec += 1
        if t >= t_end:
            break
        evs = [make_event(k, guard.get(k)) for k in range(ne)]
        try:
            sol = solve_ivp(
                fun,
                (t, t_end),
                y,
                method=name,
                rtol=rtol,
                atol=atol,
                max_step=max_step,
                dense_output=True,
                events=evs or None,
            )
        except _TooMany as exc:
            status = Status.MAX_STEPS
            t, y = exc.args  # the last point evaluated
            break
        steps += len(sol.t) - 1
        if sol.status == -1:
            failure = sol
            # the model's fault if it rejected a trial state past the last accepted step
            beyond = last_failure[0] and last_failure[1] >= sol.t[-1]
            status = Status.MODEL_FAILURE if beyond else Status.STEP_UNDERFLOW
            break
        t_seg = float(sol.t[-1])
        while i_rec < t_rec.size and t_rec[i_rec] <= t_seg:
            Y[i_rec], AUX[i_rec] = sol.sol(t_rec[i_rec]), aux
            i_rec += 1
        y = np.ascontiguousarray(sol.y[:, -1], dtype=np.float64)
        t = t_seg
        guard = {}
        if sol.status == 1:
            fired = [k for k in range(ne) if sol.t_events[k].size]
            k = min(fired, key=lambda j: sol.t_events[j][0])
            events += 1
            stop = hooks.apply_event(k, t, y, p, ip, aux, work)
            g = np.empty(ne)
            hooks.event_values(t, y, p, ip, aux, work, g)
            post = float(problem.event_direction[k]) or (math.copysign(1.0, g[k]) if g[k] else 0.0)
            if post:
                guard[k] = (t + 1e-12 * max(1.0, abs(t)), post)
            if stop:
                status = Status.TERMINATED
                break
    stats = solver_stats(
        f"scipy:{name}",
        rtol,
        float(np.max(atol)) if np.ndim(atol) else atol,
        max_step,
        steps=steps,
        rejected_steps=-1,
        rhs_evaluations=nfev[0],
        events=events,
        event_retries=0,  # scipy has no check for events inside a step
        wall_time=_time.perf_counter() - wall0,
    )
    if status is Status.TERMINATED:
        t_rec, Y, AUX = t_rec[:i_rec], Y[:i_rec], AUX[:i_rec]
    if status is Status.MAX_STEPS:
        message = (
            f"scipy:{name} stopped at t = {t:.9g} s at its limit of {max_evaluations} "
            f"right-hand side evaluations ({EVALUATIONS_PER_STEP} x solver.max_steps = "
            f"{max_steps}); raise solver.max_steps or loosen solver.rtol"
        )
        return RunResult(t_rec, Y, AUX, stats, status, message, i_rec, t, problem.state_dict(y))
    if failure is None:
        return RunResult(t_rec, Y, AUX, stats, status, "", i_rec, t)
    why = failure.message
    if last_failure[0]:
        why += f"; last model failure: {problem.failure(int(last_failure[0]))}"
    code = int(last_failure[0]) if status is Status.MODEL_FAILURE else 0
    t_fail = float(failure.t[-1])
    message = f"scipy:{name} failed after t = {t_fail:.9g} s: {why}"
    state = problem.state_dict(failure.y[:, -1])
    return RunResult(t_rec, Y, AUX, stats, status, message, i_rec, t_fail, state, code)
