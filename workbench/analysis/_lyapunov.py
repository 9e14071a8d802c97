"""Lyapunov exponents of a simulated model from its variational equations, with the saltation
matrix at every event (Müller 1995; Dellago, Posch & Hoover 1996), and the spectrum by
repeated QR re-orthonormalisation (Benettin, Galgani, Giorgilli & Strelcyn 1980, Meccanica 15,
21; Shimada & Nagashima 1979, Prog. Theor. Phys. 61, 1605)."""

from __future__ import annotations

import dataclasses

import numpy as np
import xarray as xr

from workbench._attributes import variable
from workbench.analysis._convergence import (
    BATCHES,
    TARGET,
    TRUST,
    agree,
    batch_error,
    judge,
)
from workbench.analysis._window import (
    Window,
    length_limit,
    measurement_window,
    precision_condition,
    stopping_rule,
    time_scale,
)
from workbench.scene import SceneSource
from workbench.solver import (
    state_scale,
    tangent_growths,
    tangent_problem,
    tangent_state,
    tangent_volume,
)

__all__ = ["lyapunov_spectrum"]

#: orthogonality defect (the tangent directions' log sizes minus the log of the volume they
#: span) beyond which the tangent system re-orthonormalises them at the end of a step. e^D bounds
#: the condition number of the directions, whose Gram-Schmidt factors give the volume rate (at
#: 10, 2e4 leaves ~11 digits), and their parts orthogonal to each other are known to rtol e^D.
#: A re-orthonormalisation costs no evaluation (see
#: :mod:`workbench.solver._templates.tangent_hooks`), but it sets the directions apart again,
#: and on the nine-bar's contacts they re-align within microseconds: the steps that resolve
#: that are the cost, which grows as D falls. With fewer exponents than states the integrated
#: volume (the sum check) needs the orthogonal parts, and a smaller D or a tighter tolerance
#: closes it; with all of them the volume rate is the trace on the whole state space and closes
#: at the scene's tolerance. docs/analysis.md ("The sum check", "What the tangent system
#: costs") gives both on the nine-bar's chaos case.
DEFECT = 10.0
#: records of the accumulated growths (running estimate, batch means)
RECORDS = 400
_STATS = ("steps", "rejected_steps", "rhs_evaluations", "events")
#: the tolerance check runs at rtol / CHECK_FACTOR
CHECK_FACTOR = 100.0
#: largest relative difference of the spectrum's sum and the integrated volume rate that
#: counts as closed
SUM_CHECK = 1e-3


def tangent_run(
    prep: Window,
    m: int,
    *,
    rtol: float | None = None,
    defect: float = DEFECT,
    records: int = RECORDS,
    seed: int = 0,
    length: float | None = None,
    resume: dict | None = None,
) -> dict:
    """Integrate the model and ``m`` tangent vectors over the prepared window (or ``length``
    seconds of it) in one run of the tangent system, which re-orthonormalises them at the end
    of each step where their orthogonality defect exceeds ``defect`` (see
    :func:`workbench.solver.tangent_problem`),
    and read the accumulated log growths at ``records`` equally spaced times. ``resume``: a
    run returned by this function, continued from its end (its tolerance and vectors).

    Returns a dict: ``times`` (s) and ``log_growth`` (per record interval and vector: the
    increments of Benettin's accumulators), per record interval the change of the log volume
    the vectors span, integrated with the tangent system (``log_volume``: its sum over the
    window is that of the growths; ``log_volume_memory``: the discrete state's feedback in it)
    and of the sum of ``log |det S_yy|`` at events (``log_det_events``), the number of
    re-orthonormalisations, solver statistics, and the system and its end state (``problem``,
    ``end``) to resume from.
    """
    pb = prep.problem
    n, na = pb.y0.size, pb.aux0.size
    if not 1 <= m <= n:
        raise ValueError(f"exponents={m!r}: must lie in 1..{n} (the model's state size)")
    if not defect > 0:
        raise ValueError(f"defect={defect!r}: must be a positive orthogonality defect")
    length = prep.length if length is None else float(length)
    if resume is None:
        rtol = prep.rtol if rtol is None else float(rtol)
        scale = state_scale(pb)
        rng = np.random.default_rng(seed)
        Q0, _ = np.linalg.qr(rng.standard_normal((n, n)))
        V = np.zeros((n + na, m))
        V[:n] = scale[:, None] * Q0[:, :m]
        tp = tangent_problem(pb, V, time_scale=time_scale(prep), reorthonormalise=defect)
        first, start = tp, pb.t0
        t0 = pb.t0
    else:
        rtol, tp, start = resume["rtol"], resume["problem"], resume["start"]
        Y_end, aux_end, t0 = resume["end"]
        first = dataclasses.replace(tp, y0=Y_end.copy(), aux0=aux_end.copy(), t0=t0)
    times = t0 + length * np.linspace(0.0, 1.0, records + 1)[1:]
    res = prep.solve(first, times, rtol)
    total = np.zeros((times.size + 1, m))
    volume = np.zeros((times.size + 1, 3))
    count = 0
    for r, Y in enumerate([first.y0, *res.Y]):
        total[r] = tangent_growths(tp, Y)  # as if re-orthonormalised here
        w, w_memory, count = tangent_volume(Y, n, na, m)
        volume[r] = (w, w_memory, tangent_state(Y, n, na, m)[3])
    return {
        "start": start,
        "times": times,
        "log_growth": np.diff(total, axis=0),
        "log_volume": np.diff(volume[:, 0]),
        "log_volume_memory": np.diff(volume[:, 1]),
        "log_det_events": np.diff(volume[:, 2]),
        "reorthonormalisations": count,
        "rtol": rtol,
        "stats": {k: res.stats[k] for k in _STATS},
        "problem": tp,
        "end": (res.Y[-1].copy(), res.AUX[-1].copy(), float(times[-1])),
    }


