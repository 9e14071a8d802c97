"""The stroboscopic map of a forced scene and its derivatives, for shooting.

``P^k(x; p)`` takes the state at forcing phase 0 (the problem's start ``t0``) through ``k``
forcing periods at parameter value ``p``. Its Jacobian in the state (the monodromy matrix) comes
from the tangent system with saltation at events (:func:`workbench.solver.tangent_problem`),
its derivative in ``p`` from central differences of the map.

The unknowns of a periodic orbit are the state ``y`` and the *live* discrete states: a discrete
state (for the clearance mechanisms, a contact's held onset velocity) that is active at the
strobe time (non-zero) and set again during the orbit (an onset within the ``k`` periods). An
inactive one (0, no contact at the strobe time) has no influence; one held through the whole
orbit (a contact that never ends) does not evolve and is a constant of that orbit, not an
unknown (it would add a multiplier of exactly 1). The states are measured in scaled units
(each divided by its characteristic size, :func:`workbench.solver.state_scale`, at the map's own
parameter value: :meth:`StrobeMap.scale`), the discrete states in their own units. That scale
is the map's, fixed over the parameter: a state's characteristic size can depend on it (c omega
for the mechanisms' rates), and a Jacobian in the scale at ``p`` beside a residual in the map's
is a Newton matrix off by that ratio (on the nine-bar continued from pi to 1.73 pi, 1.73 in
every rate's rows against its columns: Newton converged linearly and the branch stalled).

The monodromy matrix comes either from the tangent system (``monodromy="tangent"``) or from
central differences of the map by *copies* of the model integrated side by side in one step
sequence (``"copies"``; :func:`workbench.solver.copies_problem`), each started ``h = 1e-6``
(scaled) off the orbit along one unknown: the shared steps make the differences far more
accurate than the tolerance (the error of a difference is the tolerance times the difference,
plus O(h^2) and the rounding 1e-16 / h), and events are located per copy. The tangent system is
exact but carries the model's Jacobian along every column: by central differences of the rhs for
the mechanisms, which have no analytic Jacobian, where its step control takes several times the
bare model's steps, where copies take about the bare model's (docs/continuation.md gives the
counts on a nine-bar orbit in lasting contact). ``"auto"``
(default) takes the tangent system for a model with an analytic Jacobian and copies otherwise.

The map is integrated by an explicit compiled method: the scene's own where it is ``dop853`` or
``dopri5``, else **DOP853** in place of the scene's implicit method or ``auto`` (Radau and the
implicit stages of ``auto`` solve with the model's Jacobian, not the tangent or copies system's,
so they cannot integrate those systems, and the map and its Jacobian must come from one
integration). :class:`StrobeMap` says which (``method``, ``scene_method``,
``method_replaced``), and the orbits' datasets record it (attributes ``integration_method`` and
``scene_method``).
"""

from __future__ import annotations

import dataclasses
import importlib
import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from workbench._checks import positive_int
from workbench.continuation._contacts import ContactSequence, contact_sequence
from workbench.run import Prepared, prepare
from workbench.scene import Scene, SceneError, SceneSource, load_scene
from workbench.solver import (
    COMPILED_METHODS,
    RunResult,
    copies_problem,
    integrate,
    jacobian_for,
    split_copies,
    state_scale,
    tangent_columns,
    tangent_problem,
)

__all__ = ["SAMPLES", "MapValue", "StrobeMap"]

#: samples of the event functions per forcing period along an orbit (its contact sequence)
SAMPLES = 2048
#: where the sampled crossings miss events, the sampling is made this many times denser ...
REFINE = 4
#: ... up to this many samples per forcing period
MAX_SAMPLES = 64 * SAMPLES
#: a margin this small (relative to its event function's range) is near a grazing: it is read
#: again REFINE times denser until two densities agree within MARGIN_AGREE of its value (the
#: parabola through three samples misreads a dip narrower than their spacing, e.g. the
#: nine-bar's lasting contact read 1.7 nm from lifting off that lies 0.03 nm from it)
NEAR_MARGIN = 1e-3
MARGIN_AGREE = 0.1


