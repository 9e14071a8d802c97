"""Compiled building blocks of a mechanism in reduced (Lagrange) coordinates with clearance joints.

A mechanism model supplies its closed-form kinematics: per body b the centroid position and
angle ``pos[b] = (x, y, phi)``, their Jacobian ``J[b, :, k]`` with respect to the coordinates q
and the bias accelerations ``gam[b]`` (the accelerations at qdd = 0). From these, d'Alembert's
principle gives the reduced equations (e.g. Nikravesh 1988, *Computer-Aided Analysis of
Mechanical Systems*, Ch. 13; the nine-bar's are Chen et al. 2019, Sec. 3)

    M qdd + h = Q,   M = sum_b m_b Jc^T Jc + I_b Jphi^T Jphi,   h = sum_b m_b Jc^T gam_c + ...

and a clearance joint adds the Lankarani-Nikravesh normal force and a friction force at the
material contact points of journal and bearing (:func:`clearance_joint`). Every model with
clearance joints (``ninebar``, ``slider_crank``) uses these functions, so the contact mechanics
exist once. Units: SI throughout (m, rad, kg, N, J).
"""

from __future__ import annotations

import math

from numba import njit

from workbench.models.contact import contact_elastic_energy, lankarani_nikravesh
from workbench.models.friction import coulomb_modified, lugre_decay, lugre_force

FRICTION_NONE = 0
FRICTION_COULOMB = 1
FRICTION_LUGRE = 2

# failure codes a mechanism's right-hand side returns (messages: _clearance.failure_messages)
CODE_ASSEMBLY = 1  # the mechanism cannot be assembled (a loop does not close)
CODE_PENETRATION = 2  # penetration beyond parameters.max_penetration
CODE_SINGULAR = 3  # reduced mass matrix not positive definite
CODE_NONFINITE = 4  # non-finite force or acceleration

# layout of the friction parameter block ``fp`` (float64[N_FP]) passed to clearance_joint
FP_CF = 0  # Coulomb coefficient c_f
FP_V0 = 1  # Coulomb thresholds v0, v1, m s-1
FP_V1 = 2
FP_MUK = 3  # LuGre mu_k, mu_s
FP_MUS = 4
FP_S0 = 5  # LuGre sigma0 (m-1), sigma1, sigma2 (s m-1)
FP_S1 = 6
FP_S2 = 7
FP_VS = 8  # Stribeck velocity, m s-1
FP_GAM = 9  # Stribeck exponent
N_FP = 10


@njit(cache=True)
def cholesky_solve(M, b, n, L):
    """Solve M x = b in place in b for a small symmetric positive definite M (leading n x n),
    with L an n x n (or larger) scratch array for the factor. Returns False if M is not
    positive definite."""
    for i in range(n):
        for j in range(i + 1):
            s = M[i, j]
            for k in range(j):
                s -= L[i, k] * L[j, k]
            if i == j:
                if s <= 0.0:
                    return False
                L[i, i] = math.sqrt(s)
            else:
                L[i, j] = s / L[j, j]
    for i in range(n):
        s = b[i]
        for k in range(i):
            s -= L[i, k] * b[k]
        b[i] = s / L[i, i]
    for i in range(n - 1, -1, -1):
        s = b[i]
        for k in range(i + 1, n):
            s -= L[k, i] * b[k]
        b[i] = s / L[i, i]
    return True


@njit(cache=True)
def all_finite(values, n):
    """Whether values[:n] are all finite: one test on their sum (NaN and inf propagate), the
    element-wise test only to confirm when the sum is not finite (it may overflow)."""
    total = 0.0
    for i in range(n):
        total += values[i]
    if math.isfinite(total):
        return True
    for i in range(n):
        if not math.isfinite(values[i]):
            return False
    return True


@njit(cache=True)
def generalised_force(Q, J, pos, b, px, py, fx, fy):
    """Add the generalised force of force (fx, fy) N acting at point (px, py) m of body b."""
    arm = (px - pos[b, 0]) * fy - (py - pos[b, 1]) * fx
    for k in range(J.shape[2]):
        Q[k] += J[b, 0, k] * fx + J[b, 1, k] * fy + J[b, 2, k] * arm


@njit(cache=True)
def point_velocity(J, pos, b, px, py, qd):
    """Velocity (m s-1) of the material point (px, py) of body b."""
    vx = 0.0
    vy = 0.0
    w = 0.0
    for k in range(J.shape[2]):
        vx += J[b, 0, k] * qd[k]
        vy += J[b, 1, k] * qd[k]
        w += J[b, 2, k] * qd[k]
    return vx - w * (py - pos[b, 1]), vy + w * (px - pos[b, 0])