def _joined(a: dict, b: dict) -> dict:
    """Run ``a`` followed by its continuation ``b`` (:func:`tangent_run` with ``resume=a``)."""
    out = dict(b)
    out["start"] = a["start"]
    for key in ("times", "log_growth", "log_volume", "log_volume_memory", "log_det_events"):
        out[key] = np.concatenate([a[key], b[key]])
    out["stats"] = {k: a["stats"][k] + b["stats"][k] for k in _STATS}
    return out


def grown_run(
    prep: Window, m: int, *, limit: float, target: float, sign: float | None = None, **kwargs
) -> dict:
    """:func:`tangent_run` over the window, continued (its length doubled each time) while no
    stopping rule holds for the largest exponent (its standard error above ``target`` of its
    magnitude and, with ``sign``, its sign not decided beyond ``sign`` standard errors:
    :func:`workbench.analysis._window.stopping_rule`) and the doubled length stays within
    ``limit`` (s)."""
    run = tangent_run(prep, m, **kwargs)
    while True:
        elapsed = run["times"][-1] - run["start"]
        lam = run["log_growth"][:, 0].sum() / elapsed
        err = batch_error(run["times"], run["log_growth"][:, :1], run["start"])[0]
        if stopping_rule(lam, err, target, sign) or 2 * elapsed > limit * (1 + 1e-12):
            return run
        more = tangent_run(prep, m, length=elapsed, resume=run, **kwargs)
        run = _joined(run, more)


