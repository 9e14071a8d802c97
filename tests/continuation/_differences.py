"""Central differences for the checks' own references (``_impact_reference``,
``_stop_reference``): they share no code with the package."""

from __future__ import annotations

import numpy as np


def central_jacobian(f, u, h: float) -> np.ndarray:
    """The Jacobian of ``f`` at ``u`` by central differences, the step of each component ``h``
    times its magnitude (at least ``h``)."""
    u = np.asarray(u, float)
    columns = []
    for j in range(u.size):
        d = np.zeros(u.size)
        d[j] = h * max(1.0, abs(u[j]))
        columns.append((f(u + d) - f(u - d)) / (2 * d[j]))
    return np.stack(columns, axis=1)
