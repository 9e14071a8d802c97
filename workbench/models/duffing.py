"""Forced Duffing oscillator, a reference system for the solver and the analysis.

x'' + delta x' + alpha x + beta x^3 = gamma cos(omega t)   (Duffing 1918; Guckenheimer & Holmes
1983, Sec. 2.2). Non-dimensional: "s" stands for the model's time unit and "m" for its length.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from workbench.models import Model, Parameter, Problem, Quantity, register
from workbench.models.no_events import apply_event, event_values  # noqa: F401 (its hooks)


@njit(cache=True)
def rhs(t, y, p, ip, aux, work, dydt):
    delta, alpha, beta, gamma, omega = p[0], p[1], p[2], p[3], p[4]
    x = y[0]
    v = y[1]
    dydt[0] = v
    dydt[1] = gamma * math.cos(omega * t) - delta * v - alpha * x - beta * x * x * x
    return 0


@njit(cache=True)
def jacobian(t, y, p, ip, aux, work, J):
    """Analytic Jacobian d(x', v')/d(x, v); its trace is -delta (s-1)."""
    J[0, 0] = 0.0
    J[0, 1] = 1.0
    J[1, 0] = -p[1] - 3.0 * p[2] * y[0] * y[0]
    J[1, 1] = -p[0]
    return 0


@register
class Duffing(Model):
    """Forced Duffing oscillator; forcing period 2 pi / omega."""

    name = "duffing"
    description = (
        "Forced Duffing oscillator x'' + delta x' + alpha x + beta x^3 = gamma cos(omega t)"
    )
    reference = "Duffing (1918); Guckenheimer & Holmes (1983), Sec. 2.2"
    parameters = (
        Parameter("delta", 0.3, "s-1", "damping coefficient", lower=0.0),
        Parameter("alpha", -1.0, "s-2", "linear stiffness"),
        Parameter("beta", 1.0, "m-2 s-2", "cubic stiffness"),
        Parameter("gamma", 0.5, "m s-2", "forcing amplitude"),
        Parameter("omega", 1.2, "rad s-1", "forcing angular frequency", lower=0.0, lower_open=True),
        Parameter("x0", 1.0, "m", "initial displacement"),
        Parameter("v0", 0.0, "m s-1", "initial velocity"),
    )
    fixed_states = (
        Quantity("x", "m", "displacement", rate="v"),
        Quantity("v", "m s-1", "velocity"),
    )

    def forcing_period(self, params):
        return 2.0 * math.pi / params["omega"]

    def problem(self, params, effects, initial, requested):
        p = np.array([params[k] for k in ("delta", "alpha", "beta", "gamma", "omega")])
        y0 = [initial.get("x", params["x0"]), initial.get("v", params["v0"])]
        return Problem(hooks=__name__, states=self.fixed_states, y0=np.array(y0), p=p)
