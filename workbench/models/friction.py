"""Tangential (friction) force laws of clearance joints, shared by every mechanism.

- Modified Coulomb law of Ambrósio (2003), the paper's Eqs. (6)-(7): ``F_t = -c_f c_d(v_t) F_n
  sign(v_t)`` with the dynamic correction ``c_d`` ramping linearly from 0 at ``|v_t| = v0`` to 1
  at ``v1`` (m s-1), which removes the discontinuity of Coulomb's law at ``v_t = 0``.
- LuGre law of Canudas de Wit, Olsson, Åström & Lischinsky (1995, IEEE TAC 40:419), normalised by
  the normal force as in the paper's Eqs. (8)-(10): ``mu = s0 z + s1(v_t) z_dot + s2 v_t``,
  ``z_dot = v_t - s0 |v_t| z / g(v_t)``, ``g(v) = mu_k + (mu_s - mu_k) exp(-|v / v_s|^gamma)``;
  ``z`` is the mean bristle deflection (m), ``s0`` (m-1), ``s1`` and ``s2`` (s m-1), and the
  friction force is ``F_t = -mu F_n``. The bristle damping decays with the sliding speed as
  Olsson, Åström, Canudas de Wit, Gäfvert & Lischinsky (1998, Eur. J. Control 4:176) propose,
  ``s1(v) = s1 exp(-(v / v_d)^2)`` (:func:`lugre_damping`; ``v_d = 0`` keeps it constant, the
  paper's form).

The choice of ``s1`` (the parameter documentation of :mod:`workbench.models._clearance` quotes
this). Normalised by ``F_n``, the law keeps the force form's passivity condition of Barabanov &
Ortega (2000, IEEE TAC 45:830; Åström & Canudas de Wit 2008, IEEE Control Syst. Mag. 28(6):101,
Eq. 7): with a *constant* damping the map v_t -> F_t is passive if and only if ``s1 <= s2 mu_k /
(mu_s - mu_k)`` (:func:`lugre_passive_damping`: 0.2 s m-1 with the paper's mu_k, mu_s, s2), a
bound independent of F_n. The paper's ``s1 = sqrt(s0) = 316 s m-1`` is the value of force-form
examples (a 1-kg block: ``sigma1 = sqrt(sigma0 m)``, damping ratio 1/2), 1 600 times that bound.
It is not passive: where the bristles are far from their steady deflection (a contact onset,
where they start at z = 0, or a reversal of sliding) ``z_dot ~ v_t`` and ``mu ~ 316 v_t``, 25 at
0.08 m/s. With the velocity-dependent damping the same ``s1`` acts only in pre-sliding
(``|v_t| <~ v_d``), where Canudas de Wit et al. put it, and the law is passive whenever
``s1 v_d <= 4 sqrt(2 e) mu_k`` (about 9.33 mu_k; 0.466 with the paper's mu_k, against
``316 x 1e-3 = 0.316`` for ``v_d = v_s``): with the storage function ``s0 z^2 / 2`` the power
``mu v - s0 z z_dot = a s0 z^2 - s1(v) a v z + (s1(v) + s2) v^2`` (``a = s0 |v| / g(v)``) is a
quadratic form in z that is non-negative for every z when ``s1(v)^2 |v| <= 4 g(v) (s1(v) +
s2)``, which ``s1(v) |v| <= 4 mu_k`` ensures, and ``max_v |v| exp(-(v / v_d)^2) = v_d /
sqrt(2 e)``. The defaults are therefore ``s1 = 316.2 s m-1`` with ``v_d = v_s = 1e-3 m s-1``.
Critical damping of the normalised bristle is no alternative: a mass m resting on the bristles
under F_n is a spring s0 F_n with the damping (s1 + s2) F_n, critically damped at ``s1 =
2 sqrt(s0 m / F_n) - s2``, which depends on the load: for m ~ 1 kg and the nine-bar's contact
forces of 10 N to 7 kN it spans about 7-200 s m-1, not one constant of the law. The pre-sliding
damping the default keeps lies at or above it there (overdamped, no ringing of the bristles),
while the largest passive constant damping, 0.2 s m-1, leaves them nearly undamped
(damping ratio 0.003-0.08).

Signs: ``v_t`` is the sliding velocity of the journal surface relative to the bearing surface
along the tangent ``t``; the returned force acts on the journal along ``t`` (the bearing gets the
opposite), so it opposes sliding.
"""

