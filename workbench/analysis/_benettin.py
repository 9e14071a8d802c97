"""The largest Lyapunov exponent of a simulated model from its equations: a fiducial trajectory
and nearby copies renormalised as their separation grows or shrinks (Benettin, Galgani &
Strelcyn 1976,
Phys. Rev. A 14, 2338; Benettin, Galgani, Giorgilli & Strelcyn 1980, Meccanica 15, 9), from
several independent starts, with its convergence in time and under its knobs shown.

It needs no variational equations: the copies meet their own impacts, so it checks the
saltation matrices of :func:`workbench.analysis.lyapunov_spectrum` independently, and the
fiducial trajectory carries a tangent vector as well, so that both methods are compared on the
same trajectory (:mod:`workbench.analysis._copies_run`).
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from workbench._attributes import variable
from workbench.analysis._convergence import TARGET, agree, batch_error, judge, pooled
from workbench.analysis._copies_run import follow_copies, joined
from workbench.analysis._window import (
    Window,
    length_limit,
    measurement_window,
    precision_condition,
    stopping_rule,
)
from workbench.scene import SceneSource, load_scene

__all__ = ["lle_from_equations"]

#: default scaled separation of the copies: sqrt(machine epsilon), the step of a forward
#: difference that balances round-off (relative error eps / d) against the neglected curvature
#: (relative error ~d). docs/analysis.md, "One answer from both methods", gives the copies'
#: estimate minus the variational exponent per decade of d0 on the chaos case: a noise floor
#: below about 1e-9 at every tolerance; above it, at loose tolerances, a heavy-tailed lift of
#: some windows.
SEPARATION = math.sqrt(np.finfo(float).eps)
#: default log change of a copy's separation that triggers its renormalisation: growth or
#: shrinkage by a factor 10
GROWTH = math.log(10.0)
#: default number of independent starts (realisations of the scene, :mod:`workbench.run.
#: _ensemble`) the measured length is shared among
STARTS = 4
#: relative spread of the five knob variants above which the tolerance is tightened and above
#: which the estimate is not converged
TOLERANCE = 0.05
#: tightest tolerance the automatic tightening goes to
MIN_RTOL = 1e-11
#: the five copies: (name, separation factor, growth factor)
VARIANTS = (
    ("chosen", 1.0, 1.0),
    ("half separation", 0.5, 1.0),
    ("double separation", 2.0, 1.0),
    ("half growth", 1.0, 0.5),
    ("double growth", 1.0, 2.0),
)


def _start_windows(
    scene: SceneSource, starts: int, cycles, duration, method: str | None, start=None
) -> list[Window]:
    """The measurement windows of the starts: realisations r0, r0 + 1, ... of the scene (r0 its
    own, default 0: the unperturbed run), each advanced through the scene's transient; with
    ``start`` (one start) the window that begins there (:func:`measurement_window`)."""
    if start is not None:
        if starts != 1:
            raise ValueError(
                f"starts={starts!r}: a given start (t, y, aux) is one start; pass starts=1"
            )
        return [measurement_window(scene, cycles=cycles, duration=duration, method=method,
                                   start=start)]  # fmt: skip
    base = load_scene(scene)
    r0 = int(base.run.get("realisation", 0))
    out = []
    for k in range(starts):
        s = base if k == 0 else base.replace(run={**base.run, "realisation": r0 + k})
        out.append(measurement_window(s, cycles=cycles, duration=duration, method=method))
    return out


def _series(runs: list[dict], column: int | str) -> list[np.ndarray]:
    """Per start, the accumulated log growth at the records: copy ``column``'s, the tangent
    vector's (``"variational"``) or the copy's minus the tangent vector's (``"difference"``)."""
    if column == "variational":
        return [r["variational"] for r in runs]
    if column == "difference":
        return [r["total"][:, 0] - r["variational"] for r in runs]
    return [r["total"][:, column] for r in runs]


def _estimate(runs: list[dict], column: int | str = 0) -> dict:
    """The pooled rate (s-1) of a series over the starts and its errors (:func:`pooled`), with
    the rates and batch-means errors of the starts."""
    rates, errors = [], []
    for run, acc in zip(runs, _series(runs, column), strict=True):
        times = run["times"]
        rates.append((acc[-1] - acc[0]) / (times[-1] - times[0]))
        errors.append(batch_error(times[1:], np.diff(acc)[:, None], times[0])[0])
    mean, err, err_starts, err_batches = pooled(np.array(rates), np.array(errors))
    return {
        "value": mean,
        "stderr": err,
        "stderr_starts": err_starts,
        "stderr_batches": err_batches,
        "starts": np.array(rates),
        "start_errors": np.array(errors),
    }


