"""Assur groups of planar linkages: position, velocity and acceleration of each dyad in closed form.

A mechanism's kinematics is solved as a chain of Assur groups (modular kinematics; Hartenberg &
Denavit, *Kinematic Synthesis of Linkages*, 1964; Uicker, Pennock & Shigley, *Theory of Machines
and Mechanisms*, position, velocity and acceleration analysis of the four-bar and slider-crank
loops): each group's position routine returns the unit vectors of its links and the factors that
solve its differentiated closure equations, which depend on the position only, so that the
velocity and acceleration routines are a few products each.

Every routine takes and returns scalars (no arrays), and is inlined into its caller
(``inline="always"``), so that a whole mechanism's pass compiles to straight-line code in
registers. Used by the ``ninebar`` (two RRR dyads and an RRP dyad), the ``slider_crank`` (an
RRP dyad) and declared linkages (RRR, RRP and RPR dyads). Units: m, rad, s.
"""

from __future__ import annotations

import math

from numba import njit

__all__ = [
    "arm_acceleration",
    "arm_velocity",
    "rrp_acceleration",
    "rrp_position",
    "rrp_velocity",
    "rpr_acceleration",
    "rpr_position",
    "rpr_velocity",
    "rrr_acceleration",
    "rrr_position",
    "rrr_velocity",
]


@njit(cache=True, inline="always")
def rrr_position(x1, y1, x2, y2, l1, l2, side):
    """RRR dyad, position: the joint X with |X - P1| = l1 and |X - P2| = l2.

    Intersection of two circles (the dyad of a four-bar loop; Hartenberg & Denavit 1964; Uicker,
    Pennock & Shigley). Also returns the factors that solve the dyad's velocity and acceleration
    equations, which depend on the position only.

    Parameters
    ----------
    x1, y1, x2, y2 : float
        Known joints P1, P2 (m).
    l1, l2 : float
        Link lengths from P1 and from P2 (m).
    side : float
        +1: X left of P1 -> P2 (cross(P2 - P1, X - P1) > 0); -1: right of it.

    Returns
    -------
    (ok, c1, s1, c2, s2, f1, f2) : (bool, float, ...)
        Unit vectors e1 = (c1, s1) = (X - P1) / l1 and e2 = (c2, s2) = (X - P2) / l2, and
        f1 = 1 / (l1 sin(a2 - a1)), f2 = 1 / (l2 sin(a2 - a1)) (m-1) for the link angles a1, a2.
        ok is False (the rest zero) where the circles do not meet in two points, or on NaN.
    """
    dx = x2 - x1
    dy = y2 - y1
    d2 = dx * dx + dy * dy
    if not d2 > 0.0:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    # X - P1 = a u + h perp(u), u = (P2 - P1) / d; with ta = a / d and th = h / d one division
    # and one square root suffice
    inv_d2 = 1.0 / d2
    ta = 0.5 * (l1 * l1 - l2 * l2 + d2) * inv_d2
    th2 = l1 * l1 * inv_d2 - ta * ta
    if not th2 > 0.0:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    th = side * math.sqrt(th2)
    rx = ta * dx - th * dy
    ry = ta * dy + th * dx
    inv_l1 = 1.0 / l1
    inv_l2 = 1.0 / l2
    g = inv_d2 / th  # 1 / (d h), as sin(a2 - a1) = cross(e1, e2) = d h / (l1 l2)
    return True, rx * inv_l1, ry * inv_l1, (rx - dx) * inv_l2, (ry - dy) * inv_l2, l2 * g, l1 * g


@njit(cache=True, inline="always")
def rrr_velocity(c1, s1, c2, s2, f1, f2, v1x, v1y, v2x, v2y):
    """RRR dyad, velocity: the link angular velocities from the known joints' velocities.

    Solves the differentiated closure P1 + l1 e1 = P2 + l2 e2,
    l1 w1 perp(e1) - l2 w2 perp(e2) = v2 - v1 with perp(c, s) = (-s, c), by projecting it on
    e2 and on e1.

    Parameters
    ----------
    c1, s1, c2, s2, f1, f2 : float
        From :func:`rrr_position`.
    v1x, v1y, v2x, v2y : float
        Velocities of P1 and P2 (m s-1).

    Returns
    -------
    (w1, w2) : (float, float)
        Angular velocities of the links P1-X and P2-X (rad s-1).
    """
    rx = v2x - v1x
    ry = v2y - v1y
    return f1 * (rx * c2 + ry * s2), f2 * (rx * c1 + ry * s1)


