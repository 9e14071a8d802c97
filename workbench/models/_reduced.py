"""Compiled building blocks of a mechanism in reduced (Lagrange) coordinates with clearance joints.

A mechanism model supplies its closed-form kinematics as *passes* (built from the Assur groups
of :mod:`workbench.models._assur`): flat tuples with, per body b, the centroid x, y (m) and angle
phi (rad) or their rates or accelerations, then per point its x, y. The Jacobian column k is
the velocity pass for a unit rate of coordinate k, the bias accelerations ``gam`` the
acceleration pass at qdd = 0. From these, d'Alembert's principle gives the reduced equations
(e.g. Nikravesh 1988, *Computer-Aided Analysis of Mechanical Systems*, Ch. 13; the nine-bar's
are Chen et al. 2019, Sec. 3)

    M qdd + h = Q,   M_kl = sum_b m_b Jc_k . Jc_l + I_b Jphi_k Jphi_l,
    h_k = sum_b m_b Jc_k . gam_c + I_b Jphi_k gam_phi,

and a clearance joint adds the Lankarani-Nikravesh normal force and a friction force at the
material contact points of journal and bearing (:func:`joint_forces`). Every model with
clearance joints (``ninebar``, ``slider_crank``) uses these functions, so the contact mechanics
and the body sums exist once, in two forms that share them:

- scalar functions inlined into each model's *lean* right-hand side (``inline="always"``: the
  integration's hot path stays in registers and computes only the free columns);
- array functions (:func:`assemble`, :func:`clearance_joint`) for the *record-time*
  evaluation, which fills every output (torques, energies, forces on every body) at the
  records and is the reference the lean right-hand sides are tested against.

The layouts of the parameter blocks that every mechanism shares (a clearance joint's, the
friction laws') and of the per-joint record are declared here (:mod:`workbench.models._layout`).
Units: SI throughout (m, rad, kg, N, J).
"""

from __future__ import annotations

import math

from numba import njit

from workbench.models._base import EVENT_INSIDE_STEP
from workbench.models._layout import layout
from workbench.models.contact import (
    contact_elastic_energy,
    lankarani_nikravesh,
    onset_velocity,
)
from workbench.models.friction import coulomb_modified, lugre_decay, lugre_force

FRICTION_NONE = 0
FRICTION_COULOMB = 1
FRICTION_LUGRE = 2

# failure codes a mechanism's right-hand side returns (messages: _clearance.failure_messages)
CODE_ASSEMBLY = 1  # the mechanism cannot be assembled (a loop does not close)
CODE_PENETRATION = 2  # penetration beyond parameters.max_penetration
CODE_SINGULAR = 3  # reduced mass matrix not positive definite
CODE_NONFINITE = 4  # non-finite force or acceleration

# the friction laws' parameters (one block per mechanism)
FRICTION = layout(
    "Friction",
    [
        ("cf", 1),  # Coulomb coefficient c_f
        ("v0", 1),  # Coulomb thresholds v0, v1, m s-1
        ("v1", 1),
        ("mu_k", 1),  # LuGre mu_k, mu_s
        ("mu_s", 1),
        ("sigma0", 1),  # LuGre sigma0 (m-1), sigma1, sigma2 (s m-1)
        ("sigma1", 1),
        ("sigma2", 1),
        ("v_s", 1),  # Stribeck velocity, m s-1
        ("gamma", 1),  # Stribeck exponent
    ],
)

# one clearance joint's parameters (one block per joint)
JOINT = layout(
    "Joint",
    [
        ("r1", 1),  # bearing radius, m
        ("r2", 1),  # journal radius, m
        ("c", 1),  # clearance, m
        ("k", 1),  # contact stiffness, N m^-n
        ("n", 1),  # contact exponent
        ("ce", 1),  # restitution
        ("dmax", 1),  # largest allowed penetration, m
        ("vfloor", 1),  # impact-velocity floor of the LN damping, m s-1
    ],
)

# what the record-time evaluation stores per clearance joint
JOINT_RECORD = layout(
    "JointRecord",
    [
        ("x", 1),  # clearance vector, m
        ("y", 1),
        ("vx", 1),  # its rate, m s-1
        ("vy", 1),
        ("e", 1),  # eccentricity, m
        ("delta", 1),  # e - c, m
        ("ddot", 1),  # penetration rate, m s-1
        ("fn", 1),  # normal force, N
        ("ft", 1),  # friction force on the journal along t, N
        ("vt", 1),  # sliding velocity, m s-1
        ("zdot", 1),  # bristle rate, m s-1
        ("pdiss", 1),  # dissipated power, W
        ("eel", 1),  # elastic contact energy, J
        ("decay", 1),  # decay rate of the LuGre bristle deflection in contact, s-1 (0 otherwise)
    ],
)


