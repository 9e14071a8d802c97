"""Closed-form kinematics of the nine-bar mechanism with clearance vectors (modular dyads).

Coordinates q = (theta1, theta4, x1, y1, x2, y2) [rad, rad, m, m, m, m]. The mechanism is
solved as a chain of Assur groups (Hartenberg & Denavit 1964; Nikravesh 1988, Sec. 3): driven
cranks, the journal centres A' = A + (x1, y1) and B' = B + (x2, y2), the RRR dyad A'-P-B' (links
2 and 3), the RRR dyad O6-C-P (rocker 6 and panel 7), the panel vertex D and the RRP dyad D-E
(link 8 and the slider on the guide y = y_O6). Positions, Jacobians and bias accelerations are
exact: each dyad's velocity and acceleration follow from the 2 x 2 linear system of its
differentiated closure equation, solved for the 6 unit coordinate velocities at once.
"""

from __future__ import annotations

import math

from numba import njit

from workbench.models.ninebar._geometry import GEOMETRY_FIELDS

# point indices (pts, Jp, gamp); O1, O4 and O6 are fixed and kept internally
PT_A = 0  # bearing centre A on crank 1
PT_AJ = 1  # journal centre A' on link 2
PT_B = 2  # bearing centre B on crank 4
PT_BJ = 3  # journal centre B' on link 3
PT_P = 4  # compound joint of links 2, 3 and panel 7
PT_C = 5  # rocker 6 / panel 7
PT_D = 6  # panel 7 / link 8
PT_E = 7  # link 8 / slider 9
N_POINTS = 8
_O1, _O4, _O6 = 8, 9, 10
_NPT = 11

# angle indices
A_TH1, A_TH4, A_TH2, A_TH3, A_TH6, A_TH7, A_TH8 = 0, 1, 2, 3, 4, 5, 6

# body indices
CRANK1, LINK2, LINK3, CRANK4, ROCKER6, PANEL7, LINK8, SLIDER9 = range(8)

# failure codes of `kinematics`
ASSEMBLED = 0
FAIL_LINKS_23 = 1  # A'-P-B' does not close
FAIL_ROCKER_PANEL = 2  # O6-C-P does not close
FAIL_LINK8 = 3  # D-E cannot reach the slider guide

_G = {name: i for i, name in enumerate(GEOMETRY_FIELDS)}
G_L1, G_L2, G_L3, G_L4, G_L5 = _G["L1"], _G["L2"], _G["L3"], _G["L4"], _G["L5"]
G_L6, G_L71, G_L72, G_BETA, G_L8 = _G["L6"], _G["L71"], _G["L72"], _G["beta"], _G["L8"]
G_O6X, G_O6Y, G_S0 = _G["O6x"], _G["O6y"], _G["S0"]
G_LS1, G_LS2, G_LS3, G_LS4 = _G["Ls1"], _G["Ls2"], _G["Ls3"], _G["Ls4"]
G_LS6, G_LS8 = _G["Ls6"], _G["Ls8"]


@njit(cache=True)
def _arm(P, JP, BP, out, base, L, k, cs, sn, Ja, ba, w):
    """Point ``out`` = point ``base`` + L e(angle k), with its Jacobian and bias acceleration."""
    c = cs[k]
    s = sn[k]
    P[out, 0] = P[base, 0] + L * c
    P[out, 1] = P[base, 1] + L * s
    for col in range(6):
        JP[out, 0, col] = JP[base, 0, col] - L * s * Ja[k, col]
        JP[out, 1, col] = JP[base, 1, col] + L * c * Ja[k, col]
    BP[out, 0] = BP[base, 0] - L * s * ba[k] - L * c * w[k] * w[k]
    BP[out, 1] = BP[base, 1] + L * c * ba[k] - L * s * w[k] * w[k]


