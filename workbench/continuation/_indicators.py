"""Chaos indicators of one run, computed in a campaign's worker, and the campaign that maps them
over parameters.

Per point: the **period of the strobe** (the least k with x(t + kT) = x(t) over the recorded
strobe samples, 0 when none up to :data:`MAX_PERIOD`: quasi-periodic or chaotic), the **0-1
test's K** (Gottwald & Melbourne 2004, 2009) on the strobe samples of every recorded variable,
and the **largest Lyapunov exponent** with its batch-means standard error, measured over
:func:`lle_cycles` forcing periods after the scene's transient: from the variational equations
with saltation (:func:`workbench.analysis.lyapunov_spectrum`) for a model with an analytic
Jacobian, else by the linearised two-trajectory method (:func:`workbench.analysis.
lle_from_equations`: copies in one step sequence, renormalised before they leave the linear
range), because the tangent system of a mechanism carries central differences of the rhs along
its column and took 50x the bare model's steps on a nine-bar orbit in lasting contact
(:mod:`workbench.continuation._strobe`). A failure of the exponent's run is recorded
(``lle_status``), not raised, so one hard point does not stop a map.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from workbench.analysis import (
    lle_from_equations,
    lyapunov_spectrum,
    poincare_section,
    zero_one_test,
)
from workbench.campaign import run_campaign
from workbench.run import prepare
from workbench.scene import Scene, SceneSource, load_scene
from workbench.solver import SolverError, jacobian_for

__all__ = [
    "MAX_PERIOD",
    "chaos_indicators",
    "chaos_map",
    "exponent_method",
    "lle_cycles",
    "strobe_period",
    "strobe_zero_one",
]

#: the longest strobe period looked for (forcing periods)
MAX_PERIOD = 16
#: two strobe samples are the same point when they differ by less than this fraction of the
#: largest magnitude of their variable
PERIOD_TOLERANCE = 1e-4
LLE_STATUS = {
    "long_name": "outcome of the exponent's tangent run",
    "units": "1",
    "flag_values": np.array([0, 1], np.int8),
    "flag_meanings": "ok failed",
}


def strobe_period(samples: np.ndarray, tolerance: float = PERIOD_TOLERANCE) -> int:
    """The least k (1 .. :data:`MAX_PERIOD`) such that every strobe sample of the second half
    of the series equals the one k periods later (rows: samples, columns: variables; equal
    within ``tolerance`` times each column's largest magnitude), or 0 when there is none
    (quasi-periodic or chaotic motion, or too few samples: at least 2 k + 1 are needed). The
    first half is left to what remains of a transient (a continued point settles for only a
    few cycles before its records)."""
    x = np.asarray(samples, dtype=float)
    x = x.reshape(x.shape[0], -1)
    x = x[np.isfinite(x).all(axis=1)]
    x = x[x.shape[0] // 2 :]
    size = np.max(np.abs(x), axis=0) if x.size else np.zeros(0)
    tol = tolerance * np.where(size > 0, size, 1.0)
    for k in range(1, MAX_PERIOD + 1):
        if x.shape[0] < 2 * k + 1:
            break
        if np.all(np.abs(x[k:] - x[:-k]) <= tol):
            return k
    return 0


METHODS = {
    "variational": "variational equations with saltation, QR (workbench.analysis."
    "lyapunov_spectrum)",
    "copies": "linearised two-trajectory method, copies in one step sequence (workbench."
    "analysis.lle_from_equations)",
}


def exponent_method(scene: Scene) -> str:
    """``"variational"`` for a model with an analytic Jacobian, else ``"copies"``."""
    hooks = prepare(scene.replace(sweep={}) if scene.sweep else scene, variables=()).problem.hooks
    return "variational" if jacobian_for(hooks).HAS_ANALYTIC else "copies"


def lle_cycles(scene: Scene) -> int:
    """Forcing periods over which a map point's exponent is measured: a fifth of the recorded
    cycles, at least 10 (the exponent's batch-means error needs ten batches)."""
    return max(10, scene.run["cycles"] // 5)


def chaos_indicators(scene: Scene, run: xr.Dataset) -> xr.Dataset:
    """The chaos indicators of one point (a campaign's ``per_point``): ``strobe_period``,
    ``zero_one_K`` (median over the recorded variables' components) and ``zero_one_K_<var>``
    (per variable, over its model dims), ``lle`` and ``lle_stderr`` (s-1), ``lle_per_period``
    (1) and ``lle_status``.

    Parameters
    ----------
    scene : Scene
        The point's single-run scene (forced, recorded per period).
    run : xarray.Dataset
        Its run (:func:`workbench.simulate`).
    """
    section = poincare_section(run)
    out: dict = {}
    columns, ks = [], []
    for name in scene.variables:
        da = section[name].transpose("strobe", ...)
        values = da.values.reshape(da.sizes["strobe"], -1)
        columns.append(values)
        per = []
        for j in range(values.shape[1]):
            per.append(strobe_zero_one(values[:, j]))
        ks += per
        extra = [d for d in da.dims if d != "strobe"]
        shape = tuple(da.sizes[d] for d in extra)
        out[f"zero_one_K_{name}"] = (
            tuple(extra),
            np.array(per).reshape(shape),
            {"long_name": f"0-1 test K of the strobe samples of {name}", "units": "1"},
        )
    period = strobe_period(np.concatenate(columns, axis=1))
    out["strobe_period"] = (
        (),
        np.int16(period),
        {
            "long_name": "period of the strobe samples in forcing periods (0: none up to "
            f"{MAX_PERIOD}: quasi-periodic or chaotic)",
            "units": "1",
        },
    )
    out["zero_one_K"] = (
        (),
        float(np.nanmedian(ks)) if np.isfinite(ks).any() else np.nan,
        {"long_name": "0-1 test K, median over the recorded variables", "units": "1"},
    )
    lam, err, status = np.nan, np.nan, 0
    method = exponent_method(scene)
    try:
        if method == "variational":
            spec = lyapunov_spectrum(scene, exponents=1, cycles=lle_cycles(scene), check=False)
            lam, err = float(spec.exponent[0]), float(spec.stderr[0])
        else:
            spec = lle_from_equations(
                scene, cycles=lle_cycles(scene), tighten=False, variational=False
            )
            lam, err = float(spec.lle), float(spec.stderr)
    except (SolverError, FloatingPointError, ValueError):
        status = 1
    period_s = float(run.attrs["forcing_period"])
    out["lle"] = (
        (),
        lam,
        {"long_name": "largest Lyapunov exponent", "units": "s-1", "method": METHODS[method]},
    )
    out["lle_stderr"] = (
        (),
        err,
        {"long_name": "standard error of the largest Lyapunov exponent", "units": "s-1"},
    )
    out["lle_per_period"] = (
        (),
        lam * period_s,
        {"long_name": "largest Lyapunov exponent per forcing period", "units": "1"},
    )
    out["lle_status"] = ((), np.int8(status), LLE_STATUS)
    return xr.Dataset(out)


def strobe_zero_one(x: np.ndarray) -> float:
    """The 0-1 test's K of one series of strobe samples (:func:`workbench.analysis.
    zero_one_test`); 0 for a constant one (a period-1 orbit, where K is undefined), NaN for
    fewer than 100 samples."""
    x = x[np.isfinite(x)]
    if x.size < 100:
        return np.nan
    if np.ptp(x) <= PERIOD_TOLERANCE * max(np.max(np.abs(x)), 1e-300):
        return 0.0
    return float(zero_one_test(x).K)


def chaos_map(
    scene: SceneSource,
    store,
    *,
    client=None,
    workers: int | None = None,
    chunk: int | None = None,
    restart: bool = False,
    progress: bool = False,
) -> xr.Dataset:
    """A campaign over the scene's ``[sweep]`` that measures the chaos indicators of every
    point in its worker (:func:`chaos_indicators`) and stores them over the parameter dims,
    beside the strobe samples the scene records (resumable like any campaign,
    :func:`workbench.run_campaign`).

    The scene should record per forcing period (``record.samples_per_period = 1``) at least
    100 cycles (the 0-1 test needs 100 samples). Draw the maps with
    :func:`workbench.plot.chaos_map_figure`.
    """
    scene = load_scene(scene)
    return run_campaign(
        scene,
        store,
        client=client,
        workers=workers,
        chunk=chunk,
        restart=restart,
        progress=progress,
        per_point=chaos_indicators,
    )