@dataclass
class MapValue:
    """One evaluation of ``P^k`` at (y, aux, p).

    ``y1``, ``aux1``: the state and discrete state after ``k`` periods; ``live``: indices of
    the live discrete states; ``M``: the Jacobian of the map in the scaled unknowns
    ``(y / s, aux[live])``, ``s`` the map's :meth:`StrobeMap.scale` (fixed over the
    parameter; None without the tangent system); ``events``: events located
    over the ``k`` periods; ``stats``: solver statistics; ``M_check``: the same Jacobian at
    the map's ``check`` times larger step (copies with a ``check``, see :class:`StrobeMap`;
    else None); ``one_sided``: the unknowns (columns of the Jacobian before the held
    discrete states are dropped: the states, then the active discrete states) whose copies
    lay on two sides of a jump of the map, their columns one-sided
    (:meth:`StrobeMap._one_sided_columns`)."""

    y1: np.ndarray
    aux1: np.ndarray
    live: np.ndarray
    M: np.ndarray | None
    events: int
    stats: dict
    M_check: np.ndarray | None = None
    one_sided: tuple[int, ...] = ()


def _active(aux: np.ndarray, problem) -> np.ndarray:
    """Indices of the discrete states that are unknowns of the map: set (non-zero) and with a
    finite scale (a held onset velocity, m s-1). A discrete state without one (a mode, a
    counter, a record of the last event) is carried along but never differenced."""
    aux = np.asarray(aux, dtype=float)
    scale = np.asarray(problem.aux_scale, dtype=float)
    return np.flatnonzero((aux != 0.0) & np.isfinite(scale) & (scale > 0.0))


#: a copies' column whose forward and backward differences differ more than this factor is
#: taken to have its two copies on two sides of a jump of the map, and is taken one-sided
#: (:meth:`StrobeMap._one_sided_columns`)
STRADDLE_RATIO = 100.0
#: the shortest step of :meth:`StrobeMap.parameter_derivative`'s stencil, as the power of rtol
#: (times the parameter's scale) where the map's noise is rtol^(1/4) of the difference
SHORTEST_PARAMETER_STEP = 0.75


