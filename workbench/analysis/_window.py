"""The measurement window of an exponent from the equations: a scene advanced through its
transient, the measured length and budget, and the solver settings with which the derived
systems (tangent system, copies) are integrated."""

from __future__ import annotations

import dataclasses

import numpy as np

from workbench.analysis._convergence import BUDGET
from workbench.run import Prepared, prepare
from workbench.run import integrate as integrate_scene
from workbench.scene import SceneSource
from workbench.solver import COMPILED_METHODS, Problem, RunResult, integrate

__all__ = [
    "EXPLICIT_METHODS",
    "Window",
    "length_limit",
    "measurement_window",
    "precision_condition",
    "stopping_rule",
    "time_scale",
]

#: methods that integrate the tangent system and the copies
EXPLICIT_METHODS = ("dop853", "dopri5")


@dataclasses.dataclass(frozen=True)
class Window:
    """The measurement window of an exponent: a scene prepared at the end of its transient
    (``prepared.problem`` starts there), the measured length (s) and the solver settings."""

    prepared: Prepared
    length: float
    method: str
    rtol: float
    atol: float
    max_step: float
    max_steps: int

    @property
    def problem(self) -> Problem:
        return self.prepared.problem

    @property
    def period(self) -> float | None:
        return self.prepared.period

    def solve(self, problem: Problem, t_rec: np.ndarray, rtol: float) -> RunResult:
        """Integrate a problem derived from this window's (a tangent system, copies) with the
        window's explicit method (DOP853 for ARK548, whose implicit stages are the model's, not
        the derived system's, and for Radau IIA and ``auto``, whose Jacobian is the model's; the
        Lyapunov estimators refuse those, see :meth:`require_explicit`) at ``rtol`` (``atol`` in
        proportion); raises on a failed run."""
        res = integrate(
            problem,
            t_rec,
            method=self.method if self.method in ("dop853", "dopri5") else "dop853",
            rtol=rtol,
            atol=self.atol * rtol / self.rtol,
            max_step=self.max_step,
            max_steps=self.max_steps,
        )
        res.raise_for_status()
        return res

    def require_explicit(self) -> None:
        """Refuse a window whose method cannot integrate the derived systems: the implicit
        stages of ``radau``, ``auto`` and ``ark548`` solve with the model's Jacobian, not the
        tangent system's or the copies', and a silent switch to DOP853 would measure with
        another method than the scene names."""
        if self.method not in EXPLICIT_METHODS:
            raise ValueError(
                f"solver.method={self.method!r}: exponents from the equations integrate the "
                f"tangent system and copies of the model with an explicit method "
                f"{EXPLICIT_METHODS!r} (the implicit stages of radau, auto and ark548 use the "
                f"model's Jacobian, not the derived system's); pass method='dop853' to measure "
                f"with DOP853 (a stiff model's tangent system is stiff too: expect many steps)"
            )


def measurement_window(
    scene: SceneSource,
    *,
    cycles: int | None = None,
    duration: float | None = None,
    method: str | None = None,
    rtol: float | None = None,
    start: tuple | None = None,
) -> Window:
    """A scene's bare motion (no outputs, no energy quadratures) advanced through its transient
    with its solver, and the measured length: ``cycles`` forcing periods (forced models) or
    ``duration`` seconds, default the scene's. ``method`` and ``rtol`` override the scene's
    solver for the measurement (``atol`` follows ``rtol`` in proportion).

    ``start = (t, y, aux)`` starts the window there instead of after the transient: the time
    (s; the forcing's phase follows from it), the state and the discrete state (state units,
    the problem's order; ``aux`` None: the scene's initial discrete state), e.g. where a run
    ended (its dataset's ``end_time``, ``end_state`` and ``end_discrete_state``: the run is
    not integrated again)."""
    prep = prepare(scene, variables=())
    s = prep.scene.solver
    method = method or s["method"]
    if method not in COMPILED_METHODS:
        raise ValueError(
            f"method={method!r}: Lyapunov exponents from the equations need a compiled method "
            f"{COMPILED_METHODS!r}"
        )
    rtol_used = float(rtol) if rtol is not None else float(s["rtol"])
    atol = float(s["atol"]) * rtol_used / float(s["rtol"])
    if prep.period is not None:
        n = cycles if cycles is not None else prep.scene.run.get("cycles", 1)
        length = n * prep.period
    else:
        length = duration if duration is not None else float(prep.scene.run["duration"])
    if not length > 0:
        raise ValueError(f"the measured length must be positive; got {length!r} s")
    if start is not None:
        prep = _restarted(prep, start)
        return Window(prep, float(length), method, rtol_used, atol, s["max_step"], s["max_steps"])
    start = float(prep.times[0])
    if start > prep.problem.t0:
        res = integrate_scene(prep, [start])
        res.raise_for_status()
        prep = prep.restart(start, res.Y[-1].copy(), res.AUX[-1].copy())
    return Window(prep, float(length), method, rtol_used, atol, s["max_step"], s["max_steps"])


