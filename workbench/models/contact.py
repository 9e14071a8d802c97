"""Normal contact force laws, shared by every mechanism with clearance joints.

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
"""

from __future__ import annotations

import math

from numba import njit

__all__ = [
    "contact_elastic_energy",
    "hertz_internal_stiffness",
    "lankarani_nikravesh",
    "onset_velocity",
]


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
