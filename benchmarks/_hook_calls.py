"""Timing a compiled hook by itself: one loop that calls it at stored states, shared by the
benchmarks that measure a right-hand side per call (ninebar_speed.py, declared_speed.py)."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit  # takes the hook as an argument: numba cannot cache that
def hook_calls(f, T, Y, p, ip, AUX, work, reps):
    """Call the hook f at every state (copied element-wise: no array views in the loop),
    ``reps`` times over; returns a sum of its outputs so that nothing is optimised away."""
    n = Y.shape[1]
    y = np.empty(n)
    aux = np.empty(AUX.shape[1])
    dydt = np.empty(n)
    acc = 0.0
    for _ in range(reps):
        for i in range(T.size):
            for k in range(n):
                y[k] = Y[i, k]
            for k in range(aux.size):
                aux[k] = AUX[i, k]
            acc += f(T[i], y, p, ip, aux, work, dydt) + dydt[n - 1]
    return acc
