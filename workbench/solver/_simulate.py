"""``simulate``: one scene -> one labelled xarray.Dataset."""

from __future__ import annotations

import datetime
import math
import platform
import time as _time
from functools import lru_cache
from importlib.metadata import version

import numpy as np
import xarray as xr

from workbench._ensemble import perturb_initial_state, scene_perturbation
from workbench._errors import SolverError
from workbench._scene import Scene, load_scene
from workbench.models import Problem, get_model
from workbench.solver import _scipy_backend
from workbench.solver._compile import kernel_for
from workbench.solver._grid import record_grid

__all__ = ["simulate", "integrate", "RunResult"]

_METHOD_IDS = {"dopri5": 0, "dop853": 1, "ark548": 2}
_PACKAGES = ("workbench", "numpy", "scipy", "numba", "xarray", "netCDF4", "dask")


class RunResult:
    """Raw output of :func:`integrate`: record times, states, discrete states, statistics."""

    def __init__(self, t, Y, AUX, stats: dict, status: str) -> None:
        self.t, self.Y, self.AUX, self.stats, self.status = t, Y, AUX, stats, status


def integrate(
    problem: Problem,
    t_rec: np.ndarray,
    *,
    method: str = "dop853",
    rtol: float = 1e-8,
    atol: float = 1e-10,
    max_step: float = math.inf,
    max_steps: int = 50_000_000,
    progress=None,
) -> RunResult:
    """Integrate a model problem and record the state at ``t_rec`` (s, ascending, >= t0).

    ``progress`` is an optional callable ``progress(t)`` called between chunks of simulated time.
    Raises :class:`workbench.SolverError` naming the time, the state and the cause on failure.
    """
    t_rec = np.ascontiguousarray(t_rec, dtype=np.float64)
    if t_rec.size == 0 or t_rec[0] < problem.t0:
        raise ValueError(f"record times must be non-empty and start at or after t0={problem.t0!r}")
    atol_arr = atol * problem.atol_scale
    t_end = float(t_rec[-1])
    if method.startswith("scipy:"):
        result = _scipy_backend.integrate(problem, t_rec, method[6:], rtol, atol_arr, max_step)
        result.stats["atol"] = atol
        return result
    if problem.y0.size == 0:  # nothing to integrate (e.g. a mechanism with ideal joints)
        Y = np.empty((t_rec.size, 0))
        AUX = np.tile(problem.aux0, (t_rec.size, 1))
        stats = {
            "method": method,
            "rtol": rtol,
            "atol": atol,
            "max_step": max_step,
            "steps": 0,
            "rejected_steps": 0,
            "rhs_evaluations": 0,
            "events": 0,
            "event_retries": 0,
            "wall_time": 0.0,
        }
        return RunResult(t_rec, Y, AUX, stats, "done")
    k = kernel_for(problem.hooks)
    mid = _METHOD_IDS[method]
    n, na, ne = problem.y0.size, problem.aux0.size, problem.event_direction.size
    y = problem.y0.copy()
    aux = problem.aux0.copy()
    work = np.zeros(max(problem.work_size, 1))
    f = np.empty(n)
    g = np.empty(ne)
    stats = np.zeros(k.N_STATS, np.int64)
    ctrl = np.zeros(k.N_CTRL + problem.stiff_states.size)
    Y = np.full((t_rec.size, n), np.nan)
    AUX = np.full((t_rec.size, na), np.nan)
    _compiled(k, mid, problem, rtol, atol_arr, max_step)
    wall0 = _time.perf_counter()
    code = k.start(
        problem.t0, y, problem.p, problem.ip, aux, work, f, g, stats, problem.stiff_slots, ctrl
    )
    ctrl[k.CT_F_INSIDE] = 1.0 if code == k.EVENT_INSIDE_STEP else 0.0
    if code != 0 and code != k.EVENT_INSIDE_STEP:
        raise SolverError(
            f"the model cannot start at t = {problem.t0:g} s: {problem.failure(code)}",
            time=problem.t0,
            state=_state(problem, y),
            cause=f"model_{code}",
        )
    h0 = k.initial_step(
        mid,
        problem.t0,
        y,
        f,
        problem.p,
        problem.ip,
        aux,
        work,
        rtol,
        atol_arr,
        max_step,
        t_end,
        stats,
    )
    ctrl[k.CT_T] = problem.t0
    ctrl[k.CT_H] = h0
    chunk = (t_end - problem.t0) / 100.0 if progress is not None else math.inf
    t_pause = problem.t0 + chunk
    while True:
        status = k.advance(
            mid,
            t_end,
            t_pause,
            t_rec,
            problem.p,
            problem.ip,
            rtol,
            atol_arr,
            max_step,
            max_steps,
            problem.event_direction,
            ctrl,
            y,
            f,
            aux,
            work,
            g,
            stats,
            Y,
            AUX,
            problem.stiff_states,
            problem.stiff_slots,
            problem.implicit_slot,
        )
        if progress is not None:
            progress(float(ctrl[k.CT_T]))
        if status != k.PAUSED:
            break
        t_pause += chunk
    wall = _time.perf_counter() - wall0
    st = {
        "method": method,
        "rtol": rtol,
        "atol": atol,
        "max_step": max_step,
        "steps": int(stats[k.ST_STEPS]),
        "rejected_steps": int(stats[k.ST_REJECTED]),
        "rhs_evaluations": int(stats[k.ST_RHS]),
        "events": int(stats[k.ST_EVENTS]),
        "event_retries": int(stats[k.ST_EVENT_RETRIES]),
        "wall_time": wall,
    }
    t_now = float(ctrl[k.CT_T])
    if status < 0:
        _raise(k, status, problem, t_now, y, ctrl[k.CT_H], int(stats[k.ST_MODEL_CODE]), max_steps)
    n_rec = int(stats[k.ST_RECORDED])
    if status == k.TERMINATED:
        t_rec, Y, AUX = t_rec[:n_rec], Y[:n_rec], AUX[:n_rec]
    return RunResult(t_rec, Y, AUX, st, "terminated" if status == k.TERMINATED else "done")