def index_fields(n_joints: int) -> list[tuple[str, int]]:
    """Fields of a mechanism's integer array ``ip`` that every mechanism has.

    ``has + j``: 1 if joint j has a clearance; ``slot + j``: index in y of joint j's clearance
    x (its y follows, the rates nf later), -1 if none; ``z + j``: index in y of joint j's
    bristle deflection, -1 if none; ``friction``: FRICTION_*; ``energy``: 1 if the energy
    quadratures are integrated; ``w``: index in y of the driver-work quadrature (the dissipated
    energy follows), -1 if none; ``nf``: number of free coordinates; ``free + i``: index in q
    of free coordinate i (-1 beyond nf). The free coordinates of joint j are the
    q[nd + 2 j], q[nd + 2 j + 1] after the nd driven ones.
    """
    return [
        ("has", n_joints),
        ("slot", n_joints),
        ("z", n_joints),
        ("friction", 1),
        ("energy", 1),
        ("w", 1),
        ("nf", 1),
        ("free", 2 * n_joints),
    ]


def record_fields(n_q: int, n_cranks: int, n_joints: int) -> list[tuple[str, int]]:
    """Fields of what a mechanism's record-time evaluation stores (its workspace's head):
    full qdd (driven entries 0), driving torques (N m), the per-joint records
    (JOINT_RECORD), slider position, velocity, acceleration (m, m s-1, m s-2), kinetic and
    potential energy (J), driver and dissipated power (W)."""
    return [
        ("qdd", n_q),
        ("tau", n_cranks),
        ("joint", n_joints * JOINT_RECORD.size),
        ("slider", 3),
        ("ke", 1),
        ("pe", 1),
        ("pdrive", 1),
        ("pdiss", 1),
    ]


def work_fields(n_q: int, n_bodies: int, n_points: int) -> list[tuple[str, int]]:
    """Fields of the scratch that follows the record in a mechanism's workspace (the hooks' work
    array): q, qd, the kinematics arrays of the record-time evaluation (see
    :func:`kinematic_arrays`), M, h, Q, and ``hg``, where the solver puts h gamma (s) of an
    implicit ARK548 stage (0 otherwise)."""
    return [
        ("q", n_q),
        ("qd", n_q),
        ("pos", 3 * n_bodies),
        ("pts", 2 * n_points),
        ("J", 3 * n_bodies * n_q),
        ("Jp", 2 * n_points * n_q),
        ("gam", 3 * n_bodies),
        ("gamp", 2 * n_points),
        ("vel", 3 * n_bodies),
        ("velp", 2 * n_points),
        ("M", n_q * n_q),
        ("h", n_q),
        ("Q", n_q),
        ("hg", 1),
    ]


# ================================================================================================
# scalar building blocks (inlined)
# ================================================================================================
@njit(cache=True, inline="always")
def body_product(m, inertia, ax, ay, aw, bx, by, bw):
    """m (a_c . b_c) + I a_phi b_phi of one body for two of its (x, y, phi) rate vectors:
    its entry of M_kl (two Jacobian columns), of h_k (a column and the bias acceleration) or
    of a generalised force (a column and a force (N) and moment (N m)), in SI units."""
    return m * (ax * bx + ay * by) + inertia * aw * bw


@njit(cache=True, inline="always")
def rigid_point_velocity(vx, vy, w, cx, cy, px, py):
    """Velocity (m s-1) of the material point (px, py) (m) of a body whose centroid (cx, cy)
    (m) moves at (vx, vy) (m s-1) while the body turns at w (rad s-1)."""
    return vx - w * (py - cy), vy + w * (px - cx)


@njit(cache=True, inline="always")
def moment_arm(px, py, cx, cy, fx, fy):
    """Moment (N m) about the centroid (cx, cy) of a force (fx, fy) (N) acting at (px, py)."""
    return (px - cx) * fy - (py - cy) * fx


@njit(cache=True, inline="always")
def joint_parameters(p, jb):
    """The JOINT block of p at offset ``jb`` as a tuple (in the JOINT layout's order)."""
    return (
        p[jb + JOINT.r1], p[jb + JOINT.r2], p[jb + JOINT.c], p[jb + JOINT.k], p[jb + JOINT.n],
        p[jb + JOINT.ce], p[jb + JOINT.dmax], p[jb + JOINT.vfloor],
    )  # fmt: skip


