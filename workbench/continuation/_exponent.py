"""The largest Lyapunov exponent of one point of a chaos map or a route to chaos: from the
Floquet multipliers where the motion is periodic, from a trajectory method where it is not.

On a period-k orbit the largest exponent *is* ``ln |mu_max| / (k T)`` (``mu_max`` the Floquet
multiplier of largest modulus, ``T`` the forcing period; e.g. Parker & Chua 1989, Sec. 3.2), and
the multipliers come from the monodromy matrix of the orbit found by Newton's method
(:func:`workbench.continuation.periodic_orbit`'s machinery), exactly and cheaply. A trajectory
method is slower there and, on the nine-bar, biased: the two-trajectory method
(:func:`workbench.analysis.lle_from_equations`) renormalises a copy when its separation grows
or shrinks by a set factor (renormalised on growth alone, every copy shrank onto a contracting
orbit until its separation was the integration's noise, and the method read the noise's rate),
and on the nine-bar's contracting orbit at omega = 0.5 pi, c = 20 um it still reads above the
variational exponent on the same trajectory (docs/continuation.md, "Chaos maps", gives the
readings).

So where the strobe samples repeat with period k (:func:`workbench.continuation.strobe_period`)
the exponent is Floquet's. Its check: with the monodromy by copies (the mechanisms), the
matrix again with a 100x larger difference step, which leaves a true multiplier unchanged
(the copies stay in the linear range) and divides the differences' noise by 100 (it goes as
1 / step); with the tangent system, the orbit again at a 100x tighter tolerance. The change is
the error. Where the largest multiplier falls by more than 10x with the larger step it was the
noise floor of the differences, and the exponent is only bounded: ``ln |mu_max| / (k T)`` at
the larger step is an upper bound (``bound``). The contracting nine-bar orbit above is such
an orbit: the copies' Jacobian there is noise (entries of no structure), and the variational
monodromy of :func:`workbench.analysis.floquet` puts its exponent below the bound.

The Floquet exponent is ``converged`` where it is not a bound and its check moved it by at most
:data:`~workbench.analysis._convergence.TRUST` (20 %) of its value.

Elsewhere (no period up to 16: chaotic, quasi-periodic or a long period) the exponent is the
trajectory method's, by the analysis layer's pipeline
(:func:`workbench.analysis.largest_exponent`: its method choice, its protocols and what
each leaves out, its result type): the variational exponent for a model with an analytic
Jacobian, the two-trajectory one with the variational exponent on the same trajectories as
its check for the mechanisms (docs/continuation.md, "Chaos maps", gives what both read on
the chaotic nine-bar).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from workbench.analysis import _exponent as pipeline
from workbench.analysis._convergence import TRUST
from workbench.analysis._exponent import (
    FAST_NOT_RUN,
    MAP_SIGN,
    MAP_TARGET,
    NOT_RUN,
    PROTOCOLS,
    UNMET,
    exponent_method,
    measure_exponent,
    protocol_knobs,
    warn_unconverged,
)
from workbench.analysis._exponent import LargestExponent as PointExponent
from workbench.continuation._newton import (
    NewtonFailure,
    OrbitPoint,
    newton_step,
    orbit_at,
    residual,
)
from workbench.continuation._strobe import StrobeMap
from workbench.scene import Scene
from workbench.solver import SolverError

# the analysis layer's names a chaos map's indicators and older code import from here
__all__ = [
    "FAST_NOT_RUN",
    "MAP_SIGN",
    "MAP_TARGET",
    "METHODS",
    "NOT_RUN",
    "PROTOCOLS",
    "UNMET",
    "PointExponent",
    "exponent_method",
    "point_exponent",
]

#: how a point's exponent was measured (the flag values of ``lle_method``)
METHODS = {
    "floquet": "ln |largest Floquet multiplier| / (k T) of the period-k orbit found by Newton's "
    "method from the settled state (workbench.continuation.periodic_orbit); error: its change "
    "with a 100x larger copies' step (tangent system: at a 100x tighter tolerance); an upper "
    "bound where the multipliers are below the differences' noise",
    **pipeline.METHODS,
}
#: Newton's tolerance for the orbit (scaled residual)
ORBIT_TOLERANCE = 1e-8
#: a seeded Newton's orbit is the run's when its state at the strobe lies within this fraction of
#: each state's characteristic size of the state the run ended in (:func:`floquet_exponent`)
SEED_MATCH = 1e-3
#: Newton's iterations from a seed before it starts again from the run's end instead
SEED_ITERATIONS = 4
#: the Floquet exponent's check: the tolerance divided (tangent system) or the copies' step
#: multiplied (copies) by this
CHECK_FACTOR = 100.0
#: a largest multiplier that falls by more than this factor when the copies' step grows by
#: CHECK_FACTOR was the differences' noise
NOISE_DROP = 10.0
#: the fast protocol's map tolerance (at most the scene's rtol): a map point's Floquet exponent
#: needs the multipliers to a few per cent, not an orbit to 1e-8 of its size
FAST_RTOL = 1e-8
#: the fast protocol takes the state the run ended in as the orbit where Newton's step from it
#: is at most this (scaled units: each state by its characteristic size): the run has settled
#: onto the orbit to that distance, and the monodromy there is the orbit's to that order
SETTLED = 1e-4
#: the fast protocol's Newton tolerance (scaled residual) where the run has not settled
FAST_ORBIT_TOLERANCE = 1e-6


def _largest(M: np.ndarray, span: float) -> tuple[float, float]:
    modulus = float(np.max(np.abs(np.linalg.eigvals(M))))
    return modulus, math.log(modulus) / span


def floquet_exponent(
    scene: Scene,
    *,
    period: int,
    state=None,
    discrete_state=None,
    start_cycles: int | None = None,
    seed=None,
    fast: bool = False,
) -> PointExponent:
    """``ln |mu_max| / (k T)`` of the period-``k`` orbit Newton finds from ``state`` (state
    units; default the state after ``start_cycles`` forcing periods of the scene, default its
    transient), checked as the module docstring says (error, or an upper bound). Raises
    :class:`~workbench.continuation._newton.NewtonFailure` where Newton does not converge.

    ``seed``: ``(y, aux)``, a neighbouring point's orbit at the strobe (its
    :attr:`PointExponent.orbit`), where Newton starts first; its orbit is taken when Newton
    converges there to the orbit ``state`` lies on (within :data:`SEED_MATCH` of each state's
    characteristic size) within :data:`SEED_ITERATIONS` iterations, else Newton starts again
    from ``state``.

    ``fast`` (a map's own precision, with ``state`` where the point's run ended; copies only):
    the map at :data:`FAST_RTOL` with the monodromy and its check from one integration
    (forward differences at the copies' step and at :data:`CHECK_FACTOR` times it,
    :class:`~workbench.continuation._strobe.StrobeMap`'s ``check``), evaluated first at
    ``state``: where Newton's step from there is at most :data:`SETTLED` the run has settled
    and that evaluation is the orbit's (one integration in all); else Newton (seed first) to
    :data:`FAST_ORBIT_TOLERANCE`."""
    smap = StrobeMap(scene, None, periods=period)
    fast = fast and state is not None and smap.monodromy == "copies"
    if fast:
        rtol = min(float(smap.scene.solver["rtol"]), FAST_RTOL)
        smap = StrobeMap(scene, None, periods=period, rtol=rtol, check=CHECK_FACTOR)
    if state is None:
        y, aux = smap.initial(math.nan, start_cycles)
    else:
        y = np.asarray(state, dtype=float)
        aux = smap.prepared(math.nan).problem.aux0.copy()
        if discrete_state is not None:
            aux = np.asarray(discrete_state, dtype=float)
    span = period * smap.prepared(math.nan).period
    tolerance = FAST_ORBIT_TOLERANCE if fast else ORBIT_TOLERANCE
    pt, evaluations, seeded = None, 0, False
    if fast:
        v = smap(y, aux, math.nan)
        evaluations = 1
        G = residual(v, y, aux, smap.scale())
        if float(np.max(np.abs(newton_step(v, G)))) <= SETTLED:
            pt = OrbitPoint(math.nan, y, aux, v, 0, float(np.max(np.abs(G))), evaluations=1)
    if pt is None:
        pt, seeded, used = _orbit(smap, y, aux, seed if state is not None else None, tolerance)
        evaluations += used
    mu, lam = _largest(pt.value.M, span)
    found = {"orbit": (pt.y.copy(), pt.aux.copy()), "seeded": seeded, "evaluations": evaluations}
    if smap.monodromy == "copies":
        if fast:
            M_c, check_step = pt.value.M_check, f"{smap.step * CHECK_FACTOR:g}, forward differences"
        else:
            coarse = StrobeMap(scene, None, periods=period, step=smap.step * CHECK_FACTOR)
            M_c, check_step = coarse(pt.y, pt.aux, math.nan).M, f"{coarse.step:g}"
        mu_c, lam_c = _largest(M_c, span)
        if mu_c < mu / NOISE_DROP:
            return PointExponent(
                lam_c,
                math.nan,
                "floquet",
                bound=True,
                **found,
                detail=f"largest multiplier {mu:.3g} at step {smap.step:g}, {mu_c:.3g} at "
                f"{check_step}: below the differences' noise; the exponent is at most "
                f"{lam_c:.4g} 1/s",
            )
        check = f"a {CHECK_FACTOR:g}x larger copies' step ({check_step})"
    else:
        tight = StrobeMap(scene, None, periods=period, rtol=smap.rtol / CHECK_FACTOR)
        lam_c = _largest(
            orbit_at(tight, pt.y, pt.aux, math.nan, tolerance=ORBIT_TOLERANCE).value.M, span
        )[1]
        check = f"rtol {tight.rtol:g}"
    error = abs(lam - lam_c)
    if error <= TRUST * abs(lam):
        return PointExponent(lam, error, "floquet", **found)
    return PointExponent(
        lam,
        error,
        "floquet",
        **found,
        unmet=("floquet check",),
        detail=f"floquet check: the exponent reads {lam:.4g} 1/s and {lam_c:.4g} at {check}: "
        f"it moved by {error / max(abs(lam), 1e-300):.0%} (allowed {TRUST:.0%})",
    )


def _orbit(smap: StrobeMap, y, aux, seed, tolerance: float) -> tuple[OrbitPoint, bool, int]:
    """Newton's orbit from ``seed`` (taken where it converges within SEED_ITERATIONS to the
    orbit (y, aux) lies on, :func:`floquet_exponent`), else from (y, aux): the orbit, whether
    the seed gave it, and the map evaluations of the Newton runs that converged."""
    pt, evaluations = None, 0
    if seed is not None:
        try:
            pt = orbit_at(
                smap, seed[0], seed[1], math.nan, tolerance=tolerance,
                max_iterations=SEED_ITERATIONS,
            )  # fmt: skip
        except (NewtonFailure, SolverError, FloatingPointError, ValueError):
            pt = None  # evaluations of a failed Newton are not counted (it raised)
        else:
            evaluations = pt.evaluations
            if np.max(np.abs(pt.y - y) / smap.scale()) > SEED_MATCH:
                pt = None  # another orbit (or another phase of this one): not the run's
    if pt is not None:
        return pt, True, evaluations
    pt = orbit_at(smap, y, aux, math.nan, tolerance=tolerance)
    return pt, False, evaluations + pt.evaluations


def point_exponent(
    scene: Scene,
    *,
    period: int,
    cycles: int,
    state=None,
    discrete_state=None,
    start_cycles: int | None = None,
    start_time: float | None = None,
    protocol: str = "full",
    target: float | None = None,
    sign: float | None = None,
    seed=None,
) -> PointExponent:
    """The largest Lyapunov exponent of one point of a forced scene (see the module docstring):
    Floquet's where ``period`` (the strobe's period in forcing periods, 0 for none) is at least
    1 and Newton converges, else the trajectory method over ``cycles`` forcing periods (grown
    by doubling within its budget until its stopping rule holds). A failed run gives
    ``failed`` and a NaN value, never an exception (one hard point must not stop a map).

    Two protocols (:data:`PROTOCOLS`). ``full``: the trajectory method from four independent
    starts after the scene's transient, with the separation and growth variants (copies) and
    the error target ``target`` (default 3 %). ``fast`` (a map's own precision): everything
    starts where the point's run ended (``state``, ``discrete_state`` at ``start_time``, s,
    whole forcing periods after the problem's start, e.g. the run's ``end_time``,
    ``end_state`` and ``end_discrete_state``): Newton from there, and the trajectory method
    as one start from there (its error from the batch means of its time blocks), the
    estimate's copy alone with the variational exponent on the same trajectory (copies), its
    window grown until the standard error is at most ``target`` (default :data:`MAP_TARGET`)
    of the estimate or its sign is decided beyond ``sign`` (default :data:`MAP_SIGN`)
    standard errors, whichever first; ``rule`` says which held.

    Parameters
    ----------
    scene : Scene
        One point (single run) of a forced model.
    period : int
        The period of its strobe samples (:func:`workbench.continuation.strobe_period`).
    cycles : int
        Forcing periods of the trajectory method's window.
    state, discrete_state : array, optional
        Where Newton starts (a settled state of the point, state units).
    start_cycles : int, optional
        Without ``state``: Newton starts after this many forcing periods from the scene's
        initial state (default its transient).
    start_time : float, optional
        The time of ``state`` (s); required by the fast protocol.
    protocol : str
        ``"full"`` (default) or ``"fast"`` (see above).
    target : float, optional
        Relative standard error the trajectory method's window grows to (default 3 % for the
        full protocol, :data:`MAP_TARGET` for the fast one).
    sign : float, optional
        Fast protocol: standard errors beyond which the sign is decided and the window stops
        (default :data:`MAP_SIGN`); the full protocol has no sign rule.
    seed : (y, aux), optional
        A neighbouring point's periodic orbit at the strobe (:attr:`PointExponent.orbit`),
        where Newton starts first (:func:`floquet_exponent`; from ``state`` when it fails).
    """
    fast = protocol == "fast"
    if fast and (state is None or start_time is None):
        raise ValueError(
            "protocol='fast' starts where the point's run ended: pass state and start_time "
            "(the run's end_state and end_time)"
        )
    start = None if start_time is None else (start_time, state, discrete_state)
    protocol_knobs(protocol, target=target, sign=sign, start=start)
    notes = ""
    if period >= 1:
        try:
            return warn_unconverged(
                floquet_exponent(
                    scene,
                    period=period,
                    state=state,
                    discrete_state=discrete_state,
                    start_cycles=start_cycles,
                    seed=seed,
                    fast=fast,
                )
            )
        except (NewtonFailure, SolverError, FloatingPointError, ValueError) as exc:
            notes = f"no period-{period} orbit by Newton ({str(exc)[:160]}); "
    point = measure_exponent(
        scene, cycles=cycles, protocol=protocol, target=target, sign=sign, start=start
    )
    return warn_unconverged(dataclasses.replace(point, detail=notes + point.detail))