def _compiled(k, mid, problem, rtol, atol_arr, max_step) -> None:
    """Compile (or load from cache) every kernel entry point before the clock starts, so that
    the recorded wall time is integration only."""
    n, na, ne = problem.y0.size, problem.aux0.size, problem.event_direction.size
    y, f, aux = problem.y0.copy(), np.empty(n), problem.aux0.copy()
    g, stats = np.empty(ne), np.zeros(k.N_STATS, np.int64)
    ctrl = np.zeros(k.N_CTRL + problem.stiff_states.size)
    work = np.zeros(max(problem.work_size, 1))
    p, ip, t0 = problem.p, problem.ip, problem.t0
    ctrl[k.CT_T] = t0
    k.start(t0, y, p, ip, aux, work, f, g, stats, problem.stiff_slots, ctrl)
    k.initial_step(mid, t0, y, f, p, ip, aux, work, 1e-3, atol_arr, max_step, t0 + 1.0, stats)
    k.advance(
        mid,
        t0,
        t0,
        np.zeros(0),
        p,
        ip,
        1e-3,
        atol_arr,
        max_step,
        1,
        problem.event_direction,
        ctrl,
        y,
        f,
        aux,
        work,
        g,
        stats,
        np.empty((0, n)),
        np.empty((0, na)),
        problem.stiff_states,
        problem.stiff_slots,
        problem.implicit_slot,
    )


def _state(problem: Problem, y: np.ndarray) -> dict[str, float]:
    return {q.name: float(v) for q, v in zip(problem.states, y, strict=True)}


def _raise(k, status, problem, t, y, h, model_code, max_steps) -> None:
    state = _state(problem, y)
    shown = ", ".join(f"{n}={v:.6g}" for n, v in state.items())
    if status == k.MODEL_FAILURE:
        cause = problem.failure(model_code)
        raise SolverError(
            f"integration failed at t = {t:.9g} s: {cause} (state: {shown})",
            time=t,
            state=state,
            cause=f"model_{model_code}",
        )
    if status == k.NON_FINITE:
        raise SolverError(
            f"integration failed at t = {t:.9g} s: the state became non-finite (NaN or inf) and "
            f"smaller steps did not help (state: {shown}); likely an overflow in the model or an "
            "unphysical parameter",
            time=t,
            state=state,
            cause="non_finite",
        )
    if status == k.MAX_STEPS:
        raise SolverError(
            f"integration stopped at t = {t:.9g} s after solver.max_steps = {max_steps} steps "
            f"(state: {shown}); raise solver.max_steps or loosen solver.rtol",
            time=t,
            state=state,
            cause="max_steps",
        )
    raise SolverError(
        f"integration failed at t = {t:.9g} s: step size underflow (h = {h:.3g} s) (state: "
        f"{shown}); the problem is stiff or discontinuous here, or the tolerances are too tight",
        time=t,
        state=state,
        cause="step_underflow",
    )


