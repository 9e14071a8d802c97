"""Closed-form kinematics of the nine-bar mechanism with two revolute clearance joints.

Coordinates q = (theta1, theta4, x1, y1, x2, y2) [rad, rad, m, m, m, m]: the crank angles and
the clearance vectors (journal centre minus bearing centre) of the joints A (crank 1 / link 2)
and B (crank 4 / link 3); q[2:] = 0 is the ideal mechanism. Frame, branches and symbols:
``docs/ninebar-parameters.md`` (Chen et al. 2019, Eq. 11).

The mechanism is solved as a chain of Assur groups, each with its own position, velocity and
acceleration routine (modular kinematics; references: Hartenberg & Denavit, *Kinematic
Synthesis of Linkages*, 1964; Uicker, Pennock & Shigley, *Theory of Machines and Mechanisms*,
position, velocity and acceleration analysis of the four-bar and slider-crank loops):

1. driven cranks: A = L1 e(theta1), B = O4 + L4 e(theta4); journal centres A' = A + (x1, y1),
   B' = B + (x2, y2);
2. RRR dyad A'-P-B' (links 2 and 3), P left of A' -> B';
3. RRR dyad O6-C-P (rocker 6 and side CP of panel 7), C right of O6 -> P; theta7 = angle(P - C);
4. panel vertex D = C + L72 e(theta7 + beta);
5. RRP dyad D-E (link 8 and slider 9 on the guide y = y_O6), E on the -X side of D;
   S9 = S0 - (x_E - x_O6).

Positions are exact (circle intersections). Velocities and accelerations are exact too: each
dyad's rates solve the 2 x 2 linear system of its differentiated closure equation. The Jacobian
is the velocity analysis run with the six unit coordinate rates, the bias acceleration the
acceleration analysis at qdd = 0, so that the accelerations are ``J @ qdd + gam``.

Array layouts (all float64, written into caller-provided arrays, nothing allocated per call):

- ``pos[8, 3]``, ``gam[8, 3]``, ``J[8, 3, 6]``: per body (CRANK1 .. SLIDER9) the centroid x, y
  (m) and the angle phi (rad) measured counter-clockwise from +X, their bias accelerations and
  their derivatives with respect to q. The slider only translates (phi = 0). The crank angles
  are q[0], q[1] as given; the other angles lie in (-pi, pi].
- ``pts[N_POINTS, 2]``, ``gamp[N_POINTS, 2]``, ``Jp[N_POINTS, 2, 6]``: the moving points PT_A ..
  PT_E, likewise. The frame points O1 = (0, 0), O4 = (L5, 0) and O6 are in ``geo``.
"""

from __future__ import annotations

import math

from numba import njit

from workbench.models._assur import (
    arm_acceleration,
    arm_velocity,
    rrp_acceleration,
    rrp_position,
    rrp_velocity,
    rrr_acceleration,
    rrr_position,
    rrr_velocity,
)
from workbench.models._record import store_column, store_pass
from workbench.models.ninebar._geometry import ARRAY_FIELDS

# -- points (rows of pts, Jp, gamp) --------------------------------------------------------------
PT_A = 0  # bearing centre A on crank 1
PT_AJ = 1  # journal centre A' on link 2
PT_B = 2  # bearing centre B on crank 4
PT_BJ = 3  # journal centre B' on link 3
PT_P = 4  # joint of link 2, link 3 and panel 7
PT_C = 5  # joint of rocker 6 and panel 7
PT_D = 6  # joint of panel 7 and link 8
PT_E = 7  # joint of link 8 and slider 9, on the guide
N_POINTS = 8
POINT_NAMES = ("A", "A'", "B", "B'", "P", "C", "D", "E")

# -- bodies (rows of pos, J, gam; same order as _geometry.BODY_NAMES) ----------------------------
CRANK1, LINK2, LINK3, CRANK4, ROCKER6, PANEL7, LINK8, SLIDER9 = range(8)
N_BODIES = 8

