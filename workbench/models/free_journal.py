"""A free journal inside a fixed bearing: the test model of the clearance-contact laws.

A point mass m (the journal) moves in the plane inside a fixed bearing of radial clearance c;
beyond e = |r| > c it feels the normal force of :mod:`workbench.models.contact`, by the law the
effect ``contact`` names: Lankarani–Nikravesh (the default) with the onset velocity held by the
same contact-onset event as the mechanisms, or Hunt–Crossley, which holds nothing. Launched
radially, its rebound speed over its impact speed is the *effective* coefficient of restitution:
LN reproduces c_e for c_e near 1 (Lankarani & Nikravesh 1990; Flores et al. 2011 compare models),
Hunt–Crossley gives the exact e(alpha v) of :func:`workbench.models.contact.
hunt_crossley_restitution`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from workbench.models import register
from workbench.models._base import EVENT_INSIDE_STEP, Model, Parameter, Problem, Quantity
from workbench.models._clearance import CONTACT_EFFECT, contact_law, contact_parameters
from workbench.models.contact import (
    CONTACT_HUNT_CROSSLEY,
    CONTACT_LAWS,
    hertz_internal_stiffness,
    hunt_crossley,
    lankarani_nikravesh,
    onset_velocity,
)

# p: mass, clearance, K, n, c_e, v_floor, contact law (CONTACT_LAWS code), alpha
# aux: [held onset velocity (LN only), normal velocity at the last onset (a record)]


@njit(cache=True)
def rhs(t, y, p, ip, aux, work, dydt):
    x, yy, vx, vy = y[0], y[1], y[2], y[3]
    e = math.sqrt(x * x + yy * yy)
    fx = 0.0
    fy = 0.0
    delta = e - p[1]
    held = aux[0] if aux.size == 2 else 0.0  # Hunt-Crossley holds none
    if delta > 0.0:
        nx, ny = x / e, yy / e
        ddot = nx * vx + ny * vy
        if p[6] == CONTACT_HUNT_CROSSLEY:
            fn, _ = hunt_crossley(delta, ddot, p[2], p[3], p[7])
        else:
            onset = held if held > 0.0 else ddot
            fn, _ = lankarani_nikravesh(delta, ddot, onset, p[2], p[3], p[4], p[5])
        fx, fy = -fn * nx, -fn * ny
    dydt[0] = vx
    dydt[1] = vy
    dydt[2] = fx / p[0]
    dydt[3] = fy / p[0]
    if delta > 0.0 and held == 0.0:
        return EVENT_INSIDE_STEP  # in contact, with no onset velocity held
    return 0


@njit(cache=True)
def event_values(t, y, p, ip, aux, work, g):
    d = math.sqrt(y[0] * y[0] + y[1] * y[1]) - p[1]
    g[0] = d
    g[1] = d


@njit(cache=True)
def apply_event(k, t, y, p, ip, aux, work):
    if k == 0:
        v = onset_velocity(y[0], y[1], y[2], y[3])
        aux[aux.size - 1] = v
        if aux.size == 2:
            aux[0] = v
    elif aux.size == 2:
        aux[0] = 0.0
    return 0


# the contact parameters of the mechanisms' clearance joints that a free journal has
_CONTACT = (
    "clearance",
    "bearing_radius",
    "youngs_modulus",
    "poisson_ratio",
    "contact_exponent",
    "restitution",
    "impact_velocity_floor",
    "hunt_crossley_damping",
)


@register
class FreeJournal(Model):
    """Free journal in a fixed bearing with Lankarani–Nikravesh or Hunt–Crossley contact."""

    name = "free_journal"
    description = "Point-mass journal moving freely inside a fixed bearing (LN or HC contact)"
    reference = (
        "Lankarani & Nikravesh (1990), J. Mech. Des. 112:369; Hunt & Crossley (1975), "
        "J. Appl. Mech. 42:440"
    )
    parameters = (
        Parameter("mass", 0.8, "kg", "journal mass", lower=0.0, lower_open=True),
        *(p for p in contact_parameters(0.5e-3, 0.0) if p.name in _CONTACT),
        Parameter("speed", 0.5, "m s-1", "initial radial speed (along +x from the centre)"),
    )
    effects = (CONTACT_EFFECT,)
    fixed_states = (
        Quantity("x", "m", "journal centre x", rate="vx"),
        Quantity("y", "m", "journal centre y", rate="vy"),
        Quantity("vx", "m s-1", "journal velocity x"),
        Quantity("vy", "m s-1", "journal velocity y"),
    )
    fixed_outputs = (
        Quantity("onset_velocity", "m s-1", "normal velocity at the last contact onset"),
    )

    def problem(self, params, effects, initial, requested):
        c = params["clearance"]
        k = hertz_internal_stiffness(
            params["bearing_radius"], c, params["youngs_modulus"], params["poisson_ratio"]
        )
        law = CONTACT_LAWS[contact_law(effects)]
        p = np.array(
            [
                params["mass"],
                c,
                k,
                params["contact_exponent"],
                params["restitution"],
                params["impact_velocity_floor"],
                law,
                params["hunt_crossley_damping"],
            ]
        )
        y0 = np.array([initial.get(s.name, 0.0) for s in self.fixed_states])
        if "vx" not in initial:
            y0[2] = params["speed"]
        # the held onset velocity feeds back on the flow (m s-1; LN only); the last discrete
        # state is a record
        held = law != CONTACT_HUNT_CROSSLEY
        return Problem(
            hooks=__name__,
            states=self.fixed_states,
            y0=y0,
            p=p,
            aux0=np.array([0.0, np.nan] if held else [np.nan]),
            event_direction=np.array([1, -1]),
            atol_scale=np.array([c, c, c * 1e3, c * 1e3]),
            aux_scale=np.array([c * 1e3, np.inf] if held else [np.inf]),
        )

    def derive(self, problem, t, Y, AUX, requested):
        return {"onset_velocity": AUX[:, -1]}
