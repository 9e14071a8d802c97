"""Forced linear oscillator with a one-sided elastic stop: the reference system of grazing.

m x'' + c x' + k x + k_s (x - g) H(x - g) = F cos(omega t): a mass on a spring and damper,
forced harmonically, meets a stiff spring (the stop) at the gap ``g`` (Shaw & Holmes 1983;
Nordmark 1991; di Bernardo, Budd, Champneys & Kowalczyk 2008, Ch. 2). The stop's force is
continuous at contact (it grows from zero), so the vector field has a kink, not a jump, at
``x = g``: events at contact onset (x rising through g) and end (falling) let the solver step
exactly to the kink, and count the contacts.

The side of the stop is a discrete state, the *mode* (``aux[0]``: 1 in contact, 0 free), set by
those events, as in the hybrid-automaton form of a piecewise-smooth system (di Bernardo et al.
2008, Sec. 2.2): within a band of :data:`SIDE_BAND` times the length scale ``|g| + |F| / k``
around the stop the mode decides which law applies, beyond it the state does. So a step that
starts on the stop integrates one smooth law: read from the state alone, its stages could fall
on both sides, which the state's error does not see but its tangent system's does (the Jacobian
jumps by ``k_s``; docs/continuation.md, "Grazing in the tangent system"). A state beyond the band
on the other side than its mode makes the rhs return
:data:`~workbench.models._base.EVENT_INSIDE_STEP`, so that the step is cut to the event.

A periodic orbit that does not reach the stop is the linear one, of amplitude
``F / sqrt((k - m omega^2)^2 + (c omega)^2)``: it grazes the stop where that amplitude equals
``g``, a closed form to check a grazing bifurcation against. SI units.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from workbench.models import register
from workbench.models._base import EVENT_INSIDE_STEP, Model, Parameter, Problem, Quantity

#: half-width of the band around the stop where the mode, not the state, sets the side, relative
#: to the length scale |g| + |F| / k: some 1e4 roundings of x, far below any contact the
#: tolerances resolve
SIDE_BAND = 1e-12


@njit(cache=True)
def in_contact(y, p, aux):
    """Whether the stop's law applies at state ``y``: beyond the band around the stop the state
    decides (x > g), inside it the mode ``aux[0]``. Returns ``(contact, consistent)``, where
    ``consistent`` is False for a state beyond the band on the side its mode is not (an event
    not yet fired)."""
    gap = p[4]
    d = y[0] - gap
    band = SIDE_BAND * (abs(gap) + abs(p[5]) / p[2])
    mode = aux[0] > 0.5
    if d > band:
        return True, mode
    if d < -band:
        return False, not mode
    return mode, True


@njit(cache=True)
def rhs(t, y, p, ip, aux, work, dydt):
    m, c, k, ks, gap, force, omega = p[0], p[1], p[2], p[3], p[4], p[5], p[6]
    x = y[0]
    v = y[1]
    f = force * math.cos(omega * t) - c * v - k * x
    contact, consistent = in_contact(y, p, aux)
    if contact:
        f -= ks * (x - gap)
    dydt[0] = v
    dydt[1] = f / m
    return 0 if consistent else EVENT_INSIDE_STEP


@njit(cache=True)
def jacobian(t, y, p, ip, aux, work, J):
    """d(x', v')/d(x, v): the stop's stiffness adds to k on the contact side (s-2, s-1)."""
    m, c, k, ks = p[0], p[1], p[2], p[3]
    contact, _ = in_contact(y, p, aux)
    stiff = k + ks if contact else k
    J[0, 0] = 0.0
    J[0, 1] = 1.0
    J[1, 0] = -stiff / m
    J[1, 1] = -c / m
    return 0


@njit(cache=True)
def event_values(t, y, p, ip, aux, work, g):
    d = y[0] - p[4]
    g[0] = d  # rising: contact onset
    g[1] = d  # falling: contact end


@njit(cache=True)
def apply_event(k, t, y, p, ip, aux, work):
    # the force is continuous at the stop: nothing jumps but the mode
    aux[0] = 1.0 if k == 0 else 0.0
    return 0


@register
class StopOscillator(Model):
    """Harmonically forced linear oscillator with a one-sided elastic stop at distance g."""

    name = "stop_oscillator"
    description = (
        "Forced linear oscillator m x'' + c x' + k x + k_s (x - g) H(x - g) = F cos(omega t) "
        "with a one-sided elastic stop at the gap g"
    )
    reference = "Shaw & Holmes (1983); Nordmark (1991); di Bernardo et al. (2008), Ch. 2"
    event_units = "m"  # both event functions are x - g
    parameters = (
        Parameter("mass", 1.0, "kg", "mass", lower=0.0, lower_open=True),
        Parameter("damping", 0.1, "N s m-1", "viscous damping coefficient c", lower=0.0),
        Parameter("stiffness", 1.0, "N m-1", "spring stiffness k", lower=0.0, lower_open=True),
        Parameter("stop_stiffness", 100.0, "N m-1", "stiffness k_s of the stop", lower=0.0),
        Parameter("gap", 1.0, "m", "distance g from the rest position to the stop", lower=0.0),
        Parameter("force", 0.5, "N", "forcing amplitude F"),
        Parameter("omega", 0.5, "rad s-1", "forcing angular frequency", lower=0.0, lower_open=True),
        Parameter("x0", 0.0, "m", "initial displacement"),
        Parameter("v0", 0.0, "m s-1", "initial velocity"),
    )
    fixed_states = (
        Quantity("x", "m", "displacement"),
        Quantity("v", "m s-1", "velocity"),
    )

    def forcing_period(self, params):
        return 2.0 * math.pi / params["omega"]

    def problem(self, params, effects, initial, requested):
        names = ("mass", "damping", "stiffness", "stop_stiffness", "gap", "force", "omega")
        p = np.array([params[k] for k in names])
        y0 = [initial.get("x", params["x0"]), initial.get("v", params["v0"])]
        return Problem(
            hooks=__name__,
            states=self.fixed_states,
            y0=np.array(y0, dtype=float),
            p=p,
            # the mode (1 in contact): the side the start lies on; it is no quantity the flow
            # depends on smoothly (no scale: no tangent or Newton component)
            aux0=np.array([1.0 if y0[0] > params["gap"] else 0.0]),
            aux_scale=np.array([np.inf]),
            event_direction=np.array([1, -1]),
        )


def grazing_amplitude(params) -> float:
    """Amplitude (m) of the non-impacting periodic orbit: F / sqrt((k - m w^2)^2 + (c w)^2)."""
    m, c, k = params["mass"], params["damping"], params["stiffness"]
    w = params["omega"]
    return abs(params["force"]) / math.hypot(k - m * w * w, c * w)