@njit(cache=True, inline="always")
def friction_parameters(p, fb):
    """The FRICTION block of p at offset ``fb`` as a tuple (in the FRICTION layout's order)."""
    return (
        p[fb + FRICTION.cf], p[fb + FRICTION.v0], p[fb + FRICTION.v1], p[fb + FRICTION.mu_k],
        p[fb + FRICTION.mu_s], p[fb + FRICTION.sigma0], p[fb + FRICTION.sigma1],
        p[fb + FRICTION.sigma2], p[fb + FRICTION.v_s], p[fb + FRICTION.gamma],
    )  # fmt: skip


@njit(cache=True, inline="always")
def joint_forces(x, y, vx, vy, onset, bcx, bcy, vj, vb, jp, fp, friction, z, hg):
    """Contact and friction forces of one revolute clearance joint.

    Parameters
    ----------
    x, y, vx, vy : float
        Clearance vector (journal centre minus bearing centre, m; the same numbers the model's
        contact events see) and its rate (m s-1).
    onset : float
        Normal velocity held since the contact began (m s-1; 0 if not located).
    bcx, bcy : float
        Bearing centre, m.
    vj, vb : tuple of 5 floats
        Journal and bearing bodies: centroid velocity (m s-1), angular velocity (rad s-1),
        centroid position (m).
    jp, fp : tuples of float
        The joint's parameters (JOINT layout) and the friction parameters (FRICTION layout),
        see :func:`joint_parameters`, :func:`friction_parameters`.
    friction : int
        FRICTION_*.
    z : float
        LuGre bristle deflection (m); in an implicit ARK548 stage its known part B.
    hg : float
        h gamma (s) of an implicit ARK548 stage, else 0: z is then replaced by the solution of
        z = B + hg (vt - a z) (see :mod:`workbench.solver._kernel`).

    Returns
    -------
    tuple
        (e, delta, ddot, fn, fdamp, ft, vt, z, zdot, decay, jx, jy, bx, by, fx, fy):
        eccentricity and penetration (m), penetration rate (m s-1), normal force and its damping
        part (N), friction force on the journal along t = (-ny, nx) (N), sliding velocity
        (m s-1), the bristle deflection used (m), its rate (m s-1) and decay rate a in
        zdot = vt - a z (s-1; both 0 out of contact, where the bristles are frozen), the
        material contact points of journal and bearing (m), and the force on the journal (N;
        the bearing gets the opposite). Out of contact the forces and points are 0.
    """
    e = math.sqrt(x * x + y * y)
    delta = e - jp[JOINT.c]
    if delta <= 0.0 or e == 0.0:
        return e, delta, 0.0, 0.0, 0.0, 0.0, 0.0, z, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    nx = x / e
    ny = y / e
    ddot = nx * vx + ny * vy
    fn, fdamp = lankarani_nikravesh(
        delta,
        ddot,
        onset if onset > 0.0 else ddot,
        jp[JOINT.k],
        jp[JOINT.n],
        jp[JOINT.ce],
        jp[JOINT.vfloor],
    )
    r1 = jp[JOINT.r1]
    r2 = jp[JOINT.r2]
    jx = bcx + x + r2 * nx
    jy = bcy + y + r2 * ny
    bx = bcx + r1 * nx
    by = bcy + r1 * ny
    vjx, vjy = rigid_point_velocity(vj[0], vj[1], vj[2], vj[3], vj[4], jx, jy)
    vbx, vby = rigid_point_velocity(vb[0], vb[1], vb[2], vb[3], vb[4], bx, by)
    tx = -ny
    ty = nx
    vt = (vjx - vbx) * tx + (vjy - vby) * ty
    ft = 0.0
    zdot = 0.0
    decay = 0.0
    if friction == FRICTION_COULOMB:
        ft = coulomb_modified(vt, fn, fp[FRICTION.cf], fp[FRICTION.v0], fp[FRICTION.v1])
    elif friction == FRICTION_LUGRE and fn > 0.0:
        s0 = fp[FRICTION.sigma0]
        decay = lugre_decay(
            vt, s0, fp[FRICTION.mu_k], fp[FRICTION.mu_s], fp[FRICTION.v_s], fp[FRICTION.gamma]
        )
        z = (z + hg * vt) / (1.0 + hg * decay)  # exact for hg = 0
        zdot = vt - decay * z  # the bristle equation, Eq. (9)
        ft = lugre_force(vt, z, zdot, fn, s0, fp[FRICTION.sigma1], fp[FRICTION.sigma2])
    # force on the journal: the normal force pushes it back towards the bearing centre
    fx = -fn * nx + ft * tx
    fy = -fn * ny + ft * ty
    return e, delta, ddot, fn, fdamp, ft, vt, z, zdot, decay, jx, jy, bx, by, fx, fy


@njit(cache=True, inline="always")
def pass_rows(v, b):
    """Body b's (x, y, phi) entries of a pass."""
    return v[3 * b], v[3 * b + 1], v[3 * b + 2]


