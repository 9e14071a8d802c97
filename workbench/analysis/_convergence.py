"""When an exponent estimated over a finite window has converged, and what to say when it has not.

An exponent from the equations is a time average over a chaotic trajectory: its knobs
(tolerance, separation, renormalisation) move it by their bias, and the finite window by its
statistical error, which no knob variant on the same trajectory shows. The error is taken from
batch means (the window cut into ``BATCHES`` consecutive blocks whose mean rates are treated
as independent samples; e.g. Flyvbjerg & Petersen 1989), the estimators grow their window
until it meets a relative error target within a budget, and an estimate is ``converged`` only
where every condition holds; otherwise the estimate names the ones that failed and warns
(:class:`ConvergenceWarning`). Estimates from several independent starts (realisations of the
same window) are pooled by :func:`pooled`, whose error is also the starts' spread.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

__all__ = [
    "BATCHES",
    "BUDGET",
    "TARGET",
    "TRUST",
    "ConvergenceWarning",
    "agree",
    "batch_error",
    "judge",
    "pooled",
]

#: batch means of the standard error
BATCHES = 10
#: default relative standard error of the largest exponent the window grows to reach
TARGET = 0.03
#: default budget: the window grows (doubling) to at most this many times the requested length
BUDGET = 8
#: a value whose standard error exceeds this fraction of it is never trusted
TRUST = 0.2


class ConvergenceWarning(UserWarning):
    """An estimate stopped before its convergence conditions held (the window's budget was
    spent, or its tolerance check disagreed); the message names the conditions that failed."""


def batch_error(times: np.ndarray, contributions: np.ndarray, start: float) -> np.ndarray:
    """Standard error of a rate from ``BATCHES`` batch means of its per-interval
    ``contributions`` (e.g. log growths over the intervals ending at ``times``, s, from
    ``start``), per column; NaN with fewer than two batches."""
    edges = np.linspace(start, times[-1], BATCHES + 1)
    idx = np.clip(np.searchsorted(edges, times, side="left") - 1, 0, BATCHES - 1)
    lam = []
    prev = np.concatenate([[start], times[:-1]])
    for b in range(BATCHES):
        sel = idx == b
        if sel.any():
            dur = float(np.sum(times[sel] - prev[sel]))
            lam.append(contributions[sel].sum(axis=0) / dur)
    lam = np.array(lam)
    if lam.shape[0] < 2:
        return np.full(contributions.shape[1:], np.nan)
    return lam.std(axis=0, ddof=1) / math.sqrt(lam.shape[0])


def pooled(rates: np.ndarray, errors: np.ndarray) -> tuple[float, float, float, float]:
    """Pool the rates of independent starts over windows of equal length (``rates``, one per
    start, e.g. s-1) with their own batch-means standard ``errors``: ``(mean, stderr,
    stderr_starts, stderr_batches)``. ``stderr_starts`` is the spread across the starts, std
    (ddof 1) / sqrt(S), free of any correlation between a start's batches but itself noisy
    with few starts (NaN for one); ``stderr_batches`` is sqrt(sum of errors^2) / S, the starts'
    batch means combined; ``stderr`` is the larger of the two (the batch means alone where
    there is one start).

    >>> m, e, es, eb = pooled(np.array([1.0, 3.0]), np.array([0.1, 0.1]))
    >>> m, round(e, 3), round(es, 3), round(eb, 3)
    (2.0, 1.0, 1.0, 0.071)
    """
    rates = np.asarray(rates, dtype=float)
    errors = np.asarray(errors, dtype=float)
    s = rates.size
    mean = float(rates.mean())
    batches = float(math.sqrt(np.sum(errors**2)) / s)
    starts = float(rates.std(ddof=1) / math.sqrt(s)) if s > 1 else math.nan
    return mean, (batches if s == 1 else max(starts, batches)), starts, batches


def agree(a, b, err_a, err_b, *, sigmas: float = 2.0):
    """Whether estimates ``a`` and ``b`` with standard errors ``err_a`` and ``err_b`` agree
    within ``sigmas`` standard errors of their difference (False where an error is NaN)."""
    return np.abs(np.asarray(a) - np.asarray(b)) <= sigmas * np.hypot(err_a, err_b)


def judge(conditions: dict[str, tuple[bool, str]], what: str) -> tuple[bool, str]:
    """``converged`` (all ``conditions`` hold: name -> (holds, what it measured)) and the text
    of those that failed, one per line; warns with that text when any failed."""
    failed = [f"{name}: {text}" for name, (ok, text) in conditions.items() if not ok]
    if failed:
        warnings.warn(
            f"{what} has not converged:\n" + "\n".join(failed), ConvergenceWarning, stacklevel=3
        )
    return not failed, "\n".join(failed)
