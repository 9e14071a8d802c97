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
    state_scale,
    tangent_growths,
    tangent_problem,
    tangent_state,
    tangent_volume,
)

__all__ = ["lyapunov_spectrum"]

#: orthogonality defect (the tangent directions' log sizes minus the log of the volume they
#: span) at which the tangent system re-orthonormalises them: a direction whose part
#: orthogonal to the others has shrunk by e^-D relative to its size is integrated to rtol e^D
#: of that part, and e^D bounds the condition number of the vectors whose volume the system
#: integrates (rtol e^3 = 2e-5 at rtol 1e-6)
DEFECT = 3.0
#: records of the accumulated growths (running estimate, batch means)
RECORDS = 400
_STATS = ("steps", "rejected_steps", "rhs_evaluations", "events")
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


def tangent_run(
    prep: Window,
    m: int,
    *,
    rtol: float | None = None,
    defect: float = DEFECT,
    records: int = RECORDS,
    seed: int = 0,
) -> dict:
    """Integrate the model and ``m`` tangent vectors over the prepared window in one run of the
    tangent system, which re-orthonormalises them wherever their orthogonality defect reaches
    ``defect`` (see :func:`workbench.solver.tangent_problem`), and read the accumulated log
    growths at ``records`` equally spaced times.

    Returns a dict: ``times`` (s) and ``log_growth`` (per record interval and vector: the
    increments of Benettin's accumulators), per record interval the change of the log volume
    the vectors span, integrated with the tangent system (``log_volume``: its sum over the
    window is that of the growths; ``log_volume_memory``: the discrete state's feedback in it)
    and of the sum of ``log |det S_yy|`` at events (``log_det_events``), the number of
    re-orthonormalisations, solver statistics.
    """
    pb = prep.problem
    n, na = pb.y0.size, pb.aux0.size
    if not 1 <= m <= n:
        raise ValueError(f"exponents={m!r}: must lie in 1..{n} (the model's state size)")
    if not defect > 0:
        raise ValueError(f"defect={defect!r}: must be a positive orthogonality defect")
    rtol = prep.rtol if rtol is None else float(rtol)
    scale = state_scale(pb)
    rng = np.random.default_rng(seed)
    Q0, _ = np.linalg.qr(rng.standard_normal((n, n)))
    V = np.zeros((n + na, m))
    V[:n] = scale[:, None] * Q0[:, :m]
    tp = tangent_problem(pb, V, time_scale=_time_scale(prep), reorthonormalise=defect)
    times = pb.t0 + prep.length * np.linspace(0.0, 1.0, records + 1)[1:]
    res = prep.solve(tp, times, rtol)
    total = np.zeros((times.size + 1, m))
    volume = np.zeros((times.size + 1, 3))
    count = 0
    for r, Y in enumerate(res.Y, start=1):
        total[r] = tangent_growths(tp, Y)  # as if re-orthonormalised here
        w, w_memory, count = tangent_volume(Y, n, na, m)
        volume[r] = (w, w_memory, tangent_state(Y, n, na, m)[3])
    return {
        "start": pb.t0,
        "times": times,
        "log_growth": np.diff(total, axis=0),
        "log_volume": np.diff(volume[:, 0]),
        "log_volume_memory": np.diff(volume[:, 1]),
        "log_det_events": np.diff(volume[:, 2]),
        "reorthonormalisations": count,
        "rtol": rtol,
        "stats": {k: res.stats[k] for k in _STATS},
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
    defect: float = DEFECT,
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
    defect : float
        Orthogonality defect of the tangent vectors at which they are re-orthonormalised
        (default DEFECT; see :func:`tangent_run`).
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
    run = tangent_run(prep, m, rtol=rtol, defect=defect, seed=seed)
    out = _spectrum_dataset(prep, run)
    if check:
        tight = tangent_run(prep, m, rtol=run["rtol"] / 10, defect=defect, seed=seed)
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
    m = lam.size
    volume = float(np.sum(run["log_volume"])) / T
    memory = float(np.sum(run["log_volume_memory"])) / T
    closure = abs(float(lam.sum()) - volume) / max(abs(volume), 1e-300)
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
            "volume_rate": (
                (),
                volume,
                {
                    "units": "s-1",
                    "long_name": "mean rate of ln |det V| of the n tangent vectors, integrated "
                    "with the tangent system (trace of its generator, the discrete state's "
                    "feedback included, plus the log volume jump at events); equals the full "
                    "spectrum's sum",
                },
            ),
            "sum_check": (
                (),
                closure,
                {
                    "units": "1",
                    "long_name": "relative difference of the spectrum's sum and volume_rate",
                },
            ),
            "divergence": (
                (),
                volume - memory,
                {
                    "units": "s-1",
                    "long_name": "mean phase-space contraction rate (trace of J plus log |det "
                    "S_yy| at events, per time)",
                },
            ),
            "memory_rate": (
                (),
                memory,
                {
                    "units": "s-1",
                    "long_name": "part of volume_rate fed back by the discrete state (a "
                    "contact's held onset velocity): tr(J_a V_a V_y^-1) and its jumps at events",
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
            "rtol": run["rtol"],
            "start_time": start,
            "reorthonormalisations": int(run["reorthonormalisations"]),
            **{f"solver_{k}": v for k, v in run["stats"].items()},
        },
    )
    if np.isfinite(memory):  # all n exponents
        ds.attrs["memory"] = int(memory != 0.0)
        ds.attrs["memory_note"] = (
            "1: the discrete state (e.g. a contact's held onset velocity) feeds back on the "
            "flow, and the spectrum's sum is the divergence plus memory_rate"
        )
    if prep.period is not None:
        ds["exponent_per_period"] = (
            "index",
            lam * prep.period,
            {"units": "1", "long_name": "exponent per forcing period"},
        )
        ds.attrs["forcing_period"] = prep.period
    return ds
