"""Delay embedding and the choice of its dimension: false nearest neighbours (Kennel, Brown &
Abarbanel 1992) and Cao's E1/E2 (Cao 1997)."""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy.spatial import cKDTree

from workbench._attributes import variable
from workbench.analysis._degenerate import series_without_dynamics
from workbench.analysis._series import as_series, require_samples

__all__ = ["embed", "embedding_fnn", "embedding_cao", "nearest_neighbours"]

#: the false-neighbour statistics are averages over reference points: this many, evenly spread
#: over the series, give them to about +-1 % (binomial error of a fraction) at a fraction of the
#: cost of querying every point
REFERENCE_POINTS = 4000


def embed(x: np.ndarray, dim: int, delay: int) -> np.ndarray:
    """Delay vectors ``[x_i, x_{i+delay}, ..., x_{i+(dim-1) delay}]``, shape (N - (dim-1) delay,
    dim); a view, no copy.

    Examples
    --------
    >>> embed(np.arange(5.0), 2, 2).tolist()
    [[0.0, 2.0], [1.0, 3.0], [2.0, 4.0]]
    """
    if int(dim) < 1 or int(delay) < 1:
        raise ValueError(f"dim={dim!r}, delay={delay!r}; allowed: dim >= 1 and delay >= 1")
    x = np.ascontiguousarray(x, dtype=float)
    n = x.size - (dim - 1) * delay
    if n < 2:
        raise ValueError(
            f"series of {x.size} samples too short for dim={dim}, delay={delay}: use a longer "
            "record or a smaller dimension or delay"
        )
    stride = x.strides[0]
    return np.lib.stride_tricks.as_strided(x, (n, dim), (stride, delay * stride), writeable=False)


