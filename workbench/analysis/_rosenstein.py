"""Largest Lyapunov exponent by Rosenstein, Collins & De Luca (1993), Physica D 65, 117, as
computed by nolds (Schölzel 2019), with an automatic fit of the linear region of the mean
log-divergence curve. A cross-check of :func:`workbench.analysis.wolf_lle`."""

from __future__ import annotations

import warnings

import numpy as np
import xarray as xr

from workbench._attributes import variable
from workbench.analysis._degenerate import series_without_dynamics
from workbench.analysis._delay import delay_ami
from workbench.analysis._embedding import embedding_fnn
from workbench.analysis._series import as_series
from workbench.analysis._wolf_embedding import mean_period

__all__ = ["rosenstein_lle"]

MAX_POINTS = 6000  # nolds builds a dense N x N distance matrix: 6000 points take 290 MB


def rosenstein_lle(
    x,
    *,
    dt: float | None = None,
    dim: int | None = None,
    delay: int | None = None,
    theiler: int | None = None,
    trajectory_len: int | None = None,
    max_points: int = MAX_POINTS,
) -> xr.Dataset:
    """LLE from the slope of the mean log-divergence of nearest neighbours (nolds.lyap_r).

    The slope is fitted over the linear region of the divergence curve, found automatically:
    before the curve reaches 90 % of its rise (saturation), the window of a third of its
    length over which the local slope varies least (after the fast initial alignment of the
    separations with the unstable direction). Only the first ``max_points`` samples are used
    (nolds' distance matrix is dense). None-parameters are chosen as in :func:`wolf_lle`
    (``trajectory_len`` default: 10 delays).

    Returns an ``xarray.Dataset`` with ``lle`` (1/s), the curve ``divergence`` over ``k``
    (samples), the fit window ``fit_start``/``fit_stop`` and the settings.

    Examples
    --------
    >>> import workbench
    >>> ds = workbench.simulate({"model": {"name": "lorenz"},
    ...                          "run": {"duration": 80.0, "transient": 20.0},
    ...                          "record": {"dt": 0.01}})
    >>> 0.6 < float(rosenstein_lle(ds.x).lle) < 1.2
    True
    """
    import nolds

    s = as_series(x, dt)
    problem = series_without_dynamics(s)
    if problem:
        raise ValueError(problem)
    v = s.values[:max_points]
    delay = int(delay_ami(v).delay) if delay is None else delay
    dim = int(embedding_fnn(v, delay=delay).dim) if dim is None else dim
    theiler = int(round(mean_period(v))) if theiler is None else theiler
    trajectory_len = 10 * delay if trajectory_len is None else trajectory_len
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        _, (ks, div, _) = nolds.lyap_r(
            v,
            emb_dim=dim,
            lag=delay,
            min_tsep=theiler,
            trajectory_len=trajectory_len,
            fit="poly",
            debug_data=True,
        )
    ks, div = np.asarray(ks, float), np.asarray(div, float)
    ok = np.isfinite(div)
    ks, div = ks[ok], div[ok]
    lo, hi = _linear_region(div)
    slope = float(np.polyfit(ks[lo : hi + 1], div[lo : hi + 1], 1)[0])
    t_units = "s-1" if s.time_units == "s" else "1/sample"
    return xr.Dataset(
        {
            "lle": ((), slope / s.dt, variable("largest Lyapunov exponent", t_units)),
            "divergence": ("k", div, variable("mean log divergence")),
            "fit_start": ((), ks[lo], variable("first k of the fit")),
            "fit_stop": ((), ks[hi], variable("last k of the fit")),
            "dim": ((), dim, variable("embedding dimension")),
            "delay": ((), delay, variable("delay (samples)")),
            "theiler": ((), theiler, variable("Theiler window (samples)")),
            "points": ((), v.size, variable("samples used")),
        },
        coords={"k": ("k", ks, variable("steps after the start (samples)"))},
        attrs={"method": "Rosenstein et al. (1993) via nolds.lyap_r; automatic linear fit"},
    )


def _linear_region(div: np.ndarray) -> tuple[int, int]:
    """(first, last) index of the straightest part of a divergence curve before saturation."""
    rise = div - div[0]
    end = int(np.argmax(rise >= 0.9 * rise.max())) if rise.max() > 0 else div.size - 1
    end = max(end, min(div.size - 1, 6))
    width = max(3, (end + 1) // 3)
    slope = np.gradient(div[: end + 1])
    best, best_lo = np.inf, 0
    for lo in range(0, end + 2 - width):
        w = slope[lo : lo + width]
        spread = float(np.std(w) / max(abs(np.mean(w)), 1e-300))
        if spread < best:
            best, best_lo = spread, lo
    return best_lo, best_lo + width - 1
