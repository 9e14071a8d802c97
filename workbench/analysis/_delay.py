"""Delay selection for delay embeddings: first minimum of the average mutual information
(Fraser & Swinney 1986) and autocorrelation rules."""

from __future__ import annotations

import numpy as np
import xarray as xr

from workbench._attributes import variable
from workbench.analysis._series import as_series, require_samples

__all__ = ["MIN_ACF_SAMPLES", "delay_ami", "delay_acf", "mutual_information"]

#: the shortest series :func:`delay_acf` (and :func:`delay_ami`) reads a delay from: with fewer
#: samples the lags up to N // 4 are too few, and each too poorly estimated, to place one
MIN_ACF_SAMPLES = 20


def mutual_information(x: np.ndarray, lag: int, bins: int) -> float:
    """Average mutual information (nats) between x(t) and x(t + lag) from a 2-D histogram of
    ``bins`` equal cells over the range of x (one partition for both, Fraser & Swinney 1986)."""
    return float(_ami_curve(_cells(x, bins), np.array([lag]), bins)[0])


def _cells(x: np.ndarray, bins: int) -> np.ndarray:
    """Index (0..bins-1) of the equal-width cell over [min x, max x] of every sample."""
    lo, hi = float(np.min(x)), float(np.max(x))
    width = (hi - lo) / bins or 1.0
    return np.minimum(((x - lo) / width).astype(np.int64), bins - 1)


def _ami_curve(cells: np.ndarray, lags: np.ndarray, bins: int) -> np.ndarray:
    """AMI (nats) at each lag from the samples' cell indices (joint counts by bincount)."""
    out = np.empty(lags.size)
    for i, lag in enumerate(lags):
        a = cells[: cells.size - lag]
        b = cells[lag:]
        joint = np.bincount(a * bins + b, minlength=bins * bins).reshape(bins, bins)
        pxy = joint / a.size
        px, py = pxy.sum(axis=1), pxy.sum(axis=0)
        nz = pxy > 0
        out[i] = np.sum(pxy[nz] * np.log(pxy[nz] / np.outer(px, py)[nz]))
    return out


