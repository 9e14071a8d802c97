"""The nine-bar's bodies and joint points at the initial crank angles: the public placement an
independent multibody engine is built from (``workbench.verify``)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from workbench.models.ninebar._geometry import BODY_NAMES
from workbench.models.ninebar._kinematics import (
    CRANK1,
    CRANK4,
    G_L5,
    G_O6X,
    G_O6Y,
    G_S0,
    LINK2,
    LINK3,
    LINK8,
    N_POINTS,
    PANEL7,
    PT_A,
    PT_B,
    PT_C,
    PT_D,
    PT_E,
    PT_P,
    ROCKER6,
    SLIDER9,
    jacobian,
    positions,
)
from workbench.models.ninebar._model import geometry_of

__all__ = ["Placement", "placement"]

#: body indices of the kinematics, by role
BODY_INDEX = {
    "crank1": CRANK1,
    "link2": LINK2,
    "link3": LINK3,
    "crank4": CRANK4,
    "rocker6": ROCKER6,
    "panel7": PANEL7,
    "link8": LINK8,
    "slider9": SLIDER9,
}


@dataclass(frozen=True)
class Placement:
    """The nine-bar at its initial crank angles with centred journals.

    Attributes
    ----------
    names : tuple[str, ...]
        Body names in the order of ``position`` and ``velocity`` (and of :data:`BODY_INDEX`).
    position, velocity : ndarray (8, 3)
        Centroid (x, y) and angle per body (m, m, rad), and their rates (m s-1, m s-1, rad s-1).
    points : dict[str, tuple[float, float]]
        The joint points A, B (bearings of the clearance joints), P, C, D, E (m).
    ground : dict[str, tuple[float, float]]
        Ground pivots: O1 (crank 1), O5 (crank 4), O6 (rocker 6) (m).
    slider_offset : float
        S0 of the slider position S9 = S0 - (x_E - x_O6) (m).
    """

    names: tuple[str, ...]
    position: np.ndarray
    velocity: np.ndarray
    points: dict[str, tuple[float, float]]
    ground: dict[str, tuple[float, float]]
    slider_offset: float


def placement(params: dict[str, Any]) -> Placement:
    """The placement for the model's resolved parameters (SI units; ``theta10``, ``theta40``
    rad, ``omega`` rad s-1)."""
    geometry = geometry_of(params)
    omega = params["omega"]
    q = np.array([params["theta10"], params["theta40"], 0.0, 0.0, 0.0, 0.0])
    qd = np.array([-omega, omega, 0.0, 0.0, 0.0, 0.0])
    pos = np.empty((8, 3))
    pts = np.empty((N_POINTS, 2))
    J = np.empty((8, 3, 6))
    Jp = np.empty((N_POINTS, 2, 6))
    if positions(q, geometry, pos, pts) or jacobian(q, geometry, J, Jp):
        raise ValueError("the nine-bar mechanism does not assemble at its initial angles")
    names = {PT_A: "A", PT_B: "B", PT_P: "P", PT_C: "C", PT_D: "D", PT_E: "E"}
    return Placement(
        names=tuple(BODY_NAMES),
        position=pos.copy(),
        velocity=J @ qd,
        points={name: (float(pts[i, 0]), float(pts[i, 1])) for i, name in names.items()},
        ground={
            "O1": (0.0, 0.0),
            "O5": (float(geometry[G_L5]), 0.0),
            "O6": (float(geometry[G_O6X]), float(geometry[G_O6Y])),
        },
        slider_offset=float(geometry[G_S0]),
    )
