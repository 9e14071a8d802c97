"""An independent reference for the stop oscillator's periodic orbits, written for the checks
alone (it shares no code with the package): the piecewise-linear flow in closed form on each side
of the stop, the stroboscopic map through its switchings, and its multipliers.

The system: m x'' + c x' + k x + k_s (x - g) H(x - g) = F cos(w t) (SI units). On each side the
equation is linear with constant coefficients, so the state z = (x, v) is the steady forced
response of that side plus its free response: ``z(t) = zp(t) + V exp(L (t - t0)) V^-1 (z(t0) -
zp(t0))``, with ``L``, ``V`` the eigenvalues and eigenvectors of ``[[0, 1], [-k_j / m, -c /
m]]`` (``k_j`` = k free, k + k_s in contact) and ``zp`` the harmonic response (complex amplitude
``F / (k_j - m w^2 + i c w)``) plus, in contact, the static offset ``k_s g / (k + k_s)``. The
map from the strobe time t = 0 to t = T = 2 pi / w switches sides where x crosses g (found on a
grid and by Brent's method on the closed form). The stop's force is continuous, so the map is
C^1 and its Jacobian is taken by central differences.
"""

from __future__ import annotations

import math

import numpy as np
from _differences import central_jacobian
from scipy.optimize import brentq


class StopReference:
    """The stop oscillator at mass ``m`` (kg), damping ``c`` (N s/m), stiffness ``k`` (N/m),
    stop stiffness ``ks`` (N/m), gap ``g`` (m), force ``F`` (N) and frequency ``w`` (rad/s)."""

    def __init__(self, m, c, k, ks, g, F, w, per_period: int = 1000) -> None:
        self.g, self.w, self.T = g, w, 2 * math.pi / w
        self.per_period = per_period
        self.sides = []
        for kj, offset in ((k, 0.0), (k + ks, ks * g / (k + ks))):
            L, V = np.linalg.eig(np.array([[0.0, 1.0], [-kj / m, -c / m]]))
            X = F / (kj - m * w * w + 1j * c * w)
            self.sides.append((L, V, np.linalg.inv(V), X, offset))

    def forced(self, side: int, t):
        _, _, _, X, offset = self.sides[side]
        e = X * np.exp(1j * self.w * np.asarray(t, float))
        return np.array([e.real + offset, (1j * self.w * e).real])

    def flow(self, side: int, z0, t0: float, t):
        """(x, v) at time(s) t from z0 at t0, on one side of the stop throughout."""
        L, V, Vi, _, _ = self.sides[side]
        t = np.asarray(t, float)
        coef = Vi @ (np.asarray(z0, float) - self.forced(side, t0))  # complex
        free = V @ (np.exp(np.multiply.outer(L, t - t0)) * coef.reshape(2, *[1] * t.ndim))
        return self.forced(side, t) + free.real

    def _gap(self, q: float, side: int, z, t: float) -> float:
        return float(self.flow(side, z, t, q)[0]) - self.g

    def strobe(self, z0, t0: float = 0.0) -> np.ndarray:
        """The state one period after (x, v) = z0 at t0."""
        z, t, end = np.asarray(z0, float), t0, t0 + self.T
        side = int(z[0] > self.g or (z[0] == self.g and z[1] > 0))
        while True:
            n = max(8, int(math.ceil((end - t) / self.T * self.per_period)))
            ts = np.linspace(t, end, n + 1)[1:]
            d = self.flow(side, z, t, ts)[0] - self.g
            d0 = z[0] - self.g
            prev = np.concatenate([[d0], d[:-1]])
            out = (prev <= 0) & (d > 0) if side == 0 else (prev >= 0) & (d < 0)
            hit = np.flatnonzero(out)
            if side == 0 and d0 == 0:
                hit = hit[hit > 0]
            if hit.size == 0:
                return self.flow(side, z, t, end)
            j = hit[0]
            lo = t if j == 0 else ts[j - 1]
            ts1 = brentq(self._gap, lo, ts[j], args=(side, z, t), xtol=1e-15, rtol=1e-15)
            z = self.flow(side, z, t, ts1)
            z[0] = self.g
            t, side = ts1, 1 - side

    def jacobian(self, z, h: float = 1e-7) -> np.ndarray:
        return central_jacobian(self.strobe, z, h)

    def orbit(self, z, tolerance: float = 1e-12) -> np.ndarray:
        """The period-one orbit near z (the state at t = 0), by Newton's method."""
        z = np.asarray(z, float)
        for _ in range(40):
            G = self.strobe(z) - z
            if np.max(np.abs(G)) < tolerance * max(1.0, np.max(np.abs(z))):
                return z
            z = z - np.linalg.solve(self.jacobian(z) - np.eye(2), G)
        raise ValueError(f"no period-one orbit near {z}: residual {np.max(np.abs(G)):.3g}")

    def multipliers(self, z) -> np.ndarray:
        return np.linalg.eigvals(self.jacobian(z))


NAMES = ("mass", "damping", "stiffness", "stop_stiffness", "gap", "force", "omega")


def _reference(params: dict) -> StopReference:
    return StopReference(*[params[n] for n in NAMES])


def parameter_at(params: dict, parameter: str, x0: float, v: float, p: float) -> float:
    """The value of ``parameter`` at which a period-one orbit passes x = x0 at the strobe time:
    Newton on (v, p) from (v, p), the Jacobian by central differences."""
    u = np.array([v, p], float)

    def residual(u):
        z = np.array([x0, u[0]])
        return _reference({**params, parameter: u[1]}).strobe(z) - z

    for _ in range(40):
        R = residual(u)
        if np.max(np.abs(R)) < 1e-13 * max(1.0, abs(x0), abs(u[0])):
            return float(u[1])
        u = u - np.linalg.solve(central_jacobian(residual, u, 1e-7), R)
    raise ValueError(f"no period-one orbit through x = {x0} near {u}")


def fold(params: dict, parameter: str, z, p: float, width: float) -> float:
    """The fold of the period-one orbits near the orbit z (the state at the strobe time) at
    ``parameter`` = p: the extremum of the parameter over the orbits' strobe x within
    ``width`` of z's (the orbits are parametrised by x through the fold, which turns in p)."""
    from scipy.optimize import minimize_scalar

    x, v = float(z[0]), float(z[1])
    at = {x + s * width: parameter_at(params, parameter, x + s * width, v, p) for s in (-1, 0, 1)}
    sign = 1.0 if at[x] >= max(at[x - width], at[x + width]) else -1.0  # a maximum, or minimum
    best = minimize_scalar(
        lambda q: -sign * parameter_at(params, parameter, q, v, p),
        bounds=(x - width, x + width),
        method="bounded",
        options={"xatol": 1e-12 * max(1.0, abs(x))},
    )
    return -sign * best.fun