# -- return codes: which group fails to assemble -------------------------------------------------
ASSEMBLED = 0
FAIL_LINKS_23 = 1  # A'-P-B': |A'B'| outside [|L2 - L3|, L2 + L3]
FAIL_ROCKER_PANEL = 2  # O6-C-P: |O6 P| outside [|L6 - L71|, L6 + L71]
FAIL_LINK8 = 3  # D-E: D is L8 or farther from the slider guide


# -- indices into geo ----------------------------------------------------------------------------
_G = {name: i for i, name in enumerate(ARRAY_FIELDS)}
G_L1, G_L2, G_L3, G_L4, G_L5 = _G["L1"], _G["L2"], _G["L3"], _G["L4"], _G["L5"]
G_L6, G_L71, G_L72, G_BETA, G_L8 = _G["L6"], _G["L71"], _G["L72"], _G["beta"], _G["L8"]
G_COS_BETA, G_SIN_BETA = _G["cos_beta"], _G["sin_beta"]
G_O6X, G_O6Y, G_S0 = _G["O6x"], _G["O6y"], _G["S0"]
G_LS1, G_LS2, G_LS3, G_LS4 = _G["Ls1"], _G["Ls2"], _G["Ls3"], _G["Ls4"]
G_LS6, G_LS8 = _G["Ls6"], _G["Ls8"]

# A configuration is carried between the passes as one flat tuple (no allocation): the unit
# vectors (c, s) of theta1, theta4, theta2, theta3, theta6, theta7, theta7 + beta, theta8; the
# dyads' rate factors f2, f3 (A'-P-B'), f6, f7 (O6-C-P), fw8, fs8 (D-E); the points A, A', B,
# B', P, C, D, E.
_N_STATE = 38
_THIRD = 1.0 / 3.0  # the panel's centroid is the mean of C, P, D
_STATE_POINTS = _N_STATE - 2 * N_POINTS  # where the points begin
_STATE_XE = _STATE_POINTS + 2 * PT_E
_NO_STATE = (0.0,) * _N_STATE
# Pass results are 40-tuples: per body (x, y, phi) in body order, then per point (x, y).
_V_SLIDER_X = 3 * SLIDER9  # x of the slider in a pass result


# ================================================================================================
# the mechanism: configuration, then positions, velocities and bias accelerations of everything
# ================================================================================================
@njit(cache=True, inline="always")
def configuration(th1, th4, x1, y1, x2, y2, geo):
    """Assemble the mechanism at q = (th1, th4, x1, y1, x2, y2): (code, state), state laid out
    as described at _N_STATE (all zero unless code is ASSEMBLED)."""
    c1 = math.cos(th1)
    s1 = math.sin(th1)
    c4 = math.cos(th4)
    s4 = math.sin(th4)
    xa = geo[G_L1] * c1
    ya = geo[G_L1] * s1
    xb = geo[G_L5] + geo[G_L4] * c4
    yb = geo[G_L4] * s4
    xaj = xa + x1
    yaj = ya + y1
    xbj = xb + x2
    ybj = yb + y2
    ok, c2, s2, c3, s3, f2, f3 = rrr_position(xaj, yaj, xbj, ybj, geo[G_L2], geo[G_L3], 1.0)
    if not ok:
        return FAIL_LINKS_23, _NO_STATE
    xp = xaj + geo[G_L2] * c2
    yp = yaj + geo[G_L2] * s2
    o6x = geo[G_O6X]
    o6y = geo[G_O6Y]
    ok, c6, s6, ccp, scp, f6, f7 = rrr_position(o6x, o6y, xp, yp, geo[G_L6], geo[G_L71], -1.0)
    if not ok:
        return FAIL_ROCKER_PANEL, _NO_STATE
    c7 = -ccp  # theta7 is the angle of P - C, the opposite of C - P
    s7 = -scp
    xc = o6x + geo[G_L6] * c6
    yc = o6y + geo[G_L6] * s6
    cb = geo[G_COS_BETA]
    sb = geo[G_SIN_BETA]
    cd = c7 * cb - s7 * sb  # e(theta7 + beta)
    sd = s7 * cb + c7 * sb
    xd = xc + geo[G_L72] * cd
    yd = yc + geo[G_L72] * sd
    ok, c8, s8, se, fw8, fs8 = rrp_position(xd, yd, o6x, o6y, 1.0, 0.0, geo[G_L8], -1.0)
    if not ok:
        return FAIL_LINK8, _NO_STATE
    state = (
        c1, s1, c4, s4, c2, s2, c3, s3, c6, s6, c7, s7, cd, sd, c8, s8,
        f2, f3, f6, f7, fw8, fs8,
        xa, ya, xaj, yaj, xb, yb, xbj, ybj, xp, yp, xc, yc, xd, yd, o6x + se, o6y,
    )  # fmt: skip
    return ASSEMBLED, state


