"""Compiled dynamics of the nine-bar mechanism with revolute clearance joints (solver hooks).

Reduced (Lagrange) formulation in the coordinates q = (theta1, theta4, x1, y1, x2, y2)
(Chen et al. 2019, Sec. 3): the crank angles are driven, theta1 = theta10 - omega t and
theta4 = theta40 + omega t; the free coordinates are the clearance vectors of the joints that
have a clearance. With body centroid and angle Jacobians J (exact, from the closed-form
kinematics) and bias accelerations gamma (the accelerations at zero qdd), d'Alembert's principle
gives, for the free set f and the driven set d,

    M_ff qdd_f = Q_f - h_f,        tau_d = M_df qdd_f + h_d - Q_d,

with M = sum_b m_b Jc_b^T Jc_b + I_b Jphi_b^T Jphi_b, h = sum_b m_b Jc_b^T gamma_b +
I_b Jphi_b^T gammaphi_b and Q the generalised forces of gravity and of the contact and friction
forces (applied at the material contact points of journal and bearing, so friction also acts as a
moment on both bodies). The driving torques tau are the motors' reactions.

Two evaluations share these formulas (:mod:`workbench.models._reduced`,
:mod:`._kinematics`):

- :func:`rhs`, the solver's hook, computes only what the integration reads, in registers: the
  Jacobian columns of the free coordinates (the cranks do not move with them, so only the six
  other bodies enter M_ff, h_f and Q_f), the contact forces on the journals' bodies, the
  accelerations by a 4 x 4 block solve (:func:`workbench.models._reduced.spd4_solve`); the
  driver power only when the energy quadratures are integrated.
- :func:`evaluate`, at the records, fills everything (layout ``W``, head ``RECORD``): the full
  6 x 6 system, torques, slider motion, energies, per-joint forces. It is also the reference
  that :func:`rhs` is tested against (:func:`rhs_reference` is the right-hand side it gives).

State y = [q_f (m), qd_f (m s-1), z per clearance joint (m, LuGre only), per clearance joint
the times above mu_s and beyond the law's envelope (s, LuGre, when requested), driver work (J)
and dissipated energy (J) when requested]. Discrete state aux = [onset normal velocity per joint
(m s-1; 0 = not in contact)], set by the contact-onset event of each joint, under the
Lankarani-Nikravesh law only; under the Hunt-Crossley law, which has no memory, aux is empty.
"""

from __future__ import annotations

import math

from numba import njit

from workbench.models._base import EVENT_INSIDE_STEP
from workbench.models._layout import layout
from workbench.models._mechanism_hooks import mechanism_hooks
from workbench.models._mechanism_layouts import (
    CODE_ASSEMBLY,
    CODE_NONFINITE,
    CODE_PENETRATION,
    CODE_SINGULAR,
    FRICTION,
    JOINT,
    JOINT_RECORD,
    index_fields,
    record_fields,
    work_fields,
)
from workbench.models._record import evaluate_mechanism, kinematic_arrays
from workbench.models._record_types import MechanismLayout, Slider
from workbench.models._reduced import (
    column_force,
    dissipated_power,
    driver_power,
    friction_excess,
    friction_parameters,
    held_onset,
    joint_parameters,
    lean_joint,
    pass_term,
    spd4_solve,
)
from workbench.models.ninebar._geometry import ARRAY_FIELDS, GEOMETRY_FIELDS
from workbench.models.ninebar._kinematics import (
    CRANK1,
    CRANK4,
    LINK2,
    LINK3,
    LINK8,
    N_BODIES,
    N_POINTS,
    PANEL7,
    PT_A,
    PT_B,
    ROCKER6,
    SLIDER9,
    bias,
    centroids,
    configuration,
    kinematics,
    point,
    velocities,
)

N_GEO = len(ARRAY_FIELDS)  # the geometry array's length
N_Q = 6  # coordinates (theta1, theta4, x1, y1, x2, y2)
N_JOINTS = 2  # A, B

