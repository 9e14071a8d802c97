"""Hooks of classic test problems for the implicit method, selected by ``ip[0]``.

0. Van der Pol oscillator y1' = y2, y2' = mu (1 - y1^2) y2 - y1 with mu = p[0] (stiff for
   mu >> 1; Hairer & Wanner 1996, Sec. IV.1).
1. Robertson's chemical reaction (Robertson 1966; Hairer & Wanner 1996, Sec. IV.1, Eq. 1.4):
   y1' = -0.04 y1 + 1e4 y2 y3, y2' = 0.04 y1 - 1e4 y2 y3 - 3e7 y2^2, y3' = 3e7 y2^2, whose
   sum y1 + y2 + y3 is conserved.
2. Harmonic oscillator y1' = y2, y2' = -w^2 y1 with w = p[0] (linear: y1 = cos w t from
   (1, 0)), with an analytic Jacobian, so that a simplified Newton iteration is exact.
Analytic Jacobians for all three (the nine-bar exercises the finite-difference one). No events.
"""

from numba import njit

from workbench.solver._templates.placeholder_hooks import apply_event, event_values  # noqa: F401 (no events)


@njit(cache=True)
def rhs(t, y, p, ip, aux, work, dydt):  # noqa: ARG001
    kind = ip[0]
    if kind == 0:
        dydt[0] = y[1]
        dydt[1] = p[0] * (1.0 - y[0] * y[0]) * y[1] - y[0]
    elif kind == 1:
        r1 = 0.04 * y[0]
        r2 = 1e4 * y[1] * y[2]
        r3 = 3e7 * y[1] * y[1]
        dydt[0] = -r1 + r2
        dydt[1] = r1 - r2 - r3
        dydt[2] = r3
    else:
        dydt[0] = y[1]
        dydt[1] = -p[0] * p[0] * y[0]
    return 0


@njit(cache=True)
def jacobian(t, y, p, ip, aux, work, J):  # noqa: ARG001
    """Analytic Jacobians of the three problems."""
    kind = ip[0]
    if kind == 0:
        J[0, 0] = 0.0
        J[0, 1] = 1.0
        J[1, 0] = -2.0 * p[0] * y[0] * y[1] - 1.0
        J[1, 1] = p[0] * (1.0 - y[0] * y[0])
    elif kind == 1:
        J[0, 0] = -0.04
        J[0, 1] = 1e4 * y[2]
        J[0, 2] = 1e4 * y[1]
        J[1, 0] = 0.04
        J[1, 1] = -1e4 * y[2] - 6e7 * y[1]
        J[1, 2] = -1e4 * y[1]
        J[2, 0] = 0.0
        J[2, 1] = 6e7 * y[1]
        J[2, 2] = 0.0
    else:
        J[0, 0] = 0.0
        J[0, 1] = 1.0
        J[1, 0] = -p[0] * p[0]
        J[1, 1] = 0.0
    return 0
