"""``prepare``: a scene becomes a problem ready to integrate, once, in one place."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from workbench.models import Model, get_model
from workbench.run._ensemble import perturb_initial_state, scene_perturbation
from workbench.run._memory import check_memory, record_count, values_per_record, what_to_lower
from workbench.scene import Scene, SceneError, SceneSource, load_scene
from workbench.solver import Problem

__all__ = ["Prepared", "prepare", "record_times"]


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
    """

    scene: Scene
    model: Model
    parameters: dict
    variables: tuple[str, ...]
    problem: Problem
    period: float | None
    times: np.ndarray
    record_attrs: dict

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
    if scene.sweep:
        raise SceneError(
            "sweep",
            f"the scene sweeps {list(scene.sweep)!r}; a run is one scene: run the sweep with "
            "workbench.run_campaign, or drop it (scene.replace(sweep={}))",
        )
    model = get_model(scene.model)
    params = scene.resolved_parameters
    variables = scene.variables if variables is None else tuple(variables)
    problem = model.problem(params, scene.effects, scene.initial, variables)
    problem = perturb_initial_state(problem, *scene_perturbation(scene.run))
    period = model.forcing_period(params)
    count = record_count(scene.run, scene.record, period)
    states = [q.name for q in problem.states]
    per_record = values_per_record(model, scene.effects, variables, states) + problem.aux0.size
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
    return Prepared(scene, model, params, variables, problem, period, times, attrs)


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