# float parameters p; the geometry first, so that p serves as the kinematics' geometry array
P = layout(
    "NineBarParameters",
    [
        ("geometry", N_GEO),  # ARRAY_FIELDS order (geometry_array), m and rad
        ("mass", N_BODIES),  # kg, body order
        ("inertia", N_BODIES),  # centroidal, kg m2
        ("gx", 1),  # gravity vector, m s-2
        ("gy", 1),
        ("omega", 1),  # crank speed, rad s-1
        ("theta10", 1),  # initial crank angles, rad
        ("theta40", 1),
        ("joint", N_JOINTS * JOINT.size),  # per joint (A, B) a JOINT block
        ("friction", FRICTION.size),
    ],
)
# integer parameters ip (fields: workbench.models._mechanism_layouts.index_fields)
IP = layout("NineBarIndices", index_fields(N_JOINTS))
# workspace of `evaluate` (and the hooks' work array): the record, then scratch
_RECORD_FIELDS = record_fields(N_Q, 2, N_JOINTS)
RECORD = layout("NineBarRecord", _RECORD_FIELDS)
W = layout("NineBarWork", [*_RECORD_FIELDS, *work_fields(N_Q, N_BODIES, N_POINTS)])
WORK_SIZE = W.size

BEARING_BODY = (CRANK1, CRANK4)  # crank 1 carries bearing A, crank 4 bearing B
JOURNAL_BODY = (LINK2, LINK3)  # link 2 carries journal A, link 3 journal B
BEARING_POINT = (PT_A, PT_B)
# what the record-time evaluation (workbench.models._record) knows of the model
MECHANISM = MechanismLayout(
    P=P,
    IP=IP,
    W=W,
    RECORD=RECORD,
    journal=JOURNAL_BODY,
    bearing=BEARING_BODY,
    bearing_point=BEARING_POINT,
)
_G_S0 = GEOMETRY_FIELDS.index("S0")
_G_O6X = GEOMETRY_FIELDS.index("O6x")


# ================================================================================================
# record-time evaluation (the reference)
# ================================================================================================
@njit(cache=True)
def evaluate(t, y, p, ip, aux, work):
    """Everything the model knows at (t, y): accelerations, torques, forces, energies.

    Fills ``work[:RECORD.size]`` (layout RECORD; the rest of ``work`` is scratch) and returns 0
    or a failure code (CODE_*).
    """
    omega = p[P.omega]
    nf = ip[IP.nf]
    kin = kinematic_arrays(work, W, N_Q, N_BODIES, N_POINTS)
    q, qd, pos, pts, J, Jp, gam, gamp, vel, velp = kin
    q[:] = 0.0
    qd[:] = 0.0
    q[0] = p[P.theta10] - omega * t
    q[1] = p[P.theta40] + omega * t
    qd[0] = -omega
    qd[1] = omega
    for i in range(nf):
        q[ip[IP.free + i]] = y[i]
        qd[ip[IP.free + i]] = y[nf + i]
    if kinematics(q, qd, p, pos, pts, J, Jp, gam, gamp, vel, velp) != 0:
        return CODE_ASSEMBLY
    # slider: S9 = S0 - (x_E - x_O6); body SLIDER9 moves with E
    slider = Slider(body=SLIDER9, sign=-1.0, offset=p[_G_S0] + p[_G_O6X])
    return evaluate_mechanism(y, p, ip, aux, work, MECHANISM, kin, slider)


# the hooks every mechanism shares, compiled as functions of this module
evaluate_many, rhs_reference, event_values, apply_event = mechanism_hooks(
    __name__, evaluate, MECHANISM
)


# ================================================================================================
# the lean right-hand side (the solver's hot path)
# ================================================================================================
@njit(cache=True, inline="always")
def _moving(p, a, c, gx, gy):
    """:func:`pass_term` summed over the bodies that move with the clearance vectors (all but
    the cranks): with Jacobian columns a, c an entry of M_ff, with a column and the bias pass
    (and gravity) an entry of h_f - Q_f(gravity)."""
    return (
        pass_term(p, P, a, c, LINK2, gx, gy)
        + pass_term(p, P, a, c, LINK3, gx, gy)
        + pass_term(p, P, a, c, ROCKER6, gx, gy)
        + pass_term(p, P, a, c, PANEL7, gx, gy)
        + pass_term(p, P, a, c, LINK8, gx, gy)
        + pass_term(p, P, a, c, SLIDER9, gx, gy)
    )


