"""Hooks of a stiff test problem with a known solution (Prothero & Robinson 1974 type).

State (u, z): u' = cos t (u = sin t), z' = r - a z with the decay rate a = a0 (1 + u^2) (s-1)
depending on the non-stiff state only and r = a phi(t) + phi'(t), phi(t) = cos(2 t), so that
z = phi(t) exactly when z(0) = 1, whatever a0. p = (a0,). ARK548 protocol (see
workbench.solver._templates.integration_loop): the decay rate goes to work[0], h gamma comes
in work[1].
"""

import math

from numba import njit

from workbench.solver._templates.placeholder_hooks import apply_event, event_values  # noqa: F401 (no events)


@njit(cache=True)
def rhs(t, y, p, ip, aux, work, dydt):  # noqa: ARG001
    a = p[0] * (1.0 + y[0] * y[0])
    r = a * math.cos(2.0 * t) - 2.0 * math.sin(2.0 * t)
    y[1] = (y[1] + work[1] * r) / (1.0 + work[1] * a)
    work[0] = a
    dydt[0] = math.cos(t)
    dydt[1] = r - a * y[1]
    return 0
