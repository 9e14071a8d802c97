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

and a clearance joint adds the normal force of its contact law (Lankarani-Nikravesh or
Hunt-Crossley, :mod:`workbench.models.contact`) and a friction force at the
material contact points of journal and bearing (:func:`joint_forces`). Every model with
clearance joints (``ninebar``, ``slider_crank``) uses these functions, so the contact mechanics
and the body sums exist once, in two forms that share them:

- scalar functions (this module) inlined into each model's *lean* right-hand side
  (``inline="always"``: the integration's hot path stays in registers and computes only the
  free columns);
- array functions (:mod:`workbench.models._record`: ``assemble``, ``clearance_joint``) for
  the *record-time* evaluation, which fills every output (torques, energies, forces on every
  body) at the records and is the reference the lean right-hand sides are tested against.

The layouts of the parameter blocks that every mechanism shares (a clearance joint's, the
friction laws') and of the per-joint record are in :mod:`workbench.models._mechanism_layouts`,
the contact events in :mod:`workbench.models._contact_events`. Units: SI throughout (m, rad,
kg, N, J).
"""

from __future__ import annotations

import math

from numba import njit

from workbench.models._mechanism_layouts import (
    FRICTION,
    FRICTION_COULOMB,
    FRICTION_LUGRE,
    JOINT,
)
from workbench.models.contact import (
    CONTACT_HUNT_CROSSLEY,
    hunt_crossley,
    lankarani_nikravesh,
)
from workbench.models.friction import (
    coulomb_modified,
    lugre_coefficient,
    lugre_damping,
    lugre_decay,
    lugre_envelope,
)


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
def held_onset(aux, j):
    """Joint j's normal velocity held since its contact's onset (m s-1; 0 out of contact or
    before the onset is located): aux[j] where the problem holds one (the Lankarani-Nikravesh
    law), 0 where it holds none (a law without memory: no discrete state, aux shorter). A
    joint in contact with 0 here has its onset not located, or no onset to locate: the
    right-hand side then says EVENT_INSIDE_STEP, so that the solver still steps to the
    onset's event. Without memory every state in contact says so, and the solver's search for
    a contact that begins and ends within one step (which it runs only for steps that start
    without EVENT_INSIDE_STEP) covers the steps that start with every joint out of contact:
    while one joint's contact lasts, a contact of another joint shorter than a step is not
    forced to be located (its force still acts at the stages that see it)."""
    return aux[j] if j < aux.size else 0.0


@njit(cache=True, inline="always")
def joint_parameters(p, jb):
    """The JOINT block of p at offset ``jb`` as a tuple (in the JOINT layout's order)."""
    return (
        p[jb + JOINT.r1], p[jb + JOINT.r2], p[jb + JOINT.c], p[jb + JOINT.k], p[jb + JOINT.n],
        p[jb + JOINT.ce], p[jb + JOINT.dmax], p[jb + JOINT.vfloor], p[jb + JOINT.law],
        p[jb + JOINT.alpha],
    )  # fmt: skip


@njit(cache=True, inline="always")
def friction_parameters(p, fb):
    """The FRICTION block of p at offset ``fb`` as a tuple (in the FRICTION layout's order)."""
    return (
        p[fb + FRICTION.cf], p[fb + FRICTION.v0], p[fb + FRICTION.v1], p[fb + FRICTION.mu_k],
        p[fb + FRICTION.mu_s], p[fb + FRICTION.sigma0], p[fb + FRICTION.sigma1],
        p[fb + FRICTION.sigma2], p[fb + FRICTION.v_s], p[fb + FRICTION.gamma],
        p[fb + FRICTION.v_d],
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
        Normal velocity held since the contact began (m s-1; 0 if not located); read by the
        Lankarani-Nikravesh law only (the Hunt-Crossley law has no memory).
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
        z = B + hg (vt - a z) (see :mod:`workbench.solver._templates.integration_loop`).

    Returns
    -------
    tuple
        (e, delta, ddot, fn, fdamp, ft, mu, vt, z, zdot, decay, jx, jy, bx, by, fx, fy):
        eccentricity and penetration (m), penetration rate (m s-1), normal force and its damping
        part (N), friction force on the journal along t = (-ny, nx) (N), the friction
        coefficient of the law mu (1; 0 without friction or contact; -ft / fn, with LuGre's
        bristle deflection taken on its invariant set, see :func:`lugre_diagnostic`), sliding
        velocity (m s-1), the bristle deflection used (m), its rate (m s-1) and decay rate a in
        zdot = vt - a z (s-1; both 0 out of contact, where the bristles are frozen), the
        material contact points of journal and bearing (m), and the force on the journal (N;
        the bearing gets the opposite). Out of contact the forces and points are 0.
    """
    e = math.sqrt(x * x + y * y)
    delta = e - jp[JOINT.c]
    if delta <= 0.0 or e == 0.0:
        return e, delta, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, z, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    nx = x / e
    ny = y / e
    ddot = nx * vx + ny * vy
    if jp[JOINT.law] == CONTACT_HUNT_CROSSLEY:
        fn, fdamp = hunt_crossley(delta, ddot, jp[JOINT.k], jp[JOINT.n], jp[JOINT.alpha])
    else:
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
    mu = 0.0
    zdot = 0.0
    decay = 0.0
    if friction == FRICTION_COULOMB:
        ft = coulomb_modified(vt, fn, fp[FRICTION.cf], fp[FRICTION.v0], fp[FRICTION.v1])
        mu = -ft / fn if fn > 0.0 else 0.0
    elif friction == FRICTION_LUGRE and fn > 0.0:
        s0 = fp[FRICTION.sigma0]
        decay = lugre_decay(
            vt, s0, fp[FRICTION.mu_k], fp[FRICTION.mu_s], fp[FRICTION.v_s], fp[FRICTION.gamma]
        )
        z = (z + hg * vt) / (1.0 + hg * decay)  # exact for hg = 0
        zdot = vt - decay * z  # the bristle equation, Eq. (9)
        s1 = lugre_damping(vt, fp[FRICTION.sigma1], fp[FRICTION.v_d])
        ft = -lugre_coefficient(vt, z, zdot, s0, s1, fp[FRICTION.sigma2]) * fn
        mu = lugre_diagnostic(vt, z, decay, s0, s1, fp)
    # force on the journal: the normal force pushes it back towards the bearing centre
    fx = -fn * nx + ft * tx
    fy = -fn * ny + ft * ty
    return e, delta, ddot, fn, fdamp, ft, mu, vt, z, zdot, decay, jx, jy, bx, by, fx, fy


@njit(cache=True, inline="always")
def lugre_diagnostic(vt, z, decay, s0, s1, fp):
    """The LuGre friction coefficient (1) the diagnostics report: the law's, with the bristle
    deflection z (m) on its invariant set |z| <= max(mu_s, mu_k) / s0 (Canudas de Wit et al.
    1995, Property 1: the exact solution never leaves it). Where the integration is accurate
    it is -F_t / F_n; a z beyond the set is the integrator's error, not the law's (a stage of
    an explicit step, or the dense output of the stiff bristle state between two steps of
    DOP853 at its stability bound: :mod:`workbench.models._friction_report`), and is not the
    friction law leaving its physics. ``decay`` is the relaxation rate a (s-1), s0 (m-1) and
    the damping in effect s1 (s m-1) as in :func:`workbench.models.friction.lugre_coefficient`.
    """
    zmax = max(fp[FRICTION.mu_s], fp[FRICTION.mu_k]) / s0
    zc = min(max(z, -zmax), zmax)
    return lugre_coefficient(vt, zc, vt - decay * zc, s0, s1, fp[FRICTION.sigma2])


@njit(cache=True, inline="always")
def friction_excess(mu, vt, fp):
    """The rates of a joint's friction-law quadratures (:mod:`workbench.models._friction_report`):
    (1, _) where the friction coefficient |mu| exceeds the static mu_s, (_, 1) where it exceeds
    the law's envelope 2 mu_s + s2 |vt| (:func:`workbench.models.friction.lugre_envelope`; vt
    the sliding velocity, m s-1), else 0 (mu is 0 out of contact)."""
    m = abs(mu)
    mu_s = fp[FRICTION.mu_s]
    above = 1.0 if m > mu_s else 0.0
    beyond = 1.0 if m > lugre_envelope(vt, mu_s, fp[FRICTION.sigma2]) else 0.0
    return above, beyond


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

    Returns (delta, ddot, fdamp, ft, mu, vt, z, zdot, decay, jx, jy, bx, by, fx, fy, arm,
    barm) with the moments (N m) of the journal force about the journal body's centroid and of
    the bearing's (the opposite) force about the bearing body's centroid.
    """
    e, delta, ddot, fn, fdamp, ft, mu, vt, z, zdot, decay, jx, jy, bx, by, fx, fy = joint_forces(
        x, yy, vx, vy, onset, bc[0], bc[1], body_motion(rates, cen, journal),
        body_motion(rates, cen, bearing), jp, fp, friction, z, hg,
    )  # fmt: skip
    arm = moment_arm(jx, jy, cen[2 * journal], cen[2 * journal + 1], fx, fy)
    barm = moment_arm(bx, by, cen[2 * bearing], cen[2 * bearing + 1], -fx, -fy)
    return delta, ddot, fdamp, ft, mu, vt, z, zdot, decay, jx, jy, bx, by, fx, fy, arm, barm


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
    (an unrolled Cholesky factorisation chains four square roots and ten divisions, and cost
    0.07 us: benchmarks/RESULTS.md, "Before 0.2.0", "Cost of an evaluation"). M is positive
    definite exactly when A and S are (Horn & Johnson 2013, *Matrix Analysis*, 2nd ed., Sec.
    7.7), i.e. when m00, det A, s00 and det S are positive. A smaller system is solved by
    padding it with identity rows (zero off-diagonal entries, 1 on the diagonal, 0 right-hand
    side).

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
