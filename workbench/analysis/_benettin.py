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

import math

import numpy as np
import xarray as xr

from workbench.analysis._lyapunov import Window, batch_error, measurement_window
from workbench.scene import SceneSource
from workbench.solver import (
    copies_problem,
    split_copies,
    state_scale,
    tangent_problem,
    tangent_state,
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
) -> dict:
    """Integrate the fiducial trajectory and one copy per entry of ``separations`` (scaled,
    dimensionless) side by side over ``length`` seconds, each renormalised whenever its log
    growth reaches its ``growth``; with ``variational`` the fiducial also carries a tangent
    vector (the variational equations with saltation, :mod:`workbench.solver._tangent`), so
    that both estimates follow one trajectory. Returns the record ``times`` (s), every copy's
    accumulated log growth at them (renormalisations plus the current separation), the tangent
    vector's (``variational``), renormalisation counts and solver statistics."""
    pb = prep.problem
    n, na = pb.y0.size, pb.aux0.size
    scale = state_scale(pb)
    rng = np.random.default_rng(seed)
    u = rng.standard_normal(n)
    u /= np.linalg.norm(u)
    separations = np.asarray(separations, dtype=float)
    k = separations.size + 1
    base = pb
    if variational:
        base = tangent_problem(pb, np.concatenate([u * scale, np.zeros(na)])[:, None])
    Y = np.tile(base.y0, (k, 1))
    Y[1:, n:] = 0.0  # only the fiducial copy carries the tangent vector
    Y[1:, :n] += separations[:, None] * u[None, :] * scale[None, :]
    system = copies_problem(
        base, Y, np.tile(base.aux0, (k, 1)), separations=separations, growth=growth, measured=n
    )
    t_rec = pb.t0 + np.linspace(0.0, length, _RECORDS + 1)
    total = np.zeros((t_rec.size, k - 1))
    tangent = np.zeros(t_rec.size)
    res = prep.solve(system, t_rec[1:], rtol)
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
        if variational:  # the tangent vector is its direction times e^(log size)
            _, U, log_size, _ = tangent_state(Yr[0], n, na, 1)
            tangent[r] = log_size[0] + math.log(np.linalg.norm(U[:n, 0] / scale))
    return {
        "times": t_rec,
        "total": total,
        "variational": tangent if variational else None,
        "renormalisations": counts,
        "stats": stats,
    }


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


def lle_from_equations(
    scene: SceneSource,
    *,
    cycles: int | None = None,
    duration: float | None = None,
    separation: float | None = None,
    growth: float = GROWTH,
    rtol: float | None = None,
    tighten: bool = True,
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
    interval halved and doubled. ``converged`` says whether all five agree within 5 %.

    Parameters
    ----------
    scene : Scene, path or mapping
    cycles, duration : optional
        Measured length: forcing periods (forced models) or seconds; default the scene's.
    separation : float, optional
        Scaled separation d0. Default: from a pilot run over the first quarter of the window
        with copies at 1e-11 .. 1e-4, the geometric middle of the widest range of them whose
        estimates agree within 5 % (below it the integration error, above it the nonlinearity
        moves the estimate).
    growth : float
        Log growth of a copy's separation that triggers its renormalisation (default ln 10).
    rtol : float, optional
        Tolerance (default the scene's; ``atol`` scales with it).
    tighten : bool
        Where the five variants do not agree, repeat at a 100x tighter tolerance (down to
        1e-11): in the linear range they differ only by the integration error (and the rare
        contact whose timing a copy resolves differently). Every attempt is reported
        (``attempt_rtol``, ``attempt_lle``, ``attempt_spread``).
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
        ``lle`` (s-1) and ``lle_per_period`` (forced models), ``converged``, the five
        ``estimate`` values over dim ``variant`` with their ``separation`` and ``growth``,
        ``spread`` (largest relative deviation from ``lle``), ``stderr`` (10 batch means),
        ``running`` estimate over ``elapsed`` (s), and the pilot evidence (``pilot_rate`` over
        ``pilot_separation``).

    Examples
    --------
    >>> r = lle_from_equations({"model": {"name": "lorenz"},
    ...                         "run": {"duration": 200.0, "transient": 10.0}})
    >>> abs(float(r.lle) - 0.9056) < 0.05, bool(r.converged)
    (True, True)
    """
    prep = measurement_window(scene, cycles=cycles, duration=duration)
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
        times, total = run["times"], run["total"]
        estimates = total[-1] / prep.length
        lle = float(estimates[0])
        spread = float(np.max(np.abs(estimates - lle)) / max(abs(lle), 1e-300))
        tried.append((rtol, lle, spread))
        if spread <= TOLERANCE or not tighten or rtol / 100 < MIN_RTOL:
            break
        rtol /= 100  # the variants part by the integration error: tighten, and say so
    start = times[0]
    stderr = float(batch_error(times[1:], np.diff(total[:, :1], axis=0), start)[0])
    out = xr.Dataset(
        {
            "lle": ((), lle, {"units": "s-1", "long_name": "largest Lyapunov exponent"}),
            "converged": (
                (),
                spread <= TOLERANCE,
                {"long_name": f"the five variants agree within {TOLERANCE:.0%}"},
            ),
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
            **{f"solver_{k}": v for k, v in run["stats"].items()},
        },
    )
    if variational:
        lv = float(run["variational"][-1] / prep.length)
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
