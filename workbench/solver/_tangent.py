"""The tangent (variational) system of a problem, as a problem the compiled loop integrates.

See :mod:`workbench.solver._templates.tangent_hooks` for the equations (variational equations
between
events, the saltation matrix at events) and the layout of the arrays built here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from workbench.solver._compile import tangent_for
from workbench.solver._problem import Problem

__all__ = ["tangent_problem", "tangent_columns", "state_scale", "N_META"]

N_META = 7


@dataclass(frozen=True)
class _State:
    """An internal state of a derived system (the solver's view of a declared state)."""

    name: str
    units: str = "1"
    long_name: str = ""


def state_scale(problem: Problem) -> np.ndarray:
    """Characteristic size of each state (state units): the problem's ``atol_scale`` where it is
    finite and positive, else 1. Tangent vectors are measured and orthonormalised in the state
    divided by this scale."""
    s = np.asarray(problem.atol_scale, dtype=float)
    return np.where(np.isfinite(s) & (s > 0), s, 1.0)


def tangent_problem(
    problem: Problem, V: np.ndarray, *, time_scale: float = 1.0, log_det: float = 0.0
) -> Problem:
    """The problem's state extended by the tangent vectors ``V`` (shape ``(n + na, m)``: state
    then discrete-state components, in their units) and the accumulated ``log |det S_yy|``.

    Parameters
    ----------
    problem : Problem
        The model's problem (its ``t0``, ``y0``, ``aux0`` are the start of the tangent run).
    V : ndarray
        Initial tangent vectors of the extended state ``(y, aux)``, one per column.
    time_scale : float
        A characteristic time of the model (s), which sizes the difference step in time of
        the event update and event function.
    log_det : float
        Initial value of the accumulated log volume change at events.
    """
    n, na = problem.y0.size, problem.aux0.size
    V = np.asarray(V, dtype=float)
    if V.ndim != 2 or V.shape[0] != n + na:
        raise ValueError(
            f"tangent vectors must have shape (n + na, m) = ({n + na}, m); got {V.shape!r}"
        )
    m = V.shape[1]
    hooks = tangent_for(problem.hooks).__name__
    scale = state_scale(problem)
    states = tuple(problem.states) + tuple(
        _State(f"_tangent_{c}_{i}", "1", "tangent vector component")
        for c in range(m)
        for i in range(n + na)
    )
    states += (_State("_log_det_saltation", "1", "sum of log |det S_yy| at events"),)
    vscale = np.concatenate([scale, np.ones(na)])
    atol_scale = np.concatenate([scale, np.tile(vscale, m), [1.0]])
    meta = [n, na, m, problem.event_direction.size, problem.p.size, problem.ip.size]
    meta.append(problem.work_size)
    return Problem(
        hooks=hooks,
        states=states,
        y0=np.concatenate([problem.y0, V.T.ravel(), [log_det]]),
        p=np.concatenate([problem.p, scale, [time_scale]]),
        ip=np.concatenate([problem.ip, np.array(meta, dtype=np.int64)]),
        aux0=problem.aux0,
        event_direction=problem.event_direction,
        atol_scale=atol_scale,
        t0=problem.t0,
        work_size=problem.work_size + 3 * n + n * na + n * n,
        failure=problem.failure,
    )


def tangent_columns(Y: np.ndarray, n: int, na: int, m: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Split a tangent-system state into the model state ``y``, the tangent vectors ``V``
    (``(n + na, m)``) and the accumulated log volume change at events."""
    y = Y[:n]
    V = Y[n : n + m * (n + na)].reshape(m, n + na).T
    return y, V, float(Y[n + m * (n + na)])
