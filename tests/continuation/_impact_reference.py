"""An independent reference for the impact oscillator's period-one impacting orbits, written for
the checks alone (it shares no code with the package): the linear flow between impacts in closed
form, the impact map, its fixed points and their multipliers.

The system: x'' + c x' + x = cos(w t) while x < g (m = k = F = 1, SI units), v -> -r v at the
stop x = g. Between impacts the state z = (x, v) is the forced response plus the free one,
``z(t) = zp(t) + V exp(L (t - t0)) V^-1 (z(t0) - zp(t0))``, with ``zp`` the steady harmonic
response (complex amplitude ``1 / (1 - w^2 + i c w)``) and ``L``, ``V`` the eigenvalues and
eigenvectors of ``[[0, 1], [-1, -c]]``. The impact map takes an impact (time t, speed v > 0
towards the stop) to the next one; a period-one orbit with one impact is its fixed point with
the time advanced by T = 2 pi / w (Shaw & Holmes 1983). Its multipliers are those of the
stroboscopic map (both are Poincare maps of one orbit), and their product is
``r^2 exp(-c T)`` (the flow's volume contraction times the impact's ``r`` and the ratio of the
impact speeds, ``r`` again, at the fixed point).

Closed form of the fixed points: with ``P = exp(A T)`` and ``(a, b) = zp(t0)``, the orbit
starting from the impact at t0, ``(g, -r v)``, returns to ``(g, v)`` one period later, so
``(g - a, v - b) = P (g - a, -r v - b)``: the first row gives ``v(t0)``, the second a scalar
equation ``F(t0, w) = 0`` for the impact time.
"""

from __future__ import annotations

import math

import numpy as np
from _differences import central_jacobian
from scipy.optimize import brentq, minimize_scalar


class ImpactReference:
    """The impact oscillator at damping ``c`` (N s/m), gap ``g`` (m), restitution ``r`` and
    forcing frequency ``w`` (rad/s)."""

    def __init__(self, c: float, g: float, r: float, w: float) -> None:
        self.c, self.g, self.r, self.w = c, g, r, w
        self.T = 2 * math.pi / w
        self.L, self.V = np.linalg.eig(np.array([[0.0, 1.0], [-1.0, -c]]))
        self.Vi = np.linalg.inv(self.V)
        self.X = 1.0 / (1.0 - w * w + 1j * c * w)
        self.P = ((self.V * np.exp(self.L * self.T)) @ self.Vi).real  # exp(A T)

    def forced(self, t):
        """The steady forced response (x, v) at time(s) t."""
        e = self.X * np.exp(1j * self.w * np.asarray(t, float))
        return np.array([e.real, (1j * self.w * e).real])

    def state(self, z0, t0: float, t):
        """(x, v) at time(s) t from z0 at t0 with no impact between."""
        t = np.asarray(t, float)
        coef = self.Vi @ (np.asarray(z0, float) - self.forced(t0))  # complex
        free = self.V @ (np.exp(np.multiply.outer(self.L, t - t0)) * coef.reshape(2, *[1] * t.ndim))
        return self.forced(t) + free.real

    def next_impact(self, t0: float, v: float, per_period: int = 2000) -> tuple[float, float]:
        """The next impact (time, speed) after leaving the stop at t0 with speed r v."""
        z0 = (self.g, -self.r * v)
        ts = t0 + np.linspace(0.0, 3 * self.T, 3 * per_period + 1)[1:]
        x = self.state(z0, t0, ts)[0] - self.g
        up = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
        if up.size == 0:
            raise ValueError("no impact within three periods")
        lo, hi = up[0], up[0] + 1

        def f(t):
            return float(self.state(z0, t0, t)[0]) - self.g

        while f(ts[lo]) >= 0 and lo > 0:  # rounding between the two evaluations
            lo -= 1
        t1 = brentq(f, ts[lo], ts[hi], xtol=1e-15, rtol=1e-15)
        return t1, float(self.state(z0, t0, t1)[1])

    def impact_map(self, z) -> np.ndarray:
        """(t, v) of an impact -> (t' - T, v') of the next one."""
        t1, v1 = self.next_impact(float(z[0]), float(z[1]))
        return np.array([t1 - self.T, v1])

    def jacobian(self, z, h: float = 1e-6) -> np.ndarray:
        """The impact map's Jacobian at z by central differences."""
        return central_jacobian(self.impact_map, z, h)

    def orbit(self, z, tolerance: float = 1e-12) -> np.ndarray:
        """The fixed point of the impact map near z, by Newton's method."""
        z = np.asarray(z, float)
        for _ in range(40):
            G = self.impact_map(z) - z
            if np.max(np.abs(G)) < tolerance:
                return z
            z = z - np.linalg.solve(self.jacobian(z) - np.eye(2), G)
        raise ValueError(f"no fixed point near {z}: residual {np.max(np.abs(G)):.3g}")

    def speed(self, t0: float) -> float:
        """The impact speed of the period-one orbit that impacts at t0 (closed form)."""
        a, b = self.forced(t0)
        return -(b + (1 - self.P[0, 0]) * (self.g - a) / self.P[0, 1]) / self.r

    def closure(self, t0: float) -> float:
        """F(t0): zero where an impact at t0 with :meth:`speed` returns one period later."""
        a, b = self.forced(t0)
        v = self.speed(t0)
        return float((self.P @ np.array([self.g - a, -self.r * v - b]))[1] - (v - b))

    def period_one(self, samples: int = 4000, checked: bool = True) -> list[np.ndarray]:
        """Every period-one orbit ``(t0, v)`` with one impact (t0 in [0, T)); ``checked``: only
        those whose flight does not reach the stop before the period ends."""
        ts = np.linspace(0.0, self.T, samples + 1)
        f = np.array([self.closure(t) for t in ts])
        out = []
        for j in np.flatnonzero(f[:-1] * f[1:] < 0):
            t0 = brentq(self.closure, ts[j], ts[j + 1], xtol=1e-15, rtol=1e-15)
            v = self.speed(t0)
            if v <= 0:
                continue
            if checked:
                try:
                    t1, v1 = self.next_impact(t0, v)
                except ValueError:
                    continue
                if abs(t1 - t0 - self.T) > 1e-9 or abs(v1 - v) > 1e-9 * max(1.0, v):
                    continue
            out.append(np.array([t0, v]))
        return out

    def margin(self, z) -> float:
        """The largest interior local maximum of x - g over the flight from the impact z to
        the next one a period later (m; -inf where x has none): zero at a grazing."""
        t0, v = float(z[0]), float(z[1])
        z0 = (self.g, -self.r * v)
        ts = t0 + np.linspace(0.0, self.T, 2001)[1:-1]
        x = self.state(z0, t0, ts)[0]
        top = np.flatnonzero((x[1:-1] > x[:-2]) & (x[1:-1] >= x[2:])) + 1
        if top.size == 0:
            return -math.inf
        i = top[np.argmax(x[top])]
        best = minimize_scalar(
            lambda t: -float(self.state(z0, t0, t)[0]),
            bounds=(ts[i - 1], ts[i + 1]),
            method="bounded",
            options={"xatol": 1e-13},
        )
        return -best.fun - self.g

    def strobe_state(self, z) -> list[float]:
        """(x, v) at the package's strobe time (forcing phase pi) after the impact z."""
        t0, v = float(z[0]), float(z[1])
        ts = math.pi / self.w
        t = ts + math.ceil((t0 - ts) / self.T) * self.T
        return [float(q) for q in self.state((self.g, -self.r * v), t0, t)]


