"""Stage 1 of the Wolf estimate (:func:`workbench.analysis.wolf_lle`): choose the embedding.

From the series alone: map or sampled flow (:func:`smoothness`), the delay (first minimum of
the average mutual information, Fraser & Swinney 1986), the dimension (false nearest
neighbours, Kennel et al. 1992, with Cao's E1/E2 as a second opinion and E2 as a noise test,
Cao 1997), the Theiler window (the mean period) and the evolution time; then the length scales
between which a neighbour is followed (:func:`choose_scales`). Every choice the caller left as
None is made here and listed in :attr:`Embedding.chosen`, with the evidence behind it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import xarray as xr
from scipy.spatial import cKDTree

from workbench.analysis._delay import delay_ami
from workbench.analysis._embedding import embed, embedding_cao, embedding_fnn
from workbench.analysis._series import Series

__all__ = [
    "Embedding",
    "Scales",
    "choose_embedding",
    "choose_scales",
    "mean_period",
    "smoothness",
]

#: a series is a resolved sampled flow when the lag-1 autocorrelation of its successive
#: differences (:func:`smoothness`) is at least this: a sinusoid sampled at n points per cycle
#: gives cos(2 pi / n), so 0.9 means at least ~14 samples per dominant cycle and no kinks at
#: the sample scale (unresolved impacts lower it). Development set: Lorenz x 0.97-0.998 at dt
#: 0.005-0.02 s, 0.94 at 0.03, 0.85 at 0.05, 0.51 at 0.1, -0.05 at 0.2; Rossler x 0.98-0.996
#: at 0.05-0.1, 0.88 at 0.3, 0.68 at 0.6; the clearance coordinates of the nine-bar mechanism
#: (Sec. 5.1 run) -0.42..0.21 at 100 samples per crank period, 0.25-0.58 at 1 000, 0.95-0.98
#: at 10 000; maps and noise <= 0 (Henon -0.70, white noise -0.50).
FLOW_SMOOTHNESS = 0.9
#: below 0.9 but at least this (about 6 or more samples per cycle), a coarsely sampled flow:
#: the flow program still applies (Lorenz x at dt = 0.05-0.1 s: -3 % .. +7 %; as a map with
#: delay 1: +19 .. +46 %) but the estimate is flagged; below it the series is taken for a map
FLOW_MIN_SMOOTHNESS = 0.5
#: the sampled-flow scale: this fraction of the median distance to the 50th nearest point
#: (development set: Lorenz and Rossler x, 30 series of 10 000 points; 0.5 and 1.0 scattered
#: more), and the map scale: the median distance to the 20th nearest point (Henon)
FLOW_SCALE_FRACTION, FLOW_SCALE_POINTS, MAP_SCALE_POINTS = 0.7, 50, 20
#: reference points of the false-neighbour statistics (FNN, Cao) behind the dimension: a
#: fraction to about +-1.3 % (binomial error)
EVIDENCE_POINTS = 1500
#: Cao's E2 within this of 1 at every dimension up to 4: a stochastic series (Cao 1997, Sec. 3)
E2_NOISE_BAND = 0.1


def mean_period(v: np.ndarray) -> float:
    """Mean period (samples) from the power-weighted mean frequency of the spectrum.

    Examples
    --------
    >>> round(mean_period(np.sin(2 * np.pi * np.arange(1000) / 50)))
    50
    """
    v = np.asarray(v, dtype=float)
    p = np.abs(np.fft.rfft(v - v.mean())) ** 2
    f = np.fft.rfftfreq(v.size)
    total = float(np.sum(p[1:]))
    fbar = float(np.sum(f[1:] * p[1:]) / total) if total > 0 else 0.0
    return 1.0 / fbar if fbar > 0 else float(v.size)


def smoothness(v: np.ndarray) -> float:
    """Lag-1 autocorrelation of the successive differences of a series: near 1 for a finely
    sampled flow (cos(2 pi / n) for a sinusoid at n samples per cycle), at or below 0 for a map
    or noise (-0.5 for white noise). NaN for a constant series.

    Examples
    --------
    >>> t = np.arange(2000)
    >>> round(smoothness(np.sin(2 * np.pi * t / 20)), 2)   # cos(2 pi / 20) = 0.951
    0.95
    >>> smoothness(np.random.default_rng(0).standard_normal(20000)) < -0.45
    True
    """
    d = np.diff(np.asarray(v, dtype=float))
    d = d - d.mean()
    den = float(np.dot(d, d))
    return float(np.dot(d[1:], d[:-1]) / den) if den > 0 else math.nan


@dataclass(frozen=True)
class Embedding:
    """The delay embedding chosen for a series, with the evidence behind each choice.

    ``points`` are the delay vectors (rows); ``flow`` says whether they sample a flow (1) or
    iterate a map; ``chosen_flow`` whether that was detected (True) or given; ``smoothness``
    and ``samples_per_period`` are the detection's evidence; ``ami``, ``fnn`` and ``cao`` the
    Datasets of :func:`~workbench.analysis.delay_ami`, :func:`~workbench.analysis.embedding_fnn`
    and :func:`~workbench.analysis.embedding_cao`; ``stochastic`` is Cao's noise test (E2
    within 0.1 of 1 at every dimension up to 4); ``chosen`` lists the settings chosen here."""

    points: np.ndarray
    flow: bool
    chosen_flow: bool
    delay: int
    dim: int
    theiler: int
    evolve: int
    smoothness: float
    samples_per_period: float
    ami: xr.Dataset
    fnn: xr.Dataset
    cao: xr.Dataset
    stochastic: bool
    chosen: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class Scales:
    """Separations (units of the series) between which a neighbour is followed."""

    scale_min: float
    scale_max: float


def choose_embedding(
    s: Series,
    *,
    flow: bool | None,
    delay: int | None,
    dim: int | None,
    theiler: int | None,
    evolve: int | None,
) -> Embedding:
    """Stage 1: map or flow, delay, dimension, Theiler window and evolution time of a series
    (each one given as None is chosen; see :func:`workbench.analysis.wolf_lle`), and the delay
    vectors. Raises ValueError if the series is too short for them."""
    v = s.values
    chosen = []
    smooth = smoothness(v)
    spp = mean_period(v)
    chosen_flow = flow is None
    if flow is None:
        flow = s.sampling != "strobe" and smooth >= FLOW_MIN_SMOOTHNESS
        chosen.append("flow")
    flow = bool(flow)
    ami = delay_ami(v, max_lag=max(2, min(v.size // 10, 2000)))
    if delay is None:
        delay = int(ami.delay) if flow else 1
        chosen.append("delay")
    fits = max(1, (v.size - 20) // delay - 2)  # dimensions whose embedding the series can hold
    fnn = embedding_fnn(v, delay=delay, max_dim=min(10, fits), points=EVIDENCE_POINTS)
    if dim is None:
        dim = int(fnn.dim)
        chosen.append("dim")
    cao_max = min(max(dim + 2, 4), fits)
    cao = embedding_cao(v, delay=delay, max_dim=cao_max, points=EVIDENCE_POINTS)
    # Cao's E2 stays near 1 at every dimension for a stochastic series (Cao 1997): such a
    # series gets a positive "LLE" from any estimator, which is no evidence of chaos
    stochastic = bool(np.all(np.abs(cao.E2.values[: min(4, cao_max)] - 1.0) < E2_NOISE_BAND))
    if theiler is None:
        theiler = max(1, int(round(spp)))
        chosen.append("theiler")
    if evolve is None:
        evolve = max(1, int(round(delay / 4))) if flow else 1
        chosen.append("evolve")
    Y = np.ascontiguousarray(embed(v, dim, delay))
    n = Y.shape[0]
    if n < 4 * theiler + 4 * evolve + 4:
        raise ValueError(
            f"x ({s.name!r}) has {v.size} samples, too few for dim={dim}, delay={delay}, "
            f"theiler={theiler}, evolve={evolve}: it needs at least "
            f"{4 * theiler + 4 * evolve + 4 + (dim - 1) * delay}; record a longer series"
        )
    return Embedding(
        points=Y,
        flow=flow,
        chosen_flow=chosen_flow,
        delay=delay,
        dim=dim,
        theiler=theiler,
        evolve=evolve,
        smoothness=smooth,
        samples_per_period=spp,
        ami=ami,
        fnn=fnn,
        cao=cao,
        stochastic=stochastic,
        chosen=chosen,
    )


def choose_scales(emb: Embedding, *, scale_min: float | None, scale_max: float | None) -> Scales:
    """The length scales (each one given as None is chosen, and added to ``emb.chosen``):
    ``scale_max`` = 0.7 times the median distance to the 50th nearest point for a flow, the
    median distance to the 20th for a map; ``scale_min`` = scale_max / 1000. Raises
    ValueError unless 0 <= scale_min < scale_max."""
    Y = emb.points
    n = Y.shape[0]
    if scale_max is None:
        tree = cKDTree(Y)
        k = FLOW_SCALE_POINTS if emb.flow else MAP_SCALE_POINTS
        probe = np.linspace(0, n - 1, min(n, 500)).astype(np.int64)
        dk, _ = tree.query(Y[probe], k=min(k + 1, n))
        scale_max = float(np.median(dk[:, -1])) * (FLOW_SCALE_FRACTION if emb.flow else 1.0)
        emb.chosen.append("scale_max")
    if scale_min is None:
        scale_min = 1e-3 * scale_max
        emb.chosen.append("scale_min")
    if not 0 <= scale_min < scale_max:
        raise ValueError(
            f"scale_min={scale_min!r} and scale_max={scale_max!r}: need 0 <= scale_min < scale_max"
        )
    return Scales(scale_min, scale_max)