@njit(cache=True, inline="always")
def rrr_acceleration(c1, s1, c2, s2, f1, f2, l1, l2, w1, w2, a1x, a1y, a2x, a2y):
    """RRR dyad, acceleration: the link angular accelerations.

    Solves the closure differentiated twice, l1 al1 perp(e1) - l2 al2 perp(e2) =
    a2 - a1 + l1 w1^2 e1 - l2 w2^2 e2, as in :func:`rrr_velocity`.

    Parameters
    ----------
    c1, s1, c2, s2, f1, f2 : float
        From :func:`rrr_position`.
    l1, l2 : float
        Link lengths (m).
    w1, w2 : float
        Link angular velocities from :func:`rrr_velocity` (rad s-1).
    a1x, a1y, a2x, a2y : float
        Accelerations of P1 and P2 (m s-2).

    Returns
    -------
    (al1, al2) : (float, float)
        Angular accelerations of the links P1-X and P2-X (rad s-2).
    """
    l1w2 = l1 * w1 * w1
    l2w2 = l2 * w2 * w2
    return rrr_velocity(
        c1, s1, c2, s2, f1, f2, 0.0, 0.0,
        a2x - a1x + l1w2 * c1 - l2w2 * c2, a2y - a1y + l1w2 * s1 - l2w2 * s2,
    )  # fmt: skip


@njit(cache=True, inline="always")
def rrp_position(xd, yd, gx, gy, ux, uy, length, side):
    """RRP dyad, position: a link from the joint D to a slider joint E on a fixed guide.

    E = G + sE u with |E - D| = length: intersection of a circle and a line (the dyad of a
    slider-crank loop; Hartenberg & Denavit 1964; Uicker, Pennock & Shigley). Also returns the
    factors that solve the velocity and acceleration equations.

    Parameters
    ----------
    xd, yd : float
        Known joint D (m).
    gx, gy, ux, uy : float
        A point G of the guide line (m) and its unit direction u.
    length : float
        Link length DE (m).
    side : float
        +1: E ahead of the foot of D along u; -1: behind it.

    Returns
    -------
    (ok, c, s, sE, fw, fs) : (bool, float, ...)
        Link unit vector (c, s) = (E - D) / length, slider coordinate sE along the guide (m),
        fw = 1 / (length e.u) (m-1) and fs = 1 / (e.u). ok is False (the rest zero) where D is
        ``length`` or farther from the guide, or on NaN.
    """
    wx = xd - gx
    wy = yd - gy
    dist = ux * wy - uy * wx  # signed distance of D from the guide
    h2 = (length - dist) * (length + dist)
    if not h2 > 0.0:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0
    h = side * math.sqrt(h2)  # sE - (D - G).u, and length e.u
    se = wx * ux + wy * uy + h
    fw = 1.0 / h
    inv_l = 1.0 / length
    return True, (se * ux - wx) * inv_l, (se * uy - wy) * inv_l, se, fw, length * fw


@njit(cache=True, inline="always")
def rrp_velocity(c, s, fw, fs, ux, uy, vdx, vdy):
    """RRP dyad, velocity: link angular velocity and slider velocity.

    Solves the differentiated closure D + length e = G + sE u,
    length w perp(e) - sE' u = -v_D, by projecting it on perp(u) and on e.

    Parameters
    ----------
    c, s, fw, fs : float
        From :func:`rrp_position`.
    ux, uy : float
        Guide direction (fixed guide).
    vdx, vdy : float
        Velocity of D (m s-1).

    Returns
    -------
    (w, sdot) : (float, float)
        Link angular velocity (rad s-1) and slider velocity along u (m s-1).
    """
    return fw * (uy * vdx - ux * vdy), fs * (vdx * c + vdy * s)


@njit(cache=True, inline="always")
def rrp_acceleration(c, s, fw, fs, length, ux, uy, w, adx, ady):
    """RRP dyad, acceleration: length al perp(e) - sE'' u = -a_D + length w^2 e.

    Parameters
    ----------
    c, s, fw, fs : float
        From :func:`rrp_position`.
    length : float
        Link length (m).
    ux, uy : float
        Guide direction (fixed guide).
    w : float
        Link angular velocity from :func:`rrp_velocity` (rad s-1).
    adx, ady : float
        Acceleration of D (m s-2).

    Returns
    -------
    (al, sddot) : (float, float)
        Link angular acceleration (rad s-2) and slider acceleration along u (m s-2).
    """
    lw2 = length * w * w
    return rrp_velocity(c, s, fw, fs, ux, uy, adx - lw2 * c, ady - lw2 * s)


