"""Solvers: compiled embedded Runge–Kutta pairs with dense output and events, and scipy's
``solve_ivp`` as the independent reference backend.

The solver knows only its own protocol: a :class:`Problem` (compiled hooks, initial state,
tolerance scales, stiff states) goes in, a :class:`RunResult` with a :class:`Status` comes out.
It imports neither scenes nor models; :mod:`workbench.run` turns a scene into a Problem.
Derived systems of a problem are problems too: its tangent (variational) system with
saltation at events (:func:`tangent_problem`), copies integrated side by side in one step
sequence (:func:`copies_problem`); :func:`jacobian_for` gives a model's compiled Jacobian and
:func:`generated_source` the code generated for a model from the templates.
"""

from workbench._cache import register_cache_locator

# Before any module of the solver or of a model (which imports the solver first) defines a
# cached compiled function.
register_cache_locator()

from workbench.solver._compile import TEMPLATE_MODULES, generated_source, jacobian_for  # noqa: E402
from workbench.solver._copies import copies_problem, shrink_counts, split_copies  # noqa: E402
from workbench.solver._integrate import COMPILED_METHODS, METHODS, PAUSE_SECONDS, integrate  # noqa: E402
from workbench.solver._problem import EVENT_INSIDE_STEP, Problem  # noqa: E402
from workbench.solver._result import RunResult, SolverError, Status  # noqa: E402
from workbench.solver._tangent import (  # noqa: E402
    state_scale,
    tangent_columns,
    tangent_growths,
    tangent_problem,
    tangent_state,
    tangent_volume,
    tangent_weights,
)

__all__ = [
    "COMPILED_METHODS",
    "EVENT_INSIDE_STEP",
    "METHODS",
    "PAUSE_SECONDS",
    "Problem",
    "RunResult",
    "SolverError",
    "Status",
    "TEMPLATE_MODULES",
    "copies_problem",
    "generated_source",
    "integrate",
    "jacobian_for",
    "shrink_counts",
    "split_copies",
    "state_scale",
    "tangent_columns",
    "tangent_problem",
    "tangent_growths",
    "tangent_state",
    "tangent_volume",
    "tangent_weights",
]
