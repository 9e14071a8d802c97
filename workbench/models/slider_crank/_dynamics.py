"""Compiled dynamics of the slider-crank mechanism with a revolute clearance joint (solver hooks).

Reduced (Lagrange) formulation in q = (theta1, x, y) (Flores et al. 2006): the crank angle is
driven, theta1 = theta10 + omega t; the free coordinates are the clearance vector (x, y) of the rod
/ slider joint. The equations of motion, contact (Lankarani-Nikravesh or Hunt-Crossley) and friction
(modified Coulomb, LuGre) are those of every mechanism (:mod:`workbench.models._reduced`); the crank
torque is the motor's reaction. As for the nine-bar (:mod:`workbench.models.ninebar._dynamics`) two
evaluations share the formulas: the lean :func:`rhs` (the free columns only: the crank does not move
with them, the rod and the slider do; both feel the contact force) and the record-time
:func:`evaluate` with every output, the reference of the tests.

State y = [x, y (m), vx, vy (m s-1), z (m, LuGre only), the times above mu_s and beyond the
law's envelope (s, LuGre, when requested), driver work and dissipated energy (J) when
requested]; aux = [onset normal velocity (m s-1; 0 = not in contact)] under the
Lankarani-Nikravesh law, empty under the Hunt-Crossley law (no memory).
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
from workbench.models.slider_crank._geometry import GEOMETRY_FIELDS
from workbench.models.slider_crank._kinematics import (
    N_BODIES,
    N_POINTS,
    PT_B,
    ROD,
    SLIDER,
    bias,
    centroids,
    configuration,
    kinematics,
    point,
    velocities,
)

N_GEO = len(GEOMETRY_FIELDS)
N_Q = 3  # coordinates (theta1, x, y)
N_JOINTS = 1  # B

# float parameters p; the geometry first, so that p serves as the kinematics' geometry array
P = layout(
    "SliderCrankParameters",
    [
        ("geometry", N_GEO),  # GEOMETRY_FIELDS order, m
        ("mass", N_BODIES),  # kg, body order
        ("inertia", N_BODIES),  # centroidal, kg m2
        ("gx", 1),  # gravity vector, m s-2
        ("gy", 1),
        ("omega", 1),  # crank speed, rad s-1
        ("theta10", 1),  # initial crank angle, rad
        ("joint", N_JOINTS * JOINT.size),
        ("friction", FRICTION.size),
    ],
)
IP = layout("SliderCrankIndices", index_fields(N_JOINTS))
_RECORD_FIELDS = record_fields(N_Q, 1, N_JOINTS)
RECORD = layout("SliderCrankRecord", _RECORD_FIELDS)
W = layout("SliderCrankWork", [*_RECORD_FIELDS, *work_fields(N_Q, N_BODIES, N_POINTS)])
WORK_SIZE = W.size

JOURNAL_BODY = (ROD,)  # the rod's end B' is the journal
BEARING_BODY = (SLIDER,)  # the slider carries the bearing
BEARING_POINT = (PT_B,)
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
_ZERO_PASS = (0.0,) * (3 * N_BODIES + 2 * N_POINTS)


# ================================================================================================
# record-time evaluation (the reference)
# ================================================================================================
@njit(cache=True)
def evaluate(t, y, p, ip, aux, work):
    """Accelerations, torque, forces and energies at (t, y) into ``work[:RECORD.size]``
    (layout RECORD); returns 0 or a failure code (CODE_*)."""
    omega = p[P.omega]
    kin = kinematic_arrays(work, W, N_Q, N_BODIES, N_POINTS)
    q, qd, pos, pts, J, Jp, gam, gamp, vel, velp = kin
    q[:] = 0.0
    qd[:] = 0.0
    q[0] = p[P.theta10] + omega * t
    qd[0] = omega
    if ip[IP.has] == 1:
        q[1], q[2], qd[1], qd[2] = y[0], y[1], y[2], y[3]
    if kinematics(q, qd, p, pos, pts, J, Jp, gam, gamp, vel, velp) != 0:
        return CODE_ASSEMBLY
    slider = Slider(body=SLIDER, sign=1.0, offset=0.0)
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
    """:func:`pass_term` summed over the bodies that move with the clearance vector (the rod
    and the slider; the crank does not)."""
    return pass_term(p, P, a, c, ROD, gx, gy) + pass_term(p, P, a, c, SLIDER, gx, gy)


@njit(cache=True, inline="always")
def _residual(p, c, acc, gx, gy, fx, fy, arm, barm):
    """Entry of Q_f - h_f along Jacobian column c: gravity and inertia of the moving bodies,
    the contact force (fx, fy) (N) on the rod with moment arm (N m), the opposite on the slider
    with moment barm."""
    return (
        column_force(c, ROD, fx, fy, arm)
        + column_force(c, SLIDER, -fx, -fy, barm)
        - _moving(p, c, acc, gx, gy)
    )


@njit(cache=True, error_model="numpy", _nrt=False)
def rhs(t, y, p, ip, aux, work, dydt):
    """dy/dt at (t, y) (the solver's hook; protocol in
    :mod:`workbench.solver._templates.integration_loop`).

    Equal to :func:`rhs_reference` to rounding, computing only what the integration reads;
    compiled as the nine-bar's :func:`workbench.models.ninebar._dynamics.rhs` (no reference
    counting, IEEE divisions)."""
    omega = p[P.omega]
    x, yy, vx, vy = y[0], y[1], y[2], y[3]  # the hook runs only with the clearance
    iz = ip[IP.z]
    code, state = configuration(p[P.theta10] + omega * t, x, yy, p)
    if code != 0:
        return CODE_ASSEMBLY
    rates = velocities(p, state, omega, vx, vy)
    acc = bias(p, state, rates)
    cen = centroids(p, state)
    c0 = velocities(p, state, 0.0, 1.0, 0.0)
    c1 = velocities(p, state, 0.0, 0.0, 1.0)
    gx = p[P.gx]
    gy = p[P.gy]
    jp = joint_parameters(p, P.joint)
    fp = friction_parameters(p, P.friction)
    onset = held_onset(aux, 0)
    delta, ddot, fdamp, ft, mu, vt, z, zdot, decay, jx, jy, bx, by, fx, fy, arm, barm = lean_joint(
        x, yy, vx, vy, onset, y[max(iz, 0)], ip[IP.friction], jp, fp, work[W.hg], rates, cen,
        ROD, SLIDER, point(state, PT_B),
    )  # fmt: skip
    if delta > jp[JOINT.dmax]:
        return CODE_PENETRATION
    # the 2 x 2 system M_ff qdd_f = Q_f - h_f, padded with identity rows; both bodies of the
    # joint move with the clearance vector
    ok, a0, a1, _, _ = spd4_solve(
        _moving(p, c0, c0, 0.0, 0.0),
        _moving(p, c1, c0, 0.0, 0.0),
        _moving(p, c1, c1, 0.0, 0.0),
        0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0,
        _residual(p, c0, acc, gx, gy, fx, fy, arm, barm),
        _residual(p, c1, acc, gx, gy, fx, fy, arm, barm),
        0.0, 0.0,
    )  # fmt: skip
    if not ok:
        return CODE_SINGULAR
    p_diss = dissipated_power(fdamp, ddot, ft, vt)
    if not math.isfinite(a0 + a1 + zdot + p_diss):
        return CODE_NONFINITE
    dydt[0] = vx
    dydt[1] = vy
    dydt[2] = a0
    dydt[3] = a1
    if iz >= 0:
        y[iz] = z  # solved in an implicit stage (unchanged otherwise)
        dydt[iz] = zdot  # bristles exist only in contact: frozen outside (reset at onsets)
        work[W.joint + JOINT_RECORD.decay] = decay
    im = ip[IP.mu]
    if im >= 0:
        dydt[im], dydt[im + 1] = friction_excess(mu, vt, fp)
    iw = ip[IP.w]
    if iw >= 0:
        power = driver_power(
            (p[P.mass], p[P.mass + 1], p[P.mass + 2]),
            (p[P.inertia], p[P.inertia + 1], p[P.inertia + 2]), gx, gy,
            velocities(p, state, omega, 0.0, 0.0), cen, acc, (c0, c1, _ZERO_PASS, _ZERO_PASS),
            (a0, a1, 0.0, 0.0), ((jx, jy, bx, by, fx, fy),), JOURNAL_BODY, BEARING_BODY,
        )  # fmt: skip
        if not math.isfinite(power):
            return CODE_NONFINITE
        dydt[iw] = power
        dydt[iw + 1] = p_diss
    if delta > 0.0 and onset == 0.0:
        return EVENT_INSIDE_STEP  # in contact, with no onset velocity held (see held_onset)
    return 0
