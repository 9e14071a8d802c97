"""Forced linear oscillator with a rigid stop and Newton's restitution law: the impact oscillator.

m x'' + c x' + k x = F cos(omega t) while x < g; where the mass reaches the stop at x = g moving
towards it (v > 0) its velocity is reversed, v -> -r v (Shaw & Holmes 1983; Nordmark 1991;
Budd & Dux 1994; di Bernardo, Budd, Champneys & Kowalczyk 2008, Ch. 2 and 4). SI units; the
non-dimensional form of the literature, x'' + 2 zeta x' + x = cos(omega t) with the stop at
sigma, is m = k = F = 1, c = 2 zeta, g = sigma.

The stop is rigid, so an impact is an event with a jump of the velocity, unlike the stop
oscillator's continuous elastic force (:mod:`workbench.models.stop_oscillator`): near a grazing
impact (an impact at vanishing velocity) the stroboscopic map has a square-root singularity
(Nordmark 1991), where the stop oscillator's map is C^1. An orbit that does not reach the stop
is the linear one, of amplitude ``F / sqrt((k - m omega^2)^2 + (c omega)^2)``
(:func:`grazing_amplitude`, shared with the stop oscillator): it grazes the stop where that
amplitude equals ``g``.

**Events** (event functions in m). 0: the impact, ``x - g`` rising through 0. 1: the release of
a mass resting on the stop (below). 2: ``min(v / omega, g - x)`` falling through 0, at the top
of every swing that stays short of the stop and at the stop where the mass reaches it. A
shallow impact can lie wholly between two step ends, where ``x - g`` is negative at both; event
2 changes sign over such a step all the same, and its first zero is the impact: it is located
at the stop exactly, however shallow (the impacts of the square-root map near a grazing are
all shallow). ``x - g`` peaks at exactly 0 at an impact and is negative elsewhere: along an
impacting orbit its local maxima measure the free passes' margins to the stop, not the impacts'
depths. So the stop (event 0) is the model's one switching surface (``Problem.event_surface``):
event 2 also changes sign at every turning point short of the stop, where nothing happens to
the orbit, and event 1 marks a time; neither has grazings.

**Sticking.** Where the forcing presses the mass against the stop, ``F cos(omega t) > k g``,
the impacts accumulate: each rebound is ``r`` times slower and comes sooner, infinitely many in
a finite time (chattering; Budd & Dux 1994; di Bernardo et al. 2008, Sec. 2.4). An impact whose
rebound speed ``r v`` is below ``rest_speed`` while the forcing presses the mass against the
stop ends the sequence: the mass rests on the stop (``x = g``, ``v = 0``; output ``sticking``
1) until the forcing lets it go, at the next time where ``F cos(omega t) = k g`` falling, known
in closed form when the rest begins and held in the discrete state (event 1 fires there; with
``k g <= -F`` the forcing never lets go). A slow impact while the forcing pulls the mass away
(the grazing impacts of the square-root map) is never cut short. With ``r < 1`` every
chattering sequence thus ends after about ``log(v / rest_speed) / log(1 / r)`` impacts, and
every integration ends.

**Time origin.** Runs start, and the stroboscopic map samples, at forcing phase pi
(``t0 = pi / omega``), where the forcing pulls the mass away from the stop hardest: no orbit
rests on the stop there (unless the forcing never lets it go), so the discrete state at a strobe
time is that of a free mass, the same whatever the time origin, and periodic orbits and
continued sweeps restart from it exactly.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from workbench._errors import SceneError
from workbench.models import EVENT_INSIDE_STEP, register
from workbench.models._base import Model, Parameter, Problem, Quantity
from workbench.models.stop_oscillator import grazing_amplitude

__all__ = ["ImpactOscillator", "grazing_amplitude"]

#: the discrete state: 1 while the mass rests on the stop, and the time it is let go (s; -1: the
#: forcing never lets it go); both 0 while it is free
STICKING, RELEASE = 0, 1
#: value of the release event function while the mass is free, or never let go (m)
FREE = -1.0


@njit(cache=True)
def rhs(t, y, p, ip, aux, work, dydt):
    m, c, k, gap, force, omega = p[0], p[1], p[2], p[3], p[5], p[6]
    if aux[STICKING] != 0.0:  # resting on the stop until the forcing lets it go
        dydt[0] = 0.0
        dydt[1] = 0.0
        return 0
    dydt[0] = y[1]
    dydt[1] = (force * math.cos(omega * t) - c * y[1] - k * y[0]) / m
    if y[0] > gap:
        # beyond the stop without a located impact: the step rose and fell back through the
        # stop between its ends, so the loop must retry it shorter (see EVENT_INSIDE_STEP)
        return EVENT_INSIDE_STEP
    return 0


@njit(cache=True)
def jacobian(t, y, p, ip, aux, work, J):
    """d(x', v')/d(x, v) (s-2, s-1): the linear oscillator's, zero while resting on the stop."""
    m, c, k = p[0], p[1], p[2]
    free = 1.0 if aux[STICKING] == 0.0 else 0.0
    J[0, 0] = 0.0
    J[0, 1] = free
    J[1, 0] = -free * k / m
    J[1, 1] = -free * c / m
    return 0


@njit(cache=True)
def event_values(t, y, p, ip, aux, work, g):
    k, force, omega = p[2], p[5], p[6]
    g[0] = y[0] - p[3]  # rising: the impact
    # falling: at the stop moving towards it, or else at the top of the motion short of it
    # (m): it changes sign over a step that crossed the stop and came back, whose ends the
    # impact's own function g[0] sees on one side only, and its first zero is the impact
    g[2] = min(y[1] / omega, p[3] - y[0])
    if aux[STICKING] != 0.0 and aux[RELEASE] > 0.0:
        # rising at the release time: the time to it, measured by the forcing's static
        # displacement F / k advancing at omega (m), linear in t so that no step can miss it
        g[1] = (t - aux[RELEASE]) * force * omega / k
    else:
        g[1] = FREE