@njit(cache=True, inline="always")
def point(state, i):
    """Position (x, y) of point i (PT_*) of an assembled configuration, m."""
    return state[_STATE_POINTS + 2 * i], state[_STATE_POINTS + 2 * i + 1]


@njit(cache=True, inline="always")
def centroids(geo, state):
    """Centroid positions (x, y) in body order (m): the position pass without the angles."""
    (
        c1, s1, c4, s4, c2, s2, c3, s3, c6, s6, c7, s7, cd, sd, c8, s8,
        f2, f3, f6, f7, fw8, fs8,
        xa, ya, xaj, yaj, xb, yb, xbj, ybj, xp, yp, xc, yc, xd, yd, xe, ye,
    ) = state  # fmt: skip
    return (
        geo[G_LS1] * c1, geo[G_LS1] * s1,
        xaj + geo[G_LS2] * c2, yaj + geo[G_LS2] * s2,
        xbj + geo[G_LS3] * c3, ybj + geo[G_LS3] * s3,
        geo[G_L5] + geo[G_LS4] * c4, geo[G_LS4] * s4,
        geo[G_O6X] + geo[G_LS6] * c6, geo[G_O6Y] + geo[G_LS6] * s6,
        (xc + xp + xd) * _THIRD, (yc + yp + yd) * _THIRD,
        xd + geo[G_LS8] * c8, yd + geo[G_LS8] * s8,
        xe, ye,
    )  # fmt: skip


@njit(cache=True)
def _placement(q, geo, state):
    """Positions: body (x, y, phi) in body order, then the points (m, rad)."""
    (
        c1, s1, c4, s4, c2, s2, c3, s3, c6, s6, c7, s7, cd, sd, c8, s8,
        f2, f3, f6, f7, fw8, fs8,
        xa, ya, xaj, yaj, xb, yb, xbj, ybj, xp, yp, xc, yc, xd, yd, xe, ye,
    ) = state  # fmt: skip
    g = centroids(geo, state)
    return (
        g[0], g[1], q[0],
        g[2], g[3], math.atan2(s2, c2),
        g[4], g[5], math.atan2(s3, c3),
        g[6], g[7], q[1],
        g[8], g[9], math.atan2(s6, c6),
        g[10], g[11], math.atan2(s7, c7),
        g[12], g[13], math.atan2(s8, c8),
        g[14], g[15], 0.0,
        xa, ya, xaj, yaj, xb, yb, xbj, ybj, xp, yp, xc, yc, xd, yd, xe, ye,
    )  # fmt: skip