def lyapunov_spectrum(
    scene: SceneSource,
    *,
    exponents: int | None = None,
    cycles: int | None = None,
    duration: float | None = None,
    budget: float | None = None,
    target: float = TARGET,
    rtol: float | None = None,
    method: str | None = None,
    defect: float = DEFECT,
    check: bool = True,
    seed: int = 0,
    sign: float | None = None,
    start: tuple | None = None,
) -> xr.Dataset:
    """Lyapunov spectrum of a scene's model from its variational equations with saltation.

    ``exponents`` tangent vectors (default: all n) follow the scene's run from the end of its
    transient, with the saltation matrix applied at every event (contact onset and end, state
    resets), and are re-orthonormalised (Gram-Schmidt in the state scaled by each state's size)
    wherever they lose their orthogonality; the exponents are the mean logarithmic growths
    (Benettin et al. 1980), sorted, each with its standard error (batch means). The window grows
    (its length doubled, the run continued) until the largest exponent's standard error is
    below ``target`` of its magnitude or the ``budget`` is spent. Valid for the non-smooth
    contact models, whose impacts the two-trajectory method sees only through its separation;
    the reference for :func:`workbench.analysis.lle_from_equations`. With ``sign`` the window
    also stops growing where the largest exponent's sign is decided, ``|lambda_1| > sign *
    stderr`` (the error target or the sign, whichever comes first; the ``stopped_by``
    attribute names the rule, ``budget`` where neither held), and the error target's condition
    below holds where either rule does.

    ``converged`` holds only where the error target is met, a run at ``rtol / 100`` over the
    same window agrees with every exponent within two standard errors of the difference, and
    the spectrum's sum equals the rate of the log volume the vectors span, integrated with the
    tangent system (trace of its generator, the held onset velocity's feedback included, plus
    the volume jumps at events), to SUM_CHECK; otherwise the ``failed`` attribute says which
    failed and a :class:`ConvergenceWarning` is raised. An exponent is ``trusted`` where the
    estimate converged, its own standard error is at most 20 % of its magnitude (a zero
    exponent never is) and the tighter run agrees with it.

    Parameters
    ----------
    scene : Scene, path or mapping
        The scene whose model and run are measured (as :func:`workbench.load_scene` takes it).
    exponents : int, optional
        How many exponents (1 .. n), largest first.
    cycles, duration : optional
        Measured length: forcing periods (forced models) or seconds; default the scene's.
    budget : float, optional
        Longest window, forcing periods (forced models) or seconds; default BUDGET (8) times
        the measured length.
    target : float
        Relative standard error of the largest exponent the window grows to (default 3 %).
    rtol : float, optional
        Tolerance of the tangent run (default the scene's); ``atol`` scales with it.
    method : str, optional
        ``dop853`` or ``dopri5`` (default the scene's; an implicit method is refused).
    defect : float
        Orthogonality defect of the tangent vectors at which they are re-orthonormalised
        (default DEFECT; see :func:`tangent_run`).
    check : bool
        Also run at ``rtol / 100`` over the same window (``exponent_tight``, ``agrees``);
        without it the estimate is never ``converged``.
    seed : int
        Seed of the random initial tangent vectors.
    sign : float, optional
        Also stop where the largest exponent's sign is decided beyond this many standard
        errors (see above; default: the error target alone).
    start : tuple, optional
        ``(t, y, aux)``: the window starts at this time (s) and state instead of after the
        scene's transient (:func:`workbench.analysis._window.measurement_window`), e.g. where
        the scene's own run ended.

    Returns
    -------
    xarray.Dataset
        ``exponent`` (dim ``index``, s-1, descending) with its ``stderr`` (batch means) and
        ``trusted``, ``running`` estimates over ``elapsed`` (s), ``exponent_per_period`` (forced
        models), ``spectrum_sum``, ``volume_rate`` and ``sum_check``; with all n exponents the
        mean phase-space contraction rate ``divergence`` and the discrete state's share
        ``memory_rate`` (their sum is the volume rate); ``converged`` and the check at the
        tighter tolerance; attributes ``cycles`` or ``duration`` followed, ``failed``,
        ``stopped_by`` (the rule that ended the window: ``error target``, ``sign`` or
        ``budget``).

    Examples
    --------
    >>> r = lyapunov_spectrum({"model": {"name": "lorenz"},
    ...                        "run": {"duration": 400.0, "transient": 10.0}},
    ...                       check=False, budget=400.0)
    >>> sprott = (0.9056, 0.0, -14.5723)  # Sprott (2003), Appendix A
    >>> bool(np.all(np.abs(r.exponent.values - sprott) < 3 * r.stderr.values + 0.02))
    True
    >>> bool(r.converged), "tolerance check: not run (check=False)" in r.attrs["failed"]
    (False, True)
    """
    if not 0 < target < 1:
        raise ValueError(f"target={target!r}: must be a relative error in (0, 1)")
    if sign is not None and not sign > 0:
        raise ValueError(f"sign={sign!r}: must be a positive number of standard errors")
    prep = measurement_window(scene, cycles=cycles, duration=duration, method=method, start=start)
    prep.require_explicit()
    limit = length_limit(prep, budget)
    n = prep.problem.y0.size
    m = n if exponents is None else int(exponents)
    run = grown_run(
        prep, m, limit=limit, target=target, sign=sign, rtol=rtol, defect=defect, seed=seed
    )
    out = _spectrum_dataset(prep, run)
    length = float(out.elapsed[-1])
    lam, err = out["exponent"].values, out["stderr"].values
    unit, units = time_scale(prep), ("cycles" if prep.period is not None else "s")
    precision, rule = precision_condition(
        float(lam[0]), float(err[0]), target, sign,
        f"after {length / unit:g} {units} (budget {limit / unit:g} {units})",
    )  # fmt: skip
    conditions = {
        "error target": precision,
        "sum check": (
            float(out.sum_check) <= SUM_CHECK,
            f"the spectrum's sum and the integrated volume rate differ by "
            f"{float(out.sum_check):.2g} of it (allowed {SUM_CHECK:g})",
        ),
    }
    agrees = np.zeros(m, bool)
    if check:
        tight = tangent_run(
            prep, m, rtol=run["rtol"] / CHECK_FACTOR, defect=defect, seed=seed, length=length
        )
        lam_t = np.sort(tight["log_growth"].sum(axis=0) / length)[::-1]
        err_t = batch_error(tight["times"], tight["log_growth"], tight["start"])
        err_t = err_t[np.argsort(tight["log_growth"].sum(axis=0))[::-1]]
        agrees = agree(lam, lam_t, err, err_t)
        out["exponent_tight"] = (
            "index",
            lam_t,
            variable(f"exponent at rtol = {tight['rtol']:g}", "s-1"),
        )
        out["agrees"] = (
            "index",
            agrees,
            variable("agrees with the tighter run within 2 standard errors"),
        )
        conditions["tolerance check"] = (
            bool(agrees.all()),
            f"at rtol {tight['rtol']:g} the exponents read {np.round(lam_t, 4).tolist()} 1/s "
            f"against {np.round(lam, 4).tolist()}",
        )
    else:
        conditions["tolerance check"] = (False, "not run (check=False)")
    converged, failed = judge(conditions, "the Lyapunov spectrum")
    out["converged"] = ((), converged, variable("every convergence condition holds"))
    out["trusted"] = (
        "index",
        converged & agrees & (err <= TRUST * np.abs(lam)),
        variable(f"converged, agrees at rtol/100, standard error <= {TRUST:.0%}"),
    )
    out.attrs["failed"] = failed
    out.attrs["stopped_by"] = rule or "budget"
    out.attrs["cycles" if prep.period is not None else "duration"] = length / unit
    return out


