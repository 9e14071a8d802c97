"""Solvers: compiled embedded Runge–Kutta pairs with dense output and events, and scipy's
``solve_ivp`` as the independent reference backend.

The solver knows only its own protocol: a :class:`Problem` (compiled hooks, initial state,
tolerance scales, stiff states) goes in, a :class:`RunResult` with a :class:`Status` comes out.
It imports neither scenes nor models; :mod:`workbench.run` turns a scene into a Problem.
"""

from workbench.solver._integrate import COMPILED_METHODS, METHODS, integrate
from workbench.solver._problem import EVENT_INSIDE_STEP, Problem
from workbench.solver._result import RunResult, SolverError, Status

__all__ = [
    "COMPILED_METHODS",
    "EVENT_INSIDE_STEP",
    "METHODS",
    "Problem",
    "RunResult",
    "SolverError",
    "Status",
    "integrate",
]
