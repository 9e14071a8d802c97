"""What accuracy costs in time: work-precision studies of a scene.

Impact dynamics are chaotic, so two correct runs diverge after a few impacts; accuracy is judged
on quantities that stay meaningful (Hairer, Nørsett & Wanner 1993, Sec. II.10, for
work-precision diagrams; for non-smooth systems e.g. Acary & Brogliato 2008, Ch. 1):

(a) ``short_error``: the largest difference from the reference over a short horizon before
    chaotic divergence, relative to the reference's range. The horizon is half the time after
    which the reference and a run 100x looser than it separate by 1 % of a variable's range
    (at most the first forcing period from t0): for an impacting mechanism whose nearby
    trajectories separate at tens of 1/s or more (the nine-bar's chaos case: docs/analysis.md),
    a whole crank cycle would measure chaos, not accuracy. It is cut further where the
    reference itself stops being exact: where it and a twin run 10x tighter separate by
    REFERENCE_FLOOR (1e-6) of a range (impacts amplify the reference's own error too, which
    would make small errors a matter of luck; docs/accuracy.md). The largest twin separation
    over the horizon is stored as ``reference_error``;
(b) ``peak_error``: the relative error of the peak of each variable over that horizon (e.g.
    the peak force of the first impacts), and ``events_error``: the relative error of the
    number of events (e.g. contact onsets and ends) per forcing period over the whole run;
(c) ``statistic_error``: the error of the mean and of the standard deviation of the stroboscopic
    samples of the whole run, relative to the reference's standard deviation.

The reference is DOP853 at 100x below the tightest tolerance studied (stated in the result);
its own error is the separation from a twin 10x tighter still (``reference_error``), and every
error within 3x of it is flagged ``at_reference_limit``: :func:`recommend` does not use it.
"""

from __future__ import annotations

import math
import os
import time as _time
import warnings
from collections import Counter
from collections.abc import Callable, Sequence
from functools import partial

import numpy as np
import xarray as xr

from workbench._attributes import named, variable
from workbench._progress import TimeLeft
from workbench.precision._measures import (
    ERRORS,
    LIMIT_BITS,
    LIMIT_FACTOR,
    measure,
    records_within,
    reference_limited,
    short_horizon,
    strobe,
)
from workbench.precision._store import study_store
from workbench.run import (
    provenance,
    run_status,
    separation,
    short_scene,
    simulate,
    status_attrs,
    with_solver,
)
from workbench.scene import SceneSource, load_scene
from workbench.solver import Status

__all__ = ["DEFAULT_METHODS", "DEFAULT_TOLERANCES", "REFERENCE_MIN_TOL", "accuracy"]

DEFAULT_METHODS = ("dop853", "dopri5", "scipy:DOP853", "scipy:Radau", "scipy:LSODA")
DEFAULT_TOLERANCES = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11)
_COSTS = ("wall_time", "steps", "rhs_evaluations")  # of the long run; solver_<name> attributes
RTOL_MIN = 1e-14  # the smallest rtol a scene accepts (solver.rtol)
# The tightest default reference: its twin (10x tighter) is then still at RTOL_MIN.
REFERENCE_MIN_TOL = 1e-13


def _check_settings(
    methods: Sequence[str], tolerances: Sequence[float]
) -> tuple[list[str], list[float]]:
    """The settings as lists, refused before any run if malformed (naming the argument)."""
    if isinstance(methods, str) or not len(methods):
        raise ValueError(f"methods must be a non-empty sequence of method names, got {methods!r}")
    tolerances = [float(t) for t in tolerances]
    if not tolerances or any(not (RTOL_MIN <= t < 1) for t in tolerances):
        raise ValueError(
            f"tolerances must be a non-empty sequence of numbers in [{RTOL_MIN:g}, 1), got "
            f"{tolerances!r}"
        )
    if len(set(tolerances)) != len(tolerances) or len(set(methods)) != len(methods):
        raise ValueError(
            f"methods and tolerances must not repeat a value, got {list(methods)!r} and "
            f"{tolerances!r}"
        )
    return list(methods), tolerances


