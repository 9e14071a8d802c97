"""Ensemble statistics of a study: medians, quartiles and the rank tests its verdicts rest on.

A chaotic run's peak is one sample of a distribution. A study therefore runs every case as an
ensemble of realisations (:mod:`workbench.run._ensemble`) and decides a comparison only where the
difference exceeds the ensemble's own scatter:

- two samples (e.g. peaks of case a and case b): the two-sided Mann-Whitney U test
  (:func:`scipy.stats.mannwhitneyu`) at level :data:`ALPHA`; where it rejects equality, the
  sign of the difference of the medians says which is larger;
- one sample against zero (e.g. Wolf LLEs): the two-sided Wilcoxon signed-rank test
  (:func:`scipy.stats.wilcoxon`) at the same level, and the sign of the median.

With fewer than 4 realisations per side no outcome of the two-sample test reaches p < 0.05:
such a comparison is always "not resolved".
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

__all__ = ["ALPHA", "describe", "compare_samples", "sign_test_zero", "VERDICTS"]

ALPHA = 0.05
VERDICTS = ("reproduced", "contradicted", "not resolved", "undecided")


def _finite(values: Sequence[float]) -> np.ndarray:
    x = np.asarray(values, dtype=float).ravel()
    return x[np.isfinite(x)]


def describe(values: Sequence[float]) -> dict:
    """Median, quartiles, extremes and count of the finite values (units of the values).

    Returns ``{"median", "q25", "q75", "min", "max", "n"}`` (NaN statistics and n = 0 when no
    value is finite).

    Examples
    --------
    >>> describe([1.0, 2.0, 3.0, 4.0, float("nan")])["median"], describe([1.0, 2.0])["n"]
    (2.5, 2)
    """
    x = _finite(values)
    if x.size == 0:
        nan = float("nan")
        return {"median": nan, "q25": nan, "q75": nan, "min": nan, "max": nan, "n": 0}
    q25, med, q75 = np.percentile(x, [25, 50, 75])
    return {
        "median": float(med),
        "q25": float(q25),
        "q75": float(q75),
        "min": float(x.min()),
        "max": float(x.max()),
        "n": int(x.size),
    }


def compare_samples(larger: Sequence[float], smaller: Sequence[float]) -> dict:
    """Is ``larger`` larger than ``smaller`` beyond the scatter of both?

    Parameters
    ----------
    larger, smaller : sequence of float
        The samples the claim expects to be larger and smaller (NaN ignored).

    Returns
    -------
    dict
        ``verdict``: ``"reproduced"`` (p < ALPHA and median(larger) > median(smaller)),
        ``"contradicted"`` (p < ALPHA and the opposite), ``"not resolved"`` (p >= ALPHA, or
        equal medians) or ``"undecided"`` (a sample is empty); ``p_value`` (two-sided
        Mann-Whitney U, 1 when both samples are the same constant), ``median_difference``
        (median(larger) - median(smaller)), and :func:`describe` of each sample.

    Examples
    --------
    >>> compare_samples([10, 11, 12, 13], [1, 2, 3, 4])["verdict"]
    'reproduced'
    >>> compare_samples([1, 5, 2, 6], [4, 3, 7, 0])["verdict"]
    'not resolved'
    """
    from scipy.stats import mannwhitneyu

    a, b = _finite(larger), _finite(smaller)
    out = {"larger": describe(a), "smaller": describe(b)}
    if a.size == 0 or b.size == 0:
        return out | {"verdict": "undecided", "p_value": math.nan, "median_difference": math.nan}
    diff = float(np.median(a) - np.median(b))
    if np.ptp(np.concatenate([a, b])) == 0:
        p = 1.0  # every value the same: no evidence of a difference
    else:
        p = float(mannwhitneyu(a, b, alternative="two-sided").pvalue)
    if p < ALPHA and diff != 0:
        verdict = "reproduced" if diff > 0 else "contradicted"
    else:
        verdict = "not resolved"
    return out | {"verdict": verdict, "p_value": p, "median_difference": diff}


def sign_test_zero(values: Sequence[float]) -> dict:
    """Is the median of ``values`` different from zero beyond their scatter?

    Returns ``{"sign", "p_value", "stats"}``: ``sign`` +1 or -1 where the two-sided Wilcoxon
    signed-rank test rejects a zero median at level ALPHA (the sign of the median), 0 where it
    does not (or no value is finite); ``stats`` is :func:`describe` of the values.

    Examples
    --------
    >>> sign_test_zero([0.5, 0.7, 0.6, 0.9, 1.1, 0.8])["sign"]
    1
    >>> sign_test_zero([0.5, -0.7, 0.6, -0.9])["sign"]
    0
    """
    from scipy.stats import wilcoxon

    x = _finite(values)
    stats = describe(x)
    if x.size == 0 or not np.any(x != 0):
        return {"sign": 0, "p_value": math.nan if x.size == 0 else 1.0, "stats": stats}
    p = float(wilcoxon(x, alternative="two-sided").pvalue)
    sign = int(np.sign(np.median(x))) if p < ALPHA else 0
    return {"sign": sign, "p_value": p, "stats": stats}
