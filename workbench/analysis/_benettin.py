"""The largest Lyapunov exponent of a simulated model from its equations: two nearby
trajectories with periodic renormalisation (Benettin, Galgani, Giorgilli & Strelcyn 1980,
Meccanica 15, 9). The reference the time-series estimates are judged against; it needs no
variational equations, so it holds for the non-smooth contact models as well."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import xarray as xr

from workbench.models import get_model
from workbench.run import record_times as record_grid
from workbench.scene import Scene, load_scene
from workbench.solver import COMPILED_METHODS, integrate

__all__ = ["lle_from_equations"]


def lle_from_equations(
    scene: Scene | str | dict,
    *,
    cycles: int | None = None,
    duration: float | None = None,
    interval: float | None = None,
    separation: float = 1e-8,
    seed: int = 0,
) -> xr.Dataset:
    """LLE (1/s) of a scene's model: follow the scene's run and a copy displaced by
    ``separation`` (relative to each state's scale, the model's ``atol_scale``); every
    ``interval`` seconds add log(d / separation) and pull the copy back along the separation.

    Parameters
    ----------
    scene : Scene, path or mapping
        The run starts after the scene's transient (the state there is computed first).
    cycles, duration : optional
        Length of the measurement: forcing periods (forced models) or seconds; default: the
        scene's ``cycles`` or ``duration``.
    interval : float, optional
        Renormalisation interval, s; default T/32 for a forced model (an impacting mechanism
        separates at ~100-300 1/s, so a whole period would saturate), else 0.1 s.
    separation : float
        Initial and renormalised separation in scaled units (dimensionless).

    Returns
    -------
    xarray.Dataset
        ``lle`` (1/s), ``lle_per_period`` (forced models), ``running`` over ``elapsed`` (s), and
        the settings.

    Examples
    --------
    >>> r = lle_from_equations({"model": {"name": "lorenz"},
    ...                         "run": {"duration": 100.0, "transient": 10.0}})
    >>> abs(float(r.lle) - 0.9056) < 0.05
    True
    """
    scene = scene if isinstance(scene, Scene) else load_scene(scene)
    model = get_model(scene.model)
    params = dict(scene.resolved_parameters)
    problem = model.problem(params, scene.effects, scene.initial, ())
    s = scene.solver
    if s["method"].startswith("scipy:"):
        raise ValueError(
            f"solver.method={s['method']!r}: lle_from_equations needs a compiled method "
            f"{COMPILED_METHODS!r}"
        )
    period = model.forcing_period(params)
    t_rec, _ = record_grid(scene, problem.t0, period)
    start = float(t_rec[0])
    if period is not None:
        n_cycles = cycles if cycles is not None else scene.run.get("cycles", 1)
        length = n_cycles * period
        interval = period / 32 if interval is None else interval
    else:
        length = duration if duration is not None else float(scene.run["duration"])
        interval = 0.1 if interval is None else interval
    if interval <= 0 or length < interval:
        raise ValueError(f"interval={interval!r} s must be positive and at most {length!r} s")

    def advance(pb, t1: float):
        res = integrate(
            pb,
            np.array([t1]),
            method=s["method"],
            rtol=s["rtol"],
            atol=s["atol"],
            max_step=s["max_step"],
            max_steps=s["max_steps"],
        )
        res.raise_for_status()
        return res.Y[-1].copy(), res.AUX[-1].copy()

    y, aux = (problem.y0, problem.aux0) if start == problem.t0 else advance(problem, start)
    scale = np.where(np.isfinite(problem.atol_scale), problem.atol_scale, 0.0)
    scale = np.where(scale > 0, scale, np.maximum(np.abs(y), 1.0))
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(y.size)
    u /= np.linalg.norm(u)
    y2, aux2 = y + separation * u * scale, aux.copy()
    n_steps = int(math.floor(length / interval + 1e-9))
    total = 0.0
    running = np.empty(n_steps)
    t = start
    for k in range(n_steps):
        t1 = start + (k + 1) * interval
        y, aux = advance(dataclasses.replace(problem, y0=y, aux0=aux, t0=t), t1)
        y2, aux2 = advance(dataclasses.replace(problem, y0=y2, aux0=aux2, t0=t), t1)
        d = (y2 - y) / scale
        dist = float(np.linalg.norm(d))
        if not dist > 0:
            raise ValueError(f"the two trajectories coincide at t = {t1:g} s: increase separation")
        total += math.log(dist / separation)
        running[k] = total / (t1 - start)
        y2 = y + d * (separation / dist) * scale
        t = t1
    lle = float(running[-1])
    out = xr.Dataset(
        {
            "lle": ((), lle, {"units": "s-1", "long_name": "largest Lyapunov exponent"}),
            "running": ("elapsed", running, {"units": "s-1", "long_name": "running estimate"}),
            "interval": ((), interval, {"units": "s", "long_name": "renormalisation interval"}),
            "separation": ((), separation, {"units": "1", "long_name": "scaled separation"}),
        },
        coords={
            "elapsed": (
                "elapsed",
                interval * np.arange(1, n_steps + 1),
                {"units": "s", "long_name": "time followed"},
            )
        },
        attrs={"method": "two trajectories, periodic renormalisation (Benettin et al. 1980)"},
    )
    if period is not None:
        out["lle_per_period"] = ((), lle * period, {"units": "1", "long_name": "LLE per period"})
    return out