@njit(cache=True, inline="always")
def pass_term(p, P, a, c, b, gx, gy):
    """Body b's term m_b a_b . (c_b - g) + I_b a_phi c_phi of two passes a, c (masses and
    inertias at ``P.mass``, ``P.inertia`` of p; gravity (gx, gy) m s-2, or 0): with two
    Jacobian columns its entry of M, with a column and the bias pass of h - Q_gravity."""
    ax, ay, aw = pass_rows(a, b)
    cx, cy, cw = pass_rows(c, b)
    return body_product(p[P.mass + b], p[P.inertia + b], ax, ay, aw, cx - gx, cy - gy, cw)


@njit(cache=True, inline="always")
def column_force(c, b, fx, fy, arm):
    """Generalised force along Jacobian column c of a force (fx, fy) (N) acting on body b with
    moment ``arm`` (N m) about its centroid."""
    cx, cy, cw = pass_rows(c, b)
    return body_product(1.0, 1.0, cx, cy, cw, fx, fy, arm)


@njit(cache=True, inline="always")
def body_motion(rates, cen, b):
    """(vx, vy, w, cx, cy) of body b from a velocity pass and the centroids (x, y per body)."""
    return rates[3 * b], rates[3 * b + 1], rates[3 * b + 2], cen[2 * b], cen[2 * b + 1]


@njit(cache=True, inline="always")
def lean_joint(x, yy, vx, vy, onset, z, friction, jp, fp, hg, rates, cen, journal, bearing, bc):
    """:func:`joint_forces` of a joint (journal and bearing bodies, bearing centre ``bc`` (m))
    from the velocity pass and the centroids, with scalars and tuples only (so that the lean
    right-hand sides keep everything in registers).

    Returns (delta, ddot, fdamp, ft, vt, z, zdot, decay, jx, jy, bx, by, fx, fy, arm, barm)
    with the moments (N m) of the journal force about the journal body's centroid and of the
    bearing's (the opposite) force about the bearing body's centroid.
    """
    e, delta, ddot, fn, fdamp, ft, vt, z, zdot, decay, jx, jy, bx, by, fx, fy = joint_forces(
        x, yy, vx, vy, onset, bc[0], bc[1], body_motion(rates, cen, journal),
        body_motion(rates, cen, bearing), jp, fp, friction, z, hg,
    )  # fmt: skip
    arm = moment_arm(jx, jy, cen[2 * journal], cen[2 * journal + 1], fx, fy)
    barm = moment_arm(bx, by, cen[2 * bearing], cen[2 * bearing + 1], -fx, -fy)
    return delta, ddot, fdamp, ft, vt, z, zdot, decay, jx, jy, bx, by, fx, fy, arm, barm


@njit(cache=True, inline="always")
def acceleration_entry(g, cols, qdd, i):
    """Entry i of the acceleration pass J_f qdd_f + gam from the bias pass g, the four free
    columns and their accelerations."""
    c0, c1, c2, c3 = cols
    a0, a1, a2, a3 = qdd
    return g[i] + c0[i] * a0 + c1[i] * a1 + c2[i] * a2 + c3[i] * a3


@njit(cache=True)  # not inlined: its loops index tuples at run time (long to compile, rarely run)
def driver_power(mass, inertia, gx, gy, vd, cen, acc, cols, qdd, forces, journal, bearing):
    """Driver power tau . qd_d (W) without the torques.

    With v_d the velocity pass of the driven rates alone (free rates 0), the rows d of
    M qdd + h - Q weighted by qd_d give tau . qd_d = sum_b m_b v_d . (a_b - g) +
    I_b w_d alpha_b - sum_j F_j . (v_d(journal point) - v_d(bearing point)), with the body
    accelerations a = J_f qdd_f + gam (:func:`acceleration_entry`; ``cols`` the four free
    columns, ``qdd`` their accelerations), masses (kg) and inertias (kg m2) per body, gravity
    (gx, gy) (m s-2) and per joint ``forces[j] = (jx, jy, bx, by, fx, fy)``: the contact
    points (m) and the force on the journal (N).
    """
    power = 0.0
    for b in range(len(mass)):
        vx, vy, w = pass_rows(vd, b)
        power += body_product(
            mass[b], inertia[b], vx, vy, w,
            acceleration_entry(acc, cols, qdd, 3 * b) - gx,
            acceleration_entry(acc, cols, qdd, 3 * b + 1) - gy,
            acceleration_entry(acc, cols, qdd, 3 * b + 2),
        )  # fmt: skip
    for j in range(len(forces)):
        jx, jy, bx, by, fx, fy = forces[j]
        vx, vy, w, cx, cy = body_motion(vd, cen, journal[j])
        vjx, vjy = rigid_point_velocity(vx, vy, w, cx, cy, jx, jy)
        vx, vy, w, cx, cy = body_motion(vd, cen, bearing[j])
        vbx, vby = rigid_point_velocity(vx, vy, w, cx, cy, bx, by)
        power -= fx * (vjx - vbx) + fy * (vjy - vby)
    return power


