"""Delay embedding and the choice of its dimension: false nearest neighbours (Kennel, Brown &
Abarbanel 1992) and Cao's E1/E2 (Cao 1997)."""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy.spatial import cKDTree

from workbench.analysis._series import as_series

__all__ = ["embed", "embedding_fnn", "embedding_cao", "nearest_neighbours"]


def embed(x: np.ndarray, dim: int, delay: int) -> np.ndarray:
    """Delay vectors ``[x_i, x_{i+delay}, ..., x_{i+(dim-1) delay}]``, shape (N - (dim-1) delay,
    dim); a view, no copy."""
    n = x.size - (dim - 1) * delay
    if n < 2:
        raise ValueError(
            f"series of {x.size} samples too short for dim={dim}, delay={delay}: use a longer "
            "record or a smaller dimension or delay"
        )
    stride = x.strides[0]
    return np.lib.stride_tricks.as_strided(x, (n, dim), (stride, delay * stride), writeable=False)


def nearest_neighbours(Y: np.ndarray, theiler: int, p: float = 2) -> tuple[np.ndarray, np.ndarray]:
    """Index and distance of each point's nearest neighbour at least ``theiler`` samples away in
    time (KD-tree, O(N log N), memory O(N); ``p``: Minkowski norm, inf for the max norm)."""
    tree = cKDTree(Y)
    n = Y.shape[0]
    idx = np.full(n, -1)
    dist = np.full(n, np.inf)
    k = 2 * theiler + 2
    todo = np.arange(n)
    while todo.size:
        kk = min(k, n)
        d, j = tree.query(Y[todo], k=kk, p=p, workers=-1)
        ok = np.abs(j - todo[:, None]) > theiler
        ok &= d > 0
        has = ok.any(axis=1)
        first = np.argmax(ok, axis=1)
        sel = todo[has]
        idx[sel] = j[has, first[has]]
        dist[sel] = d[has, first[has]]
        if kk == n:
            break
        todo = todo[~has]
        k *= 4
    return idx, dist


def _theiler_default(delay: int) -> int:
    return max(1, delay)


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
):
    """Embedding dimension by false nearest neighbours (Kennel, Brown & Abarbanel 1992, Phys.
    Rev. A 45, 3403): a neighbour in d dimensions is false if adding the (d+1)-th coordinate
    moves it more than ``rtol`` times their distance, or farther than ``atol`` times the
    series' standard deviation. The dimension is the first d whose fraction of false
    neighbours is below ``threshold``.

    Returns an ``xarray.Dataset`` with ``dim`` and the curve ``fnn_fraction`` over
    ``dimension``.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(3000) * 0.1
    >>> int(embedding_fnn(np.sin(t), delay=15).dim)   # a circle needs two dimensions
    2
    """
    s = as_series(x, dt)
    v = s.values
    theiler = _theiler_default(delay) if theiler is None else theiler
    sd = float(np.std(v))
    dims = np.arange(1, max_dim + 1)
    fractions = np.full(dims.size, np.nan)
    for i, d in enumerate(dims):
        Y = embed(v, int(d), delay)[: v.size - int(d) * delay]  # points with a (d+1)-th coordinate
        j, r = nearest_neighbours(Y, theiler)
        valid = j >= 0
        a, b = np.flatnonzero(valid), j[valid]
        extra = np.abs(v[a + d * delay] - v[b + d * delay])
        r = r[valid]
        r1 = np.sqrt(r**2 + extra**2)
        false = (extra > rtol * r) | (r1 > atol * sd)
        fractions[i] = float(false.mean()) if false.size else np.nan
        if fractions[i] < threshold:
            break
    below = np.flatnonzero(fractions < threshold)
    dim = int(dims[below[0]]) if below.size else int(dims[np.nanargmin(fractions)])
    return xr.Dataset(
        {
            "dim": ((), dim, {"units": "1", "long_name": "embedding dimension"}),
            "fnn_fraction": (
                "dimension",
                fractions,
                {"units": "1", "long_name": "fraction of false nearest neighbours"},
            ),
        },
        coords={"dimension": ("dimension", dims, {"units": "1", "long_name": "dimension"})},
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
    saturation: float = 0.9,
    dt: float | None = None,
):
    """Embedding dimension by Cao's method (Cao 1997, Physica D 110, 43): E1(d) = E(d+1)/E(d)
    stops changing (reaches ``saturation``) once d + 1 is a sufficient dimension; E2(d) stays
    near 1 for all d for random data. E1(d) has saturated for every d > d0, and d0 + 1 is the
    dimension: ``dim`` is the first d with E1(d) >= ``saturation``. Also the curves ``E1``,
    ``E2`` over ``dimension``.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(3000) * 0.1
    >>> int(embedding_cao(np.sin(t), delay=15).dim) <= 3
    True
    """
    s = as_series(x, dt)
    v = s.values
    theiler = _theiler_default(delay) if theiler is None else theiler
    dims = np.arange(1, max_dim + 1)
    E = np.full(dims.size + 1, np.nan)
    Es = np.full(dims.size + 1, np.nan)
    for i, d in enumerate(np.arange(1, max_dim + 2)):
        Y = embed(v, int(d), delay)[: v.size - int(d) * delay]
        j, r = nearest_neighbours(Y, theiler, p=np.inf)
        ok = (j >= 0) & (r > 0)
        a, b = np.flatnonzero(ok), j[ok]
        extra = np.abs(v[a + d * delay] - v[b + d * delay])
        r_next = np.maximum(r[ok], extra)
        E[i] = float(np.mean(r_next / r[ok]))
        Es[i] = float(np.mean(extra))
    E1 = E[1:] / E[:-1]
    E2 = Es[1:] / Es[:-1]
    sat = np.flatnonzero(E1 >= saturation)
    # E1(d) >= saturation for d > d0 means d0 + 1 suffices (Cao 1997): the first such d
    dim = int(dims[sat[0]]) if sat.size else int(max_dim)
    return xr.Dataset(
        {
            "dim": ((), dim, {"units": "1", "long_name": "embedding dimension"}),
            "E1": ("dimension", E1, {"units": "1", "long_name": "Cao E1(d) = E(d+1)/E(d)"}),
            "E2": ("dimension", E2, {"units": "1", "long_name": "Cao E2(d) = E*(d+1)/E*(d)"}),
        },
        coords={"dimension": ("dimension", dims, {"units": "1", "long_name": "dimension d"})},
        attrs={"method": "Cao (1997)", "delay": delay, "theiler": theiler},
    )
