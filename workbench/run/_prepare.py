"""``prepare``: a scene becomes a problem ready to integrate, once, in one place; and
:meth:`Prepared.at`, the same run at other parameter values (a point of a campaign or of a
strobe map) without validating the whole scene again."""

from __future__ import annotations

import dataclasses
import math
import numbers
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from workbench.models import Model, get_model
from workbench.run._ensemble import perturb_initial_state, scene_perturbation
from workbench.run._memory import check_memory, record_count, values_per_record, what_to_lower
from workbench.scene import RUN_SWEEP_KEYS, Scene, SceneError, SceneSource, load_scene
from workbench.scene._tables import ENSEMBLE_KEYS, integer, validate_parameters
from workbench.solver import Problem

__all__ = ["Prepared", "forcing_period", "prepare", "record_times"]


@dataclass(frozen=True)
class Prepared:
    """A scene made ready to integrate: everything a runner of the scene needs.

    Attributes
    ----------
    scene : Scene
        The (single-run) scene.
    model : Model
        Its model.
    parameters : dict[str, float]
        The model's defaults overridden by the scene's parameters (SI units).
    variables : tuple[str, ...]
        The variables the problem was built to compute (the model simulates nothing else).
    problem : Problem
        What the solver integrates.
    period : float or None
        Forcing period, s; None for an autonomous model.
    times : ndarray
        Record times, s (:func:`record_times`).
    record_attrs : dict
        Attributes that describe the record times (``samples_per_period``, ``cycles``, ...).
    max_memory : float, str or None
        The memory limit the records are checked against (:func:`prepare`), here and by
        :meth:`at`.
    """

    scene: Scene
    model: Model
    parameters: dict
    variables: tuple[str, ...]
    problem: Problem
    period: float | None
    times: np.ndarray
    record_attrs: dict
    max_memory: float | str | None = None

    def at(self, **values: float) -> Prepared:
        """The same run at other parameter values: one point of a campaign grid, or of a strobe
        map's parameter.

        Only ``values`` are checked, each against its parameter's declared range (the
        validation of :func:`workbench.load_scene`, with its one-line errors), then the
        model's cross-parameter check; the scene's other tables were validated when it was
        loaded and are kept as they are. What depends on the parameters is built again: the
        model's problem, the forcing period, the record times, and the check of the records
        against the memory limit. The scene of the result is the one
        :meth:`workbench.Scene.with_parameters` gives (no sweep), built without a text round
        trip.

        Parameters
        ----------
        **values : float
            Model parameter -> value (SI units); a swept ``[run]`` key (``realisation``) goes
            to ``[run]``.

        Returns
        -------
        Prepared
            With :attr:`variables` and :attr:`max_memory` of this one.

        Raises
        ------
        SceneError
            A value outside its parameter's range or an unknown name (naming
            ``parameters.NAME``, the value and the allowed range), a combination the model
            rejects, or records above the memory limit (:class:`MemoryLimitError`).

        Examples
        --------
        >>> from workbench.run import prepare
        >>> p = prepare({"model": {"name": "duffing"}, "run": {"cycles": 2}})
        >>> q = p.at(omega=2.0)
        >>> round(q.period, 6), q.scene.parameters["omega"], p.scene.parameters.get("omega")
        (3.141593, 2.0, None)
        >>> p.at(omega=-1.0)
        Traceback (most recent call last):
        ...
        workbench._errors.SceneError: parameters.omega: got -1.0; must lie in (0, inf] rad s-1
        """
        scene = _scene_at(self.scene, self.model, values)
        params = scene.resolved_parameters
        self.model.validate(params, scene.effects)
        period = forcing_period(self.model, params)
        if (period is None) != (self.period is None):  # the run's tables change meaning:
            # validate the whole scene (its [run] and [record] are those of a forced model or
            # of an autonomous one)
            return prepare(load_scene(scene.to_dict()), variables=self.variables,
                           max_memory=self.max_memory)  # fmt: skip
        return _build(scene, self.model, params, period, self.variables, self.max_memory)

    def restart(self, t0: float, y0: np.ndarray, aux0: np.ndarray | None = None) -> Prepared:
        """The same problem started at time ``t0`` (s) from state ``y0`` (and discrete state
        ``aux0``, default unchanged), e.g. to continue a run piecewise."""
        aux0 = self.problem.aux0 if aux0 is None else aux0
        problem = dataclasses.replace(self.problem, t0=float(t0), y0=y0, aux0=aux0)
        return dataclasses.replace(self, problem=problem)


