"""Largest Lyapunov exponent from a scalar time series: the fixed-evolution-time program of
Wolf, Swift, Swinney & Vastano (1985), Physica D 16, 285, with a KD-tree neighbour search, for
maps (and stroboscopic sections) and for sampled flows, which it tells apart from the series;
for a flow, separations are measured between orbits (the flow direction projected out).

:func:`wolf_lle` runs three stages, each a function of its own module, the way ChaosTools
separates its high-level calls from the low-level ones on an embedded data set:

1. choose the embedding (:func:`~workbench.analysis._wolf_embedding.choose_embedding` and
   :func:`~workbench.analysis._wolf_embedding.choose_scales`),
2. evolve (:func:`~workbench.analysis._wolf_follow.follow`, Wolf et al.'s FET program),
3. judge (:func:`~workbench.analysis._wolf_judge.wolf_verdict`: the reliability flag and its
   reasons).
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from workbench._attributes import flags, variable
from workbench.analysis._degenerate import series_without_dynamics
from workbench.analysis._series import Series, as_series, require_samples
from workbench.analysis._surrogate import SURROGATES
from workbench.analysis._wolf_embedding import (
    FLOW_MIN_SMOOTHNESS,
    FLOW_SMOOTHNESS,
    Embedding,
    Scales,
    choose_embedding,
    choose_scales,
    mean_period,
    smoothness,
)
from workbench.analysis._wolf_follow import Followed, follow
from workbench.analysis._wolf_judge import Verdict, correlation_dimension, wolf_verdict

__all__ = ["wolf_lle", "mean_period", "smoothness", "correlation_dimension"]

#: fewest samples for any estimate at all
MIN_SAMPLES = 100


def _check_choice(name: str, value, lowest: int) -> int | None:
    if value is None:
        return None
    if int(value) != value or int(value) < lowest:
        raise ValueError(
            f"{name}={value!r}; allowed: a whole number >= {lowest}, or None (automatic)"
        )
    return int(value)


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
    flow: bool | None = None,
    surrogates: int = SURROGATES,
) -> xr.Dataset:
    """Largest Lyapunov exponent of a scalar series of a map or a sampled flow by the method of
    Wolf, Swift, Swinney & Vastano (1985), Physica D 16, 285 (their fixed-evolution-time
    program FET, Appendix A), every choice automatic and reported, with a reliability flag.

    A fiducial trajectory and one neighbour in the delay embedding are followed for
    ``evolve`` samples and the log of the growth of their separation is accumulated; the
    exponent is that sum over the total time followed. The neighbour is kept while the
    separation stays within [``scale_min``, ``scale_max``], else replaced by a point within
    ``scale_max`` of the fiducial point (and more than ``theiler`` samples away in time) whose
    separation lies within ``max_angle`` of the evolved separation's orientation, in either
    sense (FET: ``cth = abs(dot / (dnew * df))``): "its separation from the evolved fiducial
    point is small, and the angular separation between the evolved and replacement elements is
    small" (Sec. 6). For a map, the one at the smallest angle (FET); for a flow the nearest
    within the angle, so that each pair is followed over the widest range of scales. If none
    qualifies, the search widens the scale (up to 4 x), then the angle (up to 4 x), and only
    then keeps the old neighbour (FET).

    **Map or flow.** The series is a sampled flow when the lag-1 autocorrelation of its
    successive differences (:func:`smoothness`) is at least 0.5 (about 6 or more samples per
    dominant cycle; a resolved one from 0.9, ~14 samples), else it is treated as a map (delay
    1, one iteration per step); a stroboscopic section as
    :func:`~workbench.analysis.poincare_section` returns it is a map.
    For a sampled flow, separations are measured between orbits, not between samples: the
    flow direction carries a zero exponent (Haken 1983, Phys. Lett. A 94, 71), so the
    component of each separation along the fiducial trajectory (centred difference) is
    removed, and a neighbour is slid along its own samples to its closest approach (candidates
    too: one per passing strand).

    **Automatic choices** (parameters left as None; listed in the ``chosen`` attribute):
    ``flow`` by :func:`smoothness`; ``delay`` by the first minimum of the average mutual
    information (Fraser & Swinney 1986) for a flow, 1 for a map; ``dim`` by false nearest
    neighbours (Kennel et al. 1992) at that delay, with Cao's E1/E2 (Cao 1997) as a second
    opinion and E2 as a noise test; ``theiler`` = the mean period (power-weighted mean
    frequency); ``evolve`` = a quarter of the delay for a flow, 1 for a map; ``scale_max`` = 0.7
    times the median distance to the 50th nearest point for a flow, the median distance to the
    20th for a map (it follows the density of the data); ``scale_min`` = scale_max / 1000
    (noise-free data: Wolf et al. put it above the noise level, so raise it for noisy data).
    They were tuned on a development set (Henon; Lorenz and Rossler x, 30 series) and checked
    on held-out maps and flows (docs/results.md, "Analysis", gives the held-out figures).

    **Reliability.** ``reliable`` is 0, with the reasons in its ``message`` attribute (and the
    ``warning`` attribute of the Dataset), when: a series with a time step does not look like
    a sampled flow (too coarse a sampling of a flow, or a map given a time step: pass
    ``flow=False`` for a map); a flow's smoothness is below 0.9 (coarse sampling, or fast
    events between samples), its lambda dt above 0.1 per sample or it has fewer than 10
    samples per mean period, or spans fewer than 20 mean periods; the series has fewer than
    10**D points, D the correlation dimension (Grassberger & Procaccia 1983) of the embedded
    points at the neighbours' scales (Eckmann & Ruelle 1992; Wolf et al. 1985, Sec. 7);
    Cao's E2 is within 0.1 of 1 at every dimension (noise: a positive exponent is then no
    evidence of chaos); or the exponent is positive and the series is predicted no better than
    its IAAFT surrogates (:func:`~workbench.analysis.surrogate_test`: Theiler et al. 1992;
    Kennel & Isabelle 1992), i.e. nothing tells it from linear correlated noise. A series with
    no dynamics at all (constant, constant to rounding, parked at one value, a few repeated
    values: :func:`~workbench.analysis.no_dynamics`) raises ValueError with that verdict,
    at once.

    **Stages.** The estimate runs in three stages, each a function of its own module (the way
    ChaosTools separates its high-level calls from the low-level ones on an embedded data
    set): choose the embedding (``workbench.analysis._wolf_embedding``), evolve
    (``_wolf_follow``: the FET program on the embedded points) and judge (``_wolf_judge``).

    Parameters
    ----------
    x : array or DataArray
        The scalar series, at least 100 samples (a DataArray with ``time`` gives dt; one with
        dim ``strobe`` and coordinate ``strobe_time`` is a stroboscopic section).
    dt : float, optional
        Sampling step (s) of a plain array; without it, exponents are per sample.
    dim, delay, evolve : int, optional
        Embedding dimension, delay (samples), evolution time (samples).
    scale_min, scale_max : float, optional
        Separations (units of x) between which a neighbour is kept.
    max_angle : float
        Largest angle (rad, 0 < max_angle <= pi/2) between a replacement and the evolved
        separation.
    theiler : int, optional
        Theiler window (samples: neighbours are at least this far apart in time).
    period : float, optional
        Forcing period (s) for ``lle_per_period`` (default: the series' ``forcing_period``).
    flow : bool, optional
        Force a sampled flow (True) or a map (False) instead of detecting it.
    surrogates : int
        IAAFT surrogates of the noise test of a positive estimate (19: a one-sided rank test
        at 5 %; 0: no test).

    Returns
    -------
    xarray.Dataset
        ``lle`` (s-1 with dt; else "1", per sample: per iteration of a map), ``lle_per_sample``
        (lambda dt), ``lle_per_period`` (with a forcing period), ``running`` (the estimate over
        ``elapsed`` time), ``reliable`` (1/0 with ``message``), the detection evidence
        ``smoothness`` and ``samples_per_period``, ``flow`` (1: a sampled flow); the evidence
        for the embedding: ``ami`` over ``lag`` (the delay), ``fnn_fraction``, ``cao_E1`` and
        ``cao_E2`` over ``dimension``, ``cao_dim``, ``stochastic``; the settings ``dim``,
        ``delay``, ``evolve``, ``theiler``, ``scale_min``, ``scale_max`` (units of x),
        ``max_angle`` (rad); and ``replacements``, ``kept`` (steps that kept their neighbour
        for want of a replacement), ``steps``, ``points`` (embedded points), the
        ``correlation_dimension`` D and ``min_points`` (10**D); the surrogate test's
        ``prediction_error``, ``surrogate_error`` over ``surrogate`` and
        ``surrogate_stochastic`` (1: not told from linear noise, 0: deterministic, -1: not
        tested).

    Raises
    ------
    ValueError
        For fewer than 100 samples, a series with no dynamics (the verdict of
        :func:`~workbench.analysis.no_dynamics`), a series too short for the chosen embedding,
        or a setting out of its range (the message names it and what is allowed).

    References
    ----------
    Wolf, Swift, Swinney & Vastano (1985), Physica D 16, 285. Fraser & Swinney (1986), Phys.
    Rev. A 33, 1134. Kennel, Brown & Abarbanel (1992), Phys. Rev. A 45, 3403. Cao (1997),
    Physica D 110, 43. Eckmann & Ruelle (1992), Physica D 56, 185. Theiler (1986), Phys. Rev.
    A 34, 2427 (the Theiler window). Theiler, Eubank, Longtin, Galdrikian & Farmer (1992),
    Physica D 58, 77 (surrogate data). Kennel & Isabelle (1992), Phys. Rev. A 46, 3111.

    Examples
    --------
    >>> import numpy as np
    >>> x = np.empty(3000); a, b = 0.1, 0.0
    >>> for i in range(3000):             # Henon map: 0.41922 per iteration
    ...     a, b = 1 - 1.4 * a * a + b, 0.3 * a
    ...     x[i] = a
    >>> r = wolf_lle(x[100:])
    >>> int(r.flow), int(r.delay), int(r.dim), bool(r.reliable)
    (0, 1, 2, True)
    >>> abs(float(r.lle) / 0.41922 - 1) < 0.05
    True
    >>> import workbench
    >>> ds = workbench.simulate({"model": {"name": "lorenz"},
    ...                          "run": {"duration": 200.0, "transient": 20.0},
    ...                          "record": {"dt": 0.01}})
    >>> r = wolf_lle(ds.x)
    >>> int(r.flow), bool(r.reliable), 0.8 < float(r.lle) < 1.0   # 0.9056 1/s
    (1, True, True)
    >>> bool(wolf_lle(ds.x[::20]).reliable)   # dt = 0.2 s: flagged
    False
    """
    s = as_series(x, dt)
    require_samples(s, MIN_SAMPLES, "wolf_lle")
    v = s.values
    dim = _check_choice("dim", dim, 1)
    delay = _check_choice("delay", delay, 1)
    evolve = _check_choice("evolve", evolve, 1)
    theiler = _check_choice("theiler", theiler, 0)
    if not 0 < max_angle <= math.pi / 2:
        raise ValueError(f"max_angle={max_angle!r}; allowed: 0 < max_angle <= pi/2 (rad)")
    for name, value in (("scale_min", scale_min), ("scale_max", scale_max)):
        if value is not None and not (np.isfinite(value) and value >= 0):
            raise ValueError(f"{name}={value!r}; allowed: a finite separation >= 0 (units of x)")
    if period is not None and not period > 0:
        raise ValueError(f"period={period!r}; allowed: a positive forcing period (s)")
    if surrogates != 0 and (int(surrogates) != surrogates or surrogates < SURROGATES):
        raise ValueError(
            f"surrogates={surrogates!r}; allowed: 0 (no noise test) or a whole number >= 19"
        )
    problem = series_without_dynamics(s)
    if problem:
        raise ValueError(problem)
    # 1. choose the embedding and the scales
    emb = choose_embedding(s, flow=flow, delay=delay, dim=dim, theiler=theiler, evolve=evolve)
    scales = choose_scales(emb, scale_min=scale_min, scale_max=scale_max)
    # 2. evolve
    followed = follow(
        emb.points,
        flow=emb.flow,
        evolve=emb.evolve,
        scale_min=scales.scale_min,
        scale_max=scales.scale_max,
        max_angle=max_angle,
        theiler=emb.theiler,
    )
    if followed.logs.size == 0:
        raise ValueError(
            f"no neighbour pair could be followed in x ({s.name!r}, {v.size} samples): the "
            "series is too short or too sparse for the chosen scales"
        )
    elapsed_samples = emb.evolve * np.arange(1, followed.logs.size + 1)
    running_per_sample = np.cumsum(followed.logs) / elapsed_samples
    per_sample = float(running_per_sample[-1])
    # 3. judge
    verdict = wolf_verdict(s, emb, scales, followed.tree, per_sample, surrogates=int(surrogates))
    return _result(
        s, emb, scales, followed, verdict, running_per_sample, elapsed_samples, max_angle, period
    )


def _result(
    s: Series,
    emb: Embedding,
    scales: Scales,
    followed: Followed,
    verdict: Verdict,
    running_per_sample: np.ndarray,
    elapsed_samples: np.ndarray,
    max_angle: float,
    period: float | None,
) -> xr.Dataset:
    """The Dataset of :func:`wolf_lle`: the estimate, the verdict and the evidence."""
    per_sample = float(running_per_sample[-1])
    lle = per_sample / s.dt
    flow, cao, fnn, ami = emb.flow, emb.cao, emb.fnn, emb.ami
    reliable, message = verdict.reliable, verdict.message
    stochastic, smooth, spp = emb.stochastic, emb.smoothness, emb.samples_per_period
    dim, delay, evolve, theiler = emb.dim, emb.delay, emb.evolve, emb.theiler
    scale_min, scale_max = scales.scale_min, scales.scale_max
    replacements, kept, logs = followed.replacements, followed.kept, followed.logs
    n = emb.points.shape[0]
    d2, min_points, chosen = verdict.correlation_dimension, verdict.min_points, emb.chosen
    timed = s.time_units == "s"
    t_units = "s-1" if timed else "1"
    per = "" if timed else (" per iteration" if not flow else " per sample")
    dims = cao.dimension.values
    fnn_curve = np.full(dims.size, np.nan)
    m = min(dims.size, fnn.fnn_fraction.size)
    fnn_curve[:m] = fnn.fnn_fraction.values[:m]
    out = xr.Dataset(
        {
            "lle": ((), lle, variable("largest Lyapunov exponent" + per, t_units)),
            "lle_per_sample": (
                (),
                per_sample,
                variable("largest Lyapunov exponent per sample (lambda dt)"),
            ),
            "running": (
                "elapsed",
                running_per_sample / s.dt,
                variable("running estimate of the LLE" + per, t_units),
            ),
            "reliable": (
                (),
                np.int8(reliable),
                flags(
                    "estimate not flagged by the sampling, length and noise checks",
                    ["flagged", "reliable"],
                    message=message,
                    reasons="\n".join(verdict.reasons),
                ),
            ),
            "smoothness": (
                (),
                smooth,
                variable(
                    "lag-1 autocorrelation of successive differences (map/flow)",
                    resolved_flow_threshold=FLOW_SMOOTHNESS,
                    flow_threshold=FLOW_MIN_SMOOTHNESS,
                ),
            ),
            "samples_per_period": (
                (),
                spp,
                variable("samples per mean period (mean frequency)"),
            ),
            "flow": (
                (),
                np.int8(flow),
                variable("sampled flow (1; flow direction projected out)"),
            ),
            "ami": (
                "lag",
                ami.ami.values,
                variable("average mutual information", "nat"),
            ),
            "fnn_fraction": (
                "dimension",
                fnn_curve,
                variable("fraction of false nearest neighbours"),
            ),
            "cao_E1": ("dimension", cao.E1.values, variable("Cao E1(d)")),
            "cao_E2": ("dimension", cao.E2.values, variable("Cao E2(d)")),
            "cao_dim": ((), int(cao.dim), variable("dimension by Cao E1")),
            "stochastic": (
                (),
                np.int8(stochastic),
                variable("Cao's E2 within 0.1 of 1 for d = 1..4 (noise)"),
            ),
            "dim": ((), dim, variable("embedding dimension")),
            "delay": ((), delay, variable("delay (samples)")),
            "evolve": ((), evolve, variable("evolution time (samples)")),
            "theiler": ((), theiler, variable("Theiler window (samples)")),
            "scale_min": ((), scale_min, variable("smallest separation", s.units)),
            "scale_max": ((), scale_max, variable("largest separation", s.units)),
            "max_angle": (
                (),
                max_angle,
                variable("largest angle (orientation, either sense)", "rad"),
            ),
            "replacements": ((), replacements, variable("replacements")),
            "kept": ((), kept, variable("old neighbour kept (none found)")),
            "steps": ((), logs.size, variable("evolution steps")),
            "points": ((), n, variable("embedded points")),
            "correlation_dimension": (
                (),
                d2,
                variable("correlation dimension at the neighbours' scales"),
            ),
            "min_points": ((), min_points, variable("10^D points")),
            **_surrogate_variables(verdict.surrogate),
        },
        coords={
            "elapsed": (
                "elapsed",
                elapsed_samples * s.dt,
                variable("time followed", s.time_units),
            ),
            "lag": ("lag", ami.lag.values, variable("lag (samples)")),
            "dimension": ("dimension", dims, variable("embedding dimension")),
            "surrogate": (
                "surrogate",
                np.arange(0 if verdict.surrogate is None else verdict.surrogate.sizes["surrogate"]),
                variable("IAAFT surrogate"),
            ),
        },
        attrs={
            "method": "Wolf et al. (1985), fixed evolution time",
            "series_kind": "sampled flow" if flow else "map",
            "chosen": ", ".join(chosen),
            "warning": "" if reliable else message,
        },
    )
    period = period or s.period
    if period and timed:
        out["lle_per_period"] = (
            (),
            lle * period,
            variable("largest Lyapunov exponent per forcing period"),
        )
    return out


def _surrogate_variables(test: xr.Dataset | None) -> dict:
    """The surrogate test's variables in :func:`wolf_lle`'s Dataset (NaN, empty and -1 when
    the test did not run: a non-positive estimate, or ``surrogates=0``)."""
    if test is None:
        error, curve, flag = math.nan, np.empty(0), -1
    else:
        error, curve = float(test.error), test.surrogate_error.values
        flag = int(test.stochastic)
    return {
        "prediction_error": (
            (),
            error,
            variable("normalised nonlinear prediction error of the series"),
        ),
        "surrogate_error": (
            "surrogate",
            curve,
            variable("normalised nonlinear prediction error of a surrogate"),
        ),
        "surrogate_stochastic": (
            (),
            np.int8(flag),
            flags(
                "not told from linear correlated noise by IAAFT surrogates",
                {-1: "not_tested", 0: "deterministic", 1: "stochastic"},
            ),
        ),
    }