@njit(cache=True, inline="always")
def dissipated_power(fdamp, ddot, ft, vt):
    """Power (W) lost in a joint: normal damping and friction on the relative sliding (the
    elastic part of the normal force stores energy instead)."""
    return fdamp * ddot - ft * vt


@njit(cache=True, inline="always")
def spd4_solve(m00, m10, m11, m20, m21, m22, m30, m31, m32, m33, b0, b1, b2, b3):
    """Solve M x = b for a symmetric positive definite 4 x 4 M (lower triangle given by rows).

    Block elimination with 2 x 2 blocks M = [[A, B], [B^T, C]]: x_2 = S^-1 (b_2 - B^T A^-1 b_1)
    with the Schur complement S = C - B^T A^-1 B, then x_1 = A^-1 (b_1 - B x_2), each 2 x 2
    inverse by its adjugate (block LU factorisation: Golub & Van Loan 2013, *Matrix
    Computations*, 4th ed., Sec. 3.2). Two divisions and no square root on the critical path
    (an unrolled Cholesky factorisation chains four square roots and ten divisions: measured
    0.07 us of a 0.33 us right-hand side). M is positive definite exactly when A and S are
    (Horn & Johnson 2013, *Matrix Analysis*, 2nd ed., Sec. 7.7), i.e. when m00, det A, s00
    and det S are positive. A smaller system is solved by padding it with identity rows (zero
    off-diagonal entries, 1 on the diagonal, 0 right-hand side).

    Returns
    -------
    (ok, x0, x1, x2, x3) : (bool, float, ...)
        ok is False (x zero) where M is not positive definite (or not finite).
    """
    det_a = m00 * m11 - m10 * m10
    if not (m00 > 0.0 and det_a > 0.0):
        return False, 0.0, 0.0, 0.0, 0.0
    inv_a = 1.0 / det_a
    # X = A^-1 B with B = [[m20, m30], [m21, m31]], u = A^-1 (b0, b1)
    x00 = (m11 * m20 - m10 * m21) * inv_a
    x10 = (m00 * m21 - m10 * m20) * inv_a
    x01 = (m11 * m30 - m10 * m31) * inv_a
    x11 = (m00 * m31 - m10 * m30) * inv_a
    u0 = (m11 * b0 - m10 * b1) * inv_a
    u1 = (m00 * b1 - m10 * b0) * inv_a
    s00 = m22 - (m20 * x00 + m21 * x10)
    s10 = m32 - (m30 * x00 + m31 * x10)
    s11 = m33 - (m30 * x01 + m31 * x11)
    det_s = s00 * s11 - s10 * s10
    if not (s00 > 0.0 and det_s > 0.0):
        return False, 0.0, 0.0, 0.0, 0.0
    inv_s = 1.0 / det_s
    r2 = b2 - (m20 * u0 + m21 * u1)
    r3 = b3 - (m30 * u0 + m31 * u1)
    x2 = (s11 * r2 - s10 * r3) * inv_s
    x3 = (s00 * r3 - s10 * r2) * inv_s
    return True, u0 - (x00 * x2 + x01 * x3), u1 - (x10 * x2 + x11 * x3), x2, x3


# ================================================================================================
# array forms for the record-time evaluation
# ================================================================================================
@njit(cache=True)
def store_pass(values, body, point):
    """Write a pass result (per body x, y, phi, then per point x, y) into body[nb, 3] and
    point[np, 2]."""
    nb = body.shape[0]
    for b in range(nb):
        for r in range(3):
            body[b, r] = values[3 * b + r]
    for i in range(point.shape[0]):
        for r in range(2):
            point[i, r] = values[3 * nb + 2 * i + r]


@njit(cache=True)
def store_column(values, J, Jp, k):
    """Write a velocity pass into column k of J[nb, 3, nq] and Jp[np, 2, nq]."""
    nb = J.shape[0]
    for b in range(nb):
        for r in range(3):
            J[b, r, k] = values[3 * b + r]
    for i in range(Jp.shape[0]):
        for r in range(2):
            Jp[i, r, k] = values[3 * nb + 2 * i + r]