@njit(cache=True)
def _rrr(P, JP, BP, i1, l1, i2, l2, side, k1, k2, ang, cs, sn, Ja, ba, w, qd):
    """RRR dyad: links of lengths l1 from point i1 and l2 from point i2 meet at a joint X on
    ``side`` (+1: left of i1 -> i2). Sets angles k1 = angle(X - P_i1), k2 = angle(X - P_i2) with
    their Jacobians, rates and bias accelerations. Returns False if the dyad cannot close."""
    dx = P[i2, 0] - P[i1, 0]
    dy = P[i2, 1] - P[i1, 1]
    d2 = dx * dx + dy * dy
    if d2 == 0.0:
        return False
    d = math.sqrt(d2)
    a = (l1 * l1 - l2 * l2 + d2) / (2.0 * d)
    h2 = l1 * l1 - a * a
    if h2 < 0.0:
        return False
    h = math.sqrt(h2)
    ux = dx / d
    uy = dy / d
    xx = P[i1, 0] + a * ux - side * h * uy
    xy = P[i1, 1] + a * uy + side * h * ux
    ang[k1] = math.atan2(xy - P[i1, 1], xx - P[i1, 0])
    ang[k2] = math.atan2(xy - P[i2, 1], xx - P[i2, 0])
    c1, s1 = (xx - P[i1, 0]) / l1, (xy - P[i1, 1]) / l1
    c2, s2 = (xx - P[i2, 0]) / l2, (xy - P[i2, 1]) / l2
    cs[k1], sn[k1], cs[k2], sn[k2] = c1, s1, c2, s2
    # l1 w1 (-s1, c1) - l2 w2 (-s2, c2) = v_i2 - v_i1
    m00, m01, m10, m11 = -l1 * s1, l2 * s2, l1 * c1, -l2 * c2
    det = m00 * m11 - m01 * m10
    if det == 0.0:
        return False
    w1 = 0.0
    w2 = 0.0
    for col in range(6):
        rx = JP[i2, 0, col] - JP[i1, 0, col]
        ry = JP[i2, 1, col] - JP[i1, 1, col]
        Ja[k1, col] = (rx * m11 - m01 * ry) / det
        Ja[k2, col] = (m00 * ry - m10 * rx) / det
        w1 += Ja[k1, col] * qd[col]
        w2 += Ja[k2, col] * qd[col]
    w[k1] = w1
    w[k2] = w2
    rx = BP[i2, 0] - BP[i1, 0] + l1 * w1 * w1 * c1 - l2 * w2 * w2 * c2
    ry = BP[i2, 1] - BP[i1, 1] + l1 * w1 * w1 * s1 - l2 * w2 * w2 * s2
    ba[k1] = (rx * m11 - m01 * ry) / det
    ba[k2] = (m00 * ry - m10 * rx) / det
    return True


@njit(cache=True)
def _body(pos, J, gam, b, P, JP, BP, pt, k, ang, Ja, ba):
    """Body b: centroid = point pt, angle = angle k (k < 0: a translating body, angle 0)."""
    for r in range(2):
        pos[b, r] = P[pt, r]
        gam[b, r] = BP[pt, r]
        for col in range(6):
            J[b, r, col] = JP[pt, r, col]
    if k >= 0:
        pos[b, 2] = ang[k]
        gam[b, 2] = ba[k]
        for col in range(6):
            J[b, 2, col] = Ja[k, col]
    else:
        pos[b, 2] = 0.0
        gam[b, 2] = 0.0
        for col in range(6):
            J[b, 2, col] = 0.0


KIN_SCRATCH = _NPT * 2 + _NPT * 12 + _NPT * 2 + 7 + 42 + 7 + 7 + 14  # floats of scratch