def nearest_neighbours(
    Y: np.ndarray, theiler: int, p: float = 2, query: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Index and distance of the nearest neighbour at least ``theiler`` + 1 samples away in
    time of each point (of the points ``query`` if given) among all rows of ``Y`` (KD-tree,
    O(N log N), memory O(N); ``p``: Minkowski norm, inf for the max norm); -1 and inf where
    there is none."""
    tree = cKDTree(Y)
    n = Y.shape[0]
    todo = np.arange(n) if query is None else np.asarray(query, dtype=np.int64)
    idx = np.full(todo.size, -1)
    dist = np.full(todo.size, np.inf)
    pos = np.arange(todo.size)
    # most points find a neighbour on another strand among a few nearest: start small and ask
    # more only for the points that did not (the samples of their own strand crowd them)
    k = min(2 * theiler + 2, 12)
    while todo.size:
        kk = min(k, n)
        d, j = tree.query(Y[todo], k=kk, p=p)
        ok = np.abs(j - todo[:, None]) > theiler
        ok &= d > 0
        has = ok.any(axis=1)
        first = np.argmax(ok, axis=1)
        idx[pos[has]] = j[has, first[has]]
        dist[pos[has]] = d[has, first[has]]
        if kk == n:
            break
        todo, pos = todo[~has], pos[~has]
        k *= 4
    return idx, dist


def _theiler_default(delay: int) -> int:
    return max(1, delay)


def _reference_points(n: int, points: int | None) -> np.ndarray | None:
    """Evenly spread indices of at most ``points`` of ``n`` rows (None: all of them)."""
    if points is None or points >= n:
        return None
    return np.unique(np.linspace(0, n - 1, points).astype(np.int64))


def _check_embedding_args(s, delay: int, max_dim: int, what: str) -> None:
    if int(delay) < 1:
        raise ValueError(f"delay={delay!r}; allowed: a whole number of samples >= 1")
    if int(max_dim) < 1:
        raise ValueError(f"max_dim={max_dim!r}; allowed: a whole number >= 1")
    require_samples(s, max_dim * delay + 20, f"{what} with delay={delay}, max_dim={max_dim}")
    problem = series_without_dynamics(s)
    if problem:  # exact copies of a few points: neighbours would be searched for minutes
        raise ValueError(problem)


def _added_coordinate(
    v: np.ndarray, d: int, delay: int, theiler: int, points: int | None, p: float
) -> tuple[np.ndarray, np.ndarray]:
    """What the (d+1)-th delay coordinate adds to nearest neighbours in d dimensions.

    Over the reference points of the d-dimensional embedding that have a (d+1)-th coordinate
    (:func:`_reference_points`), each with a nearest neighbour more than ``theiler`` samples
    away (norm ``p``): their distance in d dimensions and the distance of the (d+1)-th
    coordinates."""
    Y = embed(v, d, delay)[: v.size - d * delay]  # points with a (d+1)-th coordinate
    ref = _reference_points(Y.shape[0], points)
    j, r = nearest_neighbours(Y, theiler, p=p, query=ref)
    a = np.arange(Y.shape[0]) if ref is None else ref
    valid = j >= 0
    a, b = a[valid], j[valid]
    return r[valid], np.abs(v[a + d * delay] - v[b + d * delay])


def embedding_fnn(
    x,
    *,
    delay: int,
    max_dim: int = 10,
    rtol: float = 10.0,
    atol: float = 2.0,
    theiler: int | None = None,
    threshold: float = 0.01,
    dt: float | None = None,
    points: int | None = REFERENCE_POINTS,
) -> xr.Dataset:
    """Embedding dimension by false nearest neighbours (Kennel, Brown & Abarbanel 1992, Phys.
    Rev. A 45, 3403): a neighbour in d dimensions is false if adding the (d+1)-th coordinate
    moves it more than ``rtol`` times their distance, or farther than ``atol`` times the
    series' standard deviation. The dimension is the first d whose fraction of false
    neighbours is below ``threshold``; where it levels off above it (noise, or few points:
    neighbours far apart fail the second test; Kennel et al. 1992, Sec. IV), the first d within
    ``threshold`` of its smallest value. (The smallest value itself can lie anywhere on the
    plateau, and Wolf's estimate in a dimension at its far end can fail: docs/analysis.md, "The
    Wolf estimate, in three stages".)

    The fraction is taken over ``points`` reference points evenly spread over the series (all
    of them if None), each with its nearest neighbour among all points more than ``theiler``
    samples away in time (default: the delay).

    Returns
    -------
    xarray.Dataset
        ``dim`` and the curve ``fnn_fraction`` over ``dimension`` (NaN beyond the first
        dimension below the threshold: not computed).

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(3000) * 0.1
    >>> int(embedding_fnn(np.sin(t), delay=15).dim)   # a circle needs two dimensions
    2
    """
    s = as_series(x, dt)
    _check_embedding_args(s, delay, max_dim, "embedding_fnn")
    v = s.values
    theiler = _theiler_default(delay) if theiler is None else theiler
    sd = float(np.std(v))
    dims = np.arange(1, max_dim + 1)
    fractions = np.full(dims.size, np.nan)
    for i, d in enumerate(dims):
        r, extra = _added_coordinate(v, int(d), delay, theiler, points, 2)
        r1 = np.sqrt(r**2 + extra**2)
        false = (extra > rtol * r) | (r1 > atol * sd)
        fractions[i] = float(false.mean()) if false.size else np.nan
        if fractions[i] < threshold:
            break
    below = np.flatnonzero(fractions < threshold)
    if not below.size:  # the fraction levels off above the threshold: where it reaches its floor
        below = np.flatnonzero(fractions <= np.nanmin(fractions) + threshold)
    dim = int(dims[below[0]])
    return xr.Dataset(
        {
            "dim": ((), dim, variable("embedding dimension")),
            "fnn_fraction": (
                "dimension",
                fractions,
                variable("fraction of false nearest neighbours"),
            ),
        },
        coords={"dimension": ("dimension", dims, variable("dimension"))},
        attrs={
            "method": "false nearest neighbours (Kennel et al. 1992)",
            "delay": delay,
            "rtol": rtol,
            "atol": atol,
            "theiler": theiler,
            "threshold": threshold,
        },
    )


def embedding_cao(
    x,
    *,
    delay: int,
    max_dim: int = 10,
    theiler: int | None = None,
    saturation: float = 0.75,
    dt: float | None = None,
    points: int | None = REFERENCE_POINTS,
) -> xr.Dataset:
    """Embedding dimension by Cao's method (Cao 1997, Physica D 110, 43).

    E(d) is the mean ratio by which the distance of each point to its nearest neighbour (max
    norm) grows when the (d+1)-th delay coordinate is added; E1(d) = E(d+1)/E(d) "stops
    changing when d is greater than some value d0 if the time series comes from an
    attractor. Then d0 + 1 is the minimum embedding dimension" (Cao 1997, Sec. 2). Read
    here as: ``dim`` is the first d at which E1 has reached ``saturation`` times its plateau
    (the median of the upper half of its values, about 1). A fixed level (E1 >= 0.9) is
    fragile: on Rossler x (a = b = 0.2, c = 5.7, 10 000 points, delay at the first AMI minimum)
    E1(3) lies close to 0.9, above it in some series and below it in others, so that 4 or 3
    came out by chance, while E1(2) is far below the plateau. E2(d) =
    E*(d+1)/E*(d), from the distances of the next samples alone, stays near 1 at every d for a
    stochastic series (Cao 1997, Sec. 3).

    The averages are taken over ``points`` reference points evenly spread over the series (all
    of them if None), each with its nearest neighbour among all points more than ``theiler``
    samples away in time (default: the delay).

    Returns
    -------
    xarray.Dataset
        ``dim``; the curves ``E1`` and ``E2`` over ``dimension``.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(3000) * 0.1
    >>> int(embedding_cao(np.sin(t), delay=15).dim) <= 3
    True
    """
    s = as_series(x, dt)
    _check_embedding_args(s, delay, max_dim + 1, "embedding_cao")
    if not 0 < saturation <= 1:
        raise ValueError(f"saturation={saturation!r}; allowed: 0 < saturation <= 1")
    v = s.values
    theiler = _theiler_default(delay) if theiler is None else theiler
    dims = np.arange(1, max_dim + 1)
    E = np.full(dims.size + 1, np.nan)
    Es = np.full(dims.size + 1, np.nan)
    for i, d in enumerate(np.arange(1, max_dim + 2)):
        r, extra = _added_coordinate(v, int(d), delay, theiler, points, np.inf)
        ok = r > 0
        r, extra = r[ok], extra[ok]
        r_next = np.maximum(r, extra)
        E[i] = float(np.mean(r_next / r))
        Es[i] = float(np.mean(extra))
    E1 = E[1:] / E[:-1]
    E2 = Es[1:] / Es[:-1]
    finite = E1[np.isfinite(E1)]
    plateau = float(np.median(finite[finite >= np.median(finite)])) if finite.size else np.nan
    sat = np.flatnonzero(E1 >= saturation * plateau)
    dim = int(dims[sat[0]]) if sat.size else int(max_dim)
    return xr.Dataset(
        {
            "dim": ((), dim, variable("embedding dimension")),
            "E1": ("dimension", E1, variable("Cao E1(d) = E(d+1)/E(d)")),
            "E2": ("dimension", E2, variable("Cao E2(d) = E*(d+1)/E*(d)")),
        },
        coords={"dimension": ("dimension", dims, variable("dimension d"))},
        attrs={
            "method": "Cao (1997)",
            "delay": delay,
            "theiler": theiler,
            "saturation": saturation,
            "E1_plateau": plateau,
        },
    )
