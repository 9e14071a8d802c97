"""Newton's method on the stroboscopic map: a periodic orbit at a fixed parameter value, or on
the pseudo-arclength hyperplane of a branch (Keller 1977; Seydel 2010, Sec. 4.4; Allgower &
Georg 2003, Ch. 2), and the branch's tangent.

A point of a branch is ``u = (y / s, aux[live], p / pscale)``: the scaled state, the live
discrete states (:mod:`workbench.continuation._strobe`) and the scaled parameter. The orbit
condition is ``G(u) = P^k(y, aux; p) - (y, aux)`` (scaled) ``= 0``; pseudo-arclength adds
``tau . (u - u_pred) = 0`` with the tangent ``tau`` of the previous point, so that Newton's
method converges through folds, where the parameter turns back.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from workbench._errors import WorkbenchError
from workbench.continuation._contacts import ContactSequence
from workbench.continuation._strobe import MapValue, StrobeMap
from workbench.scene import SceneError
from workbench.solver import SolverError

__all__ = [
    "NewtonFailure",
    "OrbitPoint",
    "correct",
    "newton_step",
    "next_step",
    "orbit_at",
    "residual",
    "tangent",
]


class NewtonFailure(WorkbenchError, RuntimeError):
    """Newton's method did not converge (or an integration failed on the way).

    Attributes
    ----------
    last : OrbitPoint or None
        Where Newton ran out of iterations: its last iterate (the map evaluated there, its
        residual above the tolerance); None where an integration or a linear solve failed.
    """

    def __init__(self, message: str, last: OrbitPoint | None = None) -> None:
        super().__init__(message)
        self.last = last


@dataclass
class OrbitPoint:
    """A converged periodic orbit: parameter ``p``, strobe state ``y`` and discrete state
    ``aux``, the map's value there (its Jacobian ``value.M`` in the scaled unknowns), the
    derivative in the scaled parameter (``Pp``; None at a fixed parameter), Newton's work."""

    p: float
    y: np.ndarray
    aux: np.ndarray
    value: MapValue
    iterations: int
    residual: float
    Pp: np.ndarray | None = None
    evaluations: int = 0
    tau: np.ndarray | None = field(default=None, repr=False)
    #: the orbit's contact sequence, once computed (:meth:`StrobeMap.contact_sequence`)
    sequence: ContactSequence | None = field(default=None, repr=False)

    @property
    def multipliers(self) -> np.ndarray:
        """Floquet multipliers (eigenvalues of the monodromy matrix), largest modulus first."""
        mu = np.linalg.eigvals(self.value.M)
        return mu[np.lexsort((-mu.imag, -np.abs(mu)))]

    def u(self, s: np.ndarray, pscale: float) -> np.ndarray:
        """The point in scaled unknowns (y / s, aux[live], p / pscale)."""
        live = self.value.live
        return np.concatenate([self.y / s, self.aux[live], [self.p / pscale]])


def residual(v: MapValue, y, aux, s) -> np.ndarray:
    """The orbit condition ``P^k(y, aux) - (y, aux)`` in the scaled unknowns (the states
    divided by their sizes ``s``, the live discrete states in their units)."""
    live = v.live
    return np.concatenate([(v.y1 - y) / s, v.aux1[live] - aux[live]])


def live_changed(v: MapValue, periods: int, live: int) -> str:
    """Why an iterate whose live discrete states differ from its curve's (``live`` of them)
    cannot be corrected: what the iterate's orbit does."""
    return (
        f"the live discrete states changed ({v.events} events per {periods} period(s), live "
        f"discrete states {v.live.tolist()}, against {live} where it started: a contact held "
        "through the orbit lifts off and begins again within it, or the reverse)"
    )


def _evaluate(smap: StrobeMap, y, aux, p) -> MapValue:
    try:
        return smap(y, aux, p)
    except SolverError as exc:
        raise NewtonFailure(f"the map failed at p = {p:.10g}: {exc}") from exc
    except SceneError as exc:  # an iterate outside the parameter's valid range
        raise NewtonFailure(f"no orbit at p = {p:.10g}: {exc}") from exc


def orbit_at(
    smap: StrobeMap,
    y: np.ndarray,
    aux: np.ndarray,
    p: float,
    *,
    tolerance: float,
    max_iterations: int = 30,
) -> OrbitPoint:
    """Newton's method on ``P^k(x) = x`` at the fixed parameter value ``p`` from (y, aux)."""
    s = smap.scale()
    y, aux = np.array(y, float), np.array(aux, float)
    r = math.inf
    for it in range(max_iterations + 1):
        try:
            v = _evaluate(smap, y, aux, p)
        except NewtonFailure as exc:
            if it == 0:
                raise
            raise NewtonFailure(
                f"Newton's iterate {it} at p = {p:.10g} left the states the map can start from "
                f"(scaled residual {r:.3g} before that step): {exc}. The start is far from a "
                f"period-{smap.periods} orbit: a longer transient or the state of a continued "
                "sweep may be closer; workbench.continuation.strobe_period says whether the "
                "motion there is periodic at all"
            ) from exc
        G = residual(v, y, aux, s)
        r = float(np.max(np.abs(G)))
        if r < tolerance:
            return OrbitPoint(p, y, aux, v, it, r, evaluations=it + 1)
        if it == max_iterations:
            break
        step = newton_step(v, G)
        y = y + s * step[: y.size]
        aux[v.live] = aux[v.live] + step[y.size :]
    raise NewtonFailure(
        f"Newton's method did not converge at p = {p:.10g} in {max_iterations} iterations "
        f"(scaled residual {r:.3g}, tolerance {tolerance:.3g}); start closer to the orbit (a "
        "longer transient, or the state of a continued sweep) or loosen the tolerance",
        last=OrbitPoint(p, y, aux, v, it, r, evaluations=it + 1),
    )