@njit(cache=True)
def kinematics(q, qd, geo, pos, pts, J, Jp, gam, gamp, scratch):
    """Positions, Jacobians and bias accelerations of the eight moving bodies and named points.

    Parameters
    ----------
    q, qd : float64[6]
        Coordinates (theta1, theta4, x1, y1, x2, y2) [rad, rad, m, m, m, m] and their rates.
    geo : float64[len(GEOMETRY_FIELDS)]
        Geometry (m, rad), see :mod:`._geometry`.
    pos : float64[8, 3] (out)
        Centroid x, y (m) and angle (rad) of each body (CRANK1 .. SLIDER9).
    pts : float64[N_POINTS, 2] (out)
        Named points PT_* (m).
    J, Jp : float64[8, 3, 6], float64[N_POINTS, 2, 6] (out)
        d(pos)/dq and d(pts)/dq.
    gam, gamp : float64[8, 3], float64[N_POINTS, 2] (out)
        Accelerations at qdd = 0 (m s-2, rad s-2), so that acc = J @ qdd + gam.
    scratch : float64[KIN_SCRATCH]
        Work space (overwritten), so that nothing is allocated per call.

    Returns
    -------
    int
        ASSEMBLED (0) or the FAIL_* code of the group that cannot close.
    """
    scratch[:] = 0.0
    o = 0
    P = scratch[o : o + _NPT * 2].reshape((_NPT, 2))
    o += _NPT * 2
    JP = scratch[o : o + _NPT * 12].reshape((_NPT, 2, 6))
    o += _NPT * 12
    BP = scratch[o : o + _NPT * 2].reshape((_NPT, 2))
    o += _NPT * 2
    ang = scratch[o : o + 7]
    Ja = scratch[o + 7 : o + 49].reshape((7, 6))
    ba = scratch[o + 49 : o + 56]
    w = scratch[o + 56 : o + 63]
    cs = scratch[o + 63 : o + 70]  # cos and sin of each angle, computed once
    sn = scratch[o + 70 : o + 77]
    P[_O4, 0] = geo[G_L5]
    P[_O6, 0] = geo[G_O6X]
    P[_O6, 1] = geo[G_O6Y]
    ang[A_TH1] = q[0]
    ang[A_TH4] = q[1]
    cs[A_TH1], sn[A_TH1] = math.cos(q[0]), math.sin(q[0])
    cs[A_TH4], sn[A_TH4] = math.cos(q[1]), math.sin(q[1])
    Ja[A_TH1, 0] = 1.0
    Ja[A_TH4, 1] = 1.0
    w[A_TH1] = qd[0]
    w[A_TH4] = qd[1]
    _arm(P, JP, BP, PT_A, _O1, geo[G_L1], A_TH1, cs, sn, Ja, ba, w)
    _arm(P, JP, BP, PT_B, _O4, geo[G_L4], A_TH4, cs, sn, Ja, ba, w)
    for r in range(2):
        P[PT_AJ, r] = P[PT_A, r] + q[2 + r]
        P[PT_BJ, r] = P[PT_B, r] + q[4 + r]
        BP[PT_AJ, r] = BP[PT_A, r]
        BP[PT_BJ, r] = BP[PT_B, r]
        for col in range(6):
            JP[PT_AJ, r, col] = JP[PT_A, r, col]
            JP[PT_BJ, r, col] = JP[PT_B, r, col]
        JP[PT_AJ, r, 2 + r] += 1.0
        JP[PT_BJ, r, 4 + r] += 1.0
    if not _rrr(
        P, JP, BP, PT_AJ, geo[G_L2], PT_BJ, geo[G_L3], 1.0, A_TH2, A_TH3, ang, cs, sn, Ja, ba, w, qd
    ):
        return FAIL_LINKS_23
    _arm(P, JP, BP, PT_P, PT_AJ, geo[G_L2], A_TH2, cs, sn, Ja, ba, w)
    if not _rrr(
        P, JP, BP, _O6, geo[G_L6], PT_P, geo[G_L71], -1.0, A_TH6, A_TH7, ang, cs, sn, Ja, ba, w, qd
    ):
        return FAIL_ROCKER_PANEL
    _arm(P, JP, BP, PT_C, _O6, geo[G_L6], A_TH6, cs, sn, Ja, ba, w)
    # theta7 is the angle of P - C, i.e. that of C - P plus pi
    ang[A_TH7] = math.atan2(-sn[A_TH7], -cs[A_TH7])
    cs[A_TH7], sn[A_TH7] = -cs[A_TH7], -sn[A_TH7]
    # D = C + L72 e(theta7 + beta): an arm on a shifted angle (slot A_TH8 used as scratch)
    ang[A_TH8] = ang[A_TH7] + geo[G_BETA]
    cb, sb = math.cos(geo[G_BETA]), math.sin(geo[G_BETA])
    cs[A_TH8] = cs[A_TH7] * cb - sn[A_TH7] * sb
    sn[A_TH8] = sn[A_TH7] * cb + cs[A_TH7] * sb
    ba[A_TH8] = ba[A_TH7]
    w[A_TH8] = w[A_TH7]
    for col in range(6):
        Ja[A_TH8, col] = Ja[A_TH7, col]
    _arm(P, JP, BP, PT_D, PT_C, geo[G_L72], A_TH8, cs, sn, Ja, ba, w)
    # RRP dyad: E = D + L8 e(theta8) on y = y_O6, E on the -X side of D
    L8 = geo[G_L8]
    dy = geo[G_O6Y] - P[PT_D, 1]
    if abs(dy) >= L8:
        return FAIL_LINK8
    dx = -math.sqrt(L8 * L8 - dy * dy)
    ang[A_TH8] = math.atan2(dy, dx)
    c8, s8 = dx / L8, dy / L8
    cs[A_TH8], sn[A_TH8] = c8, s8
    w8 = 0.0
    for col in range(6):
        Ja[A_TH8, col] = -JP[PT_D, 1, col] / (L8 * c8)
        w8 += Ja[A_TH8, col] * qd[col]
    w[A_TH8] = w8
    ba[A_TH8] = (L8 * w8 * w8 * s8 - BP[PT_D, 1]) / (L8 * c8)
    _arm(P, JP, BP, PT_E, PT_D, L8, A_TH8, cs, sn, Ja, ba, w)
    # body centroids
    _body(pos, J, gam, SLIDER9, P, JP, BP, PT_E, -1, ang, Ja, ba)
    for b, base, L, k in (
        (CRANK1, _O1, geo[G_LS1], A_TH1),
        (LINK2, PT_AJ, geo[G_LS2], A_TH2),
        (LINK3, PT_BJ, geo[G_LS3], A_TH3),
        (CRANK4, _O4, geo[G_LS4], A_TH4),
        (ROCKER6, _O6, geo[G_LS6], A_TH6),
        (LINK8, PT_D, geo[G_LS8], A_TH8),
    ):
        _centroid(pos, J, gam, b, P, JP, BP, base, L, k, ang, cs, sn, Ja, ba, w)
    # panel 7: triangle centroid (C + P + D) / 3
    for r in range(2):
        pos[PANEL7, r] = (P[PT_C, r] + P[PT_P, r] + P[PT_D, r]) / 3.0
        gam[PANEL7, r] = (BP[PT_C, r] + BP[PT_P, r] + BP[PT_D, r]) / 3.0
        for col in range(6):
            J[PANEL7, r, col] = (JP[PT_C, r, col] + JP[PT_P, r, col] + JP[PT_D, r, col]) / 3.0
    pos[PANEL7, 2] = ang[A_TH7]
    gam[PANEL7, 2] = ba[A_TH7]
    for col in range(6):
        J[PANEL7, 2, col] = Ja[A_TH7, col]
    for i in range(N_POINTS):
        for r in range(2):
            pts[i, r] = P[i, r]
            gamp[i, r] = BP[i, r]
            for col in range(6):
                Jp[i, r, col] = JP[i, r, col]
    return ASSEMBLED


@njit(cache=True)
def _centroid(pos, J, gam, b, P, JP, BP, base, L, k, ang, cs, sn, Ja, ba, w):
    """Body b with centroid at distance L from point ``base`` along angle k."""
    c = cs[k]
    s = sn[k]
    pos[b, 0] = P[base, 0] + L * c
    pos[b, 1] = P[base, 1] + L * s
    pos[b, 2] = ang[k]
    gam[b, 0] = BP[base, 0] - L * s * ba[k] - L * c * w[k] * w[k]
    gam[b, 1] = BP[base, 1] + L * c * ba[k] - L * s * w[k] * w[k]
    gam[b, 2] = ba[k]
    for col in range(6):
        J[b, 0, col] = JP[base, 0, col] - L * s * Ja[k, col]
        J[b, 1, col] = JP[base, 1, col] + L * c * Ja[k, col]
        J[b, 2, col] = Ja[k, col]
