"""The largest Lyapunov exponent of a simulated model from its equations: a fiducial trajectory
and nearby copies renormalised as their separation grows (Benettin, Galgani & Strelcyn 1976,
Phys. Rev. A 14, 2338; Benettin, Galgani, Giorgilli & Strelcyn 1980, Meccanica 15, 9), with the
separation chosen from evidence and the convergence under its knobs shown.

It needs no variational equations: the copies meet their own impacts, so it checks the
saltation matrices of :func:`workbench.analysis.lyapunov_spectrum` independently. The copies are
integrated side by side with the fiducial trajectory in one step-size sequence, so that their
integration errors are nearly equal and their separation is integrated far more accurately than
the tolerance (two separately integrated trajectories differ by the tolerance times the ~1e4-fold
amplification of an impact's timing error, a noise floor far above any useful separation).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import xarray as xr

from workbench.analysis._convergence import TARGET, agree, batch_error, judge
from workbench.analysis._window import Window, length_limit, measurement_window
from workbench.scene import SceneSource
from workbench.solver import (
    copies_problem,
    split_copies,
    state_scale,
    tangent_growths,
    tangent_problem,
)

__all__ = ["lle_from_equations"]

#: candidate scaled separations of the pilot run
_PILOT_SEPARATIONS = 10.0 ** np.arange(-11, -3)
#: default log growth of a copy's separation that triggers its renormalisation (a factor 10)
GROWTH = math.log(10.0)
#: records per measured window (running estimate, batch means)
_RECORDS = 400
#: relative agreement that counts as converged
TOLERANCE = 0.05
#: tightest tolerance the automatic tightening goes to
MIN_RTOL = 1e-11


def follow_copies(
    prep: Window,
    separations: np.ndarray,
    growth: np.ndarray,
    length: float,
    rtol: float,
    seed: int,
    *,
    variational: bool = False,
    resume: dict | None = None,
) -> dict:
    """Integrate the fiducial trajectory and one copy per entry of ``separations`` (scaled,
    dimensionless) side by side over ``length`` seconds, each renormalised whenever its log
    growth reaches its ``growth``; with ``variational`` the fiducial also carries a tangent
    vector (the variational equations with saltation, :mod:`workbench.solver._tangent`), so
    that both estimates follow one trajectory. Returns the record ``times`` (s), every copy's
    accumulated log growth at them (renormalisations plus the current separation), the tangent
    vector's (``variational``), renormalisation counts, solver statistics, and the system and
    its end state to continue from (``resume``: a run returned by this function, continued
    from its end over ``length`` seconds with its copies, tolerance and tangent vector)."""
    pb = prep.problem
    n, na = pb.y0.size, pb.aux0.size
    scale = state_scale(pb)
    separations = np.asarray(separations, dtype=float)
    k = separations.size + 1
    if resume is None:
        rng = np.random.default_rng(seed)
        u = rng.standard_normal(n)
        u /= np.linalg.norm(u)
        base = pb
        if variational:
            base = tangent_problem(pb, np.concatenate([u * scale, np.zeros(na)])[:, None])
        Y = np.tile(base.y0, (k, 1))
        Y[1:, n:] = 0.0  # only the fiducial copy carries the tangent vector
        Y[1:, :n] += separations[:, None] * u[None, :] * scale[None, :]
        system = copies_problem(
            base, Y, np.tile(base.aux0, (k, 1)), separations=separations, growth=growth,
            measured=n,
        )  # fmt: skip
        first, t0 = system, pb.t0
    else:
        system, base, rtol = resume["system"], resume["base"], resume["rtol"]
        Y_end, aux_end, t0 = resume["end"]
        first = dataclasses.replace(system, y0=Y_end.copy(), aux0=aux_end.copy(), t0=t0)
        variational = resume["variational"] is not None
    t_rec = t0 + np.linspace(0.0, length, _RECORDS + 1)
    total = np.zeros((t_rec.size, k - 1))
    tangent = np.zeros(t_rec.size)
    if resume is not None:
        total[0] = resume["total"][-1]
        tangent[0] = resume["variational"][-1] if variational else 0.0
    res = prep.solve(first, t_rec[1:], rtol)
    keys = ("steps", "rejected_steps", "rhs_evaluations", "events")
    stats = {key: res.stats[key] for key in keys}
    counts = np.zeros(k - 1)
    for r in range(1, t_rec.size):
        Yr, _, logs, counts = split_copies(res.Y[r - 1], res.AUX[r - 1], k)
        d = np.linalg.norm((Yr[1:, :n] - Yr[0, :n]) / scale, axis=1)
        if not np.all(d > 0) or not np.all(np.isfinite(d)):
            raise FloatingPointError(
                f"a copy coincides with the fiducial trajectory or left it at t = "
                f"{t_rec[r]:g} s (scaled distances {d!r}); choose other separations"
            )
        total[r] = logs + np.log(d / separations)
        if variational:  # the tangent vector's log growth
            tangent[r] = tangent_growths(base, Yr[0])[0]
    return {
        "times": t_rec,
        "total": total,
        "variational": tangent if variational else None,
        "renormalisations": counts,
        "stats": stats,
        "rtol": rtol,
        "system": system,
        "base": base,
        "end": (res.Y[-1].copy(), res.AUX[-1].copy(), float(t_rec[-1])),
    }


def _joined(a: dict, b: dict) -> dict:
    """Run ``a`` followed by its continuation ``b`` (:func:`follow_copies` with ``resume=a``):
    records of both (``b``'s first is ``a``'s last), statistics summed."""
    out = dict(b)
    out["times"] = np.concatenate([a["times"], b["times"][1:]])
    out["total"] = np.concatenate([a["total"], b["total"][1:]])
    if a["variational"] is not None:
        out["variational"] = np.concatenate([a["variational"], b["variational"][1:]])
    out["stats"] = {k: a["stats"][k] + b["stats"][k] for k in a["stats"]}
    return out


def _rate_and_error(run: dict, column: int = 0) -> tuple[float, float]:
    """The exponent of a copy (its mean log growth rate, s-1) and its standard error."""
    times, total = run["times"], run["total"][:, column]
    elapsed = times[-1] - times[0]
    err = batch_error(times[1:], np.diff(total)[:, None], times[0])[0]
    return float(total[-1] / elapsed), float(err)


def _plateau(rates: np.ndarray) -> tuple[int, int]:
    """The widest range of consecutive candidates whose estimates agree within TOLERANCE of
    their median (first of equal width)."""
    best = (0, 0)
    for i in range(rates.size):
        for j in range(i, rates.size):
            window = rates[i : j + 1]
            med = float(np.median(window))
            if np.all(np.abs(window - med) <= TOLERANCE * max(abs(med), 1e-300)):
                if j - i > best[1] - best[0]:
                    best = (i, j)
    return best


def _spread(run: dict) -> tuple[float, float]:
    """The chosen copy's estimate (s-1) and the largest relative deviation of the variants."""
    estimates = run["total"][-1] / (run["times"][-1] - run["times"][0])
    lle = float(estimates[0])
    return lle, float(np.max(np.abs(estimates - lle)) / max(abs(lle), 1e-300))


