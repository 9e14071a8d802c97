"""Chaos indicators of one run, computed in a campaign's worker, and the campaign that maps them
over parameters.

Per point: the **period of the strobe** (the least k with x(t + kT) = x(t) over the recorded
strobe samples, 0 when none up to :data:`MAX_PERIOD`: quasi-periodic or chaotic), the **0-1
test's K** (Gottwald & Melbourne 2004, 2009) on the strobe samples of every recorded variable,
and the **largest Lyapunov exponent** with its error (:func:`workbench.continuation.
point_exponent`): where the strobe has a period k, ``ln |mu_max| / (k T)`` of the period-k
orbit Newton finds from the state where the run ended (a trajectory method cannot measure a
strongly contracting orbit: :mod:`workbench.continuation._exponent`), else over
:func:`lle_cycles` forcing periods after the scene's transient from the variational equations
with saltation for a model with an analytic Jacobian, or by the linearised two-trajectory method
(the mechanisms), checked by the variational exponent on the same trajectories. A failure of
the exponent's runs is recorded (``lle_status``), not raised, so one hard point does not stop a
map; whether the exponent converged is recorded beside it (``lle_converged``, and
``lle_unmet``: which of its conditions did not hold,
:data:`workbench.continuation._exponent.UNMET`).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from workbench.analysis import poincare_section, zero_one_test
from workbench.campaign import run_campaign
from workbench.continuation._exponent import METHODS, NOT_RUN, UNMET, point_exponent
from workbench.scene import Scene, SceneSource, load_scene

__all__ = [
    "MAX_PERIOD",
    "chaos_indicators",
    "chaos_map",
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
    "long_name": "outcome of the exponent's runs",
    "units": "1",
    "flag_values": np.array([0, 1, 2], np.int8),
    "flag_meanings": "ok failed upper_bound",
    "comment": "upper_bound: lle is an upper bound (the Floquet multipliers are below the noise "
    "of the copies' differences; lle_stderr NaN)",
}
LLE_METHOD = {
    "long_name": "how the largest Lyapunov exponent was measured",
    "units": "1",
    "flag_values": np.arange(len(METHODS), dtype=np.int8),
    "flag_meanings": " ".join(METHODS),
    **{f"method_{k}": v for k, v in METHODS.items()},
}
LLE_CONVERGED = {
    "long_name": "the largest Lyapunov exponent converged",
    "units": "1",
    "flag_values": np.array([0, 1], np.int8),
    "flag_meanings": "not_converged converged",
    "comment": "1 where every convergence condition the map runs holds (lle_unmet = 0): "
    "trajectory methods: the error target, the separation and growth variants and the "
    "variational exponent on the same trajectories (copies), the error target and the sum "
    "check (variational); floquet: the "
    "exponent moves by at most 20 % with its check; never for an upper bound or a failed "
    "run. Not run in a map (their cost): "
    + "; ".join(f"{m}: {', '.join(c)}" for m, c in NOT_RUN.items()),
}
LLE_UNMET = {
    "long_name": "the convergence conditions of the largest Lyapunov exponent that failed",
    "units": "1",
    "flag_masks": np.array([1 << i for i in range(len(UNMET))], np.int16),
    "flag_meanings": " ".join(u.replace(" ", "_") for u in UNMET),
    "comment": "bit field, 0: converged. error_target: the standard error is above 3 % of the "
    "estimate after the window's budget; variants: the two-trajectory separation and growth "
    "variants disagree; tolerance_check: the run at rtol / 100 disagrees; sum_check: the "
    "spectrum's sum and the integrated volume rate differ; floquet_check: the Floquet exponent "
    "moves by more than 20 % with its check; upper_bound: see lle_status; failed: the "
    "exponent's runs failed; variational: the copies' exponent and the variational one on the "
    "same trajectories differ; other: a condition of the estimator not named here",
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


def lle_cycles(scene: Scene) -> int:
    """Forcing periods over which a map point's exponent is measured: a fifth of the recorded
    cycles, at least 10 (the exponent's batch-means error needs ten batches)."""
    return max(10, scene.run["cycles"] // 5)


def chaos_indicators(scene: Scene, run: xr.Dataset) -> xr.Dataset:
    """The chaos indicators of one point (a campaign's ``per_point``): ``strobe_period``,
    ``zero_one_K`` (median over the recorded variables' components) and ``zero_one_K_<var>``
    (per variable, over its model dims), ``lle`` and ``lle_stderr`` (s-1), ``lle_per_period``
    (1), ``lle_method`` (floquet, variational or copies: :func:`workbench.continuation.
    point_exponent`), ``lle_status``, ``lle_converged`` and ``lle_unmet`` (why not; the
    estimator's own words in the attribute ``lle_detail``).

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
    exp = point_exponent(
        scene,
        period=period,
        cycles=lle_cycles(scene),
        start_cycles=scene.run["transient_cycles"] + scene.run["cycles"],
    )
    period_s = float(run.attrs["forcing_period"])
    out["lle"] = (
        (),
        exp.value,
        {"long_name": "largest Lyapunov exponent", "units": "s-1"},
    )
    out["lle_stderr"] = (
        (),
        exp.error,
        {
            "long_name": "error of the largest Lyapunov exponent (batch means; floquet: its "
            "change with the copies' step or the tolerance, see lle_method)",
            "units": "s-1",
        },
    )
    out["lle_per_period"] = (
        (),
        exp.value * period_s,
        {"long_name": "largest Lyapunov exponent per forcing period", "units": "1"},
    )
    out["lle_method"] = ((), np.int8(list(METHODS).index(exp.method)), LLE_METHOD)
    status = 1 if exp.failed else 2 if exp.bound else 0
    out["lle_status"] = ((), np.int8(status), LLE_STATUS)
    out["lle_converged"] = ((), np.int8(exp.converged), LLE_CONVERGED)
    out["lle_unmet"] = ((), np.int16(exp.unmet_code), LLE_UNMET)
    return xr.Dataset(out, attrs={"lle_detail": exp.detail})


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

    Parameters
    ----------
    scene : Scene, path or mapping
        A forced model with a ``[sweep]`` (without ``continuation``).
    store : str or PathLike
        Path of the campaign archive; blocks and manifest go to ``<store>.blocks/``.
    client : dask.distributed.Client, optional
        Run the blocks on this cluster (default: a local process pool).
    workers : int, optional
        Processes of the local pool (default: the CPUs available); not with ``client``.
    chunk : int, optional
        Points per block (task); default about four blocks per worker.
    restart : bool
        Discard whatever the store holds and start afresh.
    progress : bool
        Show a progress bar over points.

    Returns
    -------
    xarray.Dataset
        The campaign (:func:`workbench.run_campaign`) with the indicators of
        :func:`chaos_indicators` over the parameter dims.
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
