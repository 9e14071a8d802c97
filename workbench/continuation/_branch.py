"""Branches of periodic orbits: pseudo-arclength continuation in one parameter, bifurcations
detected and located on the way, and the switch to the doubled branch at a period doubling.

Between two consecutive points of a branch a bifurcation shows as a sign change of a test
function of the Floquet multipliers ``mu`` (Seydel 2010, Sec. 7.4-7.6; Kuznetsov 2004,
Sec. 10.2):

* ``det(M - I)`` (a real multiplier through +1): a **fold** (cyclic fold, saddle-node of
  orbits) where the parameter turns back (the tangent's parameter component changes sign), a
  **branch point** where it does not (e.g. a symmetry-breaking pitchfork);
* ``det(M + I)`` (a real multiplier through -1): a **period doubling** (flip);
* the number of complex multipliers outside the unit circle: a **Neimark-Sacker** (torus)
  bifurcation;
* the number of events per period (for the clearance mechanisms: contact onsets and ends):
  a **grazing** (contact) bifurcation, where the orbit touches an event surface (Nordmark 1991;
  di Bernardo et al. 2008, Ch. 2);
* the tangent's parameter component changes sign while no multiplier passes +1: a
  **nonsmooth fold**, where the branch turns at a point the map is not smooth at (e.g. a
  contact about to lift off; a border-collision pair, di Bernardo et al. 2008, Ch. 3).

Each is located by the Illinois (regula falsi) method along the arclength between the two
points (bisection for the integer event count), each trial point corrected onto the branch.
At a period doubling the doubled branch (``P^{2k}``) leaves in the direction of the
multiplier's eigenvector ``v``: its first point is corrected on the hyperplane through
``u* + eps v`` normal to ``v`` (branch switching; Seydel 2010, Sec. 5.6).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from workbench.continuation._newton import (
    NewtonFailure,
    OrbitPoint,
    correct,
    orbit_at,
    tangent,
)
from workbench.continuation._strobe import StrobeMap

__all__ = ["LABELS", "Settings", "trace", "switch_at_doubling"]

#: point labels (CF flag_values / flag_meanings of the stored ``label``)
LABELS = {
    "regular": 0,
    "start": 1,
    "end": 2,
    "fold": 3,
    "branch_point": 4,
    "period_doubling": 5,
    "neimark_sacker": 6,
    "grazing": 7,
    "nonsmooth_fold": 8,
}
#: a multiplier counts as complex when its imaginary part exceeds this fraction of its modulus
COMPLEX = 1e-6


@dataclass
class Settings:
    """Knobs of the continuation (scaled units: states by their sizes, the parameter by
    ``pscale``)."""

    pscale: float
    bounds: tuple[float, float]
    tolerance: float = 1e-8
    step: float = 0.02
    max_step: float = 0.1
    min_step: float = 1e-6
    max_points: int = 300
    locate_tolerance: float = 1e-7  # of pscale, for the located bifurcations
    max_iterations: int = 8


@dataclass
class Traced:
    """A traced branch: its points (special points included, in order), their labels, the
    map, and the reason it ended."""

    smap: StrobeMap
    points: list[OrbitPoint] = field(default_factory=list)
    labels: list[str] = field(default_factory=list)
    critical: list[complex] = field(default_factory=list)
    ended: str = ""
    evaluations: int = 0
    wall_time: float = 0.0


def _tests(pt: OrbitPoint) -> dict:
    M = pt.value.M
    m = M.shape[0]
    mu = pt.multipliers
    cplx = np.abs(mu.imag) > COMPLEX * np.maximum(np.abs(mu), 1e-300)
    return {
        "size": m,
        "fold": float(np.linalg.det(M - np.eye(m))),
        "pd": float(np.linalg.det(M + np.eye(m))),
        "ns": int(np.sum(cplx & (np.abs(mu) > 1.0))),
        "events": pt.value.events,
        "turn": float(pt.tau[-1]),
    }


def _ns_value(pt: OrbitPoint) -> float:
    mu = pt.multipliers
    cplx = np.abs(mu.imag) > COMPLEX * np.maximum(np.abs(mu), 1e-300)
    return float(np.max(np.abs(mu[cplx])) - 1.0) if cplx.any() else float("nan")


def _detect(a: dict, b: dict) -> list[str]:
    if a["size"] != b["size"]:
        return []
    found = []
    turned = np.sign(a["turn"]) != np.sign(b["turn"])
    if np.sign(a["fold"]) != np.sign(b["fold"]):
        found.append("fold" if turned else "branch_point")
    elif turned:
        found.append("nonsmooth_fold")
    if np.sign(a["pd"]) != np.sign(b["pd"]):
        found.append("period_doubling")
    if a["ns"] != b["ns"]:
        found.append("neimark_sacker")
    if a["events"] != b["events"]:
        found.append("grazing")
    return found


def _predict(smap: StrobeMap, A: OrbitPoint, u: np.ndarray, pscale: float) -> OrbitPoint:
    s = smap.scale()
    n = A.y.size
    live = A.value.live
    y = s * u[:n]
    aux = A.aux.copy()
    aux[live] = u[n:-1]
    return OrbitPoint(float(u[-1] * pscale), y, aux, A.value, 0, np.inf)


def _at(smap, A: OrbitPoint, sigma: float, cfg: Settings) -> OrbitPoint:
    """The branch point at arclength ``sigma`` from A along A's tangent."""
    s = smap.scale()
    u_pred = A.u(s, cfg.pscale) + sigma * A.tau
    pred = _predict(smap, A, u_pred, cfg.pscale)
    B = correct(
        smap,
        pred,
        A.tau,
        u_pred,
        cfg.pscale,
        tolerance=cfg.tolerance,
        max_iterations=cfg.max_iterations,
    )
    if B.Pp is None:  # converged at the prediction: the column there
        B.Pp = smap.parameter_derivative(B.y, B.aux, B.p, B.value.live, cfg.pscale)
        B.evaluations += 2
    B.tau = tangent(B, A.tau)
    return B


