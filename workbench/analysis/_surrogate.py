"""Surrogate data test for nonlinear determinism (Theiler, Eubank, Longtin, Galdrikian & Farmer
1992) with the nonlinear prediction error as its statistic (Sugihara & May 1990; Kennel &
Isabelle 1992).

The null hypothesis: the series is a linear Gaussian stochastic process seen through a static,
monotonic measurement function. Surrogates that obey it exactly are built from the series by
the iterative amplitude-adjusted Fourier transform (IAAFT, Schreiber & Schmitz 1996): the same
amplitude distribution and (nearly) the same power spectrum, the phases randomised. A
deterministic series is predicted from its own past better than every surrogate; a stochastic
one is not. The test cannot tell linear noise from a periodic signal (both keep their
spectrum), and says so: its verdict is "no evidence of nonlinear determinism", not "noise".
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy.fft import irfft, prev_fast_len, rfft

from workbench._attributes import variable
from workbench.analysis._embedding import embed, nearest_neighbours
from workbench.analysis._series import as_series, require_samples

__all__ = ["iaaft", "prediction_error", "surrogate_test"]

#: the test's surrogates: with 19, the series is predicted better than all of them by chance
#: with probability 1/20 under the null hypothesis (a one-sided rank test at 5 %, Theiler et
#: al. 1992, Sec. 2.3)
SURROGATES = 19
#: reference points of the prediction error (its relative standard error about 2 %)
PREDICTION_POINTS = 1000
#: IAAFT iterations at most (Schreiber & Schmitz 1996: the spectrum's error falls fastest in the
#: first few; the rank order rarely settles exactly in a long series)
IAAFT_ITERATIONS = 16
#: the test reads at most this many samples from the start of a series, cut to a length whose
#: FFT is fast (5-smooth: a length with a large prime factor, such as 100 001 = 11 x 9091,
#: makes every FFT of the IAAFT iterations slower). Not fewer: its neighbours must come from
#: other passes of the orbit (a nine-bar series at 10 000 samples per crank cycle cut to its
#: first 16 384 samples, 1.6 cycles, was not told from its surrogates; its 10 cycles were)
MAX_SAMPLES = 131072


def iaaft(v: np.ndarray, rng: np.random.Generator, iterations: int = IAAFT_ITERATIONS):
    """One IAAFT surrogate of ``v`` (Schreiber & Schmitz 1996, Phys. Rev. Lett. 77, 635): its
    values are a permutation of ``v`` (the same distribution, exactly) whose power spectrum is
    that of ``v`` as nearly as the permutation allows.

    Examples
    --------
    >>> v = np.sin(0.1 * np.arange(500)) ** 3
    >>> s = iaaft(v, np.random.default_rng(0))
    >>> bool(np.array_equal(np.sort(s), np.sort(v)))
    True
    """
    v = np.asarray(v, dtype=float)
    values = np.sort(v)
    amplitude = np.abs(rfft(v))
    s = rng.permutation(v)
    ranks = None
    for _ in range(iterations):
        spectrum = rfft(s)
        phase = np.exp(1j * np.angle(spectrum))
        s = irfft(amplitude * phase, v.size)
        new_ranks = np.argsort(s, kind="stable")
        s = np.empty_like(v)
        s[new_ranks] = values
        if ranks is not None and np.array_equal(new_ranks, ranks):
            break
        ranks = new_ranks
    return s


def prediction_error(
    v: np.ndarray,
    *,
    dim: int,
    delay: int,
    horizon: int,
    theiler: int,
    points: int = PREDICTION_POINTS,
) -> float:
    """Normalised error of the zeroth-order nonlinear predictor (Sugihara & May 1990; Kennel &
    Isabelle 1992): each of ``points`` reference points of the delay embedding (``dim``,
    ``delay``) is predicted ``horizon`` samples ahead by what its nearest neighbour (more than
    ``theiler`` samples away in time) did; the root mean square error over the standard
    deviation of the series (1: no better than the mean; 0: perfect)."""
    v = np.asarray(v, dtype=float)
    lead = (dim - 1) * delay + horizon
    Y = embed(v, dim, delay)[: v.size - lead]  # the points whose target v[i + lead] exists
    n = Y.shape[0]
    ref = np.unique(np.linspace(0, n - 1, min(points, n)).astype(np.int64))
    j, _ = nearest_neighbours(np.ascontiguousarray(Y), theiler, query=ref)
    ok = j >= 0
    a, b = ref[ok], j[ok]
    err = v[a + lead] - v[b + lead]
    sd = float(np.std(v))
    return float(np.sqrt(np.mean(err**2)) / sd) if a.size and sd > 0 else np.nan


def surrogate_test(
    x,
    *,
    dim: int,
    delay: int,
    horizon: int | None = None,
    theiler: int | None = None,
    surrogates: int = SURROGATES,
    seed: int = 0,
    dt: float | None = None,
) -> xr.Dataset:
    """Test a series for nonlinear determinism against IAAFT surrogates (Theiler et al. 1992,
    Physica D 58, 77; Schreiber & Schmitz 1996), with the nonlinear prediction error as the
    statistic (Sugihara & May 1990, Nature 344, 734; Kennel & Isabelle 1992, Phys. Rev. A 46,
    3111).

    The series (its first 131 072 samples at most, cut to a length whose FFT is fast) is
    predicted ``horizon`` samples ahead in its delay embedding (``dim``,
    ``delay``) by :func:`prediction_error`, and so is each of ``surrogates`` IAAFT surrogates
    (seeded by ``seed``: the same series gives the same answer). ``deterministic`` is 1 when
    the series is predicted better than every surrogate: the null hypothesis of a (rescaled)
    linear Gaussian process is then rejected at the level 1 / (surrogates + 1) (5 % with 19).
    Otherwise the series is called ``stochastic``: nothing in it distinguishes it from linear
    correlated noise, and a positive Lyapunov exponent estimated from it is no evidence of
    chaos. (A periodic signal keeps its spectrum in its surrogates and is not distinguished
    either; its exponent is not positive.)

    Parameters
    ----------
    x : array or DataArray
        The scalar series (at least 100 samples).
    dim, delay : int
        Embedding dimension and delay (samples), e.g. those of :func:`wolf_lle`.
    horizon : int, optional
        Samples predicted ahead (default: the delay; use 1 for a map).
    theiler : int, optional
        Neighbours are more than this many samples apart in time (default: the delay).
    surrogates : int
        Number of surrogates, at least 19.
    seed : int
        Seed of the surrogates' random phases.
    dt : float, optional
        Sampling step (s) of a plain array (not used by the test; accepted for symmetry).

    Returns
    -------
    xarray.Dataset
        ``error`` (the series' normalised prediction error), ``surrogate_error`` over
        ``surrogate``, ``p_value`` (the share of the surrogates plus the series whose error
        is at most the series'), ``deterministic`` and ``stochastic`` (1/0 flags).

    Examples
    --------
    >>> import numpy as np
    >>> x = np.empty(2000); a, b = 0.1, 0.0
    >>> for i in range(2000):                      # Henon map: deterministic
    ...     a, b = 1 - 1.4 * a * a + b, 0.3 * a
    ...     x[i] = a
    >>> int(surrogate_test(x[100:], dim=2, delay=1, horizon=1).deterministic)
    1
    >>> noise = np.random.default_rng(1).standard_normal(2000)
    >>> int(surrogate_test(noise, dim=2, delay=1, horizon=1).stochastic)
    1
    """
    s = as_series(x, dt)
    require_samples(s, 100, "surrogate_test")
    for name, value, lowest in (("dim", dim, 1), ("delay", delay, 1)):
        if int(value) != value or value < lowest:
            raise ValueError(f"{name}={value!r}; allowed: a whole number >= {lowest}")
    if surrogates < 19 or int(surrogates) != surrogates:
        raise ValueError(
            f"surrogates={surrogates!r}; allowed: a whole number >= 19 (a 5 % one-sided test)"
        )
    horizon = int(delay if horizon is None else horizon)
    theiler = int(delay if theiler is None else theiler)
    if horizon < 1:
        raise ValueError(f"horizon={horizon!r}; allowed: a whole number of samples >= 1")
    v = s.values[: prev_fast_len(min(s.values.size, MAX_SAMPLES), real=True)]
    settings = {"dim": int(dim), "delay": int(delay), "horizon": horizon, "theiler": theiler}
    e0 = prediction_error(v, **settings)
    rng = np.random.default_rng(seed)
    es = np.array([prediction_error(iaaft(v, rng), **settings) for _ in range(surrogates)])
    p = (1 + int(np.sum(es <= e0))) / (surrogates + 1)
    deterministic = bool(np.isfinite(e0) and np.all(es > e0))
    return xr.Dataset(
        {
            "error": ((), e0, variable("normalised prediction error")),
            "surrogate_error": (
                "surrogate",
                es,
                variable("normalised prediction error of a surrogate"),
            ),
            "p_value": (
                (),
                p,
                variable("rank p-value (one-sided: series predicted best)"),
            ),
            "deterministic": (
                (),
                np.int8(deterministic),
                variable("predicted better than every surrogate"),
            ),
            "stochastic": (
                (),
                np.int8(not deterministic),
                variable("not distinguished from linear correlated noise"),
            ),
        },
        coords={"surrogate": ("surrogate", np.arange(surrogates), {"units": "1"})},
        attrs={
            "method": "IAAFT surrogates (Schreiber & Schmitz 1996), nonlinear prediction error "
            "(Sugihara & May 1990; Kennel & Isabelle 1992), rank test (Theiler et al. 1992)",
            "seed": seed,
            "samples": v.size,
            **settings,
        },
    )
