"""The largest Lyapunov exponent of one scene by every method the workbench has, side by side.

The chaos study of the paper (Sec. 5.1) reads chaos off Wolf exponents of the clearance
coordinates. A Wolf exponent of a sampled series depends on the sampling, and on a mechanism
whose impacts stretch nearby states within milliseconds a coarse series cannot resolve the
exponent at all; the variational equations with saltation at every contact event give the
exponent itself, and the two-trajectory method (Benettin et al. 1980) checks them independently
on the same trajectory. This module measures all of them on one scene, with the evidence that
says which to believe: the convergence flag and spread of the equations' estimates, the
reliability flag of every Wolf estimate, and the standard errors of the finite window.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import xarray as xr

from workbench import analysis
from workbench._attributes import named, variable
from workbench.run import simulate
from workbench.scene import Scene

__all__ = ["exponent_table", "reference_exponent"]

#: (samples per crank cycle, recorded cycles) of the series Wolf's method reads
WOLF_SAMPLING = ((100, 200), (1000, 40), (10000, 8))


def exponent_table(
    scene: Scene,
    *,
    cycles: int = 40,
    budget_cycles: int | None = None,
    spectrum_cycles: int | None = None,
    spectrum_exponents: int = 4,
    transient_cycles: int = 4,
    coordinate: tuple[str, dict] = ("clearance_x", {"joint": "A"}),
    wolf_sampling: tuple[tuple[int, int], ...] = WOLF_SAMPLING,
    strobe_cycles: int = 400,
) -> xr.Dataset:
    """The chaos case's largest Lyapunov exponent by every method, in 1/s and per crank cycle.

    Rows (dim ``method``):

    - ``two trajectories``: :func:`workbench.analysis.largest_exponent`'s full protocol by
      :func:`workbench.analysis.lle_from_equations` with the run at rtol/100 (four
      independent starts, realisations 0-3, sharing the length) from ``cycles`` cycles
      after ``transient_cycles``, grown to at most ``budget_cycles`` (default twice
      ``cycles``) until its standard error is 3 % of it (trusted: converged, i.e. that error
      target met, five separation and renormalisation variants within 5 % and two standard
      errors, runs at rtol/100 and the variational exponent within two standard errors);
    - ``variational, same trajectory``: the variational equations with saltation carried by
      those runs' fiducial trajectories (the reference: trusted where the two-trajectory
      estimate converged), with its own pooled standard error;
    - ``variational spectrum``: the ``spectrum_exponents`` largest exponents by
      :func:`workbench.analysis.lyapunov_spectrum` from ``spectrum_cycles`` (default
      ``cycles``; its own run: every exponent needs its own tangent vector), each with its
      standard error and trust (converged, agrees at rtol/100, error at most 20 %);
    - ``Wolf, N per cycle``: :func:`workbench.analysis.wolf_lle` of ``coordinate`` recorded at
      N samples per crank cycle (reliable: its own flag);
    - ``Wolf, stroboscopic map``: the same on one sample per cycle over ``strobe_cycles``.

    Returns
    -------
    xarray.Dataset
        ``lle`` (s-1), ``lle_per_cycle`` (1), ``stderr`` (s-1, NaN where not estimated),
        ``trusted`` (converged or reliable), ``note``, ``wall_time`` (s); the largest exponents
        ``spectrum`` (s-1) over ``index`` with ``spectrum_stderr`` and ``spectrum_trusted``, and
        the spectrum's sum check (attributes ``spectrum_sum``, ``volume_rate``,
        ``sum_check``).
    """
    period = 2 * math.pi / float(scene.resolved_parameters["omega"])
    run = {"cycles": cycles, "transient_cycles": transient_cycles}
    window = scene.replace(run=run, sweep={})
    rows: list[dict] = []

    budget = 2 * cycles if budget_cycles is None else budget_cycles
    with warnings.catch_warnings():  # said in the rows' notes
        warnings.simplefilter("ignore", analysis.ConvergenceWarning)
        result, wall = _timed(
            analysis.largest_exponent, window, cycles=cycles, method="copies", budget=budget,
            tolerance_check=True,
        )  # fmt: skip
    if result.failed:
        raise RuntimeError(f"the two-trajectory estimate failed: {result.detail}")
    bench = result.estimate  # the estimator's dataset: the numbers the notes quote
    used = bench.attrs["cycles"]
    starts = f"{bench.attrs['starts']} starts x {bench.attrs['cycles_per_start']:g} cycles"
    failed = _failed(bench.attrs["failed"])
    rows.append(
        _row(
            "two trajectories",
            result.value,
            result.error,
            bool(bench.converged),
            f"{used:g} cycles ({starts}; error the larger of the starts' spread, "
            f"{float(bench.stderr_starts):.2g}, and their batch means, "
            f"{float(bench.stderr_batches):.2g}); five variants within "
            f"{100 * float(bench.spread):.2g} %; separation {float(bench.separation[0]):.2g} "
            f"of each state's size; rtol {float(bench.attempt_rtol[-1]):g}; at rtol/100: "
            f"{float(bench.lle_tight):.4g} +/- {float(bench.stderr_tight):.2g} 1/s{failed}",
            wall,
        )
    )
    rows.append(
        _row(
            "variational, same trajectory",
            float(bench.lle_variational),
            float(bench.stderr_variational),
            bool(bench.converged),
            f"{used:g} cycles ({starts}); the two-trajectory estimate minus it: "
            f"{float(bench.difference):+.3g} +/- {float(bench.stderr_difference):.2g} 1/s",
            0.0,
        )
    )
    n_spectrum = cycles if spectrum_cycles is None else spectrum_cycles
    short = scene.replace(run={**run, "cycles": n_spectrum}, sweep={})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", analysis.ConvergenceWarning)
        spectrum, wall = _timed(
            analysis.lyapunov_spectrum, short, exponents=spectrum_exponents,
            budget=2 * n_spectrum if budget_cycles is None else budget_cycles,
        )  # fmt: skip
    rows.append(
        _row(
            "variational spectrum",
            float(spectrum.exponent[0]),
            float(spectrum.stderr[0]),
            bool(spectrum.trusted[0]),
            f"own run over {spectrum.attrs['cycles']:g} cycles; at rtol/100: "
            f"{float(spectrum.exponent_tight[0]):.4g} 1/s; sum check "
            f"{float(spectrum.sum_check):.1g}{_failed(spectrum.attrs['failed'])}",
            wall,
        )
    )
    var, where = coordinate
    for spp, n in wolf_sampling:
        rows.append(_wolf_row(scene, var, where, spp, n, transient_cycles, f"{spp} per cycle"))
    rows.append(
        _wolf_row(scene, var, where, 1, strobe_cycles, transient_cycles, "stroboscopic map")
    )
    lle = np.array([r["lle"] for r in rows])
    return xr.Dataset(
        {
            "lle": ("method", lle, variable("largest Lyapunov exponent", "s-1")),
            "lle_per_cycle": (
                "method",
                lle * period,
                variable("largest Lyapunov exponent per crank cycle"),
            ),
            "stderr": (
                "method",
                [r["stderr"] for r in rows],
                variable("standard error of the finite window", "s-1"),
            ),
            "trusted": (
                "method",
                [r["trusted"] for r in rows],
                variable("converged (equations) or reliable (Wolf)"),
            ),
            "note": ("method", [r["note"] for r in rows], named("evidence")),
            "wall_time": (
                "method",
                [r["wall_time"] for r in rows],
                variable("wall time of the estimate", "s"),
            ),
            "spectrum": (
                "index",
                spectrum.exponent.values,
                variable("largest Lyapunov exponents (variational equations)", "s-1"),
            ),
            "spectrum_stderr": (
                "index",
                spectrum.stderr.values,
                variable("their standard errors (batch means)", "s-1"),
            ),
            "spectrum_trusted": (
                "index",
                spectrum.trusted.values,
                variable("converged, agrees at rtol/100, standard error <= 20 %"),
            ),
        },
        coords={
            "method": ("method", [r["method"] for r in rows]),
            "index": ("index", spectrum.index.values, variable("exponent index")),
        },
        attrs={
            "forcing_period": period,
            "cycles": cycles,
            "transient_cycles": transient_cycles,
            "coordinate": f"{var} at {where}",
            "spectrum_cycles": float(spectrum.attrs["cycles"]),
            "spectrum_sum": float(spectrum.spectrum_sum),
            "volume_rate": float(spectrum.volume_rate),
            "sum_check": float(spectrum.sum_check),
        },
    )


def _timed(f, *args, **kwargs):
    import time

    t0 = time.perf_counter()
    out = f(*args, **kwargs)
    return out, time.perf_counter() - t0


def _failed(text: str) -> str:
    """The failed convergence conditions of an estimate, for its note ('' if none)."""
    return "; not converged: " + " / ".join(text.splitlines()) if text else ""


def _row(method, lle, stderr, trusted, note, wall) -> dict:
    return {"method": method, "lle": lle, "stderr": stderr, "trusted": trusted, "note": note,
            "wall_time": wall}  # fmt: skip


def _wolf_row(scene, var, where, spp, cycles, transient, label) -> dict:
    """Wolf's estimate of ``var`` (at ``where``) recorded at ``spp`` samples per cycle."""
    s = scene.replace(
        run={"cycles": cycles, "transient_cycles": transient},
        record={"samples_per_period": spp, "variables": [var]},
        sweep={},
    )
    ds = simulate(s)
    if spp == 1:  # a stroboscopic section: a map, one iteration per crank cycle
        x = analysis.poincare_section(ds, var)[var].sel(where)
    else:
        x = ds[var].sel(where)
    r, wall = _timed(analysis.wolf_lle, x, period=ds.attrs["forcing_period"])
    reliable = bool(r.reliable)
    note = "reliable" if reliable else str(r.reliable.attrs.get("message", "flagged"))
    return _row(f"Wolf, {label}", float(r.lle), math.nan, reliable, note, wall)


def reference_exponent(exponents: dict) -> dict | None:
    """The row of a measured exponent table (:func:`exponent_table` as a dict of lists) the
    chaos verdict rests on: the two-trajectory estimate, with ``lle`` (s-1), ``stderr`` (s-1),
    ``trusted`` (converged) and ``lle_per_cycle``; None if there is none."""
    if not exponents or "two trajectories" not in exponents.get("method", []):
        return None
    i = exponents["method"].index("two trajectories")
    return {k: exponents[k][i] for k in ("lle", "lle_per_cycle", "stderr", "trusted", "note")}