def _restarted(prep: Prepared, start: tuple) -> Prepared:
    """``prep`` restarted at ``start = (t, y, aux)`` (see :func:`measurement_window`), checked."""
    try:
        t, y, aux = start
    except (TypeError, ValueError):
        raise ValueError(f"start={start!r}: must be (t, y, aux), a time (s) and states") from None
    pb = prep.problem
    y = np.atleast_1d(np.asarray(y, dtype=np.float64)).copy()
    aux = pb.aux0.copy() if aux is None else np.atleast_1d(np.asarray(aux, np.float64)).copy()
    if y.shape != pb.y0.shape or aux.shape != pb.aux0.shape:
        raise ValueError(
            f"start: a state of shape {y.shape} and a discrete state of shape {aux.shape}; "
            f"the model's are {pb.y0.shape} and {pb.aux0.shape}"
        )
    if not (np.isfinite(float(t)) and np.all(np.isfinite(y)) and np.all(np.isfinite(aux))):
        raise ValueError(f"start: the time and states must be finite; got t = {t!r}, y = {y!r}")
    return prep.restart(float(t), y, aux)


def time_scale(prep: Window) -> float:
    return prep.period if prep.period is not None else 1.0


def length_limit(prep: Window, budget: float | None) -> float:
    """The budget (forcing periods or s; default BUDGET times the window) in seconds."""
    if budget is None:
        return BUDGET * prep.length
    limit = float(budget) * time_scale(prep)
    if not limit >= prep.length * (1 - 1e-12):
        unit = "cycles" if prep.period is not None else "s"
        raise ValueError(
            f"budget={budget!r}: must be at least the measured length, "
            f"{prep.length / time_scale(prep):g} {unit}"
        )
    return limit


def stopping_rule(value: float, stderr: float, target: float, sign: float | None) -> str:
    """Which rule of an estimator's sequential stop holds for an estimate ``value`` with
    standard error ``stderr``: ``"error target"`` (``stderr <= target |value|``), else
    ``"sign"`` (with ``sign`` given: ``|value| > sign stderr``, the sign decided beyond ``sign``
    standard errors), else ``""`` (neither: the window grows while its budget allows)."""
    if stderr <= target * abs(value):
        return "error target"
    if sign is not None and abs(value) > sign * stderr:
        return "sign"
    return ""


def precision_condition(
    value: float, stderr: float, target: float, sign: float | None, after: str
) -> tuple[tuple[bool, str], str]:
    """The convergence condition ``error target`` of an estimate (``(holds, text)``, see
    :func:`workbench.analysis._convergence.judge`) and the rule that met it
    (:func:`stopping_rule`; ``""``: none, the budget ended the window). With ``sign`` the
    condition holds where either rule does, and its text names the rule; ``after`` says over
    what window (e.g. "after 40 cycles (budget 160 cycles)")."""
    rel = stderr / abs(value) if value != 0 else np.inf
    rule = stopping_rule(value, stderr, target, sign)
    text = f"the standard error is {rel:.1%} of the estimate {after} (target {target:.0%})"
    if sign is not None:
        sigmas = abs(value) / stderr if stderr > 0 else np.inf
        decided = "decided" if sigmas > sign else "not decided"
        text += f"; the sign is {decided}: |estimate| = {sigmas:.3g} standard errors (> {sign:g})"
    return (bool(rule), text), rule
