"""Butcher tableaux of the explicit embedded Runge–Kutta pairs.

The coefficients are the published ones of Dormand & Prince (1980, J. Comput. Appl. Math. 6:19)
for DOPRI5 with Shampine's (1986) continuous extension, and of Hairer's DOP853 (Hairer, Nørsett &
Wanner 1993, *Solving ODEs I*, Sec. II.10) with its 7th-order dense output. They are taken from
the class attributes of :class:`scipy.integrate.RK45` and :class:`scipy.integrate.DOP853` so that
the compiled integrators and the scipy reference backend use bit-identical numbers.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import DOP853, RK45


def _c(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64)


# DOPRI5: 6 stages + FSAL, 5th-order solution, 4th-order error estimator, 4th-order dense output.
RK45_A = _c(RK45.A)
RK45_B = _c(RK45.B)
RK45_C = _c(RK45.C)
RK45_E = _c(RK45.E)
RK45_P = _c(RK45.P)

# DOP853: 12 stages + FSAL, 8th-order solution, 5th- and 3rd-order error estimators,
# 3 extra stages for the 7th-order dense output.
DOP853_A = _c(DOP853.A)
DOP853_B = _c(DOP853.B)
DOP853_C = _c(DOP853.C)
DOP853_E3 = _c(DOP853.E3)
DOP853_E5 = _c(DOP853.E5)
DOP853_D = _c(DOP853.D)
DOP853_A_EXTRA = _c(DOP853.A_EXTRA)
DOP853_C_EXTRA = _c(DOP853.C_EXTRA)

# Step-size controller constants (as scipy and Hairer's codes): safety factor and bounds of the
# step-size ratio.
SAFETY = 0.9
MIN_FACTOR = 0.2
MAX_FACTOR = 10.0
