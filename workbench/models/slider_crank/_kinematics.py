"""Closed-form kinematics of the slider-crank mechanism with a revolute clearance joint.

Coordinates q = (theta1, x, y) [rad, m, m]: the driven crank angle and the clearance vector
(x, y) = B' - B of the joint between the rod's end B' (the journal) and the slider's pin B (the
bearing centre), which runs on the x axis. Solved as a chain of Assur groups
(:mod:`workbench.models._assur`), like the nine-bar:

1. driven crank: A = L1 e(theta1);
2. RRP dyad A-B' (the rod, length L2) with B' on the line y' = y, which translates with the
   clearance's y, B' to the +x side of A: sin(theta2) = (y - L1 sin theta1) / L2;
3. the slider's pin B = B' - (x, y) = (s, 0): s = x_B' - x.

Velocities and accelerations are exact: the RRP dyad's rates solve its differentiated closure
relative to its guide (which moves at (0, y')). The Jacobian is the velocity analysis for the
three unit coordinate rates, the bias acceleration the acceleration analysis at qdd = 0.

Array layouts (float64, written into caller-provided arrays): ``pos[3, 3]``, ``gam[3, 3]``,
``J[3, 3, 3]`` per body (CRANK, ROD, SLIDER) the centroid x, y (m) and the angle phi (rad);
``pts[N_POINTS, 2]``, ``gamp``, ``Jp[N_POINTS, 2, 3]`` the points PT_A, PT_BJ, PT_B.
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
)
from workbench.models._record import store_column, store_pass
from workbench.models.slider_crank._geometry import GEOMETRY_FIELDS

# -- points (rows of pts, Jp, gamp) --------------------------------------------------------------
PT_A = 0  # crank pin A (crank / rod)
PT_BJ = 1  # journal centre B' on the rod
PT_B = 2  # bearing centre B on the slider, on the x axis
N_POINTS = 3

# -- bodies (rows of pos, J, gam; same order as _geometry.BODY_NAMES) ----------------------------
CRANK, ROD, SLIDER = range(3)
N_BODIES = 3

ASSEMBLED = 0
FAIL_ROD = 1  # the rod cannot reach the line of B': |y - L1 sin theta1| >= L2

_G = {name: i for i, name in enumerate(GEOMETRY_FIELDS)}
G_L1, G_L2, G_LC1, G_LC2 = _G["L1"], _G["L2"], _G["Lc1"], _G["Lc2"]

# A configuration is one flat tuple: the unit vectors (c, s) of theta1 and theta2, the RRP
# dyad's rate factors fw, fs, the points A, B', B.
_N_STATE = 12
_STATE_POINTS = _N_STATE - 2 * N_POINTS
_NO_STATE = (0.0,) * _N_STATE


@njit(cache=True, inline="always")
def configuration(th1, x, y, geo):
    """Assemble the mechanism at q = (th1, x, y): (code, state), state laid out as described
    at _N_STATE (all zero unless code is ASSEMBLED)."""
    c1 = math.cos(th1)
    s1 = math.sin(th1)
    xa = geo[G_L1] * c1
    ya = geo[G_L1] * s1
    ok, c2, s2, xbj, fw, fs = rrp_position(xa, ya, 0.0, y, 1.0, 0.0, geo[G_L2], 1.0)
    if not ok:
        return FAIL_ROD, _NO_STATE
    return ASSEMBLED, (c1, s1, c2, s2, fw, fs, xa, ya, xbj, y, xbj - x, 0.0)


@njit(cache=True, inline="always")
def point(state, i):
    """Position (x, y) of point i (PT_*) of an assembled configuration, m."""
    return state[_STATE_POINTS + 2 * i], state[_STATE_POINTS + 2 * i + 1]


@njit(cache=True, inline="always")
def centroids(geo, state):
    """Centroid positions (x, y) in body order (m)."""
    c1, s1, c2, s2, fw, fs, xa, ya, xbj, ybj, xb, yb = state
    return (
        geo[G_LC1] * c1, geo[G_LC1] * s1,
        xa + geo[G_LC2] * c2, ya + geo[G_LC2] * s2,
        xb, yb,
    )  # fmt: skip


@njit(cache=True)
def _placement(th1, geo, state):
    """Positions: body (x, y, phi) in body order, then the points (m, rad)."""
    c1, s1, c2, s2, fw, fs, xa, ya, xbj, ybj, xb, yb = state
    g = centroids(geo, state)
    return (
        g[0], g[1], th1,
        g[2], g[3], math.atan2(s2, c2),
        g[4], g[5], 0.0,
        xa, ya, xbj, ybj, xb, yb,
    )  # fmt: skip


@njit(cache=True, inline="always")
def velocities(geo, state, w1, vx, vy):
    """Velocity analysis for qd = (w1, vx, vy): rates laid out as _placement. Linear in qd:
    with a unit rate it is a column of the Jacobian."""
    c1, s1, c2, s2, fw, fs, xa, ya, xbj, ybj, xb, yb = state
    vax, vay = arm_velocity(0.0, 0.0, geo[G_L1], w1, c1, s1)
    # the dyad's guide (the line of B') translates at (0, vy): A's velocity relative to it
    w2, vbjx = rrp_velocity(c2, s2, fw, fs, 1.0, 0.0, vax, vay - vy)
    v1x, v1y = arm_velocity(0.0, 0.0, geo[G_LC1], w1, c1, s1)
    v2x, v2y = arm_velocity(vax, vay, geo[G_LC2], w2, c2, s2)
    return (
        v1x, v1y, w1,
        v2x, v2y, w2,
        vbjx - vx, 0.0, 0.0,
        vax, vay, vbjx, vy, vbjx - vx, 0.0,
    )  # fmt: skip


@njit(cache=True, inline="always")
def bias(geo, state, rates):
    """Acceleration analysis at qdd = 0 for the rates of velocities: laid out as _placement."""
    c1, s1, c2, s2, fw, fs, xa, ya, xbj, ybj, xb, yb = state
    w1 = rates[3 * CRANK + 2]
    w2 = rates[3 * ROD + 2]
    aax, aay = arm_acceleration(0.0, 0.0, geo[G_L1], w1, 0.0, c1, s1)
    al2, abjx = rrp_acceleration(c2, s2, fw, fs, geo[G_L2], 1.0, 0.0, w2, aax, aay)
    a1x, a1y = arm_acceleration(0.0, 0.0, geo[G_LC1], w1, 0.0, c1, s1)
    a2x, a2y = arm_acceleration(aax, aay, geo[G_LC2], w2, al2, c2, s2)
    return (
        a1x, a1y, 0.0,
        a2x, a2y, al2,
        abjx, 0.0, 0.0,
        aax, aay, abjx, 0.0, abjx, 0.0,
    )  # fmt: skip


@njit(cache=True)
def kinematics(q, qd, geo, pos, pts, J, Jp, gam, gamp, vel, velp):
    """Positions, Jacobians, velocities and bias accelerations in one pass (the record-time
    dynamics' entry point).

    Parameters
    ----------
    q, qd : float64[3]
        Coordinates (theta1, x, y) [rad, m, m] and their rates [rad s-1, m s-1, m s-1].
    geo : float64 array
        Geometry (m) in GEOMETRY_FIELDS order (more entries may follow).
    pos, pts : float64[3, 3], float64[N_POINTS, 2] (out)
        Centroid x, y (m) and angle (rad) per body; the points (m).
    J, Jp : float64[3, 3, 3], float64[N_POINTS, 2, 3] (out)
        Their derivatives with respect to q.
    gam, gamp : float64[3, 3], float64[N_POINTS, 2] (out)
        Their accelerations at qdd = 0: acc = J @ qdd + gam.
    vel, velp : float64[3, 3], float64[N_POINTS, 2] (out)
        Their velocities J @ qd, from the velocity pass.

    Returns
    -------
    int
        ASSEMBLED (0) or FAIL_ROD (outputs untouched).
    """
    code, state = configuration(q[0], q[1], q[2], geo)
    if code == ASSEMBLED:
        store_pass(_placement(q[0], geo, state), pos, pts)
        store_column(velocities(geo, state, 1.0, 0.0, 0.0), J, Jp, 0)
        store_column(velocities(geo, state, 0.0, 1.0, 0.0), J, Jp, 1)
        store_column(velocities(geo, state, 0.0, 0.0, 1.0), J, Jp, 2)
        rates = velocities(geo, state, qd[0], qd[1], qd[2])
        store_pass(rates, vel, velp)
        store_pass(bias(geo, state, rates), gam, gamp)
    return code