def lle_from_equations(
    scene: SceneSource,
    *,
    cycles: int | None = None,
    duration: float | None = None,
    starts: int = STARTS,
    budget: float | None = None,
    target: float = TARGET,
    separation: float = SEPARATION,
    growth: float = GROWTH,
    rtol: float | None = None,
    method: str | None = None,
    tighten: bool = True,
    check: bool = True,
    variational: bool = True,
    seed: int = 0,
    variants: bool = True,
    sign: float | None = None,
    start: tuple | None = None,
) -> xr.Dataset:
    """Largest Lyapunov exponent (1/s) of a scene's model by the two-trajectory method, from
    independent starts, with its convergence shown.

    The measured length is shared among ``starts`` independent starts: realisations 0, 1, ... of
    the scene (:mod:`workbench.run._ensemble`: initial states perturbed by the scene's
    ``perturbation``, 1e-9 of each state's size by default, then its transient), whose windows
    are independent once the perturbation has grown to the attractor's size (after about
    ln(1/1e-9) / λ; docs/analysis.md gives it on the chaos case). On each start a fiducial
    trajectory and copies displaced by a scaled separation ``d0`` (each state divided by its
    size, the model's ``atol_scale``) are integrated side by side in one step sequence; whenever
    a copy's separation has grown by ``exp(growth)`` or shrunk by the same factor (located as
    events, so that the copies stay in the linear range through the bursts of stretching at
    impacts) it adds the log change and is moved back to ``d0`` along its separation.
    Renormalising on shrinkage as well (Benettin et al. 1980 rescale at every renormalisation,
    whatever the change) keeps the copies off the integration's noise on a contracting orbit, so
    that negative exponents (stable equilibria and periodic orbits) are measured: renormalised
    on growth alone, a copy shrank onto the fiducial trajectory until its separation was noise,
    and the noise's growth was read as the exponent (on the nine-bar's stable period-1 orbit at
    omega = 0.5 pi, c = 20 um), or it coincided with the fiducial trajectory and the run failed
    (a damped linear oscillator); on that nine-bar orbit they now read somewhat above the
    variational exponent on the same trajectory, a gap that depends on neither d0, tolerance nor
    step and is not yet explained (docs/analysis.md, "Contracting orbits"). The trigger is the
    same both ways, so that a copy's separation stays within a band symmetric about ``d0`` in
    the log: the default ``d0`` balances round-off (relative error eps / d) against curvature
    (relative error ~d), and the band keeps both within the same factor ``exp(growth)`` of that
    balance (docs/analysis.md gives the noise floor before and after on the chaos case, and how
    many renormalisations were shrinkages). Five copies run at once: ``(d0, growth)`` (the
    estimate), ``(d0 / 2, growth)``, ``(2 d0, growth)``, ``(d0, growth / 2)`` and ``(d0, 2
    growth)``. The windows then grow (their lengths doubled, the runs continued) until the
    pooled estimate's standard error is below ``target`` of its magnitude or the ``budget`` is
    spent. The standard error is the larger of the spread across the starts and the starts'
    batch means (10 per start) combined (:func:`workbench.analysis._convergence.pooled`).

    The reference is the variational exponent, carried by the same fiducial trajectories
    (``lle_variational``): the two-trajectory estimate is a forward difference of the flow
    along the separation, whose limit d0 -> 0 is the growth of the linearised flow, i.e. of the
    variational equations (Benettin et al. 1980), with the saltation matrix at every contact
    event (Müller 1995) where the flow is non-smooth. A finite ``d0`` adds two errors the
    variational equations do not have: round-off, relative size eps / d0, and the nonlinearity
    and integration error the copies meet where they cross a contact onset at different times
    (the Hertz force's curvature is unbounded there). On the chaos case both are measured (see
    ``SEPARATION``): the default d0 = sqrt(eps) sits between them, at rtol 1e-6 and 1e-10.

    With ``sign`` the windows also stop growing where the sign of the estimate is decided,
    ``|lle| > sign * stderr`` (a sequential rule: the error target or the sign, whichever comes
    first; the ``stopped_by`` attribute names the rule that held, ``budget`` where neither
    did), and the error target's condition below holds where either rule does.

    ``converged`` holds only where (1) the error target is met, (2) the five variants spread
    by at most 5 % and each lies within two standard errors of the estimate, (3) runs at
    ``rtol / 100`` (not below 1e-11) from the same starts agree within two standard errors of
    the difference and (4) the variational exponent on the same trajectories lies within two
    standard errors; otherwise the ``failed`` attribute says which failed, with their numbers,
    and a :class:`~workbench.analysis.ConvergenceWarning` is raised.

    Parameters
    ----------
    scene : Scene, path or mapping
        The scene whose model and run are measured (as :func:`workbench.load_scene` takes it).
    cycles, duration : optional
        Measured length, shared among the starts: forcing periods (forced models) or seconds;
        default the scene's.
    starts : int
        Independent starts (default 4; 1: the scene's own run only, whose error is then its
        batch means alone).
    budget : float, optional
        Longest total length, forcing periods (forced models) or seconds; default 8 times the
        measured length.
    target : float
        Relative standard error the windows grow to (default 3 %).
    separation : float
        Scaled separation d0 (default sqrt(eps) = 1.5e-8; see above).
    growth : float
        Log change of a copy's separation that triggers its renormalisation: growth by
        ``exp(growth)`` or shrinkage by the same factor (default ln 10).
    rtol : float, optional
        Tolerance (default the scene's; ``atol`` scales with it).
    method : str, optional
        ``dop853`` or ``dopri5`` (default the scene's; an implicit method is refused).
    tighten : bool
        Where the five variants spread by more than 5 %, repeat at a 100x tighter tolerance
        (down to 1e-11). Every attempt is reported (``attempt_rtol``, ``attempt_lle``,
        ``attempt_spread``).
    check : bool
        Also run the chosen copy at ``rtol / 100`` from the same starts (``lle_tight``);
        without it the estimate is never ``converged``.
    variational : bool
        The fiducial trajectories also carry a tangent vector of the variational equations
        with saltation at events: ``lle_variational`` on the very same trajectories; without
        it the estimate is never ``converged``.
    seed : int
        Seed of the direction of the initial separation (start k uses ``seed + k``).
    variants : bool
        Run the four separation and growth variants beside the estimate's copy; without them
        (one copy) the estimate is never ``converged``.
    sign : float, optional
        Also stop where the estimate's sign is decided beyond this many standard errors (see
        above; default: the error target alone).
    start : tuple, optional
        ``(t, y, aux)``: one start from this time (s) and state instead of the scene's
        transient (:func:`workbench.analysis._window.measurement_window`), e.g. where the
        scene's own run ended; with ``starts=1``.

    Returns
    -------
    xarray.Dataset
        ``lle`` (s-1) and ``lle_per_period`` (forced models), ``stderr`` with
        ``stderr_starts`` and ``stderr_batches``, ``converged`` (attribute ``failed``: the
        conditions that failed), per ``start`` its ``start_lle``, ``start_stderr`` and
        ``start_variational``, the five ``estimate`` values over dim ``variant`` with their
        ``separation`` and ``growth`` and their ``renormalisations`` (all starts) with
        ``shrink_renormalisations`` (those on shrinkage), ``spread`` (largest relative
        deviation from ``lle``),
        ``running`` estimate over ``elapsed`` (s, per start), ``lle_variational`` with its
        ``stderr_variational`` and ``difference`` (two trajectories minus variational, s-1)
        with its ``stderr_difference``, ``lle_tight``; attributes ``starts``, ``cycles`` or
        ``duration`` used in total and per start, ``stopped_by`` (the rule that ended the
        window: ``error target``, ``sign`` or ``budget``).

    Examples
    --------
    >>> r = lle_from_equations({"model": {"name": "lorenz"},
    ...                         "run": {"duration": 400.0, "transient": 20.0}})
    >>> abs(float(r.lle) - 0.9056) < 0.05, bool(r.converged), r.attrs["failed"]
    (True, True, '')
    """
    if not 0 < target < 1:
        raise ValueError(f"target={target!r}: must be a relative error in (0, 1)")
    if isinstance(starts, bool) or not isinstance(starts, int | np.integer) or starts < 1:
        raise ValueError(f"starts={starts!r}: must be an integer >= 1")
    if not growth > 0:
        raise ValueError(f"growth={growth!r}: must be a positive log growth")
    if not separation > 0:
        raise ValueError(f"separation={separation!r}: must be a positive scaled separation")
    if sign is not None and not sign > 0:
        raise ValueError(f"sign={sign!r}: must be a positive number of standard errors")
    preps = _start_windows(scene, int(starts), cycles, duration, method, start)
    prep = preps[0]
    prep.require_explicit()
    length = prep.length / starts
    limit = length_limit(prep, budget) / starts
    rtol = prep.rtol if rtol is None else float(rtol)
    copies = VARIANTS if variants else VARIANTS[:1]
    seps = np.array([v[1] for v in copies]) * float(separation)
    grow = np.array([v[2] for v in copies]) * float(growth)

    def follow(p, k, span, tol, copies=slice(None), var=variational, resume=None):
        return follow_copies(
            p, seps[copies], grow[copies], span, tol, seed + k, variational=var, resume=resume
        )

    tried = []
    while True:
        runs = [follow(p, k, length, rtol) for k, p in enumerate(preps)]
        estimates = np.array([_estimate(runs, c)["value"] for c in range(len(copies))])
        spread = float(np.max(np.abs(estimates - estimates[0])) / max(abs(estimates[0]), 1e-300))
        tried.append((rtol, float(estimates[0]), spread))
        if spread <= TOLERANCE or not tighten or rtol / 100 < MIN_RTOL:
            break
        rtol /= 100  # the variants part by the integration error: tighten, and say so
    while True:  # the windows grow until a stopping rule holds or the budget is spent
        elapsed = runs[0]["times"][-1] - runs[0]["times"][0]
        est = _estimate(runs)
        rule = stopping_rule(est["value"], est["stderr"], target, sign)
        if rule or 2 * elapsed > limit * (1 + 1e-12):
            break
        runs = [
            joined(r, follow(p, k, elapsed, rtol, resume=r))
            for k, (p, r) in enumerate(zip(preps, runs, strict=True))
        ]
    lle, stderr = est["value"], est["stderr"]
    estimates = np.array([_estimate(runs, c)["value"] for c in range(len(copies))])
    spread = float(np.max(np.abs(estimates - lle)) / max(abs(lle), 1e-300))
    worst = float(np.max(np.abs(estimates - lle)))
    unit = prep.period if prep.period is not None else 1.0
    units = "cycles" if prep.period is not None else "s"
    precision, rule = precision_condition(
        lle, stderr, target, sign,
        f"after {starts} x {elapsed / unit:g} {units} (budget {starts * limit / unit:g} {units})",
    )  # fmt: skip
    conditions = {"error target": precision}
    if variants:
        conditions["variants"] = (
            spread <= TOLERANCE and worst <= 2 * stderr,
            f"the separation and growth variants read {np.round(estimates, 4).tolist()} 1/s: "
            f"spread {spread:.1%} (allowed {TOLERANCE:.0%}), largest deviation "
            f"{worst:.3g} 1/s (allowed two standard errors, {2 * stderr:.3g})",
        )
    else:
        conditions["variants"] = (False, "not run (variants=False)")
    tight = None
    if check:
        rtol_t = max(rtol / 100, MIN_RTOL)
        tight_runs = [
            follow(p, k, elapsed, rtol_t, copies=slice(0, 1), var=False)
            for k, p in enumerate(preps)
        ]
        tight = _estimate(tight_runs)
        conditions["tolerance check"] = (
            bool(agree(lle, tight["value"], stderr, tight["stderr"])),
            f"at rtol {rtol_t:g} the estimate reads {tight['value']:.4g} +/- "
            f"{tight['stderr']:.2g} 1/s against {lle:.4g} +/- {stderr:.2g}",
        )
    else:
        conditions["tolerance check"] = (False, "not run (check=False)")
    var = diff = None
    if variational:
        var, diff = _estimate(runs, "variational"), _estimate(runs, "difference")
        conditions["variational"] = (
            abs(diff["value"]) <= 2 * stderr,
            f"the variational exponent on the same trajectories reads {var['value']:.4g} 1/s "
            f"against {lle:.4g} +/- {stderr:.2g} (difference {diff['value']:+.3g} +/- "
            f"{diff['stderr']:.2g})",
        )
    else:
        conditions["variational"] = (False, "not run (variational=False)")
    converged, failed = judge(conditions, "the two-trajectory exponent")
    return _dataset(
        prep, runs, est, estimates, spread, seps, grow, tried, tight, var, diff,
        converged=converged, failed=failed, rtol=rtol, starts=int(starts),
        stopped_by=rule or "budget", names=[v[0] for v in copies],
    )  # fmt: skip


