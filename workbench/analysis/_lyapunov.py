"""Lyapunov exponents of a simulated model from its variational equations, with the saltation
matrix at every event (Müller 1995; Dellago, Posch & Hoover 1996), and the spectrum by
repeated QR re-orthonormalisation (Benettin, Galgani, Giorgilli & Strelcyn 1980, Meccanica 15,
21; Shimada & Nagashima 1979, Prog. Theor. Phys. 61, 1605)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import xarray as xr

from workbench.run import Prepared, prepare
from workbench.run import integrate as integrate_scene
from workbench.scene import SceneSource
from workbench.solver import (
    COMPILED_METHODS,
    Problem,
    RunResult,
    integrate,
    jacobian_for,
    state_scale,
    tangent_problem,
    tangent_state,
)

__all__ = ["lyapunov_spectrum"]

#: largest growth (log) of a tangent vector between two re-orthonormalisations before the
#: interval is halved (e^25 ~ 7e10 keeps ~5 significant digits of the weakest column), and the
#: smallest before it is doubled
_MAX_LOG_GROWTH = 25.0
_MIN_LOG_GROWTH = 2.0
_BATCHES = 10


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
        the derived system's, and for Radau IIA and ``auto``, whose Jacobian is the model's) at
        ``rtol`` (``atol`` in proportion); raises on a failed run."""
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


def measurement_window(
    scene: SceneSource,
    *,
    cycles: int | None = None,
    duration: float | None = None,
    method: str | None = None,
    rtol: float | None = None,
) -> Window:
    """A scene's bare motion (no outputs, no energy quadratures) advanced through its transient
    with its solver, and the measured length: ``cycles`` forcing periods (forced models) or
    ``duration`` seconds, default the scene's. ``method`` and ``rtol`` override the scene's
    solver for the measurement (``atol`` follows ``rtol`` in proportion)."""
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
    start = float(prep.times[0])
    if start > prep.problem.t0:
        res = integrate_scene(prep, [start])
        res.raise_for_status()
        prep = prep.restart(start, res.Y[-1].copy(), res.AUX[-1].copy())
    return Window(prep, float(length), method, rtol_used, atol, s["max_step"], s["max_steps"])


def _time_scale(prep: Window) -> float:
    return prep.period if prep.period is not None else 1.0


