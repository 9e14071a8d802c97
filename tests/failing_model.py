"""A one-state test model that ends its run with the :class:`workbench.Status` it is asked for,
registered as the model ``failing`` when imported.

Parameter ``mode`` is the value of the status; what the model does after ``t_fail`` (s):

0. ``ok``: y' = -y throughout.
1. ``terminated``: an event at t_fail asks to stop.
2. ``max_steps``: y' = -1e6 (y - 1) throughout, a stiff decay: an explicit method's stability
   bound (h < ~3.3e-6 s) needs ~3e5 steps per second, beyond a small ``solver.max_steps``.
3. ``step_underflow``: y' = -1 / (2 y) from y(0) = sqrt(t_fail), i.e. y = sqrt(t_fail - t):
   its slope is unbounded at t_fail, where the step collapses while the state stays finite.
4. ``non_finite``: the derivative is NaN after t_fail.
5. ``model_failure``: ``rhs`` returns the model failure code 7 after t_fail.

And 6: ``problem`` raises RuntimeError, as a bug would (no status: a campaign stops).
"""

import math

import numpy as np
from numba import njit

from workbench.models import Model, Parameter, Problem, Quantity, register

OK, TERMINATED, MAX_STEPS, STEP_UNDERFLOW, NON_FINITE, MODEL_FAILURE, BUG = range(7)
CODE = 7  # the model failure code of MODEL_FAILURE


@njit(cache=True)
def rhs(t, y, p, ip, aux, work, dydt):  # noqa: ARG001
    mode, t_fail = ip[0], p[0]
    if mode == MAX_STEPS:
        dydt[0] = -1e6 * (y[0] - 1.0)
    elif mode == STEP_UNDERFLOW:
        dydt[0] = -0.5 / y[0]
    elif mode == NON_FINITE and t > t_fail:
        dydt[0] = math.nan
    elif mode == MODEL_FAILURE and t > t_fail:
        dydt[0] = 0.0
        return CODE
    else:
        dydt[0] = -y[0]
    return 0


@njit(cache=True)
def event_values(t, y, p, ip, aux, work, g):  # noqa: ARG001
    g[0] = t - p[0] if ip[0] == TERMINATED else -1.0


@njit(cache=True)
def apply_event(k, t, y, p, ip, aux, work):  # noqa: ARG001
    return 1


@register
class Failing(Model):
    """y' = -y, or the failure of the module docstring."""

    name = "failing"
    parameters = (
        Parameter("mode", 0.0, "1", "value of the workbench.Status to end with, 6 a bug", 0, 6),
        Parameter("t_fail", 0.5, "s", "time of the failure", lower=0.0, lower_open=True),
    )
    fixed_states = (Quantity("y", "1", "state"),)

    def problem(self, params, effects, initial, requested):
        mode = int(params["mode"])
        if mode == BUG:
            raise RuntimeError("a bug in the test model")
        y0 = math.sqrt(params["t_fail"]) if mode == STEP_UNDERFLOW else 2.0
        return Problem(
            hooks=__name__,
            states=self.fixed_states,
            y0=np.array([initial.get("y", y0)]),
            p=np.array([params["t_fail"]]),
            ip=np.array([mode]),
            event_direction=np.array([1]),
            failure=lambda code: f"the test model refuses t > t_fail (code {code})",
        )
