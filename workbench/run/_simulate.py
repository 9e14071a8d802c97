"""``simulate``: one scene -> one labelled xarray.Dataset (prepare, integrate, dataset)."""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence

import numpy as np
import xarray as xr

from workbench._errors import ModelWarning
from workbench.run._compare import divergence_time, separation, short_scene
from workbench.run._dataset import derive, to_dataset
from workbench.run._prepare import Prepared, prepare
from workbench.scene import Scene, SceneSource
from workbench.solver import RunResult
from workbench.solver import integrate as _integrate

__all__ = ["check_error", "integrate", "simulate"]


def integrate(
    prepared: Prepared,
    times: Sequence[float] | np.ndarray | None = None,
    *,
    progress: Callable[[float], None] | None = None,
) -> RunResult:
    """Integrate a prepared scene with its ``[solver]`` settings.

    Parameters
    ----------
    prepared : Prepared
        From :func:`prepare` (or :meth:`Prepared.restart`).
    times : array_like, optional
        Record times, s, ascending, at or after the problem's ``t0``; default the scene's
        (``prepared.times``).
    progress : callable, optional
        ``progress(t)`` between chunks of simulated time.

    Returns
    -------
    RunResult
        Its ``status`` says how the run ended; :meth:`RunResult.raise_for_status` raises
        :class:`workbench.SolverError` for a failure.

    Examples
    --------
    >>> from workbench.run import integrate, prepare
    >>> p = prepare({"model": {"name": "lorenz"}, "run": {"duration": 1.0}})
    >>> r = integrate(p, [0.5, 1.0])
    >>> r.status.label, r.Y.shape
    ('ok', (2, 3))
    """
    s = prepared.scene.solver
    return _integrate(
        prepared.problem,
        prepared.times if times is None else np.asarray(times, dtype=np.float64),
        method=s["method"],
        rtol=s["rtol"],
        atol=s["atol"],
        max_step=s["max_step"],
        max_steps=s["max_steps"],
        progress=progress,
    )


def simulate(
    scene: SceneSource | Prepared,
    *,
    progress: bool = False,
    throw: bool = True,
    max_memory: float | str | None = None,
) -> xr.Dataset:
    """Run one scene and return its records as a labelled dataset.

    Parameters
    ----------
    scene : Scene, path, mapping or Prepared
        Loaded with :func:`workbench.load_scene`. A scene with a ``[sweep]`` is a campaign:
        use :func:`workbench.run_campaign`. A :class:`Prepared` (from :func:`prepare` or
        :meth:`Prepared.at`) runs as it is (its records were checked against its own memory
        limit; ``max_memory`` is not used).
    progress : bool
        Show progress over simulated time on stderr: a bar on a terminal, a few lines in a
        log (:class:`workbench._progress.Progress`).
    throw : bool
        Raise :class:`workbench.SolverError` if the run fails (default). With ``throw=False`` a
        failed run returns its dataset: the records before the failure, NaN after it, and the
        failure in ``run_status`` and ``run_message``.
    max_memory : float or str, optional
        Refuse, before anything is allocated, a run whose records would take more memory than
        this (bytes, or text such as ``"16 GiB"``; default: the environment variable
        ``WORKBENCH_MAX_MEMORY``, else half of this machine's memory).

    Returns
    -------
    xarray.Dataset
        Dim ``time`` (the records after the transient), one variable per requested state and
        output, ``units`` and ``long_name`` on everything, provenance, solver statistics,
        ``run_status`` (a :class:`workbench.Status` label) and the state the run ended in in
        the global attributes: ``end_time`` (s), ``end_state`` (every state of the problem, in
        its order and units, recorded or not), ``end_state_names`` (space-separated) and, for
        a model with a discrete state, ``end_discrete_state`` (at the last record that holds
        the solution; a measurement continues from there instead of integrating the run again).

    Raises
    ------
    SolverError
        With ``throw=True``, when the run fails (the error's ``status`` says how).
    SceneError, ValueError
        For an invalid scene, or a scene with a sweep; :class:`MemoryLimitError` (a
        SceneError) for records above the memory limit.
    KeyboardInterrupt
        Ctrl-C stops the run within about 0.1 s (the compiled loop pauses that often).

    Warns
    -----
    ModelWarning
        Where the model finds that a law left its physics (e.g. a LuGre friction coefficient
        beyond its envelope; :meth:`workbench.models.Model.diagnose`).

    Examples
    --------
    >>> import workbench
    >>> ds = workbench.simulate({"model": {"name": "lorenz"}, "run": {"duration": 1.0}})
    >>> ds.x.attrs["units"], ds.sizes["time"], ds.attrs["run_status"]
    ('1', 1001, 'ok')
    """
    if isinstance(scene, Prepared):
        prepared = scene
    else:
        prepared = prepare(scene, max_memory=max_memory)
    result = _with_progress_bar(prepared) if progress else integrate(prepared)
    derived, result = derive(prepared, result)
    if throw:
        result.raise_for_status()
    ds = to_dataset(prepared, result, derived)
    for message in prepared.model.diagnose(ds, prepared.scene.resolved_parameters):
        warnings.warn(ModelWarning(message), stacklevel=2)
    if prepared.scene.solver["check"] and not result.status.failed:
        ds.attrs.update({f"solver_{k}": v for k, v in check_error(prepared.scene).items()})
    return ds


def _with_progress_bar(prepared: Prepared) -> RunResult:
    """Integrate with progress over simulated time (:class:`workbench._progress.Progress`: a
    bar on a terminal, a few lines in a log)."""
    from workbench._progress import Progress

    t0 = prepared.problem.t0
    total = float(prepared.times[-1] - t0)
    with Progress(total, desc="simulated time", unit="s") as bar:
        return integrate(prepared, progress=lambda t: bar.update_to(t - t0))


def check_error(scene: Scene) -> dict[str, float]:
    """Self-check of a run (``solver.check = true``): the first period (or the first 10 % of the
    run) at the scene's tolerances against a run 100x tighter in both rtol and atol.

    Returns ``check_error``, the largest difference relative to each recorded variable's range
    (dimensionless), ``check_divergence_time`` (s, when the two first differ by 1 % of a range;
    ``inf`` if never: for a chaotic impacting run the error over a whole period is O(1) at any
    tolerance, and this time is what the tolerance buys), ``check_tolerance`` (the reference
    rtol) and ``check_horizon`` (s). :func:`simulate` stores them as ``solver_check_*``
    attributes.
    """
    s = scene.solver
    factor = max(s["rtol"] / 100, 1e-13) / s["rtol"]
    tight, tight_atol = s["rtol"] * factor, s["atol"] * factor
    a = simulate(short_scene(scene, s["method"], s["rtol"], s["atol"]))
    b = simulate(short_scene(scene, s["method"], tight, tight_atol))
    return {
        "check_error": float(np.max(separation(a, b))),
        "check_divergence_time": divergence_time(a, b),
        "check_tolerance": tight,
        "check_horizon": float(a.time[-1] - a.time[0]),
    }