def _qr(V: np.ndarray, scale: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Re-orthonormalise tangent vectors in the scaled state (the discrete-state components are
    carried along): returns the new vectors and log of the growth of each, ``log R_kk``."""
    Q, R = np.linalg.qr(V[:n] / scale[:, None])
    d = np.diag(R)
    if not np.all(np.isfinite(d)) or np.any(d == 0.0):
        raise FloatingPointError(
            "the tangent vectors became degenerate or non-finite; shorten the interval"
        )
    R = R * np.sign(d)[:, None]
    return np.linalg.solve(R.T, V.T).T, np.log(np.abs(d))


def tangent_run(
    prep: Window,
    m: int,
    *,
    rtol: float | None = None,
    interval: float | None = None,
    seed: int = 0,
    samples_per_interval: int = 16,
) -> dict:
    """Integrate the model and ``m`` tangent vectors over the prepared window, re-orthonormalised
    every ``interval`` (s; halved or doubled on the way so that the growth between two
    re-orthonormalisations stays within e^2 .. e^25, and at most a fortieth of the window so
    that each of the ten batches of the standard error holds four intervals).

    Returns a dict: ``times`` (s) and ``log_growth`` (per interval and vector), the volume
    terms (integral of the Jacobian's trace, s-1 * s; sum of log |det S_yy| at events), whether
    the discrete state fed back on the flow (``memory``), solver statistics.
    """
    pb = prep.problem
    n, na = pb.y0.size, pb.aux0.size
    if not 1 <= m <= n:
        raise ValueError(f"exponents={m!r}: must lie in 1..{n} (the model's state size)")
    rtol = prep.rtol if rtol is None else float(rtol)
    scale = state_scale(pb)
    rng = np.random.default_rng(seed)
    Q0, _ = np.linalg.qr(rng.standard_normal((n, n)))
    V = np.zeros((n + na, m))
    V[:n] = scale[:, None] * Q0[:, :m]
    tau = interval if interval is not None else (
        prep.period / 64 if prep.period is not None else 0.1
    )  # fmt: skip
    t, t_end = pb.t0, pb.t0 + prep.length
    # at least four intervals per batch of the standard error
    tau_max = prep.length / (4 * _BATCHES) if interval is None else 4 * interval
    tau = min(tau, tau_max)
    y, aux, log_det = pb.y0.copy(), pb.aux0.copy(), 0.0
    jac = jacobian_for(pb.hooks)
    work = np.zeros(max(pb.work_size, 1))
    times, growth = [], []
    trace_integral, memory = 0.0, False
    stats = {"steps": 0, "rejected_steps": 0, "rhs_evaluations": 0, "events": 0}
    while t < t_end * (1 - 1e-14):
        t1 = min(t + tau, t_end)
        t_rec = np.linspace(t, t1, samples_per_interval + 1)
        tp = tangent_problem(
            dataclasses.replace(pb, y0=y, aux0=aux, t0=t), V, time_scale=_time_scale(prep),
            log_det=log_det,
        )  # fmt: skip
        res = prep.solve(tp, t_rec, rtol)
        for k in stats:
            stats[k] += res.stats[k]
        Yb = np.ascontiguousarray(res.Y[:, :n])
        Js = np.empty((t_rec.size, n, n))
        Jas = np.empty((t_rec.size, n, na))
        codes = jac.jacobians_along(res.t, Yb, res.AUX, pb.p, pb.ip, work, scale, Js, Jas)
        if codes.any():
            raise FloatingPointError(f"the model failed at a record: {pb.failure(codes.max())}")
        tr = np.trace(Js, axis1=1, axis2=2)
        trace_integral += float(np.trapezoid(tr, res.t))
        memory = memory or bool(np.any(Jas != 0.0))
        y, U, log_size, log_det = tangent_state(res.Y[-1], n, na, m)
        y, aux = y.copy(), res.AUX[-1].copy()
        V, g = _qr(U.copy(), scale, n)
        g = g + log_size  # the vectors are U e^log_size: R_kk of V is R_kk of U times e^l_k
        times.append(t1)
        growth.append(g)
        t = t1
        big = float(np.max(np.abs(g)))
        if big > _MAX_LOG_GROWTH:
            tau /= 2
        elif big < _MIN_LOG_GROWTH and 2 * tau <= tau_max:
            tau *= 2
    return {
        "start": pb.t0,
        "times": np.array(times),
        "log_growth": np.array(growth),
        "trace_integral": trace_integral,
        "log_det_events": log_det,
        "memory": memory,
        "rtol": rtol,
        "stats": stats,
    }


def batch_error(times: np.ndarray, contributions: np.ndarray, start: float) -> np.ndarray:
    """Standard error of an exponent from ``_BATCHES`` batch means of its per-interval
    contributions (log growth over each interval ending at ``times``), per column."""
    edges = np.linspace(start, times[-1], _BATCHES + 1)
    idx = np.clip(np.searchsorted(edges, times, side="left") - 1, 0, _BATCHES - 1)
    lam = []
    prev = np.concatenate([[start], times[:-1]])
    for b in range(_BATCHES):
        sel = idx == b
        if sel.any():
            dur = float(np.sum(times[sel] - prev[sel]))
            lam.append(contributions[sel].sum(axis=0) / dur)
    lam = np.array(lam)
    if lam.shape[0] < 2:
        return np.full(contributions.shape[1:], np.nan)
    return lam.std(axis=0, ddof=1) / math.sqrt(lam.shape[0])


def lyapunov_spectrum(
    scene: SceneSource,
    *,
    exponents: int | None = None,
    cycles: int | None = None,
    duration: float | None = None,
    rtol: float | None = None,
    interval: float | None = None,
    check: bool = True,
    seed: int = 0,
) -> xr.Dataset:
    """Lyapunov spectrum of a scene's model from its variational equations with saltation.

    ``exponents`` tangent vectors (default: all n) follow the scene's run from the end of its
    transient, with the saltation matrix applied at every event (contact onset and end, state
    resets), and are re-orthonormalised by QR in the state scaled by each state's size; the
    exponents are the mean logarithmic growths (Benettin et al. 1980). Valid for the non-smooth
    contact models, whose impacts the two-trajectory method sees only through its separation.

    Parameters
    ----------
    scene : Scene, path or mapping
    exponents : int, optional
        How many exponents (1 .. n), largest first.
    cycles, duration : optional
        Measured length: forcing periods (forced models) or seconds; default the scene's.
    rtol : float, optional
        Tolerance of the tangent run (default the scene's); ``atol`` scales with it.
    interval : float, optional
        First re-orthonormalisation interval, s (adapted on the way; default T/64 or 0.1 s).
    check : bool
        Also run at ``rtol / 10`` over the same window and report that estimate
        (``exponent_tight``) and whether the two agree (``converged``: within 5 % of the
        largest exponent's magnitude or two standard errors of the difference).
    seed : int
        Seed of the random initial tangent vectors.

    Returns
    -------
    xarray.Dataset
        ``exponent`` (dim ``index``, s-1) with its ``stderr`` (batch means), ``running``
        estimates over ``elapsed`` (s), ``exponent_per_period`` (forced models), the sum and
        the mean phase-space contraction rate ``divergence`` (mean trace of the Jacobian plus
        the log volume change at events per time, s-1; equal to the sum of the full spectrum
        when the discrete state does not feed back on the flow, see ``memory``), and the
        check at the tighter tolerance.

    Examples
    --------
    >>> r = lyapunov_spectrum({"model": {"name": "lorenz"},
    ...                        "run": {"duration": 400.0, "transient": 10.0}}, check=False)
    >>> [round(float(v), 1) for v in r.exponent]
    [0.9, 0.0, -14.6]
    """
    prep = measurement_window(scene, cycles=cycles, duration=duration)
    n = prep.problem.y0.size
    m = n if exponents is None else int(exponents)
    run = tangent_run(prep, m, rtol=rtol, interval=interval, seed=seed)
    out = _spectrum_dataset(prep, run)
    if check:
        tight = tangent_run(prep, m, rtol=run["rtol"] / 10, interval=interval, seed=seed)
        lam_t = tight["log_growth"].sum(axis=0) / prep.length
        err_t = batch_error(tight["times"], tight["log_growth"], tight["start"])
        lam = out["exponent"].values
        diff = np.abs(lam_t - lam)
        allowed = np.maximum(0.05 * abs(lam[0]), 2.0 * np.hypot(out["stderr"].values, err_t))
        out["exponent_tight"] = (
            "index",
            lam_t,
            {"units": "s-1", "long_name": f"exponent at rtol = {tight['rtol']:g}"},
        )
        out["converged"] = (
            "index",
            diff <= allowed,
            {"long_name": "agrees with the tighter run (5 % of |lambda_1| or 2 stderr)"},
        )
    return out


def _spectrum_dataset(prep: Window, run: dict) -> xr.Dataset:
    times, growth, start = run["times"], run["log_growth"], run["start"]
    T = times[-1] - start
    lam = growth.sum(axis=0) / T
    running = np.cumsum(growth, axis=0) / (times - start)[:, None]
    err = batch_error(times, growth, start)
    divergence = (run["trace_integral"] + run["log_det_events"]) / T
    m = lam.size
    ds = xr.Dataset(
        {
            "exponent": ("index", lam, {"units": "s-1", "long_name": "Lyapunov exponent"}),
            "stderr": (
                "index",
                err,
                {"units": "s-1", "long_name": f"standard error ({_BATCHES} batch means)"},
            ),
            "running": (
                ("elapsed", "index"),
                running,
                {"units": "s-1", "long_name": "running estimate"},
            ),
            "spectrum_sum": ((), float(lam.sum()), {"units": "s-1", "long_name": "sum"}),
            "divergence": (
                (),
                divergence,
                {
                    "units": "s-1",
                    "long_name": "mean phase-space contraction rate (trace of J + log |det S| "
                    "at events, per time)",
                },
            ),
        },
        coords={
            "index": ("index", np.arange(1, m + 1), {"long_name": "exponent index"}),
            "elapsed": ("elapsed", times - start, {"units": "s", "long_name": "time followed"}),
        },
        attrs={
            "method": "variational equations with saltation at events, QR re-orthonormalisation "
            "(Benettin et al. 1980; Mueller 1995; Dellago, Posch & Hoover 1996)",
            "memory": int(run["memory"]),
            "memory_note": "1: the discrete state (e.g. a contact's held onset velocity) feeds "
            "back on the flow, so the full spectrum's sum need not equal the divergence",
            "rtol": run["rtol"],
            "start_time": start,
            "reorthonormalisations": int(times.size),
            **{f"solver_{k}": v for k, v in run["stats"].items()},
        },
    )
    if prep.period is not None:
        ds["exponent_per_period"] = (
            "index",
            lam * prep.period,
            {"units": "1", "long_name": "exponent per forcing period"},
        )
        ds.attrs["forcing_period"] = prep.period
    return ds