def _grazing_test(smap, A: OrbitPoint, B: OrbitPoint):
    """The smooth test of a grazing between A and B: the extreme value of an event function
    along the orbit that changes sign between them (its largest value: a contact appears or
    vanishes; its smallest: a lasting contact starts to lift off), or None."""
    a_max, a_min = smap.event_extrema(A.y, A.aux, A.p)
    b_max, b_min = smap.event_extrema(B.y, B.aux, B.p)
    for k in range(a_max.size):
        if np.sign(a_max[k]) != np.sign(b_max[k]):
            return lambda pt, k=k: float(smap.event_extrema(pt.y, pt.aux, pt.p)[0][k])
        if np.sign(a_min[k]) != np.sign(b_min[k]):
            return lambda pt, k=k: float(smap.event_extrema(pt.y, pt.aux, pt.p)[1][k])
    return None


def _locate(smap, A: OrbitPoint, B: OrbitPoint, h: float, kind: str, cfg: Settings):
    """The bifurcation ``kind`` between A and B (B at arclength h from A): the Illinois method
    on its test function (for a grazing, the extreme value of the event function that changes
    sign; bisection on the event count if none does); returns the point and its evaluations."""
    evals = 0
    integer = False
    if kind in ("fold", "branch_point"):
        value = lambda pt: _tests(pt)["fold"]  # noqa: E731
    elif kind == "period_doubling":
        value = lambda pt: _tests(pt)["pd"]  # noqa: E731
    elif kind == "neimark_sacker":
        value = _ns_value
    elif kind == "nonsmooth_fold":
        value = lambda pt: float(pt.tau[-1])  # noqa: E731
    else:
        value = _grazing_test(smap, A, B)
        if value is None:
            integer = True
            value = lambda pt: float(pt.value.events)  # noqa: E731

    lo, hi, f_lo, f_hi = 0.0, h, value(A), value(B)
    best, side = B, 0
    for _ in range(60):
        if abs(hi - lo) * max(abs(A.tau[-1]), 1e-3) < cfg.locate_tolerance:
            break
        if integer or not (np.isfinite(f_lo) and np.isfinite(f_hi)) or f_lo == f_hi:
            mid = 0.5 * (lo + hi)
        else:
            mid = hi - f_hi * (hi - lo) / (f_hi - f_lo)
            if not lo < mid < hi:
                mid = 0.5 * (lo + hi)
        try:
            pt = _at(smap, A, mid, cfg)
        except NewtonFailure:
            break
        evals += pt.evaluations
        f = value(pt)
        best = pt
        same_as_lo = (f == f_lo) if integer else (np.sign(f) == np.sign(f_lo))
        if same_as_lo:
            lo, f_lo = mid, f
            if side == -1 and not integer:
                f_hi /= 2.0
            side = -1
        else:
            hi, f_hi = mid, f
            if side == 1 and not integer:
                f_lo /= 2.0
            side = 1
        if not integer and f == 0.0:
            break
    return best, evals


