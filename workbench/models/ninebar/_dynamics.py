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

State y = [q_f (m), qd_f (m s-1), z per clearance joint (m, LuGre only), driver work (J) and
dissipated energy (J) when requested]. Discrete state aux = [onset normal velocity per joint
(m s-1; 0 = not in contact)], set by the contact-onset event of each joint.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from workbench.models._base import EVENT_INSIDE_STEP
from workbench.models._reduced import (
    CODE_ASSEMBLY,
    CODE_NONFINITE,
    CODE_PENETRATION,
    CODE_SINGULAR,
    FRICTION_LUGRE,
    N_FP,
    all_finite,
    assemble,
    cholesky_solve,
    clearance_joint,
)
from workbench.models.contact import onset_velocity
from workbench.models.ninebar._geometry import GEOMETRY_FIELDS
from workbench.models.ninebar._kinematics import (
    N_POINTS,
    PT_A,
    PT_B,
    kinematics,
)

N_GEO = len(GEOMETRY_FIELDS)

# --- float parameter layout: geometry, then these ----------------------------------------------
P_MASS = N_GEO  # 8 body masses, kg
P_INERTIA = P_MASS + 8  # 8 centroidal inertias, kg m2
P_GX = P_INERTIA + 8  # gravity vector, m s-2
P_GY = P_GX + 1
P_OMEGA = P_GY + 1  # crank speed, rad s-1
P_TH10 = P_OMEGA + 1  # initial crank angles, rad
P_TH40 = P_TH10 + 1
P_JOINT = P_TH40 + 1  # per joint (A, B) block of N_PJ values:
PJ_R1 = 0  # bearing radius, m
PJ_R2 = 1  # journal radius, m
PJ_C = 2  # clearance, m
PJ_K = 3  # contact stiffness, N m^-n
PJ_N = 4  # contact exponent
PJ_CE = 5  # restitution
PJ_DMAX = 6  # largest allowed penetration, m
N_PJ = 7
P_CF = P_JOINT + 2 * N_PJ  # Coulomb friction coefficient
P_V0 = P_CF + 1  # Coulomb velocity thresholds, m s-1
P_V1 = P_V0 + 1
P_MUK = P_V1 + 1  # LuGre
P_MUS = P_MUK + 1
P_S0 = P_MUS + 1
P_S1 = P_S0 + 1
P_S2 = P_S1 + 1
P_VS = P_S2 + 1
P_GAM = P_VS + 1
P_VFLOOR = P_GAM + 1  # impact-velocity floor, m s-1
N_P = P_VFLOOR + 1

# --- integer parameter layout -------------------------------------------------------------------
IP_HAS = 0  # IP_HAS + j: 1 if joint j (0 = A, 1 = B) has a clearance
IP_FRICTION = 2  # 0 none, 1 modified Coulomb, 2 LuGre
IP_ENERGY = 3  # 1 if the energy quadratures are integrated
IP_NF = 4  # number of free coordinates
IP_FREE = 5  # IP_FREE + i: index in q of free coordinate i (4 slots)
IP_Z = 9  # IP_Z + j: index of joint j's bristle state in y, -1 if none
IP_W = 11  # index of the driver-work quadrature in y, -1 if none
N_IP = 12


# --- workspace layout of `evaluate` ---------------------------------------------------------------
W_QDD = 0  # 6: full qdd (driven entries 0)
W_TAU = 6  # 2: driving torques of crank 1 and crank 4, N m
W_JOINT = 8  # per joint block of N_WJ:
WJ_X = 0  # clearance vector, m
WJ_Y = 1
WJ_VX = 2  # its rate, m s-1
WJ_VY = 3
WJ_E = 4  # eccentricity, m
WJ_DELTA = 5  # e - c, m
WJ_DDOT = 6  # penetration rate, m s-1
WJ_FN = 7  # normal force, N
WJ_FT = 8  # friction force on the journal along t, N
WJ_VT = 9  # sliding velocity, m s-1
WJ_ZDOT = 10  # bristle rate, m s-1
WJ_PDISS = 11  # dissipated power, W
WJ_EEL = 12  # elastic contact energy, J
WJ_DECAY = 13  # decay rate of the LuGre bristle deflection in contact, s-1 (0 otherwise)
N_WJ = 14
W_SLIDER = W_JOINT + 2 * N_WJ  # slider position, velocity, acceleration (m, m s-1, m s-2)
W_KE = W_SLIDER + 3  # kinetic energy, J
W_PE = W_KE + 1  # potential energy (gravity + contact), J
W_PDRIVE = W_PE + 1  # driver power, W
W_PDISS = W_PDRIVE + 1  # dissipated power, W
N_W = W_PDISS + 1

BEARING_BODY = (0, 3)  # crank 1 carries bearing A, crank 4 bearing B
JOURNAL_BODY = (1, 2)  # link 2 carries journal A, link 3 journal B