class StrobeMap:
    """``P^k`` of a forced scene over one of its parameters.

    Parameters
    ----------
    scene : Scene, path or mapping
        A forced model, single run (its sweep, if any, is ignored).
    parameter : str or None
        The model parameter the map depends on (None: the scene's own values).
    periods : int
        ``k``, forcing periods per map iteration.
    rtol : float, optional
        Integration tolerance (default ``min(scene rtol, 1e-9)``; ``atol`` scales with it).
    monodromy : str
        ``"tangent"``, ``"copies"`` or ``"auto"`` (see the module docstring).
    step : float
        Central-difference step of the copies (scaled units; discrete states: relative).
    check : float, optional
        Copies only: instead of central differences at ``step``, forward differences at
        ``step`` and at ``check * step`` from the same copies (as many as the central ones), so
        that one integration gives the monodromy (``MapValue.M``, error O(step)) and its check
        at the larger step (``MapValue.M_check``): a true multiplier is the same in both, the
        differences' noise (which goes as 1 / step) is ``check`` times smaller in the second.

    Attributes
    ----------
    method : str
        The integrator of the map, its tangent system and its copies: the scene's method where
        it is ``dop853`` or ``dopri5``, else ``dop853`` (see the module docstring).
    scene_method : str
        The scene's own ``solver.method``.
    method_replaced : bool
        Whether ``method`` replaced the scene's method.
    """

    #: default central-difference step of the copies (scaled units; discrete states: relative)
    COPIES_STEP = 1e-6

    def __init__(
        self,
        scene: SceneSource,
        parameter: str | None = None,
        *,
        periods: int = 1,
        rtol: float | None = None,
        monodromy: str = "auto",
        step: float = COPIES_STEP,
        check: float | None = None,
    ) -> None:
        scene = load_scene(scene)
        if not 0 < step < 1:
            raise ValueError(f"step={step!r}: must be a scaled step in (0, 1)")
        if check is not None and not (check > 1 and check * step < 1):
            raise ValueError(
                f"check={check!r}: must be a factor > 1 that keeps check * step ({step:g}) "
                "below 1 (scaled), or None for central differences"
            )
        self.step = float(step)
        self.check = None if check is None else float(check)
        self._spent = [0]  # evaluations of the map (shared with the maps derived from it)
        self._samples, self._refine = SAMPLES, True  # the contact sequences' density
        self.scene: Scene = scene.replace(sweep={}) if scene.sweep else scene
        self.parameter = parameter
        if parameter is not None and parameter not in self.scene.resolved_parameters:
            raise ValueError(
                f"parameter={parameter!r} is not a parameter of model {self.scene.model!r}; "
                f"allowed: {', '.join(sorted(self.scene.resolved_parameters))}"
            )
        self.periods = positive_int("periods", periods)
        s = self.scene.solver
        self.rtol = min(float(s["rtol"]), 1e-9) if rtol is None else float(rtol)
        self.atol = float(s["atol"]) * self.rtol / float(s["rtol"])
        self.scene_method = str(s["method"])
        # the tangent and copies systems need an explicit compiled method (module docstring)
        self.method = s["method"] if s["method"] in ("dop853", "dopri5") else "dop853"
        self.method_replaced = self.method != self.scene_method
        self.max_steps = int(s["max_steps"])
        self._base = prepare(self.scene, variables=())  # the bare problem (no outputs)
        self._at = lru_cache(maxsize=64)(self._base.at)  # one per parameter value
        base = self._base
        if base.period is None:
            raise ValueError(f"model {self.scene.model!r} is not forced: it has no strobe map")
        if monodromy not in ("auto", "tangent", "copies"):
            raise ValueError(f"monodromy={monodromy!r}; allowed: 'auto', 'tangent', 'copies'")
        if monodromy == "auto":
            analytic = jacobian_for(base.problem.hooks).HAS_ANALYTIC
            monodromy = "tangent" if analytic else "copies"
        self.monodromy = monodromy
        self._scale = state_scale(self.prepared(self.value).problem)
        if self.method not in COMPILED_METHODS:  # pragma: no cover - guarded above
            raise ValueError(self.method)

    # -- the problem at a parameter value --------------------------------------------------------
    @property
    def value(self) -> float:
        """The scene's own value of the parameter (nan without one)."""
        if self.parameter is None:
            return math.nan
        return float(self.scene.resolved_parameters[self.parameter])

    def prepared(self, p: float) -> Prepared:
        """The bare problem (no outputs) at parameter value ``p`` (the scene's own for nan or
        without a parameter; :meth:`workbench.run.Prepared.at`: only ``p`` is checked, a
        SceneError beyond the parameter's range)."""
        if self.parameter is None or math.isnan(p):
            return self._base
        return self._at(**{self.parameter: float(p)})

    def with_periods(self, periods: int) -> StrobeMap:
        """The same map over another number of periods."""
        return self._like(
            self.scene,
            self.parameter,
            periods=periods,
            rtol=self.rtol,
            monodromy=self.monodromy,
            step=self.step,
            check=self.check,
        )

    def with_rtol(self, rtol: float) -> StrobeMap:
        """The same map integrated at another tolerance (``atol`` scaled alike)."""
        return self._like(
            self.scene,
            self.parameter,
            periods=self.periods,
            rtol=rtol,
            monodromy=self.monodromy,
            step=self.step,
            check=self.check,
        )

    def _like(self, *args, **kwargs) -> StrobeMap:
        """A new map (arguments as for the constructor) reading contact sequences at this
        one's density."""
        other = StrobeMap(*args, **kwargs)
        other._samples, other._refine = self._samples, self._refine
        other._spent = self._spent
        return other

    @property
    def evaluations(self) -> int:
        """Evaluations of the map so far, failed ones included (each a run over its ``k``
        periods, with the monodromy or without: a parameter derivative is two), by this map and
        every map derived from it (:meth:`with_periods`, :meth:`with_rtol`): what a branch
        cost, where its corrections failed too."""
        return self._spent[0]

    def jitter(
        self, value: MapValue, y: np.ndarray, aux: np.ndarray, p: float, size: float
    ) -> float:
        """How far the map departs from its linearisation over a step of ``size`` (scaled) from
        (y, aux): ``max |P(y + size s v) - P(y) - M size v| / s`` for a fixed unit direction
        ``v`` (scaled units). Over a step this short the curvature's share is ``size^2``; the rest
        is the map's own noise (its step sequence changes with the start), the floor below
        which Newton's residual cannot be driven."""
        s = self.scale()
        n = s.size
        v = np.random.default_rng(0).standard_normal(n)
        v /= np.linalg.norm(v)
        moved = self(y + size * s * v, aux, p, tangent=False)
        linear = value.M[:n, :n] @ (size * v)
        return float(np.max(np.abs((moved.y1 - value.y1) / s - linear)))

    def scale(self) -> np.ndarray:
        """The characteristic size of each state (state units) at the map's own parameter
        value: the scaled unknowns of its residuals, Jacobians (:attr:`MapValue.M`,
        :meth:`flow`) and parameter derivatives, the same at every ``p``."""
        return self._scale.copy()

    def initial(self, p: float, cycles: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The state after the scene's transient (``cycles`` periods, default the scene's
        ``run.transient_cycles``) from its initial state, at parameter ``p``: a start for
        Newton's method."""
        prep = self.prepared(p)
        n = self.scene.run.get("transient_cycles", 0) if cycles is None else cycles
        pb = prep.problem
        if n == 0:
            return pb.y0.copy(), pb.aux0.copy()
        res = self._solve(pb, pb.t0 + n * prep.period)
        return res.Y[-1].copy(), res.AUX[-1].copy()

    def _solve(self, problem, t_end: float, records: int = 1) -> RunResult:
        t_rec = np.linspace(problem.t0, t_end, records + 1)[1:] if records > 1 else [t_end]
        res = integrate(
            problem,
            np.asarray(t_rec, dtype=float),
            method=self.method,
            rtol=self.rtol,
            atol=self.atol,
            max_steps=self.max_steps,
        )
        res.raise_for_status()
        return res

    # -- the map ----------------------------------------------------------------------------------
    def __call__(
        self, y: np.ndarray, aux: np.ndarray, p: float, *, tangent: bool = True
    ) -> MapValue:
        """``P^k(y, aux; p)``, with its Jacobian in the scaled unknowns when ``tangent``."""
        self._spent[0] += 1
        prep = self.prepared(p)
        pb = prep.problem
        start = dataclasses.replace(pb, y0=np.asarray(y, float), aux0=np.asarray(aux, float))
        span = self.periods * prep.period
        t_end = pb.t0 + span
        n, na = pb.y0.size, pb.aux0.size
        active = _active(aux, pb)
        if not tangent:
            res = self._solve(start, t_end)
            y1, aux1 = res.Y[-1].copy(), res.AUX[-1].copy()
            live = active[aux1[active] != np.asarray(aux)[active]]
            return MapValue(y1, aux1, live, None, int(res.stats["events"]), res.stats)
        s = self._scale
        m = n + active.size
        W_check, one_sided = None, ()
        if self.monodromy == "copies":
            y1, aux1, W, events, stats, W_check, one_sided = self._copies(start, active, t_end)
        else:
            V = np.zeros((n + na, m))
            V[:n, :n] = np.diag(s)
            for c, k in enumerate(active):
                V[n + k, n + c] = 1.0
            res = self._solve(tangent_problem(start, V, time_scale=span), t_end)
            Y = res.Y[-1]
            y1, aux1 = Y[:n].copy(), res.AUX[-1].copy()
            _, W, _ = tangent_columns(Y, n, na, m)
            events, stats = int(res.stats["events"]), res.stats
        # a discrete state held through the orbit: its own column unchanged and nothing set it
        held = np.array(
            [
                abs(W[n + k, n + c] - 1.0) <= 1e-9 and aux1[k] == aux[k]
                for c, k in enumerate(active)
            ],
            dtype=bool,
        )
        keep_cols = np.concatenate([np.arange(n), n + np.flatnonzero(~held)]).astype(int)
        live = active[~held]
        scale_rows = np.concatenate([s, np.ones(live.size)])

        def reduced(W: np.ndarray) -> np.ndarray:  # the live unknowns' rows and columns, scaled
            return np.concatenate([W[:n], W[n + live]], axis=0)[:, keep_cols] / scale_rows[:, None]

        M_check = None if W_check is None else reduced(W_check)
        return MapValue(y1, aux1, live, reduced(W), events, stats, M_check, one_sided)

    def _copies(self, start, active: np.ndarray, t_end: float):
        """The map and its Jacobian columns (extended state per unknown: the states scaled, the
        active discrete states in their units) by central differences of copies integrated in
        one step sequence; with :attr:`check`, forward differences at ``step`` and, as the last
        returned item (else None), at ``check * step``, from copies started at both. The copies
        start ``step`` off in the scale at the start's own parameter value (the linear range
        there); the columns are per unit of the map's scaled unknowns (:meth:`scale`)."""
        n, na = start.y0.size, start.aux0.size
        s = state_scale(start)
        h = self.step
        # per unknown, two copies: +h and -h (central), or +h and +check h (forward pair)
        signs = (1.0, -1.0) if self.check is None else (1.0, self.check)
        rows_y = [start.y0]
        rows_a = [start.aux0]
        steps = []
        for j in range(n):
            for sign in signs:
                d = np.zeros(n)
                d[j] = sign * h * s[j]
                rows_y.append(start.y0 + d)
                rows_a.append(start.aux0)
            steps.append(h)
        for k in active:
            ha = h * abs(start.aux0[k])
            for sign in signs:
                a = start.aux0.copy()
                a[k] += sign * ha
                rows_y.append(start.y0)
                rows_a.append(a)
            steps.append(ha)
        k_copies = len(rows_y)
        system = copies_problem(start, np.array(rows_y), np.array(rows_a))
        res = self._solve(system, t_end)
        Yc, Ac, _, _ = split_copies(res.Y[-1], res.AUX[-1], k_copies)
        X = np.concatenate([Yc, Ac], axis=1)
        W = np.empty((n + na, len(steps)))
        W_check = None if self.check is None else np.empty_like(W)
        for c, step in enumerate(steps):
            if W_check is None:
                W[:, c] = (X[1 + 2 * c] - X[2 + 2 * c]) / (2.0 * step)
            else:
                W[:, c] = (X[1 + 2 * c] - X[0]) / step
                W_check[:, c] = (X[2 + 2 * c] - X[0]) / (self.check * step)
        one_sided = () if W_check is not None else self._one_sided_columns(W, X, steps)
        for w in (W, W_check):  # per unit of y / s to per unit of y / scale()
            if w is not None:
                w[:, :n] *= self._scale / s
        if one_sided:  # copies met contacts the orbit does not: the orbit's own count, alone
            events = int(self._solve(start, t_end).stats["events"])
        else:
            events = int(round(res.stats["events"] / k_copies))
        return Yc[0].copy(), Ac[0].copy(), W, events, res.stats, W_check, one_sided

    @staticmethod
    def _one_sided_columns(W, X, steps) -> tuple[int, ...]:
        """Where a column's two copies lie on two sides of a jump of the map (one of them meets
        a contact the orbit does not, or loses one: near a grazing, within the copies' step of
        the orbit, and under a contact law with memory the map jumps there), the central
        difference is the jump over the step, not the derivative: on the nine-bar's lasting
        contact near its lift-off, 1.4e6 against 10 (largest |multiplier| 3.3e3 against
        0.034). A column whose forward and backward differences differ more than
        :data:`STRADDLE_RATIO`-fold is the one-sided difference on the smaller side (first
        order; a jump J adds J / step to the other). Which copy met the contact cannot be
        read off a run alone: a dip of -2.5e-12 m is located or missed with the step sequence,
        and the copies' sequence is not a lone run's. ``W`` is changed in place; returns the
        columns taken one-sided."""
        taken = []
        for c, step in enumerate(steps):
            fwd = X[1 + 2 * c] - X[0]
            bwd = X[0] - X[2 + 2 * c]
            nf, nb = float(np.linalg.norm(fwd)), float(np.linalg.norm(bwd))
            if max(nf, nb) <= STRADDLE_RATIO * min(nf, nb) or min(nf, nb) == 0.0:
                continue
            W[:, c] = (fwd if nf < nb else bwd) / step
            taken.append(c)
        return tuple(taken)

    def parameter_derivative(
        self, y: np.ndarray, aux: np.ndarray, p: float, live: np.ndarray, pscale: float
    ) -> np.ndarray:
        """d P^k / d(p / pscale) in the scaled unknowns, by central differences (step
        ``sqrt(rtol) pscale``: two runs with their own steps differ by ~rtol, so the column is
        good to ~sqrt(rtol), enough for Newton; a shorter stencil than rtol^(1/3) stays on one
        side of a nonsmooth point sooner); one-sided (second order) at the edge of the
        parameter's valid range.

        Where the stencil straddles a change of the contact structure (its two ends locate
        other numbers of events, or set other discrete states: a grazing lies within the
        stencil, across which the map has a kink or even a jump, e.g. a lasting contact that
        lifts off), the difference is taken on the side whose structure is that at ``p``
        itself (one-sided, second order), the step shortened tenfold until one side is clean,
        down to :data:`SHORTEST_PARAMETER_STEP` (``rtol^(3/4) pscale``: noise ``rtol^(1/4)``),
        first order there. A central difference across a jump is the jump over the step: on
        the nine-bar's lasting contact 1e-5 pi below its lift-off it was 58x the derivative,
        and the branch's tangent turned to the state axis (its parameter component 1e-4
        instead of 8e-3), so the steps collapsed short of the grazing."""
        h = h0 = math.sqrt(self.rtol) * pscale
        floor = self.rtol**SHORTEST_PARAMETER_STEP * pscale
        memo: dict[float, MapValue | None] = {}

        def value(q: float) -> MapValue | None:
            if q not in memo:
                try:
                    memo[q] = self(y, aux, q, tangent=False)
                except SceneError:  # beyond the parameter's valid range
                    memo[q] = None
            return memo[q]

        def at(q: float) -> np.ndarray | None:
            v = value(q)
            return None if v is None else np.concatenate([v.y1, v.aux1[live]])

        def structure(q: float) -> tuple | None:
            v = value(q)
            return None if v is None else (v.events, tuple(v.live))

        s = np.concatenate([self.scale(), np.ones(live.size)])
        plus, minus = at(p + h), at(p - h)
        if plus is None or minus is None:  # the edge of the valid range
            side = 1.0 if plus is not None else -1.0
            da = self._one_sided(at, p, h, side)
            if da is None:
                raise SceneError(
                    self.parameter or "", f"no valid value within {2 * h:.3g} of {p:.10g}"
                )
            return da * pscale / s
        if structure(p + h) == structure(p - h):
            return (plus - minus) / (2 * h) * pscale / s
        own = structure(p)
        while h >= floor:
            for side in (1.0, -1.0):
                if structure(p + side * h) != own:
                    continue
                if structure(p + 2 * side * h) == own:
                    return self._one_sided(at, p, h, side) * pscale / s
                if h / 10.0 < floor:  # the shortest step: first order
                    return side * (at(p + side * h) - at(p)) / h * pscale / s
            h /= 10.0
        # p itself lies within the shortest step of changes on both sides (on the border, for
        # Newton's iterate): no side is clean, and the central difference is returned as it is
        return (plus - minus) / (2 * h0) * pscale / s

    @staticmethod
    def _one_sided(at, p: float, h: float, side: float) -> np.ndarray | None:
        """The one-sided second-order difference ``d/dp`` on ``side`` (+1 or -1) at step h
        from ``at(q)`` (None where q is out of range)."""
        here, first, second = at(p), at(p + side * h), at(p + 2 * side * h)
        if here is None or first is None or second is None:
            return None
        return side * (-3.0 * here + 4.0 * first - second) / (2 * h)

    def flow(
        self, y: np.ndarray, aux: np.ndarray, p: float, t: float, *, jacobian: bool = True
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray]:
        """The state and discrete state at time ``t`` (s, at or after the problem's ``t0``)
        from (y, aux) at ``t0``, at parameter value ``p``: ``(y_t, aux_t, W, active)``.

        With ``jacobian``, ``W`` (shape ``(n + na, n + active.size)``) is the derivative of
        ``(y_t, aux_t)`` (their units) in the scaled unknowns: ``y / s`` (column ``j``), then
        the active discrete states (non-zero at ``t0``; column ``n + i`` for ``active[i]``),
        by central differences of copies in one step sequence (as the monodromy by copies,
        :meth:`__call__`); else None. E.g. the point where an orbit touches an event surface,
        for a grazing condition."""
        pb = self.prepared(p).problem
        y, aux = np.asarray(y, float), np.asarray(aux, float)
        n, na = y.size, aux.size
        active = _active(aux, pb)
        if not t > pb.t0:
            W = np.zeros((n + na, n + active.size))
            W[:n, :n] = np.diag(self._scale)
            W[n + active, n + np.arange(active.size)] = 1.0
            return y.copy(), aux.copy(), W if jacobian else None, active
        start = dataclasses.replace(pb, y0=y, aux0=aux)
        if not jacobian:
            res = self._solve(start, float(t))
            return res.Y[-1].copy(), res.AUX[-1].copy(), None, active
        y1, aux1, W, _, _, _, _ = self._copies(start, active, float(t))
        return y1, aux1, W, active

    def orbit_samples(self, y: np.ndarray, aux: np.ndarray, p: float) -> np.ndarray:
        """The states of a period-k orbit at its k strobe times (rows: ``y``, ``P(y)``, ...)."""
        prep = self.prepared(p)
        pb = prep.problem
        if self.periods == 1:
            return np.asarray(y, float)[None, :].copy()
        start = dataclasses.replace(pb, y0=np.asarray(y, float), aux0=np.asarray(aux, float))
        res = self._solve(start, pb.t0 + (self.periods - 1) * prep.period, self.periods - 1)
        return np.concatenate([np.asarray(y, float)[None, :], res.Y], axis=0)

    def sampled_events(
        self, y: np.ndarray, aux: np.ndarray, p: float, samples: int = SAMPLES
    ) -> np.ndarray:
        """The event functions along the orbit through (y, aux) over its ``k`` periods, at
        ``samples`` equally spaced times per period from the strobe time on (the strobe time
        itself included, the end excluded: rows of ``g``, event units)."""
        return self._sampled(y, aux, p, samples)[0]

    def _sampled(
        self, y: np.ndarray, aux: np.ndarray, p: float, samples: int
    ) -> tuple[np.ndarray, int]:
        """:meth:`sampled_events` and the number of events the integration located."""
        prep = self.prepared(p)
        pb = prep.problem
        ne = pb.event_direction.size
        n_rec = samples * self.periods
        if ne == 0:
            return np.zeros((n_rec, 0)), 0
        start = dataclasses.replace(pb, y0=np.asarray(y, float), aux0=np.asarray(aux, float))
        res = self._solve(start, pb.t0 + self.periods * prep.period, n_rec)
        # records at j span / n_rec, j = 1 .. n_rec: the last is the strobe state again (by
        # periodicity), so it stands for j = 0
        values = _event_values(pb, res.t, res.Y, res.AUX)
        return np.roll(values, 1, axis=0), int(res.stats["events"])

    def event_extrema(
        self, y: np.ndarray, aux: np.ndarray, p: float, samples: int = SAMPLES
    ) -> tuple[np.ndarray, np.ndarray]:
        """The largest and smallest value of each event function along the orbit through (y,
        aux) over its ``k`` periods (``samples`` records per period, the extreme record refined
        by the parabola through it and its neighbours): an onset event's largest value crosses
        zero where a contact appears (grazing), the smallest where a lasting one starts to
        lift off. Units of the event functions (the mechanisms: penetration, m)."""
        values = self.sampled_events(y, aux, p, samples)
        if values.shape[1] == 0:
            return np.zeros(0), np.zeros(0)
        return _extreme(values, np.argmax, 1.0), _extreme(values, np.argmin, -1.0)

    @property
    def samples(self) -> int:
        """Samples per forcing period of the contact sequences this map reads now (raised by
        :meth:`contact_sequence` where a contact falls between samples, never lowered)."""
        return self._samples

    def contact_sequence(
        self, y: np.ndarray, aux: np.ndarray, p: float, samples: int | None = None
    ) -> ContactSequence:
        """The contact sequence of the orbit through (y, aux) at ``p``
        (:mod:`workbench.continuation._contacts`): per event function its crossings and the
        local maxima of its signed value, the margins to the next grazing.

        Read off the event functions sampled at ``samples`` points per period (default
        :attr:`samples`). A contact shorter than the samples' spacing (an impact) can fall
        between two samples; so where the sampled crossings are fewer than the events the
        integration located, the sampling is made :data:`REFINE` times denser until they are
        as many, up to :data:`MAX_SAMPLES` per period, and the map keeps that density for the
        orbits it reads later (neighbouring orbits are compared at one density). Where even
        that does not find them (events whose function does not change sign, e.g. an
        instantaneous impact), the density found before stays and the map stops refining.
        Near a grazing (:data:`NEAR_MARGIN`) the smallest margin is read again denser until
        two densities agree (:meth:`_near_grazing`)."""
        pb = self.prepared(p).problem
        span = self.periods * self.prepared(p).period
        n = self._samples if samples is None else int(samples)
        values, events = self._sampled(y, aux, p, n)
        seq = contact_sequence(values, pb.event_direction, span, n, pb.event_surface)
        if samples is not None or not self._refine:
            return seq
        finer = n
        while sum(seq.counts) < events and finer * REFINE <= MAX_SAMPLES:
            finer *= REFINE
            values, events = self._sampled(y, aux, p, finer)
            seq_f = contact_sequence(values, pb.event_direction, span, finer, pb.event_surface)
            if sum(seq_f.counts) >= events:
                self._samples = finer
                return self._near_grazing(seq_f, y, aux, p)
        if sum(seq.counts) < events:
            # sampling does not find these events (an instantaneous impact, whose event
            # function touches zero at a corner: no margin to refine either): refine no more
            self._refine = False
            return seq
        return self._near_grazing(seq, y, aux, p)

    def _near_grazing(self, seq: ContactSequence, y, aux, p: float) -> ContactSequence:
        """``seq`` read again denser while its smallest margin is near a grazing
        (:data:`NEAR_MARGIN`) and changes by more than :data:`MARGIN_AGREE` of its value from
        one density to the next, up to :data:`MAX_SAMPLES` (the map keeps the density)."""
        pb = self.prepared(p).problem
        span = seq.span
        n = seq.samples
        while n * REFINE <= MAX_SAMPLES:
            k, phase, value = seq.smallest_margin()
            if (
                k < 0
                or abs(value) > NEAR_MARGIN * float(seq.scale[k])
                or _at_event(seq, phase, span / (n * self.periods))
            ):
                break
            n *= REFINE
            values, _ = self._sampled(y, aux, p, n)
            finer = contact_sequence(values, pb.event_direction, span, n, pb.event_surface)
            if finer.surface_counts != seq.surface_counts:
                break  # another sequence at this density: the crossings' own rule decides
            self._samples = max(self._samples, n)
            _, _, value_f = finer.smallest_margin()
            seq = finer
            if abs(value_f - value) <= MARGIN_AGREE * abs(value_f):
                break
        return seq