@njit(cache=True)
def release_time(t, p):
    """The time (s) at or after ``t`` where the forcing stops pressing the resting mass on the
    stop: the next ``omega t' = a (mod 2 pi)`` with ``cos a = k g / F``; -1 if it never does
    (``k g <= -F``)."""
    k, gap, force, omega = p[2], p[3], p[5], p[6]
    if force <= 0.0 or k * gap <= -force:
        return -1.0
    a = math.acos(min(k * gap / force, 1.0))
    phase = omega * t
    phase -= 2.0 * math.pi * math.floor((phase - a) / (2.0 * math.pi))  # in [a, a + 2 pi)
    return t + (a + 2.0 * math.pi - phase) / omega if phase > a else t


@njit(cache=True)
def _impact(t, y, p, aux):
    """Newton's restitution law at the stop; the end of a chattering sequence where the rebound
    is slower than ``rest_speed`` while the forcing presses the mass on the stop."""
    stiffness, gap, r, force, omega, rest = p[2], p[3], p[4], p[5], p[6], p[7]
    y[0] = gap
    rebound = -r * y[1]
    if abs(rebound) < rest and force * math.cos(omega * t) > stiffness * gap:
        y[1] = 0.0  # at rest on the stop
        aux[STICKING] = 1.0
        aux[RELEASE] = release_time(t, p)
    else:
        y[1] = rebound


@njit(cache=True)
def apply_event(k, t, y, p, ip, aux, work):
    if k == 1:  # the forcing lets the resting mass go
        aux[STICKING] = 0.0
        aux[RELEASE] = 0.0
    elif k == 0 or (y[1] > 0.0 and y[0] >= p[3] and aux[STICKING] == 0.0):
        # event 0, or event 2 where it fires at the stop moving towards it (an impact that
        # lies between two step ends) rather than at a top short of it
        _impact(t, y, p, aux)
    return 0


@register
class ImpactOscillator(Model):
    """Harmonically forced linear oscillator with a rigid stop at distance g and restitution r."""

    name = "impact_oscillator"
    description = (
        "Forced linear oscillator m x'' + c x' + k x = F cos(omega t) for x < g with a rigid "
        "stop at x = g: v -> -r v at impact (Newton's restitution law), resting on the stop "
        "where a chattering sequence ends"
    )
    reference = (
        "Shaw & Holmes (1983); Nordmark (1991), J. Sound Vib. 145:279; Budd & Dux (1994); "
        "di Bernardo et al. (2008), Ch. 2 and 4"
    )
    event_units = "m"  # x - g; the time to the release times F omega / k; min(v / omega, g - x)
    parameters = (
        Parameter("mass", 1.0, "kg", "mass", lower=0.0, lower_open=True),
        Parameter("damping", 2.5, "N s m-1", "viscous damping coefficient c", lower=0.0),
        Parameter("stiffness", 1.0, "N m-1", "spring stiffness k", lower=0.0, lower_open=True),
        Parameter("gap", 0.17, "m", "distance g from the rest position to the stop"),
        Parameter("restitution", 0.8, "1", "coefficient of restitution r", lower=0.0, upper=1.0),
        Parameter("force", 1.0, "N", "forcing amplitude F", lower=0.0),
        Parameter("omega", 2.1, "rad s-1", "forcing angular frequency", lower=0.0, lower_open=True),
        Parameter(
            "rest_speed",
            1e-6,
            "m s-1",
            "rebound speed below which the mass comes to rest on the stop while pressed on it",
            lower=0.0,
            lower_open=True,
        ),
        Parameter("x0", 0.0, "m", "initial displacement (at most the gap)"),
        Parameter("v0", 0.0, "m s-1", "initial velocity"),
    )
    fixed_states = (
        Quantity("x", "m", "displacement", rate="v"),
        Quantity("v", "m s-1", "velocity"),
    )
    fixed_outputs = (Quantity("sticking", "1", "1 while the mass rests on the stop, else 0"),)
    forcing_frequency = "omega"

    def problem(self, params, effects, initial, requested):
        names = ("mass", "damping", "stiffness", "gap", "restitution", "force", "omega")
        p = np.array([params[k] for k in names] + [params["rest_speed"]], dtype=float)
        x0 = float(initial.get("x", params["x0"]))
        if x0 > params["gap"]:
            key = "initial.x" if "x" in initial else "parameters.x0"
            raise SceneError(
                key,
                f"got {x0!r} m, beyond the stop at gap = {params['gap']!r} m; the mass starts "
                "at or before the stop (x <= gap)",
            )
        y0 = np.array([x0, float(initial.get("v", params["v0"]))])
        size = grazing_amplitude(params) or 1.0  # the free linear response's amplitude, m
        return Problem(
            hooks=__name__,
            states=self.fixed_states,
            y0=y0,
            p=p,
            aux0=np.zeros(2),
            event_direction=np.array([1, 1, -1]),
            # the stop is the one switching surface: the release is a time event, and event 2
            # only locates impacts between step ends (its turning points are no surface)
            event_surface=np.array([True, False, False]),
            atol_scale=np.array([size, params["omega"] * size]),
            t0=math.pi / params["omega"],  # forcing phase pi: the module's "Time origin"
        )

    def derive(self, problem, t, Y, AUX, requested):
        return {"sticking": AUX[:, STICKING]}