@njit(cache=True, inline="always")
def _unit(k, i):
    """1.0 if k == i, else 0.0 (branch-free)."""
    return (k == i) * 1.0


@njit(cache=True, inline="always")
def _residual(p, c, acc, gx, gy, fxa, fya, arma, fxb, fyb, armb):
    """Entry of Q_f - h_f along Jacobian column c: gravity and inertia of the moving bodies,
    the contact forces (fx, fy) (N) and moments (N m) on the journals' bodies (links 2, 3)."""
    return (
        column_force(c, LINK2, fxa, fya, arma)
        + column_force(c, LINK3, fxb, fyb, armb)
        - _moving(p, c, acc, gx, gy)
    )


@njit(cache=True, inline="always")
def _bodies(p, offset):
    """The N_BODIES values of p from ``offset`` (masses or inertias) as a tuple."""
    return (
        p[offset], p[offset + 1], p[offset + 2], p[offset + 3], p[offset + 4], p[offset + 5],
        p[offset + 6], p[offset + 7],
    )  # fmt: skip


@njit(cache=True, inline="always")
def _column(p, state, k):
    """Jacobian column of coordinate k (2..5; any other k gives a zero column)."""
    return velocities(p, state, 0.0, 0.0, _unit(k, 2), _unit(k, 3), _unit(k, 4), _unit(k, 5))