@njit(cache=True)
def kinematic_arrays(work, W, n_q, n_bodies, n_points):
    """Views into ``work`` (layout W, fields of :func:`work_fields`) of q, qd and the
    kinematics arrays: (q, qd, pos, pts, J, Jp, gam, gamp, vel, velp) with pos, gam, vel
    [n_bodies, 3], pts, gamp, velp [n_points, 2], J [n_bodies, 3, n_q], Jp [n_points, 2, n_q]."""
    nb, npt, nq = n_bodies, n_points, n_q
    return (
        work[W.q : W.q + nq],
        work[W.qd : W.qd + nq],
        work[W.pos : W.pos + 3 * nb].reshape((nb, 3)),
        work[W.pts : W.pts + 2 * npt].reshape((npt, 2)),
        work[W.J : W.J + 3 * nb * nq].reshape((nb, 3, nq)),
        work[W.Jp : W.Jp + 2 * npt * nq].reshape((npt, 2, nq)),
        work[W.gam : W.gam + 3 * nb].reshape((nb, 3)),
        work[W.gamp : W.gamp + 2 * npt].reshape((npt, 2)),
        work[W.vel : W.vel + 3 * nb].reshape((nb, 3)),
        work[W.velp : W.velp + 2 * npt].reshape((npt, 2)),
    )


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
def body_velocity(vel, pos, b):
    """(vx, vy, w, cx, cy) of body b: centroid velocity (m s-1) and angular velocity
    (rad s-1) from the velocity pass ``vel``, and centroid position (m)."""
    return vel[b, 0], vel[b, 1], vel[b, 2], pos[b, 0], pos[b, 1]


@njit(cache=True)
def generalised_force(Q, J, pos, b, px, py, fx, fy):
    """Add the generalised force of force (fx, fy) N acting at point (px, py) m of body b."""
    arm = moment_arm(px, py, pos[b, 0], pos[b, 1], fx, fy)
    for k in range(J.shape[2]):
        Q[k] += body_product(1.0, 1.0, J[b, 0, k], J[b, 1, k], J[b, 2, k], fx, fy, arm)


