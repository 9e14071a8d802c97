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

import numpy as np
import xarray as xr

from workbench import analysis
from workbench.run import simulate
from workbench.scene import Scene

__all__ = ["exponent_table", "reference_exponent"]

#: (samples per crank cycle, recorded cycles) of the series Wolf's method reads
WOLF_SAMPLING = ((100, 200), (1000, 40), (10000, 8))


def exponent_table(
    scene: Scene,
    *,
    cycles: int = 6,
    spectrum_cycles: int = 2,
    spectrum_exponents: int = 4,
    transient_cycles: int = 4,
    coordinate: tuple[str, dict] = ("clearance_x", {"joint": "A"}),
    wolf_sampling: tuple[tuple[int, int], ...] = WOLF_SAMPLING,
    strobe_cycles: int = 400,
) -> xr.Dataset:
    """The chaos case's largest Lyapunov exponent by every method, in 1/s and per crank cycle.

    Rows (dim ``method``):

    - ``two trajectories``: :func:`workbench.analysis.lle_from_equations` with its defaults
      over ``cycles`` cycles after ``transient_cycles`` (converged: five separation and
      renormalisation variants within 5 %);
    - ``variational, same trajectory``: the variational equations with saltation carried by
      that run's fiducial trajectory;
    - ``variational spectrum``: the ``spectrum_exponents`` largest exponents by
      :func:`workbench.analysis.lyapunov_spectrum` over ``spectrum_cycles`` (its own run:
      every exponent needs its own tangent vector; converged: agrees with a 10x tighter
      tolerance within 5 % or two standard errors);
    - ``Wolf, N per cycle``: :func:`workbench.analysis.wolf_lle` of ``coordinate`` recorded at
      N samples per crank cycle (reliable: its own flag);
    - ``Wolf, stroboscopic map``: the same on one sample per cycle over ``strobe_cycles``.

    Returns
    -------
    xarray.Dataset
        ``lle`` (s-1), ``lle_per_cycle`` (1), ``stderr`` (s-1, NaN where not estimated),
        ``trusted`` (converged or reliable), ``note``, ``wall_time`` (s); the full
        ``spectrum`` (s-1) over ``index``.
    """
    period = 2 * math.pi / float(scene.resolved_parameters["omega"])
    run = {"cycles": cycles, "transient_cycles": transient_cycles}
    window = scene.replace(run=run, sweep={})
    rows: list[dict] = []

    bench, wall = _timed(analysis.lle_from_equations, window)
    rows.append(
        _row(
            "two trajectories",
            float(bench.lle),
            float(bench.stderr),
            bool(bench.converged),
            f"five variants within {100 * float(bench.spread):.2g} %; separation "
            f"{float(bench.separation[0]):.2g} of each state's size; rtol "
            f"{float(bench.attempt_rtol[-1]):g}",
            wall,
        )
    )
    rows.append(
        _row(
            "variational, same trajectory",
            float(bench.lle_variational),
            float(bench.stderr),
            float(bench.method_difference) < 0.05,
            f"differs from the two-trajectory estimate by "
            f"{100 * float(bench.method_difference):.2g} %",
            0.0,
        )
    )
    short = scene.replace(run={**run, "cycles": min(spectrum_cycles, cycles)}, sweep={})
    spectrum, wall = _timed(analysis.lyapunov_spectrum, short, exponents=spectrum_exponents)
    rows.append(
        _row(
            "variational spectrum",
            float(spectrum.exponent[0]),
            float(spectrum.stderr[0]),
            bool(spectrum.converged[0]),
            f"own run over {min(spectrum_cycles, cycles)} cycles; at rtol/10: "
            f"{float(spectrum.exponent_tight[0]):.3g} 1/s",
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
            "lle": ("method", lle, {"units": "s-1", "long_name": "largest Lyapunov exponent"}),
            "lle_per_cycle": (
                "method",
                lle * period,
                {"units": "1", "long_name": "largest Lyapunov exponent per crank cycle"},
            ),
            "stderr": (
                "method",
                [r["stderr"] for r in rows],
                {"units": "s-1", "long_name": "standard error of the finite window"},
            ),
            "trusted": (
                "method",
                [r["trusted"] for r in rows],
                {"long_name": "converged (equations) or reliable (Wolf)"},
            ),
            "note": ("method", [r["note"] for r in rows], {"long_name": "evidence"}),
            "wall_time": (
                "method",
                [r["wall_time"] for r in rows],
                {"units": "s", "long_name": "wall time of the estimate"},
            ),
            "spectrum": (
                "index",
                spectrum.exponent.values,
                {"units": "s-1", "long_name": "largest Lyapunov exponents (variational equations)"},
            ),
        },
        coords={
            "method": ("method", [r["method"] for r in rows]),
            "index": ("index", spectrum.index.values, {"long_name": "exponent index"}),
        },
        attrs={
            "forcing_period": period,
            "cycles": cycles,
            "transient_cycles": transient_cycles,
            "coordinate": f"{var} at {where}",
            "spectrum_sum": float(spectrum.spectrum_sum),
            "divergence": float(spectrum.divergence),
        },
    )


def _timed(f, *args, **kwargs):
    import time

    t0 = time.perf_counter()
    out = f(*args, **kwargs)
    return out, time.perf_counter() - t0


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
