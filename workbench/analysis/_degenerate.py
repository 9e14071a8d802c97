"""Series with nothing to analyse: constant, constant to rounding, parked at one value, or a few
repeated values. Said at once, before any estimator builds a neighbour search on them (whose
exact duplicates made one take minutes and then fail with "scale_max = 0")."""

from __future__ import annotations

import numpy as np

from workbench.analysis._series import Series, as_series

__all__ = ["no_dynamics", "series_without_dynamics"]

#: a range within this many units in the last place of the series' magnitude is rounding
ROUNDING_ULPS = 1000
#: one value held by more than this share of the samples: the series is parked there
MOST_COMMON_SHARE = 0.5
#: fewer distinct values than this: a periodic orbit of a map or a coarsely quantised record
MIN_DISTINCT = 16


def no_dynamics(x, dt: float | None = None) -> str | None:
    """Why a series has no dynamics to analyse, in one sentence, or None if it may have some.

    A series has none when it is constant; when its range is within 1000 units in the last
    place of its magnitude (rounding, e.g. a computed constant); when one value holds more than
    half of its samples (a variable parked at a value, e.g. a contact force that is zero while
    the contact is open, or a constant with rare departures); or when it takes fewer than 16
    distinct values, each repeated (four times or more on average: a periodic orbit of a map,
    or a coarsely quantised record). A series too short for these to mean anything is left to
    the estimators' own length checks. Delay
    embeddings of such series are made of exact copies of a few points: neighbours cannot be
    followed and no exponent, dimension or delay can be estimated.

    Parameters
    ----------
    x : array or DataArray
        The scalar series (a DataArray gives its name and units to the sentence).
    dt : float, optional
        Sampling step (s) of a plain array (not needed for the verdict).

    Examples
    --------
    >>> no_dynamics(np.full(3001, 0.25))
    'x is constant (0.25 at all 3001 samples): no dynamics to analyse'
    >>> no_dynamics(np.sin(0.1 * np.arange(1000))) is None
    True
    """
    return series_without_dynamics(as_series(x, dt))


def series_without_dynamics(s: Series) -> str | None:
    """:func:`no_dynamics` of a :class:`~workbench.analysis._series.Series`."""
    v = s.values
    n = v.size
    unit = "" if s.units in ("1", "") else f" {s.units}"
    if n == 0:
        return f"{s.name} is empty: no dynamics to analyse"
    lo, hi = float(v.min()), float(v.max())
    if lo == hi:
        return f"{s.name} is constant ({lo:g}{unit} at all {n} samples): no dynamics to analyse"
    scale = max(abs(lo), abs(hi))
    if hi - lo <= ROUNDING_ULPS * np.spacing(scale):
        return (
            f"{s.name} varies only at the rounding level of its values (range {hi - lo:.3g}"
            f"{unit} about {scale:.6g}{unit}, within {ROUNDING_ULPS} units in the last place): "
            "no dynamics to analyse"
        )
    values, counts = np.unique(v, return_counts=True)
    top = int(np.argmax(counts))
    share = counts[top] / n
    if share > MOST_COMMON_SHARE:
        return (
            f"{s.name} sits at {values[top]:g}{unit} at {counts[top]} of its {n} samples "
            "(a variable parked at one value, or a constant with rare departures): no motion "
            "for an embedding to follow; analyse a variable that moves"
        )
    if values.size < MIN_DISTINCT and n >= 4 * values.size:  # each value repeated
        return (
            f"{s.name} takes only {values.size} distinct values over {n} samples (a periodic "
            "orbit of a map, or a coarsely quantised record): no dynamics an embedding can "
            "resolve"
        )
    return None