@njit(cache=True, inline="always")
def rpr_position(x1, y1, x2, y2, offset, side):
    """RPR dyad, position: a guide link pivoted at P1 whose line passes through the pin P2 of a
    block that slides along it (the inverted slider-crank, Whitworth's quick return).

    The guide's line lies at the signed distance ``offset`` from P1 along its normal
    n = perp(u), perp(c, s) = (-s, c): n.(P2 - P1) = offset, an intersection of the line's
    normal with a circle (Hartenberg & Denavit 1964; Uicker, Pennock & Shigley, the inverted
    slider-crank). With d = P2 - P1, L = |d| and h = u.d, the closed form is
    n = (offset d + h perp(d)) / L^2, h = side sqrt(L^2 - offset^2). Also returns the factor
    that solves the velocity and acceleration equations.

    Parameters
    ----------
    x1, y1, x2, y2 : float
        Pivot P1 of the guide and pin P2 of the block (m).
    offset : float
        Signed distance of the guide's line from P1 along n (m); 0 for a line through P1.
    side : float
        +1: P2 ahead of the foot of P1 on the line along u (u.d > 0); -1: behind it.

    Returns
    -------
    (ok, c, s, h, f) : (bool, float, ...)
        Unit direction u = (c, s) of the guide's line, h = u.(P2 - P1) (m) and f = 1 / h (m-1).
        ok is False (the rest zero) where P2 lies within |offset| of P1, or on NaN.
    """
    dx = x2 - x1
    dy = y2 - y1
    d2 = dx * dx + dy * dy
    h2 = d2 - offset * offset
    if not h2 > 0.0:
        return False, 0.0, 0.0, 0.0, 0.0
    h = side * math.sqrt(h2)
    inv_d2 = 1.0 / d2
    nx = (offset * dx - h * dy) * inv_d2
    ny = (offset * dy + h * dx) * inv_d2
    return True, ny, -nx, h, 1.0 / h  # u = -perp(n)


@njit(cache=True, inline="always")
def rpr_velocity(c, s, offset, f, vx, vy):
    """RPR dyad, velocity: the guide's angular velocity and the block's sliding velocity.

    Differentiates n.d = offset (n' = -w u) and s_P2 = u.d - const (u' = w n), with
    d' = v_P2 - v_P1: w = f n.d', and the sliding velocity along u, s' = w offset + u.d'.

    Parameters
    ----------
    c, s, offset, f : float
        From :func:`rpr_position` and the line's offset (m).
    vx, vy : float
        Relative velocity v_P2 - v_P1 (m s-1).

    Returns
    -------
    (w, sdot) : (float, float)
        Angular velocity of the guide and of the block (rad s-1), sliding velocity of the
        block along u (m s-1).
    """
    w = f * (c * vy - s * vx)  # n = (-s, c)
    return w, w * offset + c * vx + s * vy


@njit(cache=True, inline="always")
def rpr_acceleration(c, s, offset, f, w, vx, vy, ax, ay):
    """RPR dyad, acceleration: al h = n.d'' - 2 w u.d' - w^2 offset (the Coriolis term
    2 w u.d'), s'' = al offset + w n.d' + u.d''.

    Parameters
    ----------
    c, s, offset, f : float
        From :func:`rpr_position` and the line's offset (m).
    w : float
        Angular velocity from :func:`rpr_velocity` (rad s-1).
    vx, vy : float
        Relative velocity v_P2 - v_P1 (m s-1).
    ax, ay : float
        Relative acceleration a_P2 - a_P1 (m s-2).

    Returns
    -------
    (al, sddot) : (float, float)
        Angular acceleration of the guide and of the block (rad s-2), sliding acceleration of
        the block along u (m s-2).
    """
    un = c * vx + s * vy  # u.d'
    nv = c * vy - s * vx  # n.d'
    al = f * (c * ay - s * ax - 2.0 * w * un - w * w * offset)
    return al, al * offset + w * nv + c * ax + s * ay


@njit(cache=True, inline="always")
def arm_velocity(vx, vy, length, w, c, s):
    """Velocity of base + length e(angle) (m s-1)."""
    return vx - length * w * s, vy + length * w * c


@njit(cache=True, inline="always")
def arm_acceleration(ax, ay, length, w, al, c, s):
    """Acceleration of base + length e(angle) (m s-2)."""
    lw2 = length * w * w
    return ax - length * al * s - lw2 * c, ay + length * al * c - lw2 * s