# --- scratch layout of the hooks' work array (after the workspace W_*) ----------------------------
_O_Q = N_W
_O_QD = _O_Q + 6
_O_POS = _O_QD + 6
_O_PTS = _O_POS + 24
_O_J = _O_PTS + 2 * N_POINTS
_O_JP = _O_J + 144
_O_GAM = _O_JP + 12 * N_POINTS
_O_GAMP = _O_GAM + 24
_O_M = _O_GAMP + 2 * N_POINTS
_O_H = _O_M + 36
_O_Q6 = _O_H + 6
_O_MFF = _O_Q6 + 6
_O_RF = _O_MFF + 36
_O_QDD = _O_RF + 6
_O_L = _O_QDD + 6
O_HG = _O_L + 36  # h gamma of an implicit ARK548 stage (s; 0 otherwise), set by the solver
WORK_SIZE = O_HG + 1


@njit(cache=True)
def evaluate(t, y, p, ip, aux, work):
    """Everything the model knows at (t, y): accelerations, torques, forces, energies.

    Fills ``work[:N_W]`` (layout W_*; the rest of ``work`` is scratch) and returns 0 or a
    failure code (CODE_*). One function serves the right-hand side and the derived outputs, so
    they cannot disagree.
    """
    ws = work
    geo = p[:N_GEO]
    omega = p[P_OMEGA]
    nf = ip[IP_NF]
    q = work[_O_Q : _O_Q + 6]
    qd = work[_O_QD : _O_QD + 6]
    q[:] = 0.0
    qd[:] = 0.0
    q[0] = p[P_TH10] - omega * t
    q[1] = p[P_TH40] + omega * t
    qd[0] = -omega
    qd[1] = omega
    for i in range(nf):
        q[ip[IP_FREE + i]] = y[i]
        qd[ip[IP_FREE + i]] = y[nf + i]
    pos = work[_O_POS : _O_POS + 24].reshape((8, 3))
    pts = work[_O_PTS : _O_PTS + 2 * N_POINTS].reshape((N_POINTS, 2))
    J = work[_O_J : _O_J + 144].reshape((8, 3, 6))
    Jp = work[_O_JP : _O_JP + 12 * N_POINTS].reshape((N_POINTS, 2, 6))
    gam = work[_O_GAM : _O_GAM + 24].reshape((8, 3))
    gamp = work[_O_GAMP : _O_GAMP + 2 * N_POINTS].reshape((N_POINTS, 2))
    if kinematics(q, qd, geo, pos, pts, J, Jp, gam, gamp) != 0:
        return CODE_ASSEMBLY
    for i in range(N_W):
        ws[i] = 0.0

    # mass matrix, bias and gravity (full 6 x 6; cheap at this size)
    M = work[_O_M : _O_M + 36].reshape((6, 6))
    h = work[_O_H : _O_H + 6]
    Q = work[_O_Q6 : _O_Q6 + 6]
    ke, pe = assemble(
        J, gam, pos, qd, p[P_MASS : P_MASS + 8], p[P_INERTIA : P_INERTIA + 8], p[P_GX], p[P_GY],
        M, h, Q,
    )  # fmt: skip

    # contact and friction at each clearance joint
    friction = ip[IP_FRICTION]
    p_diss = 0.0
    for j in range(2):
        if ip[IP_HAS + j] == 0:
            continue
        base = P_JOINT + j * N_PJ
        wb = W_JOINT + j * N_WJ
        ix = 2 + 2 * j
        x = q[ix]
        yv = q[ix + 1]
        vx = qd[ix]
        vy = qd[ix + 1]
        bearing = PT_A if j == 0 else PT_B
        z = y[ip[IP_Z + j]] if friction == FRICTION_LUGRE else 0.0
        e, delta, ddot, fn, ft, vt, z, zdot, decay, pd, eel = clearance_joint(
            Q, J, pos, qd, JOURNAL_BODY[j], BEARING_BODY[j], pts[bearing, 0], pts[bearing, 1],
            x, yv, vx, vy, aux[j], p[base + PJ_R1], p[base + PJ_R2], p[base + PJ_C],
            p[base + PJ_K], p[base + PJ_N], p[base + PJ_CE], p[P_VFLOOR], friction,
            p[P_CF : P_CF + N_FP], z, work[O_HG],
        )  # fmt: skip
        if friction == FRICTION_LUGRE:
            y[ip[IP_Z + j]] = z  # solved in an implicit stage (unchanged otherwise)
        ws[wb + WJ_X] = x
        ws[wb + WJ_Y] = yv
        ws[wb + WJ_VX] = vx
        ws[wb + WJ_VY] = vy
        ws[wb + WJ_E] = e
        ws[wb + WJ_DELTA] = delta
        if delta > p[base + PJ_DMAX]:
            return CODE_PENETRATION
        p_diss += pd
        pe += eel
        ws[wb + WJ_DDOT] = ddot
        ws[wb + WJ_FN] = fn
        ws[wb + WJ_FT] = ft
        ws[wb + WJ_VT] = vt
        ws[wb + WJ_ZDOT] = zdot
        ws[wb + WJ_DECAY] = decay
        ws[wb + WJ_PDISS] = pd
        ws[wb + WJ_EEL] = eel

    # free accelerations
    free = ip[IP_FREE : IP_FREE + nf]
    Mff = work[_O_MFF : _O_MFF + 36].reshape((6, 6))
    rhs_f = work[_O_RF : _O_RF + 6]
    for a in range(nf):
        rhs_f[a] = Q[free[a]] - h[free[a]]
        for c in range(nf):
            Mff[a, c] = M[free[a], free[c]]
    L = work[_O_L : _O_L + 36].reshape((6, 6))
    if nf > 0 and not cholesky_solve(Mff, rhs_f, nf, L):
        return CODE_SINGULAR
    qdd = work[_O_QDD : _O_QDD + 6]
    qdd[:] = 0.0
    for a in range(nf):
        qdd[free[a]] = rhs_f[a]
        ws[W_QDD + free[a]] = rhs_f[a]
    # driving torques (reactions): tau_d = M_d. qdd + h_d - Q_d
    for d in range(2):
        s = h[d] - Q[d]
        for k in range(6):
            s += M[d, k] * qdd[k]
        ws[W_TAU + d] = s
    # slider: S9 = S0 - (x_E - x_O6); body 7 moves with E
    vxs = 0.0
    axs = gam[7, 0]
    for k in range(6):
        vxs += J[7, 0, k] * qd[k]
        axs += J[7, 0, k] * qdd[k]
    ws[W_SLIDER] = geo[_S0] - (pos[7, 0] - geo[_O6X])
    ws[W_SLIDER + 1] = -vxs
    ws[W_SLIDER + 2] = -axs
    ws[W_KE] = ke
    ws[W_PE] = pe
    ws[W_PDRIVE] = ws[W_TAU] * qd[0] + ws[W_TAU + 1] * qd[1]
    ws[W_PDISS] = p_diss
    if not all_finite(ws, N_W):
        return CODE_NONFINITE
    return 0


