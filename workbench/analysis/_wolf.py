"""Largest Lyapunov exponent from a scalar time series: the fixed-evolution-time program of
Wolf, Swift, Swinney & Vastano (1985), Physica D 16, 285, with a KD-tree neighbour search."""

from __future__ import annotations

import math

import numpy as np
import xarray as xr
from scipy.spatial import cKDTree

from workbench.analysis._delay import delay_ami
from workbench.analysis._embedding import embed, embedding_cao, embedding_fnn
from workbench.analysis._series import as_series

__all__ = ["wolf_lle", "mean_period"]


def mean_period(v: np.ndarray) -> float:
    """Mean period (samples) from the power-weighted mean frequency of the spectrum."""
    p = np.abs(np.fft.rfft(v - v.mean())) ** 2
    f = np.fft.rfftfreq(v.size)
    fbar = float(np.sum(f[1:] * p[1:]) / np.sum(p[1:]))
    return 1.0 / fbar if fbar > 0 else float(v.size)


def _angle(u: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Angles (rad) between the rows of u and the vector w."""
    nu = np.linalg.norm(u, axis=1)
    nw = np.linalg.norm(w)
    c = (u @ w) / np.maximum(nu * nw, 1e-300)
    return np.arccos(np.clip(c, -1.0, 1.0))


def wolf_lle(
    x,
    *,
    dt: float | None = None,
    dim: int | None = None,
    delay: int | None = None,
    evolve: int | None = None,
    scale_min: float | None = None,
    scale_max: float | None = None,
    max_angle: float = 0.3,
    theiler: int | None = None,
    period: float | None = None,
) -> xr.Dataset:
    """Largest Lyapunov exponent of a scalar series by the method of Wolf et al. (1985).

    A fiducial trajectory and one neighbour in the delay embedding are followed for ``evolve``
    samples; the log of the growth of their separation is accumulated; then the neighbour is
    replaced by the point that keeps the separation's direction best: among points at
    distances in [``scale_min``, ``scale_max``] from the fiducial point (and ``theiler`` samples
    away in time), the one at the smallest angle to the evolved separation, if that angle is
    below ``max_angle``. If none qualifies the search widens the scale (up to 4 x), then the
    angle (up to 4 x), and only then keeps the old neighbour (Wolf et al., Sec. 6 and their
    program FET).

    Parameters left as None are chosen from the series and reported: ``delay`` by the first
    AMI minimum, ``dim`` by false nearest neighbours, ``theiler`` = the mean period (power-
    weighted mean frequency), ``evolve`` = half the delay, ``scale_max`` = 1.7 x the median
    distance to the 50th nearest neighbour (it follows the density of the data: Wolf's method
    underestimates when the scale reaches the nonlinear folding and scatters when too few
    replacement points lie within it), ``scale_min`` = scale_max / 1000.

    Returns
    -------
    xarray.Dataset
        ``lle`` (1/s; per sample without dt), ``lle_per_period`` (per forcing period, when
        ``period`` (s) is given or the series carries ``forcing_period``), ``running`` (the
        estimate over ``elapsed`` time), ``replacements``,
        ``stochastic`` (1 when Cao's E2 is near 1 at every dimension: the series looks like
        noise and its LLE is no evidence of chaos),
        ``kept`` (steps that kept their neighbour for want of a replacement), ``steps``, and the
        settings ``dim``, ``delay``, ``evolve``, ``theiler``, ``scale_min``, ``scale_max``
        (units of x), ``max_angle`` (rad), with ``chosen`` listing those chosen automatically.

    Examples
    --------
    >>> import workbench
    >>> from workbench.analysis import wolf_lle
    >>> ds = workbench.simulate({"model": {"name": "lorenz"},
    ...                          "run": {"duration": 200.0, "transient": 20.0},
    ...                          "record": {"dt": 0.01}})
    >>> r = wolf_lle(ds.x)
    >>> 0.8 < float(r.lle) < 1.0   # the Lorenz LLE is 0.9056 1/s
    True
    """
    s = as_series(x, dt)
    v = s.values
    chosen = []
    if delay is None:
        delay = int(delay_ami(v).delay)
        chosen.append("delay")
    # Cao's E2 stays near 1 at every dimension for a stochastic series (Cao 1997): such a
    # series gets a positive "LLE" from any estimator, which is no evidence of chaos
    e2 = embedding_cao(v[: min(v.size, 20000)], delay=delay, max_dim=6).E2.values
    stochastic = bool(np.all(np.abs(e2 - 1.0) < 0.1))
    if dim is None:
        dim = int(embedding_fnn(v, delay=delay).dim)
        chosen.append("dim")
    if theiler is None:
        theiler = int(round(mean_period(v)))
        chosen.append("theiler")
    if evolve is None:
        evolve = max(1, delay // 2)
        chosen.append("evolve")
    Y = np.ascontiguousarray(embed(v, dim, delay))
    n = Y.shape[0]
    tree = cKDTree(Y)
    if scale_max is None:
        # a few typical neighbour spacings: 1.7 x the median distance to the 50th nearest
        # neighbour (500 sample points), so that the scale follows the density of the data
        probe = np.linspace(0, n - 1, min(n, 500)).astype(np.int64)
        dk, _ = tree.query(Y[probe], k=min(51, n))
        scale_max = 1.7 * float(np.median(dk[:, -1]))
        chosen.append("scale_max")
    if scale_min is None:
        scale_min = 1e-3 * scale_max
        chosen.append("scale_min")
    if not 0 <= scale_min < scale_max:
        raise ValueError(
            f"scale_min={scale_min!r} and scale_max={scale_max!r}: need 0 <= scale_min < scale_max"
        )
    if n < 4 * theiler + 4 * evolve:
        raise ValueError(
            f"{v.size} samples are too few for dim={dim}, delay={delay}, theiler={theiler}, "
            f"evolve={evolve}: record a longer series"
        )

    def replace(i: int, direction: np.ndarray | None) -> tuple[int, float]:
        smax, amax = scale_max, max_angle
        for widen in range(5):
            cand = np.asarray(tree.query_ball_point(Y[i], smax), dtype=np.int64)
            cand = cand[(np.abs(cand - i) > theiler) & (cand + evolve < n)]
            if cand.size:
                sep = Y[cand] - Y[i]
                d = np.linalg.norm(sep, axis=1)
                ok = d >= scale_min
                cand, sep, d = cand[ok], sep[ok], d[ok]
            if cand.size:
                if direction is None:
                    k = int(np.argmin(d))
                    return int(cand[k]), float(d[k])
                ang = _angle(sep, direction)
                k = int(np.argmin(ang))
                if ang[k] <= amax:
                    return int(cand[k]), float(d[k])
            if widen < 2:
                smax *= 2.0  # widen the length scale first ...
            else:
                amax = min(2 * amax, math.pi)  # ... then the angle
        return -1, math.nan

    i = 0
    j, d0 = replace(i, None)
    while j < 0 and i + evolve < n:
        i += 1
        j, d0 = replace(i, None)
    total, elapsed = 0.0, 0
    running_t, running = [], []
    replacements = kept = 0
    while j >= 0 and i + evolve < n:
        if j + evolve >= n:  # the neighbour runs out of data before the fiducial point
            j, d0 = replace(i, Y[j] - Y[i])
            if j < 0:
                break
        d1 = float(np.linalg.norm(Y[i + evolve] - Y[j + evolve]))
        if d1 > 0 and d0 > 0:
            total += math.log(d1 / d0)
        elapsed += evolve
        running_t.append(elapsed * s.dt)
        running.append(total / (elapsed * s.dt))
        i, j_old = i + evolve, j + evolve
        if scale_min <= d1 <= scale_max:
            j, d0 = j_old, d1  # the evolved neighbour is still a good one: keep it
            continue
        k, dk = replace(i, Y[j_old] - Y[i])
        if k >= 0 and k != j_old:
            j, d0 = k, dk
            replacements += 1
        else:
            j, d0 = j_old, d1
            kept += 1
    if not running:
        raise ValueError("no neighbour pair could be followed: the series is too short or flat")
    lle = running[-1]
    t_units = "s-1" if s.time_units == "s" else "1/sample"
    out = xr.Dataset(
        {
            "lle": ((), lle, {"units": t_units, "long_name": "largest Lyapunov exponent"}),
            "running": (
                "elapsed",
                np.asarray(running),
                {"units": t_units, "long_name": "running estimate of the LLE"},
            ),
            "replacements": ((), replacements, {"units": "1", "long_name": "replacements"}),
            "kept": ((), kept, {"units": "1", "long_name": "old neighbour kept (none found)"}),
            "steps": ((), len(running), {"units": "1", "long_name": "evolution steps"}),
            "dim": ((), dim, {"units": "1", "long_name": "embedding dimension"}),
            "stochastic": (
                (),
                int(stochastic),
                {"units": "1", "long_name": "Cao's E2 within 0.1 of 1 for d = 1..6 (noise)"},
            ),
            "delay": ((), delay, {"units": "1", "long_name": "delay (samples)"}),
            "evolve": ((), evolve, {"units": "1", "long_name": "evolution time (samples)"}),
            "theiler": ((), theiler, {"units": "1", "long_name": "Theiler window (samples)"}),
            "scale_min": ((), scale_min, {"units": s.units, "long_name": "smallest separation"}),
            "scale_max": ((), scale_max, {"units": s.units, "long_name": "largest separation"}),
            "max_angle": ((), max_angle, {"units": "rad", "long_name": "largest angle"}),
        },
        coords={
            "elapsed": (
                "elapsed",
                np.asarray(running_t),
                {"units": s.time_units, "long_name": "time followed"},
            )
        },
        attrs={"method": "Wolf et al. (1985), fixed evolution time", "chosen": ", ".join(chosen)},
    )
    period = period or s.period
    if period:
        out["lle_per_period"] = (
            (),
            lle * period,
            {"units": "1", "long_name": "largest Lyapunov exponent per forcing period"},
        )
    return out
