"""Placeholder hooks that make the kernel template importable and testable on its own.

A trivial model, dy/dt = -y with no events; :mod:`workbench.solver._compile` replaces this import
with the hooks of the model being integrated.
"""

from __future__ import annotations

from numba import njit


@njit(cache=True)
def rhs(t, y, p, ip, aux, work, dydt):  # noqa: ARG001
    for i in range(y.size):
        dydt[i] = -y[i]
    return 0


@njit(cache=True)
def event_values(t, y, p, ip, aux, work, g):  # noqa: ARG001
    return None


@njit(cache=True)
def apply_event(k, t, y, p, ip, aux, work):  # noqa: ARG001
    return 0