def _dataset(
    prep, runs, est, estimates, spread, seps, grow, tried, tight, var, diff, **info
) -> xr.Dataset:
    """The estimate's dataset (see :func:`lle_from_equations`)."""
    times0 = runs[0]["times"]
    elapsed = times0[1:] - times0[0]
    running = np.mean([r["total"][1:, 0] for r in runs], axis=0) / elapsed
    unit = prep.period if prep.period is not None else 1.0
    key = "cycles" if prep.period is not None else "duration"
    s, e = "s-1", "standard error"
    out = xr.Dataset(
        {
            "lle": ((), est["value"], variable("largest Lyapunov exponent", s)),
            "converged": ((), info["converged"], variable("every condition holds")),
            "stderr": ((), est["stderr"], variable(f"{e}, pooled", s)),
            "stderr_starts": ((), est["stderr_starts"], variable("spread", s)),
            "stderr_batches": ((), est["stderr_batches"], variable("batches", s)),
            "start_lle": ("start", est["starts"], variable("estimate", s)),
            "start_stderr": ("start", est["start_errors"], variable(e, s)),
            "spread": ((), spread, variable("largest relative deviation")),
            "estimate": ("variant", estimates, variable("estimate", s)),
            "separation": ("variant", seps, variable("scaled separation")),
            "growth": ("variant", grow, variable("log growth per renorm.")),
            "attempt_rtol": ("attempt", [a[0] for a in tried], {"units": "1"}),
            "attempt_lle": ("attempt", [a[1] for a in tried], {"units": s}),
            "attempt_spread": ("attempt", [a[2] for a in tried], {"units": "1"}),
            "renormalisations": (
                "variant",
                np.sum([r["renormalisations"] for r in runs], axis=0),
                variable("number of renormalisations, all starts"),
            ),
            "shrink_renormalisations": (
                "variant",
                np.sum([r["shrinkages"] for r in runs], axis=0),
                variable("number of renormalisations on shrinkage, all starts"),
            ),
            "running": (
                "elapsed",
                running,
                variable("running estimate, mean over the starts", s),
            ),
        },
        coords={
            "variant": ("variant", info["names"]),
            "start": ("start", np.arange(len(runs)), variable("start (realisation offset)")),
            "elapsed": ("elapsed", elapsed, variable("time followed", "s")),
        },
        attrs={
            "method": "fiducial trajectory and copies in one step sequence, renormalised on "
            "growth and on shrinkage, from independent starts (Benettin et al. 1976, 1980)",
            "rtol": info["rtol"],
            "start_time": float(times0[0]),
            "failed": info["failed"],
            "stopped_by": info["stopped_by"],
            "starts": info["starts"],
            key: info["starts"] * elapsed[-1] / unit,
            f"{key}_per_start": elapsed[-1] / unit,
            **{f"solver_{k}": sum(r["stats"][k] for r in runs) for k in runs[0]["stats"]},
        },
    )
    if tight is not None:
        out["lle_tight"] = ((), tight["value"], variable("at rtol / 100", s))
        out["stderr_tight"] = ((), tight["stderr"], variable(e, s))
    if var is not None:
        lv = var["value"]
        out["lle_variational"] = (
            (),
            lv,
            variable("LLE of the variational equations, same trajectories", s),
        )
        out["stderr_variational"] = ((), var["stderr"], variable(e, s))
        out["start_variational"] = ("start", var["starts"], {"units": s})
        out["running_variational"] = (
            "elapsed",
            np.mean([r["variational"][1:] for r in runs], axis=0) / elapsed,
            variable("running variational estimate, mean over the starts", s),
        )
        out["difference"] = (
            (),
            diff["value"],
            variable("two trajectories minus variational, same trajectories", s),
        )
        out["stderr_difference"] = ((), diff["stderr"], variable(e, s))
        out["method_difference"] = (
            (),
            abs(diff["value"]) / max(abs(lv), 1e-300),
            variable("relative difference, two trajectories vs variational"),
        )
    if prep.period is not None:
        out["lle_per_period"] = (
            (),
            est["value"] * prep.period,
            variable("LLE per forcing period"),
        )
        out.attrs["forcing_period"] = prep.period
    return out