def lle_from_equations(
    scene: SceneSource,
    *,
    cycles: int | None = None,
    duration: float | None = None,
    budget: float | None = None,
    target: float = TARGET,
    separation: float | None = None,
    growth: float = GROWTH,
    rtol: float | None = None,
    method: str | None = None,
    tighten: bool = True,
    check: bool = True,
    variational: bool = True,
    seed: int = 0,
) -> xr.Dataset:
    """Largest Lyapunov exponent (1/s) of a scene's model by the two-trajectory method, with
    its convergence shown.

    A fiducial trajectory (the scene's run after its transient) and copies displaced by a
    scaled separation ``d0`` (each state divided by its size, the model's ``atol_scale``) are
    integrated side by side in one step sequence; whenever a copy's separation has grown by
    ``exp(growth)`` (located as an event, so that the copies stay in the linear range through
    the bursts of stretching at impacts, whatever their rate) it adds the log growth and is
    pulled back along its separation. Five copies run at once on the same fiducial trajectory:
    ``(d0, growth)`` (the estimate), ``(d0 / 2, growth)``, ``(2 d0, growth)``,
    ``(d0, growth / 2)`` and ``(d0, 2 growth)``: the separation and the renormalisation
    interval halved and doubled. The window then grows (its length doubled, the run continued)
    until the estimate's standard error (batch means) is below ``target`` of its magnitude or
    the ``budget`` is spent.

    ``converged`` holds only where the error target is met, the five variants agree within 5 %,
    a run at ``rtol / 100`` (not below 1e-11) over the same window agrees within two standard
    errors of the difference, and the variational exponent on the same trajectory agrees
    within two standard errors; otherwise the ``failed`` attribute says which failed and a
    :class:`~workbench.analysis.ConvergenceWarning` is raised. The variational exponent is the
    reference: it is the linearised growth itself, free of the copies' finite separation (whose
    nonlinearity and integration error move the two-trajectory estimate, the more so where a
    copy and the fiducial trajectory meet a contact at different times).

    Parameters
    ----------
    scene : Scene, path or mapping
    cycles, duration : optional
        Measured length: forcing periods (forced models) or seconds; default the scene's.
    budget : float, optional
        Longest window, forcing periods (forced models) or seconds; default 8 times the
        measured length.
    target : float
        Relative standard error the window grows to (default 3 %).
    separation : float, optional
        Scaled separation d0. Default: from a pilot run over the first quarter of the window
        with copies at 1e-11 .. 1e-4, the geometric middle of the widest range of them whose
        estimates agree within 5 % (below it the integration error, above it the nonlinearity
        moves the estimate).
    growth : float
        Log growth of a copy's separation that triggers its renormalisation (default ln 10).
    rtol : float, optional
        Tolerance (default the scene's; ``atol`` scales with it).
    method : str, optional
        ``dop853`` or ``dopri5`` (default the scene's; an implicit method is refused).
    tighten : bool
        Where the five variants do not agree, repeat at a 100x tighter tolerance (down to
        1e-11): in the linear range they differ only by the integration error (and the rare
        contact whose timing a copy resolves differently). Every attempt is reported
        (``attempt_rtol``, ``attempt_lle``, ``attempt_spread``).
    check : bool
        Also run the chosen copy at ``rtol / 100`` over the final window (``lle_tight``);
        without it the estimate is never ``converged``.
    variational : bool
        The fiducial trajectory also carries a tangent vector of the variational equations
        with saltation at events (:func:`workbench.analysis.lyapunov_spectrum`'s method):
        ``lle_variational`` on the very same trajectory, so that the two methods are compared
        without the scatter of two chaotic realisations.
    seed : int
        Seed of the direction of the initial separation.

    Returns
    -------
    xarray.Dataset
        ``lle`` (s-1) and ``lle_per_period`` (forced models), ``converged`` (attribute
        ``failed``: the conditions that failed), the five
        ``estimate`` values over dim ``variant`` with their ``separation`` and ``growth``,
        ``spread`` (largest relative deviation from ``lle``), ``stderr`` (10 batch means),
        ``running`` estimate over ``elapsed`` (s), and the pilot evidence (``pilot_rate`` over
        ``pilot_separation``).

    Examples
    --------
    >>> r = lle_from_equations({"model": {"name": "lorenz"},
    ...                         "run": {"duration": 200.0, "transient": 10.0}})
    >>> abs(float(r.lle) - 0.9056) < 0.05, bool(r.converged), r.attrs["failed"]
    (True, True, '')
    """
    if not 0 < target < 1:
        raise ValueError(f"target={target!r}: must be a relative error in (0, 1)")
    prep = measurement_window(scene, cycles=cycles, duration=duration, method=method)
    prep.require_explicit()
    limit = length_limit(prep, budget)
    rtol = prep.rtol if rtol is None else float(rtol)
    if not growth > 0:
        raise ValueError(f"growth={growth!r}: must be a positive log growth")
    pilot = None
    if separation is None:
        pilot_length = prep.length / 4
        run = follow_copies(
            prep, _PILOT_SEPARATIONS, np.full(_PILOT_SEPARATIONS.size, growth), pilot_length,
            rtol, seed,
        )  # fmt: skip
        rates = run["total"][-1] / pilot_length
        i, j = _plateau(rates)
        separation = float(np.sqrt(_PILOT_SEPARATIONS[i] * _PILOT_SEPARATIONS[j]))
        pilot = (rates, pilot_length)
    if not separation > 0:
        raise ValueError(f"separation={separation!r}: must be a positive scaled separation")
    seps = np.array([1.0, 0.5, 2.0, 1.0, 1.0]) * separation
    grow = np.array([1.0, 1.0, 1.0, 0.5, 2.0]) * growth
    tried = []
    while True:
        run = follow_copies(prep, seps, grow, prep.length, rtol, seed, variational=variational)
        lle, spread = _spread(run)
        tried.append((rtol, lle, spread))
        if spread <= TOLERANCE or not tighten or rtol / 100 < MIN_RTOL:
            break
        rtol /= 100  # the variants part by the integration error: tighten, and say so
    while True:  # the window grows until the error target is met or the budget is spent
        elapsed = run["times"][-1] - run["times"][0]
        lle, stderr = _rate_and_error(run)
        if stderr <= target * abs(lle) or 2 * elapsed > limit * (1 + 1e-12):
            break
        run = _joined(run, follow_copies(prep, seps, grow, elapsed, rtol, seed, resume=run))
    lle, spread = _spread(run)
    times, total = run["times"], run["total"]
    estimates = total[-1] / elapsed
    unit = prep.period if prep.period is not None else 1.0
    units = "cycles" if prep.period is not None else "s"
    conditions = {
        "error target": (
            stderr <= target * abs(lle),
            f"the standard error is {stderr / abs(lle):.1%} of the estimate after "
            f"{elapsed / unit:g} {units} (target {target:.0%}, budget {limit / unit:g} {units})",
        ),
        "variants": (
            spread <= TOLERANCE,
            f"the separation and growth variants spread by {spread:.1%} (allowed {TOLERANCE:.0%})",
        ),
    }
    tight = None
    if check:
        rtol_t = max(rtol / 100, MIN_RTOL)
        tight = follow_copies(prep, seps[:1], grow[:1], elapsed, rtol_t, seed)
        lle_t, err_t = _rate_and_error(tight)
        conditions["tolerance check"] = (
            bool(agree(lle, lle_t, stderr, err_t)),
            f"at rtol {rtol_t:g} the estimate reads {lle_t:.4g} +/- {err_t:.2g} 1/s against "
            f"{lle:.4g} +/- {stderr:.2g}",
        )
    else:
        conditions["tolerance check"] = (False, "not run (check=False)")
    if variational:
        lv = float(run["variational"][-1] / elapsed)
        conditions["variational"] = (
            abs(lle - lv) <= 2 * stderr,
            f"the variational exponent on the same trajectory reads {lv:.4g} 1/s against "
            f"{lle:.4g} +/- {stderr:.2g}",
        )
    converged, failed = judge(conditions, "the two-trajectory exponent")
    start = times[0]
    out = xr.Dataset(
        {
            "lle": ((), lle, {"units": "s-1", "long_name": "largest Lyapunov exponent"}),
            "converged": ((), converged, {"long_name": "every convergence condition holds"}),
            "spread": (
                (),
                spread,
                {"units": "1", "long_name": "largest relative deviation of a variant"},
            ),
            "stderr": (
                (),
                stderr,
                {"units": "s-1", "long_name": "standard error (10 batch means)"},
            ),
            "estimate": ("variant", estimates, {"units": "s-1", "long_name": "estimate"}),
            "separation": (
                "variant",
                seps,
                {"units": "1", "long_name": "scaled separation"},
            ),
            "growth": (
                "variant",
                grow,
                {"units": "1", "long_name": "log growth between renormalisations"},
            ),
            "attempt_rtol": (
                "attempt",
                [a[0] for a in tried],
                {"units": "1", "long_name": "rtol of the attempt"},
            ),
            "attempt_lle": (
                "attempt",
                [a[1] for a in tried],
                {"units": "s-1", "long_name": "estimate of the attempt"},
            ),
            "attempt_spread": (
                "attempt",
                [a[2] for a in tried],
                {"units": "1", "long_name": "spread of the attempt"},
            ),
            "renormalisations": (
                "variant",
                run["renormalisations"],
                {"units": "1", "long_name": "number of renormalisations"},
            ),
            "running": (
                "elapsed",
                total[1:, 0] / (times[1:] - start),
                {"units": "s-1", "long_name": "running estimate"},
            ),
        },
        coords={
            "variant": (
                "variant",
                ["chosen", "half separation", "double separation", "half growth", "double growth"],
            ),  # fmt: skip
            "elapsed": (
                "elapsed",
                times[1:] - start,
                {"units": "s", "long_name": "time followed"},
            ),
        },
        attrs={
            "method": "fiducial trajectory and copies in one step sequence, renormalised on "
            "growth (Benettin et al. 1976, 1980)",
            "rtol": rtol,
            "start_time": start,
            "failed": failed,
            ("cycles" if prep.period is not None else "duration"): elapsed / unit,
            **{f"solver_{k}": v for k, v in run["stats"].items()},
        },
    )
    if tight is not None:
        out["lle_tight"] = (
            (),
            lle_t,
            {"units": "s-1", "long_name": f"estimate at rtol = {rtol_t:g}"},
        )
        out["stderr_tight"] = ((), err_t, {"units": "s-1", "long_name": "its standard error"})
    if variational:
        out["lle_variational"] = (
            (),
            lv,
            {"units": "s-1", "long_name": "LLE of the variational equations, same trajectory"},
        )
        out["running_variational"] = (
            "elapsed",
            run["variational"][1:] / (times[1:] - start),
            {"units": "s-1", "long_name": "running estimate of the variational equations"},
        )
        out["method_difference"] = (
            (),
            abs(lle - lv) / max(abs(lv), 1e-300),
            {"units": "1", "long_name": "relative difference, two trajectories vs variational"},
        )
    if pilot is not None:
        out["pilot_rate"] = (
            "pilot_separation",
            pilot[0],
            {"units": "s-1", "long_name": "pilot estimate"},
        )
        out = out.assign_coords(
            pilot_separation=(
                "pilot_separation",
                _PILOT_SEPARATIONS,
                {"units": "1", "long_name": "scaled separation of the pilot copies"},
            )
        )
        out.attrs["pilot_length"] = pilot[1]
    if prep.period is not None:
        out["lle_per_period"] = (
            (),
            lle * prep.period,
            {"units": "1", "long_name": "LLE per forcing period"},
        )
        out.attrs["forcing_period"] = prep.period
    return out