@njit(cache=True, inline="always")
def velocities(geo, state, w1, w4, vx1, vy1, vx2, vy2):
    """Velocity analysis for qd = (w1, w4, vx1, vy1, vx2, vy2): rates laid out as _placement.
    Linear in qd: with a unit rate it is a column of the Jacobian."""
    (
        c1, s1, c4, s4, c2, s2, c3, s3, c6, s6, c7, s7, cd, sd, c8, s8,
        f2, f3, f6, f7, fw8, fs8,
        xa, ya, xaj, yaj, xb, yb, xbj, ybj, xp, yp, xc, yc, xd, yd, xe, ye,
    ) = state  # fmt: skip
    l2 = geo[G_L2]
    vax, vay = arm_velocity(0.0, 0.0, geo[G_L1], w1, c1, s1)
    vbx, vby = arm_velocity(0.0, 0.0, geo[G_L4], w4, c4, s4)
    vajx = vax + vx1
    vajy = vay + vy1
    vbjx = vbx + vx2
    vbjy = vby + vy2
    w2, w3 = rrr_velocity(c2, s2, c3, s3, f2, f3, vajx, vajy, vbjx, vbjy)
    vpx, vpy = arm_velocity(vajx, vajy, l2, w2, c2, s2)
    w6, w7 = rrr_velocity(c6, s6, -c7, -s7, f6, f7, 0.0, 0.0, vpx, vpy)
    vcx, vcy = arm_velocity(0.0, 0.0, geo[G_L6], w6, c6, s6)
    vdx, vdy = arm_velocity(vcx, vcy, geo[G_L72], w7, cd, sd)
    w8, vex = rrp_velocity(c8, s8, fw8, fs8, 1.0, 0.0, vdx, vdy)
    v1x, v1y = arm_velocity(0.0, 0.0, geo[G_LS1], w1, c1, s1)
    v2x, v2y = arm_velocity(vajx, vajy, geo[G_LS2], w2, c2, s2)
    v3x, v3y = arm_velocity(vbjx, vbjy, geo[G_LS3], w3, c3, s3)
    v4x, v4y = arm_velocity(0.0, 0.0, geo[G_LS4], w4, c4, s4)
    v6x, v6y = arm_velocity(0.0, 0.0, geo[G_LS6], w6, c6, s6)
    v8x, v8y = arm_velocity(vdx, vdy, geo[G_LS8], w8, c8, s8)
    return (
        v1x, v1y, w1, v2x, v2y, w2, v3x, v3y, w3, v4x, v4y, w4, v6x, v6y, w6,
        (vcx + vpx + vdx) * _THIRD, (vcy + vpy + vdy) * _THIRD, w7, v8x, v8y, w8, vex, 0.0, 0.0,
        vax, vay, vajx, vajy, vbx, vby, vbjx, vbjy, vpx, vpy, vcx, vcy, vdx, vdy, vex, 0.0,
    )  # fmt: skip


@njit(cache=True, inline="always")
def bias(geo, state, rates):
    """Acceleration analysis at qdd = 0 for the rates of velocities: laid out as _placement."""
    (
        c1, s1, c4, s4, c2, s2, c3, s3, c6, s6, c7, s7, cd, sd, c8, s8,
        f2, f3, f6, f7, fw8, fs8,
        xa, ya, xaj, yaj, xb, yb, xbj, ybj, xp, yp, xc, yc, xd, yd, xe, ye,
    ) = state  # fmt: skip
    w1 = rates[3 * CRANK1 + 2]
    w2 = rates[3 * LINK2 + 2]
    w3 = rates[3 * LINK3 + 2]
    w4 = rates[3 * CRANK4 + 2]
    w6 = rates[3 * ROCKER6 + 2]
    w7 = rates[3 * PANEL7 + 2]
    w8 = rates[3 * LINK8 + 2]
    l2 = geo[G_L2]
    # the journal centres accelerate as the bearing centres when qdd = 0
    aax, aay = arm_acceleration(0.0, 0.0, geo[G_L1], w1, 0.0, c1, s1)
    abx, aby = arm_acceleration(0.0, 0.0, geo[G_L4], w4, 0.0, c4, s4)
    al2, al3 = rrr_acceleration(c2, s2, c3, s3, f2, f3, l2, geo[G_L3], w2, w3, aax, aay, abx, aby)
    apx, apy = arm_acceleration(aax, aay, l2, w2, al2, c2, s2)
    al6, al7 = rrr_acceleration(
        c6, s6, -c7, -s7, f6, f7, geo[G_L6], geo[G_L71], w6, w7, 0.0, 0.0, apx, apy
    )
    acx, acy = arm_acceleration(0.0, 0.0, geo[G_L6], w6, al6, c6, s6)
    adx, ady = arm_acceleration(acx, acy, geo[G_L72], w7, al7, cd, sd)
    al8, aex = rrp_acceleration(c8, s8, fw8, fs8, geo[G_L8], 1.0, 0.0, w8, adx, ady)
    a1x, a1y = arm_acceleration(0.0, 0.0, geo[G_LS1], w1, 0.0, c1, s1)
    a2x, a2y = arm_acceleration(aax, aay, geo[G_LS2], w2, al2, c2, s2)
    a3x, a3y = arm_acceleration(abx, aby, geo[G_LS3], w3, al3, c3, s3)
    a4x, a4y = arm_acceleration(0.0, 0.0, geo[G_LS4], w4, 0.0, c4, s4)
    a6x, a6y = arm_acceleration(0.0, 0.0, geo[G_LS6], w6, al6, c6, s6)
    a8x, a8y = arm_acceleration(adx, ady, geo[G_LS8], w8, al8, c8, s8)
    return (
        a1x, a1y, 0.0, a2x, a2y, al2, a3x, a3y, al3, a4x, a4y, 0.0, a6x, a6y, al6,
        (acx + apx + adx) * _THIRD, (acy + apy + ady) * _THIRD, al7, a8x, a8y, al8, aex, 0.0, 0.0,
        aax, aay, aax, aay, abx, aby, abx, aby, apx, apy, acx, acy, adx, ady, aex, 0.0,
    )  # fmt: skip