def prepare(
    scene: SceneSource,
    *,
    variables: Iterable[str] | None = None,
    max_memory: float | str | None = None,
    points: bool = False,
) -> Prepared:
    """Build the problem of a single-run scene and its record times.

    Parameters
    ----------
    scene : Scene, path or mapping
        Loaded with :func:`workbench.load_scene`. A scene with a ``[sweep]`` is a campaign and
        is refused.
    variables : iterable of str, optional
        The variables to compute; default the scene's ``record.variables``. Fewer variables
        mean fewer states and outputs (e.g. ``()`` for the bare motion: no energy quadratures).
    max_memory : float or str, optional
        Refuse a run whose records would take more memory than this (bytes, or text such as
        ``"16 GiB"``); default the environment variable ``WORKBENCH_MAX_MEMORY``, else half
        of this machine's memory (:mod:`workbench.run._memory`).
    points : bool
        Prepare a campaign's scene for its points (:meth:`Prepared.at`): its ``[sweep]`` is
        dropped instead of refused, and the records are checked against the memory limit at
        each point, not at the scene's own parameter values.

    Returns
    -------
    Prepared

    Raises
    ------
    SceneError
        For a scene with a ``[sweep]`` (key ``sweep``), or when the model rejects the scene's
        values.
    MemoryLimitError
        (a SceneError) When the records would exceed the memory limit; estimated before
        anything is allocated, the message says what to lower.

    Examples
    --------
    >>> from workbench.run import prepare
    >>> p = prepare({"model": {"name": "duffing"}, "run": {"cycles": 2},
    ...              "record": {"samples_per_period": 4}})
    >>> p.times.size, p.problem.y0.size, round(p.period, 6)
    (9, 2, 5.235988)
    """
    scene = load_scene(scene)
    if scene.sweep and points:
        scene = scene.replace(sweep={})
    elif scene.sweep:
        raise SceneError(
            "sweep",
            f"the scene sweeps {list(scene.sweep)!r}; a run is one scene: run the sweep with "
            "workbench.run_campaign, or drop it (scene.replace(sweep={}))",
        )
    model = get_model(scene.model)
    params = scene.resolved_parameters
    variables = scene.variables if variables is None else tuple(variables)
    period = forcing_period(model, params)
    return _build(scene, model, params, period, variables, max_memory, check=not points)


def forcing_period(model: Model, params: Mapping[str, float]) -> float | None:
    """The forcing period (s) of ``model`` at the parameters ``params``: the one place that asks
    a model for it (a run, a point of a campaign, the campaign's plan).

    Returns
    -------
    float or None
        The model's :meth:`~workbench.models.Model.forcing_period`; None for an autonomous
        model.

    Raises
    ------
    SceneError
        The model gives neither None nor a finite positive number (the message names the model
        and the value). An error the model's own code raises passes through unchanged.

    Examples
    --------
    >>> from workbench.models import get_model
    >>> duffing = get_model("duffing")
    >>> forcing_period(duffing, {**duffing.default_parameters(), "omega": 3.141592653589793})
    2.0
    >>> forcing_period(get_model("lorenz"), get_model("lorenz").default_parameters()) is None
    True
    """
    period = model.forcing_period(params)
    if period is None or (isinstance(period, numbers.Real) and 0 < period < math.inf):
        return period
    raise SceneError(
        "",
        f"model {model.name!r} gives the forcing period {period!r}, not a finite positive "
        "number of seconds (its forcing_period)",
    )


