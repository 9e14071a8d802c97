"""Forced Duffing oscillator, a reference system for the solver and the analysis.

x'' + delta x' + alpha x + beta x^3 = gamma cos(omega t)   (Duffing 1918; Guckenheimer & Holmes
1983, Sec. 2.2), in the non-dimensional form of that reference: the displacement x, the velocity
v = x', the coefficients delta, alpha, beta and the forcing amplitude gamma are pure numbers
(units "1"), and so is every quantity derived from them. The independent variable t is the
non-dimensional time; the solver, the archives and the analysis label every time axis "s" (a
forcing period, a record time, an exponent per unit time "s-1"), and so does this model: read
"s" as the model's unit of time and omega's "rad s-1" as radians per unit of it.
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
    """Analytic Jacobian d(x', v')/d(x, v); its trace is -delta (per unit of time)."""
    J[0, 0] = 0.0
    J[0, 1] = 1.0
    J[1, 0] = -p[1] - 3.0 * p[2] * y[0] * y[0]
    J[1, 1] = -p[0]
    return 0


@register
class Duffing(Model):
    """Forced Duffing oscillator, non-dimensional (units "1"; time in the model's unit, labelled
    "s"); forcing period 2 pi / omega."""

    name = "duffing"
    description = (
        "Forced Duffing oscillator x'' + delta x' + alpha x + beta x^3 = gamma cos(omega t)"
    )
    reference = "Duffing (1918); Guckenheimer & Holmes (1983), Sec. 2.2"
    parameters = (
        Parameter("delta", 0.3, "1", "damping coefficient", lower=0.0),
        Parameter("alpha", -1.0, "1", "linear stiffness"),
        Parameter("beta", 1.0, "1", "cubic stiffness"),
        Parameter("gamma", 0.5, "1", "forcing amplitude"),
        Parameter("omega", 1.2, "rad s-1", "forcing angular frequency", lower=0.0, lower_open=True),
        Parameter("x0", 1.0, "1", "initial displacement"),
        Parameter("v0", 0.0, "1", "initial velocity"),
    )
    fixed_states = (
        Quantity("x", "1", "displacement", rate="v"),
        Quantity("v", "1", "velocity"),
    )

    def forcing_period(self, params):
        return 2.0 * math.pi / params["omega"]

    def problem(self, params, effects, initial, requested):
        p = np.array([params[k] for k in ("delta", "alpha", "beta", "gamma", "omega")])
        y0 = [initial.get("x", params["x0"]), initial.get("v", params["v0"])]
        return Problem(hooks=__name__, states=self.fixed_states, y0=np.array(y0), p=p)