@njit(cache=True)
def _store_jacobian(geo, state, J, Jp):
    """J and Jp column by column: the velocity analysis for each unit coordinate rate."""
    store_column(velocities(geo, state, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0), J, Jp, 0)
    store_column(velocities(geo, state, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0), J, Jp, 1)
    store_column(velocities(geo, state, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0), J, Jp, 2)
    store_column(velocities(geo, state, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0), J, Jp, 3)
    store_column(velocities(geo, state, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0), J, Jp, 4)
    store_column(velocities(geo, state, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0), J, Jp, 5)


# ================================================================================================
# public API
# ================================================================================================
@njit(cache=True)
def positions(q, geo, pos, pts):
    """Positions of the bodies and points.

    Parameters
    ----------
    q : float64[6]
        (theta1, theta4, x1, y1, x2, y2) [rad, rad, m, m, m, m].
    geo : float64[len(ARRAY_FIELDS)]
        Geometry (m, rad), see :func:`workbench.models.ninebar._geometry.geometry_array`.
    pos : float64[8, 3] (out)
        Centroid x, y (m) and angle phi (rad) per body.
    pts : float64[N_POINTS, 2] (out)
        Points PT_A .. PT_E (m).

    Returns
    -------
    int
        ASSEMBLED (0), or the FAIL_* code of the group that does not close (outputs untouched).
    """
    code, state = configuration(q[0], q[1], q[2], q[3], q[4], q[5], geo)
    if code == ASSEMBLED:
        store_pass(_placement(q, geo, state), pos, pts)
    return code


@njit(cache=True)
def jacobian(q, geo, J, Jp):
    """Exact Jacobians of the body coordinates and points with respect to q.

    Parameters
    ----------
    q : float64[6]
        Coordinates [rad, rad, m, m, m, m].
    geo : float64[len(ARRAY_FIELDS)]
        Geometry (m, rad).
    J : float64[8, 3, 6] (out)
        J[b, r, k] = d pos[b, r] / d q[k] (m rad-1, 1, rad m-1 as the units require).
    Jp : float64[N_POINTS, 2, 6] (out)
        Jp[i, r, k] = d pts[i, r] / d q[k].

    Returns
    -------
    int
        ASSEMBLED (0) or a FAIL_* code (outputs untouched).
    """
    code, state = configuration(q[0], q[1], q[2], q[3], q[4], q[5], geo)
    if code == ASSEMBLED:
        _store_jacobian(geo, state, J, Jp)
    return code