@njit(cache=True)
def assemble(J, gam, pos, qd, mass, inertia, gx, gy, M, h, Q):
    """Mass matrix M, bias force h and gravity force Q (overwritten) of the bodies.

    ``mass[b]`` (kg) and ``inertia[b]`` (centroidal, kg m2); gravity (gx, gy) m s-2. Returns
    (kinetic energy, gravity potential energy), J.
    """
    nq = J.shape[2]
    for k in range(nq):
        h[k] = 0.0
        Q[k] = 0.0
        for l in range(nq):
            M[k, l] = 0.0
    ke = 0.0
    pe = 0.0
    for b in range(J.shape[0]):
        m = mass[b]
        inert = inertia[b]
        vx = 0.0
        vy = 0.0
        w = 0.0
        for k in range(nq):
            vx += J[b, 0, k] * qd[k]
            vy += J[b, 1, k] * qd[k]
            w += J[b, 2, k] * qd[k]
        ke += 0.5 * (m * (vx * vx + vy * vy) + inert * w * w)
        pe -= m * (gx * pos[b, 0] + gy * pos[b, 1])
        for k in range(nq):
            h[k] += m * (J[b, 0, k] * gam[b, 0] + J[b, 1, k] * gam[b, 1])
            h[k] += inert * J[b, 2, k] * gam[b, 2]
            Q[k] += m * (J[b, 0, k] * gx + J[b, 1, k] * gy)
            for l in range(k, nq):
                v = m * (J[b, 0, k] * J[b, 0, l] + J[b, 1, k] * J[b, 1, l])
                M[k, l] += v + inert * J[b, 2, k] * J[b, 2, l]
    for k in range(nq):
        for l in range(k):
            M[k, l] = M[l, k]
    return ke, pe


@njit(cache=True)
def clearance_joint(
    Q, J, pos, qd, bj, bb, bcx, bcy, x, y, vx, vy, onset, r1, r2, c, K, n, ce, vfloor,
    friction, fp, z, hg,
):  # fmt: skip
    """Contact and friction of one revolute clearance joint; adds their generalised forces to Q.

    Parameters: journal body ``bj``, bearing body ``bb`` with its centre at (bcx, bcy) m;
    (x, y) the clearance vector (journal centre minus bearing centre, m; the same numbers the
    model's contact events see) and (vx, vy) its rate, m s-1; ``onset`` the normal velocity
    held since the contact began (m s-1, 0 if not located); bearing and journal radii r1, r2
    and clearance c (m); contact stiffness K (N m^-n), exponent n, restitution ce,
    impact-velocity floor vfloor (m s-1); ``friction`` (FRICTION_*), its parameter block
    ``fp`` (FP_* layout), the LuGre bristle deflection z (m) and ``hg`` (s): h gamma of an
    implicit stage of ARK548 (0 otherwise), for which z is the stage's known part B and is
    replaced by the solution of z = B + hg (vt - a z) (see :mod:`workbench.solver._kernel`).

    Returns (e, delta, ddot, fn, ft, vt, z, zdot, decay, p_diss, e_el): eccentricity and
    penetration (m), penetration rate (m s-1), normal and friction force on the journal (N,
    friction along t = (-ny, nx)), sliding velocity (m s-1), the bristle deflection used (m),
    its rate (m s-1) and decay rate a in zdot = vt - a z (s-1; both 0 out of contact, where the
    bristles are frozen), dissipated power (W) and stored elastic energy (J). The
    forces act at the material contact points (journal and bearing surfaces along n), so
    friction also exerts moments on both bodies.
    """
    e = math.sqrt(x * x + y * y)
    delta = e - c
    if delta <= 0.0 or e == 0.0:
        return e, delta, 0.0, 0.0, 0.0, 0.0, z, 0.0, 0.0, 0.0, 0.0
    nx = x / e
    ny = y / e
    ddot = nx * vx + ny * vy
    fn, fdamp = lankarani_nikravesh(delta, ddot, onset if onset > 0.0 else ddot, K, n, ce, vfloor)
    jx = bcx + x + r2 * nx
    jy = bcy + y + r2 * ny
    bx = bcx + r1 * nx
    by = bcy + r1 * ny
    vjx, vjy = point_velocity(J, pos, bj, jx, jy, qd)
    vbx, vby = point_velocity(J, pos, bb, bx, by, qd)
    tx = -ny
    ty = nx
    vt = (vjx - vbx) * tx + (vjy - vby) * ty
    ft = 0.0
    zdot = 0.0
    decay = 0.0
    if friction == FRICTION_COULOMB:
        ft = coulomb_modified(vt, fn, fp[FP_CF], fp[FP_V0], fp[FP_V1])
    elif friction == FRICTION_LUGRE and fn > 0.0:
        decay = lugre_decay(vt, fp[FP_S0], fp[FP_MUK], fp[FP_MUS], fp[FP_VS], fp[FP_GAM])
        z = (z + hg * vt) / (1.0 + hg * decay)  # exact for hg = 0
        zdot = vt - decay * z  # the bristle equation, Eq. (9)
        ft = lugre_force(vt, z, zdot, fn, fp[FP_S0], fp[FP_S1], fp[FP_S2])
    # force on the journal: the normal force pushes it back towards the bearing centre
    fx = -fn * nx + ft * tx
    fy = -fn * ny + ft * ty
    generalised_force(Q, J, pos, bj, jx, jy, fx, fy)
    generalised_force(Q, J, pos, bb, bx, by, -fx, -fy)
    # power lost: normal damping + friction (relative sliding); the elastic energy is stored
    p_diss = fdamp * ddot - ft * vt
    return e, delta, ddot, fn, ft, vt, z, zdot, decay, p_diss, contact_elastic_energy(delta, K, n)
