"""Default geometry and mass properties of the slider-crank mechanism (SI units).

Values of Flores, Ambrosio, Claro & Lankarani (2006, Mech. Mach. Theory 41:247).
Frame: crank pivot O at the origin, angles counter-clockwise from +X, the slider's pin B on the
x axis (the slider guide).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from workbench.models._layout import named_values

# order of the float64 geometry array passed to the compiled kinematics
GEOMETRY_FIELDS = (
    "L1",  # crank OA, m
    "L2",  # connecting rod AB, m
    "Lc1",  # crank centroid from O, m
    "Lc2",  # rod centroid from A, m
)

DEFAULT_GEOMETRY: dict[str, float] = {"L1": 0.05, "L2": 0.12, "Lc1": 0.025, "Lc2": 0.06}

# the three moving bodies, in the row order of the kinematics' pos, J and gam
BODY_NAMES = ("crank", "rod", "slider")
MASSES = (0.30, 0.21, 0.14)  # kg
INERTIAS = (1.0e-4, 2.5e-4, 0.0)  # centroidal, kg m2 (the slider only translates)


def geometry_array(values: Mapping[str, float] | None = None) -> np.ndarray:
    """The float64 geometry array that the compiled kinematics take.

    Parameters
    ----------
    values : mapping of str to float, optional
        Overrides of DEFAULT_GEOMETRY by field name (m).

    Returns
    -------
    numpy.ndarray
        float64[len(GEOMETRY_FIELDS)] in GEOMETRY_FIELDS order.

    Raises
    ------
    KeyError
        For a name that is not in GEOMETRY_FIELDS.
    """
    return named_values(GEOMETRY_FIELDS, DEFAULT_GEOMETRY, values, "slider-crank geometry field")