def _scene_at(scene: Scene, model: Model, values: Mapping[str, float]) -> Scene:
    """``scene.with_parameters(**values)`` without validating the rest of the scene again: the
    values checked as :func:`workbench.load_scene` checks them, the tables in the order and form
    it gives them."""
    values = dict(values)
    ensemble = {k: int(values.pop(k)) for k in list(values) if k in RUN_SWEEP_KEYS}
    parameters = dict(scene.parameters)
    parameters.update({k: float(v) for k, v in values.items()})
    # the changed values, checked in the order load_scene checks the scene's
    validate_parameters(model, {k: v for k, v in parameters.items() if k in values}, "parameters")
    run = {k: v for k, v in scene.run.items() if k not in ENSEMBLE_KEYS}
    given = {k: v for k, v in scene.run.items() if k in ENSEMBLE_KEYS}
    given.update({k: integer(f"run.{k}", v, 0) for k, v in ensemble.items()})
    run.update({k: given[k] for k in ENSEMBLE_KEYS if k in given})
    return dataclasses.replace(
        scene,
        parameters=MappingProxyType(parameters),
        run=MappingProxyType(run),
        sweep=MappingProxyType({}),
        continuation=MappingProxyType({}),
    )


def _build(
    scene: Scene,
    model: Model,
    params: dict,
    period: float | None,
    variables: tuple[str, ...],
    max_memory: float | str | None,
    *,
    check: bool = True,
) -> Prepared:
    """The problem, record times and memory check of a validated single-run scene (its resolved
    parameters ``params`` and forcing period ``period``, s)."""
    problem = model.problem(params, scene.effects, scene.initial, variables)
    problem = perturb_initial_state(problem, *scene_perturbation(scene.run))
    if check:
        count = record_count(scene.run, scene.record, period)
        states = [q.name for q in problem.states]
        per_record = values_per_record(model, scene.effects, variables, states)
        per_record += problem.aux0.size
        key, lower = what_to_lower(scene.run, scene.record)
        check_memory(
            8.0 * count * per_record,
            what="the records of this run",
            count=f"{count:.3g} records x {per_record} values x 8 bytes",
            key=key,
            lower=lower,
            max_memory=max_memory,
        )
    times, attrs = record_times(scene, problem.t0, period)
    return Prepared(scene, model, params, variables, problem, period, times, attrs, max_memory)


def record_times(scene: Scene, t0: float, period: float | None) -> tuple[np.ndarray, dict]:
    """Record times (s) of a scene's run and the attributes that describe them.

    For a forced model the records lie at ``t0 + k T / samples_per_period`` for
    ``k = K0 .. K0 + cycles * samples_per_period`` (inclusive; ``K0 = transient_cycles *
    samples_per_period``), so every ``samples_per_period``-th record is a stroboscopic sample.
    Otherwise at ``t0 + transient + k dt`` up to ``transient + duration``.

    Parameters
    ----------
    scene : Scene
        The scene whose ``[run]`` and ``[record]`` give the records.
    t0 : float
        Initial time of the run, s.
    period : float or None
        Forcing period, s (None for an autonomous model).

    Returns
    -------
    times : ndarray
    attrs : dict
        ``samples_per_period``, ``transient_cycles`` and ``cycles``; or ``record_dt`` (s) and
        ``transient`` (s).
    """
    run, rec = scene.run, scene.record
    attrs: dict = {}
    if period is not None and "cycles" in run:
        spp = rec.get("samples_per_period")
        if spp is None:
            spp = max(1, round(period / rec["dt"]))
        k0 = run["transient_cycles"] * spp
        k = k0 + np.arange(record_count(run, rec, period), dtype=np.float64)
        t = t0 + k * period / spp
        attrs.update(
            samples_per_period=int(spp),
            transient_cycles=run["transient_cycles"],
            cycles=run["cycles"],
        )
    else:
        if "samples_per_period" in rec and period is not None:
            dt = period / rec["samples_per_period"]
            attrs["samples_per_period"] = int(rec["samples_per_period"])
        else:
            dt = rec["dt"]
        n = record_count(run, rec, period)
        t = t0 + run["transient"] + np.arange(n) * dt
        attrs.update(record_dt=dt, transient=run["transient"])
    return t, attrs
