"""Do two runs at one parameter value lie on the same attractor? The seam check of a continued
sweep: the previous segment's continued run at a seam point against the next segment's run
there, started by brute force ``overlap`` points earlier.

Each run is a cloud of records in the space of the recorded variables (every component of a
variable over the model's dims is a coordinate), each coordinate divided by its range over the
whole line (so the test does not depend on units). The clouds agree when the mean distance from
a record of one to the nearest record of the other (both ways, averaged) is at most
``tolerance`` plus twice the mean nearest-neighbour distance *within* the clouds: two samples of
one periodic orbit are ~0 apart, two finite samples of one chaotic attractor about as far as
their own records are from each other, two different attractors (another period, another
branch of a hysteresis loop) much further.
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy.spatial import cKDTree

__all__ = ["attractor_distance", "cloud", "line_scale"]


def cloud(ds: xr.Dataset, variables, point_dim: str, flat: int, time_dim: str) -> np.ndarray:
    """The records of point ``flat`` (over ``point_dim``) as rows: one column per component of
    each variable; rows with a NaN dropped."""
    sel = {point_dim: flat}
    cols = []
    for name in variables:
        v = ds[name].sel(sel)
        v = v.transpose(time_dim, ...).values
        cols.append(v.reshape(v.shape[0], -1))
    rows = np.concatenate(cols, axis=1)
    return rows[np.isfinite(rows).all(axis=1)]


def line_scale(clouds: list[np.ndarray]) -> np.ndarray:
    """Range of each column over a line's clouds (1 where a column does not vary)."""
    stacked = np.concatenate([c for c in clouds if c.size], axis=0)
    span = np.nanmax(stacked, axis=0) - np.nanmin(stacked, axis=0)
    return np.where(np.isfinite(span) & (span > 0), span, 1.0)


def _nearest(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.mean(cKDTree(b).query(a)[0]))


def _within(a: np.ndarray) -> float:
    if len(a) < 2:
        return 0.0
    return float(np.mean(cKDTree(a).query(a, k=2)[0][:, 1]))


def attractor_distance(a: np.ndarray, b: np.ndarray, scale: np.ndarray) -> tuple[float, float]:
    """(cross, within): the mean nearest-record distance between clouds ``a`` and ``b`` (both
    ways, averaged) and within each (averaged), in units of ``scale`` per column; NaN when a
    cloud is empty (a failed run)."""
    if len(a) == 0 or len(b) == 0:
        return float("nan"), float("nan")
    a, b = a / scale, b / scale
    cross = 0.5 * (_nearest(a, b) + _nearest(b, a))
    return cross, 0.5 * (_within(a) + _within(b))