def delay_ami(
    x, *, dt: float | None = None, max_lag: int | None = None, bins: int | None = None
) -> xr.Dataset:
    """Embedding delay at the first local minimum of the average mutual information.

    Fraser & Swinney (1986), Phys. Rev. A 33, 1134. The AMI ``I(lag)`` is estimated from a
    ``bins`` x ``bins`` histogram (default sqrt(N / 5) within 16..128, so that about five samples
    fall in an occupied cell: coarser histograms flatten the first minimum, whose position then
    wanders with the noise of the estimate).

    Parameters
    ----------
    x : array or DataArray
        Scalar series (a DataArray with ``time`` gives dt), at least 20 samples.
    dt : float, optional
        Sampling step (s) of a plain array.
    max_lag : int, optional
        Largest lag tried (samples), 1 <= max_lag < N; default N // 10.
    bins : int, optional
        Histogram cells per axis (>= 2).

    Returns
    -------
    xarray.Dataset
        ``delay`` (samples) and ``delay_time`` (s, or samples without dt); the curve ``ami``
        (nats) over ``lag`` (samples), computed lag by lag until its first minimum and shown
        up to twice the delay (at least 32 lags, at most ``max_lag``); ``found`` is 0 when no
        minimum lies within ``max_lag`` (then the delay is where the AMI first falls below 1/e
        of I(0)).

    Examples
    --------
    >>> import workbench
    >>> ds = workbench.simulate({"model": {"name": "lorenz"},
    ...                          "run": {"duration": 200.0, "transient": 20.0},
    ...                          "record": {"dt": 0.01}})
    >>> 15 <= int(delay_ami(ds.x).delay) <= 19   # Lorenz x sampled at 0.01
    True
    """
    s = as_series(x, dt)
    require_samples(s, MIN_ACF_SAMPLES, "delay_ami")
    n = s.values.size
    max_lag = max(n // 10, 2) if max_lag is None else int(max_lag)
    if not 1 <= max_lag < n:
        raise ValueError(f"max_lag={max_lag!r}; allowed: 1 <= max_lag < {n} (the series length)")
    bins = int(np.clip(np.sqrt(n / 5), 16, 128)) if bins is None else int(bins)
    if bins < 2:
        raise ValueError(f"bins={bins!r}; allowed: at least 2 cells per axis")
    cells = _cells(s.values, bins)
    # lag by lag in blocks until the first local minimum: the curve beyond it is not needed
    ami = np.empty(0)
    minima = np.empty(0, dtype=np.int64)
    while ami.size <= max_lag:
        lags = np.arange(ami.size, min(max(2 * ami.size, 32), max_lag + 1))
        ami = np.concatenate([ami, _ami_curve(cells, lags, bins)])
        minima = np.flatnonzero((ami[1:-1] < ami[:-2]) & (ami[1:-1] <= ami[2:])) + 1
        if minima.size:
            break
    found = minima.size > 0
    if found:
        delay = int(minima[0])
        shown = min(max(2 * delay + 1, 33), max_lag + 1)
        if shown > ami.size:
            ami = np.concatenate([ami, _ami_curve(cells, np.arange(ami.size, shown), bins)])
        ami = ami[:shown]
    else:
        below = np.flatnonzero(ami < ami[0] / np.e)
        delay = int(below[0]) if below.size else int(max_lag)
    lags = np.arange(ami.size)
    return xr.Dataset(
        {
            "delay": ((), delay, variable("embedding delay (samples)")),
            "delay_time": ((), delay * s.dt, variable("delay", s.time_units)),
            "ami": ("lag", ami, variable("average mutual information", "nat")),
            "found": ((), int(found), variable("a first minimum was found")),
        },
        coords={"lag": ("lag", lags, variable("lag (samples)"))},
        attrs={"method": "first minimum of AMI (Fraser & Swinney 1986)", "bins": bins},
    )


def delay_acf(x, *, dt: float | None = None, rule: str = "1/e", max_lag: int | None = None):
    """Embedding delay from the autocorrelation function: first lag where it falls below 1/e
    (``rule="1/e"``) or crosses zero (``rule="zero"``).

    Parameters
    ----------
    x : array or DataArray
        Scalar series (a DataArray with ``time`` gives dt), at least :data:`MIN_ACF_SAMPLES`
        samples (as :func:`delay_ami` needs) and not constant.
    dt : float, optional
        Sampling step (s) of a plain array.
    rule : {"1/e", "zero"}
        Where the delay is read off the autocorrelation.
    max_lag : int, optional
        Largest lag tried (samples), 1 <= max_lag < N; default N // 4.

    Returns
    -------
    xarray.Dataset
        ``delay`` (samples), ``delay_time`` and the curve ``acf`` over ``lag``.

    Raises
    ------
    ValueError
        The series is shorter than :data:`MIN_ACF_SAMPLES` (an empty one too), constant (its
        autocorrelation is undefined), or ``max_lag`` or ``rule`` is out of range.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(4000) * 0.05
    >>> int(delay_acf(np.sin(t), rule="zero").delay) in range(29, 34)   # quarter period
    True
    """
    if rule not in ("1/e", "zero"):
        raise ValueError(f"rule={rule!r}; allowed: '1/e' or 'zero'")
    s = as_series(x, dt)
    require_samples(s, MIN_ACF_SAMPLES, "delay_acf")
    v = s.values - s.values.mean()
    n = v.size
    max_lag = max(n // 4, 2) if max_lag is None else int(max_lag)
    if not 1 <= max_lag < n:
        raise ValueError(f"max_lag={max_lag!r}; allowed: 1 <= max_lag < {n} (the series length)")
    f = np.fft.rfft(v, 2 * n)
    acf = np.fft.irfft(f * np.conj(f))[: max_lag + 1]
    if not acf[0] > 0:
        raise ValueError(
            f"x ({s.name!r}) is constant: its autocorrelation is undefined, and so is a delay "
            "read from it"
        )
    acf = acf / acf[0]
    level = 1 / np.e if rule == "1/e" else 0.0
    below = np.flatnonzero(acf <= level)
    delay = int(below[0]) if below.size else int(max_lag)
    return xr.Dataset(
        {
            "delay": ((), delay, variable("embedding delay (samples)")),
            "delay_time": ((), delay * s.dt, variable("delay", s.time_units)),
            "acf": ("lag", acf, variable("autocorrelation")),
        },
        coords={"lag": ("lag", np.arange(max_lag + 1), variable("lag"))},
        attrs={"method": f"autocorrelation below {rule}"},
    )
