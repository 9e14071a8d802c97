"""Placeholder hooks that make the kernel template importable and testable on its own.

A trivial model, dy/dt = -y with no events; :mod:`workbench.solver._compile` replaces this import
with the hooks of the model being integrated.
"""

from __future__ import annotations

from numba import njit

from workbench.solver._no_events import (  # noqa: F401 (its hooks)
    apply_event,
    event_values,
    step_end,
)


@njit(cache=True, nogil=True)
def rhs(t, y, p, ip, aux, work, dydt):  # noqa: ARG001
    for i in range(y.size):
        dydt[i] = -y[i]
    return 0


@njit(cache=True, nogil=True)
def jacobian(t, y, p, ip, aux, work, J):  # noqa: ARG001
    """Analytic Jacobian of dy/dt = -y: J = -I (the optional ``jacobian`` hook)."""
    n = y.size
    for i in range(n):
        for j in range(n):
            J[i, j] = -1.0 if i == j else 0.0
    return 0