def _at_event(seq: ContactSequence, phase: float, spacing: float) -> bool:
    """Whether an event fires within two samples (``spacing``, s) of ``phase``: an extremum
    there is the corner of an instantaneous impact (its event function reaches zero at the
    impact and turns), not a margin to a grazing, and reads zero at every density."""
    near = 2.0 * spacing
    for c in seq.crossings:
        if c.size:
            d = np.abs(c - phase)
            if float(np.min(np.minimum(d, seq.span - d))) <= near:
                return True
    return False


def _event_values(pb, t: np.ndarray, Y: np.ndarray, AUX: np.ndarray) -> np.ndarray:
    """The problem's event functions at each record (rows)."""
    hooks = importlib.import_module(pb.hooks)
    ne = pb.event_direction.size
    out = np.empty((t.size, ne))
    work = np.zeros(max(pb.work_size, 1))
    g = np.empty(ne)
    for i in range(t.size):
        hooks.event_values(float(t[i]), np.ascontiguousarray(Y[i]), pb.p, pb.ip, AUX[i], work, g)
        out[i] = g
    return out


def _extreme(values: np.ndarray, pick, sign: float) -> np.ndarray:
    """Per column, the extreme of a periodic sampled function, refined by a parabola through
    the extreme sample and its two neighbours (the samples wrap around: they cover whole
    periods)."""
    n = values.shape[0]
    out = np.empty(values.shape[1])
    for k in range(values.shape[1]):
        col = values[:, k]
        i = int(pick(col))
        a, b, c = col[(i - 1) % n], col[i], col[(i + 1) % n]
        curv = a - 2.0 * b + c
        out[k] = b - (c - a) ** 2 / (8.0 * curv) if curv * sign < 0 else b
    return out
