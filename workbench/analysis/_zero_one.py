"""The 0-1 test for chaos (Gottwald & Melbourne 2004, Proc. R. Soc. A 460, 603; the correlation
method of Gottwald & Melbourne 2009, SIAM J. Appl. Dyn. Syst. 8, 129)."""

from __future__ import annotations

import numpy as np
import xarray as xr

from workbench._attributes import variable
from workbench.analysis._series import as_series

__all__ = ["zero_one_test"]


def zero_one_test(x, *, n_c: int = 100, seed: int = 0) -> xr.Dataset:
    """K near 0 for regular, near 1 for chaotic dynamics, from a series without embedding.

    For random c in (pi/5, 4 pi/5) the translation variables p_c, q_c are built from x; K_c is
    the correlation of the modified mean-square displacement D_c(n) with n (n <= N/10); K is the
    median over ``n_c`` values of c. Apply it to a coarsely sampled series (e.g. stroboscopic
    samples): oversampled flows give K near 0 even when chaotic (Gottwald & Melbourne 2009).

    Returns an ``xarray.Dataset`` with ``K`` and ``K_c`` over ``c``.

    Examples
    --------
    >>> import numpy as np
    >>> x = np.empty(2000); x[0] = 0.3
    >>> for i in range(1999): x[i + 1] = 3.97 * x[i] * (1 - x[i])    # chaotic logistic map
    >>> float(zero_one_test(x).K) > 0.9
    True
    >>> float(zero_one_test(np.sin(0.7 * np.arange(2000))).K) < 0.1
    True
    """
    s = as_series(x)
    phi = s.values - s.values.mean()
    n = phi.size
    if n < 100:
        raise ValueError(f"the 0-1 test needs at least 100 samples, got {n}")
    ncut = n // 10
    rng = np.random.default_rng(seed)
    cs = np.sort(rng.uniform(np.pi / 5, 4 * np.pi / 5, n_c))
    j = np.arange(1, n + 1)
    lags = np.arange(1, ncut + 1)
    E2 = phi.mean() ** 2
    Ks = np.empty(n_c)
    for i, c in enumerate(cs):
        p = np.cumsum(phi * np.cos(j * c))
        q = np.cumsum(phi * np.sin(j * c))
        M = np.array([np.mean((p[m:] - p[:-m]) ** 2 + (q[m:] - q[:-m]) ** 2) for m in lags])
        D = M - E2 * (1 - np.cos(lags * c)) / (1 - np.cos(c))
        Ks[i] = np.corrcoef(lags, D)[0, 1]
    return xr.Dataset(
        {
            "K": ((), float(np.median(Ks)), variable("0-1 test statistic K")),
            "K_c": ("c", Ks, variable("K for each c")),
        },
        coords={"c": ("c", cs, variable("frequency c", "rad"))},
        attrs={"method": "0-1 test, correlation method (Gottwald & Melbourne 2009)"},
    )
