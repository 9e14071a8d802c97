"""What accuracy costs in time: work-precision studies of a scene.

Impact dynamics are chaotic, so two correct runs diverge after a few impacts; accuracy is judged
on quantities that stay meaningful (Hairer, Nørsett & Wanner 1993, Sec. II.10, for
work-precision diagrams; for non-smooth systems e.g. Acary & Brogliato 2008, Ch. 1):

(a) ``short_error``: the largest difference from the reference over a short horizon before
    chaotic divergence, relative to the reference's range. The horizon is half the time after
    which the reference and a run 100x looser than it separate by 1 % of a variable's range
    (at most the first forcing period from t0): for an impacting mechanism whose nearby
    trajectories separate at ~200 1/s, a whole crank cycle would measure chaos, not accuracy.
    It is cut further where the reference itself stops being exact: where it and a twin run
    10x tighter separate by REFERENCE_FLOOR (1e-6) of a range (impacts amplify the reference's
    own error too, which would make small errors a matter of luck; README, "Accuracy and
    cost"). The largest twin separation over the horizon is stored as ``reference_error``;
(b) ``peak_error``: the relative error of the peak of each variable over that horizon (e.g.
    the peak force of the first impacts), and ``events_error``: the relative error of the
    number of events (e.g. contact onsets and ends) per forcing period over the whole run;
(c) ``statistic_error``: the error of the mean and of the standard deviation of the stroboscopic
    samples of the whole run, relative to the reference's standard deviation.

The reference is the most accurate method at the tightest tolerance (stated in the result).
"""

from __future__ import annotations

import math
import time as _time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np
import xarray as xr

from workbench.run import (
    divergence_time,
    provenance,
    run_status,
    separation,
    short_scene,
    simulate,
    status_attrs,
    with_solver,
)
from workbench.scene import SceneSource, load_scene

__all__ = [
    "DEFAULT_METHODS",
    "DEFAULT_TOLERANCES",
    "REFERENCE_FLOOR",
    "Recommendation",
    "accuracy",
    "recommend",
    "short_horizon",
]

DEFAULT_METHODS = ("dop853", "dopri5", "scipy:DOP853", "scipy:Radau", "scipy:LSODA")
DEFAULT_TOLERANCES = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11)
_ERRORS = ("short_error", "peak_error", "events_error", "statistic_error")
# The reference must be exact to this fraction of a variable's range over the short horizon:
# 1000x below the 1e-3 error targets `recommend` is meant for.
REFERENCE_FLOOR = 1e-6


def _strobe(ds: xr.Dataset) -> xr.Dataset:
    spp = int(ds.attrs.get("samples_per_period", 1))
    return ds.isel(time=slice(None, None, spp))


def short_horizon(
    ref_short: xr.Dataset, probe: xr.Dataset, twin: xr.Dataset | None = None
) -> float:
    """Half the divergence time of the reference and a looser probe (s), cut where the
    reference and a tighter ``twin`` separate by REFERENCE_FLOOR; the whole record if they never
    diverge; at least 10 records."""
    t = ref_short.time.values - ref_short.time.values[0]
    limit = 0.5 * divergence_time(probe, ref_short)
    if twin is not None:
        # the last record before the twin's separation exceeds the floor
        over = np.flatnonzero(separation(twin, ref_short) > REFERENCE_FLOOR)
        if over.size:
            limit = min(limit, t[max(over[0] - 1, 0)])
    return float(min(t[-1], max(limit, t[min(10, t.size - 1)])))


def _records_within(ref_short: xr.Dataset, horizon: float) -> int:
    """Number of records of the short runs that lie within ``horizon`` (s) of their start."""
    return int(np.searchsorted(ref_short.time.values - ref_short.time.values[0], horizon, "right"))


def _measure(
    short: xr.Dataset,
    long: xr.Dataset,
    ref_short: xr.Dataset,
    ref_long: xr.Dataset,
    periods: float,
    horizon: float,
) -> dict[str, float]:
    peak_err, stat_err = 0.0, 0.0
    n = _records_within(ref_short, horizon)
    short, ref_short = short.isel(time=slice(0, n)), ref_short.isel(time=slice(0, n))
    short_err = float(np.max(separation(short, ref_short)))
    for name in ref_short.data_vars:
        r = ref_short[name].values
        peak_ref = float(np.nanmax(np.abs(r)))
        if peak_ref > 0:
            peak = float(np.nanmax(np.abs(short[name].values)))
            peak_err = max(peak_err, abs(peak - peak_ref) / peak_ref)
    s, sr = _strobe(long), _strobe(ref_long)
    for name in sr.data_vars:
        spread = float(sr[name].std()) or 1.0
        d_mean = abs(float(s[name].mean() - sr[name].mean())) / spread
        d_std = abs(float(s[name].std() - sr[name].std())) / spread
        stat_err = max(stat_err, d_mean, d_std)
    ev, ev_ref = long.attrs["solver_events"] / periods, ref_long.attrs["solver_events"] / periods
    events_err = abs(ev - ev_ref) / ev_ref if ev_ref else float(ev != ev_ref)
    return {
        "short_error": short_err,
        "peak_error": peak_err,
        "events_error": events_err,
        "statistic_error": stat_err,
    }