def _quiet(run: Callable[[], xr.Dataset], log: list[str]) -> xr.Dataset:
    """``run()`` with the warnings it raises (e.g. scipy's overflows) appended to ``log``
    instead of printed."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ds = run()
    log.extend(f"{w.category.__name__}: {w.message}" for w in caught)
    return ds


def _summarise(log: list[str]) -> str:
    """Distinct messages with their counts, in order of first appearance."""
    counts = Counter(log)
    return "; ".join(f"{m} (x{n})" if n > 1 else m for m, n in counts.items())


# What a setting's runs cost, relative to one another, for the progress' time left: per method
# (scipy's by their solve_ivp name) the order q of the error estimate that sets its steps and
# its right-hand-side evaluations at rtol 1e-6 relative to DOP853's. Evaluation ratios: a
# Duffing study (studies/duffing.toml, rtol 1e-3..1e-11: Radau 3.0x, LSODA 0.7x DOP853's) and
# the nine-bar with Coulomb friction (benchmarks/RESULTS.md: Radau 1.4x, BDF 0.7x).
_STEP_COST = {
    "dop853": (7, 1.0),
    "auto": (7, 1.0),
    "dopri5": (4, 1.0),
    "ark548": (4, 1.0),
    "radau": (3, 2.0),
    "DOP853": (7, 1.0),
    "RK45": (4, 1.0),
    "RK23": (2, 2.0),
    "Radau": (3, 2.0),
    "BDF": (4, 0.7),
    "LSODA": (10, 0.7),  # variable order (Adams up to 12): its steps grow as rtol^(-0.09)
}
# An evaluation through scipy's Python against one inside the compiled loop: ~10-40 us against
# 0.1-0.5 us (the same Duffing study; benchmarks/RESULTS.md on the nine-bar); twice for scipy's
# implicit codes, which factor and solve in Python at every step.
_SCIPY_EVALUATION = {"Radau": 100.0, "BDF": 100.0}
_SCIPY_EVALUATION_EXPLICIT = 50.0


def expected_cost(method: str, rtol: float) -> float:
    """The expected cost of a setting's runs relative to the others' (dimensionless), which
    weights the study's estimate of its time left (:class:`workbench._progress.TimeLeft`).

    A method of error order q takes steps ~ rtol^(-1/(q+1)) (its step-size control: the local
    error ~ h^(q+1) held at rtol); times its right-hand-side evaluations per step, relative to
    DOP853's (at rtol 1e-6), times the cost of one evaluation: 1 in the compiled loop, 50-100
    through scipy's Python. So a scipy:Radau setting at rtol 1e-11 weighs ~8000 times a compiled
    DOP853 one at 1e-3, a scipy:DOP853 one at 1e-3 50 times. The measured rate of each method
    corrects these weights once one of its settings has run; an unknown method weighs as
    DOP853."""
    backend, _, name = method.rpartition(":")
    order, evaluations = _STEP_COST.get(name, (7, 1.0))
    per_evaluation = (
        _SCIPY_EVALUATION.get(name, _SCIPY_EVALUATION_EXPLICIT) if backend == "scipy" else 1.0
    )
    return evaluations * per_evaluation * (rtol / 1e-6) ** (-1.0 / (order + 1))


def _bar(total: int, initial: int, enabled: bool, time_left=None):
    """A progress bar over runs with an ETA (stderr) weighted by ``time_left``, or None."""
    if not enabled:
        return None
    from workbench._progress import Progress

    return Progress(total, initial=initial, unit="run", desc="accuracy", time_left=time_left)


def accuracy(
    scene: SceneSource,
    *,
    methods: Sequence[str] = DEFAULT_METHODS,
    tolerances: Sequence[float] = DEFAULT_TOLERANCES,
    reference: tuple[str, float] | None = None,
    horizon: float | None = None,
    progress: bool = False,
    store: str | os.PathLike | None = None,
    restart: bool = False,
) -> xr.Dataset:
    """Work-precision study: run a scene with every method at every tolerance.

    Parameters
    ----------
    scene : Scene, path or mapping
        The scene studied (its sweep, if any, is dropped).
    methods : sequence of str
        Solver methods (``"dop853"``, ``"dopri5"``, ``"ark548"``, ``"scipy:<name>"``).
    tolerances : sequence of float
        rtol = atol values in [1e-14, 1) (atol is scaled per state by the model; see the model
        docs).
    reference : (method, tolerance), optional
        The reference run; default ``("dop853", min(tolerances) / 100)``, at least
        :data:`REFERENCE_MIN_TOL` (then less than 100x tighter than the tightest tolerances:
        a warning, and their errors are flagged as below). Its own error is measured against a
        twin 10x tighter.
    horizon : float, optional
        Horizon (s) of the short-horizon error; default: chosen from the separation of the
        reference and a run 100x looser, and of the reference and a twin 10x tighter (see the
        module docstring), stored as ``short_horizon``.
    progress : bool
        A progress bar over the runs with an ETA (stderr) and one line per setting.
    store : str or PathLike, optional
        Keep every finished run in this directory (created; e.g. ``"wp.nc.runs"``), so that an
        interrupted study resumes where it stopped (see :mod:`workbench.precision._store`); one
        process writes it at a time (a lock). Default: nothing kept.
    restart : bool
        Discard what ``store`` holds first. Without it a store of another scene, reference or
        horizon is refused with the differences named.

    Returns
    -------
    xarray.Dataset
        Dims ``solver_method`` (not ``method``, a keyword of ``Dataset.sel``) and
        ``rtol`` (= atol; not ``tolerance``, a keyword of ``Dataset.sel`` too); variables
        ``wall_time`` (s, long run), ``steps``, ``rhs_evaluations``,
        the errors (dimensionless, see the module docstring), ``at_reference_limit`` (int8 CF
        flag masks: 1 the short-horizon error, 2 the peak error is within
        :data:`LIMIT_FACTOR` (3) times the reference's own error, so it measures the reference
        rather than the setting; where the reference's error is unknown, every setting less
        than 100x looser than the reference), ``status`` (int8 flags of
        :class:`workbench.Status`: the first failed run's, 0 if both ran), ``failure`` (its
        message) and ``solver_warnings`` (the warnings the setting's runs raised, with counts;
        they are not printed); the reference in the attributes, with ``reference_error``: its
        separation from the twin over the horizon (NaN without a twin).

    Raises
    ------
    ValueError
        Malformed ``methods`` or ``tolerances`` (before any run).
    workbench.SceneError
        A method the scene's solver table refuses (before any run).

    Warns
    -----
    UserWarning
        The reference is less than 100x tighter than the tightest tolerance.

    Examples
    --------
    >>> wp = accuracy({"model": {"name": "duffing"}, "run": {"cycles": 5}},
    ...               methods=["dop853"], tolerances=[1e-4, 1e-8])
    >>> bool(wp.short_error.sel(rtol=1e-8) < wp.short_error.sel(rtol=1e-4))
    True
    >>> wp.attrs["reference_tolerance"]
    1e-10
    """
    scene = load_scene(scene)
    methods, tolerances = _check_settings(methods, tolerances)
    ref_method, ref_tol = reference or ("dop853", max(min(tolerances) / 100, REFERENCE_MIN_TOL))
    ref_tol = float(ref_tol)
    for m in dict.fromkeys([*methods, ref_method]):  # every method valid before any run
        with_solver(scene, m, ref_tol)
    if min(tolerances) < 100 * ref_tol:
        warnings.warn(
            f"the reference ({ref_method} at {ref_tol:g}) is less than 100x tighter than the "
            f"tightest tolerance studied ({min(tolerances):g}); errors within {LIMIT_FACTOR:g}x "
            "of the reference's own error are flagged in 'at_reference_limit'",
            stacklevel=2,
        )
    twin_tol = ref_tol / 10 if ref_tol / 10 >= RTOL_MIN else None
    identity = {
        "scene": scene.replace(sweep={}).to_dict(),
        "reference": [ref_method, ref_tol],
        "horizon": horizon,
    }
    with study_store(store, identity, restart=restart) as runs:
        study = _Study(scene, ref_method, ref_tol, twin_tol, runs)
        names = study.run_names(methods, tolerances, horizon is None)
        stored = sum(runs.committed(n) for n in names)
        costs = {
            _Study.setting_name(m, t): (m, expected_cost(m, t)) for m in methods for t in tolerances
        }
        left = TimeLeft({k: v for k, v in costs.items() if not runs.committed(f"{k}.json")})
        bar = _bar(len(names), stored, progress, left)
        try:
            ds = study.run(methods, tolerances, horizon, bar)
        finally:
            if bar is not None:
                bar.close()
        runs.discard()
    ds.attrs.update(provenance(scene, by="workbench.accuracy"))
    return ds


class _Study:
    """The runs and measures of :func:`accuracy`, each kept in (and resumed from) a store."""

    def __init__(self, scene, ref_method: str, ref_tol: float, twin_tol, runs) -> None:
        self.scene, self.runs = scene, runs
        self.ref_method, self.ref_tol, self.twin_tol = ref_method, ref_tol, twin_tol
        self.log: list[str] = []  # the reference runs' warnings
        self.bar = None

    @staticmethod
    def setting_name(method: str, tol: float) -> str:
        return f"setting-{method.replace(':', '_')}-{tol:.6e}"

    def run_names(self, methods, tolerances, probe: bool) -> list[str]:
        """The store names of every run, each setting counted twice (its short and long run)."""
        names = ["reference-short.nc", "reference-long.nc"]
        names += ["twin.nc"] if self.twin_tol is not None else []
        names += ["probe.nc"] if probe else []
        settings = [f"{self.setting_name(m, t)}.json" for m in methods for t in tolerances]
        return names + [n for n in settings for _ in range(2)]

    def _step(self, n: int, job: str | None = None) -> None:
        if self.bar is not None:
            self.bar.update(n, job=job)

    def _reference(self, name: str, rtol: float, short: bool = True) -> xr.Dataset:
        make = short_scene if short else with_solver
        ds, reused = self.runs.dataset(
            name,
            lambda: _quiet(lambda: simulate(make(self.scene, self.ref_method, rtol)), self.log),
        )
        self._step(0 if reused else 1)
        return ds

    def run(self, methods, tolerances, horizon: float | None, bar) -> xr.Dataset:
        self.bar = bar
        ref_short = self._reference("reference-short", self.ref_tol)
        ref_long = self._reference("reference-long", self.ref_tol, short=False)
        twin = None if self.twin_tol is None else self._reference("twin", self.twin_tol)
        if horizon is None:
            probe = self._reference("probe", self.ref_tol * 100)
            horizon = short_horizon(ref_short, probe, twin)
        ref_error = math.nan
        if twin is not None:
            n = records_within(ref_short, horizon)
            ref_error = float(
                np.max(separation(twin.isel(time=slice(0, n)), ref_short.isel(time=slice(0, n))))
            )
        period = ref_long.attrs.get("forcing_period")
        total = float(ref_long.time[-1])
        self.periods = total / period if period else total
        self.horizon, self.ref_short, self.ref_long = horizon, ref_short, ref_long

        shape = (len(methods), len(tolerances))
        out = {k: np.full(shape, np.nan) for k in (*_COSTS, *ERRORS)}
        status = np.zeros(shape, np.int8)
        failures = np.full(shape, "", dtype=object)
        solver_warnings = np.full(shape, "", dtype=object)
        for i, method in enumerate(methods):
            for j, tol in enumerate(tolerances):
                t0 = _time.perf_counter()
                name = self.setting_name(method, tol)
                rec, reused = self.runs.record(name, partial(self.measure, method, tol))
                self._step(0 if reused else 2, name)
                status[i, j], failures[i, j] = rec["status"], rec["failure"]
                solver_warnings[i, j] = rec["warnings"]
                for k in out:
                    out[k][i, j] = rec.get(k, np.nan)
                if bar is not None:
                    what = (
                        f"failed: {Status(rec['status']).label}"
                        if rec["status"]
                        else f"short error {rec['short_error']:.2e}"
                    )
                    cost = "stored" if reused else f"{_time.perf_counter() - t0:.1f} s"
                    bar.write(f"{method:14s} rtol {tol:7.0e}: {what} ({cost})")
        limited = reference_limited(out, tolerances, self.ref_tol, ref_error)
        ds = _dataset(methods, tolerances, out, status, failures, solver_warnings, limited)
        return ds.assign_attrs(
            statistic_noise_floor=1.0 / math.sqrt(strobe(ref_long).sizes["time"]),
            reference_method=self.ref_method,
            reference_tolerance=self.ref_tol,
            reference_wall_time=ref_long.attrs["solver_wall_time"],
            reference_steps=ref_long.attrs["solver_steps"],
            reference_twin_tolerance=math.nan if twin is None else self.twin_tol,
            reference_error=ref_error,
            reference_warnings=_summarise(self.log),
            reference_limit_factor=LIMIT_FACTOR,
            short_horizon=horizon,
        )

    def measure(self, method: str, tol: float) -> dict:
        """One setting's record (JSON-ready): status, failure, warnings, costs, errors."""
        own: list[str] = []
        scene = self.scene
        short = _quiet(lambda: simulate(short_scene(scene, method, tol), throw=False), own)
        if run_status(short).failed:
            long = short  # the long run would fail as well: not worth its time
        else:
            long = _quiet(lambda: simulate(with_solver(scene, method, tol), throw=False), own)
        rec = {"status": 0, "failure": "", "warnings": _summarise(own)}
        failed = next((r for r in (short, long) if run_status(r).failed), None)
        if failed is not None:
            return rec | {"status": int(run_status(failed)), "failure": failed.attrs["run_message"]}
        rec |= {k: float(long.attrs[f"solver_{k}"]) for k in _COSTS}
        errors = measure(short, long, self.ref_short, self.ref_long, self.periods, self.horizon)
        return rec | {k: float(v) for k, v in errors.items()}


def _dataset(methods, tolerances, out, status, failures, solver_warnings, limited) -> xr.Dataset:
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
    data = {k: (dims, v, variable(long_names[k], units.get(k, "1"))) for k, v in out.items()}
    data["at_reference_limit"] = (
        dims,
        limited,
        variable(
            "errors that lie at the reference's own limit (not resolved)",
            flag_masks=np.array(list(LIMIT_BITS.values()), np.int8),
            flag_meanings=" ".join(f"{k}_at_reference_limit" for k in LIMIT_BITS),
            comment=f"set where the error is within {LIMIT_FACTOR:g}x the reference's own "
            "error (reference_error); recommend() does not use such errors",
        ),
    )
    data["status"] = (dims, status, status_attrs("outcome of the setting's runs"))
    data["failure"] = (dims, failures.astype(str), named("failure message"))
    data["solver_warnings"] = (
        dims,
        solver_warnings.astype(str),
        variable("warnings raised by the setting's runs (with counts)"),
    )
    return xr.Dataset(
        data,
        coords={
            "solver_method": (
                "solver_method",
                list(methods),
                variable("solver method"),
            ),
            "rtol": (
                "rtol",
                np.asarray(tolerances, float),
                variable("rtol = atol"),
            ),
        },
    )
