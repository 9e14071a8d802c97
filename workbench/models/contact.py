"""Normal contact force laws, shared by every mechanism with clearance joints.

Two dissipative laws, chosen per scene by the effect ``contact`` (:data:`CONTACT_LAWS`): the
Lankarani-Nikravesh law (the default, the paper's), whose damping is scaled by the normal
velocity at the contact's onset and so carries that velocity as a discrete state through each
contact, and the Hunt-Crossley law with a material damping constant, which has no memory.

Lankarani & Nikravesh (1990, J. Mech. Des. 112:369), the paper's Eqs. (3)-(5):

    F_n = K delta^n [1 + 3 (1 - c_e^2) / 4 * delta_dot / delta_dot_minus]      (delta > 0)

with ``delta`` the penetration (m), ``delta_dot`` its rate (m s-1) and ``delta_dot_minus`` the
normal velocity at the onset of this contact (m s-1), held through the contact. ``K`` for a
journal of radius R2 in a bearing of radius R1 = R2 + c (internal contact, Eq. 4 with the concave
radius negative) is ``K = (4/3) E* sqrt(R1 R2 / c)`` with ``E* = 1 / (sigma1 + sigma2) / pi``,
``sigma_i = (1 - nu_i^2) / (pi E_i)`` (N m^-n).

Grazing contact (``delta_dot_minus -> 0``). The hysteresis term divides by the onset velocity.
LN derived it for a dissipated energy (1 - c_e^2) m delta_dot_minus^2 / 2 per impact, which
vanishes with the impact: a grazing contact deserves (almost) no damping. Two rules keep it so:
(1) the onset velocity is floored at ``v_floor`` (a model parameter, default 1e-4 m/s), which can
only *reduce* the damping of slower impacts, whose energy loss is below
(1 - c_e^2) m v_floor^2 / 2 anyway; (2) the ratio ``delta_dot / delta_dot_minus`` is clipped to
[-1, 1]: in a free impact |delta_dot| <= delta_dot_minus holds by energy, so the clip never acts
there, while it bounds the damping force by 3 (1 - c_e^2) / 4 times the elastic force when the
mechanism drives the journal into the wall faster than it arrived (the case that blows up
without it). Finally the force is never adhesive (F_n >= 0), as usual for LN (Flores et al. 2006).

Hunt & Crossley (1975, J. Appl. Mech. 42:440), in the form of Marhefka & Orin (1999, IEEE
Trans. Syst. Man Cybern. A 29:566), F_n = K delta^n + lambda delta^n delta_dot with
lambda = (3/2) alpha K:

    F_n = K delta^n (1 + (3/2) alpha delta_dot)                                 (delta > 0)

with a material damping constant ``alpha`` (s m-1): the damping depends on the present
penetration and its rate only, so the law has no memory and needs no event to set it; it
vanishes with delta, so the force is continuous at the onset and the end of a contact. Its
restitution depends on the impact velocity v: Hunt & Crossley's e = 1 - alpha v for small
alpha v (``alpha`` is the slope of e(v) at v -> 0; Simbody's HuntCrossleyForce documents the
same law and reading). The exact e(v) of a free impact follows because the equation of the
penetration, m delta_ddot = -K delta^n (1 + chi delta_dot) with chi = (3/2) alpha, is separable
in the phase plane: m v dv / (1 + chi v) = -K delta^n d delta integrates to

    chi v_out - ln(1 + chi v_out) = chi v_in - ln(1 + chi v_in),   e = -v_out / v_in,

independent of m, K and n (:func:`hunt_crossley_restitution`; the rebound velocity
v_out > -1 / chi, so the force stays compressive throughout a free impact). Where a mechanism
pulls the journal out faster than 1 / chi the damping would pull: the force is clipped at 0,
never adhesive, as for LN.
"""

from __future__ import annotations

import math

from numba import njit
from scipy.optimize import brentq

__all__ = [
    "CONTACT_HUNT_CROSSLEY",
    "CONTACT_LANKARANI_NIKRAVESH",
    "CONTACT_LAWS",
    "contact_elastic_energy",
    "hertz_internal_stiffness",
    "hunt_crossley",
    "hunt_crossley_damping",
    "hunt_crossley_restitution",
    "lankarani_nikravesh",
    "onset_velocity",
]

CONTACT_LANKARANI_NIKRAVESH = 0
CONTACT_HUNT_CROSSLEY = 1
#: the values of the effect ``contact`` and the code of each in the compiled parameter blocks
CONTACT_LAWS = {
    "lankarani_nikravesh": CONTACT_LANKARANI_NIKRAVESH,
    "hunt_crossley": CONTACT_HUNT_CROSSLEY,
}


def hertz_internal_stiffness(
    bearing_radius: float, clearance: float, youngs_modulus: float, poisson_ratio: float
) -> float:
    """Stiffness K of a journal in a bearing of the same material (Eq. 4), N m^-1.5.

    Parameters
    ----------
    bearing_radius : float
        R1, m.
    clearance : float
        c = R1 - R2, m (0 < c < R1).
    youngs_modulus : float
        E, Pa (both bodies).
    poisson_ratio : float
        nu (both bodies).

    Examples
    --------
    >>> round(hertz_internal_stiffness(0.010, 0.5e-3, 207e9, 0.3) / 1e10, 2)
    6.61
    """
    r2 = bearing_radius - clearance
    e_star = youngs_modulus / (2.0 * (1.0 - poisson_ratio**2))
    return 4.0 / 3.0 * e_star * math.sqrt(bearing_radius * r2 / clearance)


