"""Tangential (friction) force laws of clearance joints, shared by every mechanism.

- Modified Coulomb law of Ambrósio (2003), the paper's Eqs. (6)-(7): ``F_t = -c_f c_d(v_t) F_n
  sign(v_t)`` with the dynamic correction ``c_d`` ramping linearly from 0 at ``|v_t| = v0`` to 1
  at ``v1`` (m s-1), which removes the discontinuity of Coulomb's law at ``v_t = 0``.
- LuGre law of Canudas de Wit, Olsson, Åström & Lischinsky (1995, IEEE TAC 40:419), normalised by
  the normal force as in the paper's Eqs. (8)-(10): ``mu = s0 z + s1 z_dot + s2 v_t``, ``z_dot =
  v_t - s0 |v_t| z / g(v_t)``, ``g(v) = mu_k + (mu_s - mu_k) exp(-|v / v_s|^gamma)``; ``z`` is
  the mean bristle deflection (m), ``s0`` (m-1), ``s1`` and ``s2`` (s m-1).

Signs: ``v_t`` is the sliding velocity of the journal surface relative to the bearing surface
along the tangent ``t``; the returned force acts on the journal along ``t`` (the bearing gets the
opposite), so it opposes sliding.
"""

from __future__ import annotations

import math

from numba import njit

__all__ = ["coulomb_modified", "lugre_decay", "lugre_force", "stribeck"]


@njit(cache=True, inline="always")
def coulomb_modified(v_t, F_n, c_f, v0, v1):
    """Modified Coulomb friction force on the journal (Ambrósio 2003), N."""
    speed = abs(v_t)
    if speed < v0 or F_n <= 0.0:
        return 0.0
    c_d = 1.0 if speed > v1 else (speed - v0) / (v1 - v0)
    return -c_f * c_d * F_n * (1.0 if v_t > 0.0 else -1.0)


@njit(cache=True, inline="always")
def stribeck(v_t, mu_k, mu_s, v_s, gamma):
    """Stribeck curve g(v) of the LuGre model (dimensionless). The usual gamma = 2 as a
    product: the general power is several times slower on the solver's hot path, and
    correctly rounded, so that both give the same number."""
    r = abs(v_t / v_s)
    return mu_k + (mu_s - mu_k) * math.exp(-(r * r if gamma == 2.0 else r**gamma))


@njit(cache=True, inline="always")
def lugre_decay(v_t, sigma0, mu_k, mu_s, v_s, gamma):
    """Decay rate a = s0 |v_t| / g(v_t) of the bristle deflection (s-1): dz/dt = v_t - a z.

    It is the stiff part of the LuGre model (1e5-1e6 s-1 when sliding at 0.01-0.1 m/s with
    the nine-bar's parameters) and does not depend on z, so an implicit-explicit method can
    treat ``-a z`` implicitly at the cost of one division."""
    return sigma0 * abs(v_t) / stribeck(v_t, mu_k, mu_s, v_s, gamma)


@njit(cache=True, inline="always")
def lugre_force(v_t, z, z_dot, F_n, sigma0, sigma1, sigma2):
    """LuGre friction force on the journal, -mu F_n with mu = s0 z + s1 z_dot + s2 v_t, N."""
    if F_n <= 0.0:
        return 0.0
    return -(sigma0 * z + sigma1 * z_dot + sigma2 * v_t) * F_n