def accuracy(
    scene: SceneSource,
    *,
    methods: Sequence[str] = DEFAULT_METHODS,
    tolerances: Sequence[float] = DEFAULT_TOLERANCES,
    reference: tuple[str, float] | None = None,
    horizon: float | None = None,
    progress: bool = False,
) -> xr.Dataset:
    """Work-precision study: run a scene with every method at every tolerance.

    Parameters
    ----------
    scene : Scene, path or mapping
        The scene studied (its sweep, if any, is dropped).
    methods : sequence of str
        Solver methods (``"dop853"``, ``"dopri5"``, ``"ark548"``, ``"scipy:<name>"``).
    tolerances : sequence of float
        rtol = atol values (atol is scaled per state by the model; see the model docs).
    reference : (method, tolerance), optional
        The reference run; default ``("dop853", min(tolerances) / 10)`` (at least 1e-13).
    horizon : float, optional
        Horizon (s) of the short-horizon error; default: chosen from the separation of the
        reference and a run 100x looser, and of the reference and a twin 10x tighter (see the
        module docstring), stored as ``short_horizon``.
    progress : bool
        Print one line per run.

    Returns
    -------
    xarray.Dataset
        Dims ``solver_method`` (not ``method``, a keyword of ``Dataset.sel``) and
        ``rtol`` (= atol; not ``tolerance``, a keyword of ``Dataset.sel`` too); variables
        ``wall_time`` (s, long run), ``steps``, ``rhs_evaluations``,
        the errors (dimensionless, see the module docstring), ``status`` (int8 flags of
        :class:`workbench.Status`: the first failed run's, 0 if both ran) and ``failure`` (its
        message);
        the reference in the attributes, with ``reference_error``: its separation from the
        twin over the horizon (errors below it are not resolved; NaN without a twin).

    Examples
    --------
    >>> wp = accuracy({"model": {"name": "duffing"}, "run": {"cycles": 5}},
    ...               methods=["dop853"], tolerances=[1e-4, 1e-8])
    >>> bool(wp.short_error.sel(rtol=1e-8) < wp.short_error.sel(rtol=1e-4))
    True
    """
    scene = load_scene(scene)
    ref_method, ref_tol = reference or ("dop853", max(min(tolerances) / 10, 1e-13))
    ref_short = simulate(short_scene(scene, ref_method, ref_tol))
    ref_long = simulate(with_solver(scene, ref_method, ref_tol))
    twin_tol = max(ref_tol / 10, 1e-13)
    twin = simulate(short_scene(scene, ref_method, twin_tol)) if twin_tol < ref_tol else None
    if horizon is None:
        probe = simulate(short_scene(scene, ref_method, ref_tol * 100))
        horizon = short_horizon(ref_short, probe, twin)
    ref_error = math.nan
    if twin is not None:
        n = _records_within(ref_short, horizon)
        ref_error = float(
            np.max(separation(twin.isel(time=slice(0, n)), ref_short.isel(time=slice(0, n))))
        )
    period = ref_long.attrs.get("forcing_period")
    total = float(ref_long.time[-1])
    periods = total / period if period else total
    shape = (len(methods), len(tolerances))
    out = {k: np.full(shape, np.nan) for k in ("wall_time", "steps", "rhs_evaluations", *_ERRORS)}
    status = np.zeros(shape, np.int8)
    failures = np.full(shape, "", dtype=object)
    for i, method in enumerate(methods):
        for j, tol in enumerate(tolerances):
            t0 = _time.perf_counter()
            short = simulate(short_scene(scene, method, tol), throw=False)
            if run_status(short).failed:
                long = short  # the long run would fail as well: not worth its time
            else:
                long = simulate(with_solver(scene, method, tol), throw=False)
            failed = next((r for r in (short, long) if run_status(r).failed), None)
            if failed is not None:
                status[i, j] = run_status(failed)
                failures[i, j] = failed.attrs["run_message"]
                continue
            out["wall_time"][i, j] = long.attrs["solver_wall_time"]
            out["steps"][i, j] = long.attrs["solver_steps"]
            out["rhs_evaluations"][i, j] = long.attrs["solver_rhs_evaluations"]
            for k, v in _measure(short, long, ref_short, ref_long, periods, horizon).items():
                out[k][i, j] = v
            if progress:
                print(
                    f"{method:14s} tol {tol:7.0e}: {out['wall_time'][i, j]:8.4f} s, "
                    f"short error {out['short_error'][i, j]:.2e} "
                    f"({_time.perf_counter() - t0:.1f} s incl. overhead)"
                )
    units = {"wall_time": "s", "steps": "1", "rhs_evaluations": "1"}
    long_names = {
        "wall_time": "solver wall time of the whole run",
        "steps": "accepted steps of the whole run",
        "rhs_evaluations": "right-hand-side evaluations of the whole run",
        "short_error": "largest error over the short horizon, relative to the variable's range",
        "peak_error": "relative error of the peak over the short horizon",
        "events_error": "relative error of the number of events per period",
        "statistic_error": "error of mean and spread of the stroboscopic samples, relative to "
        "the reference spread",
    }
    dims = ("solver_method", "rtol")
    data = {
        k: (dims, v, {"units": units.get(k, "1"), "long_name": long_names[k]})
        for k, v in out.items()
    }
    data["status"] = (dims, status, status_attrs("outcome of the setting's runs"))
    data["failure"] = (dims, failures.astype(str), {"long_name": "failure message"})
    ds = xr.Dataset(
        data,
        coords={
            "solver_method": (
                "solver_method",
                list(methods),
                {"long_name": "solver method", "units": "1"},
            ),
            "rtol": (
                "rtol",
                np.asarray(tolerances, float),
                {"long_name": "rtol = atol", "units": "1"},
            ),
        },
    )
    ds.attrs.update(provenance(scene, by="workbench.accuracy"))
    ds.attrs["statistic_noise_floor"] = 1.0 / math.sqrt(_strobe(ref_long).sizes["time"])
    ds.attrs.update(
        reference_method=ref_method,
        reference_tolerance=ref_tol,
        reference_wall_time=ref_long.attrs["solver_wall_time"],
        reference_steps=ref_long.attrs["solver_steps"],
        reference_twin_tolerance=twin_tol if twin is not None else math.nan,
        reference_error=ref_error,
        short_horizon=horizon,
    )
    return ds