_S0 = GEOMETRY_FIELDS.index("S0")
_O6X = GEOMETRY_FIELDS.index("O6x")


@njit(cache=True)
def rhs(t, y, p, ip, aux, work, dydt):
    ws = work
    code = evaluate(t, y, p, ip, aux, work)
    if code != 0:
        return code
    nf = ip[IP_NF]
    for i in range(nf):
        dydt[i] = y[nf + i]
        dydt[nf + i] = ws[W_QDD + ip[IP_FREE + i]]
    for j in range(2):
        iz = ip[IP_Z + j]
        if iz >= 0:
            # bristles exist only in contact: frozen out of contact (reset at each onset)
            dydt[iz] = ws[W_JOINT + j * N_WJ + WJ_ZDOT]
    iw = ip[IP_W]
    if iw >= 0:
        dydt[iw] = ws[W_PDRIVE]
        dydt[iw + 1] = ws[W_PDISS]
    for j in range(2):
        if ip[IP_HAS + j] == 1 and aux[j] == 0.0 and ws[W_JOINT + j * N_WJ + WJ_DELTA] > 0.0:
            return EVENT_INSIDE_STEP  # in contact, but its onset has not been located
    return 0


@njit(cache=True)
def event_values(t, y, p, ip, aux, work, g):
    """g_j = e_j - c_j, the penetration of joint j (m); rising zero = contact onset,
    falling zero = contact end. Events 2j (onset) and 2j+1 (end) per clearance joint."""
    k = 0
    for j in range(2):
        if ip[IP_HAS + j] == 0:
            continue
        # free coordinates of joint j are consecutive: x at slot k, y at k + 1
        x = y[k]
        yy = y[k + 1]
        d = math.sqrt(x * x + yy * yy) - p[P_JOINT + j * N_PJ + PJ_C]
        g[k] = d
        g[k + 1] = d
        k += 2
    return None


@njit(cache=True)
def apply_event(k, t, y, p, ip, aux, work):
    """Contact onset: hold the normal velocity (and reset the LuGre bristles); end: clear it."""
    nf = ip[IP_NF]
    # which joint does slot k belong to?
    j = 0 if (ip[IP_HAS] == 1 and k < 2) else 1
    slot = k - (k % 2)
    if k % 2 == 0:
        aux[j] = onset_velocity(y[slot], y[slot + 1], y[nf + slot], y[nf + slot + 1])
        iz = ip[IP_Z + j]
        if iz >= 0:
            y[iz] = 0.0
    else:
        aux[j] = 0.0
    return 0


@njit(cache=True)
def evaluate_many(t, Y, p, ip, AUX, ws):
    """`evaluate` at every record (rows of Y and AUX) into ws[i, :N_W]; returns the failure code
    per record."""
    codes = np.zeros(t.size, np.int64)
    work = np.zeros(WORK_SIZE)
    for i in range(t.size):
        codes[i] = evaluate(t[i], Y[i], p, ip, AUX[i], work)
        ws[i, :] = work[:N_W]
    return codes