def simulate(scene: Scene | str, *, progress: bool = False) -> xr.Dataset:
    """Run one scene and return its records as a labelled dataset.

    Parameters
    ----------
    scene : Scene, path or mapping
        The scene (loaded with :func:`workbench.load_scene` if it is not a Scene yet). A scene
        with a ``[sweep]`` is a campaign: use :func:`workbench.run_campaign`.
    progress : bool
        Show a progress bar over simulated time.

    Returns
    -------
    xarray.Dataset
        Dim ``time`` (the records after the transient), one variable per requested state and
        output, ``units`` and ``long_name`` on everything, provenance and solver statistics in
        the global attributes.

    Examples
    --------
    >>> import workbench
    >>> ds = workbench.simulate({"model": {"name": "lorenz"}, "run": {"duration": 1.0}})
    >>> ds.x.attrs["units"], ds.sizes["time"]
    ('1', 1001)
    """
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    if scene.sweep:
        raise ValueError(
            f"scene has a [sweep] over {list(scene.sweep)!r}; run it with workbench.run_campaign "
            "or drop the sweep (scene.replace(sweep={}))"
        )
    model = get_model(scene.model)
    params = scene.resolved_parameters
    requested = scene.variables
    problem = model.problem(params, scene.effects, scene.initial, requested)
    problem = perturb_initial_state(problem, *scene_perturbation(scene.run))
    period = model.forcing_period(params)
    t_rec, grid_attrs = record_grid(scene, problem.t0, period)
    s = scene.solver
    bar = None
    callback = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(
            total=float(t_rec[-1] - problem.t0),
            unit="s",
            desc="simulated time",
            bar_format="{l_bar}{bar}| {n:.3g}/{total:.3g} s [{elapsed}<{remaining}]",
        )

        def callback(t: float) -> None:
            bar.n = t - problem.t0
            bar.refresh()

    try:
        result = integrate(
            problem,
            t_rec,
            method=s["method"],
            rtol=s["rtol"],
            atol=s["atol"],
            max_step=s["max_step"],
            max_steps=s["max_steps"],
            progress=callback,
        )
    finally:
        if bar is not None:
            bar.close()
    ds = to_dataset(scene, model, problem, result, period, grid_attrs)
    if s["check"]:
        from workbench._accuracy import check_error  # the accuracy layer builds on simulate

        ds.attrs.update({f"solver_{k}": v for k, v in check_error(scene).items()})
    return ds


def to_dataset(scene, model, problem, result: RunResult, period, grid_attrs) -> xr.Dataset:
    """Labelled dataset of a run: only the requested variables, with units everywhere."""
    requested = scene.variables
    declared = model.variables(scene.effects)
    state_index = {q.name: i for i, q in enumerate(problem.states)}
    derived = model.derive(problem, result.t, result.Y, result.AUX, requested)
    coords = {
        "time": ("time", result.t, {"units": "s", "long_name": "time", "standard_name": "time"})
    }
    for dim, (values, attrs) in model.coords(scene.effects).items():
        coords[dim] = (dim, list(values), dict(attrs))
    data_vars = {}
    for name in requested:
        q = declared[name]
        values = result.Y[:, state_index[name]] if name in state_index else derived[name]
        data_vars[name] = (("time",) + q.dims, values, {"units": q.units, "long_name": q.long_name})
    ds = xr.Dataset(data_vars, coords=coords)
    ds.attrs.update(provenance(scene))
    ds.attrs.update({f"solver_{k}": v for k, v in result.stats.items()})
    ds.attrs["run_status"] = result.status
    ds.attrs["model"] = scene.model
    if period is not None:
        ds.attrs["forcing_period"] = float(period)
        ds.attrs["forcing_period_units"] = "s"
    ds.attrs.update(grid_attrs)
    return ds


def provenance(scene: Scene) -> dict:
    """Global attributes every stored dataset carries (CF conventions, scene, versions)."""
    now = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
    versions, source = _versions()
    return {
        "Conventions": "CF-1.11",
        "title": scene.title or f"workbench run of model {scene.model}",
        "history": f"{now} created by workbench.simulate",
        "source": source,
        "scene": scene.to_toml(),
        "package_versions": versions,
    }


@lru_cache(maxsize=1)
def _versions() -> tuple[str, str]:
    """Package versions and the source line; read once per process (metadata look-ups cost
    milliseconds, more than a short run)."""
    found = []
    for pkg in _PACKAGES:
        try:
            found.append(f"{pkg}={version(pkg)}")
        except Exception:
            found.append(f"{pkg}=unknown")
    try:
        own = version("workbench")
    except Exception:
        own = "dev"
    source = f"workbench {own} ({platform.python_implementation()} {platform.python_version()})"
    return "; ".join(found), source