@njit(cache=True)
def bias_acceleration(q, qd, geo, gam, gamp):
    """Accelerations of the body coordinates and points at qdd = 0.

    Parameters
    ----------
    q, qd : float64[6]
        Coordinates [rad, rad, m, m, m, m] and their rates [rad s-1, rad s-1, m s-1, ...].
    geo : float64[len(ARRAY_FIELDS)]
        Geometry (m, rad).
    gam : float64[8, 3] (out)
        Body accelerations (m s-2, m s-2, rad s-2) for qdd = 0: acc = J @ qdd + gam.
    gamp : float64[N_POINTS, 2] (out)
        Point accelerations (m s-2) for qdd = 0.

    Returns
    -------
    int
        ASSEMBLED (0) or a FAIL_* code (outputs untouched).
    """
    code, state = configuration(q[0], q[1], q[2], q[3], q[4], q[5], geo)
    if code == ASSEMBLED:
        rates = velocities(geo, state, qd[0], qd[1], qd[2], qd[3], qd[4], qd[5])
        store_pass(bias(geo, state, rates), gam, gamp)
    return code


@njit(cache=True)
def kinematics(q, qd, geo, pos, pts, J, Jp, gam, gamp, vel, velp):
    """Positions, Jacobians, velocities and bias accelerations in one pass (the record-time
    dynamics' entry point).

    Parameters
    ----------
    q, qd : float64[6]
        Coordinates [rad, rad, m, m, m, m] and their rates.
    geo : float64[len(ARRAY_FIELDS)]
        Geometry (m, rad).
    pos, pts : float64[8, 3], float64[N_POINTS, 2] (out)
        As in :func:`positions`.
    J, Jp : float64[8, 3, 6], float64[N_POINTS, 2, 6] (out)
        As in :func:`jacobian`.
    gam, gamp : float64[8, 3], float64[N_POINTS, 2] (out)
        As in :func:`bias_acceleration`.
    vel, velp : float64[8, 3], float64[N_POINTS, 2] (out)
        Velocities J @ qd of the bodies (m s-1, m s-1, rad s-1) and points (m s-1), from the
        velocity pass (as the lean right-hand side computes them).

    Returns
    -------
    int
        ASSEMBLED (0) or a FAIL_* code (outputs untouched).
    """
    code, state = configuration(q[0], q[1], q[2], q[3], q[4], q[5], geo)
    if code == ASSEMBLED:
        store_pass(_placement(q, geo, state), pos, pts)
        _store_jacobian(geo, state, J, Jp)
        rates = velocities(geo, state, qd[0], qd[1], qd[2], qd[3], qd[4], qd[5])
        store_pass(rates, vel, velp)
        store_pass(bias(geo, state, rates), gam, gamp)
    return code


@njit(cache=True)
def slider(q, qd, qdd, geo):
    """Slider displacement S9 = S0 - (x_E - x_O6) and its first two time derivatives.

    Parameters
    ----------
    q, qd, qdd : float64[6]
        Coordinates [rad, rad, m, m, m, m] and their first and second time derivatives.
    geo : float64[len(ARRAY_FIELDS)]
        Geometry (m, rad).

    Returns
    -------
    (s, v, a) : (float, float, float)
        S9 (m), dS9/dt (m s-1), d2S9/dt2 (m s-2).

    Raises
    ------
    ValueError
        Where the mechanism does not assemble at q.
    """
    code, state = configuration(q[0], q[1], q[2], q[3], q[4], q[5], geo)
    if code != ASSEMBLED:
        raise ValueError("the nine-bar mechanism does not assemble at q")
    rates = velocities(geo, state, qd[0], qd[1], qd[2], qd[3], qd[4], qd[5])
    forced = velocities(geo, state, qdd[0], qdd[1], qdd[2], qdd[3], qdd[4], qdd[5])
    acc = bias(geo, state, rates)
    s = geo[G_S0] - (state[_STATE_XE] - geo[G_O6X])
    return s, -rates[_V_SLIDER_X], -(forced[_V_SLIDER_X] + acc[_V_SLIDER_X])