def _spectrum_dataset(prep: Window, run: dict) -> xr.Dataset:
    times, growth, start = run["times"], run["log_growth"], run["start"]
    T = times[-1] - start
    lam = growth.sum(axis=0) / T
    # Gram-Schmidt orders the accumulators by their long-run growth; over a short window two of
    # them can still be out of order
    order = np.argsort(-lam, kind="stable")
    reordered = bool(np.any(order != np.arange(lam.size)))
    lam, growth = lam[order], growth[:, order]
    running = np.cumsum(growth, axis=0) / (times - start)[:, None]
    err = batch_error(times, growth, start)
    m = lam.size
    volume = float(np.sum(run["log_volume"])) / T
    memory = float(np.sum(run["log_volume_memory"])) / T
    closure = abs(float(lam.sum()) - volume) / max(abs(volume), 1e-300)
    ds = xr.Dataset(
        {
            "exponent": ("index", lam, variable("Lyapunov exponent", "s-1")),
            "stderr": (
                "index",
                err,
                variable(f"standard error ({BATCHES} batch means)", "s-1"),
            ),
            "running": (
                ("elapsed", "index"),
                running,
                variable("running estimate", "s-1"),
            ),
            "spectrum_sum": ((), float(lam.sum()), variable("sum", "s-1")),
            "volume_rate": (
                (),
                volume,
                variable(
                    "mean rate of the log volume the tangent vectors span, "
                    "integrated with the tangent system (trace of its generator on their span, "
                    "the discrete state's feedback included, plus the volume jumps at events); "
                    "equals the sum of the exponents",
                    "s-1",
                ),
            ),
            "sum_check": (
                (),
                closure,
                variable("relative difference of the spectrum's sum and volume_rate"),
            ),
        },
        coords={
            "index": ("index", np.arange(1, m + 1), variable("exponent index")),
            "elapsed": ("elapsed", times - start, variable("time followed", "s")),
        },
        attrs={
            "method": "variational equations with saltation at events, Gram-Schmidt "
            "re-orthonormalisation (Benettin et al. 1980; Mueller 1995; Dellago, Posch & Hoover "
            "1996)",
            "rtol": run["rtol"],
            "start_time": start,
            "reorthonormalisations": int(run["reorthonormalisations"]),
            "reordered": int(reordered),
            "reordered_note": "1: the accumulators' order was not descending over this window "
            "(the exponents were sorted; the window is short for them to separate)",
            **{f"solver_{k}": v for k, v in run["stats"].items()},
        },
    )
    if m == prep.problem.y0.size:  # all n exponents: the volume is the phase-space volume
        ds["divergence"] = (
            (),
            volume - memory,
            variable(
                "mean phase-space contraction rate (trace of J plus the log volume "
                "jumps at events, per time)",
                "s-1",
            ),
        )
        ds["memory_rate"] = (
            (),
            memory,
            variable(
                "part of volume_rate fed back by the discrete state (a contact's "
                "held onset velocity): the trace of J_a's share of the generator",
                "s-1",
            ),
        )
        ds.attrs["memory"] = int(memory != 0.0)
        ds.attrs["memory_note"] = (
            "1: the discrete state (e.g. a contact's held onset velocity) feeds back on the "
            "flow, and the spectrum's sum is the divergence plus memory_rate"
        )
    if prep.period is not None:
        ds["exponent_per_period"] = (
            "index",
            lam * prep.period,
            variable("exponent per forcing period"),
        )
        ds.attrs["forcing_period"] = prep.period
    return ds