def _critical(pt: OrbitPoint, kind: str) -> complex:
    mu = pt.multipliers
    if kind in ("fold", "branch_point"):
        return complex(mu[np.argmin(np.abs(mu - 1.0))])
    if kind == "period_doubling":
        return complex(mu[np.argmin(np.abs(mu + 1.0))])
    if kind == "nonsmooth_fold":
        return complex(mu[0])
    if kind == "neimark_sacker":
        cplx = np.abs(mu.imag) > COMPLEX * np.abs(mu)
        if cplx.any():
            c = mu[cplx]
            return complex(c[np.argmin(np.abs(np.abs(c) - 1.0))])
    return complex(np.nan, np.nan)


def trace(
    smap: StrobeMap, first: OrbitPoint, direction: np.ndarray, cfg: Settings, label="start"
) -> Traced:
    """Continue a branch from the converged point ``first`` along ``direction`` (scaled
    unknowns) until the parameter leaves ``cfg.bounds``, the step falls below
    ``cfg.min_step`` or ``cfg.max_points`` points are found."""
    wall0 = time.perf_counter()
    out = Traced(smap)
    if first.Pp is None:
        first.Pp = smap.parameter_derivative(
            first.y, first.aux, first.p, first.value.live, cfg.pscale
        )
        out.evaluations += 2
    first.tau = tangent(first, direction)
    out.points.append(first)
    out.labels.append(label)
    out.critical.append(complex(np.nan, np.nan))
    out.evaluations += first.evaluations
    lo, hi = cfg.bounds
    h = cfg.step
    A = first
    while len(out.points) < cfg.max_points:
        try:
            B = _at(smap, A, h, cfg)
        except NewtonFailure as exc:
            h /= 2.0
            if h < cfg.min_step:
                out.ended = f"the corrector failed at the smallest step ({exc})"
                _mark_end(smap, A, h, cfg, out)
                break
            continue
        out.evaluations += B.evaluations
        if float(A.tau @ B.tau) < 0.5:  # too sharp a turn: halve
            h /= 2.0
            if h < cfg.min_step:
                out.ended = (
                    f"the branch turns sharply at {A.p:.10g} however short the step (the map "
                    "is not smooth there)"
                )
                _mark_end(smap, A, h, cfg, out)
                break
            continue
        for kind in _detect(_tests(A), _tests(B)):
            pt, evals = _locate(smap, A, B, h, kind, cfg)
            out.evaluations += evals
            if lo <= pt.p <= hi:
                out.points.append(pt)
                out.labels.append(kind)
                out.critical.append(_critical(pt, kind))
        if not lo <= B.p <= hi:
            out.ended = "the parameter left its range"
            break
        out.points.append(B)
        out.labels.append("regular")
        out.critical.append(complex(np.nan, np.nan))
        A = B
        if B.iterations <= 3:
            h = min(1.5 * h, cfg.max_step)
        elif B.iterations >= 6:
            h /= 1.5
    else:
        out.ended = f"{cfg.max_points} points reached"
    # a located point is appended before the regular point that brackets it with the one
    # before: the list is in order of arclength
    if len(out.points) > 1 and out.labels[-1] == "regular":
        out.labels[-1] = "end"
    out.wall_time = time.perf_counter() - wall0
    return out