@njit(cache=True, inline="always")
def _power(delta, n):
    """delta**n for delta > 0; Hertz's n = 1.5 as delta * sqrt(delta), several times faster
    than the general power on the solver's hot path."""
    if n == 1.5:
        return delta * math.sqrt(delta)
    return delta**n


@njit(cache=True, inline="always")
def lankarani_nikravesh(delta, delta_dot, delta_dot_minus, K, n, c_e, v_floor):
    """Normal force of the Lankarani–Nikravesh law with the grazing rules above, N.

    ``delta`` penetration (m), ``delta_dot`` its rate (m s-1), ``delta_dot_minus`` onset
    velocity (m s-1), ``K`` (N m^-n), ``n`` exponent, ``c_e`` restitution, ``v_floor`` (m s-1).
    Returns (F_n, damping part of F_n), both 0 for ``delta <= 0``.
    """
    if delta <= 0.0:
        return 0.0, 0.0
    elastic = K * _power(delta, n)
    ratio = delta_dot / max(delta_dot_minus, v_floor)
    if ratio > 1.0:
        ratio = 1.0
    elif ratio < -1.0:
        ratio = -1.0
    damping = elastic * 0.75 * (1.0 - c_e * c_e) * ratio
    total = elastic + damping
    if total < 0.0:
        return 0.0, -elastic
    return total, damping


@njit(cache=True, inline="always")
def hunt_crossley(delta, delta_dot, K, n, alpha):
    """Normal force of the Hunt-Crossley law, K delta^n (1 + 1.5 alpha delta_dot), N.

    ``delta`` penetration (m), ``delta_dot`` its rate (m s-1), ``K`` (N m^-n), ``n`` exponent,
    ``alpha`` material damping constant (s m-1). Returns (F_n, damping part of F_n), both 0 for
    ``delta <= 0``; F_n >= 0 (never adhesive).
    """
    if delta <= 0.0:
        return 0.0, 0.0
    elastic = K * _power(delta, n)
    damping = elastic * 1.5 * alpha * delta_dot
    total = elastic + damping
    if total < 0.0:
        return 0.0, -elastic
    return total, damping


def hunt_crossley_restitution(alpha: float, velocity: float) -> float:
    """Coefficient of restitution of a free impact under the Hunt-Crossley law (exact).

    Parameters
    ----------
    alpha : float
        Material damping constant, s m-1 (>= 0).
    velocity : float
        Normal impact velocity, m s-1 (> 0).

    Returns
    -------
    float
        e = -v_out / v_in from chi v_out - ln(1 + chi v_out) = chi v_in - ln(1 + chi v_in),
        chi = 1.5 alpha (the module docstring); 1 - alpha v to first order in alpha v.

    Examples
    --------
    >>> round(hunt_crossley_restitution(0.1, 0.01), 6)  # 1 - alpha v + (alpha v)^2
    0.999001
    >>> round(hunt_crossley_restitution(0.111, 1.0), 3)
    0.9
    """
    a = 1.5 * alpha * velocity
    if a <= 0.0:
        return 1.0
    level = _x_minus_log1p(a)  # at the impact, > 0
    # the rebound b = chi v_out in (-1, 0) as b = expm1(-s), s = -ln(1 + b) in (0, level + 2),
    # where b - ln(1 + b) = b + s
    s = brentq(lambda s: _rebound_level(s) - level, 0.0, level + 2.0, xtol=1e-300, rtol=1e-15)
    return -math.expm1(-s) / a


def _x_minus_log1p(x: float) -> float:
    """x - ln(1 + x) for x > -1, to full relative precision also for small |x| (its series
    x^2/2 - x^3/3 + ..., where the difference would cancel)."""
    if abs(x) < 0.1:
        return sum((-x) ** k / k for k in range(40, 1, -1))
    return x - math.log1p(x)


def _rebound_level(s: float) -> float:
    """b - ln(1 + b) for b = expm1(-s) (s >= 0), accurate for small and large s."""
    b = math.expm1(-s)
    return _x_minus_log1p(b) if abs(b) < 0.1 else b + s


def hunt_crossley_damping(restitution: float, velocity: float) -> float:
    """The Hunt-Crossley damping constant alpha (s m-1) whose free impact at ``velocity``
    (m s-1, > 0) rebounds with ``restitution`` (0 < e <= 1): the inverse of
    :func:`hunt_crossley_restitution`.

    Examples
    --------
    >>> round(hunt_crossley_damping(0.9, 1.0), 4)  # steel's c_e = 0.9 read at 1 m/s
    0.111
    """
    if restitution >= 1.0:
        return 0.0
    # e(alpha) falls from 1 to 0 as alpha v grows; 1 - e = alpha v to first order
    upper = 2.0 / (restitution * velocity)  # e(chi v) < 1 / (chi v) since v_out > -1 / chi
    return brentq(
        lambda alpha: hunt_crossley_restitution(alpha, velocity) - restitution,
        0.0,
        upper,
        xtol=1e-300,
        rtol=1e-15,
    )


@njit(cache=True, inline="always")
def contact_elastic_energy(delta, K, n):
    """Elastic energy stored in a contact, K delta^(n+1) / (n+1), J (0 out of contact)."""
    if delta <= 0.0:
        return 0.0
    return K * delta * _power(delta, n) / (n + 1.0)


@njit(cache=True, inline="always")
def onset_velocity(x, y, vx, vy):
    """Normal velocity (m s-1) held through a contact from its onset, for the clearance vector
    (x, y) (m) and its rate (m s-1): at least 1e-300, so that "in contact" (aux > 0) holds even
    for a grazing onset, where the impact-velocity floor of the LN damping then applies."""
    return max((x * vx + y * vy) / math.sqrt(x * x + y * y), 1e-300)