@njit(cache=True, error_model="numpy", _nrt=False)
def rhs(t, y, p, ip, aux, work, dydt):
    """dy/dt at (t, y) (the solver's hook; protocol in
    :mod:`workbench.solver._templates.integration_loop`).

    Equal to :func:`rhs_reference` to rounding, computing only what the integration reads. It
    allocates nothing and is compiled without reference counting (``_nrt=False``: numba's
    pruning leaves the counter updates of arrays used in branches, ~10 atomic operations per
    call); divisions follow IEEE rules (a zero divisor gives inf or NaN, caught as
    CODE_NONFINITE) instead of raising."""
    omega = p[P.omega]
    nf = ip[IP.nf]
    # clearance vectors and rates (zero for a joint without clearance), LuGre bristles
    ka = ip[IP.slot]
    kb = ip[IP.slot + 1]
    ha = 1.0 if ka >= 0 else 0.0
    hb = 1.0 if kb >= 0 else 0.0
    ka = max(ka, 0)
    kb = max(kb, 0)
    x1, y1, vx1, vy1 = ha * y[ka], ha * y[ka + 1], ha * y[nf + ka], ha * y[nf + ka + 1]
    x2, y2, vx2, vy2 = hb * y[kb], hb * y[kb + 1], hb * y[nf + kb], hb * y[nf + kb + 1]
    iza = ip[IP.z]
    izb = ip[IP.z + 1]
    za = y[max(iza, 0)]  # read only under LuGre friction
    zb = y[max(izb, 0)]
    code, state = configuration(
        p[P.theta10] - omega * t, p[P.theta40] + omega * t, x1, y1, x2, y2, p
    )
    if code != 0:
        return CODE_ASSEMBLY
    rates = velocities(p, state, -omega, omega, vx1, vy1, vx2, vy2)
    acc = bias(p, state, rates)
    cen = centroids(p, state)
    c0 = _column(p, state, ip[IP.free])
    c1 = _column(p, state, ip[IP.free + 1])
    c2 = _column(p, state, ip[IP.free + 2])
    c3 = _column(p, state, ip[IP.free + 3])
    gx = p[P.gx]
    gy = p[P.gy]
    hg = work[W.hg]
    onset_a = held_onset(aux, 0)
    onset_b = held_onset(aux, 1)
    friction = ip[IP.friction]
    fp = friction_parameters(p, P.friction)
    # joint forces; only the journals' bodies move with the free coordinates (not the cranks)
    jpa = joint_parameters(p, P.joint)
    da, dda, fda, fta, mua, vta, za, zdota, decaya, jxa, jya, bxa, bya, fxa, fya, arma, _ = (
        lean_joint(
            x1, y1, vx1, vy1, onset_a, za, friction, jpa, fp, hg, rates, cen, LINK2, CRANK1,
            point(state, PT_A),
        )
    )  # fmt: skip
    jpb = joint_parameters(p, P.joint + JOINT.size)
    db, ddb, fdb, ftb, mub, vtb, zb, zdotb, decayb, jxb, jyb, bxb, byb, fxb, fyb, armb, _ = (
        lean_joint(
            x2, y2, vx2, vy2, onset_b, zb, friction, jpb, fp, hg, rates, cen, LINK3, CRANK4,
            point(state, PT_B),
        )
    )  # fmt: skip
    if da > jpa[JOINT.dmax] or db > jpb[JOINT.dmax]:
        return CODE_PENETRATION
    # M_ff qdd_f = Q_f - h_f (gravity, inertia, contact); a single joint's 2 x 2 system padded
    # with identity rows
    pad = 1.0 if nf < 4 else 0.0
    ok, a0, a1, a2, a3 = spd4_solve(
        _moving(p, c0, c0, 0.0, 0.0),
        _moving(p, c1, c0, 0.0, 0.0),
        _moving(p, c1, c1, 0.0, 0.0),
        _moving(p, c2, c0, 0.0, 0.0),
        _moving(p, c2, c1, 0.0, 0.0),
        _moving(p, c2, c2, 0.0, 0.0) + pad,
        _moving(p, c3, c0, 0.0, 0.0),
        _moving(p, c3, c1, 0.0, 0.0),
        _moving(p, c3, c2, 0.0, 0.0),
        _moving(p, c3, c3, 0.0, 0.0) + pad,
        _residual(p, c0, acc, gx, gy, fxa, fya, arma, fxb, fyb, armb),
        _residual(p, c1, acc, gx, gy, fxa, fya, arma, fxb, fyb, armb),
        _residual(p, c2, acc, gx, gy, fxa, fya, arma, fxb, fyb, armb),
        _residual(p, c3, acc, gx, gy, fxa, fya, arma, fxb, fyb, armb),
    )
    if not ok:
        return CODE_SINGULAR
    p_diss = dissipated_power(fda, dda, fta, vta) + dissipated_power(fdb, ddb, ftb, vtb)
    if not math.isfinite(a0 + a1 + a2 + a3 + zdota + zdotb + p_diss):
        return CODE_NONFINITE
    for i in range(nf):
        dydt[i] = y[nf + i]
    dydt[nf] = a0
    dydt[nf + 1] = a1
    if nf == 4:
        dydt[nf + 2] = a2
        dydt[nf + 3] = a3
    if iza >= 0:
        y[iza] = za  # solved in an implicit stage (unchanged otherwise)
        dydt[iza] = zdota  # bristles exist only in contact: frozen outside (reset at onsets)
        work[W.joint + JOINT_RECORD.decay] = decaya
    if izb >= 0:
        y[izb] = zb
        dydt[izb] = zdotb
        work[W.joint + JOINT_RECORD.size + JOINT_RECORD.decay] = decayb
    ima = ip[IP.mu]
    if ima >= 0:
        dydt[ima], dydt[ima + 1] = friction_excess(mua, vta, fp)
    imb = ip[IP.mu + 1]
    if imb >= 0:
        dydt[imb], dydt[imb + 1] = friction_excess(mub, vtb, fp)
    iw = ip[IP.w]
    if iw >= 0:
        power = driver_power(
            _bodies(p, P.mass), _bodies(p, P.inertia), gx, gy,
            velocities(p, state, -omega, omega, 0.0, 0.0, 0.0, 0.0), cen, acc,
            (c0, c1, c2, c3), (a0, a1, a2, a3),
            ((jxa, jya, bxa, bya, fxa, fya), (jxb, jyb, bxb, byb, fxb, fyb)),
            JOURNAL_BODY, BEARING_BODY,
        )  # fmt: skip
        if not math.isfinite(power):
            return CODE_NONFINITE
        dydt[iw] = power
        dydt[iw + 1] = p_diss
    if (da > 0.0 and onset_a == 0.0) or (db > 0.0 and onset_b == 0.0):
        return EVENT_INSIDE_STEP  # in contact, with no onset velocity held (see held_onset)
    return 0