@njit(cache=True)
def assemble(J, gam, pos, vel, mass, inertia, gx, gy, M, h, Q):
    """Mass matrix M, bias force h and gravity force Q (overwritten) of the bodies.

    ``mass[b]`` (kg) and ``inertia[b]`` (centroidal, kg m2); gravity (gx, gy) m s-2; ``vel``
    the bodies' velocities. Returns (kinetic energy, gravity potential energy), J.
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
        vx, vy, w, cx, cy = body_velocity(vel, pos, b)
        ke += 0.5 * body_product(m, inert, vx, vy, w, vx, vy, w)
        pe -= m * (gx * cx + gy * cy)
        for k in range(nq):
            jx = J[b, 0, k]
            jy = J[b, 1, k]
            jw = J[b, 2, k]
            h[k] += body_product(m, inert, jx, jy, jw, gam[b, 0], gam[b, 1], gam[b, 2])
            Q[k] += body_product(m, 0.0, jx, jy, jw, gx, gy, 0.0)
            for l in range(k, nq):
                M[k, l] += body_product(m, inert, jx, jy, jw, J[b, 0, l], J[b, 1, l], J[b, 2, l])
    for k in range(nq):
        for l in range(k):
            M[k, l] = M[l, k]
    return ke, pe


@njit(cache=True)
def clearance_joint(
    Q, J, pos, vel, bj, bb, bcx, bcy, x, y, vx, vy, onset, p, jb, fb, friction, z, hg
):  # fmt: skip
    """:func:`joint_forces` of a joint whose journal is body ``bj`` and bearing body ``bb``
    (rows of J and pos), with their generalised forces added to Q (the forces act at the
    material contact points, so friction also exerts moments on both bodies).

    Returns (e, delta, ddot, fn, fdamp, ft, vt, z, zdot, decay) as :func:`joint_forces`.
    """
    vj = body_velocity(vel, pos, bj)
    vb = body_velocity(vel, pos, bb)
    e, delta, ddot, fn, fdamp, ft, vt, z, zdot, decay, jx, jy, bx, by, fx, fy = joint_forces(
        x, y, vx, vy, onset, bcx, bcy, vj, vb, joint_parameters(p, jb),
        friction_parameters(p, fb), friction, z, hg,
    )  # fmt: skip
    if delta > 0.0 and e > 0.0:
        generalised_force(Q, J, pos, bj, jx, jy, fx, fy)
        generalised_force(Q, J, pos, bb, bx, by, -fx, -fy)
    return e, delta, ddot, fn, fdamp, ft, vt, z, zdot, decay


@njit(cache=True, inline="always")
def _padded(M, free, nf, a, c):
    """Entry (a, c) of M_ff padded to 4 x 4 with identity rows (see :func:`spd4_solve`)."""
    if a < nf and c < nf:
        return M[free[a], free[c]]
    return 1.0 if a == c else 0.0


@njit(cache=True, inline="always")
def _padded_rhs(h, Q, free, nf, a):
    """Entry a of Q_f - h_f padded to 4 entries with zeros."""
    return Q[free[a]] - h[free[a]] if a < nf else 0.0


@njit(cache=True)
def solve_free(M, h, Q, free, nf, qdd):
    """qdd[free[:nf]] from M_ff qdd_f = Q_f - h_f (nf <= 4); False where M_ff is not positive
    definite. The other entries of qdd are left as they are."""
    ok, a0, a1, a2, a3 = spd4_solve(
        _padded(M, free, nf, 0, 0),
        _padded(M, free, nf, 1, 0),
        _padded(M, free, nf, 1, 1),
        _padded(M, free, nf, 2, 0),
        _padded(M, free, nf, 2, 1),
        _padded(M, free, nf, 2, 2),
        _padded(M, free, nf, 3, 0),
        _padded(M, free, nf, 3, 1),
        _padded(M, free, nf, 3, 2),
        _padded(M, free, nf, 3, 3),
        _padded_rhs(h, Q, free, nf, 0),
        _padded_rhs(h, Q, free, nf, 1),
        _padded_rhs(h, Q, free, nf, 2),
        _padded_rhs(h, Q, free, nf, 3),
    )
    if not ok:
        return False
    a = (a0, a1, a2, a3)
    for i in range(nf):
        qdd[free[i]] = a[i]
    return True


@njit(cache=True)
def evaluate_mechanism(
    y, p, ip, aux, work, P, IP, W, RECORD, pos, pts, J, gam, vel, journal, bearing,
    bearing_point, slider_body, slider_sign, slider_offset,
):  # fmt: skip
    """The record-time evaluation of a mechanism whose kinematics are in the arrays.

    Parameters
    ----------
    y, p, ip, aux : float64 and int64 arrays
        State, parameters, integer parameters and discrete state of the model (layouts P, IP).
    work : float64 array (in/out)
        Workspace of layout W: q, qd (filled), the scratch M, h, Q, the solver's hg; the
        record (layout RECORD, at its head) is filled.
    P, IP, W, RECORD : Layout
        The model's layouts; P has the fields mass, inertia, gx, gy, joint, friction; W the
        record fields (:func:`record_fields`) and q, qd, M, h, Q, hg.
    pos, pts, J, gam, vel : float64 arrays
        Kinematics at q, qd: pos[nb, 3], pts[np, 2], J[nb, 3, nq], gam[nb, 3] and the bodies'
        velocities vel[nb, 3] from the velocity pass.
    journal, bearing, bearing_point : tuples of int
        Per joint: the journal's and the bearing's body (rows of pos) and the bearing centre
        (row of pts).
    slider_body, slider_sign, slider_offset : int, float, float
        The slider's record is offset + sign x of that body's centroid (m), and its rates.

    Returns
    -------
    int
        0 or a failure code CODE_* (penetration, singular mass matrix, non-finite values).
    """
    nq = J.shape[2]
    nb = J.shape[0]
    nd = nq - 2 * len(journal)  # the driven coordinates come first
    q = work[W.q : W.q + nq]
    qd = work[W.qd : W.qd + nq]
    M = work[W.M : W.M + nq * nq].reshape((nq, nq))
    h = work[W.h : W.h + nq]
    Q = work[W.Q : W.Q + nq]
    for i in range(RECORD.size):
        work[i] = 0.0
    ke, pe = assemble(
        J, gam, pos, vel, p[P.mass : P.mass + nb], p[P.inertia : P.inertia + nb], p[P.gx],
        p[P.gy], M, h, Q,
    )  # fmt: skip
    friction = ip[IP.friction]
    p_diss = 0.0
    for j in range(len(journal)):
        if ip[IP.has + j] == 0:
            continue
        jb = P.joint + j * JOINT.size
        ix = nd + 2 * j
        iz = ip[IP.z + j]
        z = y[iz] if iz >= 0 else 0.0
        e, delta, ddot, fn, fdamp, ft, vt, z, zdot, decay = clearance_joint(
            Q, J, pos, vel, journal[j], bearing[j], pts[bearing_point[j], 0],
            pts[bearing_point[j], 1], q[ix], q[ix + 1], qd[ix], qd[ix + 1], aux[j], p, jb,
            P.friction, friction, z, work[W.hg],
        )  # fmt: skip
        if iz >= 0:
            y[iz] = z  # solved in an implicit stage (unchanged otherwise)
        pd = dissipated_power(fdamp, ddot, ft, vt)
        eel = contact_elastic_energy(delta, p[jb + JOINT.k], p[jb + JOINT.n])
        wb = W.joint + j * JOINT_RECORD.size
        work[wb + JOINT_RECORD.x] = q[ix]
        work[wb + JOINT_RECORD.y] = q[ix + 1]
        work[wb + JOINT_RECORD.vx] = qd[ix]
        work[wb + JOINT_RECORD.vy] = qd[ix + 1]
        work[wb + JOINT_RECORD.e] = e
        work[wb + JOINT_RECORD.delta] = delta
        work[wb + JOINT_RECORD.ddot] = ddot
        work[wb + JOINT_RECORD.fn] = fn
        work[wb + JOINT_RECORD.ft] = ft
        work[wb + JOINT_RECORD.vt] = vt
        work[wb + JOINT_RECORD.zdot] = zdot
        work[wb + JOINT_RECORD.pdiss] = pd
        work[wb + JOINT_RECORD.eel] = eel
        work[wb + JOINT_RECORD.decay] = decay
        if delta > p[jb + JOINT.dmax]:
            return CODE_PENETRATION
        p_diss += pd
        pe += eel
    nf = ip[IP.nf]
    qdd = work[W.qdd : W.qdd + nq]
    if nf > 0 and not solve_free(M, h, Q, ip[IP.free : IP.free + nf], nf, qdd):
        return CODE_SINGULAR
    # driving torques (reactions): tau_d = M_d. qdd + h_d - Q_d
    p_drive = 0.0
    for d in range(nd):
        s = h[d] - Q[d]
        for k in range(nq):
            s += M[d, k] * qdd[k]
        work[W.tau + d] = s
        p_drive += s * qd[d]
    b = slider_body
    a = gam[b, 0]
    for k in range(nq):
        a += J[b, 0, k] * qdd[k]
    work[W.slider] = slider_offset + slider_sign * pos[b, 0]
    work[W.slider + 1] = slider_sign * vel[b, 0]
    work[W.slider + 2] = slider_sign * a
    work[W.ke] = ke
    work[W.pe] = pe
    work[W.pdrive] = p_drive
    work[W.pdiss] = p_diss
    if not all_finite(work, RECORD.size):
        return CODE_NONFINITE
    return 0


@njit(cache=True)
def rates_from_record(y, ip, aux, work, dydt, IP, W, n_joints):
    """dy/dt from a record of :func:`evaluate_mechanism` (hook protocol of ``rhs``: returns 0
    or EVENT_INSIDE_STEP where a joint is in contact whose onset was not located)."""
    nf = ip[IP.nf]
    for i in range(nf):
        dydt[i] = y[nf + i]
        dydt[nf + i] = work[W.qdd + ip[IP.free + i]]
    for j in range(n_joints):
        iz = ip[IP.z + j]
        if iz >= 0:
            # bristles exist only in contact: frozen out of contact (reset at each onset)
            dydt[iz] = work[W.joint + j * JOINT_RECORD.size + JOINT_RECORD.zdot]
    iw = ip[IP.w]
    if iw >= 0:
        dydt[iw] = work[W.pdrive]
        dydt[iw + 1] = work[W.pdiss]
    for j in range(n_joints):
        delta = work[W.joint + j * JOINT_RECORD.size + JOINT_RECORD.delta]
        if ip[IP.has + j] == 1 and aux[j] == 0.0 and delta > 0.0:
            return EVENT_INSIDE_STEP  # in contact, but its onset has not been located
    return 0


@njit(cache=True)
def contact_event_values(y, p, ip, g, P, IP, n_joints):
    """The event functions of a mechanism's clearance joints (hook ``event_values``): per joint
    with a clearance, g = e - c, its penetration (m), twice: event 2i (rising zero, contact
    onset) and 2i + 1 (falling zero, contact end) of the i-th joint with a clearance."""
    for j in range(n_joints):
        k = ip[IP.slot + j]  # the joint's clearance x and y are y[k], y[k + 1]
        if k >= 0:
            d = math.sqrt(y[k] * y[k] + y[k + 1] * y[k + 1]) - p[P.joint + j * JOINT.size + JOINT.c]
            g[k] = d
            g[k + 1] = d


@njit(cache=True)
def contact_event(k, y, ip, aux, IP, n_joints):
    """Apply event k of :func:`contact_event_values` (hook ``apply_event``): at a contact onset
    hold the normal velocity in aux (and reset the joint's LuGre bristles); at its end clear it.
    Returns 0 (the integration goes on)."""
    nf = ip[IP.nf]
    slot = k - k % 2
    for j in range(n_joints):
        if ip[IP.slot + j] == slot:
            if k % 2 == 0:
                aux[j] = onset_velocity(y[slot], y[slot + 1], y[nf + slot], y[nf + slot + 1])
                iz = ip[IP.z + j]
                if iz >= 0:
                    y[iz] = 0.0
            else:
                aux[j] = 0.0
    return 0
