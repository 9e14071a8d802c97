"""Lorenz (1963) system, a reference system for the solver and the analysis.

x' = sigma (y - x),  y' = x (rho - z) - y,  z' = x y - beta z (non-dimensional; "s" is the
model's time unit and "1" its state unit).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from workbench.models import Model, Parameter, Problem, Quantity, register
from workbench.models.no_events import apply_event, event_values  # noqa: F401 (its hooks)


@njit(cache=True)
def rhs(t, y, p, ip, aux, work, dydt):
    sigma, rho, beta = p[0], p[1], p[2]
    dydt[0] = sigma * (y[1] - y[0])
    dydt[1] = y[0] * (rho - y[2]) - y[1]
    dydt[2] = y[0] * y[1] - beta * y[2]
    return 0


@njit(cache=True)
def jacobian(t, y, p, ip, aux, work, J):
    """Analytic Jacobian d(x', y', z')/d(x, y, z) (s-1); its trace is -(sigma + 1 + beta)."""
    sigma, rho, beta = p[0], p[1], p[2]
    J[0, 0] = -sigma
    J[0, 1] = sigma
    J[0, 2] = 0.0
    J[1, 0] = rho - y[2]
    J[1, 1] = -1.0
    J[1, 2] = -y[0]
    J[2, 0] = y[1]
    J[2, 1] = y[0]
    J[2, 2] = -beta
    return 0


@register
class Lorenz(Model):
    """Lorenz system; autonomous (no forcing period)."""

    name = "lorenz"
    description = "Lorenz (1963) convection model"
    reference = "Lorenz (1963), J. Atmos. Sci. 20:130"
    parameters = (
        Parameter("sigma", 10.0, "1", "Prandtl number"),
        Parameter("rho", 28.0, "1", "reduced Rayleigh number"),
        Parameter("beta", 8.0 / 3.0, "1", "geometric factor"),
        Parameter("x0", 1.0, "1", "initial x"),
        Parameter("y0", 1.0, "1", "initial y"),
        Parameter("z0", 1.0, "1", "initial z"),
    )
    fixed_states = (
        Quantity("x", "1", "convection intensity"),
        Quantity("y", "1", "horizontal temperature difference"),
        Quantity("z", "1", "vertical temperature difference"),
    )

    def problem(self, params, effects, initial, requested):
        p = np.array([params["sigma"], params["rho"], params["beta"]])
        y0 = [initial.get(s, params[s + "0"]) for s in ("x", "y", "z")]
        return Problem(hooks=__name__, states=self.fixed_states, y0=np.array(y0), p=p)
