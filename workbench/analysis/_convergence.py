"""When an exponent estimated over a finite window has converged, and what to say when it has not.

An exponent from the equations is a time average over a chaotic trajectory: its knobs
(tolerance, separation, renormalisation) move it by their bias, and the finite window by its
statistical error, which no knob variant on the same trajectory shows. The error is taken from
batch means (the window cut into ``BATCHES`` consecutive blocks whose mean rates are treated
as independent samples; e.g. Flyvbjerg & Petersen 1989), the estimators grow their window
until it meets a relative error target within a budget, and an estimate is ``converged`` only
where every condition holds; otherwise the estimate names the ones that failed and warns
(:class:`ConvergenceWarning`).
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
