"""The largest Lyapunov exponent of a scene from its equations, by protocol: one pipeline that
chooses the trajectory method, runs it with a protocol's knobs and judges the estimate.

The method is the variational one for a model with an analytic Jacobian
(:func:`workbench.analysis.lyapunov_spectrum`, one tangent vector) or the two-trajectory one
(the mechanisms, :func:`workbench.analysis.lle_from_equations`) with the variational exponent
carried by the same trajectories as its check, with its batch-means standard error. Their runs
use DOP853 where the scene's method is implicit or ``auto``: those solve with the model's
Jacobian, not the derived system's.

Two protocols (:data:`PROTOCOLS`). ``full``: four independent starts after the scene's
transient, the separation and growth variants (two trajectories), the error target (default
3 %). ``fast`` (a chaos map's own precision): one start from a given state (where a run
ended), the estimate's copy alone, the window grown until the standard error is at most
:data:`MAP_TARGET` of the estimate or its sign is decided beyond :data:`MAP_SIGN` standard
errors, whichever first. Either leaves out the run at rtol / 100 (its cost) unless asked for
(``tolerance_check``); the fast protocol also the variants (:data:`NOT_RUN`,
:data:`FAST_NOT_RUN`). The estimate is ``converged`` where every condition its estimator did
run holds, and ``unmet`` names those that did not.

Callers: :func:`workbench.continuation.point_exponent` (Floquet's exponent first where the
strobe is periodic, this pipeline elsewhere), hence a chaos map's indicators, and the chaos
study's exponent table (:func:`workbench.study._exponents.exponent_table`).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np
import xarray as xr

from workbench.analysis._benettin import lle_from_equations
from workbench.analysis._convergence import TARGET, ConvergenceWarning
from workbench.analysis._lyapunov import lyapunov_spectrum
from workbench.run import prepare
from workbench.scene import Scene, SceneSource, load_scene
from workbench.solver import SolverError, jacobian_for

__all__ = ["LargestExponent", "exponent_method", "largest_exponent"]

#: the trajectory methods (the flag values of a chaos map's ``lle_method`` after ``floquet``)
METHODS = {
    "variational": "variational equations with saltation, QR (workbench.analysis."
    "lyapunov_spectrum); error: batch means",
    "copies": "linearised two-trajectory method, copies in one step sequence with the "
    "variational exponent on the same trajectories as its check (workbench.analysis."
    "lle_from_equations); error: batch means",
}
#: the convergence conditions of a trajectory estimator a protocol does not run (their cost):
#: they are left out of ``converged`` (every other condition must hold); per protocol
#: (:data:`PROTOCOLS`), then per method
NOT_RUN = {"variational": ("tolerance check",), "copies": ("tolerance check",)}
FAST_NOT_RUN = {"variational": ("tolerance check",), "copies": ("tolerance check", "variants")}
#: the protocols (see the module docstring)
PROTOCOLS = ("full", "fast")
#: the fast protocol's default relative error target
MAP_TARGET = 0.1
#: the fast protocol's default sign rule: the window stops growing where |value| exceeds this
#: many standard errors
MAP_SIGN = 3.0
#: why an exponent is not converged, in the order of the bits of
#: ``LargestExponent.unmet_code`` (the trajectory estimators' condition names, Floquet's check,
#: the bound, a failed run, any condition not named here, and the copies' variational check,
#: added last so that the older bits keep their meaning)
UNMET = (
    "error target",
    "variants",
    "tolerance check",
    "sum check",
    "floquet check",
    "upper bound",
    "failed",
    "other",
    "variational",
)


@dataclass(frozen=True)
class LargestExponent:
    """The largest exponent of a scene: ``value`` and ``error`` (s-1), ``method`` (a key of
    :data:`METHODS`, or ``"floquet"``: :func:`workbench.continuation.point_exponent`),
    ``failed`` (no estimate: the runs failed; value NaN), ``bound`` (the value is only an upper
    bound: the multipliers are below the noise of the differences; error NaN), ``detail`` (why
    Floquet's value was not taken, what failed, or the trajectory method's unmet convergence
    conditions), ``unmet`` (the names, from :data:`UNMET`, of the conditions that did not hold;
    empty where the estimate converged), ``rule`` (a trajectory estimate's stopping rule that
    held: ``"error target"`` or ``"sign"``; empty for Floquet's and where neither held),
    ``estimate`` (the trajectory estimator's own dataset, with the numbers behind the value;
    None for Floquet's and a failed run)."""

    value: float
    error: float
    method: str
    failed: bool = False
    detail: str = ""
    bound: bool = False
    unmet: tuple[str, ...] = ()
    rule: str = ""
    #: Floquet's: the orbit's state and discrete state at the strobe (to seed a neighbour's
    #: Newton), whether Newton started from a given seed, and its map evaluations
    orbit: tuple[np.ndarray, np.ndarray] | None = field(default=None, compare=False, repr=False)
    seeded: bool = False
    evaluations: int = 0
    estimate: xr.Dataset | None = field(default=None, compare=False, repr=False)

    def __post_init__(self):
        unmet = tuple(u for u in self.unmet if u != "failed")
        if self.failed:
            unmet += ("failed",)
        if self.bound and "upper bound" not in unmet:
            unmet += ("upper bound",)
        if any(u not in UNMET for u in unmet):
            raise ValueError(f"unmet={self.unmet!r}: each must be one of {UNMET!r}")
        object.__setattr__(self, "unmet", unmet)

    @property
    def converged(self) -> bool:
        """Every convergence condition that was run holds (not a bound, not failed)."""
        return not self.unmet

    @property
    def converged_code(self) -> int:
        """The flag ``lle_converged``: 0 not converged, 1 converged (the error target met, or
        Floquet's check), 2 converged on the sign rule (the sign decided, the error target not
        met; every other condition holds)."""
        if not self.converged:
            return 0
        return 2 if self.rule == "sign" else 1

    @property
    def unmet_code(self) -> int:
        """``unmet`` as bits: bit i set where ``UNMET[i]`` did not hold (0: converged)."""
        return sum(1 << UNMET.index(u) for u in self.unmet)


def exponent_method(scene: Scene) -> str:
    """The trajectory method for a scene: ``"variational"`` for a model with an analytic
    Jacobian, else ``"copies"``."""
    hooks = prepare(scene.replace(sweep={}) if scene.sweep else scene, variables=()).problem.hooks
    return "variational" if jacobian_for(hooks).HAS_ANALYTIC else "copies"


def protocol_knobs(
    protocol: str, *, target: float | None, sign: float | None, start
) -> tuple[float, float | None]:
    """A protocol's error target and sign rule (``target``, ``sign`` or the protocol's
    defaults), after checking that the protocol exists, that the fast one has its ``start`` and
    that the full one has no sign rule."""
    if protocol not in PROTOCOLS:
        raise ValueError(f"protocol={protocol!r}: must be one of {PROTOCOLS!r}")
    fast = protocol == "fast"
    if fast and start is None:
        raise ValueError(
            "protocol='fast' starts where a run ended: pass start=(t, y, aux) (the run's "
            "end_time, end_state and end_discrete_state)"
        )
    if not fast and sign is not None:
        raise ValueError(f"sign={sign!r}: the full protocol has no sign rule; use protocol='fast'")
    if target is None:
        target = MAP_TARGET if fast else TARGET
    if fast and sign is None:
        sign = MAP_SIGN
    return target, sign


def largest_exponent(
    scene: SceneSource,
    *,
    cycles: int | None = None,
    protocol: str = "full",
    target: float | None = None,
    sign: float | None = None,
    start: tuple | None = None,
    method: str | None = None,
    budget: float | None = None,
    tolerance_check: bool = False,
) -> LargestExponent:
    """The largest Lyapunov exponent (1/s) of a scene from its equations, by a protocol (see
    the module docstring). A failed run gives ``failed`` and a NaN value, never an exception
    (one hard point must not stop a map); an estimate that did not converge warns
    (:class:`~workbench.analysis.ConvergenceWarning`) and says why (``unmet``, ``detail``).

    Parameters
    ----------
    scene : Scene, path or mapping
        One run (as :func:`workbench.load_scene` takes it).
    cycles : int, optional
        Forcing periods of the window (forced models; default the scene's), grown by doubling
        within the estimator's budget until the protocol's stopping rule holds.
    protocol : str
        ``"full"`` (default) or ``"fast"`` (:data:`PROTOCOLS`).
    target : float, optional
        Relative standard error the window grows to (default 3 % for the full protocol,
        :data:`MAP_TARGET` for the fast one).
    sign : float, optional
        Fast protocol: standard errors beyond which the sign is decided and the window stops
        (default :data:`MAP_SIGN`); the full protocol has no sign rule.
    start : (t, y, aux), optional
        The fast protocol's start: time (s), state (state units) and discrete state, e.g. a
        run's ``end_time``, ``end_state`` and ``end_discrete_state``; required by it.
    method : str, optional
        ``"variational"`` or ``"copies"`` (default :func:`exponent_method`'s choice).
    budget : float, optional
        The estimator's longest total length (forcing periods or s; default its own).
    tolerance_check : bool
        Also run the estimate at rtol / 100 (and, two trajectories, tighten where the variants
        part): the condition the protocols leave out for their cost.

    Returns
    -------
    LargestExponent
        The value, its error, how it was measured and whether it converged, with the
        estimator's dataset (``estimate``).

    Examples
    --------
    >>> r = largest_exponent({"model": {"name": "lorenz"},
    ...                       "run": {"duration": 200.0, "transient": 20.0}}, target=0.1)
    >>> r.method, abs(r.value - 0.9056) < 0.1
    ('variational', True)
    """
    point = measure_exponent(
        scene, cycles=cycles, protocol=protocol, target=target, sign=sign, start=start,
        method=method, budget=budget, tolerance_check=tolerance_check,
    )  # fmt: skip
    return warn_unconverged(point, stacklevel=2)


def measure_exponent(
    scene: SceneSource,
    *,
    cycles: int | None = None,
    protocol: str = "full",
    target: float | None = None,
    sign: float | None = None,
    start: tuple | None = None,
    method: str | None = None,
    budget: float | None = None,
    tolerance_check: bool = False,
) -> LargestExponent:
    """:func:`largest_exponent` without its warning (for callers that add to the result's
    ``detail`` first, then warn with :func:`warn_unconverged`)."""
    target, sign = protocol_knobs(protocol, target=target, sign=sign, start=start)
    fast = protocol == "fast"
    scene = scene if isinstance(scene, Scene) else load_scene(scene)
    if method is None:
        method = exponent_method(scene)
    elif method not in METHODS:
        raise ValueError(f"method={method!r}: must be one of {tuple(METHODS)!r}")
    try:
        with warnings.catch_warnings():
            # the estimators warn on any condition they did not check, also on those a
            # protocol skips on purpose (NOT_RUN); the result warns only where one that ran
            # failed
            warnings.simplefilter("ignore", ConvergenceWarning)
            estimate, value, error, failed, rule = _trajectory_exponent(
                scene, method, cycles, target=target, sign=sign,
                start=start if fast else None, budget=budget, checked=tolerance_check,
            )  # fmt: skip
    except (SolverError, FloatingPointError, ValueError) as exc:
        return LargestExponent(math.nan, math.nan, method, True, str(exc)[:200])
    skipped = () if tolerance_check else (FAST_NOT_RUN if fast else NOT_RUN)[method]
    return LargestExponent(
        value, error, method, False, failed, unmet=_unmet(failed, skipped), rule=rule,
        estimate=estimate,
    )  # fmt: skip


def warn_unconverged(point: LargestExponent, stacklevel: int = 2) -> LargestExponent:
    """``point``, with a :class:`~workbench.analysis.ConvergenceWarning` naming its unmet
    conditions where it did not converge (``stacklevel`` as :func:`warnings.warn`'s, counted
    from the caller of this function)."""
    if not point.converged:
        warnings.warn(
            f"the {point.method} exponent {point.value:.4g} +- {point.error:.2g} 1/s has not "
            f"converged: {', '.join(point.unmet)} ({point.detail[:200]})",
            ConvergenceWarning,
            stacklevel=stacklevel + 1,
        )
    return point


def _explicit(scene: Scene) -> str | None:
    method = scene.solver["method"]
    return None if method in ("dop853", "dopri5") else "dop853"


def _trajectory_exponent(
    scene: Scene, method: str, cycles, *, target: float, sign=None, start=None, budget=None,
    checked: bool = False,
) -> tuple[xr.Dataset, float, float, str, str]:  # fmt: skip
    """The estimator's dataset, the exponent (s-1), its batch-means error (s-1), the
    estimator's ``failed`` text and the stopping rule that held ("" where none did), by
    ``method`` ("variational" or "copies") over ``cycles`` forcing periods after the scene's
    transient, without the run at rtol / 100 unless ``checked``; with ``start`` (t, y, aux),
    the fast protocol: one start from there, the estimate's copy alone (:data:`FAST_NOT_RUN`)."""
    if method == "variational":
        spec = lyapunov_spectrum(
            scene, exponents=1, cycles=cycles, check=checked, method=_explicit(scene),
            target=target, sign=sign, start=start, budget=budget,
        )  # fmt: skip
        rule = _rule(spec.attrs["stopped_by"])
        return spec, float(spec.exponent[0]), float(spec.stderr[0]), spec.attrs["failed"], rule
    fast = {} if start is None else {"starts": 1, "variants": False, "start": start}
    r = lle_from_equations(
        scene, cycles=cycles, tighten=checked, check=checked, method=_explicit(scene),
        target=target, sign=sign, budget=budget, **fast,
    )  # fmt: skip
    return r, float(r.lle), float(r.stderr), r.attrs["failed"], _rule(r.attrs["stopped_by"])


def _rule(stopped_by: str) -> str:
    """An estimator's ``stopped_by`` as a result's ``rule`` ("" for the budget)."""
    return "" if stopped_by == "budget" else stopped_by


def _unmet(failed: str, skipped: tuple[str, ...]) -> tuple[str, ...]:
    """The names of the conditions in an estimator's ``failed`` text (one ``name: what it
    measured`` line each, :func:`workbench.analysis._convergence.judge`) other than the
    ``skipped`` ones (not run on purpose); a name :data:`UNMET` does not know is ``other``."""
    names = [line.split(":", 1)[0].strip() for line in failed.splitlines() if line.strip()]
    return tuple(dict.fromkeys(n if n in UNMET else "other" for n in names if n not in skipped))