@dataclass(frozen=True)
class Recommendation:
    """The setting :func:`recommend` picks: a value, not a study (the evidence is the study).

    Attributes
    ----------
    method : str
        Solver method.
    rtol : float
        rtol = atol of the setting.
    wall_time : float
        Solver wall time of the study's long run at this setting, s.
    errors : Mapping[str, float]
        The errors that decided (dimensionless; see :func:`accuracy`).
    target : float
        The target every one of them is below.

    The repr is one line that reads as the choice, e.g.
    ``Recommendation(method='dop853', rtol=1e-08, wall_time=0.0123 s, short_error=2.1e-09,
    peak_error=3.4e-10, target=1e-06)``.
    """

    method: str
    rtol: float
    wall_time: float
    errors: Mapping[str, float] = field(hash=False)
    target: float

    def __repr__(self) -> str:
        errors = ", ".join(f"{k}={v:.2g}" for k, v in self.errors.items())
        return (
            f"Recommendation(method={self.method!r}, rtol={self.rtol:g}, "
            f"wall_time={self.wall_time:.3g} s, {errors}, target={self.target:g})"
        )


def recommend(
    wp: xr.Dataset, target: float, *, errors: Sequence[str] = ("short_error", "peak_error")
) -> Recommendation:
    """The cheapest (method, tolerance) of a work-precision study whose errors are all below
    ``target``.

    By default the deterministic errors (a) and (b) decide; the long-run statistic and the event
    count of a chaotic run have a sampling-noise floor (about ``statistic_noise_floor`` in the
    study's attributes) that no tolerance removes.

    Parameters
    ----------
    wp : xarray.Dataset
        From :func:`accuracy`.
    target : float
        Largest acceptable error (dimensionless).
    errors : sequence of str
        The error variables that must all be below ``target``.

    Returns
    -------
    Recommendation
        A frozen dataclass rather than a Dataset: it is one choice read off the study, whose
        evidence (every error and cost) is ``wp`` itself.

    Raises
    ------
    ValueError
        If no setting meets the target, naming the best error reached.

    Examples
    --------
    >>> wp = accuracy({"model": {"name": "duffing"}, "run": {"cycles": 5}},
    ...               methods=["dop853"], tolerances=[1e-4, 1e-8])
    >>> r = recommend(wp, 1e-6)
    >>> r.method, r.rtol
    ('dop853', 1e-08)
    """
    worst = wp[list(errors)].to_array("error").max("error")
    ok = (worst < target) & (wp.status == 0)
    if not bool(ok.any()):
        best = float(worst.min())
        raise ValueError(
            f"no setting reaches errors below target={target!r}; the best is "
            f"{best:.3g}: loosen the target or add tighter tolerances"
        )
    cost = wp.wall_time.where(ok)
    idx = np.unravel_index(int(np.nanargmin(cost.values)), cost.shape)
    pick = wp.isel(solver_method=idx[0], rtol=idx[1])
    return Recommendation(
        method=str(pick.solver_method.values),
        rtol=float(pick.rtol),
        wall_time=float(pick.wall_time),
        errors=MappingProxyType({e: float(pick[e]) for e in errors}),
        target=float(target),
    )
