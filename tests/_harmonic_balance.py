"""Harmonic balance of the forced Duffing oscillator, an independent formulation of its
frequency response (tests only).

x'' + delta x' + alpha x + beta x^3 = gamma cos(omega t); x = a_0 + sum_k a_k cos(k tau)
+ b_k sin(k tau), tau = omega t, up to harmonic H. The residual is projected on the same basis
by the alternating frequency-time method (samples of one period, N > 3 (2H + 1) / 2 so the
cubic term does not alias; Cameron & Griffin 1989). The response curve is traced by the first
harmonic's amplitude r = sqrt(a_1^2 + b_1^2): for each r, Newton's method (scipy's ``root``)
solves the 2H + 1 balance equations and a_1^2 + b_1^2 = r^2 for the coefficients and omega,
from the single-harmonic solution (Nayfeh & Mook 1979, Sec. 4.1). The folds of the response,
where the jumps of a slow sweep occur, are the extremes of omega(r) on the branch above the
backbone (omega^2 > alpha + 3/4 beta r^2).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import minimize_scalar, root


def single_harmonic_omega(alpha, beta, delta, gamma, r, side=+1) -> float:
    """omega of the single-harmonic balance at amplitude r: the root of
    (alpha + 3/4 beta r^2 - w^2)^2 r^2 + delta^2 w^2 r^2 = gamma^2 above (side +1) or below
    (-1) the backbone; nan where there is none."""
    k = alpha + 0.75 * beta * r * r
    b = 2 * k - delta * delta
    disc = b * b - 4 * (k * k - gamma * gamma / (r * r))
    if disc < 0:
        return math.nan
    u = 0.5 * (b + side * math.sqrt(disc))
    return math.sqrt(u) if u > 0 else math.nan


def _residual(z, alpha, beta, delta, gamma, r, H, N):
    a0 = z[0]
    a = z[1 : 2 * H + 1 : 2]
    b = z[2 : 2 * H + 1 : 2]
    w = z[-1]
    tau = 2 * math.pi * np.arange(N) / N
    k = np.arange(1, H + 1)[:, None]
    c, s = np.cos(k * tau), np.sin(k * tau)
    x = a0 + a @ c + b @ s
    xd = w * ((-a * k[:, 0]) @ s + (b * k[:, 0]) @ c)
    xdd = -(w**2) * ((a * k[:, 0] ** 2) @ c + (b * k[:, 0] ** 2) @ s)
    f = xdd + delta * xd + alpha * x + beta * x**3 - gamma * np.cos(tau)
    out = np.empty(2 * H + 2)
    out[0] = f.mean()
    out[1 : 2 * H + 1 : 2] = 2 * (c @ f) / N
    out[2 : 2 * H + 1 : 2] = 2 * (s @ f) / N
    out[-1] = z[1] ** 2 + z[2] ** 2 - r * r
    return out


def omega_at(alpha, beta, delta, gamma, r, H=7, side=+1) -> float:
    """omega (rad s-1 in the model's time unit) of the H-harmonic solution with first-harmonic
    amplitude r, on the given side of the backbone."""
    w = single_harmonic_omega(alpha, beta, delta, gamma, r, side)
    K = alpha + 0.75 * beta * r * r - w * w
    d = K * K + (delta * w) ** 2
    z = np.zeros(2 * H + 2)
    z[1], z[2] = gamma * K / d, gamma * delta * w / d
    z[1:3] *= r / math.hypot(z[1], z[2])
    z[-1] = w
    N = 4 * (2 * H + 1)
    sol = root(_residual, z, args=(alpha, beta, delta, gamma, r, H, N), tol=1e-13)
    if not sol.success:
        raise RuntimeError(f"harmonic balance did not converge at r = {r}: {sol.message}")
    return float(sol.x[-1])


def folds(alpha, beta, delta, gamma, H=7) -> tuple[float, float]:
    """(omega of the jump-up fold, omega of the jump-down fold): the least and largest omega
    of the branch above the backbone, between the single-harmonic folds' amplitudes."""
    rs = np.linspace(0.05, 5.0, 5000)
    w1 = np.array([single_harmonic_omega(alpha, beta, delta, gamma, r) for r in rs])
    ok = np.isfinite(w1)
    rs, w1 = rs[ok], w1[ok]
    turns = np.flatnonzero(np.diff(np.sign(np.diff(w1)))) + 1  # local minimum, then maximum
    i_min, i_max = int(turns[0]), int(turns[1])
    lo = rs[i_min - 20], rs[i_min + 20]
    hi = rs[i_max - 20], rs[min(i_max + 20, rs.size - 1)]
    f = lambda r: omega_at(alpha, beta, delta, gamma, r, H)  # noqa: E731
    up = minimize_scalar(f, bounds=lo, method="bounded", options={"xatol": 1e-10})
    down = minimize_scalar(lambda r: -f(r), bounds=hi, method="bounded", options={"xatol": 1e-10})
    return float(up.fun), float(-down.fun)
