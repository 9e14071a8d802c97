"""The record-time evaluation of a mechanism in reduced coordinates (array forms): the
kinematics passes stored into arrays, the full mass matrix, bias and generalised forces of the
bodies, every clearance joint's forces and record, the free accelerations, the driving
torques, the slider's motion and the energies (:func:`evaluate_mechanism`); and the
right-hand side a record gives (:func:`rates_from_record`), the reference the lean
right-hand sides (:mod:`workbench.models._reduced`) are tested against. Units: SI.

As the solver's loop, the evaluation takes its inputs besides the model's flat arrays in named
tuples (:mod:`workbench.models._record_types`); it takes the arrays out of them once (an access
of an array in a numba tuple costs a pair of reference-count operations).
"""

from __future__ import annotations

import math

from numba import njit

from workbench.models._base import EVENT_INSIDE_STEP
from workbench.models._mechanism_layouts import (
    CODE_NONFINITE,
    CODE_PENETRATION,
    CODE_SINGULAR,
    JOINT,
    JOINT_RECORD,
)
from workbench.models._record_types import JointState, Kinematics
from workbench.models._reduced import (
    body_product,
    dissipated_power,
    friction_excess,
    friction_parameters,
    held_onset,
    joint_forces,
    joint_parameters,
    moment_arm,
    spd4_solve,
)
from workbench.models.contact import (
    contact_elastic_energy,
)


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
    """The :class:`~workbench.models._record_types.Kinematics` of views into ``work`` (layout W,
    fields of :func:`workbench.models._mechanism_layouts.work_fields`): q, qd [n_q], pos, gam,
    vel [n_bodies, 3], pts, gamp, velp [n_points, 2], J [n_bodies, 3, n_q], Jp [n_points, 2,
    n_q]."""
    nb, npt, nq = n_bodies, n_points, n_q
    return Kinematics(
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
def clearance_joint(Q, J, pos, vel, joint, jp, fp, friction, hg):
    """:func:`joint_forces` of a clearance joint, with their generalised forces added to Q (the
    forces act at the material contact points, so friction also exerts moments on both bodies).

    Parameters
    ----------
    Q : float64 array [n_q] (in/out)
        Generalised forces, N or N m.
    J, pos, vel : float64 arrays
        Of the kinematics at q, qd (:class:`~workbench.models._record_types.Kinematics`): the
        bodies' Jacobian [n_bodies, 3, n_q], positions (m, rad) and velocities (m s-1,
        rad s-1) [n_bodies, 3]; passed as arrays, not in the tuple (an access of an array in a
        numba tuple costs a pair of reference-count operations, per joint and evaluation).
    joint : ~workbench.models._record_types.JointState
        The joint's bodies, bearing centre, clearance vector and contact state.
    jp, fp : tuples of float
        The joint's parameters (JOINT layout: :func:`joint_parameters`) and the friction
        parameters (FRICTION layout: :func:`friction_parameters`).
    friction : int
        The friction law (FRICTION_* of :mod:`workbench.models._mechanism_layouts`).
    hg : float
        h gamma (s) of an implicit ARK548 stage, else 0 (see :func:`joint_forces`).

    Returns
    -------
    tuple of float
        (e, delta, ddot, fn, fdamp, ft, mu, vt, z, zdot, decay) as :func:`joint_forces`.
    """
    vj = body_velocity(vel, pos, joint.journal)
    vb = body_velocity(vel, pos, joint.bearing)
    e, delta, ddot, fn, fdamp, ft, mu, vt, z, zdot, decay, jx, jy, bx, by, fx, fy = joint_forces(
        joint.x, joint.y, joint.vx, joint.vy, joint.onset, joint.bcx, joint.bcy, vj, vb, jp, fp,
        friction, joint.z, hg,
    )  # fmt: skip
    if delta > 0.0 and e > 0.0:
        generalised_force(Q, J, pos, joint.journal, jx, jy, fx, fy)
        generalised_force(Q, J, pos, joint.bearing, bx, by, -fx, -fy)
    return e, delta, ddot, fn, fdamp, ft, mu, vt, z, zdot, decay


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
def evaluate_mechanism(y, p, ip, aux, work, mech, kin, slider):
    """The record-time evaluation of a mechanism whose cranks turn at constant speeds:
    :func:`evaluate_driven` without a motor."""
    return evaluate_driven(y, p, ip, aux, work, mech, kin, slider, -1, 0.0)


@njit(cache=True)
def evaluate_driven(y, p, ip, aux, work, mech, kin, slider, motor, torque):
    """The record-time evaluation of a mechanism whose kinematics at (q, qd) are in ``kin``.

    Parameters
    ----------
    y, p, ip, aux : float64 and int64 arrays
        State, parameters, integer parameters and discrete state of the model (layouts
        mech.P, mech.IP).
    work : float64 array (in/out)
        Workspace of layout mech.W: the scratch M, h, Q, the solver's hg; the record (layout
        mech.RECORD, at its head) is filled.
    mech : ~workbench.models._record_types.MechanismLayout
        The model's layouts and the bodies and points of its clearance joints.
    kin : ~workbench.models._record_types.Kinematics
        Kinematics at q, qd (views into ``work``); q, qd, pos, pts, J, gam and vel are read.
    slider : ~workbench.models._record_types.Slider
        The slider's record is slider.offset + slider.sign x of that body's centroid (m), and
        its rates.
    motor : int
        The driven coordinate that a motor drives (-1: none): a free coordinate, the
        generalised force ``torque`` (N m) on it, whose recorded torque is ``torque``.
    torque : float
        The motor's torque, N m.

    Returns
    -------
    int
        0 or a failure code CODE_* (penetration, singular mass matrix, non-finite values).
    """
    P, IP, W, RECORD = mech.P, mech.IP, mech.W, mech.RECORD
    journal, bearing, bearing_point = mech.journal, mech.bearing, mech.bearing_point
    # the arrays taken out of the tuple once (an access costs a pair of reference-count updates)
    q, qd, pos, pts, J, gam, vel = kin.q, kin.qd, kin.pos, kin.pts, kin.J, kin.gam, kin.vel
    nq = J.shape[2]
    nb = J.shape[0]
    nd = nq - 2 * len(journal)  # the driven coordinates come first
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
    fp = friction_parameters(p, P.friction)
    p_diss = 0.0
    for j in range(len(journal)):
        if ip[IP.has + j] == 0:
            continue
        jb = P.joint + j * JOINT.size
        ix = nd + 2 * j
        iz = ip[IP.z + j]
        joint = JointState(
            journal=journal[j],
            bearing=bearing[j],
            bcx=pts[bearing_point[j], 0],
            bcy=pts[bearing_point[j], 1],
            x=q[ix],
            y=q[ix + 1],
            vx=qd[ix],
            vy=qd[ix + 1],
            onset=held_onset(aux, j),
            z=y[iz] if iz >= 0 else 0.0,
        )
        e, delta, ddot, fn, fdamp, ft, mu, vt, z, zdot, decay = clearance_joint(
            Q, J, pos, vel, joint, joint_parameters(p, jb), fp, friction, work[W.hg]
        )
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
        work[wb + JOINT_RECORD.mu] = mu
        above, beyond = friction_excess(mu, vt, fp)
        work[wb + JOINT_RECORD.above] = above
        work[wb + JOINT_RECORD.beyond] = beyond
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
    if motor >= 0:
        Q[motor] += torque
    if nf > 0 and not solve_free(M, h, Q, ip[IP.free : IP.free + nf], nf, qdd):
        return CODE_SINGULAR
    # driving torques (reactions): tau_d = M_d. qdd + h_d - Q_d
    p_drive = 0.0
    for d in range(nd):
        s = h[d] - Q[d]
        for k in range(nq):
            s += M[d, k] * qdd[k]
        if d == motor:
            s = torque  # the applied torque (its row, a free one, is solved)
        work[W.tau + d] = s
        p_drive += s * qd[d]
    b = slider.body
    sign = slider.sign
    a = gam[b, 0]
    for k in range(nq):
        a += J[b, 0, k] * qdd[k]
    work[W.slider] = slider.offset + sign * pos[b, 0]
    work[W.slider + 1] = sign * vel[b, 0]
    work[W.slider + 2] = sign * a
    work[W.ke] = ke
    work[W.pe] = pe
    work[W.pdrive] = p_drive
    work[W.pdiss] = p_diss
    if not all_finite(work, RECORD.size):
        return CODE_NONFINITE
    return 0


@njit(cache=True)
def rates_from_record(y, ip, aux, work, dydt, mech):
    """dy/dt from a record of :func:`evaluate_mechanism` in ``work`` (hook protocol of ``rhs``:
    returns 0 or EVENT_INSIDE_STEP where a joint is in contact whose onset was not located);
    ``mech`` the model's
    :class:`~workbench.models._record_types.MechanismLayout`."""
    IP, W = mech.IP, mech.W
    n_joints = len(mech.journal)
    nf = ip[IP.nf]
    for i in range(nf):
        dydt[i] = y[nf + i]
        dydt[nf + i] = work[W.qdd + ip[IP.free + i]]
    for j in range(n_joints):
        iz = ip[IP.z + j]
        if iz >= 0:
            # bristles exist only in contact: frozen out of contact (reset at each onset)
            dydt[iz] = work[W.joint + j * JOINT_RECORD.size + JOINT_RECORD.zdot]
    for j in range(n_joints):
        im = ip[IP.mu + j]
        if im >= 0:
            rec = W.joint + j * JOINT_RECORD.size
            dydt[im] = work[rec + JOINT_RECORD.above]
            dydt[im + 1] = work[rec + JOINT_RECORD.beyond]
    iw = ip[IP.w]
    if iw >= 0:
        dydt[iw] = work[W.pdrive]
        dydt[iw + 1] = work[W.pdiss]
    for j in range(n_joints):
        delta = work[W.joint + j * JOINT_RECORD.size + JOINT_RECORD.delta]
        if ip[IP.has + j] == 1 and held_onset(aux, j) == 0.0 and delta > 0.0:
            return EVENT_INSIDE_STEP  # in contact, with no onset velocity held (held_onset)
    return 0