def newton_step(value: MapValue, G: np.ndarray) -> np.ndarray:
    """Newton's step at fixed parameter from a map value with its Jacobian and its residual
    ``G`` (:func:`residual`): the solution of ``(M - I) step = -G`` in the scaled unknowns."""
    return _solve(value.M - np.eye(value.M.shape[0]), -G)


def _solve(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    try:
        x = np.linalg.solve(A, b)
    except np.linalg.LinAlgError as exc:
        raise NewtonFailure(f"singular Newton matrix ({exc})") from exc
    if not np.all(np.isfinite(x)):
        raise NewtonFailure("the Newton step is not finite (singular matrix)")
    return x


def correct(
    smap: StrobeMap,
    pred: OrbitPoint,
    tau: np.ndarray,
    u_pred: np.ndarray,
    pscale: float,
    *,
    tolerance: float,
    max_iterations: int = 8,
) -> OrbitPoint:
    """Newton's method on the pseudo-arclength system from the predicted point ``pred`` (its
    y, aux and p; ``u_pred`` in scaled unknowns, ``tau`` the tangent): ``G = 0`` and
    ``tau . (u - u_pred) = 0``. The parameter column ``Pp`` (d P / d(p / pscale), central
    differences) is computed at every iterate (a column kept from the prediction slowed the
    convergence to linear near branch points); the one of the last iterate is returned with
    the point (for its tangent)."""
    s = smap.scale()
    y, aux, p = np.array(pred.y, float), np.array(pred.aux, float), float(pred.p)
    n = y.size
    evaluations = 0
    Pp = None
    for it in range(max_iterations + 1):
        v = _evaluate(smap, y, aux, p)
        evaluations += 1
        G = residual(v, y, aux, s)
        r = float(np.max(np.abs(G)))
        u = np.concatenate([y / s, aux[v.live], [p / pscale]])
        if u.size != tau.size:
            raise NewtonFailure(
                f"{live_changed(v, smap.periods, tau.size - 1 - n)} during the correction "
                f"(iterate {it}); take a shorter step"
            )
        arc = float(tau @ (u - u_pred))
        if r < tolerance and abs(arc) < tolerance:
            return OrbitPoint(p, y, aux, v, it, r, Pp=Pp, evaluations=evaluations)
        if it == max_iterations:
            break
        try:
            Pp = smap.parameter_derivative(y, aux, p, v.live, pscale)
        except (SolverError, SceneError) as exc:
            raise NewtonFailure(f"the map failed near p = {p:.10g}: {exc}") from exc
        evaluations += 2
        m = v.M.shape[0]
        J = np.zeros((m + 1, m + 1))
        J[:m, :m] = v.M - np.eye(m)
        J[:m, m] = Pp
        J[m] = tau
        step = _solve(J, -np.concatenate([G, [arc]]))
        y = y + s * step[:n]
        aux[v.live] = aux[v.live] + step[n:m]
        p = p + pscale * step[m]
    raise NewtonFailure(
        f"the corrector did not converge near p = {p:.10g} (scaled residual {r:.3g}, "
        f"tolerance {tolerance:.3g})"
    )


def tangent(point: OrbitPoint, orientation: np.ndarray) -> np.ndarray:
    """The unit tangent of the branch at a converged point (``point.Pp`` needed), oriented
    along ``orientation`` (the previous tangent, or the direction to go)."""
    M = point.value.M
    m = M.shape[0]
    J = np.zeros((m + 1, m + 1))
    J[:m, :m] = M - np.eye(m)
    J[:m, m] = point.Pp
    J[m] = orientation
    t = _solve(J, np.concatenate([np.zeros(m), [1.0]]))
    t /= np.linalg.norm(t)
    return t if t @ orientation >= 0 else -t


def next_step(h: float, iterations: int, max_step: float) -> float:
    """The continuation step after a point that took ``iterations`` Newton iterations: 1.5 x
    ``h`` (at most ``max_step``) after an easy correction (at most 3), ``h`` / 1.5 after a hard
    one (6 or more), else ``h`` (units of ``h``: the branch's or curve's scaled arclength).

    >>> next_step(1.0, 2, 10.0), next_step(1.0, 4, 10.0), next_step(1.5, 7, 10.0)
    (1.5, 1.0, 1.0)
    """
    if iterations <= 3:
        return min(1.5 * h, max_step)
    if iterations >= 6:
        return h / 1.5
    return h
