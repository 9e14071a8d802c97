"""A ball bouncing on a rigid floor: the test model of event location and state updates.

h'' = -g in flight; at h = 0 moving down, v+ = -e v- (Newton's restitution law). Bounce times
are known in closed form, so the event machinery is checked against exact numbers.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from workbench.models import register
from workbench.models._base import EVENT_INSIDE_STEP, Model, Parameter, Problem, Quantity


@njit(cache=True)
def rhs(t, y, p, ip, aux, work, dydt):
    dydt[0] = y[1]
    dydt[1] = -p[0]
    if y[0] < 0.0:
        # below the floor without a located bounce: a step that rose and fell back through the
        # floor between its ends (the free flight is a parabola, which the error estimate
        # cannot see), so the loop must retry it shorter (see EVENT_INSIDE_STEP)
        return EVENT_INSIDE_STEP
    return 0


@njit(cache=True)
def jacobian(t, y, p, ip, aux, work, J):
    """d(h', v')/d(h, v) = [[0, 1], [0, 0]]."""
    J[0, 0] = 0.0
    J[0, 1] = 1.0
    J[1, 0] = 0.0
    J[1, 1] = 0.0
    return 0


@njit(cache=True)
def event_values(t, y, p, ip, aux, work, g):
    g[0] = y[0]


@njit(cache=True)
def apply_event(k, t, y, p, ip, aux, work):
    y[0] = 0.0
    y[1] = -p[1] * y[1]
    aux[0] += 1.0  # bounce counter
    aux[1] = t  # time of the last bounce
    return 1 if y[1] < p[2] else 0


@register
class BouncingBall(Model):
    """Ball dropped from rest at height h0 onto a floor with restitution e."""

    name = "bouncing_ball"
    description = "Ball bouncing on a rigid floor with Newton restitution"
    reference = "Newton's law of restitution; e.g. Pfeiffer & Glocker (1996), Sec. 5"
    parameters = (
        Parameter("g", 9.81, "m s-2", "gravitational acceleration", lower=0.0, lower_open=True),
        Parameter("restitution", 0.8, "1", "coefficient of restitution", lower=0.0, upper=1.0),
        Parameter("h0", 1.0, "m", "drop height", lower=0.0, lower_open=True),
        Parameter(
            "rest_speed", 1e-6, "m s-1", "rebound speed below which the ball is at rest", lower=0.0
        ),
    )
    fixed_states = (
        Quantity("h", "m", "height above the floor", rate="v"),
        Quantity("v", "m s-1", "velocity"),
    )
    fixed_outputs = (
        Quantity("bounces", "1", "number of bounces so far"),
        Quantity("last_bounce_time", "s", "time of the last bounce"),
    )

    def problem(self, params, effects, initial, requested):
        y0 = np.array([initial.get("h", params["h0"]), initial.get("v", 0.0)])
        p = np.array([params["g"], params["restitution"], params["rest_speed"]])
        return Problem(
            hooks=__name__,
            states=self.fixed_states,
            y0=y0,
            p=p,
            aux0=np.array([0.0, np.nan]),
            event_direction=np.array([-1]),
        )

    def derive(self, problem, t, Y, AUX, requested):
        return {"bounces": AUX[:, 0], "last_bounce_time": AUX[:, 1]}