def stable_orbit(c: float, g: float, r: float, w: float) -> np.ndarray:
    """The period-one impacting orbit with the smallest largest multiplier at w."""
    ref = ImpactReference(c, g, r, w)
    orbits = ref.period_one()
    return min(orbits, key=lambda z: float(np.max(np.abs(np.linalg.eigvals(ref.jacobian(z))))))


def flip(c: float, g: float, r: float, lo: float, hi: float) -> float:
    """The omega (rad/s) in (lo, hi) where the period-one orbit's multiplier passes -1
    (det(J + I) = 0), following the orbit by Newton from the stable one at lo."""
    z = stable_orbit(c, g, r, lo)

    def det(w: float) -> float:
        ref = ImpactReference(c, g, r, w)
        return float(np.linalg.det(ref.jacobian(ref.orbit(z)) + np.eye(2)))

    return brentq(det, lo, hi, xtol=1e-14, rtol=1e-15)


def fold(c: float, g: float, r: float, t_range, w_range) -> float:
    """The largest omega (rad/s) of the period-one orbits: the maximum over the impact time
    t0 in ``t_range`` of omega(t0), the root of F(t0, omega) in ``w_range``."""

    def omega(t0: float) -> float:
        return brentq(
            lambda w: ImpactReference(c, g, r, w).closure(t0), *w_range, xtol=1e-15, rtol=1e-15
        )

    best = minimize_scalar(lambda t: -omega(t), bounds=t_range, method="bounded",
                           options={"xatol": 1e-11})  # fmt: skip
    return -best.fun


def grazing(c: float, g: float, r: float, lo: float, hi: float, t_near: float) -> float:
    """The omega (rad/s) in (lo, hi) where the period-one orbit impacting near t0 = t_near
    reaches the stop with an interior turning point (:meth:`ImpactReference.margin` zero; past
    it the orbit continued without that contact is virtual)."""

    def margin(w: float) -> float:
        ref = ImpactReference(c, g, r, w)
        z = min(ref.period_one(8000, checked=False), key=lambda z: abs(z[0] - t_near))
        return ref.margin(z)

    return brentq(margin, lo, hi, xtol=1e-14, rtol=1e-15)