from __future__ import annotations

import math

from numba import njit

__all__ = [
    "coulomb_modified",
    "lugre_coefficient",
    "lugre_damping",
    "lugre_decay",
    "lugre_envelope",
    "lugre_force",
    "lugre_passive_damping",
    "lugre_passive_damping_velocity",
    "stribeck",
]


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
def lugre_damping(v_t, sigma1, v_d):
    """Bristle damping s1(v_t) = s1 exp(-(v_t / v_d)^2) (s m-1) of Olsson et al. (1998): the
    pre-sliding damping s1 (s m-1), fading once the surfaces slide faster than v_d (m s-1);
    ``v_d = 0`` gives the constant s1 of Canudas de Wit et al. (1995)."""
    if v_d <= 0.0:
        return sigma1
    r = v_t / v_d
    return sigma1 * math.exp(-(r * r))


@njit(cache=True, inline="always")
def lugre_coefficient(v_t, z, z_dot, sigma0, sigma1, sigma2):
    """Friction coefficient mu = s0 z + s1 z_dot + s2 v_t of the LuGre law (dimensionless):
    bristle deflection z (m) and its rate z_dot (m s-1), sliding velocity v_t (m s-1), s0
    (m-1), the damping s1 in effect (s m-1; see :func:`lugre_damping`) and s2 (s m-1)."""
    return sigma0 * z + sigma1 * z_dot + sigma2 * v_t


@njit(cache=True, inline="always")
def lugre_force(v_t, z, z_dot, F_n, sigma0, sigma1, sigma2):
    """LuGre friction force on the journal, -mu F_n (:func:`lugre_coefficient`), N."""
    if F_n <= 0.0:
        return 0.0
    return -lugre_coefficient(v_t, z, z_dot, sigma0, sigma1, sigma2) * F_n


@njit(cache=True, inline="always")
def lugre_envelope(v_t, mu_s, sigma2):
    """The friction coefficient a LuGre law may reach (dimensionless): 2 mu_s + s2 |v_t|.

    At steady sliding mu = g(v) sign(v) + s2 v never exceeds mu_s + s2 |v|; the bristle
    dynamics may overshoot the static level (break-away, frictional memory), and twice the
    static coefficient is taken as the most it can do (issue 29). A run reports the time
    beyond this envelope; a physical parameter set keeps it 0."""
    return 2.0 * mu_s + sigma2 * abs(v_t)


def lugre_passive_damping(mu_k: float, mu_s: float, sigma2: float) -> float:
    """The largest constant bristle damping s1 (s m-1) for which the LuGre law is passive:
    ``s2 mu_k / (mu_s - mu_k)`` (Barabanov & Ortega 2000; Åström & Canudas de Wit 2008,
    Eq. 7), with s2 in s m-1; infinite when mu_s <= mu_k (no Stribeck drop)."""
    return math.inf if mu_s <= mu_k else sigma2 * mu_k / (mu_s - mu_k)


def lugre_passive_damping_velocity(mu_k: float, sigma1: float) -> float:
    """The largest v_d (m s-1) of the velocity-dependent damping s1 exp(-(v / v_d)^2) for
    which the LuGre law is passive by the storage function s0 z^2 / 2 (module docstring):
    ``4 sqrt(2 e) mu_k / s1``, with s1 in s m-1; infinite for s1 = 0."""
    return math.inf if sigma1 <= 0.0 else 4.0 * math.sqrt(2.0 * math.e) * mu_k / sigma1