def _mark_end(smap: StrobeMap, A: OrbitPoint, h: float, cfg: Settings, out: Traced) -> None:
    """Where a branch ends because it cannot be continued: if a contact appears, ends or is
    held differently just beyond the last point (the events per period or the live discrete
    states differ at the predicted next point), the last point is where the orbit's contact
    structure changes: labelled grazing. With a discrete state that is held through a lasting
    contact (the mechanisms' onset velocity of the contact damping), the map jumps there: a
    contact that starts again takes a new onset velocity, so the branch cannot be continued
    through it."""
    s = smap.scale()
    u = A.u(s, cfg.pscale) + 4 * cfg.min_step * A.tau
    beyond = _predict(smap, A, u, cfg.pscale)
    try:
        v = smap(beyond.y, beyond.aux, beyond.p, tangent=False)
    except Exception:  # noqa: BLE001 - the reason is reported as it is
        return
    changed = v.events != A.value.events or not np.array_equal(v.live, A.value.live)
    try:
        gmax, gmin = smap.event_extrema(A.y, A.aux, A.p)
        if gmax.size:
            out.ended += (
                f"; event functions along the last orbit: largest {gmax.max():.3g}, smallest "
                f"{gmin.min():.3g}"
            )
    except Exception:  # noqa: BLE001, S110 - a diagnosis only
        pass
    if changed and out.points and out.points[-1] is A:
        out.labels[-1] = "grazing"
        out.ended += (
            f"; the contact structure changes there (events per {smap.periods} period(s) "
            f"{A.value.events} -> {v.events}, live discrete states {A.value.live.tolist()} -> "
            f"{v.live.tolist()})"
        )


def switch_at_doubling(
    smap: StrobeMap, pd: OrbitPoint, cfg: Settings, epsilon: float = 0.05
) -> tuple[StrobeMap, OrbitPoint, np.ndarray]:
    """The first point of the period-2k branch born at the period doubling ``pd`` of the
    period-k branch of ``smap``, and the direction to continue it in (away from ``pd``).

    The offset ``epsilon`` (scaled units) along the eigenvector is halved until the corrected
    point lies within ``1e-3`` of the parameter range from the bifurcation: the doubled
    branch leaves as a parabola (p - p* ~ epsilon^2) whose width shrinks down a cascade."""
    mu, vecs = np.linalg.eig(pd.value.M)
    i = int(np.argmin(np.abs(mu + 1.0)))
    v = np.real(vecs[:, i])
    v /= np.linalg.norm(v)
    double = smap.with_periods(2 * smap.periods)
    s = smap.scale()
    u_star = pd.u(s, cfg.pscale)
    m = v.size
    tau0 = np.concatenate([v, [0.0]])
    failure: Exception | None = None
    while epsilon >= 1e-5:
        u0 = u_star + epsilon * tau0
        pred = _predict(smap, pd, u0, cfg.pscale)
        try:
            first = correct(
                double,
                pred,
                tau0,
                u0,
                cfg.pscale,
                tolerance=cfg.tolerance,
                max_iterations=2 * cfg.max_iterations,
            )
        except NewtonFailure as exc:
            failure, epsilon = exc, epsilon / 2.0
            continue
        if abs(first.p - pd.p) <= 1e-3 * cfg.pscale:
            break
        epsilon /= 2.0
    else:
        raise NewtonFailure(f"no doubled orbit near the period doubling ({failure})")
    if first.value.M.shape[0] != m:
        raise NewtonFailure("the doubled orbit has other live discrete states; cannot switch")
    away = first.u(s, cfg.pscale) - u_star
    return double, first, away / np.linalg.norm(away)


#: Newton's iterations at most for the first orbit of a branch (from a guess, not a prediction)
START_ITERATIONS = 30


def start_point(
    smap: StrobeMap, y, aux, p: float, cfg: Settings, max_iterations: int = START_ITERATIONS
) -> OrbitPoint:
    """The converged orbit at ``p`` from the guess (y, aux), in at most ``max_iterations``
    Newton iterations (:class:`NewtonFailure` otherwise)."""
    return orbit_at(smap, y, aux, p, tolerance=cfg.tolerance, max_iterations=max_iterations)
