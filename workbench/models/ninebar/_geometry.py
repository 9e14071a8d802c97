"""Default geometry and mass properties of the nine-bar mechanism (SI units).

Values and their provenance: ``docs/ninebar-parameters.md`` (tags R read from Chen et al.
2019, A assumed reconstructions, D derived). Frame: angles counter-clockwise from +X; O1 at the
origin, O4 at (L5, 0); the slider guide is the line y = y_O6.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from workbench.models._layout import named_values

# order of the float64 geometry array passed to the compiled kinematics. The panel centroid is
# the triangle centroid (C + P + D) / 3 (spec: Ls7 = 0.147 m from C), so it needs no field.
GEOMETRY_FIELDS = (
    "L1",  # crank 1, O1A, m (R)
    "L2",  # link 2, AP, m (R)
    "L3",  # link 3, BP, m (R)
    "L4",  # crank 4, O4B, m (R)
    "L5",  # frame, O1O4, m (R)
    "L6",  # rocker 6, O6C, m (R)
    "L71",  # panel 7, CP, m (A)
    "L72",  # panel 7, CD, m (A)
    "beta",  # panel 7, angle PCD, rad (A)
    "L8",  # link 8, DE, m (A)
    "O6x",  # rocker pivot x, m (A)
    "O6y",  # rocker pivot y = slider guide, m (A)
    "S0",  # slider offset: S9 = S0 - (x_E - x_O6), m (A)
    "Ls1",  # crank 1 centroid from O1, m (R)
    "Ls2",  # link 2 centroid from A, m (R)
    "Ls3",  # link 3 centroid from B, m (R)
    "Ls4",  # crank 4 centroid from O4, m (R)
    "Ls6",  # rocker 6 centroid from O6, m (R)
    "Ls8",  # link 8 centroid from D, m (R)
)

# entries that geometry_array appends, derived from the fields, so that the compiled kinematics
# does not recompute them at every call
DERIVED_FIELDS = (
    "cos_beta",  # cos(beta)
    "sin_beta",  # sin(beta)
)
ARRAY_FIELDS = GEOMETRY_FIELDS + DERIVED_FIELDS  # the geometry array's entries

DEFAULT_GEOMETRY: dict[str, float] = {
    "L1": 0.045,
    "L2": 0.326,
    "L3": 0.497,
    "L4": 0.095,
    "L5": 0.430,
    "L6": 0.230,
    "L71": 0.330,
    "L72": 0.330,
    "beta": math.radians(96.0),  # 96 deg
    "L8": 0.336,
    "O6x": -0.330,
    "O6y": 0.350,
    "S0": -0.1970,
    "Ls1": 0.023,
    "Ls2": 0.163,
    "Ls3": 0.249,
    "Ls4": 0.048,
    "Ls6": 0.115,
    "Ls8": 0.168,
}

# the eight moving bodies, in the row order of the kinematics' pos, J and gam
BODY_NAMES = ("crank1", "link2", "link3", "crank4", "rocker6", "panel7", "link8", "slider9")
# kg (R)
MASSES = (0.148, 0.805, 0.603, 0.265, 0.581, 4.334, 0.827, 0.801)
# centroidal moments of inertia, kg m2 (A: m L^2 / 12 for rods, m (a^2 + b^2 + c^2) / 36 for the
# triangular panel; the slider only translates)
INERTIAS = (2.4975e-5, 7.1293e-3, 1.2412e-2, 1.9930e-4, 2.5612e-3, 5.5182e-2, 7.7804e-3, 0.0)


def geometry_array(values: Mapping[str, float] | None = None) -> np.ndarray:
    """The float64 geometry array that the compiled kinematics take.

    Parameters
    ----------
    values : mapping of str to float, optional
        Overrides of DEFAULT_GEOMETRY by field name (m, rad).

    Returns
    -------
    numpy.ndarray
        float64[len(ARRAY_FIELDS)]: the fields in GEOMETRY_FIELDS order, then DERIVED_FIELDS.

    Raises
    ------
    KeyError
        For a name that is not in GEOMETRY_FIELDS.
    """
    geo = named_values(GEOMETRY_FIELDS, DEFAULT_GEOMETRY, values, "nine-bar geometry field")
    beta = geo[GEOMETRY_FIELDS.index("beta")]
    return np.concatenate([geo, [math.cos(beta), math.sin(beta)]])
