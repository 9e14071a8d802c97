"""Reference systems for the time-series Lyapunov estimators: maps and flows with the exponent
of the very orbit or window that the series samples.

A series and its reference come from one computation: a map is iterated together with its
Jacobian, a flow is integrated (scipy's ``solve_ivp``, DOP853) together with its variational
equations, and the tangent vector is renormalised every iteration (maps) or every ~5 s of
integration (flows) (Benettin, Galgani, Giorgilli & Strelcyn 1980, Meccanica 15, 9; with one
vector the QR step is a normalisation). The tangent vector is aligned with the most unstable
direction during the transient, before the window starts, so the sum of log growths over the
window is the window's finite-time largest Lyapunov exponent.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

#: Published largest Lyapunov exponents (base e): per iteration for the maps, 1/s for the
#: flows. Sprott (2003), Appendix A, and its web version "Common chaotic systems" (Sprott,
#: 1998-2004); for the Tinkerbell map 0.19978 (Dobriyanchik, "Tinkerbell map", ChaosSoft
#: notes, 2024), which the product of Jacobians reproduces (0.2000 over 10^7 iterates).
PUBLISHED = {
    "henon": 0.41922,  # a = 1.4, b = 0.3
    "lozi": 0.47023,  # a = 1.7, b = 0.5
    "ikeda": 0.50760,  # mu = 0.9
    "logistic": math.log(2.0),  # r = 4: ln 2 exactly
    "tinkerbell": 0.19978,  # a = 0.9, b = -0.6013, c = 2.0, d = 0.5 (not Sprott: see above)
    "lorenz": 0.9056,  # sigma = 10, rho = 28, beta = 8/3
    "rossler": 0.0714,  # a = b = 0.2, c = 5.7
}


@dataclass(frozen=True)
class Reference:
    """A sampled scalar series (``x``, first state component) with the finite-time largest
    Lyapunov exponent of the same orbit or window (``lle``: per iteration for a map, 1/s for
    a flow; per forcing period for a stroboscopic section) and the sampling step ``dt``
    (None for a map)."""

    x: np.ndarray
    lle: float
    dt: float | None


# ---- maps: (state) -> next state, (state) -> Jacobian --------------------------------------


def _henon(s):
    x, y = s
    return np.array([1.0 - 1.4 * x * x + y, 0.3 * x]), np.array([[-2.8 * x, 1.0], [0.3, 0.0]])


def _lozi(s):
    x, y = s
    return (
        np.array([1.0 - 1.7 * abs(x) + y, 0.5 * x]),
        np.array([[-1.7 * math.copysign(1.0, x), 1.0], [0.5, 0.0]]),
    )


def _ikeda(s, mu=0.9):
    x, y = s
    r2 = 1.0 + x * x + y * y
    t = 0.4 - 6.0 / r2
    c, sn = math.cos(t), math.sin(t)
    dt_dx, dt_dy = 12.0 * x / r2**2, 12.0 * y / r2**2
    # d/dx of (x cos t - y sin t) = cos t + (-x sin t - y cos t) dt/dx, etc.
    a = -x * sn - y * c
    b = x * c - y * sn
    jac = mu * np.array(
        [[c + a * dt_dx, -sn + a * dt_dy], [sn + b * dt_dx, c + b * dt_dy]],
    )
    return np.array([1.0 + mu * (x * c - y * sn), mu * (x * sn + y * c)]), jac


def _logistic(s):
    (x,) = s
    return np.array([4.0 * x * (1.0 - x)]), np.array([[4.0 - 8.0 * x]])


def _tinkerbell(s):
    x, y = s
    a, b, c, d = 0.9, -0.6013, 2.0, 0.5
    return (
        np.array([x * x - y * y + a * x + b * y, 2.0 * x * y + c * x + d * y]),
        np.array([[2.0 * x + a, -2.0 * y + b], [2.0 * y + c, 2.0 * x + d]]),
    )


MAPS: dict[str, tuple[Callable, tuple[np.ndarray, np.ndarray]]] = {
    # name: (step, (low, high) of the box the initial state is drawn from)
    "henon": (_henon, (np.array([-0.1, -0.05]), np.array([0.1, 0.05]))),
    "lozi": (_lozi, (np.array([-0.1, -0.05]), np.array([0.1, 0.05]))),
    "ikeda": (_ikeda, (np.array([0.0, 0.0]), np.array([0.5, 0.5]))),
    "logistic": (_logistic, (np.array([0.1]), np.array([0.9]))),
    "tinkerbell": (_tinkerbell, (np.array([-0.75, -0.6]), np.array([-0.70, -0.55]))),
}


def map_series(name: str, n: int, seed: int, transient: int = 1000) -> Reference:
    """``n`` iterates of the first coordinate of map ``name`` (after ``transient``) and the
    largest Lyapunov exponent of that orbit (per iteration) from the product of Jacobians."""
    step, (lo, hi) = MAPS[name]
    s = np.random.default_rng(seed).uniform(lo, hi)
    v = np.ones(s.size) / math.sqrt(s.size)
    x = np.empty(n)
    total = 0.0
    for i in range(transient + n):
        if i >= transient:
            x[i - transient] = s[0]
        s, jac = step(s)
        v = jac @ v
        g = float(np.linalg.norm(v))
        v /= g
        if i >= transient and i < transient + n - 1:  # growth from sample i to sample i + 1
            total += math.log(g)
    return Reference(x, total / (n - 1), None)


# ---- flows: the state and one tangent vector -------------------------------------------------


def _lorenz(t, u, sigma=10.0, rho=28.0, beta=8.0 / 3.0):
    x, y, z, a, b, c = u
    return [
        sigma * (y - x),
        x * (rho - z) - y,
        x * y - beta * z,
        sigma * (b - a),
        (rho - z) * a - b - x * c,
        y * a + x * b - beta * c,
    ]


def _rossler(t, u, a=0.2, b=0.2, c=5.7):
    x, y, z, p, q, r = u
    return [-y - z, x + a * y, b + z * (x - c), -q - r, p + a * q, z * p + (x - c) * r]


def _duffing(t, u, delta=0.3, alpha=-1.0, beta=1.0, gamma=0.5, omega=1.2):
    x, v, p, q = u
    return [
        v,
        gamma * math.cos(omega * t) - delta * v - alpha * x - beta * x**3,
        q,
        -delta * q - (alpha + 3.0 * beta * x * x) * p,
    ]


FLOWS: dict[str, tuple[Callable, int, tuple[np.ndarray, np.ndarray], float]] = {
    # name: (right-hand side of state + tangent, state size, initial box, transient in s)
    "lorenz": (_lorenz, 3, (np.array([-10.0, -10.0, 15.0]), np.array([10.0, 10.0, 35.0])), 20.0),
    "rossler": (_rossler, 3, (np.array([-5.0, -5.0, 0.0]), np.array([5.0, 5.0, 0.5])), 150.0),
    "duffing": (
        _duffing,
        2,
        (np.array([-1.0, -0.5]), np.array([1.0, 0.5])),
        50 * 2 * math.pi / 1.2,
    ),
}


def flow_series(
    name: str, n: int, dt: float, seed: int, rtol: float = 1e-8, method: str = "DOP853"
) -> Reference:
    """``n`` samples, ``dt`` apart, of the first state component of flow ``name`` after its
    transient, with the finite-time largest Lyapunov exponent (1/s) of the same window: the
    state and a tangent vector are integrated together and the vector is renormalised after
    every block of samples (Benettin et al. 1980). For the forced Duffing oscillator pass
    ``dt`` = its period 2 pi / 1.2 for the stroboscopic section (sampled at whole periods)."""
    rhs, m, (lo, hi), transient = FLOWS[name]
    rng = np.random.default_rng(seed)
    u = np.concatenate([rng.uniform(lo, hi), np.ones(m) / math.sqrt(m)])
    t0 = math.ceil(transient / dt) * dt  # the window starts on the sampling grid
    opts = {"method": method, "rtol": rtol, "atol": rtol}
    u = solve_ivp(rhs, (0.0, t0), u, **opts).y[:, -1]
    u[m:] /= np.linalg.norm(u[m:])
    x = np.empty(n)
    x[0] = u[0]
    total = 0.0
    # blocks of samples spanning about 5 s (at least one sample): the tangent vector is
    # renormalised at the end of each, which keeps it far from overflow (Lorenz: e^5 per block)
    block = max(1, int(5.0 / dt))
    k = 1
    while k < n:
        kk = min(n - k, block)
        t = t0 + dt * np.arange(k - 1, k + kk)
        sol = solve_ivp(rhs, (t[0], t[-1]), u, t_eval=t, **opts)
        x[k : k + kk] = sol.y[0, 1:]
        u = sol.y[:, -1]
        g = float(np.linalg.norm(u[m:]))
        u[m:] /= g
        total += math.log(g)
        k += kk
    return Reference(x, total / ((n - 1) * dt), dt)
